//! The one place where core errors become Python exceptions.

use ndtrace::NdError;
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyValueError};
use pyo3::PyErr;

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
