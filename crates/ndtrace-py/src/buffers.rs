//! Flat float64 buffers between numpy and the core's batch layers, shared by the
//! `ndtrace.geometry` and `ndtrace.rotation` kernels: C-contiguous arrays in, a flat array out
//! (reshaped by the Python wrapper).

use crate::errors::guarded;
use ndtrace::NdResult;
use numpy::{PyArray1, PyReadonlyArrayDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// A read-only float64 numpy array argument.
pub(crate) type Arr<'py> = PyReadonlyArrayDyn<'py, f64>;
/// A flat float64 numpy result.
pub(crate) type Out<'py> = PyResult<Bound<'py, PyArray1<f64>>>;

/// The array's data, which must be C-contiguous (the Python wrappers make it so).
pub(crate) fn flat<'a>(a: &'a Arr<'_>, name: &str) -> PyResult<&'a [f64]> {
    a.as_slice().map_err(|_| {
        PyValueError::new_err(format!("{name}: expected a C-contiguous float64 array"))
    })
}

/// Allocates the output, runs the core with the GIL released, hands the buffer to numpy.
pub(crate) fn run<'py, F>(py: Python<'py>, len: usize, f: F) -> Out<'py>
where
    F: FnOnce(&mut [f64]) -> NdResult<()> + Send,
{
    let mut out = vec![0.0; len];
    // The closure's type names the kernel: `_ndtrace::geometry::signed_volume::{{closure}}`.
    let name = std::any::type_name::<F>();
    let op = name
        .trim_start_matches("_ndtrace::")
        .split("::{{")
        .next()
        .unwrap_or(name)
        .replace("::", ".");
    py.detach(|| guarded(&op, || f(&mut out)))?;
    Ok(PyArray1::from_vec(py, out))
}
