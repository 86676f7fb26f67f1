//! `_ndtrace.composite`: a retina (C-contiguous float32 rgba `(..., 4)` and optional depth) and
//! a dict of options in, a float32 picture `(H, W, 4)` out. The dict is deserialized into the
//! core's `CompositeOptions` — the same struct as a scene's `[composite]` table — so its keys,
//! defaults and range checks are the core's; the Python wrapper `ndtrace.composite` documents
//! them.

use crate::errors::to_py_err;
use ndtrace::composite::{self as core, CompositeMode, CompositeOptions, Projection};
use ndtrace::scene::{self, PathError};
use ndtrace::{names, NdError};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

type Arr<'py> = PyReadonlyArrayDyn<'py, f32>;

/// The options a dict gives (keys missing from it keep their defaults).
fn options_from(dict: &Bound<'_, PyAny>) -> Result<CompositeOptions, PathError> {
    scene::deserialize(&mut pythonize::Depythonizer::from_object(dict))
}

/// Composites a retina into a picture with the options of the dict `options` (None: every
/// default); `threads=None` uses every core (the picture is the same whatever the number).
#[pyfunction]
#[pyo3(signature = (rgba, depth=None, options=None, threads=None))]
fn composite<'py>(
    py: Python<'py>,
    rgba: Arr<'py>,
    depth: Option<Arr<'py>>,
    options: Option<&Bound<'py, PyAny>>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    let opts = match options {
        None => CompositeOptions::default(),
        Some(dict) => options_from(dict).map_err(|e| {
            let arg = if e.path.is_empty() {
                "options".to_string()
            } else {
                e.path
            };
            to_py_err(NdError::Value {
                arg,
                message: e.message,
            })
        })?,
    };
    let dims = rgba.shape().to_vec();
    if dims.len() < 2 || dims[dims.len() - 1] != 4 {
        return Err(PyValueError::new_err(format!(
            "retina: expected an rgba array of shape (..., 4), got {dims:?}"
        )));
    }
    let shape = dims[..dims.len() - 1].to_vec();
    let rgba = rgba
        .as_slice()
        .map_err(|_| PyValueError::new_err("retina: expected a C-contiguous float32 rgba array"))?;
    let depth = match &depth {
        Some(d) => {
            if d.shape() != shape.as_slice() {
                return Err(PyValueError::new_err(format!(
                    "depth: expected shape {shape:?} (the rgba array's without its last axis), got {:?}",
                    d.shape()
                )));
            }
            Some(d.as_slice().map_err(|_| {
                PyValueError::new_err("depth: expected a C-contiguous float32 array")
            })?)
        }
        None => None,
    };
    let pool = crate::thread_pool(threads)?;
    let run = || core::composite(rgba, depth, &shape, &opts);
    let image = py
        .detach(|| match &pool {
            Some(p) => p.install(run),
            None => run(),
        })
        .map_err(to_py_err)?;
    Ok(PyArray1::from_vec(py, image.rgba)
        .reshape([image.height, image.width, 4])?
        .into_any())
}

/// Every composite option with its default, as a dict in the order of the fields.
#[pyfunction]
fn composite_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    pythonize::pythonize(py, &CompositeOptions::default().with_every_key())
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Checks the composite options of a dict on their own, without a retina (what a scene's
/// `[composite]` table is checked for); errors read `name: composite.key: message`.
#[pyfunction]
fn check_composite(options: &Bound<'_, PyAny>, name: &str) -> PyResult<()> {
    let located = |path: &str, message: String| {
        to_py_err(NdError::Scene {
            location: name.to_string(),
            path: if path.is_empty() {
                "composite".to_string()
            } else {
                format!("composite.{path}")
            },
            message,
        })
    };
    let opts = options_from(options).map_err(|e| located(&e.path, e.message))?;
    opts.validate().map_err(|e| located(&e.key, e.message))
}

/// Adds `composite`, `composite_defaults`, `check_composite` and the names of the composite
/// modes and projections (`COMPOSITE_MODES`, `PROJECTIONS`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_function(wrap_pyfunction!(composite, m)?)?;
    m.add_function(wrap_pyfunction!(composite_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(check_composite, m)?)?;
    m.add(
        "COMPOSITE_MODES",
        PyTuple::new(py, names::variants::<CompositeMode>())?,
    )?;
    m.add(
        "PROJECTIONS",
        PyTuple::new(py, names::variants::<Projection>())?,
    )?;
    Ok(())
}
