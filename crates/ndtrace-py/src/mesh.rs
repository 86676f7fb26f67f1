//! Meshes: the [`MeshReader`] that the scene loaders are given (a Python callable, meshio
//! behind it, reading the mesh files the core does not read itself) and the kernel behind
//! `ndtrace.mesh.orient`.

use crate::errors::to_py_err;
use ndtrace::mesh::orientation;
use ndtrace::scene::npz::Array2;
use ndtrace::scene::MeshReader;
use numpy::{PyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::path::Path;

/// A Python callable `read(path: str, dim: int) -> (vertices (V, dim) float64, simplices
/// (S, dim) int64)`; its exceptions become the messages of scene errors.
pub(crate) struct PyMeshReader(Py<PyAny>);

impl PyMeshReader {
    pub(crate) fn new(read: Option<Bound<'_, PyAny>>) -> Option<Self> {
        read.map(|r| PyMeshReader(r.unbind()))
    }
}

fn rows<T: numpy::Element + Copy>(a: &PyReadonlyArray2<'_, T>) -> Result<Vec<T>, String> {
    a.as_array()
        .as_standard_layout()
        .as_slice()
        .map(|s| s.to_vec())
        .ok_or_else(|| "not a 2-D array".to_string())
}

impl MeshReader for PyMeshReader {
    fn read(&self, path: &Path, dim: usize) -> Result<[Array2; 2], String> {
        Python::attach(|py| {
            let message = |e: PyErr| e.value(py).to_string();
            let out = self
                .0
                .bind(py)
                .call1((path.to_string_lossy().into_owned(), dim))
                .map_err(message)?;
            let (v, s): (PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, i64>) =
                out.extract().map_err(|e: PyErr| message(e))?;
            let (vs, ss) = (v.shape().to_vec(), s.shape().to_vec());
            Ok([
                Array2 {
                    shape: (vs[0], vs[1]),
                    data: rows(&v)?,
                    integer: false,
                },
                Array2 {
                    shape: (ss[0], ss[1]),
                    data: rows(&s)?.into_iter().map(|i| i as f64).collect(),
                    integer: true,
                },
            ])
        })
    }
}

/// Which simplices to flip so that the mesh is consistently oriented, outward where closed
/// (`ndtrace.mesh.orient`; indices checked by the Python wrapper).
#[pyfunction]
fn orient_flips<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    simplices: PyReadonlyArray2<'py, u32>,
) -> PyResult<Bound<'py, PyArray1<bool>>> {
    let dim = vertices.shape()[1];
    let v = rows(&vertices).map_err(pyo3::exceptions::PyValueError::new_err)?;
    let s = rows(&simplices).map_err(pyo3::exceptions::PyValueError::new_err)?;
    let flips = py
        .detach(|| orientation::orient_rows(dim, &v, &s))
        .map_err(to_py_err)?;
    Ok(PyArray1::from_vec(py, flips))
}

/// Adds the mesh functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(orient_flips, m)?)?;
    Ok(())
}
