//! The exception hierarchy and the boundary guards: every error becomes a one-line
//! Python exception (the command line's `error: ...` message without the prefix), and a
//! panic becomes an exception instead of unwinding into the interpreter.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

pyo3::create_exception!(
    sightline,
    SightlineError,
    PyValueError,
    "Base class of every sightline error; the message is the command line's one-line error."
);
pyo3::create_exception!(
    sightline,
    SceneError,
    SightlineError,
    "A scene could not be loaded or converted (bad file, geometry, heights, columns)."
);
pyo3::create_exception!(
    sightline,
    CellError,
    SightlineError,
    "A bad viewcell or cell grid (not 6 finite numbers, min > max, no free space)."
);
pyo3::create_exception!(
    sightline,
    MethodError,
    SightlineError,
    "An unknown method, bad method options, or a method that could not answer."
);
pyo3::create_exception!(
    sightline,
    PvsFileError,
    SightlineError,
    "A `.pvs` file or build journal that cannot be read, written, built or merged."
);

/// Which exception class an error maps to.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    Scene,
    Cell,
    Method,
    Pvs,
}

/// A Python exception of `kind` with a one-line message.
pub fn err(kind: Kind, msg: impl std::fmt::Display) -> PyErr {
    let msg = msg.to_string().replace('\n', " ");
    match kind {
        Kind::Scene => SceneError::new_err(msg),
        Kind::Cell => CellError::new_err(msg),
        Kind::Method => MethodError::new_err(msg),
        Kind::Pvs => PvsFileError::new_err(msg),
    }
}

/// The exception of a method error: a bad cell is a [`CellError`], the rest a
/// [`MethodError`].
pub fn method_err(e: sightline_methods::MethodError) -> PyErr {
    match e {
        sightline_methods::MethodError::BadCell(_) => err(Kind::Cell, e),
        _ => err(Kind::Method, e),
    }
}

/// Run `f` with the GIL released, turning a panic into `SightlineError`.
pub fn detached<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> PyResult<T> + Send,
{
    py.detach(|| guarded(f))
}

/// Run `f`, turning a panic into `SightlineError` (a bug, but never a dead interpreter).
pub fn guarded<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let what = payload
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| payload.downcast_ref::<&str>().copied())
                .unwrap_or("a panic");
            Err(SightlineError::new_err(format!(
                "internal error: {what} (a sightline bug: please report it)"
            )))
        }
    }
}
