//! A `.pvs` file answering as the method it was built with, so that `check` (the CLI's
//! and the Python one) compares a stored PVS against the ground truth exactly as it
//! compares a method computed on-line.

use crate::query::PvsFile;
use sightline_geom::ViewCell;
use sightline_methods::{Method, MethodError, VisibilityMethod};

/// A `.pvs` file as a [`VisibilityMethod`] over its own cells.
pub struct StoredPvs(pub PvsFile);

impl StoredPvs {
    /// `k` of the cells whose sets the file stores, spread evenly over them (all when
    /// there are fewer).
    pub fn sample_cells(&self, k: usize) -> Vec<ViewCell> {
        let stored = self.0.stored();
        let k = k.min(stored.len());
        (0..k)
            .map(|i| self.0.cells()[stored[i * stored.len() / k] as usize])
            .collect()
    }
}

impl VisibilityMethod for StoredPvs {
    fn name(&self) -> &'static str {
        self.0
            .header()
            .method
            .parse::<Method>()
            .map(Method::name)
            .unwrap_or("pvs-file")
    }

    fn is_conservative(&self) -> bool {
        self.0
            .header()
            .method
            .parse::<Method>()
            .map(Method::is_conservative)
            .unwrap_or(false)
    }

    fn params(&self) -> Vec<(String, String)> {
        self.0.header().params.clone()
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        let i = self
            .0
            .cells()
            .iter()
            .position(|c| c == cell)
            .ok_or_else(|| MethodError::BadCell("not a cell of the .pvs file".into()))?;
        self.0.pvs(i).map_err(|e| MethodError::Other(e.to_string()))
    }
}
