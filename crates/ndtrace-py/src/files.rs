//! Kernels behind `ndtrace.write_exr`, `ndtrace.read_exr` and the 8-bit pictures of
//! `ndtrace.write_image` (which Pillow writes).

use crate::errors::to_py_err;
use ndtrace::files::{self, ExrContents, Picture};
use ndtrace::render::Retina;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

fn vec_of<T: numpy::Element + Copy>(a: &PyReadonlyArrayDyn<'_, T>, name: &str) -> PyResult<Vec<T>> {
    a.as_slice()
        .map(|s| s.to_vec())
        .map_err(|_| PyValueError::new_err(format!("{name}: expected a C-contiguous array")))
}

/// Writes a retina given as its arrays (shapes checked by the Python wrapper).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (path, dim, shape, rgba, depth, normal, object_id, primitive_id, camera=None))]
fn write_retina_exr(
    py: Python<'_>,
    path: PathBuf,
    dim: usize,
    shape: Vec<usize>,
    rgba: PyReadonlyArrayDyn<'_, f32>,
    depth: PyReadonlyArrayDyn<'_, f32>,
    normal: PyReadonlyArrayDyn<'_, f32>,
    object_id: PyReadonlyArrayDyn<'_, i32>,
    primitive_id: PyReadonlyArrayDyn<'_, i64>,
    camera: Option<String>,
) -> PyResult<()> {
    let r = Retina {
        dim,
        shape,
        rgba: vec_of(&rgba, "rgba")?,
        depth: vec_of(&depth, "depth")?,
        normal: vec_of(&normal, "normal")?,
        object_id: vec_of(&object_id, "object_id")?,
        primitive_id: vec_of(&primitive_id, "primitive_id")?,
    };
    py.detach(|| files::write_retina_exr(&path, &r, camera.as_deref()))
        .map_err(to_py_err)
}

fn picture(
    rgba: &PyReadonlyArrayDyn<'_, f32>,
    depth: Option<&PyReadonlyArrayDyn<'_, f32>>,
) -> PyResult<Picture> {
    let shape = rgba.shape().to_vec();
    if shape.len() != 3 || shape[2] != 4 {
        return Err(PyValueError::new_err(format!(
            "image: expected shape (H, W, 4), got {shape:?}"
        )));
    }
    Ok(Picture {
        width: shape[1],
        height: shape[0],
        rgba: vec_of(rgba, "image")?,
        depth: depth.map(|d| vec_of(d, "depth")).transpose()?,
    })
}

/// Writes a 2D picture (H, W, 4) float32, premultiplied, with optional depth (H, W).
#[pyfunction]
#[pyo3(signature = (path, rgba, depth=None))]
fn write_picture_exr(
    py: Python<'_>,
    path: PathBuf,
    rgba: PyReadonlyArrayDyn<'_, f32>,
    depth: Option<PyReadonlyArrayDyn<'_, f32>>,
) -> PyResult<()> {
    let p = picture(&rgba, depth.as_ref())?;
    py.detach(|| files::write_picture_exr(&path, &p))
        .map_err(to_py_err)
}

/// A picture (H, W, 4) as 8-bit sRGB: (H, W, 4) with straight alpha, or (H, W, 3) opaque.
#[pyfunction]
#[pyo3(signature = (rgba, opaque=false))]
fn to_srgb8<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArrayDyn<'_, f32>,
    opaque: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let p = picture(&rgba, None)?;
    let (h, w) = (p.height, p.width);
    let bytes = py
        .detach(|| files::to_srgb8(&p, opaque))
        .map_err(to_py_err)?;
    let channels = if opaque { 3 } else { 4 };
    Ok(numpy::PyArray1::from_vec(py, bytes)
        .reshape([h, w, channels])?
        .into_any())
}

/// Reads an EXR into a dict: `kind` is "retina" (with the retina's arrays and `camera`) or
/// "picture" (`rgba` (H, W, 4) and optional `depth`).
#[pyfunction]
fn read_exr(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyDict>> {
    let contents = py.detach(|| files::read_exr(&path)).map_err(to_py_err)?;
    let d = PyDict::new(py);
    match contents {
        ExrContents::Retina(r, camera) => {
            let d = crate::scene::retina_dict(py, r)?;
            d.set_item("kind", "retina")?;
            d.set_item("camera", camera)?;
            return Ok(d);
        }
        ExrContents::Picture(p) => {
            d.set_item("kind", "picture")?;
            d.set_item(
                "rgba",
                PyArray1::from_vec(py, p.rgba).reshape(vec![p.height, p.width, 4])?,
            )?;
            if let Some(z) = p.depth {
                d.set_item(
                    "depth",
                    PyArray1::from_vec(py, z).reshape(vec![p.height, p.width])?,
                )?;
            }
        }
    }
    Ok(d)
}

/// Adds the file functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(write_retina_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_picture_exr, m)?)?;
    m.add_function(wrap_pyfunction!(to_srgb8, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    Ok(())
}
