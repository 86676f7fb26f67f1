//! N-dimensional geometry of the course notes (paper "Geometry for N-Dimensional Graphics").
//!
//! Points and vectors are `[f64; N]`; a simplex is a slice of its vertices `x_0 … x_K`.
//!
//! ## Conventions
//! * Edges are `x_k − x_0`; matrices built from edges hold them as **columns**, with `x_0` the
//!   origin, exactly as eqs. 2–3 require for a consistent right-hand rule in every N.
//! * The normal of an (N−1)-simplex is the generalized cross product of its edges (eq. 6); it
//!   satisfies `det[e_1 … e_{N−1} | v] = v · N` for every v, so `det[e_1 … e_{N−1} | N] = |N|² ≥ 0`.
//! * "Above" a hyperplane is the side its normal points to: `side(x) = sign V_N(x_0 … x_{N−1}, x)`.
//!
//! ## Degenerate input
//! A simplex is *degenerate* when its K-volume is negligible against its edge lengths:
//! `W_K ≤ DEGENERACY_TOLERANCE · Π|e_k|` (W_K the parallelepiped volume, eq. 5; the ratio is 1
//! for orthogonal edges and 0 for dependent ones, and does not change under scaling). A ray or
//! segment is *parallel* to a hyperplane when `|n̂ · d| ≤ DEGENERACY_TOLERANCE · |d|`.
//! * [`generalized_cross`], [`signed_volume`], [`gram_volume`], [`transform_normal`] are always
//!   defined: degenerate input gives a zero (or near-zero) normal or volume.
//! * [`side`] returns 0 for a degenerate hyperplane (every point is "on" it).
//! * [`hyperplane`], [`point_hyperplane_distance`], [`barycentric`], [`clip_segment`] and
//!   [`ray_hyperplane`] return `Err(Degenerate)` — they have no meaningful value.

use crate::linalg::{
    add_scaled, cofactor_matrix, det_block, det_block_in_place, dot, factorial, mat_vec, minor,
    norm, scale, solve_block, sub, Matrix, Vector,
};

/// Relative tolerance below which a simplex counts as degenerate or a direction as parallel.
pub const DEGENERACY_TOLERANCE: f64 = 1e-12;

/// Why a geometric query has no meaningful answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Degenerate {
    /// The points are repeated or affinely dependent: the simplex has no volume.
    Simplex,
    /// The segment or ray is parallel to the hyperplane (or has zero length).
    Parallel,
}

impl Degenerate {
    /// A short human-readable reason.
    pub fn reason(self) -> &'static str {
        match self {
            Degenerate::Simplex => "degenerate simplex (repeated or affinely dependent points)",
            Degenerate::Parallel => "direction parallel to the hyperplane (or of zero length)",
        }
    }
}

/// The edges `x_k − x_0`, k = 1 … K, of a simplex given by its K+1 points.
#[inline]
fn edges<const N: usize>(points: &[Vector<N>], out: &mut [Vector<N>]) {
    for (k, e) in out.iter_mut().enumerate() {
        *e = sub(&points[k + 1], &points[0]);
    }
}

/// Generalized cross product of N−1 edge vectors (eq. 6): the cofactors of the last column of
/// `[x_1−x_0 … x_{N−1}−x_0 | x̂_1 … x̂_N]`, i.e. `N_i = (−1)^(i+N) det(E without row i)` with the
/// edges as columns of E.
///
/// It is orthogonal to every edge, `det[e_1 … e_{N−1} | N] = |N|² > 0` for independent edges,
/// and `|N|² = det(Gram) = ((N−1)!·V_{N−1})²` (eqs. 5 and 8). The edges e_1 … e_{N−1} give +e_N;
/// in 2D the edge (a, b) gives (−b, a). Dependent edges give the zero vector.
///
/// # Panics
/// If `edges.len() != N − 1` (a programming error; the batch layer checks shapes).
pub fn generalized_cross<const N: usize>(edges: &[Vector<N>]) -> Vector<N> {
    assert_eq!(edges.len(), N - 1, "generalized_cross needs N−1 edges");
    // In 3D and 4D the cofactors written out (the same expansion, without the pivoted
    // eliminations of the minors: the prepared simplices of big meshes spend their time here).
    if N == 3 {
        let (a, b) = (&edges[0], &edges[1]);
        return std::array::from_fn(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            a[j] * b[k] - a[k] * b[j]
        });
    }
    if N == 4 {
        let (a, b, c) = (&edges[0], &edges[1], &edges[2]);
        // det of rows r of E = [a b c], expanded along its first column.
        let det3 = |r: [usize; 3]| {
            a[r[0]] * (b[r[1]] * c[r[2]] - b[r[2]] * c[r[1]])
                - a[r[1]] * (b[r[0]] * c[r[2]] - b[r[2]] * c[r[0]])
                + a[r[2]] * (b[r[0]] * c[r[1]] - b[r[1]] * c[r[0]])
        };
        let n = [
            -det3([1, 2, 3]),
            det3([0, 2, 3]),
            -det3([0, 1, 3]),
            det3([0, 1, 2]),
        ];
        return std::array::from_fn(|i| n[i]);
    }
    // E with the edges as its first N−1 columns; column N is the slot of the unit vectors.
    let mut e: Matrix<N> = [[0.0; N]; N];
    for (c, edge) in edges.iter().enumerate() {
        for r in 0..N {
            e[r][c] = edge[r];
        }
    }
    // Expand along the last column: N_i = (−1)^(i+N) · det(minor without row i, column N).
    std::array::from_fn(|i| {
        let sign = if (i + N - 1).is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        sign * det_block(&minor(&e, N, i, N - 1), N - 1)
    })
}

/// Generalized cross product of the simplex `x_0 … x_{N−1}` (eq. 6 with edges `x_k − x_0`).
pub fn simplex_normal<const N: usize>(points: &[Vector<N>]) -> Vector<N> {
    assert_eq!(points.len(), N, "an (N−1)-simplex has N points");
    let mut e = [[0.0; N]; N];
    edges(points, &mut e[..N - 1]);
    generalized_cross(&e[..N - 1])
}

/// Signed N-volume of the N-simplex `x_0 … x_N` (eqs. 2–3):
/// `V_N = det[x_1−x_0 … x_N−x_0] / N!`. The standard simplex (origin, then the unit vectors)
/// has `+1/N!` in every N; swapping two vertices flips the sign.
pub fn signed_volume<const N: usize>(points: &[Vector<N>]) -> f64 {
    assert_eq!(points.len(), N + 1, "an N-simplex has N+1 points");
    let mut m: Matrix<N> = [[0.0; N]; N];
    for c in 0..N {
        for r in 0..N {
            m[r][c] = points[c + 1][r] - points[0][r];
        }
    }
    det_block_in_place(&mut m, N) / factorial(N)
}

/// The Gram matrix `G_ab = e_a · e_b` of K edges, in the leading K × K block.
fn gram<const N: usize>(e: &[Vector<N>]) -> Matrix<N> {
    let mut g: Matrix<N> = [[0.0; N]; N];
    for a in 0..e.len() {
        for b in a..e.len() {
            let v = dot(&e[a], &e[b]);
            g[a][b] = v;
            g[b][a] = v;
        }
    }
    g
}

/// Unsigned K-volume of the K-simplex `x_0 … x_K` in R^N, 1 ≤ K ≤ N (eqs. 4–5):
/// `V_K = √det(G) / K!` with G the Gram matrix of the edges `x_k − x_0`.
pub fn gram_volume<const N: usize>(points: &[Vector<N>]) -> f64 {
    let k = points.len() - 1;
    assert!(
        (1..=N).contains(&k),
        "a K-simplex in R^N needs 2..=N+1 points"
    );
    let mut e = [[0.0; N]; N];
    edges(points, &mut e[..k]);
    det_block_in_place(&mut gram(&e[..k]), k).max(0.0).sqrt() / factorial(k)
}

/// An oriented hyperplane `n̂ · x = c` (eq. 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hyperplane<const N: usize> {
    /// Unit normal, the direction of the generalized cross product (eq. 6).
    pub normal: Vector<N>,
    /// Offset `c = n̂ · x_0`.
    pub offset: f64,
}

impl<const N: usize> Hyperplane<N> {
    /// Signed distance `n̂ · x − c` (eq. 11 as `h = n̂·(x − x_0)`).
    #[inline]
    pub fn distance(&self, x: &Vector<N>) -> f64 {
        dot(&self.normal, x) - self.offset
    }
}

/// The hyperplane through the N points `x_0 … x_{N−1}` (eq. 1), its unit normal the direction
/// of [`generalized_cross`] of the edges, its offset `c = n̂ · x_0`.
pub fn hyperplane<const N: usize>(points: &[Vector<N>]) -> Result<Hyperplane<N>, Degenerate> {
    assert_eq!(points.len(), N, "a hyperplane needs N points");
    let normal = unit_cross(points).ok_or(Degenerate::Simplex)?;
    Ok(Hyperplane {
        normal,
        offset: dot(&normal, &points[0]),
    })
}

/// Unit edges `(x_k − x_0)/|x_k − x_0|` of a simplex, or `None` if an edge has zero (or
/// non-finite) length. Working with unit edges keeps the degeneracy measure
/// `W_K / Π|e_k|` free of overflow and underflow at any coordinate scale.
fn unit_edges<const N: usize>(points: &[Vector<N>], out: &mut [Vector<N>]) -> Option<()> {
    edges(points, out);
    for e in out.iter_mut() {
        // |e|² of moderate size: one square root (the common case, and the cheap one).
        let n2 = dot(e, e);
        if (1e-280..1e280).contains(&n2) {
            *e = scale(e, 1.0 / n2.sqrt());
            continue;
        }
        // Else scale by the largest component first so that |e| neither overflows nor underflows.
        let m = e.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        if !(m > 0.0 && m.is_finite()) {
            return None;
        }
        let s = scale(e, 1.0 / m);
        *e = scale(&s, 1.0 / norm(&s));
    }
    Some(())
}

/// The unit normal of the (N−1)-simplex `points` (the direction of eq. 6), or `None` when it
/// is degenerate: `|cross(unit edges)| = W_{N−1}/Π|e_k| ≤ DEGENERACY_TOLERANCE`.
fn unit_cross<const N: usize>(points: &[Vector<N>]) -> Option<Vector<N>> {
    let mut u = [[0.0; N]; N];
    unit_edges(points, &mut u[..N - 1])?;
    let n = generalized_cross(&u[..N - 1]);
    let len = norm(&n);
    (len > DEGENERACY_TOLERANCE).then(|| scale(&n, 1.0 / len))
}

/// Signed distance from `x` to the hyperplane of `x_0 … x_{N−1}` and the foot point (eq. 11):
/// `h = n̂·(x − x_0) = N·V_N / V_{N−1}` with V_N the signed volume of `(x_0, …, x_{N−1}, x)`, and
/// `p = x − h·n̂` (the closest point of the hyperplane).
pub fn point_hyperplane_distance<const N: usize>(
    x: &Vector<N>,
    points: &[Vector<N>],
) -> Result<(f64, Vector<N>), Degenerate> {
    let plane = hyperplane(points)?;
    let h = dot(&plane.normal, &sub(x, &points[0]));
    Ok((h, add_scaled(x, -h, &plane.normal)))
}

/// Barycentric coordinates `t_0 … t_K` of `x` with respect to the K-simplex `x_0 … x_K`,
/// K ≤ N, written into `out[..=K]` (section "Barycentric Coordinates").
///
/// Uses the invariant squared-volume (Gram/Cramer) form: `t_1 … t_K` solve
/// `Σ_b (e_a·e_b) t_b = e_a·(x − x_0)` and `t_0 = 1 − Σ t_k`. For K < N this gives the
/// coordinates of the orthogonal projection of `x` onto the simplex's affine hull.
pub fn barycentric<const N: usize>(
    x: &Vector<N>,
    points: &[Vector<N>],
    out: &mut [f64],
) -> Result<(), Degenerate> {
    let k = points.len() - 1;
    assert!(
        k <= N && out.len() > k,
        "barycentric: K ≤ N and room for K+1 coordinates"
    );
    if k == 0 {
        out[0] = 1.0;
        return Ok(());
    }
    // Solve with unit edges u_a = e_a/|e_a| (scale-free degeneracy test and conditioning):
    // x − x_0 = Σ t_a e_a = Σ (t_a |e_a|) u_a.
    let mut e = [[0.0; N]; N];
    edges(points, &mut e[..k]);
    let mut u = [[0.0; N]; N];
    unit_edges(points, &mut u[..k]).ok_or(Degenerate::Simplex)?;
    let g = gram(&u[..k]);
    // Degenerate when det G(u) = (W_K / Π|e_k|)² is negligible.
    if !(det_block(&g, k) > DEGENERACY_TOLERANCE * DEGENERACY_TOLERANCE) {
        return Err(Degenerate::Simplex);
    }
    let d = sub(x, &points[0]);
    let mut rhs = [0.0; N];
    for a in 0..k {
        rhs[a] = dot(&u[a], &d);
    }
    let s = solve_block(g, rhs, k).ok_or(Degenerate::Simplex)?;
    let mut t0 = 1.0;
    for a in 0..k {
        let t = s[a] / norm(&e[a]);
        out[a + 1] = t;
        t0 -= t;
    }
    out[0] = t0;
    Ok(())
}

/// Side of `x` relative to the hyperplane of `x_0 … x_{N−1}` (section "Clipping"): the sign of
/// `V_N(x_0, …, x_{N−1}, x)` with x last — +1 above (the side the normal points to), −1 below,
/// 0 on it (within `DEGENERACY_TOLERANCE` relative to the simplex's size and x's distance from
/// x_0), and 0 when the hyperplane is degenerate.
pub fn side<const N: usize>(x: &Vector<N>, points: &[Vector<N>]) -> i8 {
    assert_eq!(points.len(), N, "a hyperplane needs N points");
    let Some(n) = unit_cross(points) else {
        return 0;
    };
    // sign V_N = sign(N · (x − x_0)); compared with |x − x_0| to be scale-free.
    let d = sub(x, &points[0]);
    let m = d.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if !(m > 0.0) {
        return 0;
    }
    let w = dot(&n, &scale(&d, 1.0 / m));
    let dn = norm(&scale(&d, 1.0 / m));
    if w.abs() <= DEGENERACY_TOLERANCE * dn {
        0
    } else if w > 0.0 {
        1
    } else {
        -1
    }
}

/// Parameter t at which the line `x(t) = a + t·(b − a)` crosses the hyperplane of
/// `x_0 … x_{N−1}` (eq. 10): `t = n̂·(a − x_0) / n̂·(a − b)`. The segment itself crosses when
/// `0 ≤ t ≤ 1`; values outside mean the crossing lies on the line beyond the segment.
pub fn clip_segment<const N: usize>(
    a: &Vector<N>,
    b: &Vector<N>,
    points: &[Vector<N>],
) -> Result<f64, Degenerate> {
    let plane = hyperplane(points)?;
    let ab = sub(a, b);
    let den = dot(&plane.normal, &ab);
    if !(den.abs() > DEGENERACY_TOLERANCE * norm(&ab)) {
        return Err(Degenerate::Parallel);
    }
    Ok(dot(&plane.normal, &sub(a, &points[0])) / den)
}

/// Ray parameter of the hit with the hyperplane of `x_0 … x_{N−1}` (section "Ray Tracing"):
/// with `X(t) = C + t·(P − C)` and `P − C = direction`, `t = n̂·(x_0 − C) / n̂·(P − C)`.
/// t is in units of `direction` (not normalized); negative t lies behind the origin.
pub fn ray_hyperplane<const N: usize>(
    origin: &Vector<N>,
    direction: &Vector<N>,
    points: &[Vector<N>],
) -> Result<f64, Degenerate> {
    let plane = hyperplane(points)?;
    let den = dot(&plane.normal, direction);
    if !(den.abs() > DEGENERACY_TOLERANCE * norm(direction)) {
        return Err(Degenerate::Parallel);
    }
    Ok(dot(&plane.normal, &sub(&points[0], origin)) / den)
}

/// Transforms a normal by the linear map `m` ("Are Normals Vectors? Almost!"): normals are
/// pseudotensors, so the generalized cross product of the transformed edges is `cof(m)·N`, with
/// `cof(m) = det(m)·m^(−T)` the cofactor matrix. For an orthogonal R this is `det(R)·R·N`:
/// a reflection flips the normal relative to `R·N`. Defined for singular `m` too.
pub fn transform_normal<const N: usize>(m: &Matrix<N>, normal: &Vector<N>) -> Vector<N> {
    mat_vec(&cofactor_matrix(m), normal)
}

#[cfg(test)]
mod tests;
