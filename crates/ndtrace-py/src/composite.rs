//! `_ndtrace.composite`: a retina (C-contiguous float32 rgba `(..., 4)` and optional depth) in,
//! a float32 picture `(H, W, 4)` out. The options are checked by the core
//! (`ndtrace::composite`); the Python wrapper `ndtrace.composite` documents them.

use crate::errors::to_py_err;
use ndtrace::composite::{self as core, CompositeMode, CompositeOptions, Projection};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

type Arr<'py> = PyReadonlyArrayDyn<'py, f32>;

fn parse_projection(name: &str) -> PyResult<Projection> {
    match name {
        "perspective" => Ok(Projection::Perspective),
        "orthographic" => Ok(Projection::Orthographic),
        other => Err(PyValueError::new_err(format!(
            "projection: expected 'perspective' or 'orthographic', got {other:?}"
        ))),
    }
}

/// Composites a retina into a picture; `threads=None` uses every core (the picture is the
/// same whatever the number).
#[pyfunction]
#[pyo3(signature = (
    rgba, depth=None, *, mode="volume", azimuth=30.0, elevation=20.0,
    distance=core::DEFAULT_DISTANCE, zoom=1.0, projection="perspective", size=(512, 512),
    opacity=1.0, step=0.5, depth_cue=0.0, axis=0, background=(0.0, 0.0, 0.0), stages=None,
    strip_height=32, labels=true, threads=None
))]
#[allow(clippy::too_many_arguments)]
fn composite<'py>(
    py: Python<'py>,
    rgba: Arr<'py>,
    depth: Option<Arr<'py>>,
    mode: &str,
    azimuth: f64,
    elevation: f64,
    distance: f64,
    zoom: f64,
    projection: &str,
    size: (usize, usize),
    opacity: f64,
    step: f64,
    depth_cue: f64,
    axis: usize,
    background: (f64, f64, f64),
    stages: Option<Vec<(f64, f64)>>,
    strip_height: usize,
    labels: bool,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyAny>> {
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
    let opts = CompositeOptions {
        mode: CompositeMode::parse(mode).map_err(to_py_err)?,
        azimuth,
        elevation,
        distance,
        zoom,
        projection: parse_projection(projection)?,
        size,
        opacity,
        step,
        depth_cue,
        axis,
        background: [background.0, background.1, background.2],
        stages: stages.unwrap_or_default(),
        strip_height,
        labels,
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

/// Adds `composite`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(composite, m)?)?;
    Ok(())
}
