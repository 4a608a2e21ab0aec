//! `sightline._native`: the Rust side of the Python package `sightline`.
//!
//! A thin layer over the sightline crates — the importers, the viewcell grid, the
//! visibility methods, the ground truth and the `.pvs` store — with the command line's
//! validation rules and one-line error messages. Arrays cross the boundary as
//! little-endian bytes (`f64` cells, `u32` ids) that the pure-Python layer views as
//! numpy arrays, so this module needs no numpy at build time.
//!
//! Every computation runs with the GIL released and behind a panic guard: a bug in a
//! method raises `SightlineError("internal error: ...")` instead of aborting the
//! interpreter.

mod errors;
mod scene;
mod store;

use pyo3::prelude::*;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SightlineError", py.get_type::<errors::SightlineError>())?;
    m.add("SceneError", py.get_type::<errors::SceneError>())?;
    m.add("CellError", py.get_type::<errors::CellError>())?;
    m.add("MethodError", py.get_type::<errors::MethodError>())?;
    m.add("PvsFileError", py.get_type::<errors::PvsFileError>())?;
    m.add("METHOD_NAMES", sightline_methods::METHOD_NAMES.to_vec())?;
    m.add_class::<scene::NativeScene>()?;
    m.add_class::<store::NativePvsFile>()?;
    m.add_function(wrap_pyfunction!(scene::parse_cell, m)?)?;
    m.add_function(wrap_pyfunction!(scene::check_method, m)?)?;
    m.add_function(wrap_pyfunction!(scene::methods_json, m)?)?;
    m.add_function(wrap_pyfunction!(store::build, m)?)?;
    m.add_function(wrap_pyfunction!(store::merge, m)?)?;
    m.add_function(wrap_pyfunction!(store::read_cells, m)?)?;
    m.add_function(wrap_pyfunction!(store::cells_json, m)?)?;
    m.add_function(wrap_pyfunction!(store::check, m)?)?;
    Ok(())
}
