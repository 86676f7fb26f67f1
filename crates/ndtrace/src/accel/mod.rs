//! Ray–simplex intersection and a bounding-volume hierarchy over (N−1)-simplices in R^N.
//!
//! ## Ray–simplex test (sections "Ray Tracing" and "Barycentric Coordinates")
//! A [`PreparedSimplex`] stores the unit normal n̂ of its hyperplane (the direction of the
//! generalized cross product of `x_1 − x_0 … x_{N−1} − x_0`, eq. 6), the N−1 rows `r_k` of the
//! pseudo-inverse `(EᵀE)⁻¹Eᵀ` of the edge matrix E (the Gram/Cramer form of the barycentric
//! coordinates) and the first vertex `x_0`. A ray `X(t) = C + t·d` then meets the simplex
//! without any per-ray solve, in O(N²):
//!
//! * `t = n̂·(x_0 − C) / n̂·d`;
//! * `t_k = r_k·(X(t) − x_0) = r_k·(C − x_0) + t·(r_k·d)` for k = 1 … N−1, `t_0 = 1 − Σ t_k`;
//! * it is a hit when t lies in the open interval `(tmin, tmax)` and every `t_k ≥ −BARY_SLACK`.
//!
//! The inside test is evaluated without waiting for the division: with `p = x_0 − C`,
//! `w = (n̂·p)·d − (n̂·d)·p = (n̂·d)·(X(t) − x_0)`, so `u_k = r_k·w = (n̂·d)·t_k` and the signs
//! are compared against `BARY_SLACK·|n̂·d|`; the coordinates `t_k = u_k/(n̂·d)` are divided out
//! only for the hit returned. Dot products are summed pairwise (short dependency chains).
//!
//! A ray is parallel to the hyperplane (and misses) when `|n̂·d| ≤ DEGENERACY_TOLERANCE·|d|`, the
//! rule of [`crate::geometry::ray_hyperplane`]. Hits are two-sided: orientation is left to shading.
//!
//! ## BVH
//! [`Bvh`] is built as a binary tree of N-D axis-aligned boxes with binned SAH (16 bins per axis
//! over the centroid bounds, leaves of at most 4 simplices, object-median split when SAH cannot
//! split or the tree gets deep), then collapsed into an 8-wide tree (the optimal collapse of
//! Ylitie et al., which minimises the summed surface measure of the wide nodes):
//!
//! * nodes (a `Vec`, depth-first order) hold the boxes of their up to 8 children as
//!   structure-of-arrays `f32` (rounded outward, so conservative), slab-tested together
//!   (SSE, or AVX2 when the CPU has it);
//! * every leaf is one *block*: its up to 4 prepared simplices stored structure-of-arrays
//!   (`[f64; 4]` per coefficient, one lane per simplex) with their ids, in leaf order, so one
//!   block test (SSE2, or one AVX2 register per coefficient) intersects the whole leaf.
//!
//! Every SIMD path performs, per lane, exactly the operations of [`PreparedSimplex::intersect`]
//! in the same order (no FMA), so all paths and the scalar test give bit-identical results.
//!
//! Traversal is nearest-first (the children met are visited in order of entry distance, and
//! subtrees whose entry lies beyond the current best hit are skipped) with an explicit
//! fixed-size stack and no heap allocation; [`Bvh::any_hit`] stops at the first accepted hit.
//!
//! Rays travel in packets of up to [`PACKET`] ([`Bvh::closest_hits`], [`Bvh::any_hits`]; the
//! one-ray calls are packets of one): a node is fetched, slab-tested for each ray of the packet
//! that reached it, and sorted once for the packet; each stack entry carries the bit set of the
//! rays that met its box (the masks of 8 rays × 8 children are transposed as an 8×8 bit
//! matrix), and every ray keeps its own best hit and culling limit. A ray is tested only
//! against the boxes its own tests led it to, and the leaf tests are exact, so every ray's
//! result is the one it gets alone — the minimum of (t, id) over its accepted hits — whichever
//! rays it travels with.
//! The build is parallel (rayon) for large inputs and produces the same tree for any number of
//! threads.

use crate::geometry::{hyperplane, DEGENERACY_TOLERANCE};
use crate::linalg::{dot, solve_block, sub, Matrix, Vector};
use crate::mesh::Mesh;
use rayon::prelude::*;
use std::mem::MaybeUninit;
use std::ops::Range;

/// The ray and hit types of the queries, re-exported from [`crate::ray`].
pub use crate::ray::{Hit, Ray};

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
/// wins). Exact ties are settled deterministically by [`Bvh::closest_hit`].
pub const BARY_SLACK: f64 = 1e-9;

/// Leaves hold at most this many simplices: the lanes of a block.
pub const MAX_LEAF: usize = W;
/// Rays traced together by [`Bvh::closest_hits`] and [`Bvh::any_hits`]: one bit each in the
/// ray masks of the traversal, transposed with the children's masks as an 8×8 bit matrix.
pub const PACKET: usize = 8;
const _: () = assert!(
    PACKET == 8 && NW == 8,
    "transpose8 needs 8 rays × 8 children"
);
/// Lanes of a block (simplices tested together).
const W: usize = 4;
/// Children of a node (boxes tested together).
const NW: usize = 8;
/// Bins per axis of the SAH build.
const BINS: usize = 16;
/// Below this depth SAH decides the binary splits; deeper, object-median splits bound the depth
/// (they halve a u32-indexed range, so the binary tree has at most `MAX_SAH_DEPTH + 33` levels).
const MAX_SAH_DEPTH: usize = 48;
/// Traversal stack size: a node pushes at most NW − 1 entries, and the wide tree is no deeper
/// than the binary one.
const STACK_SIZE: usize = (NW - 1) * (MAX_SAH_DEPTH + 34) + 2;
/// Nodes with at least this many simplices are built in parallel (the result does not depend on
/// it: see [`Bvh::build`]).
const PAR_MIN: usize = 16 * 1024;
/// Chunk size of the parallel binning passes.
const PAR_CHUNK: usize = 8 * 1024;
/// Relative widening of the parameter range used for box culling: covers the rounding of a
/// simplex's computed t (~N·ε·|x_0 − C| over the distance of C to its hyperplane), so that box
/// culling never rejects a node holding a simplex whose computed t is within range.
const T_PAD: f64 = 1e-9;
/// Relative shift of the ray origin that makes the `f32` slab test conservative (see
/// [`RayPre::new`]); 2⁻²⁰ covers the test's four roundings of ≤ 2⁻²⁴ each with a wide margin.
const SLAB_REL: f64 = 1.0 / (1u32 << 20) as f64;
/// Relative padding of each simplex's box, covering the `BARY_SLACK` band around it (a point
/// with `t_k ≥ −BARY_SLACK` is at most `BARY_SLACK·diameter` outside the simplex, and
/// `diameter ≤ √N·max extent ≤ 3·max extent`).
pub(crate) const BOX_PAD: f64 = 1e-8;
/// Child slot tag of a leaf (block index in the low bits).
const LEAF: u32 = 1 << 31;
/// An unused child slot (its box is empty, so it is never entered).
const EMPTY: u32 = u32::MAX;

/// Traversal counters: global with the feature `traversal-stats`, per thread in unit tests (so
/// that a test can check what a query visits), no-ops otherwise.
mod stats {
    #[cfg(test)]
    thread_local! {
        /// This thread's counts, as in `VISITS`.
        pub static LOCAL: std::cell::Cell<[u64; 3]> = const { std::cell::Cell::new([0; 3]) };
    }

    #[cfg(feature = "traversal-stats")]
    use std::sync::atomic::{AtomicU64, Ordering};

    /// Inner nodes visited (once per packet), leaf blocks tested (per ray), node slab tests
    /// (per ray).
    #[cfg(feature = "traversal-stats")]
    pub static VISITS: [AtomicU64; 3] = [AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0)];

    /// Counts one visit of kind `k` (0: node, 1: leaf, 2: node slab test).
    #[inline(always)]
    pub fn count(_k: usize) {
        #[cfg(feature = "traversal-stats")]
        VISITS[_k].fetch_add(1, Ordering::Relaxed);
        #[cfg(test)]
        LOCAL.with(|c| {
            let mut v = c.get();
            v[_k] += 1;
            c.set(v);
        });
    }
}

/// Inner nodes and leaf blocks visited by all traversals so far (feature `traversal-stats`).
#[cfg(feature = "traversal-stats")]
pub fn traversal_stats() -> [u64; 3] {
    use std::sync::atomic::Ordering;
    stats::VISITS.each_ref().map(|v| v.load(Ordering::Relaxed))
}

/// An (N−1)-simplex in R^N with everything the ray test needs precomputed:
/// `m[0] = n̂`, `m[k] = r_k` (k = 1 … N−1), and `x_0`. `N·(N+1)` f64s: 96 bytes in 3D,
/// 160 bytes in 4D, 576 bytes in 8D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedSimplex<const N: usize> {
    m: Matrix<N>,
    x0: Vector<N>,
}

/// The ray quantities the simplex test needs, computed once per ray.
#[derive(Clone, Copy)]
struct RayLocal<const N: usize> {
    o: Vector<N>,
    d: Vector<N>,
    /// `(DEGENERACY_TOLERANCE·|d|)²`: the parallel threshold for `(n̂·d)²`.
    par2: f64,
}

impl<const N: usize> RayLocal<N> {
    #[inline(always)]
    fn new(ray: &Ray<N>) -> Self {
        let d2 = dot(&ray.dir, &ray.dir);
        RayLocal {
            o: ray.origin,
            d: ray.dir,
            par2: DEGENERACY_TOLERANCE * DEGENERACY_TOLERANCE * d2,
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
        for a in 0..k {
            // Row a of G⁻¹ (G is symmetric, so it is also column a): G·y = ê_a.
            let mut unit = [0.0; N];
            unit[a] = 1.0;
            let y = solve_block(g, unit, k)?;
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
        self.hit(&RayLocal::new(ray), tmin, tmax)
    }

    /// The ray test, in the arithmetic shared bit for bit with the block test of the BVH:
    /// pairwise dot products, and the division by `n̂·d` deferred from the inside test
    /// (`u_k = r_k·w` with `w = (n̂·p)·d − (n̂·d)·p = (n̂·d)·q`, so `t_k = u_k/(n̂·d)`).
    #[inline(always)]
    fn hit(&self, ray: &RayLocal<N>, tmin: f64, tmax: f64) -> Option<(f64, [f64; N])> {
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

/// Pairwise sum: `v[j] += v[j + ⌈m/2⌉]` halving m, the order every dot product of the ray
/// tests uses (short dependency chains, and the same bits in the scalar and the SIMD code).
#[inline(always)]
fn sum_pairwise<const N: usize>(mut v: [f64; N]) -> f64 {
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
fn dot_pairwise<const N: usize>(a: &Vector<N>, b: &Vector<N>) -> f64 {
    sum_pairwise::<N>(std::array::from_fn(|i| a[i] * b[i]))
}

/// Barycentric coordinates from `u_k = (n̂·d)·t_k` (k ≥ 1; `u[0]` unused): `t_k = u_k/(n̂·d)`,
/// `t_0 = 1 − Σ t_k`.
#[inline(always)]
fn bary_from<const N: usize>(u: &[f64; N], den: f64) -> [f64; N] {
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

/// A wide node: the boxes of its up to `NW` children, structure-of-arrays, and the child
/// references.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
struct Node<const N: usize> {
    /// `b[0][axis][lane]` = min corner, `b[1][axis][lane]` = max corner (f32 rounded outward;
    /// +∞/−∞ for an empty slot).
    b: [[[f32; NW]; N]; 2],
    /// A node index, `LEAF | block index`, or `EMPTY`.
    child: [u32; NW],
}

impl<const N: usize> Node<N> {
    const EMPTY: Self = Node {
        b: [[[f32::INFINITY; NW]; N], [[f32::NEG_INFINITY; NW]; N]],
        child: [EMPTY; NW],
    };
}

/// A leaf: up to 4 prepared simplices, structure-of-arrays (lane = simplex). `x0` and `n̂`, all
/// that a test reads before its early exit, come first and lie together.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
struct Block<const N: usize> {
    /// `x0[i][lane]`.
    x0: [[f64; W]; N],
    /// `m[0][i][lane]` = n̂_i, `m[k][i][lane]` = (r_k)_i; zero in unused lanes (which then miss as
    /// parallel rays).
    m: [[[f64; W]; N]; N],
    /// The caller's ids.
    ids: [u32; W],
    /// Lanes in use.
    count: u32,
}

/// Largest f32 ≤ x.
#[inline]
fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x {
        f.next_down()
    } else {
        f
    }
}

/// Smallest f32 ≥ x.
#[inline]
fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    // Without a branch (it would go each way half the time): one step up is one ulp away from
    // zero for f ≥ +0 and towards zero for f < 0 (−∞ steps to −f32::MAX). −0 never steps
    // (x ≤ 0 when it rounds to −0), nor do +∞ and NaN (the comparison is false).
    let step = u32::from((f as f64) < x);
    let bits = f.to_bits();
    let neg = bits >> 31;
    f32::from_bits(bits.wrapping_add(step).wrapping_sub(2 * (step & neg)))
}

/// `t` widened by `T_PAD` relative (upward).
#[inline(always)]
fn pad_up(t: f64) -> f64 {
    t + t.abs() * T_PAD
}

/// `t` widened by `T_PAD` relative (downward).
#[inline(always)]
fn pad_down(t: f64) -> f64 {
    t - t.abs() * T_PAD
}

/// Per-ray data of a traversal: the simplex-test data plus the `f32` slab-test data.
#[derive(Clone, Copy)]
struct RayPre<const N: usize> {
    local: RayLocal<N>,
    /// 1 when the ray enters slab i through its max side (`d_i` negative, including −0), else 0.
    near: [usize; N],
    /// `1/d_i` in f32 (±∞ for a ±0 or tiny component).
    inv: [f32; N],
    /// Origin moved and rounded to f32 towards the side that makes the near parameter smaller…
    o_near: [f32; N],
    /// …and the far parameter larger.
    o_far: [f32; N],
}

impl<const N: usize> RayPre<N> {
    /// `reach` bounds the absolute value of every box coordinate of the tree.
    #[inline(always)]
    fn new(ray: &Ray<N>, reach: f64) -> Self {
        let mut pre = RayPre {
            local: RayLocal::new(ray),
            near: [0; N],
            inv: [0.0; N],
            o_near: [0.0; N],
            o_far: [0.0; N],
        };
        for i in 0..N {
            let (o, d) = (ray.origin[i], ray.dir[i]);
            // The f32 slab parameters `(b − o')·inv` carry four roundings (o' to f32 aside: the
            // difference, the product, and d and 1/d to f32), each ≤ 2⁻²⁴ relative, i.e. an
            // absolute error below 2⁻²²·|b − o'|·|1/d| with |b − o'| ≲ reach + |o|. Moving
            // the origin by 2δ, δ = 2⁻²⁰·(reach + |o|), towards the side that lowers the near
            // parameter (and, separately, raises the far one) more than covers that, and the
            // rounding of o ± 2δ to f32 (≤ 2⁻²⁴·|o ± 2δ| < δ) cannot undo it. So the test is
            // conservative without per-node padding; boxes are widened by ~1e-6 of the scene.
            let delta2 = 2.0 * (reach + o.abs()) * SLAB_REL;
            // (b − o')·inv ≤ (b − o)·inv needs o' ≥ o when inv ≥ 0, o' ≤ o when inv < 0.
            let neg = d.is_sign_negative();
            let (lo, hi) = ((o - delta2) as f32, (o + delta2) as f32);
            pre.near[i] = neg as usize;
            pre.inv[i] = 1.0 / d as f32;
            pre.o_near[i] = if neg { lo } else { hi };
            pre.o_far[i] = if neg { hi } else { lo };
        }
        pre
    }

    /// Slab test of the child boxes of a node against the parameter range [lo, hi]: a bit
    /// mask of the boxes met, and their entry parameters (+∞ for the boxes missed).
    ///
    /// Conservative: the near and far planes of each slab are chosen by the sign of the
    /// direction and evaluated with the origin moved and rounded to f32 in the safe direction
    /// (see [`RayPre::new`]). A zero direction component (inv = ±∞) gives −∞/+∞ for an origin
    /// strictly inside the slab and equal-signed infinities outside it; the one NaN case, `0·∞`
    /// for an origin exactly on a slab plane, is ignored by the running max/min (which keep the
    /// other operand), leaving the slab unrestricted: boxes are closed, and a ray running along
    /// a face is inside.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn slab(&self, node: &Node<N>, lo: f32, hi: f32) -> (u32, [f32; NW]) {
        use std::arch::x86_64::*;
        let mut mask = 0;
        let mut out = [0.0f32; NW];
        // SAFETY: SSE is part of the x86_64 baseline; every pointer loaded or stored is a
        // `[f32; NW]` accessed in quarters of 16 valid bytes (unaligned accesses).
        unsafe {
            for q in 0..NW / 4 {
                let ld = |a: &[f32; NW]| _mm_loadu_ps(a.as_ptr().add(4 * q));
                let mut near = [_mm_set1_ps(lo); N];
                let mut far = [_mm_set1_ps(hi); N];
                for i in 0..N {
                    let s = self.near[i] & 1;
                    let inv = _mm_set1_ps(self.inv[i]);
                    let (on, of) = (_mm_set1_ps(self.o_near[i]), _mm_set1_ps(self.o_far[i]));
                    let a = _mm_mul_ps(_mm_sub_ps(ld(&node.b[s][i]), on), inv);
                    let c = _mm_mul_ps(_mm_sub_ps(ld(&node.b[s ^ 1][i]), of), inv);
                    // maxps/minps return their second operand when either is NaN.
                    near[i] = _mm_max_ps(a, near[i]);
                    far[i] = _mm_min_ps(c, far[i]);
                }
                // Pairwise reduction (short dependency chains; max/min are exact).
                let mut m = N;
                while m > 1 {
                    let half = m.div_ceil(2);
                    for j in 0..m / 2 {
                        near[j] = _mm_max_ps(near[j], near[j + half]);
                        far[j] = _mm_min_ps(far[j], far[j + half]);
                    }
                    m = half;
                }
                let met = _mm_cmple_ps(near[0], far[0]);
                mask |= (_mm_movemask_ps(met) as u32) << (4 * q);
                let missed = _mm_andnot_ps(met, _mm_set1_ps(f32::INFINITY));
                let t = _mm_or_ps(_mm_and_ps(met, near[0]), missed);
                _mm_storeu_ps(out.as_mut_ptr().add(4 * q), t);
            }
        }
        (mask, out)
    }

    /// Portable version of the x86_64 slab test above (same arithmetic, same results).
    #[cfg(not(target_arch = "x86_64"))]
    #[inline(always)]
    fn slab(&self, node: &Node<N>, lo: f32, hi: f32) -> (u32, [f32; NW]) {
        let mut tn = [lo; NW];
        let mut tf = [hi; NW];
        for i in 0..N {
            let s = self.near[i] & 1;
            let (bn, bf) = (&node.b[s][i], &node.b[s ^ 1][i]);
            for l in 0..NW {
                let a = (bn[l] - self.o_near[i]) * self.inv[i];
                let c = (bf[l] - self.o_far[i]) * self.inv[i];
                tn[l] = if a > tn[l] { a } else { tn[l] };
                tf[l] = if c < tf[l] { c } else { tf[l] };
            }
        }
        let mut mask = 0;
        for l in 0..NW {
            let met = tn[l] <= tf[l];
            mask |= (met as u32) << l;
            if !met {
                tn[l] = f32::INFINITY;
            }
        }
        (mask, tn)
    }
}

/// Result of a block test: bit mask of the lanes hit, and per lane t, `n̂·d` and
/// `u[k][lane] = (n̂·d)·t_k` (k ≥ 1), meaningful for the lanes hit.
struct BlockHits<const N: usize> {
    mask: u32,
    t: [f64; W],
    den: [f64; W],
    u: [[f64; W]; N],
}

impl<const N: usize> BlockHits<N> {
    /// Barycentric coordinates of lane l, as [`PreparedSimplex::intersect`] computes them.
    #[inline(always)]
    fn bary(&self, l: usize) -> [f64; N] {
        bary_from(&std::array::from_fn(|k| self.u[k][l]), self.den[l])
    }
}

impl<const N: usize> Block<N> {
    /// Bytes of `x0` and `m[0]` (n̂), which lead the block: all that a test reads before its
    /// early exit.
    const HEAD: usize = 2 * N * W * size_of::<f64>();

    /// Intersects the ray with every lane: which lanes are hit with t in (tmin, tmax), and
    /// their data. Per lane, exactly the arithmetic of [`PreparedSimplex::intersect`] (the same
    /// operations in the same order, hence the same bits). Returns early, before the inside
    /// test, when no lane has t in range.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn hit(&self, ray: &RayLocal<N>, tmin: f64, tmax: f64) -> BlockHits<N> {
        use std::arch::x86_64::*;
        const H: usize = W / 2;
        /// Pairwise sum in the order of [`sum_pairwise`].
        #[inline(always)]
        fn sum2<const N: usize>(mut v: [__m128d; N]) -> __m128d {
            let mut m = N;
            while m > 1 {
                let half = m.div_ceil(2);
                for j in 0..m / 2 {
                    // SAFETY: SSE2 is part of the x86_64 baseline.
                    v[j] = unsafe { _mm_add_pd(v[j], v[j + half]) };
                }
                m = half;
            }
            v[0]
        }
        // SAFETY: SSE2 is part of the x86_64 baseline; every pointer loaded or stored is a
        // `[f64; 4]` accessed as two halves of 16 valid bytes (unaligned accesses).
        unsafe {
            let ld = |a: &[f64; W], h: usize| _mm_loadu_pd(a.as_ptr().add(2 * h));
            let zero = _mm_setzero_pd();
            let d: [__m128d; N] = std::array::from_fn(|i| _mm_set1_pd(ray.d[i]));
            let mut out = BlockHits {
                mask: 0,
                t: [0.0; W],
                den: [0.0; W],
                u: [[0.0; W]; N],
            };
            let mut den = [zero; H];
            let mut num = [zero; H];
            let mut p = [[zero; N]; H];
            let mut ok = [zero; H];
            let mut any = 0;
            let (par2, lo, hi) = (_mm_set1_pd(ray.par2), _mm_set1_pd(tmin), _mm_set1_pd(tmax));
            for h in 0..H {
                den[h] = sum2::<N>(std::array::from_fn(|i| {
                    _mm_mul_pd(ld(&self.m[0][i], h), d[i])
                }));
                p[h] =
                    std::array::from_fn(|i| _mm_sub_pd(ld(&self.x0[i], h), _mm_set1_pd(ray.o[i])));
                num[h] = sum2::<N>(std::array::from_fn(|i| {
                    _mm_mul_pd(ld(&self.m[0][i], h), p[h][i])
                }));
                let t = _mm_div_pd(num[h], den[h]);
                let par = _mm_cmpgt_pd(_mm_mul_pd(den[h], den[h]), par2);
                ok[h] = _mm_and_pd(par, _mm_and_pd(_mm_cmpgt_pd(t, lo), _mm_cmplt_pd(t, hi)));
                any |= _mm_movemask_pd(ok[h]);
                _mm_storeu_pd(out.t.as_mut_ptr().add(2 * h), t);
                _mm_storeu_pd(out.den.as_mut_ptr().add(2 * h), den[h]);
            }
            if any == 0 {
                return out;
            }
            let sign = _mm_set1_pd(-0.0);
            for h in 0..H {
                let w: [__m128d; N] = std::array::from_fn(|i| {
                    _mm_sub_pd(_mm_mul_pd(num[h], d[i]), _mm_mul_pd(den[h], p[h][i]))
                });
                let abs = _mm_andnot_pd(sign, den[h]);
                let thr = _mm_mul_pd(_mm_set1_pd(-BARY_SLACK), abs);
                let flip = _mm_and_pd(sign, den[h]);
                let mut sum = zero;
                for k in 1..N {
                    let u = sum2::<N>(std::array::from_fn(|i| {
                        _mm_mul_pd(ld(&self.m[k][i], h), w[i])
                    }));
                    _mm_storeu_pd(out.u[k].as_mut_ptr().add(2 * h), u);
                    // u_k·sign(n̂·d), exactly (a sign flip).
                    let v = _mm_xor_pd(u, flip);
                    ok[h] = _mm_and_pd(ok[h], _mm_cmpge_pd(v, thr));
                    sum = _mm_add_pd(sum, v);
                }
                ok[h] = _mm_and_pd(ok[h], _mm_cmpge_pd(_mm_sub_pd(abs, sum), thr));
                out.mask |= (_mm_movemask_pd(ok[h]) as u32) << (2 * h);
            }
            out.mask &= (1 << self.count) - 1;
            out
        }
    }

    /// The block test of [`Block::hit`] with the 4 lanes in one AVX register: the same
    /// operations in the same order (no FMA), hence the same bits, and the same early return.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn hit_avx2(&self, ray: &RayLocal<N>, tmin: f64, tmax: f64) -> BlockHits<N> {
        use std::arch::x86_64::*;
        #[inline(always)]
        fn sum4<const N: usize>(mut v: [__m256d; N]) -> __m256d {
            let mut m = N;
            while m > 1 {
                let half = m.div_ceil(2);
                for j in 0..m / 2 {
                    // SAFETY: only reached from `hit_avx2`, whose caller guarantees AVX2.
                    v[j] = unsafe { _mm256_add_pd(v[j], v[j + half]) };
                }
                m = half;
            }
            v[0]
        }
        let ld = |a: &[f64; W]| _mm256_loadu_pd(a.as_ptr());
        let d: [__m256d; N] = std::array::from_fn(|i| _mm256_set1_pd(ray.d[i]));
        let mut out = BlockHits {
            mask: 0,
            t: [0.0; W],
            den: [0.0; W],
            u: [[0.0; W]; N],
        };
        let den = sum4::<N>(std::array::from_fn(|i| {
            _mm256_mul_pd(ld(&self.m[0][i]), d[i])
        }));
        let p: [__m256d; N] =
            std::array::from_fn(|i| _mm256_sub_pd(ld(&self.x0[i]), _mm256_set1_pd(ray.o[i])));
        let num = sum4::<N>(std::array::from_fn(|i| {
            _mm256_mul_pd(ld(&self.m[0][i]), p[i])
        }));
        let t = _mm256_div_pd(num, den);
        let par = _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_mul_pd(den, den), _mm256_set1_pd(ray.par2));
        let above = _mm256_cmp_pd::<_CMP_GT_OQ>(t, _mm256_set1_pd(tmin));
        let below = _mm256_cmp_pd::<_CMP_LT_OQ>(t, _mm256_set1_pd(tmax));
        let mut ok = _mm256_and_pd(par, _mm256_and_pd(above, below));
        _mm256_storeu_pd(out.t.as_mut_ptr(), t);
        _mm256_storeu_pd(out.den.as_mut_ptr(), den);
        if _mm256_movemask_pd(ok) == 0 {
            return out;
        }
        let sign = _mm256_set1_pd(-0.0);
        let w: [__m256d; N] = std::array::from_fn(|i| {
            _mm256_sub_pd(_mm256_mul_pd(num, d[i]), _mm256_mul_pd(den, p[i]))
        });
        let abs = _mm256_andnot_pd(sign, den);
        let thr = _mm256_mul_pd(_mm256_set1_pd(-BARY_SLACK), abs);
        let flip = _mm256_and_pd(sign, den);
        let mut sum = _mm256_setzero_pd();
        for k in 1..N {
            let u = sum4::<N>(std::array::from_fn(|i| {
                _mm256_mul_pd(ld(&self.m[k][i]), w[i])
            }));
            _mm256_storeu_pd(out.u[k].as_mut_ptr(), u);
            let v = _mm256_xor_pd(u, flip);
            ok = _mm256_and_pd(ok, _mm256_cmp_pd::<_CMP_GE_OQ>(v, thr));
            sum = _mm256_add_pd(sum, v);
        }
        ok = _mm256_and_pd(
            ok,
            _mm256_cmp_pd::<_CMP_GE_OQ>(_mm256_sub_pd(abs, sum), thr),
        );
        out.mask = _mm256_movemask_pd(ok) as u32 & ((1 << self.count) - 1);
        out
    }

    /// Portable version of the x86_64 block test above (same arithmetic, same results).
    #[cfg(not(target_arch = "x86_64"))]
    #[inline(always)]
    fn hit(&self, ray: &RayLocal<N>, tmin: f64, tmax: f64) -> BlockHits<N> {
        let mut out = BlockHits {
            mask: 0,
            t: [0.0; W],
            den: [0.0; W],
            u: [[0.0; W]; N],
        };
        for l in 0..self.count as usize {
            let lane = PreparedSimplex {
                m: std::array::from_fn(|k| std::array::from_fn(|i| self.m[k][i][l])),
                x0: std::array::from_fn(|i| self.x0[i][l]),
            };
            let n = &lane.m[0];
            let den = dot_pairwise(n, &ray.d);
            let p = sub(&lane.x0, &ray.o);
            let num = dot_pairwise(n, &p);
            let w: Vector<N> = std::array::from_fn(|i| num * ray.d[i] - den * p[i]);
            out.t[l] = num / den;
            out.den[l] = den;
            for k in 1..N {
                out.u[k][l] = dot_pairwise(&lane.m[k], &w);
            }
            out.mask |= (lane.hit(ray, tmin, tmax).is_some() as u32) << l;
        }
        out
    }
}

/// A bounding-volume hierarchy over prepared simplices (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh<const N: usize> {
    /// Wide nodes in depth-first order; the root is node 0 (none when empty).
    nodes: Vec<Node<N>>,
    /// Leaves, in leaf order.
    blocks: Vec<Block<N>>,
    /// Number of simplices.
    len: usize,
    /// Bound on |coordinate| of every box of the tree (for the slab test's error bound).
    reach: f64,
    /// Per node, per child slot: the smallest (`[0]`) and largest (`[1]`) id in the child's
    /// subtree (`u32::MAX`, 0 for an empty slot), so that an any-hit query told to skip a range
    /// of ids ([`Bvh::any_hit`]) leaves out the subtrees that hold nothing else.
    ranges: Vec<[[u32; NW]; 2]>,
}

/// A binary node of the build: f32 bounds rounded outward and either two children (the left
/// one next, `first` the right one) or a leaf range `first .. first + count` (count > 0).
#[derive(Clone, Copy)]
struct BNode<const N: usize> {
    min: [f32; N],
    max: [f32; N],
    first: u32,
    count: u32,
}

/// Bounds, centroid bounds of a set of simplices.
#[derive(Clone, Copy)]
struct Info<const N: usize> {
    bmin: Vector<N>,
    bmax: Vector<N>,
    cmin: Vector<N>,
    cmax: Vector<N>,
}

impl<const N: usize> Info<N> {
    fn empty() -> Self {
        Info {
            bmin: [f64::INFINITY; N],
            bmax: [f64::NEG_INFINITY; N],
            cmin: [f64::INFINITY; N],
            cmax: [f64::NEG_INFINITY; N],
        }
    }

    fn merge(mut self, o: Self) -> Self {
        for i in 0..N {
            self.bmin[i] = self.bmin[i].min(o.bmin[i]);
            self.bmax[i] = self.bmax[i].max(o.bmax[i]);
            self.cmin[i] = self.cmin[i].min(o.cmin[i]);
            self.cmax[i] = self.cmax[i].max(o.cmax[i]);
        }
        self
    }
}

/// One SAH bin: count and bounds of the simplices whose centroid falls in it.
#[derive(Clone, Copy)]
struct Bin<const N: usize> {
    count: u32,
    min: Vector<N>,
    max: Vector<N>,
}

impl<const N: usize> Bin<N> {
    const EMPTY: Self = Bin {
        count: 0,
        min: [f64::INFINITY; N],
        max: [f64::NEG_INFINITY; N],
    };

    #[inline]
    fn grow(&mut self, lo: &Vector<N>, hi: &Vector<N>, count: u32) {
        self.count += count;
        for i in 0..N {
            self.min[i] = self.min[i].min(lo[i]);
            self.max[i] = self.max[i].max(hi[i]);
        }
    }
}

type Bins<const N: usize> = [[Bin<N>; BINS]; N];

/// Half the (N−1)-measure of a box's boundary, `Σ_i Π_{j≠i} extent_j` (half the perimeter in
/// 2D, half the surface area in 3D). By Cauchy's formula the probability that a random line
/// meets a convex body is proportional to its boundary measure, which makes this the SAH weight
/// in every N. An empty box (min > max) has measure 0.
fn half_area<const N: usize>(min: &Vector<N>, max: &Vector<N>) -> f64 {
    let e: Vector<N> = std::array::from_fn(|i| (max[i] - min[i]).max(0.0));
    let mut s = 0.0;
    for i in 0..N {
        let mut p = 1.0;
        for j in 0..N {
            if j != i {
                p *= e[j];
            }
        }
        s += p;
    }
    s
}

/// SAH cost weight of n simplices: the number of blocks they fill, since a block tests up to
/// 4 simplices at the price of one.
#[inline]
fn blocks_of(n: u32) -> f64 {
    n.div_ceil(W as u32) as f64
}

/// Bin of a centroid coordinate: `⌊(c − cmin)·scale⌋` clamped to the last bin. The same
/// function bins and partitions, so both agree exactly.
#[inline(always)]
fn bin_of(c: f64, cmin: f64, scale: f64) -> usize {
    (((c - cmin) * scale) as usize).min(BINS - 1)
}

/// Reorders `idx` so that the elements satisfying `left` come first; returns their number.
fn partition(idx: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let (mut i, mut j) = (0, idx.len());
    loop {
        while i < j && left(idx[i]) {
            i += 1;
        }
        while i < j && !left(idx[j - 1]) {
            j -= 1;
        }
        if i >= j {
            return i;
        }
        idx.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

/// Build inputs: padded bounds and centroids of every simplex (by input index).
struct Builder<const N: usize> {
    bounds: Vec<(Vector<N>, Vector<N>)>,
    cent: Vec<Vector<N>>,
    par_min: usize,
}

/// A binary subtree built in parallel: either a flat run of nodes (child indices relative to its
/// start) or an inner node over two such subtrees. Flattened once at the end, in depth-first
/// order, so the layout does not depend on which parts were built in parallel.
enum Built<const N: usize> {
    Flat(Vec<BNode<N>>),
    Split(BNode<N>, Box<Built<N>>, Box<Built<N>>),
}

impl<const N: usize> Builder<N> {
    fn info_seq(&self, idx: &[u32]) -> Info<N> {
        let mut info = Info::empty();
        for &p in idx {
            let (lo, hi) = &self.bounds[p as usize];
            let c = &self.cent[p as usize];
            for i in 0..N {
                info.bmin[i] = info.bmin[i].min(lo[i]);
                info.bmax[i] = info.bmax[i].max(hi[i]);
                info.cmin[i] = info.cmin[i].min(c[i]);
                info.cmax[i] = info.cmax[i].max(c[i]);
            }
        }
        info
    }

    /// Bounds and centroid bounds; min/max are exact, so the parallel reduction gives the same
    /// result as the sequential loop.
    fn info(&self, idx: &[u32]) -> Info<N> {
        if idx.len() >= self.par_min.max(2 * PAR_CHUNK) {
            idx.par_chunks(PAR_CHUNK)
                .map(|c| self.info_seq(c))
                .reduce(Info::empty, Info::merge)
        } else {
            self.info_seq(idx)
        }
    }

    fn bin_seq(&self, idx: &[u32], cmin: &Vector<N>, scale: &Vector<N>) -> Bins<N> {
        let mut bins = [[Bin::EMPTY; BINS]; N];
        for &p in idx {
            let (lo, hi) = &self.bounds[p as usize];
            let c = &self.cent[p as usize];
            for a in 0..N {
                if scale[a] > 0.0 {
                    bins[a][bin_of(c[a], cmin[a], scale[a])].grow(lo, hi, 1);
                }
            }
        }
        bins
    }

    /// The SAH bins; counts and min/max are exact, so the parallel reduction is deterministic.
    fn bins(&self, idx: &[u32], cmin: &Vector<N>, scale: &Vector<N>) -> Bins<N> {
        if idx.len() >= self.par_min.max(2 * PAR_CHUNK) {
            idx.par_chunks(PAR_CHUNK)
                .map(|c| self.bin_seq(c, cmin, scale))
                .reduce(
                    || [[Bin::EMPTY; BINS]; N],
                    |mut a, b| {
                        for ax in 0..N {
                            for k in 0..BINS {
                                a[ax][k].grow(&b[ax][k].min, &b[ax][k].max, b[ax][k].count);
                            }
                        }
                        a
                    },
                )
        } else {
            self.bin_seq(idx, cmin, scale)
        }
    }

    /// Chooses how to split the node over `idx` and partitions `idx` accordingly: `None` for a
    /// leaf (at most `MAX_LEAF` simplices: a block tests them at the price of one), `Some(mid)`
    /// for children `idx[..mid]` and `idx[mid..]` (both non-empty).
    fn split(&self, idx: &mut [u32], info: &Info<N>, depth: usize) -> Option<usize> {
        let n = idx.len();
        if n <= MAX_LEAF {
            return None;
        }
        let mut scale = [0.0; N];
        for a in 0..N {
            let ext = info.cmax[a] - info.cmin[a];
            let s = BINS as f64 / ext;
            if ext > 0.0 && s.is_finite() {
                scale[a] = s;
            }
        }
        if depth < MAX_SAH_DEPTH && scale.iter().any(|&s| s > 0.0) {
            let bins = self.bins(idx, &info.cmin, &scale);
            // (cost, axis, first bin of the right side); ties keep the first candidate.
            let mut best: Option<(f64, usize, usize)> = None;
            for a in 0..N {
                if scale[a] == 0.0 {
                    continue;
                }
                // Suffix sweep: right_cost[s] = area(bins s..) · blocks(bins s..).
                let mut right_cost = [0.0; BINS];
                let mut acc = Bin::EMPTY;
                for s in (1..BINS).rev() {
                    let b = &bins[a][s];
                    acc.grow(&b.min, &b.max, b.count);
                    right_cost[s] = half_area(&acc.min, &acc.max) * blocks_of(acc.count);
                }
                let mut left = Bin::EMPTY;
                for s in 1..BINS {
                    let b = &bins[a][s - 1];
                    left.grow(&b.min, &b.max, b.count);
                    let n_left = left.count as usize;
                    if n_left == 0 || n_left == n {
                        continue;
                    }
                    let cost =
                        half_area(&left.min, &left.max) * blocks_of(left.count) + right_cost[s];
                    if best.is_none_or(|(c, _, _)| cost < c) {
                        best = Some((cost, a, s));
                    }
                }
            }
            if let Some((_, a, s)) = best {
                let (cmin, sc) = (info.cmin[a], scale[a]);
                let mid = partition(idx, |p| bin_of(self.cent[p as usize][a], cmin, sc) < s);
                debug_assert!(mid > 0 && mid < n);
                return Some(mid);
            }
        }
        // Object-median split on the axis of largest centroid extent (ties: lowest axis, then
        // input index), which always splits and halves the count.
        let mut axis = 0;
        for a in 1..N {
            if info.cmax[a] - info.cmin[a] > info.cmax[axis] - info.cmin[axis] {
                axis = a;
            }
        }
        let mid = n / 2;
        let cent = &self.cent;
        idx.select_nth_unstable_by(mid, |&p, &q| {
            cent[p as usize][axis]
                .total_cmp(&cent[q as usize][axis])
                .then(p.cmp(&q))
        });
        Some(mid)
    }

    fn node(info: &Info<N>) -> BNode<N> {
        BNode {
            min: std::array::from_fn(|i| f32_down(info.bmin[i])),
            max: std::array::from_fn(|i| f32_up(info.bmax[i])),
            first: 0,
            count: 0,
        }
    }

    /// Sequential build of the subtree over `idx` (at position `offset` of the final order),
    /// appending to `out` with node indices relative to the start of `out`.
    fn build_seq(&self, idx: &mut [u32], offset: usize, depth: usize, out: &mut Vec<BNode<N>>) {
        let info = self.info_seq(idx);
        let me = out.len();
        out.push(Self::node(&info));
        match self.split(idx, &info, depth) {
            None => {
                out[me].first = offset as u32;
                out[me].count = idx.len() as u32;
            }
            Some(mid) => {
                let (l, r) = idx.split_at_mut(mid);
                self.build_seq(l, offset, depth + 1, out);
                out[me].first = out.len() as u32;
                self.build_seq(r, offset + mid, depth + 1, out);
            }
        }
    }

    /// Build of the subtree over `idx`, forking with rayon for large nodes.
    fn build_par(&self, idx: &mut [u32], offset: usize, depth: usize) -> Built<N> {
        if idx.len() < self.par_min {
            let mut out = Vec::with_capacity(idx.len() / 2 + 1);
            self.build_seq(idx, offset, depth, &mut out);
            return Built::Flat(out);
        }
        let info = self.info(idx);
        let mut node = Self::node(&info);
        match self.split(idx, &info, depth) {
            None => {
                node.first = offset as u32;
                node.count = idx.len() as u32;
                Built::Flat(vec![node])
            }
            Some(mid) => {
                let (l, r) = idx.split_at_mut(mid);
                let (bl, br) = rayon::join(
                    || self.build_par(l, offset, depth + 1),
                    || self.build_par(r, offset + mid, depth + 1),
                );
                Built::Split(node, Box::new(bl), Box::new(br))
            }
        }
    }
}

/// Appends a built subtree in depth-first order, rebasing inner nodes' child indices.
fn flatten<const N: usize>(b: Built<N>, out: &mut Vec<BNode<N>>) {
    match b {
        Built::Flat(v) => {
            let base = out.len() as u32;
            out.extend(v.into_iter().map(|mut nd| {
                if nd.count == 0 {
                    nd.first += base;
                }
                nd
            }));
        }
        Built::Split(node, l, r) => {
            let me = out.len();
            out.push(node);
            flatten(*l, out);
            out[me].first = out.len() as u32;
            flatten(*r, out);
        }
    }
}

/// The binary SAH tree over the simplices of the given bounds (each padded by [`BOX_PAD`] of
/// its largest extent), in depth-first order, and the leaf order (`idx[j]`: the input index of
/// the j-th simplex in leaf order). Forks with rayon above `par_min` simplices.
fn binary_tree<const N: usize>(
    bounds: Vec<Bounds<N>>,
    par_min: usize,
) -> (Vec<BNode<N>>, Vec<u32>) {
    let n = bounds.len();
    // Pad each box by BOX_PAD of its largest extent, so that it contains the BARY_SLACK band.
    let padded: Vec<(Vector<N>, Vector<N>)> = bounds
        .into_iter()
        .map(|(lo, hi)| {
            let ext = (0..N).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
            let pad = BOX_PAD * ext;
            (
                std::array::from_fn(|i| lo[i] - pad),
                std::array::from_fn(|i| hi[i] + pad),
            )
        })
        .collect();
    let cent = padded
        .iter()
        .map(|(lo, hi)| std::array::from_fn(|i| 0.5 * (lo[i] + hi[i])))
        .collect();
    let builder = Builder {
        bounds: padded,
        cent,
        par_min: par_min.max(2),
    };
    let mut idx: Vec<u32> = (0..n as u32).collect();
    let built = builder.build_par(&mut idx, 0, 0);
    drop(builder);
    let mut bin = Vec::new();
    flatten(built, &mut bin);
    (bin, idx)
}

/// How each binary subtree is laid out in the wide tree: the optimal collapse of Ylitie,
/// Karras and Laine ("Efficient incoherent ray traversal on GPUs through compressed wide BVHs",
/// HPG 2017, §4.1), a dynamic program over the binary tree.
///
/// The leaves are the binary tree's and each is tested exactly when its own box is met, so
/// the collapse only decides which binary inner nodes become wide nodes. A ray visits a wide
/// node (one slab test of all its slots, whatever their number) with probability proportional
/// to the node's [`half_area`], so the plan minimises the sum of the wide nodes' half areas.
/// With `S(b, k)` the least cost of holding subtree b in at most k slots of its parent:
///
/// * a leaf takes one slot at no cost: `S(b, k) = 0`;
/// * an inner node in one slot is the root of a wide node: `S(b, 1) = A(b) + D(b, 8)`, where
///   `D(b, k) = min_{1 ≤ j < k} S(left, j) + S(right, k − j)` shares k slots between its
///   children;
/// * with more slots it may also be opened: `S(b, k) = min(S(b, k − 1), D(b, k))`.
///
/// The greedy rule (open the child of largest area until 8 slots are used) leaves a small wide
/// node wherever a subtree did not fit: 66% of the nodes of a 1.3 M-triangle icosphere held 2
/// leaves.
struct Plan {
    /// `slots[b][k − 1]`: how subtree b fills at most k slots: `[0, 0]` in one slot (a leaf
    /// or a wide node's root), else `[j, m]`, j slots to the left child and m to the right.
    slots: Vec<[[u8; 2]; NW]>,
    /// The split of the `NW` slots of the wide node rooted at inner node b.
    wide: Vec<[u8; 2]>,
}

impl Plan {
    fn new<const N: usize>(bin: &[BNode<N>]) -> Self {
        let n = bin.len();
        let mut cost = vec![[0.0f64; NW]; n];
        let mut slots = vec![[[0u8; 2]; NW]; n];
        let mut wide = vec![[0u8; 2]; n];
        // Children come after their parent in depth-first order: one pass from the end.
        for b in (0..n).rev() {
            if bin[b].count > 0 {
                continue;
            }
            let (l, r) = (b + 1, bin[b].first as usize);
            // The best sharing of k slots between the children (ties: fewest to the left).
            let share = |k: usize| {
                let mut best = (f64::INFINITY, [1u8, (k - 1) as u8]);
                for j in 1..k {
                    let c = cost[l][j - 1] + cost[r][k - j - 1];
                    if c < best.0 {
                        best = (c, [j as u8, (k - j) as u8]);
                    }
                }
                best
            };
            let (d, w) = share(NW);
            let mut row = [(0.0, [0u8; 2]); NW];
            // A NaN area (from infinite bounds) counts as infinite.
            let area = half_area(&bin[b].min.map(f64::from), &bin[b].max.map(f64::from));
            row[0].0 = if area.is_nan() { f64::INFINITY } else { area } + d;
            for k in 2..=NW {
                // D(b, NW) is already known.
                let (c, how) = if k == NW { (d, w) } else { share(k) };
                // Opening b must gain: on a tie, fewer slots.
                row[k - 1] = if c < row[k - 2].0 {
                    (c, how)
                } else {
                    row[k - 2]
                };
            }
            wide[b] = w;
            for k in 0..NW {
                cost[b][k] = row[k].0;
                slots[b][k] = row[k].1;
            }
        }
        Plan { slots, wide }
    }

    /// Appends to `kids`, in left-to-right order, the binary nodes that subtree b puts in its
    /// at most k slots.
    fn expand<const N: usize>(&self, bin: &[BNode<N>], b: usize, k: usize, kids: &mut Vec<usize>) {
        match self.slots[b][k - 1] {
            [0, _] => kids.push(b),
            [j, m] => {
                self.expand(bin, b + 1, j as usize, kids);
                self.expand(bin, bin[b].first as usize, m as usize, kids);
            }
        }
    }
}

/// Collapses the binary tree into wide nodes and blocks (both in depth-first order).
struct Collapse<'a, const N: usize> {
    bin: &'a [BNode<N>],
    plan: Plan,
    /// The input simplices and ids, and the leaf order: `order[j]` is the input index of the
    /// j-th simplex in leaf order.
    prims: &'a [PreparedSimplex<N>],
    ids: &'a [u32],
    order: &'a [u32],
    nodes: Vec<Node<N>>,
    blocks: Vec<Block<N>>,
}

impl<const N: usize> Collapse<'_, N> {
    /// The reference (node index or `LEAF | block`) of binary node `b`'s subtree.
    fn child_ref(&mut self, b: usize) -> u32 {
        if self.bin[b].count > 0 {
            self.leaf(b)
        } else {
            self.node(b)
        }
    }

    fn leaf(&mut self, b: usize) -> u32 {
        let nd = self.bin[b];
        let mut block = Block {
            m: [[[0.0; W]; N]; N],
            x0: [[0.0; W]; N],
            ids: [EMPTY; W],
            count: nd.count,
        };
        for l in 0..nd.count as usize {
            let src = self.order[nd.first as usize + l] as usize;
            let p = &self.prims[src];
            for k in 0..N {
                for i in 0..N {
                    block.m[k][i][l] = p.m[k][i];
                }
            }
            for i in 0..N {
                block.x0[i][l] = p.x0[i];
            }
            block.ids[l] = self.ids[src];
        }
        self.blocks.push(block);
        LEAF | (self.blocks.len() - 1) as u32
    }

    /// The wide node over binary inner node `b`: its children as the [`Plan`] lays them out,
    /// in left-to-right order.
    fn node(&mut self, b: usize) -> u32 {
        let [j, m] = self.plan.wide[b];
        let mut kids = Vec::with_capacity(NW);
        self.plan.expand(self.bin, b + 1, j as usize, &mut kids);
        self.plan
            .expand(self.bin, self.bin[b].first as usize, m as usize, &mut kids);
        debug_assert!((2..=NW).contains(&kids.len()));
        let me = self.nodes.len();
        self.nodes.push(Node::EMPTY);
        for (l, &c) in kids.iter().enumerate() {
            let r = self.child_ref(c);
            let nd = &mut self.nodes[me];
            nd.child[l] = r;
            for i in 0..N {
                nd.b[0][i][l] = self.bin[c].min[i];
                nd.b[1][i][l] = self.bin[c].max[i];
            }
        }
        me as u32
    }
}

/// The id range of every child of every node (see [`Bvh::ranges`]). Children come after their
/// parent in depth-first order, so one pass from the last node up sees every child first.
fn id_ranges<const N: usize>(nodes: &[Node<N>], blocks: &[Block<N>]) -> Vec<[[u32; NW]; 2]> {
    let mut ranges = vec![[[u32::MAX; NW], [0; NW]]; nodes.len()];
    for i in (0..nodes.len()).rev() {
        for l in 0..NW {
            let c = nodes[i].child[l];
            let (lo, hi) = if c == EMPTY {
                (u32::MAX, 0)
            } else if c & LEAF != 0 {
                let b = &blocks[(c & !LEAF) as usize];
                let ids = &b.ids[..b.count as usize];
                (
                    ids.iter().copied().min().unwrap(),
                    ids.iter().copied().max().unwrap(),
                )
            } else {
                let r = &ranges[c as usize];
                (
                    r[0].iter().copied().min().unwrap(),
                    r[1].iter().copied().max().unwrap(),
                )
            };
            ranges[i][0][l] = lo;
            ranges[i][1][l] = hi;
        }
    }
    ranges
}

/// Best hit so far of a closest-hit traversal.
#[derive(Clone, Copy)]
struct Best<const N: usize> {
    t: f64,
    id: u32,
    bary: [f64; N],
    found: bool,
    /// Where the simplex hit is: its block and lane.
    block: u32,
    lane: u32,
}

impl<const N: usize> Bvh<N> {
    /// Builds over prepared simplices; `ids[i]` is the caller's id of `prims[i]` (returned in
    /// [`Hit::prim`]) and `bounds[i]` the (min, max) corners of its vertices.
    ///
    /// Deterministic: every decision depends only on the input (bins are integer counts and
    /// min/max, exact in any reduction order; ties go to the lowest axis, bin or index), and the
    /// parallel parts are flattened in depth-first order, so the tree is identical for any
    /// number of threads.
    ///
    /// # Panics
    /// If the three vectors differ in length or hold 2³¹ or more simplices.
    pub fn build(
        prims: Vec<PreparedSimplex<N>>,
        ids: Vec<u32>,
        bounds: Vec<([f64; N], [f64; N])>,
    ) -> Self {
        Self::build_with(prims, ids, bounds, PAR_MIN)
    }

    fn build_with(
        prims: Vec<PreparedSimplex<N>>,
        ids: Vec<u32>,
        bounds: Vec<([f64; N], [f64; N])>,
        par_min: usize,
    ) -> Self {
        let n = prims.len();
        assert!(
            ids.len() == n && bounds.len() == n,
            "Bvh::build: prims, ids, bounds lengths differ"
        );
        assert!(n < LEAF as usize, "Bvh::build: too many simplices");
        if n == 0 {
            return Bvh {
                nodes: Vec::new(),
                blocks: Vec::new(),
                len: 0,
                reach: 0.0,
                ranges: Vec::new(),
            };
        }
        let (bin, idx) = binary_tree(bounds, par_min);
        let plan = Plan::new(&bin);
        let mut c = Collapse {
            bin: &bin,
            plan,
            prims: &prims,
            ids: &ids,
            order: &idx,
            nodes: Vec::new(),
            blocks: Vec::with_capacity(bin.iter().filter(|b| b.count > 0).count()),
        };
        if bin[0].count > 0 {
            // A single leaf: a root node with one child.
            c.nodes.push(Node::EMPTY);
            let r = c.leaf(0);
            c.nodes[0].child[0] = r;
            for i in 0..N {
                c.nodes[0].b[0][i][0] = bin[0].min[i];
                c.nodes[0].b[1][i][0] = bin[0].max[i];
            }
        } else {
            c.node(0);
        }
        let (mut nodes, mut blocks) = (c.nodes, c.blocks);
        nodes.shrink_to_fit();
        blocks.shrink_to_fit();
        let root = &bin[0];
        let reach = (0..N)
            .map(|i| f64::from(root.min[i].abs()).max(f64::from(root.max[i].abs())))
            .fold(0.0, f64::max);
        // Non-finite bounds only widen the slab test (and the shift saturates to infinity).
        let reach = if reach.is_finite() {
            reach
        } else {
            f64::from(f32::MAX)
        };
        let ranges = id_ranges(&nodes, &blocks);
        Bvh {
            nodes,
            blocks,
            len: n,
            reach,
            ranges,
        }
    }

    /// Builds over the non-degenerate simplices of `points`, with `ids[i]` the id of
    /// `points[i]` (degenerate ones are skipped). Preparation runs in parallel.
    pub fn from_simplices(points: &[[[f64; N]; N]], ids: &[u32]) -> Self {
        assert_eq!(
            points.len(),
            ids.len(),
            "Bvh::from_simplices: points and ids lengths differ"
        );
        let prepared: Vec<(PreparedSimplex<N>, u32, Bounds<N>)> = points
            .par_iter()
            .zip(ids.par_iter())
            .filter_map(|(p, &id)| Some((PreparedSimplex::new(p)?, id, simplex_bounds(p))))
            .collect();
        let mut prims = Vec::with_capacity(prepared.len());
        let mut pids = Vec::with_capacity(prepared.len());
        let mut bounds = Vec::with_capacity(prepared.len());
        for (p, id, b) in prepared {
            prims.push(p);
            pids.push(id);
            bounds.push(b);
        }
        Self::build(prims, pids, bounds)
    }

    /// Builds over the non-degenerate simplices of a mesh; a hit's `prim` is the simplex index.
    pub fn from_mesh(mesh: &Mesh<N>) -> Self {
        let points: Vec<[[f64; N]; N]> = mesh
            .simplices
            .par_iter()
            .map(|idx| std::array::from_fn(|k| mesh.vertices[idx[k] as usize]))
            .collect();
        let ids: Vec<u32> = (0..points.len() as u32).collect();
        Self::from_simplices(&points, &ids)
    }

    /// Number of simplices.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no simplices.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of (8-wide) nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of leaves (blocks of up to 4 simplices).
    pub fn leaf_count(&self) -> usize {
        self.blocks.len()
    }

    /// Memory used by nodes + prims (the leaf blocks, with their ids), in bytes.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * (std::mem::size_of::<Node<N>>() + std::mem::size_of::<[[u32; NW]; 2]>())
            + self.blocks.len() * std::mem::size_of::<Block<N>>()
    }

    /// Depth of the 8-wide tree counting the leaf level (0 when empty).
    pub fn depth(&self) -> usize {
        fn rec<const N: usize>(nodes: &[Node<N>], i: usize) -> usize {
            let deepest = nodes[i]
                .child
                .iter()
                .map(|&c| {
                    if c == EMPTY || c & LEAF != 0 {
                        1
                    } else {
                        rec(nodes, c as usize)
                    }
                })
                .max()
                .unwrap_or(0);
            1 + deepest
        }
        if self.nodes.is_empty() {
            0
        } else {
            rec(&self.nodes, 0)
        }
    }

    /// Nearest hit with t in (tmin, tmax) among the simplices whose id passes `accept`.
    /// Deterministic: on an exact tie in t, the smaller id wins (so the result is the minimum of
    /// (t, id) over all accepted hits, independently of the tree's shape).
    pub fn closest_hit(
        &self,
        ray: &Ray<N>,
        tmin: f64,
        tmax: f64,
        accept: impl Fn(u32) -> bool,
    ) -> Option<Hit<N>> {
        let mut out = [None];
        self.closest_packet::<1>(std::slice::from_ref(ray), tmin, tmax, &accept, &mut out);
        out[0]
    }

    /// [`Bvh::closest_hit`] for every ray of `rays` into `out` (same length; every element is
    /// overwritten, misses with `None`), traced in packets of [`PACKET`] rays that share node
    /// visits. Each result is exactly the one
    /// [`Bvh::closest_hit`] gives for that ray alone: the minimum of (t, id) over the accepted
    /// hits does not depend on which rays travel together.
    ///
    /// # Panics
    /// If `out` and `rays` differ in length.
    pub fn closest_hits(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: f64,
        accept: impl Fn(u32) -> bool,
        out: &mut [Option<Hit<N>>],
    ) {
        assert_eq!(
            rays.len(),
            out.len(),
            "Bvh::closest_hits: rays and out differ in length"
        );
        for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
            self.closest_packet::<PACKET>(rays, tmin, tmax, &accept, out);
        }
    }

    /// One packet of at most `P` rays, with the AVX2 kernels when the CPU has them.
    #[inline]
    fn closest_packet<const P: usize>(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: f64,
        accept: &impl Fn(u32) -> bool,
        out: &mut [Option<Hit<N>>],
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 is available.
            return unsafe { self.closest_hits_avx2::<P>(rays, tmin, tmax, accept, out) };
        }
        self.closest_hits_impl::<false, P>(rays, tmin, tmax, accept, out);
    }

    /// [`Bvh::closest_hits_impl`] compiled for AVX2 (same results).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn closest_hits_avx2<const P: usize>(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: f64,
        accept: &impl Fn(u32) -> bool,
        out: &mut [Option<Hit<N>>],
    ) {
        self.closest_hits_impl::<true, P>(rays, tmin, tmax, accept, out)
    }

    /// Whether any simplex whose id passes `accept` and lies outside `skip` is hit with t in
    /// (tmin, tmax) (shadow rays; stops at the first such hit). Subtrees whose ids all lie in
    /// `skip` are not visited: a shadow ray that cannot meet its own (convex) object skips it
    /// at the cost of one comparison per child met, not of a traversal.
    pub fn any_hit(
        &self,
        ray: &Ray<N>,
        tmin: f64,
        tmax: f64,
        accept: impl Fn(u32) -> bool,
        skip: Range<u32>,
    ) -> bool {
        let mut out = [false];
        let one = std::slice::from_ref(ray);
        self.any_packet::<1>(one, tmin, &[tmax], &accept, &skip, &mut out);
        out[0]
    }

    /// [`Bvh::any_hit`] for every ray of `rays` with its own `tmax[i]`, into `out`, traced in
    /// packets of [`PACKET`] rays (same results as one ray at a time).
    ///
    /// # Panics
    /// If `rays`, `tmax` and `out` differ in length.
    pub fn any_hits(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: &[f64],
        accept: impl Fn(u32) -> bool,
        skip: Range<u32>,
        out: &mut [bool],
    ) {
        assert!(
            rays.len() == tmax.len() && rays.len() == out.len(),
            "Bvh::any_hits: rays, tmax and out differ in length"
        );
        let packets = rays.chunks(PACKET).zip(tmax.chunks(PACKET));
        for ((rays, tmax), out) in packets.zip(out.chunks_mut(PACKET)) {
            self.any_packet::<PACKET>(rays, tmin, tmax, &accept, &skip, out);
        }
    }

    /// One packet of at most `P` rays, with the AVX2 kernels when the CPU has them.
    #[inline]
    fn any_packet<const P: usize>(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: &[f64],
        accept: &impl Fn(u32) -> bool,
        skip: &Range<u32>,
        out: &mut [bool],
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 is available.
            return unsafe { self.any_hits_avx2::<P>(rays, tmin, tmax, accept, skip, out) };
        }
        self.any_hits_impl::<false, P>(rays, tmin, tmax, accept, skip, out);
    }

    /// [`Bvh::any_hits_impl`] compiled for AVX2 (same results).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn any_hits_avx2<const P: usize>(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: &[f64],
        accept: &impl Fn(u32) -> bool,
        skip: &Range<u32>,
        out: &mut [bool],
    ) {
        self.any_hits_impl::<true, P>(rays, tmin, tmax, accept, skip, out)
    }

    /// The block of a child reference with the `LEAF` bit.
    #[inline(always)]
    fn block(&self, child: u32) -> &Block<N> {
        &self.blocks[(child & !LEAF) as usize]
    }

    /// The address of [`Bvh::block`] for prefetching: no bounds check (a prefetch never
    /// faults), which a few prefetches per node visit would pay for.
    #[inline(always)]
    fn block_ptr(&self, child: u32) -> *const Block<N> {
        self.blocks.as_ptr().wrapping_add((child & !LEAF) as usize)
    }

    /// Tests a block, with the AVX2 kernel when `AVX` (only instantiated inside functions
    /// compiled for AVX2).
    #[inline(always)]
    fn block_hit<const AVX: bool>(
        &self,
        block: &Block<N>,
        ray: &RayLocal<N>,
        tmin: f64,
        tmax: f64,
    ) -> BlockHits<N> {
        stats::count(1);
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: `AVX` is only true in code running after an AVX2 check.
            return unsafe { block.hit_avx2(ray, tmin, tmax) };
        }
        block.hit(ray, tmin, tmax)
    }

    /// Tests the children of inner node `cur` against the rays of the packet in the bit set
    /// `rays` (ray q against [lo, limit[q]]) and returns the nearest child met with the rays
    /// that met it (`EMPTY` if none), after pushing the other children met, farthest first (so
    /// they are popped nearest first). A child's entry parameter is the smallest among its rays.
    /// Without `NEAREST_FIRST` (any-hit queries, whose answer does not depend on the order) the
    /// children go in slot order, unsorted, and those whose ids all lie in `skip` are dropped.
    /// Leaves met are not sorted either when no inner node is met with them: the nearest hit
    /// does not depend on the order (see [`Bvh::closest_hit`]), sorting a few leaves costs
    /// unpredictable branches, and it saves few block tests (1.99 against 1.95 per ray on an
    /// icosphere of 1.3 M triangles).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn descend<const AVX: bool, const P: usize, const NEAREST_FIRST: bool>(
        &self,
        packet: &Packet<N, P>,
        cur: u32,
        rays: u32,
        lo: f32,
        limit: &[f32; P],
        skip: &Range<u32>,
        stack: &mut [MaybeUninit<Entry>; STACK_SIZE],
        sp: &mut usize,
    ) -> (u32, u32) {
        let nd = &self.nodes[cur as usize];
        stats::count(0);
        // Byte q of `met`: the children ray q meets; `tn`: the smallest entry per child.
        let (met, tn) = slabs::<N, AVX, P>(packet, nd, rays, lo, limit);
        let mut any = met;
        any |= any >> 32;
        any |= any >> 16;
        any |= any >> 8;
        let mut mask = (any & 0xff) as u32;
        if !NEAREST_FIRST && !skip.is_empty() {
            let r = &self.ranges[cur as usize];
            for l in 0..NW {
                let inside = skip.start <= r[0][l] && r[1][l] < skip.end;
                mask &= !((inside as u32) << l);
            }
        }
        if mask == 0 {
            return (EMPTY, 0);
        }
        // The slots holding leaves (or nothing), and those holding nothing.
        let (leafy, empty) = leaf_slots::<AVX>(&nd.child);
        if NEAREST_FIRST {
            // The leaves the next packets will likely meet (see `prefetch_block`).
            let mut leaves = leafy & !empty;
            while leaves != 0 {
                let l = leaves.trailing_zeros() as usize;
                leaves &= leaves - 1;
                prefetch_block(self.block_ptr(nd.child[l]), Block::<N>::HEAD);
            }
        }
        // Byte l of `by_child`: the rays that meet child l.
        let by_child = transpose8(met);
        let rays_of = |l: usize| ((by_child >> (8 * l)) & 0xff) as u32;
        if mask & (mask - 1) == 0 {
            let l = mask.trailing_zeros() as usize;
            return (nd.child[l], rays_of(l));
        }
        if !NEAREST_FIRST || mask & !leafy == 0 {
            // Any order finds the same answer (shadow rays, leaves): children in slot order.
            let mut rest = mask & (mask - 1);
            while rest != 0 {
                let l = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                if NEAREST_FIRST {
                    // Tested soon (unless a hit culls them): fetch them whole now.
                    prefetch_block(self.block_ptr(nd.child[l]), size_of::<Block<N>>());
                }
                stack[*sp].write(Entry {
                    node: nd.child[l],
                    rays: rays_of(l),
                    t: tn[l],
                });
                *sp += 1;
            }
            let l = mask.trailing_zeros() as usize;
            return (nd.child[l], rays_of(l));
        }
        // Insertion sort of the children met by entry parameter (a fixed-trip loop over the
        // lanes predicts better than iterating over the set bits).
        let mut hits = [(0.0f32, 0usize); NW];
        let mut c = 0;
        for l in 0..NW {
            if mask & (1 << l) != 0 {
                let mut j = c;
                while j > 0 && hits[j - 1].0 > tn[l] {
                    hits[j] = hits[j - 1];
                    j -= 1;
                }
                hits[j] = (tn[l], l);
                c += 1;
            }
        }
        for j in (1..c).rev() {
            let (t, l) = hits[j];
            stack[*sp].write(Entry {
                node: nd.child[l],
                rays: rays_of(l),
                t,
            });
            *sp += 1;
        }
        let l = hits[0].1;
        (nd.child[l], rays_of(l))
    }

    /// Pops the next stack entry that still has rays within reach (ray q keeps an entry whose
    /// parameter is ≤ `limit[q]`, restricted to `alive`), or `None` when the stack is empty.
    #[inline(always)]
    fn pop<const AVX: bool, const P: usize>(
        stack: &[MaybeUninit<Entry>; STACK_SIZE],
        sp: &mut usize,
        limit: &[f32; P],
        alive: u32,
    ) -> Option<(u32, u32)> {
        while *sp > 0 {
            *sp -= 1;
            // SAFETY: the entries below `sp` were all written by `descend`.
            let e = unsafe { stack[*sp].assume_init() };
            let near = within::<AVX, P>(e.t, limit);
            let rays = e.rays & near & alive;
            if rays != 0 {
                return Some((e.node, rays));
            }
        }
        None
    }

    #[inline(always)]
    fn closest_hits_impl<const AVX: bool, const P: usize>(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: f64,
        accept: &impl Fn(u32) -> bool,
        out: &mut [Option<Hit<N>>],
    ) {
        let k = rays.len();
        if self.nodes.is_empty() || !(tmin < tmax) || k == 0 {
            out.fill(None);
            return;
        }
        let mut slot = MaybeUninit::uninit();
        let packet = Packet::<N, P>::init(&mut slot, rays, self.reach);
        // Boxes are culled against [tmin, best] widened (T_PAD, then outward to f32); simplices
        // use the exact open interval.
        let lo = f32_down(pad_down(tmin));
        let mut limit = [f32::NEG_INFINITY; P];
        limit[..k].fill(f32_up(pad_up(tmax)));
        let mut best = [Best {
            t: tmax,
            id: u32::MAX,
            bary: [0.0; N],
            found: false,
            block: 0,
            lane: 0,
        }; P];
        // Blocks accept t < tmax, then, while a hit is held, t ≤ best.t (ties are settled by id).
        let mut tmax_b = [tmax; P];
        let mut stack = [MaybeUninit::<Entry>::uninit(); STACK_SIZE];
        let mut sp = 0usize;
        let (mut cur, mut cur_rays) = (0u32, (1u32 << k) - 1);
        loop {
            // Descend through inner nodes, nearest child first.
            while cur & LEAF == 0 {
                (cur, cur_rays) = self.descend::<AVX, P, true>(
                    packet,
                    cur,
                    cur_rays,
                    lo,
                    &limit,
                    &(0..0),
                    &mut stack,
                    &mut sp,
                );
            }
            if cur != EMPTY {
                let block = self.block(cur);
                prefetch_block(block, size_of::<Block<N>>());
                let mut left = cur_rays;
                while left != 0 {
                    let q = left.trailing_zeros() as usize;
                    left &= left - 1;
                    let hits = self.block_hit::<AVX>(block, &packet.pre[q].local, tmin, tmax_b[q]);
                    let mut mask = hits.mask;
                    let b = &mut best[q];
                    while mask != 0 {
                        let l = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let (t, id) = (hits.t[l], block.ids[l]);
                        if (!b.found || t < b.t || (t == b.t && id < b.id)) && accept(id) {
                            *b = Best {
                                t,
                                id,
                                bary: hits.bary(l),
                                found: true,
                                block: cur & !LEAF,
                                lane: l as u32,
                            };
                            limit[q] = f32_up(pad_up(t));
                            // `t.next_up()`, by one step when t > 0 (then finite: the block
                            // tests accept only t < tmax_b, strictly).
                            debug_assert!(t < f64::INFINITY);
                            tmax_b[q] = if t > 0.0 {
                                f64::from_bits(t.to_bits() + 1)
                            } else {
                                t.next_up()
                            };
                        }
                    }
                }
            }
            // Pop the next subtree whose entry parameter is still within reach of a ray.
            match Self::pop::<AVX, P>(&stack, &mut sp, &limit, u32::MAX) {
                Some(next) => (cur, cur_rays) = next,
                None => break,
            }
        }
        for (o, b) in out.iter_mut().zip(&best) {
            *o = b.found.then(|| {
                let m = &self.blocks[b.block as usize].m[0];
                Hit {
                    t: b.t,
                    prim: b.id,
                    bary: b.bary,
                    normal: std::array::from_fn(|i| m[i][b.lane as usize]),
                }
            });
        }
    }

    #[inline(always)]
    fn any_hits_impl<const AVX: bool, const P: usize>(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: &[f64],
        accept: &impl Fn(u32) -> bool,
        skip: &Range<u32>,
        out: &mut [bool],
    ) {
        out.fill(false);
        let k = rays.len();
        if self.nodes.is_empty() || k == 0 {
            return;
        }
        let whole = (
            self.ranges[0][0].iter().copied().min().unwrap(),
            self.ranges[0][1].iter().copied().max().unwrap(),
        );
        if skip.start <= whole.0 && whole.1 < skip.end {
            return;
        }
        let mut slot = MaybeUninit::uninit();
        let packet = Packet::<N, P>::init(&mut slot, rays, self.reach);
        let lo = f32_down(pad_down(tmin));
        let mut limit = [f32::NEG_INFINITY; P];
        // The rays still looking for a hit.
        let mut alive = 0u32;
        for (q, &t) in tmax.iter().enumerate() {
            if tmin < t {
                limit[q] = f32_up(pad_up(t));
                alive |= 1 << q;
            }
        }
        let mut stack = [MaybeUninit::<Entry>::uninit(); STACK_SIZE];
        let mut sp = 0usize;
        let (mut cur, mut cur_rays) = (0u32, alive);
        while alive != 0 {
            while cur & LEAF == 0 {
                (cur, cur_rays) = self.descend::<AVX, P, false>(
                    packet, cur, cur_rays, lo, &limit, skip, &mut stack, &mut sp,
                );
            }
            if cur != EMPTY {
                let block = self.block(cur);
                prefetch_block(block, size_of::<Block<N>>());
                let mut left = cur_rays & alive;
                while left != 0 {
                    let q = left.trailing_zeros() as usize;
                    left &= left - 1;
                    let mut mask = self
                        .block_hit::<AVX>(block, &packet.pre[q].local, tmin, tmax[q])
                        .mask;
                    while mask != 0 {
                        let l = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let id = block.ids[l];
                        if accept(id) && !skip.contains(&id) {
                            out[q] = true;
                            alive &= !(1 << q);
                            break;
                        }
                    }
                }
            }
            match Self::pop::<AVX, P>(&stack, &mut sp, &limit, alive) {
                Some(next) => (cur, cur_rays) = next,
                None => break,
            }
        }
    }
}

/// Slab tests of the children of `node` for the rays of the packet in the bit set `rays` (ray q
/// against [lo, limit[q]]): byte q of the first result holds the children ray q meets, and the
/// second the smallest entry parameter per child (+∞ for a child no ray meets).
#[inline(always)]
fn slabs<const N: usize, const AVX: bool, const P: usize>(
    packet: &Packet<N, P>,
    node: &Node<N>,
    rays: u32,
    lo: f32,
    limit: &[f32; P],
) -> (u64, [f32; NW]) {
    #[cfg(target_arch = "x86_64")]
    if AVX && NW == 8 {
        // SAFETY: `AVX` is only true in code running after an AVX2 check.
        return unsafe { slabs_avx2(packet, node, rays, lo, limit) };
    }
    let pre = &packet.pre;
    let mut met = 0u64;
    let mut tn = [f32::INFINITY; NW];
    let mut left = rays;
    while left != 0 {
        let q = left.trailing_zeros() as usize;
        left &= left - 1;
        stats::count(2);
        let (mask, t) = pre[q].slab(node, lo, limit[q]);
        met |= u64::from(mask) << (8 * q);
        for l in 0..NW {
            // Entry parameters of boxes met are never NaN.
            tn[l] = if t[l] < tn[l] { t[l] } else { tn[l] };
        }
    }
    (met, tn)
}

/// [`slabs`] with each ray's test in AVX2 registers (the node's boxes loaded once; when every
/// ray of the packet has the same direction signs, its near and far planes are picked once).
///
/// Not itself compiled for AVX2 but always inlined, as are its helpers (closures would not be),
/// so that its intrinsics end up inlined into the AVX2-compiled traversal. As a
/// `target_feature` function it stayed a call per node visit, returning through memory: 4%
/// more instructions per ray on an icosphere of 1.3 M triangles.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn slabs_avx2<const N: usize, const P: usize>(
    packet: &Packet<N, P>,
    node: &Node<N>,
    rays: u32,
    lo: f32,
    limit: &[f32; P],
) -> (u64, [f32; NW]) {
    use std::arch::x86_64::*;
    // SAFETY (all the intrinsics below): the caller guarantees AVX2; every pointer loaded or
    // stored is a `[f32; NW]` (unaligned accesses).
    unsafe {
        let mut tn = _mm256_set1_ps(f32::INFINITY);
        let mut met = 0u64;
        let mut left = rays;
        let (mut bn, mut bf) = ([_mm256_setzero_ps(); N], [_mm256_setzero_ps(); N]);
        let (mut dn, mut df) = ([_mm256_setzero_ps(); N], [_mm256_setzero_ps(); N]);
        if let Some(side) = &packet.octant {
            for i in 0..N {
                bn[i] = _mm256_loadu_ps(node.b[side[i] & 1][i].as_ptr());
                bf[i] = _mm256_loadu_ps(node.b[(side[i] & 1) ^ 1][i].as_ptr());
            }
            if packet.shared_origin {
                // One origin (a pinhole camera's rays): the differences are the same for every
                // ray.
                slab_planes(&packet.pre[0], &bn, &bf, &mut dn, &mut df);
                while left != 0 {
                    let q = left.trailing_zeros() as usize;
                    left &= left - 1;
                    slab_ray(&packet.pre[q], q, &dn, &df, lo, limit[q], &mut met, &mut tn);
                }
            } else {
                while left != 0 {
                    let q = left.trailing_zeros() as usize;
                    left &= left - 1;
                    slab_planes(&packet.pre[q], &bn, &bf, &mut dn, &mut df);
                    slab_ray(&packet.pre[q], q, &dn, &df, lo, limit[q], &mut met, &mut tn);
                }
            }
        } else {
            while left != 0 {
                let q = left.trailing_zeros() as usize;
                left &= left - 1;
                let side = &packet.pre[q].near;
                for i in 0..N {
                    bn[i] = _mm256_loadu_ps(node.b[side[i] & 1][i].as_ptr());
                    bf[i] = _mm256_loadu_ps(node.b[(side[i] & 1) ^ 1][i].as_ptr());
                }
                slab_planes(&packet.pre[q], &bn, &bf, &mut dn, &mut df);
                slab_ray(&packet.pre[q], q, &dn, &df, lo, limit[q], &mut met, &mut tn);
            }
        }
        let mut out = [0.0f32; NW];
        _mm256_storeu_ps(out.as_mut_ptr(), tn);
        (met, out)
    }
}

/// The planes `bn` (entered) and `bf` (left) relative to the shifted origins of ray `p`, into
/// `dn` and `df`. Part of [`slabs_avx2`] (always inlined, no closures: see there).
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn slab_planes<const N: usize>(
    p: &RayPre<N>,
    bn: &[std::arch::x86_64::__m256; N],
    bf: &[std::arch::x86_64::__m256; N],
    dn: &mut [std::arch::x86_64::__m256; N],
    df: &mut [std::arch::x86_64::__m256; N],
) {
    use std::arch::x86_64::*;
    for i in 0..N {
        // SAFETY: the caller guarantees AVX2.
        unsafe {
            dn[i] = _mm256_sub_ps(bn[i], _mm256_set1_ps(p.o_near[i]));
            df[i] = _mm256_sub_ps(bf[i], _mm256_set1_ps(p.o_far[i]));
        }
    }
}

/// Ray `p` (slot q) against the slabs whose entry and exit planes, relative to its shifted
/// origin, are `dn` and `df`: (b − o')·(1/d) within [lo, limit]. Sets byte q of `met` to the
/// children met and lowers `tn` to their entry parameters. Part of [`slabs_avx2`].
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn slab_ray<const N: usize>(
    p: &RayPre<N>,
    q: usize,
    dn: &[std::arch::x86_64::__m256; N],
    df: &[std::arch::x86_64::__m256; N],
    lo: f32,
    limit: f32,
    met: &mut u64,
    tn: &mut std::arch::x86_64::__m256,
) {
    use std::arch::x86_64::*;
    stats::count(2);
    // SAFETY: the caller guarantees AVX2.
    unsafe {
        // A running max/min from [lo, limit]: maxps/minps return their second operand when
        // either is NaN, so a NaN parameter leaves its slab unrestricted, as in `RayPre::slab`
        // (whose pairwise reduction of exact max/min gives the same values).
        let mut near = _mm256_set1_ps(lo);
        let mut far = _mm256_set1_ps(limit);
        for i in 0..N {
            let inv = _mm256_set1_ps(p.inv[i]);
            near = _mm256_max_ps(_mm256_mul_ps(dn[i], inv), near);
            far = _mm256_min_ps(_mm256_mul_ps(df[i], inv), far);
        }
        let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
        *met |= (_mm256_movemask_ps(hit) as u64) << (8 * q);
        *tn = _mm256_min_ps(
            *tn,
            _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), near, hit),
        );
    }
}

/// Prefetches the first `bytes` (1 ≤ bytes ≤ its size) bytes of a block: [`Block::HEAD`] (what
/// a test reads before its early exit) or all of it (408 bytes for N = 3: 7 or 8 cache lines,
/// depending on where it starts).
///
/// Waiting for blocks took about a fifth of the time on a 1.3 M-triangle icosphere at 512²:
/// its 66 MB of blocks do not stay in the core's caches from one trace to the next, so the
/// first test of each block waited for memory, and once more for its last lines (the rows
/// `r_k`, the ids), read only after the t test passed. Three prefetches hide part of that
/// (same results; each about 2-4% faster there, within the noise on the 4D scenes):
/// - a block about to be tested is fetched whole, so that its lines arrive together;
/// - when a packet meets only leaves of a node, those pushed for later are fetched whole while
///   the first is tested;
/// - the heads of all the leaves of a node a packet enters are fetched, met or not: the next
///   packets of the tile, a few pixels away, mostly meet the same node's other leaves.
#[inline(always)]
fn prefetch_block<const N: usize>(block: *const Block<N>, bytes: usize) {
    debug_assert!((1..=size_of::<Block<N>>()).contains(&bytes));
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (block, bytes);
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        let p = block.cast::<i8>();
        // Every 64 bytes from the start, then the last byte (a fixed count: unrolled).
        for k in 0..=(bytes - 1) / 64 + 1 {
            // SAFETY: a prefetch never faults, whatever the address.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add((64 * k).min(bytes - 1))) };
        }
    }
}

/// The bit sets of the slots of `child` holding a leaf or nothing (those whose reference has
/// the `LEAF` bit) and of those holding nothing.
#[inline(always)]
fn leaf_slots<const AVX: bool>(child: &[u32; NW]) -> (u32, u32) {
    #[cfg(target_arch = "x86_64")]
    if AVX && NW == 8 {
        use std::arch::x86_64::*;
        // SAFETY: `AVX` is only true in code running after an AVX2 check; `child` holds 8 u32
        // (unaligned load).
        unsafe {
            let c = _mm256_loadu_si256(child.as_ptr().cast());
            let leafy = _mm256_movemask_ps(_mm256_castsi256_ps(c)) as u32;
            let none = _mm256_cmpeq_epi32(c, _mm256_set1_epi32(-1));
            return (leafy, _mm256_movemask_ps(_mm256_castsi256_ps(none)) as u32);
        }
    }
    let (mut leafy, mut empty) = (0, 0);
    for (l, &c) in child.iter().enumerate() {
        leafy |= u32::from(c & LEAF != 0) << l;
        empty |= u32::from(c == EMPTY) << l;
    }
    (leafy, empty)
}

/// The bit set of the rays q with `t ≤ limit[q]`.
#[inline(always)]
fn within<const AVX: bool, const P: usize>(t: f32, limit: &[f32; P]) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if AVX && P == 8 {
        use std::arch::x86_64::*;
        /// # Safety
        /// The CPU must support AVX2.
        #[target_feature(enable = "avx2")]
        #[inline]
        unsafe fn within8(t: f32, limit: *const f32) -> u32 {
            // SAFETY: the caller passes 8 valid f32 (unaligned load).
            let l = unsafe { _mm256_loadu_ps(limit) };
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_set1_ps(t), l)) as u32
        }
        // SAFETY: `AVX` is only true in code running after an AVX2 check; P == 8.
        return unsafe { within8(t, limit.as_ptr()) };
    }
    let mut near = 0u32;
    for (q, &l) in limit.iter().enumerate() {
        near |= u32::from(t <= l) << q;
    }
    near
}

/// The rays of a packet, prepared for traversal.
struct Packet<const N: usize, const P: usize> {
    pre: [RayPre<N>; P],
    /// The rays' common [`RayPre::near`] sides, when they all have the same.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    octant: Option<[usize; N]>,
    /// Whether every ray has the same shifted f32 origins ([`RayPre::o_near`], `o_far`): the
    /// slab planes relative to the origin are then computed once per node (bit-identical).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    shared_origin: bool,
}

impl<const N: usize, const P: usize> Packet<N, P> {
    /// Prepares 1 ≤ `rays.len()` ≤ P ≤ [`PACKET`] rays in `slot` (unused slots repeat the
    /// first ray; no traversal mask ever names them). In place: a packet built apart and moved
    /// cost a 1 KB copy (a `memcpy` call) per packet.
    #[inline(always)]
    fn init<'a>(slot: &'a mut MaybeUninit<Self>, rays: &[Ray<N>], reach: f64) -> &'a Self {
        let p = slot.as_mut_ptr();
        // SAFETY: the pointers are to fields of `slot`, in bounds (q < P), and every field is
        // written before the packet is referenced.
        unsafe {
            let pre = (&raw mut (*p).pre).cast::<RayPre<N>>();
            for q in 0..P {
                pre.add(q)
                    .write(RayPre::new(rays.get(q).unwrap_or(&rays[0]), reach));
            }
            let pre = &(*p).pre;
            (&raw mut (*p).octant).write(
                pre.iter()
                    .all(|p| p.near == pre[0].near)
                    .then_some(pre[0].near),
            );
            (&raw mut (*p).shared_origin).write(pre.iter().all(|p| {
                p.o_near.map(f32::to_bits) == pre[0].o_near.map(f32::to_bits)
                    && p.o_far.map(f32::to_bits) == pre[0].o_far.map(f32::to_bits)
            }));
            // Every field above: this pattern stops compiling if a field is added.
            let Packet {
                pre: _,
                octant: _,
                shared_origin: _,
            } = slot.assume_init_ref();
            slot.assume_init_ref()
        }
    }
}

/// A traversal stack entry: a subtree, the rays of the packet that met its box, and the
/// smallest of their entry parameters.
#[derive(Clone, Copy)]
struct Entry {
    node: u32,
    rays: u32,
    t: f32,
}

/// Transposes the 8×8 bit matrix whose row r is byte r of `x` (bit c of the byte is column c):
/// bit `8r + c` moves to bit `8c + r` (Hacker's Delight, §7-3).
#[inline(always)]
fn transpose8(mut x: u64) -> u64 {
    let t = (x ^ (x >> 7)) & 0x00aa_00aa_00aa_00aa;
    x ^= t ^ (t << 7);
    let t = (x ^ (x >> 14)) & 0x0000_cccc_0000_cccc;
    x ^= t ^ (t << 14);
    let t = (x ^ (x >> 28)) & 0x0000_0000_f0f0_f0f0;
    x ^ t ^ (t << 28)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{barycentric, ray_hyperplane};
    use crate::linalg::{add, add_scaled, mat_vec, norm, scale};
    use crate::testutil::{for_each_dim, random_rotation, random_vector, rng, TestRng};
    use rand::Rng;
    use std::collections::HashSet;

    /// Random simplex with vertices `center + random_vector(size)`.
    fn random_simplex<const N: usize>(
        r: &mut TestRng,
        center: &Vector<N>,
        size: f64,
    ) -> [[f64; N]; N] {
        std::array::from_fn(|_| add(center, &random_vector::<N>(r, size)))
    }

    /// A point of the simplex's hyperplane with random barycentric weights in [lo, hi] (then
    /// normalized to sum 1).
    fn plane_point<const N: usize>(
        r: &mut TestRng,
        pts: &[[f64; N]; N],
        lo: f64,
        hi: f64,
    ) -> Vector<N> {
        let mut w: Vec<f64> = (0..N).map(|_| r.random_range(lo..hi)).collect();
        let s: f64 = w.iter().sum();
        w.iter_mut().for_each(|x| *x /= s);
        let mut x = [0.0; N];
        for (p, wi) in pts.iter().zip(&w) {
            x = add_scaled(&x, *wi, p);
        }
        x
    }

    fn intersect_agrees_with_geometry<const N: usize>() {
        let mut r = rng(1000 + N as u64);
        let (mut hits, mut misses, mut near_edge) = (0, 0, 0);
        for case in 0..3000 {
            let pts = random_simplex::<N>(&mut r, &[0.0; N], 2.0);
            let Some(ps) = PreparedSimplex::new(&pts) else {
                assert!(hyperplane(&pts).is_err());
                continue;
            };
            let plane = hyperplane(&pts).unwrap();
            assert_eq!(ps.normal(), plane.normal, "N={N}");
            assert_eq!(ps.origin(), pts[0]);
            let origin = random_vector::<N>(&mut r, 4.0);
            let target = plane_point(&mut r, &pts, -0.12, 1.0);
            let dir = scale(
                &crate::linalg::sub(&target, &origin),
                r.random_range(0.2..3.0),
            );
            let ray = Ray { origin, dir };
            let (tmin, tmax) = if case % 4 == 0 {
                (0.5, 2.0)
            } else {
                (0.0, f64::INFINITY)
            };
            let got = ps.intersect(&ray, tmin, tmax);
            // Independent computation: eq. of section "Ray Tracing" + Gram/Cramer barycentrics.
            let t = ray_hyperplane(&origin, &dir, &pts).unwrap();
            let mut bary = [0.0; 9];
            barycentric(&ray.at(t), &pts, &mut bary).unwrap();
            let min_bary = bary[..N].iter().cloned().fold(f64::INFINITY, f64::min);
            let expect = t > tmin && t < tmax && min_bary >= 0.0;
            if min_bary.abs() <= 1e-9 || (t - tmin).abs() < 1e-9 || (t - tmax).abs() < 1e-9 {
                near_edge += 1;
            } else {
                assert_eq!(
                    got.is_some(),
                    expect,
                    "N={N} case {case}: t={t} bary={bary:?}"
                );
            }
            if let Some((gt, gb)) = got {
                hits += 1;
                assert!(
                    (gt - t).abs() <= 1e-9 * t.abs().max(1.0),
                    "N={N}: t {gt} vs {t}"
                );
                for k in 0..N {
                    assert!(
                        (gb[k] - bary[k]).abs() <= 1e-9,
                        "N={N}: bary {gb:?} vs {bary:?}"
                    );
                }
                let s: f64 = gb.iter().sum();
                assert!((s - 1.0).abs() < 1e-12);
            } else {
                misses += 1;
            }
            // A direction inside the hyperplane is parallel: a miss.
            let along = crate::linalg::sub(&pts[1], &pts[0]);
            assert_eq!(
                ps.intersect(
                    &Ray { origin, dir: along },
                    f64::NEG_INFINITY,
                    f64::INFINITY
                ),
                None
            );
            assert_eq!(
                ps.intersect(
                    &Ray {
                        origin,
                        dir: [0.0; N]
                    },
                    f64::NEG_INFINITY,
                    f64::INFINITY
                ),
                None
            );
        }
        assert!(
            hits > 400 && misses > 400 && near_edge < 30,
            "N={N}: {hits} {misses} {near_edge}"
        );
    }

    #[test]
    fn accel_prepared_simplex_intersect_agrees_with_geometry() {
        for_each_dim!(intersect_agrees_with_geometry);
    }

    #[test]
    fn accel_degenerate_simplices_are_rejected() {
        assert!(PreparedSimplex::<3>::new(&[[0.0; 3], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]).is_none());
        assert!(PreparedSimplex::<2>::new(&[[1.0, 2.0], [1.0, 2.0]]).is_none());
        assert!(PreparedSimplex::<2>::new(&[[f64::NAN, 0.0], [1.0, 2.0]]).is_none());
        // Both vertex orders give the same hit; the normal flips (eq. 6).
        let a = PreparedSimplex::<3>::new(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]).unwrap();
        let b = PreparedSimplex::<3>::new(&[[0., 0., 0.], [0., 1., 0.], [1., 0., 0.]]).unwrap();
        assert_eq!(a.normal(), [0., 0., 1.]);
        assert_eq!(b.normal(), [0., 0., -1.]);
        let ray = Ray {
            origin: [0.25, 0.25, 2.0],
            dir: [0.0, 0.0, -1.0],
        };
        let (ta, ba) = a.intersect(&ray, 0.0, f64::INFINITY).unwrap();
        let (tb, bb) = b.intersect(&ray, 0.0, f64::INFINITY).unwrap();
        assert_eq!((ta, tb), (2.0, 2.0));
        assert_eq!(ba, [0.5, 0.25, 0.25]);
        assert_eq!(bb, [0.5, 0.25, 0.25]);
        // The interval is open.
        assert!(a.intersect(&ray, 0.0, 2.0).is_none());
        assert!(a.intersect(&ray, 2.0, 3.0).is_none());
    }

    /// Brute force over all simplices: the minimum of (t, id) over accepted hits.
    fn brute<const N: usize>(
        prims: &[(PreparedSimplex<N>, u32)],
        ray: &Ray<N>,
        tmin: f64,
        tmax: f64,
        accept: impl Fn(u32) -> bool,
    ) -> Option<Hit<N>> {
        let mut best: Option<Hit<N>> = None;
        for (p, id) in prims {
            if !accept(*id) {
                continue;
            }
            if let Some((t, bary)) = p.intersect(ray, tmin, tmax) {
                if best.is_none_or(|b| t < b.t || (t == b.t && *id < b.prim)) {
                    best = Some(Hit {
                        t,
                        prim: *id,
                        bary,
                        normal: p.normal(),
                    });
                }
            }
        }
        best
    }

    /// A soup of `count` small random simplices (plus a few large ones and exact duplicates with
    /// other ids, which tie exactly), with scattered ids.
    fn soup<const N: usize>(r: &mut TestRng, count: usize) -> Vec<([[f64; N]; N], u32)> {
        let mut out = vec![];
        for i in 0..count {
            let size = if i % 50 == 0 { 1.5 } else { 0.35 };
            let c = random_vector::<N>(r, 2.0);
            out.push((random_simplex(r, &c, size), (7 * i as u32 + 3) ^ 0x55));
        }
        for j in 0..count / 20 {
            let (pts, id) = out[j * 7 % count];
            out.push((pts, id ^ 0x1000));
        }
        out
    }

    fn prepare<const N: usize>(soup: &[([[f64; N]; N], u32)]) -> Vec<(PreparedSimplex<N>, u32)> {
        soup.iter()
            .filter_map(|(p, id)| Some((PreparedSimplex::new(p)?, *id)))
            .collect()
    }

    fn build_soup<const N: usize>(soup: &[([[f64; N]; N], u32)], par_min: usize) -> Bvh<N> {
        let mut prims = vec![];
        let mut ids = vec![];
        let mut bounds = vec![];
        for (p, id) in soup {
            if let Some(ps) = PreparedSimplex::new(p) {
                prims.push(ps);
                ids.push(*id);
                bounds.push(simplex_bounds(p));
            }
        }
        Bvh::build_with(prims, ids, bounds, par_min)
    }

    fn bvh_agrees_with_brute_force<const N: usize>() {
        let mut r = rng(2000 + N as u64);
        for (round, count) in [1usize, 3, 5, 17, 300].into_iter().enumerate() {
            let s = soup::<N>(&mut r, count);
            let prims = prepare(&s);
            let bvh = build_soup(&s, PAR_MIN);
            assert_eq!(bvh.len(), prims.len());
            assert!(bvh.blocks.iter().all(|b| (1..=W as u32).contains(&b.count)));
            let (mut hits, mut ties) = (0, 0);
            for case in 0..1500 {
                let origin = random_vector::<N>(&mut r, 3.5);
                let dir = if case % 2 == 0 {
                    // Aim at a point of a random simplex, so that most rays hit something.
                    let (pts, _) = &s[r.random_range(0..s.len())];
                    crate::linalg::sub(&plane_point(&mut r, pts, 0.0, 1.0), &origin)
                } else {
                    random_vector::<N>(&mut r, 1.0)
                };
                let ray = Ray { origin, dir };
                let (tmin, tmax) = match case % 5 {
                    0 => (0.0, f64::INFINITY),
                    1 => (0.3, 0.9),
                    2 => (-1.0, 1.0),
                    3 => (0.0, 1.0),
                    _ => (0.5, f64::INFINITY),
                };
                let filters: [&dyn Fn(u32) -> bool; 3] =
                    [&|_| true, &|id| id % 3 != 0, &|id| id & 0x1000 == 0];
                // Ids skipped by the any-hit queries: none, a random range, or all.
                let a = r.random_range(0..2200);
                let skip = [0..0, a..a + r.random_range(0..1100), 0..u32::MAX][case % 3].clone();
                for (fi, f) in filters.iter().enumerate() {
                    let want = brute(&prims, &ray, tmin, tmax, f);
                    let got = bvh.closest_hit(&ray, tmin, tmax, f);
                    assert_eq!(got, want, "N={N} round {round} case {case} filter {fi}");
                    let kept = |id| f(id) && !skip.contains(&id);
                    let want_any = brute(&prims, &ray, tmin, tmax, kept).is_some();
                    assert_eq!(
                        bvh.any_hit(&ray, tmin, tmax, f, skip.clone()),
                        want_any,
                        "N={N} any_hit, skipping {skip:?}"
                    );
                    // The portable/SSE path too (the public calls take AVX2 when available).
                    let (mut sse, mut blocked) = ([None], [false]);
                    let one = std::slice::from_ref(&ray);
                    bvh.closest_hits_impl::<false, 1>(one, tmin, tmax, f, &mut sse);
                    assert_eq!(
                        sse[0], want,
                        "N={N} round {round} case {case} filter {fi}: SSE path"
                    );
                    bvh.any_hits_impl::<false, 1>(one, tmin, &[tmax], f, &skip, &mut blocked);
                    assert_eq!(blocked[0], want_any);
                    if let Some(h) = want {
                        hits += 1;
                        let same_t = prims.iter().filter(|(p, id)| {
                            f(*id) && p.intersect(&ray, tmin, tmax).is_some_and(|(t, _)| t == h.t)
                        });
                        ties += (same_t.count() > 1) as usize;
                    }
                }
            }
            if count == 300 {
                assert!(
                    hits > 1000 && ties > 10,
                    "N={N}: {hits} hits, {ties} exact ties"
                );
            }
        }
    }

    #[test]
    fn accel_bvh_closest_and_any_hit_equal_brute_force() {
        for_each_dim!(bvh_agrees_with_brute_force);
    }

    /// Rays for packet tests, of kind `kind`: 0 a pinhole (one origin, directions fanned
    /// around an aim at a simplex), 1 shadow-like (spread origins aimed near one point), 2
    /// random, 3 like 0 with one direction component exactly zero in every ray.
    fn packet_rays<const N: usize>(
        r: &mut TestRng,
        s: &[([[f64; N]; N], u32)],
        kind: usize,
        count: usize,
    ) -> Vec<Ray<N>> {
        let origin = random_vector::<N>(r, 3.5);
        let (pts, _) = &s[r.random_range(0..s.len())];
        let aim = plane_point(r, pts, 0.0, 1.0);
        let spread = [0.01, 0.1][r.random_range(0..2)];
        (0..count)
            .map(|_| match kind {
                0 | 3 => {
                    let to = add(&aim, &random_vector::<N>(r, spread));
                    let mut dir = crate::linalg::sub(&to, &origin);
                    if kind == 3 {
                        dir[0] = 0.0;
                    }
                    Ray { origin, dir }
                }
                1 => {
                    let o = add(&aim, &random_vector::<N>(r, spread));
                    let light = add(&origin, &random_vector::<N>(r, spread));
                    Ray {
                        origin: o,
                        dir: crate::linalg::sub(&light, &o),
                    }
                }
                _ => Ray {
                    origin: random_vector::<N>(r, 3.5),
                    dir: random_vector::<N>(r, 1.0),
                },
            })
            .collect()
    }

    fn packets_agree_with_brute_force<const N: usize>() {
        let mut r = rng(2500 + N as u64);
        let s = soup::<N>(&mut r, 300);
        let prims = prepare(&s);
        let bvh = build_soup(&s, PAR_MIN);
        let mut hits = 0;
        // Packets of mixed octants, of one octant (slab planes picked once per node), and of one
        // octant and one origin (plane differences computed once per node).
        let mut octants = [0; 3];
        for case in 0..400 {
            let kind = case % 4;
            let count = 1 + case % 11;
            let rays = packet_rays(&mut r, &s, kind, count);
            for rs in rays.chunks(PACKET) {
                let mut slot = MaybeUninit::uninit();
                let packet = Packet::<N, PACKET>::init(&mut slot, rs, bvh.reach);
                let kind = match (packet.octant, packet.shared_origin) {
                    (None, _) => 0,
                    (Some(_), false) => 1,
                    (Some(_), true) => 2,
                };
                octants[kind] += 1;
            }
            let (tmin, tmax) = [(0.0, f64::INFINITY), (0.2, 1.0)][case % 2];
            let tmaxes: Vec<f64> = (0..count).map(|_| r.random_range(0.1..2.0)).collect();
            let filters: [&dyn Fn(u32) -> bool; 2] = [&|_| true, &|id| id % 3 != 0];
            for f in filters {
                let want: Vec<_> = rays
                    .iter()
                    .map(|ray| brute(&prims, ray, tmin, tmax, f))
                    .collect();
                // Stale results, which every element's write must replace.
                let stale = Some(Hit {
                    t: -1.0,
                    prim: u32::MAX,
                    bary: [f64::NAN; N],
                    normal: [0.0; N],
                });
                let mut got = vec![stale; count];
                bvh.closest_hits(&rays, tmin, tmax, f, &mut got);
                assert_eq!(got, want, "N={N} case {case}");
                let mut portable = vec![stale; count];
                for (rs, out) in rays.chunks(PACKET).zip(portable.chunks_mut(PACKET)) {
                    bvh.closest_hits_impl::<false, PACKET>(rs, tmin, tmax, &f, out);
                }
                assert_eq!(portable, want, "N={N} case {case}: portable path");
                hits += want.iter().filter(|h| h.is_some()).count();

                let want: Vec<bool> = rays
                    .iter()
                    .zip(&tmaxes)
                    .map(|(ray, &t)| brute(&prims, ray, tmin, t, f).is_some())
                    .collect();
                let mut got = vec![false; count];
                bvh.any_hits(&rays, tmin, &tmaxes, f, 0..0, &mut got);
                assert_eq!(got, want, "N={N} case {case}: any_hits");
                let mut portable = vec![false; count];
                let chunks = rays.chunks(PACKET).zip(tmaxes.chunks(PACKET));
                for ((rs, ts), out) in chunks.zip(portable.chunks_mut(PACKET)) {
                    bvh.any_hits_impl::<false, PACKET>(rs, tmin, ts, &f, &(0..0), out);
                }
                assert_eq!(portable, want, "N={N} case {case}: portable any_hits");
            }
        }
        assert!(hits > 250, "N={N}: only {hits} hits");
        assert!(
            octants.iter().all(|&c| c > 50),
            "N={N}: packets of mixed octants, one octant, one octant and origin: {octants:?}"
        );
    }

    #[test]
    fn accel_packets_equal_brute_force_ray_by_ray() {
        for_each_dim!(packets_agree_with_brute_force);
    }

    /// Two clusters of simplices with ids 0..150 and 150..300: the id range of every child slot
    /// is the min/max over its subtree, whole subtrees of one cluster can be skipped, and
    /// any-hit queries that skip ids agree with brute force over the ids they keep.
    fn skipping_ids_agrees_with_brute_force<const N: usize>() {
        let mut r = rng(2700 + N as u64);
        let mut s = vec![];
        for i in 0..300u32 {
            let mut c = random_vector::<N>(&mut r, 1.0);
            c[0] += if i < 150 { -2.0 } else { 2.0 };
            s.push((random_simplex(&mut r, &c, 0.4), i));
        }
        let prims = prepare(&s);
        let bvh = build_soup(&s, PAR_MIN);
        fn subtree<const N: usize>(bvh: &Bvh<N>, c: u32) -> (u32, u32) {
            if c == EMPTY {
                return (u32::MAX, 0);
            }
            if c & LEAF != 0 {
                let b = &bvh.blocks[(c & !LEAF) as usize];
                let ids = &b.ids[..b.count as usize];
                return (*ids.iter().min().unwrap(), *ids.iter().max().unwrap());
            }
            bvh.nodes[c as usize]
                .child
                .iter()
                .map(|&k| subtree(bvh, k))
                .fold((u32::MAX, 0), |a, b| (a.0.min(b.0), a.1.max(b.1)))
        }
        let mut pure = 0;
        for (i, nd) in bvh.nodes.iter().enumerate() {
            for l in 0..NW {
                let want = subtree(&bvh, nd.child[l]);
                assert_eq!((bvh.ranges[i][0][l], bvh.ranges[i][1][l]), want, "N={N}");
                pure += (nd.child[l] & LEAF == 0 && want.1 < 150) as usize;
            }
        }
        assert!(
            pure > 0,
            "N={N}: no inner subtree holds only the first cluster"
        );
        let mut blocked = [0; 3];
        // Nodes visited plus blocks tested, skipping the first cluster by id range (pruned)
        // and by filter (not pruned): the same answers, less work.
        let mut work = [0u64; 2];
        let visits = || stats::LOCAL.with(|c| c.get()[0] + c.get()[1]);
        for case in 0..200 {
            let rays = packet_rays(&mut r, &s, case % 3, 1 + case % PACKET);
            let tmax: Vec<f64> = rays.iter().map(|_| r.random_range(0.5..3.0)).collect();
            let ranges = [
                0..0,
                0..150,
                150..300,
                0..300,
                100..200,
                0..149,
                1..150,
                150..299,
            ];
            for (k, skip) in ranges.into_iter().enumerate() {
                let want: Vec<bool> = rays
                    .iter()
                    .zip(&tmax)
                    .map(|(ray, &t)| brute(&prims, ray, 0.0, t, |id| !skip.contains(&id)).is_some())
                    .collect();
                let mut got = vec![false; rays.len()];
                bvh.any_hits(&rays, 0.0, &tmax, |_| true, skip.clone(), &mut got);
                assert_eq!(got, want, "N={N} case {case}, skipping {skip:?}");
                for ((ray, &t), &w) in rays.iter().zip(&tmax).zip(&want) {
                    assert_eq!(bvh.any_hit(ray, 0.0, t, |_| true, skip.clone()), w);
                }
                if k < 3 {
                    blocked[k] += want.iter().filter(|&&b| b).count();
                }
                if skip == (0..150) {
                    let mut filtered = vec![false; rays.len()];
                    let before = visits();
                    bvh.any_hits(&rays, 0.0, &tmax, |id| id >= 150, 0..0, &mut filtered);
                    let between = visits();
                    bvh.any_hits(&rays, 0.0, &tmax, |_| true, skip.clone(), &mut got);
                    work[0] += visits() - between;
                    work[1] += between - before;
                    assert_eq!(filtered, want);
                }
            }
        }
        assert!(
            blocked.iter().all(|&b| b > 20),
            "N={N}: {blocked:?} rays blocked"
        );
        assert!(
            work[0] * 4 < work[1] * 3,
            "N={N}: {} nodes and blocks visited when skipping ids 0..150, {} when filtering them",
            work[0],
            work[1]
        );
    }

    #[test]
    fn accel_any_hits_skipping_ids_equal_brute_force() {
        for_each_dim!(skipping_ids_agrees_with_brute_force);
    }

    #[test]
    fn accel_transpose8_transposes_the_bit_matrix() {
        let mut r = rng(2700);
        for _ in 0..1000 {
            let x: u64 = r.random();
            let mut want = 0u64;
            for row in 0..8 {
                for col in 0..8 {
                    want |= ((x >> (8 * row + col)) & 1) << (8 * col + row);
                }
            }
            assert_eq!(transpose8(x), want);
        }
    }

    #[test]
    fn accel_empty_bvh_misses() {
        let bvh = Bvh::<3>::build(vec![], vec![], vec![]);
        assert!(bvh.is_empty() && bvh.node_count() == 0 && bvh.depth() == 0);
        assert_eq!(bvh.len(), 0);
        let ray = Ray {
            origin: [0.0; 3],
            dir: [1.0, 0.0, 0.0],
        };
        assert_eq!(bvh.closest_hit(&ray, 0.0, f64::INFINITY, |_| true), None);
        assert!(!bvh.any_hit(&ray, 0.0, f64::INFINITY, |_| true, 0..0));
    }

    /// All permutations of 0..m.
    fn permutations(m: usize) -> Vec<Vec<usize>> {
        if m == 0 {
            return vec![vec![]];
        }
        let mut out = vec![];
        for p in permutations(m - 1) {
            for pos in 0..=p.len() {
                let mut q = p.clone();
                q.insert(pos, m - 1);
                out.push(q);
            }
        }
        out
    }

    /// The boundary of the cube [0, k]^N on the integer grid: each facet cut into k^(N−1) unit
    /// cubes of (N−1)! Kuhn simplices. Kuhn triangulations of neighbouring cubes and facets
    /// agree on shared faces, so the mesh is closed and conforming.
    fn cube_boundary<const N: usize>(k: i64) -> Vec<[[i64; N]; N]> {
        let perms = permutations(N - 1);
        let mut out = vec![];
        for axis in 0..N {
            for side in [0, k] {
                let free: Vec<usize> = (0..N).filter(|&a| a != axis).collect();
                for cell in 0..k.pow(N as u32 - 1) {
                    let mut base = [0i64; N];
                    base[axis] = side;
                    let mut c = cell;
                    for &a in &free {
                        base[a] = c % k;
                        c /= k;
                    }
                    for p in &perms {
                        let mut g = base;
                        out.push(std::array::from_fn(|j| {
                            if j > 0 {
                                g[free[p[j - 1]]] += 1;
                            }
                            g
                        }));
                    }
                }
            }
        }
        out
    }

    fn closed_mesh_is_watertight<const N: usize>() {
        let mut r = rng(3000 + N as u64);
        let k = if N <= 4 { 2 } else { 1 };
        let cells = cube_boundary::<N>(k);
        // Targets: every vertex and every edge midpoint of the mesh (on the integer grid ×2).
        let mut targets: HashSet<[i64; N]> = HashSet::new();
        for s in &cells {
            for a in 0..N {
                targets.insert(s[a].map(|x| 2 * x));
                for b in a + 1..N {
                    targets.insert(std::array::from_fn(|i| s[a][i] + s[b][i]));
                }
            }
        }
        // Every vertex (all coordinates even) and up to 400 edge midpoints (in 8D a Kuhn
        // simplex's box is its whole facet, so each ray tests thousands of simplices).
        let mut targets: Vec<[i64; N]> = targets.into_iter().collect();
        targets.sort();
        let (mut targets, mut mids): (Vec<_>, Vec<_>) = targets
            .into_iter()
            .partition(|g| g.iter().all(|x| x % 2 == 0));
        for j in 0..mids.len().min(400) {
            let pick = r.random_range(j..mids.len());
            mids.swap(j, pick);
            targets.push(mids[j]);
        }
        for shape in 0..2 {
            // 0: the cube [−1, 1]^N itself (box faces on the mesh, zero direction components);
            // 1: a random affine image of it.
            let (m, shift): (Matrix<N>, Vector<N>) = if shape == 0 {
                (crate::linalg::identity(), [0.0; N])
            } else {
                let q = random_rotation::<N>(&mut r);
                let d: Vector<N> = std::array::from_fn(|_| r.random_range(0.5..2.0));
                (
                    std::array::from_fn(|i| std::array::from_fn(|j| q[i][j] * d[j])),
                    random_vector(&mut r, 3.0),
                )
            };
            let map = |g: &[i64; N], den: f64| -> Vector<N> {
                let x: Vector<N> =
                    std::array::from_fn(|i| 2.0 * g[i] as f64 / (den * k as f64) - 1.0);
                add(&mat_vec(&m, &x), &shift)
            };
            let simplices: Vec<[[f64; N]; N]> =
                cells.iter().map(|s| s.map(|v| map(&v, 1.0))).collect();
            let ids: Vec<u32> = (0..simplices.len() as u32).collect();
            let bvh = Bvh::from_simplices(&simplices, &ids);
            assert_eq!(bvh.len(), simplices.len());
            let center = shift;
            for g in &targets {
                let target = map(g, 2.0);
                // From the inside: the one crossing is at the target, t = 1.
                let ray = Ray {
                    origin: center,
                    dir: crate::linalg::sub(&target, &center),
                };
                let h = bvh.closest_hit(&ray, 0.0, f64::INFINITY, |_| true);
                assert!(
                    h.is_some_and(|h| (h.t - 1.0).abs() < 1e-9),
                    "N={N} shape {shape}: from inside to {g:?}: {h:?}"
                );
                // From outside, along a random direction and (axis-aligned cube) along an axis:
                // the first crossing is at or before the target.
                let mut origins = vec![add_scaled(&target, 4.0, &random_unit::<N>(&mut r))];
                if shape == 0 {
                    let axis = r.random_range(0..N);
                    let mut o = target;
                    o[axis] += if target[axis] >= 0.0 { 3.0 } else { -3.0 };
                    origins.push(o);
                }
                for origin in origins {
                    let ray = Ray {
                        origin,
                        dir: crate::linalg::sub(&target, &origin),
                    };
                    let h = bvh.closest_hit(&ray, 0.0, f64::INFINITY, |_| true);
                    let ok = h.is_some_and(|h| h.t <= 1.0 + 1e-9);
                    assert!(
                        ok,
                        "N={N} shape {shape}: outside {origin:?} to {g:?}: {h:?}"
                    );
                    assert!(bvh.any_hit(&ray, 0.0, f64::INFINITY, |_| true, 0..0));
                }
            }
        }
    }

    fn random_unit<const N: usize>(r: &mut TestRng) -> Vector<N> {
        loop {
            let v = random_vector::<N>(r, 1.0);
            let l = norm(&v);
            if l > 0.1 && l <= 1.0 {
                return scale(&v, 1.0 / l);
            }
        }
    }

    #[test]
    fn accel_closed_meshes_are_watertight_at_vertices_and_edges() {
        for_each_dim!(closed_mesh_is_watertight);
    }

    #[test]
    fn accel_build_is_deterministic() {
        fn check<const N: usize>() {
            let mut r = rng(4000 + N as u64);
            let s = soup::<N>(&mut r, 3000);
            let a = build_soup(&s, PAR_MIN);
            let b = build_soup(&s, PAR_MIN);
            assert!(a == b, "N={N}: two builds differ");
            // Maximal forking, and a one-thread pool, give the same tree.
            let c = build_soup(&s, 2);
            assert!(a == c, "N={N}: parallel build differs");
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap();
            let d = pool.install(|| build_soup(&s, 2));
            assert!(a == d, "N={N}: one-thread build differs");
            assert!(a.node_count() > 1 && a.memory_bytes() > 0);
        }
        for_each_dim!(check);
    }

    /// The wide nodes (binary inner nodes) of the layout `plan` gives `bin`, each with its
    /// children, from the root down.
    fn wide_layout<const N: usize>(bin: &[BNode<N>], plan: &Plan) -> Vec<(usize, Vec<usize>)> {
        let mut out = vec![];
        let mut todo = vec![0];
        while let Some(b) = todo.pop() {
            let [j, m] = plan.wide[b];
            let mut kids = vec![];
            plan.expand(bin, b + 1, j as usize, &mut kids);
            plan.expand(bin, bin[b].first as usize, m as usize, &mut kids);
            todo.extend(kids.iter().filter(|&&c| bin[c].count == 0));
            out.push((b, kids));
        }
        out
    }

    /// Against every way of choosing which binary inner nodes become wide nodes (the root
    /// always; valid when each wide node has at most 8 children, its nearest descendants that
    /// are leaves or wide nodes), the plan is valid and has the least summed half area.
    fn wide_collapse_is_optimal<const N: usize>() {
        let mut r = rng(4500 + N as u64);
        let (mut cases, mut opened) = (0, 0);
        while cases < 12 {
            let count = r.random_range(30..70);
            let s = soup::<N>(&mut r, count);
            let bounds: Vec<Bounds<N>> = s.iter().map(|(p, _)| simplex_bounds(p)).collect();
            let (bin, _) = binary_tree(bounds, PAR_MIN);
            let area = |b: usize| half_area(&bin[b].min.map(f64::from), &bin[b].max.map(f64::from));
            let inner: Vec<usize> = (1..bin.len()).filter(|&b| bin[b].count == 0).collect();
            if bin[0].count > 0 || inner.len() > 15 {
                continue;
            }
            cases += 1;
            let plan = Plan::new(&bin);
            let layout = wide_layout(&bin, &plan);
            let mut leaves = 0;
            for (_, kids) in &layout {
                assert!(
                    (2..=NW).contains(&kids.len()),
                    "N={N}: {} children",
                    kids.len()
                );
                leaves += kids.iter().filter(|&&c| bin[c].count > 0).count();
            }
            let binary_leaves = bin.iter().filter(|b| b.count > 0).count();
            assert_eq!(leaves, binary_leaves, "N={N}: every leaf exactly once");
            let cost: f64 = layout.iter().map(|(b, _)| area(*b)).sum();
            // Brute force over the subsets of the non-root inner nodes.
            fn slots<const N: usize>(bin: &[BNode<N>], wide: &[bool], c: usize) -> usize {
                if bin[c].count > 0 || wide[c] {
                    1
                } else {
                    slots(bin, wide, c + 1) + slots(bin, wide, bin[c].first as usize)
                }
            }
            let mut best = f64::INFINITY;
            let mut wide = vec![false; bin.len()];
            for set in 0u32..1 << inner.len() {
                for (k, &b) in inner.iter().enumerate() {
                    wide[b] = set >> k & 1 == 1;
                }
                wide[0] = true;
                let roots = (0..bin.len()).filter(|&b| wide[b]);
                let valid = roots.clone().all(|b| {
                    slots(&bin, &wide, b + 1) + slots(&bin, &wide, bin[b].first as usize) <= NW
                });
                if valid {
                    best = best.min(roots.map(area).sum());
                }
            }
            assert!(
                (cost - best).abs() <= 1e-12 * best,
                "N={N}: plan {cost}, best {best}"
            );
            opened += (layout.len() < inner.len() + 1) as usize;
        }
        // The cases are not trivial: some inner nodes were opened into their parents.
        assert!(opened > 0, "N={N}: no inner node was ever opened");
    }

    #[test]
    fn leaf_slots_agree_with_the_portable_version() {
        let mut r = rng(17);
        for _ in 0..200 {
            let child: [u32; NW] = std::array::from_fn(|_| match r.random_range(0..3) {
                0 => EMPTY,
                1 => LEAF | r.random_range(0..1000u32),
                _ => r.random_range(0..1000u32),
            });
            let (leafy, empty) = leaf_slots::<false>(&child);
            for (l, &c) in child.iter().enumerate() {
                assert_eq!(leafy >> l & 1 == 1, c == EMPTY || c & LEAF != 0);
                assert_eq!(empty >> l & 1 == 1, c == EMPTY);
            }
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx2") {
                assert_eq!(leaf_slots::<true>(&child), (leafy, empty));
            }
        }
    }

    #[test]
    fn accel_wide_collapse_is_optimal() {
        for_each_dim!(wide_collapse_is_optimal);
    }

    #[test]
    fn f32_up_is_the_smallest_f32_not_below() {
        let mut r = rng(77);
        let tiny = f64::from(f32::from_bits(1));
        let big = f64::from(f32::MAX) * (1.0 + 1e-12);
        let mut xs = vec![
            0.0,
            -0.0,
            1e-50,
            -1e-50,
            0.5 * tiny,
            -0.5 * tiny,
            1.0,
            -1.0,
            big,
            -big,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for _ in 0..20000 {
            let x = r.random_range(-1.0..1.0) * 2f64.powi(r.random_range(-160..160));
            xs.extend([x, f64::from(x as f32)]);
        }
        for x in xs {
            let f = x as f32;
            let want = if (f as f64) < x { f.next_up() } else { f };
            assert_eq!(f32_up(x).to_bits(), want.to_bits(), "x = {x:e}");
            assert!(f64::from(f32_up(x)) >= x, "x = {x:e}");
        }
    }

    #[test]
    fn accel_slab_test_treats_boxes_as_closed() {
        let mut node = Node::<3>::EMPTY;
        for i in 0..3 {
            node.b[0][i][0] = 0.0;
            node.b[1][i][0] = 1.0;
        }
        let hit = |origin: [f64; 3], dir: [f64; 3]| {
            let pre = RayPre::new(&Ray { origin, dir }, 1.0);
            let (mask, tn) = pre.slab(&node, 0.0, f32::INFINITY);
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx2") {
                // SAFETY: AVX2 is available.
                // Planes picked per ray and once per packet, origin differences per ray and
                // once per packet.
                for (octant, shared_origin) in [
                    (None, false),
                    (Some(pre.near), false),
                    (Some(pre.near), true),
                ] {
                    let packet = Packet::<3, 1> {
                        pre: [pre],
                        octant,
                        shared_origin,
                    };
                    let (m2, t2) = unsafe { slabs_avx2(&packet, &node, 1, 0.0, &[f32::INFINITY]) };
                    assert_eq!(
                        (mask as u64, tn.map(f32::to_bits)),
                        (m2, t2.map(f32::to_bits))
                    );
                }
            }
            mask
        };
        // Along a face, along an edge, from a face plane with zero components of both signs.
        assert_eq!(hit([-1.0, 0.0, 0.5], [1.0, 0.0, 0.0]), 1);
        assert_eq!(hit([-1.0, 1.0, 1.0], [1.0, 0.0, -0.0]), 1);
        assert_eq!(hit([0.5, 1.0, 0.5], [0.0, -0.0, 0.0]), 1);
        // Exactly at a corner, from outside.
        assert_eq!(hit([-1.0, -2.0, -3.0], [1.0, 2.0, 3.0]), 1);
        assert_eq!(
            hit([1.0 + 1.0 / 3.0, 2.0, 3.0], [-1.0 / 3.0, -1.0, -2.0]),
            1
        );
        // Misses, and the empty slots never hit.
        assert_eq!(hit([-1.0, 1.5, 0.5], [1.0, 0.0, 0.0]), 0);
        assert_eq!(hit([-1.0, 0.5, 0.5], [-1.0, 0.0, 0.0]), 0);
        assert_eq!(hit([0.5, 0.5, 0.5], [0.0, 0.0, 0.0]), 1);
    }

    /// Every SIMD block kernel gives, lane by lane, the bits of `PreparedSimplex::intersect`.
    fn block_kernels_agree<const N: usize>() {
        let mut r = rng(5000 + N as u64);
        for case in 0..400 {
            let count = 1 + case % W;
            let c = random_vector::<N>(&mut r, 1.0);
            let pts: Vec<[[f64; N]; N]> = (0..count)
                .map(|_| random_simplex(&mut r, &c, 1.0))
                .collect();
            let prims: Vec<PreparedSimplex<N>> =
                pts.iter().filter_map(PreparedSimplex::new).collect();
            if prims.len() != count {
                continue;
            }
            let ids: Vec<u32> = (0..count as u32).collect();
            let bounds = pts.iter().map(|p| simplex_bounds(p)).collect();
            let bvh = Bvh::build(prims.clone(), ids, bounds);
            assert_eq!(bvh.blocks.len(), 1);
            let block = &bvh.blocks[0];
            for _ in 0..20 {
                let origin = random_vector::<N>(&mut r, 3.0);
                let (pts_l, _) = (&pts[r.random_range(0..count)], 0);
                let dir = crate::linalg::sub(&plane_point(&mut r, pts_l, -0.2, 1.0), &origin);
                let ray = Ray { origin, dir };
                let local = RayLocal::new(&ray);
                let mut kernels = vec![block.hit(&local, 0.0, f64::INFINITY)];
                #[cfg(target_arch = "x86_64")]
                if std::is_x86_feature_detected!("avx2") {
                    // SAFETY: AVX2 is available.
                    kernels.push(unsafe { block.hit_avx2(&local, 0.0, f64::INFINITY) });
                }
                for hits in kernels {
                    for l in 0..count {
                        let id = block.ids[l] as usize;
                        let want = prims[id].intersect(&ray, 0.0, f64::INFINITY);
                        let got = (hits.mask >> l & 1 == 1).then(|| (hits.t[l], hits.bary(l)));
                        let bits = |h: Option<(f64, [f64; N])>| {
                            h.map(|(t, b)| (t.to_bits(), b.map(f64::to_bits)))
                        };
                        assert_eq!(bits(got), bits(want), "N={N} lane {l}");
                    }
                    assert_eq!(hits.mask >> count, 0);
                }
            }
        }
    }

    #[test]
    fn accel_simd_block_kernels_match_the_scalar_test_bit_for_bit() {
        for_each_dim!(block_kernels_agree);
    }

    #[test]
    fn accel_from_mesh_matches_from_simplices() {
        let cells = cube_boundary::<4>(2);
        let mut mesh = Mesh::<4>::default();
        for c in &cells {
            let base = mesh.vertices.len() as u32;
            mesh.vertices.extend(c.iter().map(|v| v.map(|x| x as f64)));
            mesh.simplices
                .push(std::array::from_fn(|k| base + k as u32));
        }
        // One degenerate simplex (repeated vertex) is skipped; ids stay the simplex indices.
        mesh.simplices.push([0, 0, 1, 2]);
        let points: Vec<[[f64; 4]; 4]> = cells
            .iter()
            .map(|c| c.map(|v| v.map(|x| x as f64)))
            .collect();
        let ids: Vec<u32> = (0..points.len() as u32).collect();
        let a = Bvh::from_mesh(&mesh);
        assert!(a == Bvh::from_simplices(&points, &ids));
        assert_eq!(a.len(), cells.len());
        let ray = Ray {
            origin: [1.0, 1.3, 0.7, -5.0],
            dir: [0.0, 0.0, 0.0, 1.0],
        };
        let h = a.closest_hit(&ray, 0.0, f64::INFINITY, |_| true).unwrap();
        assert!((h.t - 5.0).abs() < 1e-12 && (h.prim as usize) < cells.len());
    }
}
