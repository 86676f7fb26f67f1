//! Kernels behind `ndtrace.mesh.feature_edges` and `ndtrace.edge_segments`.

use crate::buffers::{flat, Arr};
use crate::errors::guarded;
use ndtrace::edges::EdgeSegment;
use ndtrace::mesh::feature_edges as core_feature_edges;
use ndtrace::with_dim;
use numpy::{PyArray1, PyReadonlyArrayDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Feature edges of a flat mesh (`vertices` V·dim float64, `simplices` S·dim uint32): a flat
/// uint32 array of vertex pairs.
#[pyfunction]
fn feature_edges<'py>(
    py: Python<'py>,
    dim: usize,
    vertices: Arr<'py>,
    simplices: PyReadonlyArrayDyn<'py, u32>,
    angle: f64,
) -> PyResult<Bound<'py, PyArray1<u32>>> {
    let v = flat(&vertices, "vertices")?;
    let s = simplices
        .as_slice()
        .map_err(|_| PyValueError::new_err("simplices: expected a C-contiguous uint32 array"))?;
    let pairs = py.detach(|| {
        guarded("feature_edges", || {
            with_dim!(dim, N => {
                let verts: Vec<[f64; N]> = v
                    .chunks_exact(N)
                    .map(|c| std::array::from_fn(|k| c[k]))
                    .collect();
                let simps: Vec<[u32; N]> = s
                    .chunks_exact(N)
                    .map(|c| std::array::from_fn(|k| c[k]))
                    .collect();
                core_feature_edges(&verts, &simps, angle)
            })?
        })
    })?;
    Ok(PyArray1::from_vec(
        py,
        pairs.into_iter().flatten().collect(),
    ))
}

/// The pieces of `segments` as the dict `ndtrace.edge_segments` reshapes.
pub(crate) fn segments_dict<'py, const N: usize>(
    py: Python<'py>,
    segments: &[EdgeSegment<N>],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, visible) in [("visible", true), ("hidden", false)] {
        let pieces = segments.iter().filter(|s| s.visible == visible);
        let points: Vec<f64> = pieces
            .clone()
            .flat_map(|s| s.a.iter().chain(s.b.iter()).copied())
            .collect();
        let objects: Vec<i32> = pieces.map(|s| s.object as i32).collect();
        d.set_item(name, PyArray1::from_vec(py, points))?;
        d.set_item(format!("{name}_object"), PyArray1::from_vec(py, objects))?;
    }
    Ok(d)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(feature_edges, m)?)?;
    Ok(())
}
