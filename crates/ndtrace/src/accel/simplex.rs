//! The readable ray–simplex test ([`PreparedSimplex`]) and its tolerance: the equations of the
//! module docs, one ray and one simplex at a time. Every SIMD kernel of the traversal repeats
//! this arithmetic lane by lane (see `kernels`).

use crate::geometry::{hyperplane, DEGENERACY_TOLERANCE};
use crate::linalg::{dot, inverse_rows_block, sub, Matrix, Vector};
use crate::ray::Ray;

/// Slack of the barycentric inside test: a hit needs `t_k ≥ −BARY_SLACK` for every k.
///
/// Barycentric coordinates are ratios of volumes, hence dimensionless and invariant under
/// translation, rotation and scaling, so an *absolute* slack on them is already scale-free: it
/// widens every simplex by `BARY_SLACK` times its own height over each facet, whatever the units
/// of the scene. It must exceed the rounding error of the computed `t_k`, which is about
/// `c·N·ε·D/h` for a ray travelling a distance D to a simplex of size h (ε = 2.2e-16): the hit
/// point carries an absolute error ~ε·D and `|r_k| ~ 1/h`. With 1e-9 that leaves room for
/// `D/h` up to ~10⁵ (a 10⁻⁵-sized facet seen from 1 unit away), far beyond any tessellation
/// we render, so rays aimed exactly at shared vertices, edges and ridges of a closed mesh hit
/// at least one of the simplices sharing them. The price is an overlap band of relative width
/// 1e-9 at shared boundaries, invisible and harmless (the nearer or equal-t, smaller-id simplex
/// wins). Exact ties are settled deterministically by [`Bvh::closest_hit`](super::Bvh::closest_hit).
pub const BARY_SLACK: f64 = 1e-9;

/// An (N−1)-simplex in R^N with everything the ray test needs precomputed:
/// `m[0] = n̂`, `m[k] = r_k` (k = 1 … N−1), and `x_0`. `N·(N+1)` f64s: 96 bytes in 3D,
/// 160 bytes in 4D, 576 bytes in 8D (a tree stores the rows in f32: 64 + 4 + … bytes, see
/// [`PreparedSimplex::intersect_stored`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedSimplex<const N: usize> {
    pub(super) m: Matrix<N>,
    pub(super) x0: Vector<N>,
}

/// The ray quantities the simplex test needs, computed once per ray: the ray's counterpart of
/// [`PreparedSimplex`].
#[derive(Clone, Copy)]
pub(super) struct PreparedRay<const N: usize> {
    pub(super) o: Vector<N>,
    pub(super) d: Vector<N>,
    /// `(DEGENERACY_TOLERANCE·|d|)²`: the parallel threshold for `(n̂·d)²`.
    pub(super) par2: f64,
    /// `2·2⁻²⁴·Σ|d_i|`: the bound on `|n̂·d − ñ·d|` for rows rounded to f32 (see
    /// [`PreparedSimplex::hit_rounded`]).
    pub(super) e_den: f64,
    /// `max |d_i|`.
    pub(super) d_max: f64,
    /// [`ROUNDING`]` · max |d_i|`.
    pub(super) rd_max: f64,
}

impl<const N: usize> PreparedRay<N> {
    #[inline(always)]
    pub(super) fn new(ray: &Ray<N>) -> Self {
        let d2 = dot(&ray.dir, &ray.dir);
        let d_max = ray.dir.iter().fold(0.0, |m, v| v.abs().max(m));
        PreparedRay {
            o: ray.origin,
            d: ray.dir,
            par2: DEGENERACY_TOLERANCE * DEGENERACY_TOLERANCE * d2,
            e_den: ROUNDING * sum_pairwise(ray.dir.map(f64::abs)),
            d_max,
            rd_max: ROUNDING * d_max,
        }
    }
}

impl<const N: usize> PreparedSimplex<N> {
    /// Prepares the simplex `x_0 … x_{N−1}`; `None` when it is degenerate (exactly when
    /// [`crate::geometry::hyperplane`] returns `Err`) or not finite.
    pub fn new(points: &[[f64; N]; N]) -> Option<Self> {
        let plane = hyperplane(points).ok()?;
        let x0 = points[0];
        let k = N - 1;
        let mut e = [[0.0; N]; N];
        for a in 0..k {
            e[a] = sub(&points[a + 1], &x0);
        }
        // Gram matrix G_ab = e_a·e_b in the leading k × k block.
        let mut g: Matrix<N> = [[0.0; N]; N];
        for a in 0..k {
            for b in a..k {
                let v = dot(&e[a], &e[b]);
                g[a][b] = v;
                g[b][a] = v;
            }
        }
        let mut m: Matrix<N> = [[0.0; N]; N];
        m[0] = plane.normal;
        // Row a of G⁻¹ (G is symmetric, so it is also column a) solves G·y = ê_a.
        let g_inv = inverse_rows_block(g, k)?;
        for (a, y) in g_inv.iter().enumerate().take(k) {
            // r_a = Σ_b (G⁻¹)_ab e_b: row a of (EᵀE)⁻¹Eᵀ, so that r_a·e_b = δ_ab and r_a ⊥ n̂.
            let mut r = [0.0; N];
            for b in 0..k {
                for i in 0..N {
                    r[i] += y[b] * e[b][i];
                }
            }
            m[a + 1] = r;
        }
        let finite = m.iter().flatten().chain(x0.iter()).all(|v| v.is_finite());
        finite.then_some(PreparedSimplex { m, x0 })
    }

    /// Hit with t in the open interval (tmin, tmax): `(t, [t_0 … t_{N−1}])`, the barycentric
    /// coordinates summing to 1 (each ≥ −[`BARY_SLACK`]). `None` for a miss, a ray parallel to
    /// the hyperplane, or a zero direction.
    #[inline]
    pub fn intersect(&self, ray: &Ray<N>, tmin: f64, tmax: f64) -> Option<(f64, [f64; N])> {
        self.hit(&PreparedRay::new(ray), tmin, tmax)
    }

    /// The exact ray test, which decides the lanes the block test leaves unsure (and repeated
    /// in the arithmetic of [`PreparedSimplex::hit_rounded`] on the rounded rows): pairwise dot
    /// products, and the division by `n̂·d` deferred from the inside test
    /// (`u_k = r_k·w` with `w = (n̂·p)·d − (n̂·d)·p = (n̂·d)·q`, so `t_k = u_k/(n̂·d)`).
    #[inline(always)]
    pub(super) fn hit(
        &self,
        ray: &PreparedRay<N>,
        tmin: f64,
        tmax: f64,
    ) -> Option<(f64, [f64; N])> {
        let n = &self.m[0];
        let den = dot_pairwise(n, &ray.d);
        // Parallel (|n̂·d| ≤ tol·|d|), zero or NaN direction: a miss.
        if !(den * den > ray.par2) {
            return None;
        }
        let p = sub(&self.x0, &ray.o); // x_0 − C
        let num = dot_pairwise(n, &p);
        let t = num / den;
        if !(t > tmin && t < tmax) {
            return None;
        }
        let w: Vector<N> = std::array::from_fn(|i| num * ray.d[i] - den * p[i]);
        let (abs, thr) = (den.abs(), -BARY_SLACK * den.abs());
        let mut u = [0.0; N];
        let mut sum = 0.0;
        let mut inside = true;
        for k in 1..N {
            u[k] = dot_pairwise(&self.m[k], &w);
            // u_k·sign(n̂·d) = |n̂·d|·t_k (the sign bit, as the SIMD kernels flip it).
            let v = if den.is_sign_negative() { -u[k] } else { u[k] };
            inside &= v >= thr;
            sum += v;
        }
        inside &= abs - sum >= thr;
        inside.then(|| (t, bary_from(&u, den)))
    }

    /// The ray test as a tree performs it, whose blocks store the rows rounded to f32: the
    /// hits of [`PreparedSimplex::intersect`], with t and the coordinates the rounded rows give
    /// (within ~10⁻⁷ relative of the exact ones), except near the boundary, where they are the
    /// exact ones (see `PreparedSimplex::hit_rounded` and the module docs of [`crate::accel`]).
    pub fn intersect_stored(&self, ray: &Ray<N>, tmin: f64, tmax: f64) -> Option<(f64, [f64; N])> {
        let pr = PreparedRay::new(ray);
        let r = Self::hit_rounded(&self.rounded_rows(), &self.x0, &pr, tmin, tmax);
        if r.unsure {
            self.hit(&pr, tmin, tmax)
        } else {
            r.hit.then(|| (r.t, bary_from(&r.u, r.den)))
        }
    }

    /// Unit normal: the direction of the generalized cross product of `x_1 − x_0 … x_{N−1} − x_0`
    /// (eq. 6).
    #[inline]
    pub fn normal(&self) -> [f64; N] {
        self.m[0]
    }

    /// First vertex x_0.
    #[inline]
    pub fn origin(&self) -> [f64; N] {
        self.x0
    }

    /// Offset c of the hyperplane `n̂·x = c`.
    #[inline]
    pub fn offset(&self) -> f64 {
        dot(&self.m[0], &self.x0)
    }

    /// Barycentric coordinates `t_0 … t_{N−1}` of the orthogonal projection of `x` onto the
    /// simplex's hyperplane.
    pub fn barycentric(&self, x: &Vector<N>) -> [f64; N] {
        let q = sub(x, &self.x0);
        let mut out = [0.0; N];
        let mut sum = 0.0;
        for k in 1..N {
            out[k] = dot(&self.m[k], &q);
            sum += out[k];
        }
        out[0] = 1.0 - sum;
        out
    }
}

/// How far a hit point of the tree may lie off the simplex's exact hyperplane, relative to its
/// distance from `x_0`: the relative error of the unit normal rounded to the nearest f32,
/// 2⁻²⁴ (`|δn̂·q| ≤ 2⁻²⁴·|q|`); the hit lies on the hyperplane of the rounded normal through
/// the exact `x_0`.
pub const PLANE_ROUNDING: f64 = 1.0 / (1u64 << 24) as f64;

/// A bound on the f64 rounding, in both tests, of `w = num·d − den·p` relative to its terms
/// (a few ulps, 2⁻⁵⁰).
pub(super) const F64_ROUNDING: f64 = 1.0 / (1u64 << 50) as f64;

/// Twice the relative error of a row coefficient rounded to the nearest f32 (2⁻²⁴): the factor
/// 2 covers the rounding of the f64 arithmetic of both tests, which is 2²⁹ times smaller.
pub(super) const ROUNDING: f64 = 2.0 * PLANE_ROUNDING;

/// What the test with rounded rows ([`PreparedSimplex::hit_rounded`]) says of one lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct RoundedHit<const N: usize> {
    /// A hit: the exact test ([`PreparedSimplex::hit`]) finds the ray inside, and the rounded
    /// t (the hit's, as `u`) lies in the range.
    pub(super) hit: bool,
    /// The rounding could decide either way: only the exact test can tell.
    pub(super) unsure: bool,
    pub(super) t: f64,
    pub(super) den: f64,
    pub(super) u: [f64; N],
}

impl<const N: usize> PreparedSimplex<N> {
    /// The rows rounded to the nearest f32, as the tree's blocks store them.
    pub(super) fn rounded_rows(&self) -> Matrix<N> {
        self.m.map(|row| row.map(|v| f64::from(v as f32)))
    }

    /// The ray test of [`PreparedSimplex::hit`] with the rows `m` rounded to f32 (the tree's
    /// blocks) and a certified bound on what the rounding changes. Where the bound shows that
    /// the exact test finds the ray inside the simplex and not parallel to it, the rounded
    /// rows decide: a hit when their t lies in (tmin, tmax), with their t and coordinates
    /// (within ~10⁻⁷ relative of the exact ones). Where it shows that the exact test misses,
    /// a miss. Otherwise (a ray within ~10⁻⁶ of the simplex's boundary or of parallel) the lane
    /// is `unsure` and the exact test decides: so the hits near shared ridges are exactly
    /// those of the exact test, and a closed mesh stays watertight. What a lane says does not
    /// depend on tmin and tmax beyond the range test of its t, so a closest hit is the same
    /// whatever order the tree visits the simplices in. The SIMD kernels repeat this
    /// arithmetic bit for bit.
    ///
    /// With ε = [`ROUNDING`] (2·2⁻²⁴, twice the rounding of a coefficient, which covers the
    /// second-order terms), `p = x_0 − C` and `q = X − x_0 = w/den`: `|δden| ≤ ε‖d‖₁ = e_den`
    /// (n̂ is a unit vector) and `|δnum| ≤ ε‖p‖₁ = e_num`, so the exact t is within
    /// `2(e_num + |t̃|·e_den)/(|d̃en| − e_den)` of t̃ once `|d̃en| > e_den` fixes the sign (the
    /// tests against bounds are multiplied out by `|d̃en| − e_den`, which spares divisions). Since
    /// `p = t·d − q`, `δw = δnum·d − δden·p = (δn̂·d)·q − (δn̂·q)·d`: of the size of the simplex,
    /// not of the ray's length, `|δw_i| ≤ (e_den‖w‖∞ + ε‖w‖₁‖d‖∞)/|den|`; and
    /// `|δu_k| ≤ ‖r̃_k‖₁·(ε‖w̃‖∞ + ‖δw‖∞)`, plus [`F64_ROUNDING`] of the terms `w` cancels (the f64
    /// rounding of both tests).
    #[inline(always)]
    pub(super) fn hit_rounded(
        m: &Matrix<N>,
        x0: &Vector<N>,
        ray: &PreparedRay<N>,
        tmin: f64,
        tmax: f64,
    ) -> RoundedHit<N> {
        let n = &m[0];
        let den = dot_pairwise(n, &ray.d);
        let p = sub(x0, &ray.o);
        let num = dot_pairwise(n, &p);
        let t = num / den;
        let ad = den.abs();
        let p_1 = sum_pairwise(p.map(f64::abs));
        let e_num = ROUNDING * p_1;
        let (lo, hi) = (ad - ray.e_den, ad + ray.e_den);
        let sure_sign = lo > 0.0;
        // Out of range whichever t, rounded or exact (the early return of the kernels): t̃ lies
        // `e_t = g/lo` or more beyond the range, multiplied out by lo > 0.
        let g = 2.0 * (e_num + t.abs() * ray.e_den);
        let far = sure_sign && ((tmin - t) * lo >= g || (t - tmax) * lo >= g);
        let (parallel, crossing) = (!(hi * hi > ray.par2), sure_sign && lo * lo > ray.par2);
        let w: Vector<N> = std::array::from_fn(|i| num * ray.d[i] - den * p[i]);
        let w_1 = sum_pairwise(w.map(f64::abs));
        // The bound on |δu_k| is ‖r̃_k‖₁·c/lo (with ‖·‖₁ for ‖·‖∞ in `w` and `p`); the inside
        // tests are multiplied out by lo > 0.
        let c = w_1 * (ROUNDING * lo + ray.e_den + ray.rd_max)
            + F64_ROUNDING * (num.abs() * ray.d_max + ad * p_1) * lo;
        let (thr_in, thr_out) = (-BARY_SLACK * lo * lo, -BARY_SLACK * hi * lo);
        let mut u = [0.0; N];
        let (mut sum, mut r_sum) = (0.0, 0.0);
        let (mut inside, mut outside) = (true, false);
        for k in 1..N {
            u[k] = dot_pairwise(&m[k], &w);
            let v = if den.is_sign_negative() { -u[k] } else { u[k] };
            let r_1 = sum_pairwise(m[k].map(f64::abs));
            let (vl, el) = (v * lo, r_1 * c);
            inside &= vl - el >= thr_in;
            outside |= vl + el < thr_out;
            sum += v;
            r_sum += r_1;
        }
        let (v0, e0) = ((ad - sum) * lo, r_sum * c + ray.e_den * lo);
        inside &= v0 - e0 >= thr_in;
        outside |= v0 + e0 < thr_out;
        // Decided by the rounded rows: t is the rounded t, tested against the range as is.
        let decided = crossing && inside;
        let in_range = t > tmin && t < tmax;
        let hit = decided && in_range;
        let miss = parallel || far || (sure_sign && outside) || (decided && !in_range);
        RoundedHit {
            hit,
            unsure: !hit && !miss,
            t,
            den,
            u,
        }
    }
}

/// Pairwise sum: `v[j] += v[j + ⌈m/2⌉]` halving m, the order every dot product of the ray
/// tests uses (short dependency chains, and the same bits in the scalar and the SIMD code).
#[inline(always)]
pub(super) fn sum_pairwise<const N: usize>(mut v: [f64; N]) -> f64 {
    let mut m = N;
    while m > 1 {
        let half = m.div_ceil(2);
        for j in 0..m / 2 {
            v[j] += v[j + half];
        }
        m = half;
    }
    v[0]
}

/// `a·b` summed pairwise (see [`sum_pairwise`]).
#[inline(always)]
pub(super) fn dot_pairwise<const N: usize>(a: &Vector<N>, b: &Vector<N>) -> f64 {
    sum_pairwise::<N>(std::array::from_fn(|i| a[i] * b[i]))
}

/// Barycentric coordinates from `u_k = (n̂·d)·t_k` (k ≥ 1; `u[0]` unused): `t_k = u_k/(n̂·d)`,
/// `t_0 = 1 − Σ t_k`.
#[inline(always)]
pub(super) fn bary_from<const N: usize>(u: &[f64; N], den: f64) -> [f64; N] {
    let mut b = [0.0; N];
    let mut sum = 0.0;
    for k in 1..N {
        b[k] = u[k] / den;
        sum += b[k];
    }
    b[0] = 1.0 - sum;
    b
}

/// An axis-aligned box as its (min, max) corners.
pub type Bounds<const N: usize> = ([f64; N], [f64; N]);

/// The (min, max) corners of the bounding box of the points.
pub fn simplex_bounds<const N: usize>(points: &[[f64; N]]) -> Bounds<N> {
    let mut lo = [f64::INFINITY; N];
    let mut hi = [f64::NEG_INFINITY; N];
    for p in points {
        for i in 0..N {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    (lo, hi)
}

#[cfg(test)]
mod tests;
