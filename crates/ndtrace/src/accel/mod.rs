//! Ray–simplex intersection and a bounding-volume hierarchy over (N−1)-simplices in R^N.
//!
//! The algorithm first, in the order a ray meets it; the speed-ups, which change no result,
//! after it.
//!
//! ## 1. Ray–simplex test (sections "Ray Tracing" and "Barycentric Coordinates"; `simplex.rs`)
//! A [`PreparedSimplex`] stores the unit normal n̂ of its hyperplane (the direction of the
//! generalized cross product of `x_1 − x_0 … x_{N−1} − x_0`, eq. 6), the N−1 rows `r_k` of the
//! pseudo-inverse `(EᵀE)⁻¹Eᵀ` of the edge matrix E (the Gram/Cramer form of the barycentric
//! coordinates) and the first vertex `x_0`. A ray `X(t) = C + t·d` then meets the simplex
//! without any per-ray solve, in O(N²):
//!
//! * `t = n̂·(x_0 − C) / n̂·d`;
//! * `t_k = r_k·(X(t) − x_0) = r_k·(C − x_0) + t·(r_k·d)` for k = 1 … N−1, `t_0 = 1 − Σ t_k`;
//! * it is a hit when t lies in the open interval `(tmin, tmax)` and every `t_k ≥ −BARY_SLACK`
//!   ([`BARY_SLACK`]: the scale-free slack that keeps closed meshes watertight).
//!
//! The inside test is evaluated without waiting for the division: with `p = x_0 − C`,
//! `w = (n̂·p)·d − (n̂·d)·p = (n̂·d)·(X(t) − x_0)`, so `u_k = r_k·w = (n̂·d)·t_k` and the signs
//! are compared against `BARY_SLACK·|n̂·d|`; the coordinates `t_k = u_k/(n̂·d)` are divided out
//! only for the hit returned. Dot products are summed pairwise (short dependency chains).
//!
//! A ray is parallel to the hyperplane (and misses) when `|n̂·d| ≤ DEGENERACY_TOLERANCE·|d|`, the
//! rule of [`crate::geometry::ray_hyperplane`]. Hits are two-sided: orientation is left to shading.
//!
//! ## 1b. Rows in f32, decided exactly (`simplex.rs`, `hit_rounded`)
//! The tree stores the rows `n̂, r_k` rounded to f32 (x_0 stays exact): 100 bytes per simplex
//! in 4D instead of 164. The test then runs on the rounded rows, in f64, beside a certified
//! bound on what the rounding changes (each coefficient moves by at most 2⁻²⁴ of itself). Where
//! the bound shows the exact test finds the ray inside and not parallel, the rounded rows
//! decide, with their t and coordinates (the hit point on the rounded hyperplane, within 2⁻²⁴
//! of |X − x_0| of the exact one, [`PLANE_ROUNDING`]); where it shows the exact test misses, a
//! miss; in between (a ray within ~10⁻⁶ of the simplex's boundary or of parallel: fewer than
//! one camera ray in 10⁴ over a fine sphere) the lane is *unsure*, and the exact test of the
//! simplex, prepared again from the scene's vertices ([`ExactSource`]), decides. So every
//! decision at a shared ridge is the exact test's, and closed meshes stay watertight with the
//! same `BARY_SLACK`.
//!
//! A tree small enough to live in a core's caches ([`EXACT_ROWS_MAX_BYTES`]) is compute-bound,
//! not bandwidth-bound, and the bound more than doubles a block test's work: the scene keeps
//! its exact rows beside the blocks ([`Bvh::keep_exact_rows`]) and tests them with the exact
//! arithmetic of section 1, lane by lane (`hit_exact_avx2`), which leaves no lane unsure.
//!
//! ## 2. Build: binned SAH (`build.rs`)
//! [`Bvh::build`] first builds a binary tree of N-D axis-aligned boxes (each simplex's box padded
//! to hold its `BARY_SLACK` band) with the surface area heuristic, whose weight in N dimensions is
//! half the (N−1)-measure of a box's boundary (Cauchy's formula): 16 bins per axis over the
//! centroid bounds at the root (below a binned split, over twice the node's box, which its bins
//! give without another pass over its simplices), leaves of at most [`MAX_LEAF`] simplices,
//! object-median splits when SAH cannot split or the tree gets deep. The build is parallel
//! (rayon) for large inputs and produces the same tree for any number of threads. It partitions
//! records of f32 boxes in place, each held as `[lo, −hi]` so that the union of two boxes is
//! one packed minimum. A scene prepares each simplex once, in simplex order (its box and its
//! lane's f32 rows), and its blocks are filled from those rows.
//!
//! Very large inputs (the scene build switches at [`MORTON_MIN`] simplices) skip the SAH and the
//! collapse: [`Bvh::build_morton`] sorts the simplices along a Morton curve, packs runs of 4
//! into blocks and groups the blocks 8 to a node by the leading bits of their codes
//! (`morton.rs`): linear work, and no memory per simplex beyond the finished tree's.
//!
//! ## 3. Wide collapse (`collapse.rs`)
//! The binary tree is collapsed into an 8-wide tree by the optimal collapse of Ylitie, Karras and
//! Laine (a dynamic program that minimises the summed boundary measure of the wide nodes). The
//! boxes of a node's up to 8 children are stored in `f32`, rounded outward (so conservative);
//! every leaf is one *block* of up to 4 prepared simplices (rows in f32, 1b) with their ids
//! (`tree.rs`), or a flat cell (3b).
//!
//! ## 3b. Flat cells (`cell.rs`)
//! The simplices that tile one flat convex (N−1)-cell (a facet of the N-cube: (N−1)! Kuhn
//! simplices sharing a diagonal, whose boxes no tree can separate) may be given to the build as
//! a [`FlatCell`] ([`Bvh::build_lazily_with_cells`]). After checking that they are one (flat,
//! convex, properly tiled, connected), the build makes the cell a single leaf, its simplices in
//! consecutive blocks. A ray that reaches it meets the cell's hyperplane at X and walks from
//! simplex to neighbour, stepping across the facet of the most negative barycentric
//! coordinate, to the simplex holding X; only that simplex's block is tested. When X lies near
//! a ridge, the ray is nearly parallel to the cell or the walk is long, every block of the cell
//! is tested. Hits and ids are those of the simplices alone, bit for bit (the bound is in
//! `cell.rs`).
//!
//! ## 3c. Instances (`instance.rs`)
//! A scene's simplices are prepared in their objects' own space, before the object's
//! transform: untransformed objects share one tree, each transformed object has its own, and
//! [`Instances`] maps the world rays into each tree's space ([`ToObject`]) and the normals of
//! its hits back out. A frame of an animation that moves objects changes only the maps. Every
//! query still returns the least (t, id) over all the trees.
//!
//! ## 4. Traversal (`traverse.rs`)
//! Nearest-first: the children met are visited in order of entry distance, and subtrees whose
//! entry lies beyond the current best hit are skipped, with an explicit fixed-size stack and no
//! heap allocation. [`Bvh::closest_hit`] returns the minimum of (t, id) over the accepted hits
//! (so exact ties are settled by id, whatever the tree's shape); [`Bvh::any_hit`] stops at the
//! first accepted hit and skips the subtrees whose ids all lie in a given range.
//!
//! ## Speed-ups beside it
//! * Packets (`packet.rs`, `traverse.rs`): rays travel in packets of up to [`PACKET`]
//!   ([`Bvh::closest_hits`], [`Bvh::any_hits`]; the one-ray calls are packets of one). A node is
//!   fetched, slab-tested for each ray of the packet that reached it, and sorted once for the
//!   packet; each stack entry carries the bit set of the rays that met its box (the masks of
//!   8 rays × 8 children are transposed as an 8×8 bit matrix), and every ray keeps its own best
//!   hit and culling limit. A ray is tested only against the boxes its own tests led it to, and
//!   the leaf tests are exact, so every ray's result is the one it gets alone, whichever rays it
//!   travels with.
//! * Structure-of-arrays layout (`tree.rs`): a node's child boxes are slab-tested together, a
//!   block's simplices (`[f64; 4]` per coefficient, one lane per simplex) intersected together.
//! * SIMD kernels (`kernels/`): the slab tests in SSE2, or AVX2 when the CPU has it, and the
//!   block test in AVX2 (`kernels/x86_64.rs`), beside their portable versions
//!   (`kernels/portable.rs`), which every target compiles (and which test blocks on CPUs without
//!   AVX2). Every kernel performs, per lane, exactly the operations of its portable twin and of
//!   `PreparedSimplex::hit_rounded` in the same order (no FMA), so all paths give bit-identical
//!   results; the tests compare them bit for bit.
//! * Prefetches of the leaf blocks a packet will test soon (`kernels/mod.rs`).

// 1. The ray–simplex test.
mod simplex;
// 2. The SAH build, and the public constructors.
mod build;
// 2b. The Morton build, for very large inputs.
mod morton;
// 3. The wide collapse.
mod collapse;
// 3b. Flat cells: the simplices of a flat facet as one leaf.
mod cell;
// 3c. Instances: trees in their objects' own space, reached by mapped rays.
mod instance;
// 3d. The index of a scene's objects behind one constructor: which tree holds what, and how.
mod objects;
// 4. The queries.
mod traverse;
// The memory layout of the trees, the rays prepared for traversal, the kernels, the counters.
mod kernels;
mod packet;
mod stats;
mod tree;

#[cfg(test)]
mod tests;

/// The ray and hit types of the queries, re-exported from [`crate::ray`].
pub use crate::ray::{Hit, Ray};
pub(crate) use build::{Ref as BuildRef, BOX_PAD};
pub use cell::FlatCell;
pub use instance::{Instances, ToObject};
pub(crate) use kernels::prefetch_of;
pub use morton::MORTON_MIN;
pub use objects::{
    build_index, bvh_bytes, empty_box, held_box, merge_boxes, offsets_of, rebuild_members,
    AccelObject, AccelOptions, Built, FlatFacets, Meshes, Rebuilt, ShapeHints, INSTANCE_MIN,
};
pub use packet::PACKET;
pub use simplex::{simplex_bounds, Bounds, PreparedSimplex, BARY_SLACK, PLANE_ROUNDING};
#[cfg(feature = "traversal-stats")]
pub use stats::traversal_stats;
pub(crate) use tree::Lane;
pub use tree::{Bvh, ExactSource, EXACT_ROWS_MAX_BYTES, MAX_LEAF};
