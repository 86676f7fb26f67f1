//! The one place where core errors become Python exceptions.

use ndtrace::NdError;
use pyo3::exceptions::PyValueError;
use pyo3::PyErr;

/// Converts a core error into the Python exception users see.
///
/// Every current [`NdError`] is a problem with the caller's input, hence `ValueError`.
pub fn to_py_err(e: NdError) -> PyErr {
    match e {
        NdError::Dimension { .. }
        | NdError::Shape { .. }
        | NdError::NonFinite { .. }
        | NdError::Degenerate { .. }
        | NdError::Value { .. } => PyValueError::new_err(e.to_string()),
    }
}
