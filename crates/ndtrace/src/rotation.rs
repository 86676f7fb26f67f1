//! Rotations in N dimensions (course notes, Part I(B) "N-Dimensional Rotations for Computer
//! Graphics", and the rotations paper printed with them): plane rotations, the rolling ball,
//! frames from vectors, slerp, nested spheres SO(N)/SO(N−1) = S^{N−1}, quaternions in 3D and
//! double quaternions in 4D, and the 4D arcball.
//!
//! Conventions (all matrices act on column vectors, `m[row][col]`):
//! * A rotation "turns axis i toward axis j": [`plane_rotation`]`(i, j, θ)·e_i = cos θ e_i +
//!   sin θ e_j` (eq. 6, R_ij).
//! * Lists of rotations act in order, the first entry first: [`compose`]`([R_1, …, R_k]) =
//!   R_k ⋯ R_1`, like a scene's `transform` list.
//! * Columns are the new axes (notes, "Columns are Axes"): [`frame`] returns `[a_1 … a_N]`.
//! * Quaternions are `[q0, q1, q2, q3]` with q0 the scalar part; the product is the notes'
//!   `q * p` (Part II(A), "Multiplication rule").
//!
//! ```
//! use ndtrace::rotation::{compose, plane_rotation, rolling_ball, RollingAngle};
//! use ndtrace::linalg::mat_vec;
//! // Turn x toward y by 90°, then y toward z by 90°: x ends up on z.
//! let r = compose::<3>(&[plane_rotation(0, 1, 90f64.to_radians()),
//!                        plane_rotation(1, 2, 90f64.to_radians())]);
//! let x = mat_vec(&r, &[1.0, 0.0, 0.0]);
//! assert!((x[2] - 1.0).abs() < 1e-15);
//! // Rolling the 4D ball toward +x pulls the hidden axis w toward +x.
//! let m = rolling_ball::<4>(&[1.0, 0.0, 0.0], 1.0, RollingAngle::Arc);
//! assert!((m[0][3] - 1f64.sin()).abs() < 1e-15);
//! ```

use crate::camera::look_at_orientation;
use crate::linalg::{det, dot, identity, mat_mul, norm, scale, transpose, Matrix, Vector};
use crate::{NdError, NdResult};
use serde::{Deserialize, Serialize};

/// A quaternion `[q0, q1, q2, q3]`, q0 the scalar part.
pub type Quat = [f64; 4];

/// Tolerance on `| |q| − 1 |` for *computed* inputs that must be unit vectors or unit
/// quaternions: every argument of this module's API (and of `ndtrace.rotation` and
/// `ndtrace.frames` in Python). Such inputs are used as given, not renormalized.
pub const UNIT_TOLERANCE: f64 = 1e-9;
/// Tolerance on `| |q| − 1 |` for quaternions *typed by hand* into a scene file (a `rotate`
/// transform's `quaternions = [q, p]`, an animation's quaternions): `[0.7071, 0.7071, 0, 0]`
/// (|q| = 0.99999) is accepted, a typo such as `[0.65, 0.65, 0.65, 0.65]` (|q| = 1.3) is not.
/// Accepted quaternions are normalized ([`scene_quaternion`]).
pub const SCENE_UNIT_TOLERANCE: f64 = 1e-3;
/// Tolerance on the largest entry of `RᵀR − I` for inputs that must be rotations.
pub const ORTHOGONALITY_TOLERANCE: f64 = 1e-9;

// ---------------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------------

/// `|v|` when `v` is finite with `| |v| − 1 | ≤ tolerance`, else the message
/// `not a unit <what> (|<symbol>| = <len>)` (or which entry is not finite).
fn unit_length(v: &[f64], what: &str, symbol: &str, tolerance: f64) -> Result<f64, String> {
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(format!("non-finite value {} at index {i}", v[i]));
    }
    let len = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if (len - 1.0).abs() <= tolerance {
        Ok(len)
    } else {
        Err(format!("not a unit {what} (|{symbol}| = {len})"))
    }
}

/// `None` when `v` is finite with `| |v| − 1 | ≤` [`UNIT_TOLERANCE`], else the message
/// `not a unit <what> (|<symbol>| = <len>)`.
pub fn unit_problem(v: &[f64], what: &str, symbol: &str) -> Option<String> {
    unit_length(v, what, symbol, UNIT_TOLERANCE).err()
}

/// A quaternion from a scene file: accepted when finite with `| |q| − 1 | ≤`
/// [`SCENE_UNIT_TOLERANCE`] (four typed digits are enough) and returned normalized, so that
/// the rotation built from it is exactly orthogonal. The error is the message
/// `not a unit <what> (|<symbol>| = <len>)`, for the caller to prefix with the scene path.
pub fn scene_quaternion(q: &Quat, what: &str, symbol: &str) -> Result<Quat, String> {
    let len = unit_length(q, what, symbol, SCENE_UNIT_TOLERANCE)?;
    Ok(q.map(|x| x / len))
}

/// `Ok` when `i`, `j` are two different axes of R^n (numbered from 0), the plane of a plane
/// rotation R_ij; else the message `expected two different axes in 0..{n−1} (dim = n), got
/// [i, j]`.
pub fn check_plane(i: usize, j: usize, n: usize) -> Result<(), String> {
    if i < n && j < n && i != j {
        Ok(())
    } else {
        Err(format!(
            "expected two different axes in 0..{} (dim = {n}), got [{i}, {j}]",
            n.saturating_sub(1)
        ))
    }
}

/// Checks that `v` is a unit vector; the error names `arg`.
pub fn check_unit(v: &[f64], arg: &str, what: &str) -> NdResult<()> {
    match unit_problem(v, what, arg) {
        Some(message) => Err(NdError::Value {
            arg: arg.into(),
            message,
        }),
        None => Ok(()),
    }
}

/// `None` when `m` is a rotation (finite, `max|RᵀR − I| ≤` [`ORTHOGONALITY_TOLERANCE`],
/// det +1), else what is wrong.
pub fn rotation_problem<const N: usize>(m: &Matrix<N>) -> Option<String> {
    for (r, row) in m.iter().enumerate() {
        if let Some(c) = row.iter().position(|x| !x.is_finite()) {
            return Some(format!("non-finite value {} at [{r}][{c}]", row[c]));
        }
    }
    let g = mat_mul(&transpose(m), m);
    let mut err: f64 = 0.0;
    for i in 0..N {
        for j in 0..N {
            err = err.max((g[i][j] - if i == j { 1.0 } else { 0.0 }).abs());
        }
    }
    if !(err <= ORTHOGONALITY_TOLERANCE) {
        return Some(format!(
            "not orthogonal: RᵀR differs from I by {err:.3e} (tolerance {ORTHOGONALITY_TOLERANCE:.0e})"
        ));
    }
    if det(m) < 0.0 {
        return Some("is a reflection (det = −1), not a rotation (det = +1)".into());
    }
    None
}

/// Checks that `m` is a rotation; the error names `arg`.
pub fn check_rotation<const N: usize>(m: &Matrix<N>, arg: &str) -> NdResult<()> {
    match rotation_problem(m) {
        Some(message) => Err(NdError::Value {
            arg: arg.into(),
            message,
        }),
        None => Ok(()),
    }
}

// ---------------------------------------------------------------------------------------------
// Plane rotations and composition
// ---------------------------------------------------------------------------------------------

/// The course's plane rotation R_ij(θ) (rotations paper, eq. 6, "Concatenated subplane
/// rotations"): turns axis i toward axis j, `R·e_i = cos θ·e_i + sin θ·e_j`,
/// `R·e_j = −sin θ·e_i + cos θ·e_j`; the other N − 2 axes are fixed.
///
/// # Panics
/// If `i == j` or either is ≥ N (see [`check_plane`], which callers with untrusted input use
/// first).
pub fn plane_rotation<const N: usize>(i: usize, j: usize, theta: f64) -> Matrix<N> {
    if let Err(message) = check_plane(i, j, N) {
        panic!("plane_rotation: {message}");
    }
    let mut m: Matrix<N> = identity();
    let (s, c) = theta.sin_cos();
    m[i][i] = c;
    m[j][j] = c;
    m[i][j] = -s;
    m[j][i] = s;
    m
}

/// The product of a list of rotations, **the first in the list acting first**:
/// `compose([R_1, …, R_k]) = R_k ⋯ R_1` (the notes' `M = Π R_ij(θ_ij)` in list order, as in a
/// scene's `transform`). The empty list gives the identity.
pub fn compose<const N: usize>(rotations: &[Matrix<N>]) -> Matrix<N> {
    rotations.iter().fold(identity(), |acc, r| mat_mul(r, &acc))
}

/// The minimal rotation taking the unit vector `a` to the unit vector `b`: it turns `a` toward
/// `b` in their plane and fixes everything orthogonal to both ("pick two directions, rotate one
/// into the other"). For antipodal vectors (`a + b = 0`) the plane is the one of `a` and the
/// coordinate axis least aligned with it (rotation by π).
pub fn rotation_between<const N: usize>(a: &Vector<N>, b: &Vector<N>) -> Matrix<N> {
    let w: Vector<N> = std::array::from_fn(|i| a[i] + b[i]);
    if dot(&w, &w) > 0.0 {
        return two_reflections(b, &w);
    }
    two_reflections(b, &least_spanned_axis(&[*a]))
}

/// `(I − 2 b bᵀ)(I − 2 ŵ ŵᵀ)`, ŵ = w/|w|: reflecting across ŵ^⊥ and then across b^⊥. With
/// `w ∝ a + b` (or w ⊥ a when b = −a) it takes a to b; as a product of two exact reflections it
/// is orthogonal with det +1 however close a and b are to antipodal.
fn two_reflections<const N: usize>(b: &Vector<N>, w: &Vector<N>) -> Matrix<N> {
    let w = scale(w, 1.0 / norm(w));
    let bw = dot(b, &w);
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let id = if i == j { 1.0 } else { 0.0 };
            id - 2.0 * b[i] * b[j] - 2.0 * w[i] * w[j] + 4.0 * bw * b[i] * w[j]
        })
    })
}

// ---------------------------------------------------------------------------------------------
// The rolling ball
// ---------------------------------------------------------------------------------------------

/// How the rolling ball turns the controller distance r into the rolling angle θ (notes,
/// "Summary of ND Rolling").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RollingAngle {
    /// `c = R/D`, `s = r/D` with `D² = R² + r²` (the notes' default, θ = atan(r/R)).
    #[default]
    Course,
    /// `θ = r/R`: the ball rolls without slipping.
    Arc,
}

/// The N-D rolling ball M_N (rotations paper, eq. 5; notes, "Rolling Rotations in ND").
///
/// `displacement` = r·n̂ is the controller motion in the first N − 1 axes; the ball's hidden
/// "north pole" is the last axis e_N. M_N mixes e_N with n̂ and fixes every direction
/// orthogonal to both:
/// ```text
/// M_N[i][j] = δ_ij − (1 − c) n_i n_j,  M_N[i][N] = s n_i,  M_N[N][j] = −s n_j,  M_N[N][N] = c
/// ```
/// so `M_N·e_N = c e_N + s n̂`: the pole is *pulled* toward the motion, and the face of the
/// ball on the −n̂ side comes into view. It equals `R · R_N0(θ) · R⁻¹` with R any rotation of
/// the first N − 1 axes taking e_1 to n̂ and R_N0 = [`plane_rotation`]`(N−1, 0, θ)` (the notes'
/// R_0, turning the pole toward x). Zero displacement gives the identity.
///
/// Incremental motions accumulate as `M_total = M_k ⋯ M_1` (the latest on the left, see
/// [`compose`]); a small loop of the controller then rotates in the loop's plane (the
/// commutator `[R_iN, R_jN] = −R_ij` of the notes): a counterclockwise loop +e_i, +e_j, −e_i,
/// −e_j of area A (in units of R², with [`RollingAngle::Arc`]) gives
/// `plane_rotation(i, j, −A)` to second order, i.e. it turns axis j toward axis i — the
/// object turns *against* the sense of the loop.
///
/// # Panics
/// If `displacement` does not have N − 1 entries, or `radius` is not positive and finite.
pub fn rolling_ball<const N: usize>(
    displacement: &[f64],
    radius: f64,
    angle: RollingAngle,
) -> Matrix<N> {
    assert_eq!(
        displacement.len(),
        N - 1,
        "rolling_ball: displacement needs N − 1 = {} entries",
        N - 1
    );
    assert!(
        radius > 0.0 && radius.is_finite(),
        "rolling_ball: radius must be positive, got {radius}"
    );
    // r and n̂ from the displacement; scale first so that |d| cannot overflow.
    let big = displacement.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if big == 0.0 {
        return identity();
    }
    let unit: Vec<f64> = displacement.iter().map(|x| x / big).collect();
    let len = unit.iter().map(|x| x * x).sum::<f64>().sqrt();
    let r = big * len;
    let n: Vec<f64> = unit.iter().map(|x| x / len).collect();
    let (c, s) = match angle {
        RollingAngle::Course => {
            // c = R/D, s = r/D with D = hypot(R, r).
            let d = radius.hypot(r);
            (radius / d, r / d)
        }
        RollingAngle::Arc => {
            let (s, c) = (r / radius).sin_cos();
            (c, s)
        }
    };
    let last = N - 1;
    let mut m: Matrix<N> = identity();
    for i in 0..last {
        for j in 0..last {
            m[i][j] -= (1.0 - c) * n[i] * n[j];
        }
        m[i][last] = s * n[i];
        m[last][i] = -s * n[i];
    }
    m[last][last] = c;
    m
}

// ---------------------------------------------------------------------------------------------
// Frames, look_at, slerp
// ---------------------------------------------------------------------------------------------

/// The rotation whose columns are the given vectors after Gram–Schmidt ("Columns are Axes"):
/// column k is the part of `vectors[k]` orthogonal to the columns before it, normalized. With
/// K < N vectors the frame is completed by the coordinate axes that are least in the span so
/// far ([`least_spanned_axis`], lowest index on ties), and the last column's sign is chosen so
/// that det = +1. So `frame([])` and `frame([e_0])` are the identity, and `frame([a])` is
/// `[a, e, …]` with e the axis least aligned with a, orthogonalized.
///
/// Errors: more than N vectors; a non-finite vector; a vector (nearly) dependent on the ones
/// before it (residual ≤ 1e-9 of its length); N vectors forming a left-handed frame.
pub fn frame<const N: usize>(vectors: &[Vector<N>]) -> NdResult<Matrix<N>> {
    if vectors.len() > N {
        return Err(NdError::Shape {
            arg: "vectors".into(),
            expected: format!("at most {N} vectors of {N} numbers"),
            got: format!("{} vectors", vectors.len()),
        });
    }
    let mut cols: Vec<Vector<N>> = Vec::with_capacity(N);
    for (k, v) in vectors.iter().enumerate() {
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(NdError::NonFinite {
                arg: format!("vectors[{k}]"),
                index: i,
                value: v[i],
            });
        }
        let w = orthogonal_part(v, &cols);
        let l = norm(&w);
        if !(l > 1e-9 * norm(v)) || l == 0.0 {
            return Err(NdError::Value {
                arg: format!("vectors[{k}]"),
                message: "is zero or linearly dependent on the vectors before it".into(),
            });
        }
        cols.push(scale(&w, 1.0 / l));
    }
    let given = cols.len();
    while cols.len() < N {
        let next = least_spanned_axis(&cols);
        cols.push(next);
    }
    let mut m: Matrix<N> = std::array::from_fn(|r| std::array::from_fn(|c| cols[c][r]));
    if det(&m) < 0.0 {
        if given == N {
            return Err(NdError::Value {
                arg: "vectors".into(),
                message: format!(
                    "the {N} vectors form a left-handed frame (det < 0); give {} vectors to have \
                     the last axis completed with det +1",
                    N - 1
                ),
            });
        }
        for row in m.iter_mut() {
            row[N - 1] = -row[N - 1];
        }
    }
    Ok(m)
}

/// The coordinate axis least in the span of the orthonormal `axes` (fewer than N), made
/// orthogonal to them and normalized: e_k minus its projections, for the k with the largest
/// remainder, **the lowest such k on ties** (so `frame([])` and `frame([e_0])` are the
/// identity). For one unit vector a the remainder is `√(1 − a_k²)`: the axis least aligned with
/// a. This is the one fallback used wherever a direction must be completed: [`frame`]'s missing
/// columns, and the plane of [`rotation_between`] and [`slerp`] for antipodal vectors.
pub fn least_spanned_axis<const N: usize>(axes: &[Vector<N>]) -> Vector<N> {
    let mut best = ([0.0; N], -1.0);
    for k in 0..N {
        let mut e = [0.0; N];
        e[k] = 1.0;
        let w = orthogonal_part(&e, axes);
        let l = norm(&w);
        // Strictly larger: ties keep the lower index.
        if l > best.1 {
            best = (w, l);
        }
    }
    scale(&best.0, 1.0 / best.1)
}

/// `v` minus its projections on the orthonormal `axes` (modified Gram–Schmidt, done twice:
/// "twice is enough").
fn orthogonal_part<const N: usize>(v: &Vector<N>, axes: &[Vector<N>]) -> Vector<N> {
    let mut w = *v;
    for _ in 0..2 {
        for a in axes {
            w = crate::linalg::add_scaled(&w, -dot(&w, a), a);
        }
    }
    w
}

/// The camera orientation of a scene's `look_at` camera — exactly
/// [`crate::camera::look_at_orientation`]: columns u_1 … u_{N−1}, then the unit view direction
/// `(target − position)/|…|`, with `det[u_1 … u_{N−1}, −view] = +1` (so `det = −1`: a frame of
/// the camera, not a rotation). `up` holds N − 2 vectors.
pub fn look_at<const N: usize>(
    position: &Vector<N>,
    target: &Vector<N>,
    up: &[Vector<N>],
) -> NdResult<Matrix<N>> {
    if up.len() != N - 2 {
        return Err(NdError::Shape {
            arg: "up".into(),
            expected: format!("{} vectors of {N} numbers", N - 2),
            got: format!("{} vectors", up.len()),
        });
    }
    look_at_orientation(position, target, up).map_err(|bad| match bad {
        None => NdError::Value {
            arg: "target".into(),
            message: "equals position: no view direction".into(),
        },
        Some(k) => NdError::Value {
            arg: format!("up[{k}]"),
            message: "is a combination of the view direction and the up vectors before it".into(),
        },
    })
}

/// Spherical linear interpolation between unit vectors (notes, "Interpolating on Sphere"):
/// `Slerp(a, b, t) = a sin((1−t)θ)/sin θ + b sin(tθ)/sin θ`, cos θ = a·b, evaluated in the
/// equivalent well-conditioned form `cos(tθ)·a + sin(tθ)·u` with u the unit part of b
/// orthogonal to a and θ = atan2(|b − (a·b)a|, a·b). The angle from a grows as tθ (constant
/// speed); t outside [0, 1] extrapolates along the great circle. Equal vectors give a.
/// Antipodal vectors (no unique great circle) use the documented choice of
/// [`rotation_between`]: the plane of a and the coordinate axis least aligned with it.
pub fn slerp<const N: usize>(a: &Vector<N>, b: &Vector<N>, t: f64) -> Vector<N> {
    let c = dot(a, b);
    let mut u = crate::linalg::add_scaled(b, -c, a);
    let mut sin = norm(&u);
    if !(sin > 1e-15) {
        if c > 0.0 {
            return *a;
        }
        u = least_spanned_axis(&[*a]);
        sin = 0.0;
    }
    let u = scale(&u, 1.0 / norm(&u));
    let theta = sin.atan2(c);
    let (s, co) = (t * theta).sin_cos();
    std::array::from_fn(|i| co * a[i] + s * u[i])
}

// ---------------------------------------------------------------------------------------------
// Nested spheres: SO(N)/SO(N−1) = S^{N−1}
// ---------------------------------------------------------------------------------------------

/// The rotation P_k(v) of the first k axes taking the pole e_{k−1} (0-based) to the unit vector
/// v (supported on the first k coordinates), minimal: in the plane of e_{k−1} and v. For
/// v = −e_{k−1} it is the rotation by π in the plane (e_0, e_{k−1}).
fn pole_rotation<const N: usize>(v: &Vector<N>, k: usize) -> Matrix<N> {
    let pole = k - 1;
    let mut w = *v;
    // w = e_pole + v, with 1 + v_pole computed without cancellation when v_pole < 0:
    // 1 + v_p = (1 − v_p²)/(1 − v_p) = |v_⊥|²/(1 − v_p) for unit v.
    w[pole] = if v[pole] >= 0.0 {
        1.0 + v[pole]
    } else {
        let perp: f64 = (0..k).filter(|&i| i != pole).map(|i| v[i] * v[i]).sum();
        perp / (1.0 - v[pole])
    };
    if dot(&w, &w) == 0.0 {
        w = [0.0; N];
        w[0] = 1.0;
    }
    two_reflections(v, &w)
}

/// Number of floats in the nested-sphere vectors of SO(N): N + (N−1) + … + 2.
pub const fn nested_sphere_floats(n: usize) -> usize {
    n * (n + 1) / 2 - 1
}

/// The nested-sphere coordinates of a rotation (notes, "Quotient Space of Spherical
/// Rotations"): unit vectors v_N ∈ S^{N−1}, v_{N−1} ∈ S^{N−2}, …, v_2 ∈ S^1 (lengths N, N−1,
/// …, 2), N(N−1)/2 parameters in all.
///
/// Decomposition: v_N is the last column of R (where R sends the last axis). With P_N(v_N) the
/// minimal rotation taking e_N to v_N (in their plane), `P_N(v_N)ᵀ·R` fixes e_N, so it is
/// `diag(R', 1)` with R' ∈ SO(N−1); recurse on R'. Hence
/// ```text
/// R = P_N(v_N) · diag(P_{N−1}(v_{N−1}), 1) ⋯ diag(P_2(v_2), 1, …, 1).
/// ```
/// The chart is singular only where some v_k = −e_k (P is then the π rotation in the plane of
/// the first and the k-th axis). `R` is assumed to be a rotation (see [`check_rotation`]).
pub fn to_nested_spheres<const N: usize>(r: &Matrix<N>) -> Vec<Vec<f64>> {
    let mut m = *r;
    let mut out = Vec::with_capacity(N - 1);
    for k in (2..=N).rev() {
        let mut v = [0.0; N];
        for i in 0..k {
            v[i] = m[i][k - 1];
        }
        // Normalize away rounding so that P_k is built from a unit vector.
        let v = scale(&v, 1.0 / norm(&v));
        out.push(v[..k].to_vec());
        m = mat_mul(&transpose(&pole_rotation(&v, k)), &m);
    }
    out
}

/// The rotation with the given nested-sphere coordinates (inverse of [`to_nested_spheres`]):
/// `vectors[0]` has N entries, `vectors[1]` N − 1, …, the last 2; each must be a unit vector.
pub fn from_nested_spheres<const N: usize>(vectors: &[Vec<f64>]) -> NdResult<Matrix<N>> {
    if vectors.len() != N - 1 {
        return Err(NdError::Shape {
            arg: "vectors".into(),
            expected: format!("{} vectors of lengths {N}, {}, …, 2", N - 1, N - 1),
            got: format!("{} vectors", vectors.len()),
        });
    }
    for (idx, v) in vectors.iter().enumerate() {
        let k = N - idx;
        if v.len() != k {
            return Err(NdError::Shape {
                arg: format!("vectors[{idx}]"),
                expected: format!("({k},) (a point on S^{})", k - 1),
                got: format!("({},)", v.len()),
            });
        }
        check_unit(v, &format!("vectors[{idx}]"), "vector")?;
    }
    Ok(nested_product(vectors))
}

fn nested_product<const N: usize>(vectors: &[Vec<f64>]) -> Matrix<N> {
    let mut m: Matrix<N> = identity();
    for v in vectors {
        let k = v.len();
        let mut p = [0.0; N];
        p[..k].copy_from_slice(v);
        m = mat_mul(&m, &pole_rotation(&p, k));
    }
    m
}

/// Interpolation of rotations through their nested spheres: each of v_N, …, v_2 is slerped
/// from R0's to R1's ([`slerp`]) and the rotation rebuilt. t = 0 gives R0 and t = 1 gives R1;
/// the first axis moved, R·e_N, travels on a great circle at constant speed. Both inputs are
/// assumed to be rotations.
pub fn nested_slerp<const N: usize>(r0: &Matrix<N>, r1: &Matrix<N>, t: f64) -> Matrix<N> {
    let (a, b) = (to_nested_spheres(r0), to_nested_spheres(r1));
    let mid: Vec<Vec<f64>> = a
        .iter()
        .zip(&b)
        .map(|(x, y)| {
            let (mut xa, mut ya) = ([0.0; N], [0.0; N]);
            xa[..x.len()].copy_from_slice(x);
            ya[..y.len()].copy_from_slice(y);
            let v = slerp(&xa, &ya, t);
            v[..x.len()].to_vec()
        })
        .collect();
    nested_product(&mid)
}

// ---------------------------------------------------------------------------------------------
// Quaternions (3D) and double quaternions (4D)
// ---------------------------------------------------------------------------------------------

/// The quaternion product `q * p` (notes, Part II(A), "Multiplication rule").
pub fn quat_mul(q: &Quat, p: &Quat) -> Quat {
    [
        q[0] * p[0] - q[1] * p[1] - q[2] * p[2] - q[3] * p[3],
        q[0] * p[1] + q[1] * p[0] + q[2] * p[3] - q[3] * p[2],
        q[0] * p[2] + q[2] * p[0] + q[3] * p[1] - q[1] * p[3],
        q[0] * p[3] + q[3] * p[0] + q[1] * p[2] - q[2] * p[1],
    ]
}

/// The conjugate q̄ = (q0, −q1, −q2, −q3) (the inverse of a unit quaternion).
pub fn quat_conjugate(q: &Quat) -> Quat {
    [q[0], -q[1], -q[2], -q[3]]
}

/// The 3D rotation of a unit quaternion (rotations paper, eq. 9; notes, "Quaternion form in
/// 3D"): the matrix of `V ↦ q·(0, V)·q̄` on pure quaternions. `q = (cos θ/2, n̂ sin θ/2)` turns
/// by θ about n̂ (right-handed); q and −q give the same matrix.
pub fn quat_to_matrix(q: &Quat) -> Matrix<3> {
    let [q0, q1, q2, q3] = *q;
    [
        [
            q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3,
            2.0 * (q1 * q2 - q0 * q3),
            2.0 * (q1 * q3 + q0 * q2),
        ],
        [
            2.0 * (q1 * q2 + q0 * q3),
            q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3,
            2.0 * (q2 * q3 - q0 * q1),
        ],
        [
            2.0 * (q1 * q3 - q0 * q2),
            2.0 * (q2 * q3 + q0 * q1),
            q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3,
        ],
    ]
}

/// The unit quaternion of a 3D rotation, inverting eq. 9 by Shepperd's method: of
/// 4q0² = 1 + tr R and 4q_i² = 1 + 2R_ii − tr R, the largest is taken as the pivot (no
/// cancellation near 180°), the other components follow from sums and differences of
/// off-diagonal pairs. The sign is chosen with q0 ≥ 0 (rotation angle in [0, π]); at q0 = 0
/// the pivot component is positive. `m` is assumed to be a rotation.
pub fn matrix_to_quat(m: &Matrix<3>) -> Quat {
    let tr = m[0][0] + m[1][1] + m[2][2];
    let cands = [
        1.0 + tr,
        1.0 + 2.0 * m[0][0] - tr,
        1.0 + 2.0 * m[1][1] - tr,
        1.0 + 2.0 * m[2][2] - tr,
    ];
    let k = (0..4)
        .max_by(|&a, &b| cands[a].total_cmp(&cands[b]))
        .unwrap_or(0);
    // 4·q_k·q = the k-th row of the symmetric/antisymmetric combinations.
    let (s01, s02, s12) = (m[0][1] + m[1][0], m[0][2] + m[2][0], m[1][2] + m[2][1]);
    let (d1, d2, d3) = (m[2][1] - m[1][2], m[0][2] - m[2][0], m[1][0] - m[0][1]);
    let v = match k {
        0 => [cands[0], d1, d2, d3],
        1 => [d1, cands[1], s01, s02],
        2 => [d2, s01, cands[2], s12],
        _ => [d3, s02, s12, cands[3]],
    };
    let l = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let sign = if v[0] < 0.0 { -1.0 } else { 1.0 };
    std::array::from_fn(|i| sign * v[i] / l)
}

/// Makes a track of quaternions continuous: item i takes the sign with `q_i · q_{i−stride} ≥ 0`
/// (q and −q are the same rotation; notes: "choose sign … by local consistency, to get
/// continuous frames"). `stride` interleaves independent tracks.
pub fn continuous_signs(qs: &mut [Quat], stride: usize) {
    for i in stride..qs.len() {
        let prev = qs[i - stride];
        if dot(&qs[i], &prev) < 0.0 {
            qs[i] = qs[i].map(|x| -x);
        }
    }
}

/// [`matrix_to_quat`] of a sequence of rotations with signs chosen for continuity: each
/// quaternion has a non-negative dot product with the previous one (the first keeps q0 ≥ 0).
pub fn matrix_to_quat_sequence(ms: &[Matrix<3>]) -> Vec<Quat> {
    let mut qs: Vec<Quat> = ms.iter().map(matrix_to_quat).collect();
    continuous_signs(&mut qs, 1);
    qs
}

fn basis(i: usize) -> Quat {
    std::array::from_fn(|k| if k == i { 1.0 } else { 0.0 })
}

/// The 4D rotation `v ↦ q·v·p̄` on all quaternions v = (v0, v1, v2, v3) (notes, "Quaternion
/// form in 4D": every SO(4) rotation has this form, (q, p) and (−q, −p) giving the same one).
/// Column k is `q·e_k·p̄`. With p = q it fixes e_0 and its lower-right 3×3 block is eq. 9; with
/// p = 1 it is left multiplication by q, with q = 1 right multiplication by p̄. (The matrix
/// printed in the notes is `v ↦ p·v·q̄`, with a misprinted last row.)
pub fn so4_from_quaternions(q: &Quat, p: &Quat) -> Matrix<4> {
    let pc = quat_conjugate(p);
    let cols: [Quat; 4] = std::array::from_fn(|k| quat_mul(&quat_mul(q, &basis(k)), &pc));
    std::array::from_fn(|r| std::array::from_fn(|c| cols[c][r]))
}

/// The pair (q, p) with `m = `[`so4_from_quaternions`]`(q, p)`, up to the shared sign.
///
/// `m` is bilinear in (q, p): `m = Σ_ij q_i p_j C_ij` with `C_ij` the matrix of
/// `v ↦ e_i·v·ē_j`. The 16 `C_ij` are signed permutation matrices, mutually orthogonal with
/// `⟨C_ij, C_kl⟩ = 4 δ_ik δ_jl`, so the "associate matrix" `A_ij = ⟨C_ij, m⟩/4 = q_i p_j` is
/// rank one. p is its largest row normalized and q = A·p. The sign makes the largest-magnitude
/// component of q positive. `m` is assumed to be a rotation.
pub fn quaternions_from_so4(m: &Matrix<4>) -> (Quat, Quat) {
    let mut a = [[0.0; 4]; 4];
    for (i, row) in a.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            let c = so4_from_quaternions(&basis(i), &basis(j));
            *x = (0..4)
                .map(|r| (0..4).map(|k| c[r][k] * m[r][k]).sum::<f64>())
                .sum::<f64>()
                / 4.0;
        }
    }
    let i = (0..4)
        .max_by(|&x, &y| dot(&a[x], &a[x]).total_cmp(&dot(&a[y], &a[y])))
        .unwrap_or(0);
    let p = scale(&a[i], 1.0 / norm(&a[i]));
    let q = crate::linalg::mat_vec(&a, &p);
    (scale(&q, 1.0 / norm(&q)), p)
}

/// Geodesic interpolation between two 4D frames given as quaternion pairs: q and p are
/// slerped separately ([`slerp`] on S³) with the same t. Since (q1, p1) and (−q1, −p1) are the
/// same rotation, the lift of the second frame is the one with the smaller
/// `θ_q² + θ_p²` (θ_q = angle(q0, ±q1), θ_p = angle(p0, ±p1)): the short way in SO(4), with
/// one sign for the pair. t = 0 gives (q0, p0), t = 1 the chosen lift of (q1, p1).
pub fn slerp_so4(from: (&Quat, &Quat), to: (&Quat, &Quat), t: f64) -> (Quat, Quat) {
    let (q0, p0) = from;
    let (q1, p1) = to;
    let angle = |x: &Quat, y: &Quat| {
        let c = dot(x, y);
        norm(&crate::linalg::add_scaled(y, -c, x)).atan2(c)
    };
    let (nq1, np1) = (q1.map(|x| -x), p1.map(|x| -x));
    let plus = angle(q0, q1).powi(2) + angle(p0, p1).powi(2);
    let minus = angle(q0, &nq1).powi(2) + angle(p0, &np1).powi(2);
    let (q1, p1) = if minus < plus { (&nq1, &np1) } else { (q1, p1) };
    (slerp(q0, q1, t), slerp(p0, p1, t))
}

/// The 4D arcball (notes, "Arcball and Virtual Sphere Controls", "3D Arcball pairs"): two
/// pairs of points on S³ instead of Shoemake's one pair. Each pair gives an ordinary arcball
/// quaternion, `q = a1·ā0` and `p = b1·b̄0`, and the two compose into the one 4D rotation
/// [`so4_from_quaternions`]`(q, p)`: `v ↦ a1·ā0·v·b0·b̄1`.
///
/// What maps to what: the rotation takes `a0·b̄0` to `a1·b̄1`; with b0 = b1 it is left
/// multiplication by q, which takes a0 to a1 (and every v to q·v, an isoclinic rotation by the
/// arc angle). With equal pairs of pure unit quaternions (points of S² ⊂ S³) it fixes e_0 and
/// is Shoemake's 3D arcball on axes 1–3: the rotation by twice the arc a0→a1 about a0 × a1.
/// All four points are assumed to be unit quaternions.
pub fn arcball_4d(a0: &Quat, a1: &Quat, b0: &Quat, b1: &Quat) -> Matrix<4> {
    let q = quat_mul(a1, &quat_conjugate(a0));
    let p = quat_mul(b1, &quat_conjugate(b0));
    so4_from_quaternions(&q, &p)
}

pub mod spline;

#[cfg(test)]
mod tests;
