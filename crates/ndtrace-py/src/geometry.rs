//! Kernels behind `ndtrace.geometry`: flat C-contiguous float64 buffers plus `dim` and `batch`
//! in, a flat float64 array out (reshaped by the Python wrapper).

use crate::buffers::{flat, run, Arr, Out};
use ndtrace::batch::geometry::{self as batch, OnDegenerate};
use pyo3::prelude::*;

fn on_degenerate(raise: bool) -> OnDegenerate {
    if raise {
        OnDegenerate::Error
    } else {
        OnDegenerate::Nan
    }
}

#[pyfunction]
fn generalized_cross<'py>(py: Python<'py>, dim: usize, batch: usize, edges: Arr<'py>) -> Out<'py> {
    let e = flat(&edges, "edges")?;
    run(py, batch * dim, |o| batch::generalized_cross(dim, e, o))
}

#[pyfunction]
fn signed_volume<'py>(py: Python<'py>, dim: usize, batch: usize, points: Arr<'py>) -> Out<'py> {
    let p = flat(&points, "points")?;
    run(py, batch, |o| batch::signed_volume(dim, p, o))
}

#[pyfunction]
fn gram_volume<'py>(
    py: Python<'py>,
    dim: usize,
    k: usize,
    batch: usize,
    points: Arr<'py>,
) -> Out<'py> {
    let p = flat(&points, "points")?;
    run(py, batch, |o| batch::gram_volume(dim, k, p, o))
}

#[pyfunction]
fn hyperplane<'py>(
    py: Python<'py>,
    dim: usize,
    batch: usize,
    points: Arr<'py>,
    raise_degenerate: bool,
) -> Out<'py> {
    let p = flat(&points, "points")?;
    run(py, batch * (dim + 1), |o| {
        batch::hyperplane(dim, p, o, on_degenerate(raise_degenerate))
    })
}

#[pyfunction]
fn point_hyperplane_distance<'py>(
    py: Python<'py>,
    dim: usize,
    batch: usize,
    x: Arr<'py>,
    points: Arr<'py>,
    raise_degenerate: bool,
) -> Out<'py> {
    let (x, p) = (flat(&x, "x")?, flat(&points, "points")?);
    run(py, batch * (dim + 1), |o| {
        batch::point_hyperplane_distance(dim, x, p, o, on_degenerate(raise_degenerate))
    })
}

#[pyfunction]
fn barycentric<'py>(
    py: Python<'py>,
    dim: usize,
    k: usize,
    batch: usize,
    x: Arr<'py>,
    points: Arr<'py>,
    raise_degenerate: bool,
) -> Out<'py> {
    let (x, p) = (flat(&x, "x")?, flat(&points, "points")?);
    run(py, batch * (k + 1), |o| {
        batch::barycentric(dim, k, x, p, o, on_degenerate(raise_degenerate))
    })
}

#[pyfunction]
fn side<'py>(py: Python<'py>, dim: usize, batch: usize, x: Arr<'py>, points: Arr<'py>) -> Out<'py> {
    let (x, p) = (flat(&x, "x")?, flat(&points, "points")?);
    run(py, batch, |o| batch::side(dim, x, p, o))
}

#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn clip_segment<'py>(
    py: Python<'py>,
    dim: usize,
    batch: usize,
    a: Arr<'py>,
    b: Arr<'py>,
    points: Arr<'py>,
    raise_degenerate: bool,
) -> Out<'py> {
    let (a, b, p) = (flat(&a, "a")?, flat(&b, "b")?, flat(&points, "points")?);
    run(py, batch, |o| {
        batch::clip_segment(dim, a, b, p, o, on_degenerate(raise_degenerate))
    })
}

#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn ray_hyperplane<'py>(
    py: Python<'py>,
    dim: usize,
    batch: usize,
    origin: Arr<'py>,
    direction: Arr<'py>,
    points: Arr<'py>,
    raise_degenerate: bool,
) -> Out<'py> {
    let (c, d, p) = (
        flat(&origin, "origin")?,
        flat(&direction, "direction")?,
        flat(&points, "points")?,
    );
    run(py, batch, |o| {
        batch::ray_hyperplane(dim, c, d, p, o, on_degenerate(raise_degenerate))
    })
}

#[pyfunction]
fn transform_normal<'py>(
    py: Python<'py>,
    dim: usize,
    batch: usize,
    matrix: Arr<'py>,
    normal: Arr<'py>,
) -> Out<'py> {
    let (m, n) = (flat(&matrix, "matrix")?, flat(&normal, "normal")?);
    run(py, batch * dim, |o| batch::transform_normal(dim, m, n, o))
}

/// Adds the `geometry` kernel submodule.
pub fn register(parent: &Bound<'_, PyModule>) -> PyResult<()> {
    let m = PyModule::new(parent.py(), "geometry")?;
    m.add_function(wrap_pyfunction!(generalized_cross, &m)?)?;
    m.add_function(wrap_pyfunction!(signed_volume, &m)?)?;
    m.add_function(wrap_pyfunction!(gram_volume, &m)?)?;
    m.add_function(wrap_pyfunction!(hyperplane, &m)?)?;
    m.add_function(wrap_pyfunction!(point_hyperplane_distance, &m)?)?;
    m.add_function(wrap_pyfunction!(barycentric, &m)?)?;
    m.add_function(wrap_pyfunction!(side, &m)?)?;
    m.add_function(wrap_pyfunction!(clip_segment, &m)?)?;
    m.add_function(wrap_pyfunction!(ray_hyperplane, &m)?)?;
    m.add_function(wrap_pyfunction!(transform_normal, &m)?)?;
    parent.add_submodule(&m)?;
    Ok(())
}
