//! Where PVS answers come from: a `.pvs` file built beforehand, or a visibility method
//! run on-line (dual ray space paper, §1: "computing from-region visibility on-line,
//! thus eliminating the need for visibility preprocessing").
//!
//! Both sit behind [`PvsSource`]; the server puts a cache and a worker pool in front
//! ([`crate::cache`]) and never asks a source about anything but cells it located itself.

use crate::grid::{CellGrid, CellId, PointError};
use serde::Serialize;
use sightline_geom::{DVec2, DVec3, ViewCell};
use sightline_methods::VisibilityMethod;
use std::sync::Arc;

/// What a source says about itself (shown in `/api/scene`).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SourceInfo {
    /// `"online"` or `"file"`.
    pub kind: &'static str,
    /// The SPEC §4 method name that produced / produces the sets.
    pub method: String,
    /// Whether every set contains every visible object.
    pub conservative: bool,
    /// The method's parameters, `key=value`.
    pub params: Vec<String>,
}

/// Why a source could not give a cell's PVS.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum SourceError {
    #[error("no such cell {0}")]
    NoCell(CellId),
    #[error("{0}")]
    Method(String),
}

/// A provider of per-cell PVS, blocking (call it from a worker thread).
pub trait PvsSource: Send + Sync + 'static {
    fn info(&self) -> SourceInfo;
    /// The cell layout: sessions prefetch along it.
    fn grid(&self) -> &CellGrid;
    /// The cell containing a point.
    fn locate(&self, p: DVec3) -> Result<CellId, PointError> {
        self.grid().locate(p)
    }
    /// The box of a cell.
    fn cell(&self, id: CellId) -> Option<ViewCell> {
        self.grid().cell(id)
    }
    /// The cells adjacent to `id`, those ahead along `heading` first.
    fn neighbours(&self, id: CellId, heading: DVec2) -> Vec<CellId> {
        self.grid().neighbours(id, heading)
    }
    /// The PVS of a cell: sorted ascending object ids. May take long (on-line methods).
    fn pvs(&self, id: CellId) -> Result<Vec<u32>, SourceError>;
}

/// On-line source: a prepared [`VisibilityMethod`] evaluated per grid cell.
pub struct OnlineSource {
    method: Box<dyn VisibilityMethod>,
    grid: CellGrid,
}

impl OnlineSource {
    pub fn new(method: Box<dyn VisibilityMethod>, grid: CellGrid) -> Self {
        OnlineSource { method, grid }
    }
}

impl PvsSource for OnlineSource {
    fn info(&self) -> SourceInfo {
        SourceInfo {
            kind: "online",
            method: self.method.name().to_string(),
            conservative: self.method.is_conservative(),
            params: self
                .method
                .params()
                .into_iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect(),
        }
    }

    fn grid(&self) -> &CellGrid {
        &self.grid
    }

    fn pvs(&self, id: CellId) -> Result<Vec<u32>, SourceError> {
        let cell = self.grid.cell(id).ok_or(SourceError::NoCell(id))?;
        let mut v = self
            .method
            .pvs(&cell)
            .map_err(|e| SourceError::Method(e.to_string()))?;
        // The trait promises sorted, unique ids; the deltas rely on it, so make sure.
        if !v.windows(2).all(|w| w[0] < w[1]) {
            v.sort_unstable();
            v.dedup();
        }
        Ok(v)
    }
}

/// Shared handle.
pub type SharedSource = Arc<dyn PvsSource>;
