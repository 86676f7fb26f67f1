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

mod build;
mod collapse;
mod kernels;
mod packet;
mod simplex;
mod stats;
mod traverse;
mod tree;

#[cfg(test)]
mod tests;

/// The ray and hit types of the queries, re-exported from [`crate::ray`].
pub use crate::ray::{Hit, Ray};
pub(crate) use build::BOX_PAD;
pub use packet::PACKET;
pub use simplex::{simplex_bounds, Bounds, PreparedSimplex, BARY_SLACK};
#[cfg(feature = "traversal-stats")]
pub use stats::traversal_stats;
pub use tree::{Bvh, MAX_LEAF};
