//! Orientation splines through keyframes (rotations paper, "the explicit 4D extension of 3D
//! quaternion orientation splines"; notes Part I(B)).
//!
//! **Quaternion splines** (SO(3), and each S³ factor of SO(4)): the Bézier construction of
//! Shoemake ("Animating rotation with quaternion curves", SIGGRAPH '85) evaluated by de
//! Casteljau's algorithm with slerps in place of lerps, with the inner control points chosen
//! as Schlag does ("Using geometric constructions to interpolate orientation with
//! quaternions", Graphics Gems II, 1991) from Catmull–Rom tangents, weighted for unequal key
//! times so that the curve is C¹ in time:
//!
//! 1. Neighbouring keys take the shorter arc: q_{i+1} → −q_{i+1} when q_i·q_{i+1} < 0.
//! 2. The body-frame angular velocity at key i is the time-weighted mean of the chords'
//!    velocities, ω_i = (Δt_i·u_{i−1}/Δt_{i−1} + Δt_{i−1}·u_i/Δt_i) / (Δt_{i−1} + Δt_i), with
//!    u_i = log(q̄_i q_{i+1}) (a pure quaternion: half the rotation vector), Δt_i = t_{i+1} − t_i;
//!    at the ends ω = the chord's u/Δt.
//! 3. Segment i is the cubic Bézier (q_i, a_i, b_i, q_{i+1}) with a_i = q_i·exp(ω_i Δt_i / 3),
//!    b_i = q_{i+1}·exp(−ω_{i+1} Δt_i / 3): its velocity at either end is 3·log(…)/Δt_i = ω,
//!    the same from both sides of a key.
//! 4. It is evaluated at u = (t − t_i)/Δt_i by de Casteljau's three levels of slerps.
//!
//! With two keys, a and b lie on the geodesic at thirds and the curve is the slerp itself.
//!
//! **SO(4)**: the double-quaternion construction of the notes: R(t) = M(q(t), p(t)), one
//! spline on each S³ factor, the pairs' signs chosen jointly (a pair (q, p) and (−q, −p) are
//! one rotation; flipping one factor alone would change it).
//!
//! **Other N (beyond the course).** The notes say explicit splines for N > 4 are unknown. As a
//! documented alternative, [`so_n_spline`] runs the same Bézier construction in SO(N) itself,
//! its geodesics R_a·exp(s·log(R_aᵀR_b)) (the bi-invariant metric's) through the matrix
//! logarithm and exponential; for N = 3 and 4 it gives the same curves as the quaternion forms
//! (the geodesics of SO(3) and of S³ × S³ are the same curves), to rounding.

use super::{quat_conjugate, quat_mul, slerp, Quat};
use crate::linalg::{cofactor_matrix, det, dot, identity, mat_mul, norm, transpose, Matrix};
use crate::{NdError, NdResult};

/// log of a unit quaternion: the pure quaternion (0, θ·n̂) of q = (cos θ, n̂ sin θ), θ ∈ [0, π].
pub fn quat_log(q: &Quat) -> Quat {
    let v = [q[1], q[2], q[3]];
    let s = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if s < 1e-300 {
        return [0.0; 4];
    }
    let theta = s.atan2(q[0]);
    let f = theta / s;
    [0.0, f * v[0], f * v[1], f * v[2]]
}

/// exp of a pure quaternion (0, θ·n̂): (cos θ, n̂ sin θ).
pub fn quat_exp(w: &Quat) -> Quat {
    let theta = (w[1] * w[1] + w[2] * w[2] + w[3] * w[3]).sqrt();
    if theta < 1e-300 {
        return [1.0, w[1], w[2], w[3]];
    }
    let f = theta.sin() / theta;
    [theta.cos(), f * w[1], f * w[2], f * w[3]]
}

/// Checks spline keys: at least two, times finite and strictly increasing (errors name
/// `times`).
pub fn check_times(times: &[f64], keys: usize) -> NdResult<()> {
    if times.len() != keys {
        return Err(NdError::Value {
            arg: "times".into(),
            message: format!("expected one time per key ({keys}), got {}", times.len()),
        });
    }
    if keys < 2 {
        return Err(NdError::Value {
            arg: "keys".into(),
            message: format!("a spline needs at least two keys, got {keys}"),
        });
    }
    if let Some(i) = times.iter().position(|t| !t.is_finite()) {
        return Err(NdError::Value {
            arg: "times".into(),
            message: format!("times[{i}] is not finite: {}", times[i]),
        });
    }
    if let Some(i) = (1..keys).find(|&i| !(times[i] > times[i - 1])) {
        return Err(NdError::Value {
            arg: "times".into(),
            message: format!(
                "must increase strictly: times[{i}] = {} follows {}",
                times[i],
                times[i - 1]
            ),
        });
    }
    Ok(())
}

/// The segment holding time t (clamped to the keys' span) and the parameter u ∈ [0, 1] in it.
fn segment(times: &[f64], t: f64) -> (usize, f64) {
    let last = times.len() - 1;
    let t = t.clamp(times[0], times[last]);
    let i = times.partition_point(|&x| x <= t).clamp(1, last) - 1;
    let u = (t - times[i]) / (times[i + 1] - times[i]);
    (i, u.clamp(0.0, 1.0))
}

/// The Bézier control points of a quaternion spline (steps 1–3): the keys with continuous
/// signs (when `shorter`), and per segment (a_i, b_i).
fn controls(keys: &[Quat], times: &[f64], shorter: bool) -> (Vec<Quat>, Vec<(Quat, Quat)>) {
    let mut q: Vec<Quat> = keys.to_vec();
    if shorter {
        super::continuous_signs(&mut q, 1);
    }
    let k = q.len();
    let dt: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let chord: Vec<Quat> = (0..k - 1)
        .map(|i| quat_log(&quat_mul(&quat_conjugate(&q[i]), &q[i + 1])))
        .collect();
    let omega: Vec<Quat> = (0..k)
        .map(|i| {
            if i == 0 {
                chord[0].map(|x| x / dt[0])
            } else if i == k - 1 {
                chord[k - 2].map(|x| x / dt[k - 2])
            } else {
                let (a, b) = (dt[i - 1], dt[i]);
                std::array::from_fn(|c| (b * chord[i - 1][c] / a + a * chord[i][c] / b) / (a + b))
            }
        })
        .collect();
    let ab = (0..k - 1)
        .map(|i| {
            let a = quat_mul(&q[i], &quat_exp(&omega[i].map(|x| x * dt[i] / 3.0)));
            let b = quat_mul(
                &q[i + 1],
                &quat_exp(&omega[i + 1].map(|x| -x * dt[i] / 3.0)),
            );
            (a, b)
        })
        .collect();
    (q, ab)
}

/// de Casteljau's algorithm with slerps (step 4).
fn casteljau(p0: &Quat, p1: &Quat, p2: &Quat, p3: &Quat, u: f64) -> Quat {
    let a = slerp(p0, p1, u);
    let b = slerp(p1, p2, u);
    let c = slerp(p2, p3, u);
    let d = slerp(&a, &b, u);
    let e = slerp(&b, &c, u);
    let q = slerp(&d, &e, u);
    let n = norm(&q);
    q.map(|x| x / n)
}

/// A C¹ quaternion spline through unit quaternions `keys` at strictly increasing `times`,
/// evaluated at each of `ts` (clamped to the keys' span); neighbours take the shorter arc when
/// `shorter`. See the module documentation.
pub fn quaternion_spline(
    keys: &[Quat],
    times: &[f64],
    ts: &[f64],
    shorter: bool,
) -> NdResult<Vec<Quat>> {
    check_times(times, keys.len())?;
    let (q, ab) = controls(keys, times, shorter);
    Ok(ts
        .iter()
        .map(|&t| {
            let (i, u) = segment(times, t);
            casteljau(&q[i], &ab[i].0, &ab[i].1, &q[i + 1], u)
        })
        .collect())
}

/// The SO(4) spline through the rotations `(left[i], right[i])` (v ↦ q·v·p̄): the pairs' signs
/// chosen jointly for the shorter way (the smaller θ_q² + θ_p² between neighbours, as
/// [`super::slerp_so4`]), then one quaternion spline per factor, as matrices.
pub fn so4_spline(
    left: &[Quat],
    right: &[Quat],
    times: &[f64],
    ts: &[f64],
) -> NdResult<Vec<Matrix<4>>> {
    if left.len() != right.len() {
        return Err(NdError::Value {
            arg: "right_keys".into(),
            message: format!(
                "expected as many keys as left_keys ({}), got {}",
                left.len(),
                right.len()
            ),
        });
    }
    let (mut l, mut r) = (left.to_vec(), right.to_vec());
    let angle = |x: &Quat, y: &Quat| {
        let c = dot(x, y);
        norm(&crate::linalg::add_scaled(y, -c, x)).atan2(c)
    };
    for i in 1..l.len() {
        let (nl, nr) = (l[i].map(|x| -x), r[i].map(|x| -x));
        let plus = angle(&l[i - 1], &l[i]).powi(2) + angle(&r[i - 1], &r[i]).powi(2);
        let minus = angle(&l[i - 1], &nl).powi(2) + angle(&r[i - 1], &nr).powi(2);
        if minus < plus {
            (l[i], r[i]) = (nl, nr);
        }
    }
    let q = quaternion_spline(&l, times, ts, false)?;
    let p = quaternion_spline(&r, times, ts, false)?;
    Ok(q.iter()
        .zip(&p)
        .map(|(q, p)| super::so4_from_quaternions(q, p))
        .collect())
}

// ---------------------------------------------------------------------------------------------
// Beyond the course: the same construction in SO(N), through the matrix log and exp
// ---------------------------------------------------------------------------------------------

fn frobenius<const N: usize>(m: &Matrix<N>) -> f64 {
    m.iter().flatten().map(|x| x * x).sum::<f64>().sqrt()
}

fn lin<const N: usize>(a: &Matrix<N>, s: f64, b: &Matrix<N>, t: f64) -> Matrix<N> {
    std::array::from_fn(|i| std::array::from_fn(|j| s * a[i][j] + t * b[i][j]))
}

fn inverse<const N: usize>(m: &Matrix<N>) -> Matrix<N> {
    let d = det(m);
    let c = transpose(&cofactor_matrix(m));
    c.map(|r| r.map(|x| x / d))
}

/// The matrix exponential of a (skew-symmetric) matrix: scaling and squaring, Taylor terms to
/// degree 18 on a matrix of norm ≤ 1/2.
pub fn expm<const N: usize>(a: &Matrix<N>) -> Matrix<N> {
    let n = frobenius(a);
    let s = if n > 0.5 {
        (n / 0.5).log2().ceil() as i32
    } else {
        0
    };
    let b = a.map(|r| r.map(|x| x / 2f64.powi(s)));
    let mut term = identity::<N>();
    let mut sum = identity::<N>();
    for k in 1..=18 {
        term = mat_mul(&term, &b).map(|r| r.map(|x| x / k as f64));
        sum = lin(&sum, 1.0, &term, 1.0);
    }
    for _ in 0..s {
        sum = mat_mul(&sum, &sum);
    }
    sum
}

/// The principal logarithm of a rotation matrix without eigenvalue −1 (a skew-symmetric
/// matrix): inverse scaling and squaring — square roots by the Denman–Beavers iteration until
/// ‖R − I‖ ≤ 1/4, the series of log(I + X), times 2^k — made exactly skew.
pub fn logm<const N: usize>(r: &Matrix<N>) -> Matrix<N> {
    let mut y = *r;
    let mut k = 0;
    while frobenius(&lin(&y, 1.0, &identity(), -1.0)) > 0.25 && k < 40 {
        let mut z = identity::<N>();
        for _ in 0..60 {
            let yi = inverse(&y);
            let zi = inverse(&z);
            let y1 = lin(&y, 0.5, &zi, 0.5);
            let z1 = lin(&z, 0.5, &yi, 0.5);
            let done = frobenius(&lin(&y1, 1.0, &y, -1.0)) <= 1e-15 * frobenius(&y1);
            (y, z) = (y1, z1);
            if done {
                break;
            }
        }
        k += 1;
    }
    let x = lin(&y, 1.0, &identity(), -1.0);
    let mut power = x;
    let mut sum = [[0.0; N]; N];
    for j in 1..=40 {
        let sign = if j % 2 == 1 { 1.0 } else { -1.0 };
        sum = lin(&sum, 1.0, &power, sign / j as f64);
        power = mat_mul(&power, &x);
    }
    let f = 2f64.powi(k);
    std::array::from_fn(|i| std::array::from_fn(|j| f * 0.5 * (sum[i][j] - sum[j][i])))
}

/// The SO(N) geodesic R_a·exp(s·log(R_aᵀ R_b)).
fn geodesic<const N: usize>(ra: &Matrix<N>, rb: &Matrix<N>, s: f64) -> Matrix<N> {
    let l = logm(&mat_mul(&transpose(ra), rb));
    mat_mul(ra, &expm(&l.map(|r| r.map(|x| x * s))))
}

/// Beyond the course: a C¹ spline through rotations `keys` of SO(N) at strictly increasing
/// `times`, evaluated at each of `ts` (clamped): the Bézier construction of the quaternion
/// spline (Catmull–Rom tangents weighted for unequal times, de Casteljau with geodesics) in
/// SO(N) itself, geodesics through the matrix log and exp. Neighbouring keys must be less than
/// a half turn apart (log(R_iᵀR_{i+1}) defined).
pub fn so_n_spline<const N: usize>(
    keys: &[Matrix<N>],
    times: &[f64],
    ts: &[f64],
) -> NdResult<Vec<Matrix<N>>> {
    check_times(times, keys.len())?;
    let k = keys.len();
    let dt: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let chord: Vec<Matrix<N>> = (0..k - 1)
        .map(|i| logm(&mat_mul(&transpose(&keys[i]), &keys[i + 1])))
        .collect();
    let omega: Vec<Matrix<N>> = (0..k)
        .map(|i| {
            if i == 0 {
                chord[0].map(|r| r.map(|x| x / dt[0]))
            } else if i == k - 1 {
                chord[k - 2].map(|r| r.map(|x| x / dt[k - 2]))
            } else {
                let (a, b) = (dt[i - 1], dt[i]);
                lin(&chord[i - 1], b / a / (a + b), &chord[i], a / b / (a + b))
            }
        })
        .collect();
    let ab: Vec<(Matrix<N>, Matrix<N>)> = (0..k - 1)
        .map(|i| {
            let a = mat_mul(
                &keys[i],
                &expm(&omega[i].map(|r| r.map(|x| x * dt[i] / 3.0))),
            );
            let b = mat_mul(
                &keys[i + 1],
                &expm(&omega[i + 1].map(|r| r.map(|x| -x * dt[i] / 3.0))),
            );
            (a, b)
        })
        .collect();
    Ok(ts
        .iter()
        .map(|&t| {
            let (i, u) = segment(times, t);
            let (p0, p1, p2, p3) = (&keys[i], &ab[i].0, &ab[i].1, &keys[i + 1]);
            let a = geodesic(p0, p1, u);
            let b = geodesic(p1, p2, u);
            let c = geodesic(p2, p3, u);
            let d = geodesic(&a, &b, u);
            let e = geodesic(&b, &c, u);
            geodesic(&d, &e, u)
        })
        .collect())
}

#[cfg(test)]
mod tests;
