//! The one place where core errors become Python exceptions.

use ndtrace::{NdError, NdResult};
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyValueError};
use pyo3::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Converts a core error into the Python exception users see.
///
/// Problems with the caller's input are `ValueError`; a cancelled trace is `KeyboardInterrupt`.
pub fn to_py_err(e: NdError) -> PyErr {
    match e {
        NdError::Dimension { .. }
        | NdError::Shape { .. }
        | NdError::NonFinite { .. }
        | NdError::Degenerate { .. }
        | NdError::Value { .. }
        | NdError::Scene { .. } => PyValueError::new_err(e.to_string()),
        NdError::File { .. } => PyOSError::new_err(e.to_string()),
        NdError::Cancelled => PyKeyboardInterrupt::new_err("trace interrupted"),
    }
}

pyo3::create_exception!(
    ndtrace,
    InternalError,
    pyo3::exceptions::PyRuntimeError,
    "A bug in ndtrace: a check that should have refused the input did not, and the core \
     stopped (a Rust panic). The message names the operation; please report it."
);

/// Panics caught by [`guarded`] since the module was loaded (the test suite fails any test
/// during which this grows).
static CAUGHT: AtomicUsize = AtomicUsize::new(0);

/// Runs a core call; its error becomes the usual exception ([`to_py_err`]) and a panic, the
/// last line of defence behind the checks, an [`InternalError`] naming `op` instead of
/// pyo3's `PanicException` (a `BaseException` that `except Exception` does not catch).
pub fn guarded<T>(op: &str, f: impl FnOnce() -> NdResult<T>) -> PyResult<T> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(result) => result.map_err(to_py_err),
        Err(payload) => Err(internal_error(op, payload.as_ref())),
    }
}

/// The [`InternalError`] of a caught panic with `payload` in `op`.
pub fn internal_error(op: &str, payload: &(dyn std::any::Any + Send)) -> PyErr {
    CAUGHT.fetch_add(1, Ordering::Relaxed);
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "panic".into());
    InternalError::new_err(format!(
        "{op}: internal error (a bug in ndtrace; please report it with the input): {what}"
    ))
}

/// How many panics the bindings have caught and turned into `InternalError`.
#[pyfunction]
pub fn internal_errors() -> usize {
    CAUGHT.load(Ordering::Relaxed)
}

/// Adds `InternalError` and `internal_errors()`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("InternalError", m.py().get_type::<InternalError>())?;
    m.add_function(wrap_pyfunction!(internal_errors, m)?)?;
    Ok(())
}
