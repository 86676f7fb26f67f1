//! The memory layout of the tree: wide nodes of `NODE_WIDTH` child boxes in `f32` (rounded outward),
//! leaf blocks of `BLOCK_WIDTH` prepared simplices stored structure-of-arrays (rows in f32), the
//! source of their exact versions, the binary nodes of the
//! build, and the box measure both the build and the collapse minimise.

use super::cell::Cell;
use super::simplex::bary_from;
use crate::linalg::Vector;

/// Leaves hold at most this many simplices: the lanes of a block.
pub const MAX_LEAF: usize = BLOCK_WIDTH;
/// Lanes of a [`LeafBlock`]: the simplices one block test intersects together (one `f64` lane
/// each, one AVX2 register per coefficient).
pub(super) const BLOCK_WIDTH: usize = 4;
/// Child slots of a [`WideNode`]: the boxes one slab test meets together (one `f32` lane each,
/// one AVX2 register per plane); also the width of a packet's ray masks.
pub(super) const NODE_WIDTH: usize = 8;
/// The bit that tags a child reference as a leaf: `LEAF_TAG | b` is leaf block b, a reference
/// without it a wide node's index.
pub(super) const LEAF_TAG: u32 = 1 << 31;
/// The bit that tags a leaf reference as a flat cell: `LEAF_TAG | CELL_TAG | c` is cell c of
/// [`Bvh::cells`] (see `cell.rs`). Block indices stay below it.
pub(super) const CELL_TAG: u32 = 1 << 30;
/// The reference of an unused child slot (its box is empty, so it is never entered). It has the
/// [`LEAF_TAG`] bit too, so one test sorts slots into inner nodes and the rest.
pub(super) const EMPTY_SLOT: u32 = u32::MAX;

/// A wide node: the boxes of its up to `NODE_WIDTH` children, structure-of-arrays, and the child
/// references.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(super) struct WideNode<const N: usize> {
    /// `bounds[0][axis][lane]` = min corner, `bounds[1][axis][lane]` = max corner (f32 rounded outward;
    /// +∞/−∞ for an empty slot).
    pub(super) bounds: [[[f32; NODE_WIDTH]; N]; 2],
    /// A node index, `LEAF_TAG | block index`, `LEAF_TAG | CELL_TAG | cell index`, or
    /// `EMPTY_SLOT`.
    pub(super) child: [u32; NODE_WIDTH],
}

impl<const N: usize> WideNode<N> {
    /// The largest |coordinate| of the boxes of its used slots (f32::MAX when not finite): the
    /// `reach` of a tree whose root this is.
    pub(super) fn reach(&self) -> f64 {
        let reach = (0..N)
            .flat_map(|a| (0..NODE_WIDTH).map(move |l| (a, l)))
            .filter(|&(_, l)| self.child[l] != EMPTY_SLOT)
            .map(|(a, l)| {
                f64::from(self.bounds[0][a][l].abs()).max(f64::from(self.bounds[1][a][l].abs()))
            })
            .fold(0.0, f64::max);
        if reach.is_finite() {
            reach
        } else {
            f64::from(f32::MAX)
        }
    }

    /// A node with every slot unused.
    pub(super) const EMPTY: Self = WideNode {
        bounds: [
            [[f32::INFINITY; NODE_WIDTH]; N],
            [[f32::NEG_INFINITY; NODE_WIDTH]; N],
        ],
        child: [EMPTY_SLOT; NODE_WIDTH],
    };
}

/// A leaf: up to [`BLOCK_WIDTH`] prepared simplices, structure-of-arrays (lane = simplex), with
/// the rows `n̂, r_1 … r_{N−1}` rounded to f32 (tested by `PreparedSimplex::hit_rounded`) and
/// `x_0` exact. `x0` and `n̂`, all that a test reads before its early exit, come first and lie
/// together. 100 bytes per lane in 4D (160 + 4 in f64).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub(super) struct LeafBlock<const N: usize> {
    /// `x0[i][lane]`.
    pub(super) x0: [[f64; BLOCK_WIDTH]; N],
    /// `m[0][i][lane]` = n̂_i, `m[k][i][lane]` = (r_k)_i rounded to the nearest f32; zero in
    /// unused lanes (which then miss as parallel rays).
    pub(super) m: [[[f32; BLOCK_WIDTH]; N]; N],
    /// The caller's ids; `EMPTY_SLOT` in unused lanes (the used ones come first).
    pub(super) ids: [u32; BLOCK_WIDTH],
}

/// Largest f32 ≤ x.
#[inline]
pub(super) fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x {
        f.next_down()
    } else {
        f
    }
}

/// Smallest f32 ≥ x.
#[inline]
pub(super) fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    // Without a branch (it would go each way half the time): one step up is one ulp away from
    // zero for f ≥ +0 and towards zero for f < 0 (−∞ steps to −f32::MAX). −0 never steps
    // (x ≤ 0 when it rounds to −0), nor do +∞ and NaN (the comparison is false).
    let step = u32::from((f as f64) < x);
    let bits = f.to_bits();
    let neg = bits >> 31;
    f32::from_bits(bits.wrapping_add(step).wrapping_sub(2 * (step & neg)))
}

/// What a block's lane holds of a prepared simplex: its rows rounded to f32, and its first
/// vertex `x_0`.
#[derive(Clone, Copy)]
pub(crate) struct Lane<const N: usize> {
    pub(crate) rows: [[f32; N]; N],
    pub(crate) x0: [f64; N],
}

impl<const N: usize> Lane<N> {
    /// The rows of `p` rounded to f32.
    #[inline]
    pub(crate) fn rows_of(p: &super::PreparedSimplex<N>) -> [[f32; N]; N] {
        p.m.map(|row| row.map(|x| x as f32))
    }

    /// The lane of `p`.
    #[inline]
    pub(crate) fn of(p: &super::PreparedSimplex<N>) -> Self {
        Lane {
            rows: Self::rows_of(p),
            x0: p.x0,
        }
    }
}

/// Result of a block test: bit mask of the lanes hit, and per lane t, `n̂·d` and
/// `u[k][lane] = (n̂·d)·t_k` (k ≥ 1), meaningful for the lanes hit.
pub(super) struct BlockHits<const N: usize> {
    pub(super) mask: u32,
    /// The lanes the rounded rows cannot decide: their exact test decides (see `simplex.rs`).
    pub(super) unsure: u32,
    pub(super) t: [f64; BLOCK_WIDTH],
    pub(super) den: [f64; BLOCK_WIDTH],
    pub(super) u: [[f64; BLOCK_WIDTH]; N],
}

impl<const N: usize> BlockHits<N> {
    /// No lane hit nor unsure, every value zero: what a block test starts from.
    pub(super) const NONE: Self = BlockHits {
        mask: 0,
        unsure: 0,
        t: [0.0; BLOCK_WIDTH],
        den: [0.0; BLOCK_WIDTH],
        u: [[0.0; BLOCK_WIDTH]; N],
    };

    /// Barycentric coordinates of lane l, as [`PreparedSimplex::intersect`](super::PreparedSimplex::intersect) computes them.
    #[inline(always)]
    pub(super) fn bary(&self, l: usize) -> [f64; N] {
        bary_from(&std::array::from_fn(|k| self.u[k][l]), self.den[l])
    }
}

impl<const N: usize> LeafBlock<N> {
    /// A block with no simplices (unused lanes are zero, and miss as parallel rays).
    pub(super) const EMPTY: Self = LeafBlock {
        m: [[[0.0; BLOCK_WIDTH]; N]; N],
        x0: [[0.0; BLOCK_WIDTH]; N],
        ids: [EMPTY_SLOT; BLOCK_WIDTH],
    };

    /// Stores the simplex `lane` with id `id` in lane `l`.
    #[inline]
    pub(super) fn set_lane(&mut self, l: usize, lane: &Lane<N>, id: u32) {
        for k in 0..N {
            for i in 0..N {
                self.m[k][i][l] = lane.rows[k][i];
            }
        }
        for i in 0..N {
            self.x0[i][l] = lane.x0[i];
        }
        self.ids[l] = id;
    }

    /// Lanes in use (the first ones).
    #[inline(always)]
    pub(super) fn count(&self) -> usize {
        self.ids.iter().take_while(|&&id| id != EMPTY_SLOT).count()
    }

    /// The bit set of the lanes in use.
    #[inline(always)]
    pub(super) fn used(&self) -> u32 {
        let mut m = 0;
        for (l, &id) in self.ids.iter().enumerate() {
            m |= u32::from(id != EMPTY_SLOT) << l;
        }
        m
    }

    /// Bytes of `x0` and `m[0]` (n̂), which lead the block: all that a test reads before its
    /// early exit.
    pub(super) const HEAD: usize = N * BLOCK_WIDTH * (size_of::<f64>() + size_of::<f32>());
}

/// Where a tree finds the exact prepared simplex of an id, for the rare lanes its rounded rows
/// leave unsure (see the module docs of [`crate::accel`], 1b): the scene's meshes, or the
/// simplices given to the build.
/// Not part of a tree's identity: two trees compare equal whatever their sources.
#[derive(Clone)]
pub struct ExactSource<const N: usize>(
    pub(super) std::sync::Arc<dyn Fn(u32) -> super::PreparedSimplex<N> + Send + Sync>,
);

impl<const N: usize> ExactSource<N> {
    /// The source that prepares simplex `id` with `prepare` (which must give the simplex the
    /// tree was built with).
    pub fn new(prepare: impl Fn(u32) -> super::PreparedSimplex<N> + Send + Sync + 'static) -> Self {
        ExactSource(std::sync::Arc::new(prepare))
    }

    /// The exact prepared simplex `id`.
    #[inline]
    pub fn prepare(&self, id: u32) -> super::PreparedSimplex<N> {
        (self.0)(id)
    }

    /// A source with no simplices: for an empty tree, or until [`Bvh::set_exact`].
    pub(crate) fn none() -> Self {
        Self::new(|id| panic!("no exact source for simplex {id}"))
    }
}

impl<const N: usize> PartialEq for ExactSource<N> {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl<const N: usize> std::fmt::Debug for ExactSource<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ExactSource")
    }
}

/// A bounding-volume hierarchy over prepared simplices (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh<const N: usize> {
    /// Wide nodes in depth-first order; the root is node 0 (none when empty).
    pub(super) nodes: Vec<WideNode<N>>,
    /// Leaves, in leaf order.
    pub(super) blocks: Vec<LeafBlock<N>>,
    /// Number of simplices.
    pub(super) len: usize,
    /// Bound on |coordinate| of every box of the tree (for the slab test's error bound).
    pub(super) reach: f64,
    /// Per node, per child slot: the smallest (`[0]`) and largest (`[1]`) id in the child's
    /// subtree (`u32::MAX`, 0 for an empty slot), so that an any-hit query told to skip a range
    /// of ids ([`Bvh::any_hit`]) leaves out the subtrees that hold nothing else.
    pub(super) ranges: Vec<[[u32; NODE_WIDTH]; 2]>,
    /// The flat cells (see `cell.rs`); their simplices are in `blocks`.
    pub(super) cells: Vec<Cell>,
    /// The cells' neighbour links, `count` per cell from its `links`.
    pub(super) cell_links: Vec<[u32; N]>,
    /// The cells' simplices, exact, as `cell_links` (the walks locate hit points with them).
    pub(super) cell_prepared: Vec<super::PreparedSimplex<N>>,
    /// The exact simplices of the unsure lanes.
    pub(super) exact: ExactSource<N>,
    /// For a tree small enough to live in a core's caches ([`Bvh::keep_exact_rows`]): per
    /// block, its lanes' rows `n̂, r_k` exact, `exact_rows[b][k][i][lane]`, which its blocks are
    /// tested with instead of their rounded rows; empty otherwise.
    pub(super) exact_rows: Vec<ExactRows<N>>,
}

/// The exact rows `n̂, r_k` of a block's lanes, `[k][i][lane]` ([`Bvh::keep_exact_rows`]).
pub(super) type ExactRows<const N: usize> = [[[f64; BLOCK_WIDTH]; N]; N];

/// The most bytes of exact rows the trees of a scene keep beside their blocks
/// ([`Bvh::keep_exact_rows`]): 1 MiB, 8,192 simplices in 4D, 14,563 in 3D.
///
/// The rows in f32 (1b in the module docs of [`crate::accel`]) save memory bandwidth where a
/// tree does not fit in a core's caches, and cost compute everywhere: the certified bound on
/// their rounding more than doubles the instructions of a block test (about 250 against 110
/// in 4D). A scene whose trees' exact rows take at most 1 MiB (with blocks and nodes, about a
/// quarter of the 2–4 MiB L2 cache of a current core, the bench machine's is 4 MiB) is
/// compute-bound, so it is tested with exact rows, which need no bound and leave no lane
/// unsure. Its memory grows by `32·N²` bytes per block (512 in 4D), 1 MiB at most per
/// scene; larger scenes are unchanged (≤ 150 B/simplex in 4D).
pub const EXACT_ROWS_MAX_BYTES: usize = 1 << 20;

/// A binary node of the build: f32 bounds rounded outward and either two children (the left
/// one next, `first` the right one) or a leaf range `first .. first + count` (count > 0).
#[derive(Clone, Copy)]
pub(super) struct BinaryNode<const N: usize> {
    pub(super) min: [f32; N],
    pub(super) max: [f32; N],
    pub(super) first: u32,
    pub(super) count: u32,
}

/// Half the (N−1)-measure of a box's boundary, `Σ_i Π_{j≠i} extent_j` (half the perimeter in
/// 2D, half the surface area in 3D). By Cauchy's formula the probability that a random line
/// meets a convex body is proportional to its boundary measure, which makes this the SAH weight
/// in every N. An empty box (min > max) has measure 0.
pub(super) fn half_area<const N: usize>(min: &Vector<N>, max: &Vector<N>) -> f64 {
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

impl<const N: usize> Bvh<N> {
    /// Gives the tree the source of its exact simplices (a build without one: see
    /// [`Bvh::build_with_cells_borrowing`]); it must give the simplices the tree was built with.
    pub(crate) fn set_exact(&mut self, exact: ExactSource<N>) {
        self.exact = exact;
    }

    /// The bytes its exact rows take, kept or not ([`Bvh::keep_exact_rows`]).
    pub fn exact_rows_bytes(&self) -> usize {
        self.blocks.len() * size_of::<ExactRows<N>>()
    }

    /// Whether it keeps its exact rows.
    pub fn has_exact_rows(&self) -> bool {
        !self.exact_rows.is_empty()
    }

    /// Keeps, beside the blocks, every lane's exact rows (prepared again by the tree's
    /// [`ExactSource`], which must be set): the blocks are then tested exactly, with the
    /// arithmetic of the exact test (`PreparedSimplex::hit`) and no unsure lane, and their hits
    /// carry the exact t and coordinates. A scene keeps them when all its trees' take at most
    /// [`EXACT_ROWS_MAX_BYTES`].
    pub fn keep_exact_rows(&mut self) {
        use rayon::prelude::*;
        let exact = &self.exact;
        self.exact_rows = self
            .blocks
            .par_iter()
            .map(|block| {
                let mut rows = [[[0.0; BLOCK_WIDTH]; N]; N];
                for (l, &id) in block.ids[..block.count()].iter().enumerate() {
                    let p = exact.prepare(id);
                    debug_assert_eq!(p.x0.map(f64::to_bits), block.x0.map(|x| x[l].to_bits()));
                    for (k, row) in p.m.iter().enumerate() {
                        for (i, &v) in row.iter().enumerate() {
                            rows[k][i][l] = v;
                        }
                    }
                }
                rows
            })
            .collect();
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
        self.nodes.len()
            * (std::mem::size_of::<WideNode<N>>() + std::mem::size_of::<[[u32; NODE_WIDTH]; 2]>())
            + self.blocks.len() * std::mem::size_of::<LeafBlock<N>>()
            + self.cells.len() * std::mem::size_of::<Cell>()
            + self.cell_links.len()
                * (std::mem::size_of::<[u32; N]>() + size_of::<super::PreparedSimplex<N>>())
            + self.exact_rows.len() * size_of::<ExactRows<N>>()
    }

    /// Number of flat cells (each holding the simplices of one flat facet, see `cell.rs`).
    pub fn cell_count(&self) -> usize {
        self.cells.len()
    }

    /// Where each id `0..count` lies: `block · BLOCK_WIDTH + lane`, or `u32::MAX` for an id the
    /// tree does not hold (a degenerate simplex). For trees whose ids are below `count`.
    pub fn id_slots(&self, count: usize) -> Vec<u32> {
        let mut slots = vec![u32::MAX; count];
        self.fill_id_slots(&mut slots);
        slots
    }

    /// Writes the slot of each id this tree holds into `slots[id]` (see [`Bvh::id_slots`]),
    /// leaving the others: the slots of a scene's trees, which hold disjoint ids, in one list.
    pub fn fill_id_slots(&self, slots: &mut [u32]) {
        for (b, block) in self.blocks.iter().enumerate() {
            for (l, &id) in block.ids[..block.count()].iter().enumerate() {
                slots[id as usize] = (b * BLOCK_WIDTH + l) as u32;
            }
        }
    }

    /// The unit normal n̂ of the prepared simplex in `slot` (see [`Bvh::id_slots`]) as the tree
    /// stores it: [`PreparedSimplex::normal`](super::PreparedSimplex::normal) rounded to f32, the
    /// normal of its hits.
    #[inline]
    pub fn slot_normal(&self, slot: u32) -> Vector<N> {
        let (b, l) = (slot as usize / BLOCK_WIDTH, slot as usize % BLOCK_WIDTH);
        std::array::from_fn(|i| f64::from(self.blocks[b].m[0][i][l]))
    }

    /// Depth of the 8-wide tree counting the leaf level (0 when empty).
    pub fn depth(&self) -> usize {
        fn rec<const N: usize>(nodes: &[WideNode<N>], i: usize) -> usize {
            let deepest = nodes[i]
                .child
                .iter()
                .map(|&c| {
                    if c == EMPTY_SLOT || c & LEAF_TAG != 0 {
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
}

#[cfg(test)]
mod tests;
