//! Kernels behind `ndtrace.rotation`: flat C-contiguous float64 buffers (plus `dim` and the
//! sizes the core cannot infer) in, a flat float64 array out (reshaped by the Python wrapper).
//! Every check lives in the core's `ndtrace::batch::rotation`.

use crate::buffers::{flat, run, Arr, Out};
use crate::errors::to_py_err;
use ndtrace::batch::rotation as batch;
use ndtrace::rotation::RollingAngle;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

#[pyfunction]
fn plane<'py>(py: Python<'py>, dim: usize, i: usize, j: usize, theta: Arr<'py>) -> Out<'py> {
    let t = flat(&theta, "theta")?;
    run(py, t.len() * dim * dim, |o| {
        batch::plane_rotation(dim, i, j, t, o)
    })
}

#[pyfunction]
fn compose<'py>(
    py: Python<'py>,
    dim: usize,
    k: usize,
    batch: usize,
    rotations: Arr<'py>,
) -> Out<'py> {
    let r = flat(&rotations, "rotations")?;
    run(py, batch * dim * dim, |o| batch::compose(dim, k, r, o))
}

#[pyfunction]
fn rolling_ball<'py>(
    py: Python<'py>,
    dim: usize,
    displacement: Arr<'py>,
    radius: f64,
    angle: &str,
) -> Out<'py> {
    let angle = match angle {
        "course" => RollingAngle::Course,
        "arc" => RollingAngle::Arc,
        other => {
            return Err(PyValueError::new_err(format!(
                "angle: expected \"course\" or \"arc\", got {other:?}"
            )))
        }
    };
    let d = flat(&displacement, "displacement")?;
    let items = d.len() / dim.saturating_sub(1).max(1);
    run(py, items * dim * dim, |o| {
        batch::rolling_ball(dim, d, radius, angle, o)
    })
}

#[pyfunction]
fn frame<'py>(py: Python<'py>, dim: usize, k: usize, batch: usize, vectors: Arr<'py>) -> Out<'py> {
    let v = flat(&vectors, "vectors")?;
    run(py, batch * dim * dim, |o| batch::frame(dim, k, v, o))
}

#[pyfunction]
fn rotation_between<'py>(py: Python<'py>, dim: usize, a: Arr<'py>, b: Arr<'py>) -> Out<'py> {
    let (a, b) = (flat(&a, "a")?, flat(&b, "b")?);
    run(py, a.len() * dim, |o| batch::rotation_between(dim, a, b, o))
}

/// Raises ValueError `<arg>: not a unit <what> …` unless every `width`-float item is a unit
/// vector to `UNIT_TOLERANCE`.
#[pyfunction]
fn check_units(arg: &str, buf: Arr<'_>, width: usize, what: &str) -> PyResult<()> {
    batch::check_units(arg, flat(&buf, arg)?, width, what).map_err(to_py_err)
}

/// Raises ValueError naming `arg` unless every `(dim, dim)` item is a rotation.
#[pyfunction]
fn check_rotations(arg: &str, dim: usize, buf: Arr<'_>) -> PyResult<()> {
    batch::check_rotations(arg, dim, flat(&buf, arg)?).map_err(to_py_err)
}

#[pyfunction]
fn look_at<'py>(
    py: Python<'py>,
    dim: usize,
    position: Arr<'py>,
    target: Arr<'py>,
    up: Arr<'py>,
) -> Out<'py> {
    let (p, t, u) = (
        flat(&position, "position")?,
        flat(&target, "target")?,
        flat(&up, "up")?,
    );
    run(py, dim * dim, |o| batch::look_at(dim, p, t, u, o))
}

#[pyfunction]
fn slerp<'py>(py: Python<'py>, dim: usize, a: Arr<'py>, b: Arr<'py>, t: Arr<'py>) -> Out<'py> {
    let (a, b, t) = (flat(&a, "a")?, flat(&b, "b")?, flat(&t, "t")?);
    run(py, a.len() * t.len(), |o| batch::slerp(dim, a, b, t, o))
}

#[pyfunction]
fn to_nested_spheres<'py>(py: Python<'py>, dim: usize, rotations: Arr<'py>) -> Out<'py> {
    let r = flat(&rotations, "R")?;
    let items = r.len() / (dim * dim).max(1);
    let w = ndtrace::rotation::nested_sphere_floats(dim);
    run(py, items * w, |o| batch::to_nested_spheres(dim, r, o))
}

#[pyfunction]
fn from_nested_spheres<'py>(py: Python<'py>, dim: usize, packed: Arr<'py>) -> Out<'py> {
    let p = flat(&packed, "vectors")?;
    let w = ndtrace::rotation::nested_sphere_floats(dim).max(1);
    run(py, p.len() / w * dim * dim, |o| {
        batch::from_nested_spheres(dim, p, o)
    })
}

#[pyfunction]
fn nested_slerp<'py>(
    py: Python<'py>,
    dim: usize,
    r0: Arr<'py>,
    r1: Arr<'py>,
    t: Arr<'py>,
) -> Out<'py> {
    let (a, b, t) = (flat(&r0, "R0")?, flat(&r1, "R1")?, flat(&t, "t")?);
    run(py, t.len() * dim * dim, |o| {
        batch::nested_slerp(dim, a, b, t, o)
    })
}

#[pyfunction]
fn quat_multiply<'py>(py: Python<'py>, a: Arr<'py>, b: Arr<'py>) -> Out<'py> {
    let (a, b) = (flat(&a, "a")?, flat(&b, "b")?);
    run(py, a.len(), |o| batch::quat_multiply(a, b, o))
}

#[pyfunction]
fn quat_conjugate<'py>(py: Python<'py>, q: Arr<'py>) -> Out<'py> {
    let q = flat(&q, "q")?;
    run(py, q.len(), |o| batch::quat_conjugate(q, o))
}

#[pyfunction]
fn quat_to_matrix<'py>(py: Python<'py>, q: Arr<'py>) -> Out<'py> {
    let q = flat(&q, "q")?;
    run(py, q.len() / 4 * 9, |o| batch::quat_to_matrix(q, o))
}

#[pyfunction]
fn matrix_to_quat<'py>(py: Python<'py>, rotations: Arr<'py>, stride: usize) -> Out<'py> {
    let r = flat(&rotations, "R")?;
    run(py, r.len() / 9 * 4, |o| batch::matrix_to_quat(r, stride, o))
}

#[pyfunction]
fn so4_from_quaternions<'py>(py: Python<'py>, q: Arr<'py>, p: Arr<'py>) -> Out<'py> {
    let (q, p) = (flat(&q, "q")?, flat(&p, "p")?);
    run(py, q.len() * 4, |o| batch::so4_from_quaternions(q, p, o))
}

#[pyfunction]
fn quaternions_from_so4<'py>(py: Python<'py>, rotations: Arr<'py>) -> Out<'py> {
    let r = flat(&rotations, "R")?;
    run(py, r.len() / 2, |o| batch::quaternions_from_so4(r, o))
}

#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn slerp_so4<'py>(
    py: Python<'py>,
    q0: Arr<'py>,
    p0: Arr<'py>,
    q1: Arr<'py>,
    p1: Arr<'py>,
    t: Arr<'py>,
) -> Out<'py> {
    let (q0, p0, q1, p1, t) = (
        flat(&q0, "q0")?,
        flat(&p0, "p0")?,
        flat(&q1, "q1")?,
        flat(&p1, "p1")?,
        flat(&t, "t")?,
    );
    run(py, t.len() * 8, |o| batch::slerp_so4(q0, p0, q1, p1, t, o))
}

#[pyfunction]
fn arcball_4d<'py>(
    py: Python<'py>,
    a0: Arr<'py>,
    a1: Arr<'py>,
    b0: Arr<'py>,
    b1: Arr<'py>,
) -> Out<'py> {
    let (a0, a1, b0, b1) = (
        flat(&a0, "a0")?,
        flat(&a1, "a1")?,
        flat(&b0, "b0")?,
        flat(&b1, "b1")?,
    );
    run(py, a0.len() * 4, |o| batch::arcball_4d(a0, a1, b0, b1, o))
}

#[pyfunction]
fn quaternion_spline<'py>(
    py: Python<'py>,
    keys: Arr<'py>,
    times: Arr<'py>,
    t: Arr<'py>,
) -> Out<'py> {
    let (k, times, t) = (flat(&keys, "keys")?, flat(&times, "times")?, flat(&t, "t")?);
    run(py, t.len() * 4, |o| {
        batch::quaternion_spline(k, times, t, o)
    })
}

#[pyfunction]
fn so4_spline<'py>(
    py: Python<'py>,
    left_keys: Arr<'py>,
    right_keys: Arr<'py>,
    times: Arr<'py>,
    t: Arr<'py>,
) -> Out<'py> {
    let (l, r) = (
        flat(&left_keys, "left_keys")?,
        flat(&right_keys, "right_keys")?,
    );
    let (times, t) = (flat(&times, "times")?, flat(&t, "t")?);
    run(py, t.len() * 16, |o| batch::so4_spline(l, r, times, t, o))
}

#[pyfunction]
fn so_n_spline<'py>(
    py: Python<'py>,
    n: usize,
    keys: Arr<'py>,
    times: Arr<'py>,
    t: Arr<'py>,
) -> Out<'py> {
    let (k, times, t) = (flat(&keys, "keys")?, flat(&times, "times")?, flat(&t, "t")?);
    run(py, t.len() * n * n, |o| {
        batch::so_n_spline(n, k, times, t, o)
    })
}

/// Adds the `rotation` kernel submodule.
pub fn register(parent: &Bound<'_, PyModule>) -> PyResult<()> {
    let m = PyModule::new(parent.py(), "rotation")?;
    m.add_function(wrap_pyfunction!(plane, &m)?)?;
    m.add_function(wrap_pyfunction!(compose, &m)?)?;
    m.add_function(wrap_pyfunction!(rolling_ball, &m)?)?;
    m.add_function(wrap_pyfunction!(frame, &m)?)?;
    m.add_function(wrap_pyfunction!(rotation_between, &m)?)?;
    m.add_function(wrap_pyfunction!(check_units, &m)?)?;
    m.add_function(wrap_pyfunction!(check_rotations, &m)?)?;
    m.add("UNIT_TOLERANCE", ndtrace::rotation::UNIT_TOLERANCE)?;
    m.add(
        "SCENE_UNIT_TOLERANCE",
        ndtrace::rotation::SCENE_UNIT_TOLERANCE,
    )?;
    m.add(
        "ORTHOGONALITY_TOLERANCE",
        ndtrace::rotation::ORTHOGONALITY_TOLERANCE,
    )?;
    m.add_function(wrap_pyfunction!(look_at, &m)?)?;
    m.add_function(wrap_pyfunction!(slerp, &m)?)?;
    m.add_function(wrap_pyfunction!(to_nested_spheres, &m)?)?;
    m.add_function(wrap_pyfunction!(from_nested_spheres, &m)?)?;
    m.add_function(wrap_pyfunction!(nested_slerp, &m)?)?;
    m.add_function(wrap_pyfunction!(quat_multiply, &m)?)?;
    m.add_function(wrap_pyfunction!(quat_conjugate, &m)?)?;
    m.add_function(wrap_pyfunction!(quat_to_matrix, &m)?)?;
    m.add_function(wrap_pyfunction!(matrix_to_quat, &m)?)?;
    m.add_function(wrap_pyfunction!(so4_from_quaternions, &m)?)?;
    m.add_function(wrap_pyfunction!(quaternions_from_so4, &m)?)?;
    m.add_function(wrap_pyfunction!(slerp_so4, &m)?)?;
    m.add_function(wrap_pyfunction!(arcball_4d, &m)?)?;
    m.add_function(wrap_pyfunction!(quaternion_spline, &m)?)?;
    m.add_function(wrap_pyfunction!(so4_spline, &m)?)?;
    m.add_function(wrap_pyfunction!(so_n_spline, &m)?)?;
    parent.add_submodule(&m)?;
    Ok(())
}
