//! The `.pvs` store from Python: build (with journal, resume and shards), merge, open
//! and query, and `check` against the ground truth — the semantics of the CLI's
//! `build`, `merge`, `query` and `check`.

use crate::errors::{detached, err, guarded, method_err, Kind};
use crate::scene::{
    cells_from_bytes, cells_to_bytes, ids_to_bytes, method_options, on_pool, pool, NativeScene,
};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use sightline_core::check::{aggregate, check_cell_prepared, report_json, TruthOptions};
use sightline_geom::{DVec3, ViewCell};
use sightline_methods::VisibilityMethod;
use sightline_pvs::build::journal_path;
use sightline_pvs::{BuildOptions, PvsFile, Shard, StoredPvs};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Side of the street cells `check` picks when given a number of cells (metres).
const AUTO_CELL_M: f64 = 10.0;

fn open(path: &Path) -> PyResult<PvsFile> {
    PvsFile::open(path).map_err(|e| err(Kind::Pvs, format!("cannot open {}: {e}", path.display())))
}

/// Build the `.pvs` of `cells` (N×6 `f64` bytes) into `out`, as `sightline build`;
/// returns the build statistics as JSON text. `progress(done, total)` is called from
/// the worker threads (with the GIL) at the start and after every finished cell.
#[pyfunction]
#[pyo3(signature = (scene, cells, method, out, resolution=None, sweep=false, planes=None,
                    resume=false, shard=None, threads=None, progress=None, knobs=Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub fn build(
    py: Python<'_>,
    scene: &NativeScene,
    cells: &[u8],
    method: &str,
    out: PathBuf,
    resolution: Option<u32>,
    sweep: bool,
    planes: Option<u32>,
    resume: bool,
    shard: Option<&str>,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
    knobs: Vec<(String, String)>,
) -> PyResult<String> {
    let shard = shard
        .map(|s| Shard::parse(s, |k| std::env::var(k).ok()))
        .transpose()
        .map_err(|e| err(Kind::Pvs, e))?;
    let cells = cells_from_bytes(cells)?;
    if cells.is_empty() {
        return Err(err(Kind::Cell, "no cells to build"));
    }
    let opts = method_options(method, resolution, sweep, planes, knobs)?;
    let pool = pool(threads)?;
    let callback_error: Mutex<Option<PyErr>> = Mutex::new(None);
    let report = |done: usize, total: usize| {
        let Some(cb) = &progress else { return };
        Python::attach(|py| {
            if let Err(e) = cb.call1(py, (done, total)) {
                if let Ok(mut slot) = callback_error.lock() {
                    slot.get_or_insert(e);
                }
            }
        });
    };
    let stats = detached(py, || {
        let m = scene.method(method, &opts)?;
        let bopts = BuildOptions {
            resume,
            shard,
            ..BuildOptions::default()
        };
        on_pool(pool.as_deref(), || {
            sightline_pvs::build(&scene.scene, m.as_ref(), &cells, &out, &bopts, &report)
        })
        .map_err(|e| {
            err(
                Kind::Pvs,
                format!(
                    "building {} (finished cells are kept in {}; rerun with resume=True): {e}",
                    out.display(),
                    journal_path(&out).display()
                ),
            )
        })
    })?;
    if let Some(e) = callback_error.lock().ok().and_then(|mut s| s.take()) {
        return Err(e);
    }
    let v = serde_json::json!({
        "out": out.display().to_string(),
        "method": method,
        "shard": shard.map(|s| format!("{}/{}", s.index, s.count)),
        "cells": stats.cells,
        "resumed": stats.resumed,
        "computed": stats.computed,
        "bytes": stats.bytes,
        "compute_seconds": stats.compute_seconds,
        "encode_seconds": stats.encode_seconds,
    });
    serde_json::to_string(&v).map_err(|e| err(Kind::Pvs, e))
}

/// Merge shard files into `out` (written atomically), as `sightline merge`.
#[pyfunction]
pub fn merge(py: Python<'_>, inputs: Vec<PathBuf>, out: PathBuf) -> PyResult<(usize, u64)> {
    detached(py, || {
        let files = inputs
            .iter()
            .map(|p| open(p).map(|f| (p.display().to_string(), f)))
            .collect::<PyResult<Vec<_>>>()?;
        let bytes = sightline_pvs::merge(&files).map_err(|e| err(Kind::Pvs, e))?;
        sightline_pvs::build::write_atomic(&out, &bytes)
            .map_err(|e| err(Kind::Pvs, format!("cannot write {}: {e}", out.display())))?;
        Ok((files[0].1.cells().len(), bytes.len() as u64))
    })
}

/// Read a cells.json (a JSON array of `[x0,y0,z0,x1,y1,z1]`) as N×6 `f64` bytes.
#[pyfunction]
pub fn read_cells<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyBytes>> {
    let cells = detached(py, || {
        let text = std::fs::read_to_string(&path)
            .map_err(|e| err(Kind::Cell, format!("cannot read {}: {e}", path.display())))?;
        let cells: Vec<ViewCell> = serde_json::from_str(&text).map_err(|e| {
            err(
                Kind::Cell,
                format!(
                    "{}: expected a JSON array of [x0,y0,z0,x1,y1,z1] cells: {e}",
                    path.display()
                ),
            )
        })?;
        if cells.is_empty() {
            return Err(err(Kind::Cell, format!("{}: no cells", path.display())));
        }
        Ok(cells)
    })?;
    Ok(PyBytes::new(py, &cells_to_bytes(&cells)))
}

/// The cells.json text of N×6 `f64` bytes (one box per line, as `sightline cells`).
#[pyfunction]
pub fn cells_json(cells: &[u8]) -> PyResult<String> {
    let cells = cells_from_bytes(cells)?;
    let mut out = String::from("[");
    for (k, c) in cells.iter().enumerate() {
        out.push_str(if k == 0 { "\n" } else { ",\n" });
        out.push_str(&serde_json::to_string(c).map_err(|e| err(Kind::Cell, e))?);
    }
    out.push_str("\n]\n");
    Ok(out)
}

/// `sightline check --json`: a `.pvs` file (`k` of its cells, evenly spread) or a method
/// (on `cells`, or on `k` street cells) against the ground truth.
#[pyfunction]
#[pyo3(signature = (scene, pvs=None, method=None, cells=None, k=None, resolution=None,
                    sweep=false, planes=None, threads=None, knobs=Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub fn check(
    py: Python<'_>,
    scene: &NativeScene,
    pvs: Option<PathBuf>,
    method: Option<&str>,
    cells: Option<&[u8]>,
    k: Option<usize>,
    resolution: Option<u32>,
    sweep: bool,
    planes: Option<u32>,
    threads: Option<usize>,
    knobs: Vec<(String, String)>,
) -> PyResult<String> {
    if k == Some(0) {
        return Err(err(Kind::Cell, "cells must be a positive number of cells"));
    }
    let given = cells.map(cells_from_bytes).transpose()?;
    let pool = pool(threads)?;
    let (m, picked): (Arc<dyn VisibilityMethod>, Vec<ViewCell>) = match (pvs, method) {
        (Some(_), Some(_)) => {
            return Err(err(
                Kind::Method,
                "check takes a .pvs file or a method, not both",
            ))
        }
        (None, None) => return Err(err(Kind::Method, "check needs method=NAME or a .pvs file")),
        (Some(file), None) => {
            if sweep || planes.is_some() || resolution.is_some() || !knobs.is_empty() {
                return Err(err(
                    Kind::Method,
                    "resolution, sweep, planes and knobs are method options, not options of a .pvs file",
                ));
            }
            if given.is_some() {
                return Err(err(
                    Kind::Cell,
                    "with a .pvs file, cells is a number of cells to sample",
                ));
            }
            let f = detached(py, || open(&file))?;
            f.check_scene(&scene.scene).map_err(|e| {
                err(
                    Kind::Pvs,
                    format!(
                        "{} does not belong to {}: {e}",
                        file.display(),
                        scene.name()
                    ),
                )
            })?;
            let stored = StoredPvs(f);
            let picked = stored.sample_cells(k.unwrap_or(20));
            (Arc::new(stored), picked)
        }
        (None, Some(name)) => {
            let opts = method_options(name, resolution, sweep, planes, knobs.clone())?;
            let m = detached(py, || scene.method(name, &opts))?;
            let picked = match given {
                Some(c) if c.is_empty() => return Err(err(Kind::Cell, "no cells")),
                Some(c) => c,
                None => {
                    let k = k.unwrap_or(20);
                    let c = detached(py, || {
                        Ok(sightline_core::check::street_cells(
                            &scene.scene,
                            AUTO_CELL_M,
                            (1.5, 2.0),
                            k,
                            sightline_core::check::Clearance::Box,
                        ))
                    })?;
                    if c.is_empty() {
                        return Err(err(
                            Kind::Cell,
                            format!("no free {AUTO_CELL_M} m street cell found in the scene"),
                        ));
                    }
                    c
                }
            };
            (m, picked)
        }
    };
    let report = detached(py, || {
        let ts = scene.truth_scene();
        let opts = TruthOptions::default();
        on_pool(pool.as_deref(), || {
            use rayon::prelude::*;
            picked
                .par_iter()
                .map(|c| check_cell_prepared(&ts, m.as_ref(), c, &opts))
                .collect::<Result<Vec<_>, _>>()
        })
        .map(|per_cell| aggregate(m.name(), per_cell))
        .map_err(method_err)
    })?;
    let v = report_json(&report, m.as_ref());
    serde_json::to_string(&v).map_err(|e| err(Kind::Method, e))
}

/// An opened `.pvs` file: header, cell table and spatial index in memory, each cell's set
/// decoded on demand.
#[pyclass(module = "sightline._native", frozen, name = "NativePvsFile")]
pub struct NativePvsFile {
    file: PvsFile,
    path: String,
    /// The same file through `sightline-runtime`, opened on the first gameplay query.
    runtime: std::sync::OnceLock<Result<sightline_runtime::Pvs, String>>,
}

#[pymethods]
impl NativePvsFile {
    #[staticmethod]
    fn open(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let file = detached(py, || open(&path))?;
        Ok(NativePvsFile {
            file,
            path: path.display().to_string(),
            runtime: std::sync::OnceLock::new(),
        })
    }

    fn __len__(&self) -> usize {
        self.file.cells().len()
    }

    #[getter]
    fn path(&self) -> &str {
        &self.path
    }

    /// The header as JSON text (method, params, object count, fingerprint, shard).
    fn header_json(&self) -> PyResult<String> {
        let h = self.file.header();
        let v = serde_json::json!({
            "method": h.method,
            "params": h.params.iter().cloned().collect::<std::collections::BTreeMap<_, _>>(),
            "objects": h.object_count,
            "fingerprint": format!("{:016x}", h.fingerprint),
            "shard": h.shard.map(|s| format!("{}/{}", s.index, s.count)),
        });
        serde_json::to_string(&v).map_err(|e| err(Kind::Pvs, e))
    }

    /// The cell table as N×6 `f64` bytes.
    fn cells<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &cells_to_bytes(self.file.cells()))
    }

    /// Indices of the cells whose set this file stores (all but in a shard file).
    fn stored(&self) -> Vec<u32> {
        self.file.stored()
    }

    /// The index of the cell containing `(x, y, z)`, if any.
    fn locate(&self, x: f64, y: f64, z: f64) -> PyResult<Option<usize>> {
        guarded(|| Ok(self.file.locate(DVec3::new(x, y, z))))
    }

    /// The set of cell `index`, as little-endian `u32` bytes.
    fn pvs<'py>(&self, py: Python<'py>, index: usize) -> PyResult<Bound<'py, PyBytes>> {
        let n = self.file.cells().len();
        if index >= n {
            return Err(err(
                Kind::Cell,
                format!("cell {index} is out of range ({} has {n} cells)", self.path),
            ));
        }
        let ids = detached(py, || {
            self.file.pvs(index).map_err(|e| {
                err(
                    Kind::Pvs,
                    format!("cannot read cell {index} of {}: {e}", self.path),
                )
            })
        })?;
        Ok(PyBytes::new(py, &ids_to_bytes(&ids)))
    }

    /// Whether cell `a` may see cell `b` (the guarantee of `sightline_runtime::gameplay`).
    fn can_see(&self, py: Python<'_>, a: u32, b: u32) -> PyResult<bool> {
        self.check_cell(a)?;
        self.check_cell(b)?;
        detached(py, || {
            let pvs = self.runtime()?;
            pvs.can_see(&mut sightline_runtime::Query::new(), a, b)
                .map_err(|e| err(Kind::Pvs, format!("{}: {e}", self.path)))
        })
    }

    /// The cells that may see the point `(x, y, z)` as little-endian `u32` bytes; `None`
    /// when no cell holds the point.
    fn seen_by<'py>(
        &self,
        py: Python<'py>,
        x: f64,
        y: f64,
        z: f64,
    ) -> PyResult<Option<Bound<'py, PyBytes>>> {
        let cells = detached(py, || {
            let pvs = self.runtime()?;
            let mut out = Vec::new();
            let q = &mut sightline_runtime::Query::new();
            let cell = pvs
                .cells_seeing_point_into(q, [x, y, z], &mut out)
                .map_err(|e| err(Kind::Pvs, format!("{}: {e}", self.path)))?;
            Ok(cell.map(|_| out))
        })?;
        Ok(cells.map(|c| PyBytes::new(py, &ids_to_bytes(&c))))
    }

    /// The secondary PVS of cell `index` (the union of the sets of the cells that may
    /// see it) as little-endian `u32` bytes.
    fn secondary<'py>(&self, py: Python<'py>, index: u32) -> PyResult<Bound<'py, PyBytes>> {
        self.check_cell(index)?;
        let ids = detached(py, || {
            let pvs = self.runtime()?;
            let mut out = Vec::new();
            pvs.secondary_into(&mut sightline_runtime::Query::new(), index, &mut out)
                .map_err(|e| err(Kind::Pvs, format!("{}: {e}", self.path)))?;
            Ok(out)
        })?;
        Ok(PyBytes::new(py, &ids_to_bytes(&ids)))
    }

    /// Decode every stored cell and check every checksum.
    fn verify(&self, py: Python<'_>) -> PyResult<()> {
        detached(py, || {
            self.file
                .verify()
                .map_err(|e| err(Kind::Pvs, format!("{}: {e}", self.path)))
        })
    }
}

impl NativePvsFile {
    fn runtime(&self) -> PyResult<&sightline_runtime::Pvs> {
        self.runtime
            .get_or_init(|| sightline_runtime::Pvs::open(&self.path).map_err(|e| e.to_string()))
            .as_ref()
            .map_err(|e| err(Kind::Pvs, format!("{}: {e}", self.path)))
    }

    fn check_cell(&self, cell: u32) -> PyResult<()> {
        let n = self.file.cells().len();
        if cell as usize >= n {
            return Err(err(
                Kind::Cell,
                format!("cell {cell} is out of range ({} has {n} cells)", self.path),
            ));
        }
        Ok(())
    }
}
