//! The rotation toolkit over flat, C-ordered `f64` buffers with a runtime dimension: the layer
//! the Python bindings call (`ndtrace.rotation`). Each function checks buffer sizes and every
//! precondition of the generic functions (unit quaternions, rotations, lengths), naming the
//! argument and, for batches, the item in C order; then it dispatches on `dim` through
//! [`crate::with_dim!`]. The batch size is inferred from the buffer lengths.

use super::{as_matrices, as_matrices_mut, as_vectors, batch_len, check_len};
use crate::linalg::Matrix;
use crate::rotation::{self, *};
use crate::{with_dim, NdError, NdResult};

fn with_index(message: String, index: usize, batch: usize) -> String {
    if batch > 1 {
        format!("{message} at batch index {index}")
    } else {
        message
    }
}

/// A core error about item `index` of a batch of `batch`, with the index added to a value
/// error's message.
fn at_index(e: NdError, index: usize, batch: usize) -> NdError {
    match e {
        NdError::Value { arg, message } => NdError::Value {
            arg,
            message: with_index(message, index, batch),
        },
        other => other,
    }
}

/// Every `width`-float item of `buf` is a unit vector ("quaternion" or "vector").
fn unit_items(arg: &str, buf: &[f64], width: usize, what: &str) -> NdResult<()> {
    let batch = buf.len() / width;
    for (i, v) in buf.chunks_exact(width).enumerate() {
        if let Some(m) = unit_problem(v, what, arg) {
            return Err(NdError::Value {
                arg: arg.into(),
                message: with_index(m, i, batch),
            });
        }
    }
    Ok(())
}

fn as_quats(flat: &[f64]) -> &[Quat] {
    flat.as_chunks::<4>().0
}

/// Every matrix of `mats` is a rotation.
fn rotation_items<const N: usize>(arg: &str, mats: &[Matrix<N>]) -> NdResult<()> {
    for (i, m) in mats.iter().enumerate() {
        if let Some(message) = rotation_problem(m) {
            return Err(NdError::Value {
                arg: arg.into(),
                message: with_index(message, i, mats.len()),
            });
        }
    }
    Ok(())
}

fn finite(arg: &str, buf: &[f64]) -> NdResult<()> {
    match buf.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(NdError::NonFinite {
            arg: arg.into(),
            index,
            value: buf[index],
        }),
        None => Ok(()),
    }
}

/// [`plane_rotation`]`(i, j, θ)` for every θ of `thetas` (radians) → `(T, N, N)`.
pub fn plane_rotation(
    dim: usize,
    i: usize,
    j: usize,
    thetas: &[f64],
    out: &mut [f64],
) -> NdResult<()> {
    check_plane(i, j, dim).map_err(|message| NdError::Value {
        arg: "i, j".into(),
        message,
    })?;
    finite("theta", thetas)?;
    with_dim!(dim, N => {
        check_len("out", out, N * N, thetas.len(), "(N, N)")?;
        for (o, &t) in as_matrices_mut::<N>(out).iter_mut().zip(thetas) {
            *o = rotation::plane_rotation::<N>(i, j, t);
        }
        Ok(())
    })?
}

/// [`compose`] of `(B, K, N, N)` rotations → `(B, N, N)` (B from `out`); each input must be a
/// rotation.
pub fn compose(dim: usize, k: usize, rotations: &[f64], out: &mut [f64]) -> NdResult<()> {
    with_dim!(dim, N => {
        let b = out.len() / (N * N);
        check_len("out", out, N * N, b, "(N, N)")?;
        check_len("rotations", rotations, k * N * N, b, "(K, N, N)")?;
        let mats = as_matrices::<N>(rotations);
        rotation_items("rotations", mats)?;
        for (idx, o) in as_matrices_mut::<N>(out).iter_mut().enumerate() {
            *o = rotation::compose(&mats[idx * k..(idx + 1) * k]);
        }
        Ok(())
    })?
}

/// [`rolling_ball`] of displacements `(B, N−1)` → `(B, N, N)`.
pub fn rolling_ball(
    dim: usize,
    displacement: &[f64],
    radius: f64,
    angle: RollingAngle,
    out: &mut [f64],
) -> NdResult<()> {
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(NdError::Value {
            arg: "radius".into(),
            message: format!("must be a positive number, got {radius}"),
        });
    }
    finite("displacement", displacement)?;
    with_dim!(dim, N => {
        let b = batch_len("displacement", displacement, N - 1, "(N−1,)")?;
        check_len("out", out, N * N, b, "(N, N)")?;
        for (o, d) in as_matrices_mut::<N>(out).iter_mut().zip(displacement.chunks_exact(N - 1)) {
            *o = rotation::rolling_ball::<N>(d, radius, angle);
        }
        Ok(())
    })?
}

/// [`frame`] of `(B, K, N)` vectors → `(B, N, N)` (B from `out`).
pub fn frame(dim: usize, k: usize, vectors: &[f64], out: &mut [f64]) -> NdResult<()> {
    with_dim!(dim, N => {
        if k > N {
            return Err(NdError::Shape {
                arg: "vectors".into(),
                expected: format!("(..., K, {N}) with K ≤ {N}"),
                got: format!("K = {k}"),
            });
        }
        let b = out.len() / (N * N);
        check_len("vectors", vectors, k * N, b, "(K, N)")?;
        check_len("out", out, N * N, b, "(N, N)")?;
        let vs = as_vectors::<N>(vectors);
        for (idx, o) in as_matrices_mut::<N>(out).iter_mut().enumerate() {
            *o = rotation::frame(&vs[idx * k..(idx + 1) * k]).map_err(|e| at_index(e, idx, b))?;
        }
        Ok(())
    })?
}

/// [`rotation_between`] of unit vectors `a`, `b` `(B, N)` → `(B, N, N)`: the minimal rotation
/// taking each a to its b (antipodal pairs turn in the plane of a and its least aligned axis).
pub fn rotation_between(dim: usize, a: &[f64], b: &[f64], out: &mut [f64]) -> NdResult<()> {
    with_dim!(dim, N => {
        let n = batch_len("a", a, N, "(N,)")?;
        check_len("b", b, N, n, "(N,)")?;
        check_len("out", out, N * N, n, "(N, N)")?;
        unit_items("a", a, N, "vector")?;
        unit_items("b", b, N, "vector")?;
        let (av, bv) = (as_vectors::<N>(a), as_vectors::<N>(b));
        for ((o, x), y) in as_matrices_mut::<N>(out).iter_mut().zip(av).zip(bv) {
            *o = rotation::rotation_between(x, y);
        }
        Ok(())
    })?
}

/// Checks that every `width`-float item of `buf` is a unit vector (to [`UNIT_TOLERANCE`]); the
/// error names `arg` and the item: the check of the Python modules' unit arguments.
pub fn check_units(arg: &str, buf: &[f64], width: usize, what: &str) -> NdResult<()> {
    batch_len(arg, buf, width, &format!("({width},)"))?;
    unit_items(arg, buf, width, what)
}

/// Checks that every `(N, N)` matrix of `buf` is a rotation ([`rotation_problem`]); the error
/// names `arg` and the item.
pub fn check_rotations(arg: &str, dim: usize, buf: &[f64]) -> NdResult<()> {
    with_dim!(dim, N => {
        batch_len(arg, buf, N * N, "(N, N)")?;
        rotation_items(arg, as_matrices::<N>(buf))
    })?
}

/// [`look_at`]: position, target `(N,)`, up `(N−2, N)` → `(N, N)`.
pub fn look_at(
    dim: usize,
    position: &[f64],
    target: &[f64],
    up: &[f64],
    out: &mut [f64],
) -> NdResult<()> {
    finite("position", position)?;
    finite("target", target)?;
    finite("up", up)?;
    with_dim!(dim, N => {
        check_len("position", position, N, 1, "(N,)")?;
        check_len("target", target, N, 1, "(N,)")?;
        check_len("up", up, N, N - 2, "(N,)")?;
        check_len("out", out, N * N, 1, "(N, N)")?;
        let m = rotation::look_at::<N>(&as_vectors(position)[0], &as_vectors(target)[0], as_vectors(up))?;
        as_matrices_mut::<N>(out)[0] = m;
        Ok(())
    })?
}

/// [`slerp`] between unit vectors `a`, `b` `(B, N)` at every t of `ts` → `(T, B, N)`.
pub fn slerp(dim: usize, a: &[f64], b: &[f64], ts: &[f64], out: &mut [f64]) -> NdResult<()> {
    finite("t", ts)?;
    with_dim!(dim, N => {
        let n = batch_len("a", a, N, "(N,)")?;
        check_len("b", b, N, n, "(N,)")?;
        check_len("out", out, N, n * ts.len(), "(N,)")?;
        unit_items("a", a, N, "vector")?;
        unit_items("b", b, N, "vector")?;
        let (av, bv) = (as_vectors::<N>(a), as_vectors::<N>(b));
        for (o, idx) in out.chunks_exact_mut(N).zip(0..) {
            let (ti, bi) = (idx / n, idx % n);
            o.copy_from_slice(&rotation::slerp(&av[bi], &bv[bi], ts[ti]));
        }
        Ok(())
    })?
}

/// [`to_nested_spheres`] of rotations `(B, N, N)` → `(B, N(N+1)/2 − 1)`: per item the vectors
/// v_N, v_{N−1}, …, v_2 one after the other.
pub fn to_nested_spheres(dim: usize, rotations: &[f64], out: &mut [f64]) -> NdResult<()> {
    with_dim!(dim, N => {
        let b = batch_len("R", rotations, N * N, "(N, N)")?;
        let w = nested_sphere_floats(N);
        check_len("out", out, w, b, "(N(N+1)/2 − 1,)")?;
        let mats = as_matrices::<N>(rotations);
        rotation_items("R", mats)?;
        for (o, m) in out.chunks_exact_mut(w).zip(mats) {
            let flat: Vec<f64> = rotation::to_nested_spheres(m).concat();
            o.copy_from_slice(&flat);
        }
        Ok(())
    })?
}

/// [`from_nested_spheres`] of packed vectors `(B, N(N+1)/2 − 1)` → `(B, N, N)`.
pub fn from_nested_spheres(dim: usize, packed: &[f64], out: &mut [f64]) -> NdResult<()> {
    with_dim!(dim, N => {
        let w = nested_sphere_floats(N);
        let b = batch_len("vectors", packed, w, "(N(N+1)/2 − 1,)")?;
        check_len("out", out, N * N, b, "(N, N)")?;
        finite("vectors", packed)?;
        for (idx, (o, p)) in as_matrices_mut::<N>(out).iter_mut().zip(packed.chunks_exact(w)).enumerate() {
            let mut vs = Vec::with_capacity(N - 1);
            let mut at = 0;
            for k in (2..=N).rev() {
                vs.push(p[at..at + k].to_vec());
                at += k;
            }
            *o = rotation::from_nested_spheres::<N>(&vs).map_err(|e| at_index(e, idx, b))?;
        }
        Ok(())
    })?
}

/// [`nested_slerp`] between rotations `r0`, `r1` `(N, N)` at every t of `ts` → `(T, N, N)`.
pub fn nested_slerp(
    dim: usize,
    r0: &[f64],
    r1: &[f64],
    ts: &[f64],
    out: &mut [f64],
) -> NdResult<()> {
    finite("t", ts)?;
    with_dim!(dim, N => {
        check_len("R0", r0, N * N, 1, "(N, N)")?;
        check_len("R1", r1, N * N, 1, "(N, N)")?;
        check_len("out", out, N * N, ts.len(), "(N, N)")?;
        let (a, b) = (as_matrices::<N>(r0), as_matrices::<N>(r1));
        rotation_items("R0", a)?;
        rotation_items("R1", b)?;
        for (o, &t) in as_matrices_mut::<N>(out).iter_mut().zip(ts) {
            *o = rotation::nested_slerp(&a[0], &b[0], t);
        }
        Ok(())
    })?
}

/// [`quat_mul`] of `(B, 4)` by `(B, 4)` (any quaternions).
pub fn quat_multiply(a: &[f64], b: &[f64], out: &mut [f64]) -> NdResult<()> {
    let n = batch_len("a", a, 4, "(4,)")?;
    check_len("b", b, 4, n, "(4,)")?;
    check_len("out", out, 4, n, "(4,)")?;
    for ((o, x), y) in out.chunks_exact_mut(4).zip(as_quats(a)).zip(as_quats(b)) {
        o.copy_from_slice(&quat_mul(x, y));
    }
    Ok(())
}

/// [`quat_conjugate`] of `(B, 4)`.
pub fn quat_conjugate(q: &[f64], out: &mut [f64]) -> NdResult<()> {
    let n = batch_len("q", q, 4, "(4,)")?;
    check_len("out", out, 4, n, "(4,)")?;
    for (o, x) in out.chunks_exact_mut(4).zip(as_quats(q)) {
        o.copy_from_slice(&rotation::quat_conjugate(x));
    }
    Ok(())
}

/// [`quat_to_matrix`] of unit quaternions `(B, 4)` → `(B, 3, 3)`.
pub fn quat_to_matrix(q: &[f64], out: &mut [f64]) -> NdResult<()> {
    let n = batch_len("q", q, 4, "(4,)")?;
    check_len("out", out, 9, n, "(3, 3)")?;
    unit_items("q", q, 4, "quaternion")?;
    for (o, x) in as_matrices_mut::<3>(out).iter_mut().zip(as_quats(q)) {
        *o = rotation::quat_to_matrix(x);
    }
    Ok(())
}

/// [`matrix_to_quat`] of rotations `(B, 3, 3)` → `(B, 4)`; with `stride > 0` the signs are then
/// made continuous along tracks of that stride ([`continuous_signs`]).
pub fn matrix_to_quat(m: &[f64], stride: usize, out: &mut [f64]) -> NdResult<()> {
    let n = batch_len("R", m, 9, "(3, 3)")?;
    check_len("out", out, 4, n, "(4,)")?;
    let mats = as_matrices::<3>(m);
    rotation_items("R", mats)?;
    let mut qs: Vec<Quat> = mats.iter().map(rotation::matrix_to_quat).collect();
    if stride > 0 {
        continuous_signs(&mut qs, stride);
    }
    out.copy_from_slice(qs.as_flattened());
    Ok(())
}

/// [`so4_from_quaternions`] of unit `q`, `p` `(B, 4)` → `(B, 4, 4)`.
pub fn so4_from_quaternions(q: &[f64], p: &[f64], out: &mut [f64]) -> NdResult<()> {
    let n = batch_len("q", q, 4, "(4,)")?;
    check_len("p", p, 4, n, "(4,)")?;
    check_len("out", out, 16, n, "(4, 4)")?;
    unit_items("q", q, 4, "quaternion")?;
    unit_items("p", p, 4, "quaternion")?;
    for ((o, x), y) in as_matrices_mut::<4>(out)
        .iter_mut()
        .zip(as_quats(q))
        .zip(as_quats(p))
    {
        *o = rotation::so4_from_quaternions(x, y);
    }
    Ok(())
}

/// [`quaternions_from_so4`] of rotations `(B, 4, 4)` → `(B, 8)` packed as `[q…, p…]`.
pub fn quaternions_from_so4(m: &[f64], out: &mut [f64]) -> NdResult<()> {
    let n = batch_len("R", m, 16, "(4, 4)")?;
    check_len("out", out, 8, n, "(8,)")?;
    let mats = as_matrices::<4>(m);
    rotation_items("R", mats)?;
    for (o, x) in out.chunks_exact_mut(8).zip(mats) {
        let (q, p) = rotation::quaternions_from_so4(x);
        o[..4].copy_from_slice(&q);
        o[4..].copy_from_slice(&p);
    }
    Ok(())
}

/// [`slerp_so4`] from unit `(q0, p0)` to `(q1, p1)` (each `(4,)`) at every t → `(T, 8)` packed as
/// `[q…, p…]`.
pub fn slerp_so4(
    q0: &[f64],
    p0: &[f64],
    q1: &[f64],
    p1: &[f64],
    ts: &[f64],
    out: &mut [f64],
) -> NdResult<()> {
    finite("t", ts)?;
    for (arg, v) in [("q0", q0), ("p0", p0), ("q1", q1), ("p1", p1)] {
        check_len(arg, v, 4, 1, "(4,)")?;
        unit_items(arg, v, 4, "quaternion")?;
    }
    check_len("out", out, 8, ts.len(), "(8,)")?;
    let g = |v: &[f64]| -> Quat { std::array::from_fn(|i| v[i]) };
    let (q0, p0, q1, p1) = (g(q0), g(p0), g(q1), g(p1));
    for (o, &t) in out.chunks_exact_mut(8).zip(ts) {
        let (q, p) = rotation::slerp_so4((&q0, &p0), (&q1, &p1), t);
        o[..4].copy_from_slice(&q);
        o[4..].copy_from_slice(&p);
    }
    Ok(())
}

/// [`arcball_4d`] of unit quaternions `(B, 4)` each → `(B, 4, 4)`.
pub fn arcball_4d(a0: &[f64], a1: &[f64], b0: &[f64], b1: &[f64], out: &mut [f64]) -> NdResult<()> {
    let n = batch_len("a0", a0, 4, "(4,)")?;
    for (arg, v) in [("a0", a0), ("a1", a1), ("b0", b0), ("b1", b1)] {
        check_len(arg, v, 4, n, "(4,)")?;
        unit_items(arg, v, 4, "quaternion")?;
    }
    check_len("out", out, 16, n, "(4, 4)")?;
    let (a0, a1, b0, b1) = (as_quats(a0), as_quats(a1), as_quats(b0), as_quats(b1));
    for (i, o) in as_matrices_mut::<4>(out).iter_mut().enumerate() {
        *o = rotation::arcball_4d(&a0[i], &a1[i], &b0[i], &b1[i]);
    }
    Ok(())
}

/// [`spline::quaternion_spline`] through unit `keys` `(K, 4)` at `times` `(K,)`, at every t →
/// `(T, 4)`.
pub fn quaternion_spline(keys: &[f64], times: &[f64], ts: &[f64], out: &mut [f64]) -> NdResult<()> {
    finite("t", ts)?;
    batch_len("keys", keys, 4, "(K, 4)")?;
    unit_items("keys", keys, 4, "quaternion")?;
    check_len("out", out, 4, ts.len(), "(4,)")?;
    let q = rotation::spline::quaternion_spline(as_quats(keys), times, ts, true)?;
    out.copy_from_slice(q.as_flattened());
    Ok(())
}

/// [`spline::so4_spline`] through unit quaternion pairs `left`, `right` `(K, 4)` at `times`,
/// at every t → `(T, 4, 4)`.
pub fn so4_spline(
    left: &[f64],
    right: &[f64],
    times: &[f64],
    ts: &[f64],
    out: &mut [f64],
) -> NdResult<()> {
    finite("t", ts)?;
    batch_len("left_keys", left, 4, "(K, 4)")?;
    batch_len("right_keys", right, 4, "(K, 4)")?;
    unit_items("left_keys", left, 4, "quaternion")?;
    unit_items("right_keys", right, 4, "quaternion")?;
    check_len("out", out, 16, ts.len(), "(4, 4)")?;
    let m = rotation::spline::so4_spline(as_quats(left), as_quats(right), times, ts)?;
    for (o, m) in as_matrices_mut::<4>(out).iter_mut().zip(m) {
        *o = m;
    }
    Ok(())
}

/// [`spline::so_n_spline`] through rotations `keys` `(K, N, N)` at `times`, at every t →
/// `(T, N, N)`.
pub fn so_n_spline(
    dim: usize,
    keys: &[f64],
    times: &[f64],
    ts: &[f64],
    out: &mut [f64],
) -> NdResult<()> {
    finite("t", ts)?;
    with_dim!(dim, N => {
        batch_len("keys", keys, N * N, "(K, N, N)")?;
        check_len("out", out, N * N, ts.len(), "(N, N)")?;
        let k = as_matrices::<N>(keys);
        check_rotations("keys", N, keys)?;
        let m = rotation::spline::so_n_spline(k, times, ts)?;
        for (o, m) in as_matrices_mut::<N>(out).iter_mut().zip(m) {
            *o = m;
        }
    })?;
    Ok(())
}

#[cfg(test)]
mod tests;
