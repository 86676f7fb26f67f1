//! Meshes: the [`MeshReader`] that the scene loaders are given (a Python callable, meshio
//! behind it, reading the mesh files the core does not read itself) and the kernel behind
//! `ndtrace.mesh.orient`.

use crate::errors::guarded;
use ndtrace::mesh::elevation::{self, Field};
use ndtrace::mesh::orientation;
use ndtrace::mesh::slice;
use ndtrace::scene::npz::{self, Array2, ArrayNd};
use ndtrace::scene::MeshReader;
use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use std::path::Path;

/// A Python callable `read(path: str, dim: int) -> (vertices (V, dim) float64, simplices
/// (S, dim) int64)`; its exceptions become the messages of scene errors, except those that
/// are not an `Exception` (Ctrl-C's `KeyboardInterrupt`, `SystemExit`): the first of these is
/// kept and raised again when the load returns ([`PyMeshReader::finish`]), so that Ctrl-C
/// during a slow read stops the command as it does anywhere else.
pub(crate) struct PyMeshReader(Py<PyAny>, std::sync::Mutex<Option<PyErr>>);

impl PyMeshReader {
    pub(crate) fn new(read: Option<Bound<'_, PyAny>>) -> Option<Self> {
        read.map(|r| PyMeshReader(r.unbind(), std::sync::Mutex::new(None)))
    }

    /// The message of a reader's exception; a `BaseException` that is not an `Exception` is
    /// kept to be raised again by [`finish`](Self::finish).
    fn message(&self, py: Python<'_>, e: PyErr) -> String {
        if e.is_instance_of::<pyo3::exceptions::PyException>(py) {
            return e.value(py).to_string();
        }
        let text = e.value(py).to_string();
        let mut pending = self.1.lock().unwrap_or_else(|p| p.into_inner());
        pending.get_or_insert(e);
        format!("interrupted {text}").trim_end().to_string()
    }

    /// `result`, unless a reader was interrupted during the load: then that exception.
    pub(crate) fn finish<T>(reader: &Option<Self>, result: PyResult<T>) -> PyResult<T> {
        let pending = reader
            .as_ref()
            .and_then(|r| r.1.lock().unwrap_or_else(|p| p.into_inner()).take());
        match pending {
            Some(e) => Err(e),
            None => result,
        }
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
            let message = |e: PyErr| self.message(py, e);
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

    fn read_field(&self, path: &Path) -> Result<ArrayNd, String> {
        self.field(path)
    }
}

impl PyMeshReader {
    /// `reader.field(path)` → a 3-D float64 array (NIfTI through nibabel).
    fn field(&self, path: &Path) -> Result<ArrayNd, String> {
        Python::attach(|py| {
            let message = |e: PyErr| self.message(py, e);
            let out = self
                .0
                .bind(py)
                .call_method1("field", (path.to_string_lossy().into_owned(),))
                .map_err(message)?;
            let a: PyReadonlyArray3<'_, f64> =
                out.extract().map_err(|e| message(PyErr::from(e)))?;
            let shape = a.shape().to_vec();
            let data = a
                .as_array()
                .as_standard_layout()
                .as_slice()
                .map(|s| s.to_vec())
                .ok_or("not a 3-D array")?;
            Ok(ArrayNd {
                shape,
                data,
                integer: false,
                dtype: "<f8".into(),
            })
        })
    }
}

/// `ndtrace.mesh.elevation_map`: the vertices (V, 4), simplices (S, 4) and holes of the
/// elevation map of a C-ordered 3-D float64 field (checked by the Python wrapper).
#[pyfunction]
#[pyo3(signature = (field, extent, height))]
#[allow(clippy::type_complexity)]
fn elevation_map<'py>(
    py: Python<'py>,
    field: PyReadonlyArray3<'py, f64>,
    extent: Option<[[f64; 2]; 3]>,
    height: f64,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>, usize)> {
    let shape = field.shape();
    let shape = [shape[0], shape[1], shape[2]];
    let values = field.as_slice().map_err(|_| {
        pyo3::exceptions::PyValueError::new_err("field: expected a C-contiguous array")
    })?;
    let e = py
        .detach(|| {
            guarded("mesh.elevation_map", || {
                Ok(elevation::elevation_map::<4>(
                    &Field { values, shape },
                    extent.as_ref(),
                    height,
                ))
            })
        })?
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("field: {e}")))?;
    let v: Vec<f64> = e.mesh.vertices.iter().flatten().copied().collect();
    let s: Vec<i64> = e
        .mesh
        .simplices
        .iter()
        .flatten()
        .map(|&i| i64::from(i))
        .collect();
    let nv = e.mesh.vertices.len();
    let ns = e.mesh.simplices.len();
    Ok((
        PyArray1::from_vec(py, v).reshape([nv, 4])?,
        PyArray1::from_vec(py, s).reshape([ns, 4])?,
        e.holes,
    ))
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
    let flips = py.detach(|| guarded("mesh.orient", || orientation::orient_rows(dim, &v, &s)))?;
    Ok(PyArray1::from_vec(py, flips))
}

/// An array of an `.npy` file, or of an `.npz` archive (the array `name`, or its only one),
/// read by the core's reader as the scene loaders read them — header first, its size checked
/// by the memory guard before the data is read or inflated, an archive member's CRC-32
/// checked — as `(float64 array of the stored shape, the stored dtype, e.g. "<i8")`. Errors
/// are ValueErrors naming the file (and the array).
#[pyfunction]
#[pyo3(signature = (path, name=None))]
fn read_array<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    name: Option<String>,
) -> PyResult<(Bound<'py, PyAny>, String)> {
    let npz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npz"));
    let a = py
        .detach(|| {
            guarded("mesh.read_array", || {
                Ok(if npz {
                    npz::read_npz_array(&path, name.as_deref())
                } else {
                    npz::read_npy(&path)
                })
            })
        })?
        .map_err(pyo3::exceptions::PyValueError::new_err)?;
    let array = PyArray1::from_vec(py, a.data).reshape(a.shape)?;
    // The header writes the dtype as a Python string literal, '<i8'.
    Ok((array.into_any(), a.dtype.trim_matches('\'').to_string()))
}

/// `ndtrace.mesh.slice`'s kernel: the slice of the mesh by the hyperplane n̂·x = `offset`
/// (arrays checked by the Python wrapper): vertices (V', N−1), simplices (S', N−1), basis
/// (N−1, N), origin (N,), the `values` interpolated at the new vertices (V',) and the parent
/// simplex of each new one (S',).
#[pyfunction]
#[pyo3(signature = (vertices, simplices, normal, offset, values=None))]
#[allow(clippy::type_complexity)]
fn slice_mesh<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    simplices: PyReadonlyArray2<'py, u32>,
    normal: Vec<f64>,
    offset: f64,
    values: Option<numpy::PyReadonlyArray1<'py, f64>>,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<i64>>,
)> {
    let dim = vertices.shape()[1];
    let v = rows(&vertices).map_err(pyo3::exceptions::PyValueError::new_err)?;
    let s = rows(&simplices).map_err(pyo3::exceptions::PyValueError::new_err)?;
    let values = values.map(|a| a.as_array().to_vec());
    let r = py.detach(|| {
        guarded("mesh.slice", || {
            slice::slice_rows(dim, &v, &s, &normal, offset, values.as_deref())
        })
    })?;
    let m = dim - 1;
    let nv = r.coords.len() / m;
    let ns = r.simplices.len() / m;
    Ok((
        PyArray1::from_vec(py, r.coords).reshape([nv, m])?,
        PyArray1::from_vec(py, r.simplices.into_iter().map(i64::from).collect())
            .reshape([ns, m])?,
        PyArray1::from_vec(py, r.basis).reshape([m, dim])?,
        PyArray1::from_vec(py, r.origin),
        PyArray1::from_vec(py, r.values),
        PyArray1::from_vec(py, r.parents.into_iter().map(i64::from).collect()),
    ))
}

/// Adds the mesh functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_array, m)?)?;
    m.add_function(wrap_pyfunction!(slice_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(orient_flips, m)?)?;
    m.add_function(wrap_pyfunction!(elevation_map, m)?)?;
    Ok(())
}
