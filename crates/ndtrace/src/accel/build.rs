//! The SAH build of the binary tree (binned, parallel, deterministic) and the public
//! constructors of [`Bvh`], which collapse it into the wide tree (see `collapse`).

use super::cell::{CellGeometry, FlatCell};
use super::collapse::{id_ranges, wide_tree, CELL_MARK};
use super::simplex::{simplex_bounds, Bounds, PreparedSimplex};
use super::tree::{
    f32_down, f32_up, half_area, BinaryNode, Bvh, ExactSource, Lane, BLOCK_WIDTH, LEAF_TAG,
    MAX_LEAF,
};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// SahBins per axis of the SAH build.
const BINS: usize = 16;
/// Below this depth SAH decides the binary splits; deeper, object-median splits bound the depth
/// (they halve a u32-indexed range, so the binary tree has at most `MAX_SAH_DEPTH + 33` levels).
pub(super) const MAX_SAH_DEPTH: usize = 48;
/// Nodes with at least this many simplices are built in parallel (the result does not depend on
/// it: see [`Bvh::build`]).
pub(super) const PAR_MIN: usize = 16 * 1024;
/// Chunk size of the parallel binning passes.
const PAR_CHUNK: usize = 8 * 1024;
/// Relative padding of each simplex's box, covering the `BARY_SLACK` band around it (a point
/// with `t_k ≥ −BARY_SLACK` is at most `BARY_SLACK·diameter` outside the simplex, and
/// `diameter ≤ √N·max extent ≤ 3·max extent`).
pub(crate) const BOX_PAD: f64 = 1e-8;

/// A box as `[lo, −hi]`: its lower corner and its upper corner negated, so that the union of
/// two boxes is one elementwise minimum over 2N lanes (packed `minps`; negation is exact, so
/// every bound is the one a `[lo, hi]` box would give).
type NegBox<const N: usize> = [[f32; N]; 2];

/// The empty [`NegBox`]: every lane +∞.
#[inline(always)]
const fn empty_box<const N: usize>() -> NegBox<N> {
    [[f32::INFINITY; N]; 2]
}

/// Grows `acc` to contain `x` (see [`lesser`]: one `minps` per 4 lanes).
#[inline(always)]
fn grow_box<const N: usize>(acc: &mut NegBox<N>, x: &NegBox<N>) {
    for (a, &x) in acc.as_flattened_mut().iter_mut().zip(x.as_flattened()) {
        *a = lesser(*a, x);
    }
}

/// The upper corner of a [`NegBox`].
#[inline(always)]
fn upper<const N: usize>(b: &NegBox<N>) -> [f32; N] {
    b[1].map(|x| -x)
}

/// A simplex during the build: its padded box rounded outward to f32 and its input index.
/// The build partitions these records in place, so every pass over a node reads memory in
/// order (not through an index array). Aligned to 8 bytes: in 3D its 28 bytes then take 32,
/// which copy as two 16-byte halves rather than two overlapping ones, so that a partition
/// reading a record just written gets it forwarded from the store.
#[derive(Clone, Copy)]
#[repr(C, align(8))]
pub(crate) struct Ref<const N: usize> {
    b: NegBox<N>,
    /// The input index (the scene's pass over its meshes puts a global id here first).
    pub(crate) id: u32,
}

impl<const N: usize> Ref<N> {
    /// The record of input `id` over the box `(lo, hi)` of a simplex's vertices: padded by
    /// [`BOX_PAD`] of its largest extent, so that it contains the `BARY_SLACK` band, and
    /// rounded outward to f32.
    pub(crate) fn new(id: u32, (lo, hi): &Bounds<N>) -> Self {
        let ext = (0..N).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
        let pad = BOX_PAD * ext;
        Ref {
            b: [
                std::array::from_fn(|i| f32_down(lo[i] - pad)),
                std::array::from_fn(|i| -f32_up(hi[i] + pad)),
            ],
            id,
        }
    }

    /// The smallest record containing both boxes, with `self`'s id.
    fn union(mut self, o: &Self) -> Self {
        grow_box(&mut self.b, &o.b);
        self
    }

    /// Twice the box centre on axis `a`, `lo + hi` (the factor 2 cancels in the binning).
    #[inline(always)]
    fn centre2(&self, a: usize) -> f32 {
        self.b[0][a] - self.b[1][a]
    }
}

/// The bounding box of a set of simplices and a box holding their (doubled) centres, both as
/// [`NegBox`]es: what the split of the node over them needs. The centres' box is exact
/// ([`NodeBounds::of`]) at the root and after an object-median split, twice the bounding box
/// after a binned one ([`NodeBounds::of_bins`]).
#[derive(Clone, Copy)]
struct NodeBounds<const N: usize> {
    b: NegBox<N>,
    c: NegBox<N>,
}

impl<const N: usize> NodeBounds<N> {
    fn empty() -> Self {
        NodeBounds {
            b: empty_box(),
            c: empty_box(),
        }
    }

    #[inline(always)]
    fn grow(&mut self, r: &Ref<N>) {
        grow_box(&mut self.b, &r.b);
        let c: NegBox<N> = [
            std::array::from_fn(|i| r.centre2(i)),
            std::array::from_fn(|i| -r.centre2(i)),
        ];
        grow_box(&mut self.c, &c);
    }

    fn merge(mut self, o: Self) -> Self {
        grow_box(&mut self.b, &o.b);
        grow_box(&mut self.c, &o.c);
        self
    }

    fn of(refs: &[Ref<N>]) -> Self {
        let mut b = Self::empty();
        for r in refs {
            b.grow(r);
        }
        b
    }

    /// The bounds of the simplices of `bins`: their box exactly, and for the centres twice
    /// that box (which holds them), so that a side of a binned split needs no pass over its
    /// records. Its bins then span the side's box rather than its centres: where the simplices
    /// are small beside the node, much the same; the rays' node and leaf visits and slab
    /// tests over icospheres and a 3-sphere changed by 1.2 % at most.
    fn of_bins(bins: &[SahBin<N>]) -> Self {
        let mut u = empty_box();
        for bin in bins {
            grow_box(&mut u, &bin.b);
        }
        NodeBounds {
            b: u,
            c: u.map(|side| side.map(|x| 2.0 * x)),
        }
    }

    /// The extent of the centres on axis `a`.
    #[inline(always)]
    fn centre_extent(&self, a: usize) -> f32 {
        -self.c[1][a] - self.c[0][a]
    }
}

/// One SAH bin: count and bounds of the simplices whose centre falls in it.
#[derive(Clone, Copy)]
struct SahBin<const N: usize> {
    b: NegBox<N>,
    count: u32,
}

impl<const N: usize> SahBin<N> {
    const EMPTY: Self = SahBin {
        b: empty_box(),
        count: 0,
    };

    #[inline(always)]
    fn grow(&mut self, b: &NegBox<N>, count: u32) {
        self.count += count;
        grow_box(&mut self.b, b);
    }

    fn half_area(&self) -> f64 {
        half_area(&self.b[0].map(f64::from), &upper(&self.b).map(f64::from))
    }
}

type SahBins<const N: usize> = [[SahBin<N>; BINS]; N];

/// The bins of two sets of simplices together (exact: counts, min and max).
fn merge_bins<const N: usize>(mut a: SahBins<N>, b: &SahBins<N>) -> SahBins<N> {
    for ax in 0..N {
        for k in 0..BINS {
            a[ax][k].grow(&b[ax][k].b, b[ax][k].count);
        }
    }
    a
}

/// SAH cost weight of n simplices: the number of blocks they fill, since a block tests up to
/// 4 simplices at the price of one.
#[inline]
fn blocks_of(n: u32) -> f64 {
    n.div_ceil(BLOCK_WIDTH as u32) as f64
}

/// The bin of a doubled centre coordinate: `⌊(c − cmin)·scale⌋` clamped to the last bin. The
/// same function bins and partitions, so both agree exactly. Clamped before the conversion,
/// which then needs no saturation (a NaN, which the build never has, would give bin 0).
#[inline(always)]
fn bin_of(c: f32, cmin: f32, scale: f32) -> usize {
    ((c - cmin) * scale).clamp(0.0, (BINS - 1) as f32) as u32 as usize
}

/// `min(acc, x)` for an `acc` that is not NaN: a NaN `x` is ignored, as [`f32::min`] ignores
/// it, and a tie keeps `acc`. One `minss` (`minps` over lanes) where `f32::min` needs four
/// instructions to handle a NaN `acc` (which the build never has: boxes are never NaN, and a
/// NaN centre is never taken).
#[inline(always)]
fn lesser(acc: f32, x: f32) -> f32 {
    if x < acc {
        x
    } else {
        acc
    }
}

/// Reorders `refs` so that the records satisfying `left` come first; returns their number.
///
/// Without branches on the side (which is as good as random to a branch predictor): every
/// record is swapped with the first record of the right side so far, which advances by one
/// when it was a left record (`refs[..j]` are left records, `refs[j..i]` right ones).
fn partition<const N: usize>(refs: &mut [Ref<N>], left: impl Fn(&Ref<N>) -> bool) -> usize {
    let mut j = 0;
    for i in 0..refs.len() {
        let r = refs[i];
        let is_left = left(&r);
        refs[i] = refs[j];
        refs[j] = r;
        j += usize::from(is_left);
    }
    j
}

/// A binary subtree built in parallel: either a flat run of nodes (child indices relative to its
/// start) or an inner node over two such subtrees. Flattened once at the end, in depth-first
/// order, so the layout does not depend on which parts were built in parallel.
enum BuiltSubtree<const N: usize> {
    Flat(Vec<BinaryNode<N>>),
    Split(BinaryNode<N>, Box<BuiltSubtree<N>>, Box<BuiltSubtree<N>>),
}

/// The build's settings: nodes with at least `par_min` simplices are built in parallel; inputs
/// from `cells_from` on are flat cells, each a leaf of its own.
struct Builder {
    par_min: usize,
    cells_from: u32,
}

impl Builder {
    /// Bounds and centre bounds; min/max are exact, so the parallel reduction gives the same
    /// result as the sequential loop.
    fn info<const N: usize>(&self, refs: &[Ref<N>]) -> NodeBounds<N> {
        if refs.len() >= self.par_min.max(2 * PAR_CHUNK) {
            refs.par_chunks(PAR_CHUNK)
                .map(NodeBounds::of)
                .reduce(NodeBounds::empty, NodeBounds::merge)
        } else {
            NodeBounds::of(refs)
        }
    }

    /// Adds the record `r` to its bin on every axis. (An axis that is not binned, `scale` 0,
    /// has every record in bin 0: no branch, and the sweep passes it by.)
    #[inline(always)]
    fn bin_into<const N: usize>(
        bins: &mut SahBins<N>,
        r: &Ref<N>,
        cmin: &[f32; N],
        scale: &[f32; N],
    ) {
        let at: [usize; N] = std::array::from_fn(|a| bin_of(r.centre2(a), cmin[a], scale[a]));
        for a in 0..N {
            bins[a][at[a]].grow(&r.b, 1);
        }
    }

    fn bin_seq<const N: usize>(refs: &[Ref<N>], cmin: &[f32; N], scale: &[f32; N]) -> SahBins<N> {
        let mut bins = [[SahBin::EMPTY; BINS]; N];
        if refs.len() < 2 * BINS {
            refs.iter()
                .for_each(|r| Self::bin_into(&mut bins, r, cmin, scale));
            return bins;
        }
        // Neighbouring records mostly fall into the same bins: two sets of bins, alternating,
        // halve the chains of updates to one bin (counts and min/max merge exactly).
        let mut odd = [[SahBin::EMPTY; BINS]; N];
        for pair in refs.chunks(2) {
            Self::bin_into(&mut bins, &pair[0], cmin, scale);
            if let Some(r) = pair.get(1) {
                Self::bin_into(&mut odd, r, cmin, scale);
            }
        }
        merge_bins(bins, &odd)
    }

    /// The SAH bins; counts and min/max are exact, so the parallel reduction is deterministic.
    fn bins<const N: usize>(
        &self,
        refs: &[Ref<N>],
        cmin: &[f32; N],
        scale: &[f32; N],
    ) -> SahBins<N> {
        if refs.len() >= self.par_min.max(2 * PAR_CHUNK) {
            refs.par_chunks(PAR_CHUNK)
                .map(|c| Self::bin_seq(c, cmin, scale))
                .reduce(|| [[SahBin::EMPTY; BINS]; N], |a, b| merge_bins(a, &b))
        } else {
            Self::bin_seq(refs, cmin, scale)
        }
    }

    /// Chooses how to split the node over `refs` and partitions them accordingly: `None` for a
    /// leaf (at most `MAX_LEAF` simplices: a block tests them at the price of one),
    /// `Some((mid, [left, right]))` for children `refs[..mid]` and `refs[mid..]` (both
    /// non-empty) with their bounds.
    fn split<const N: usize>(
        &self,
        refs: &mut [Ref<N>],
        info: &NodeBounds<N>,
        depth: usize,
    ) -> Option<(usize, [NodeBounds<N>; 2])> {
        let n = refs.len();
        // A flat cell is a leaf alone (it is one child reference).
        if n == 1 || (n <= MAX_LEAF && refs.iter().all(|r| r.id < self.cells_from)) {
            return None;
        }
        let mut scale = [0.0f32; N];
        for a in 0..N {
            let ext = info.centre_extent(a);
            let s = BINS as f32 / ext;
            if ext > 0.0 && s.is_finite() {
                scale[a] = s;
            }
        }
        if depth < MAX_SAH_DEPTH && scale.iter().any(|&s| s > 0.0) {
            let bins = self.bins(refs, &info.c[0], &scale);
            // (cost, axis, first bin of the right side); ties keep the first candidate.
            let mut best: Option<(f64, usize, usize)> = None;
            for a in 0..N {
                if scale[a] == 0.0 {
                    continue;
                }
                // Suffix sweep: right_cost[s] = area(bins s..) · blocks(bins s..). An empty
                // bin changes neither side, so its cost is its neighbour's: a small node's
                // sweep only evaluates the bins it fills (the same costs and choice).
                let mut right_cost = [0.0; BINS];
                let mut acc = SahBin::EMPTY;
                for s in (1..BINS).rev() {
                    let b = &bins[a][s];
                    if b.count == 0 && s + 1 < BINS {
                        right_cost[s] = right_cost[s + 1];
                        continue;
                    }
                    acc.grow(&b.b, b.count);
                    right_cost[s] = acc.half_area() * blocks_of(acc.count);
                }
                let mut left = SahBin::EMPTY;
                for s in 1..BINS {
                    let b = &bins[a][s - 1];
                    // The cost at s equals the cost at s − 1 (taken first on a tie).
                    if b.count == 0 {
                        continue;
                    }
                    left.grow(&b.b, b.count);
                    let n_left = left.count as usize;
                    if n_left == 0 || n_left == n {
                        continue;
                    }
                    let cost = left.half_area() * blocks_of(left.count) + right_cost[s];
                    if best.is_none_or(|(c, _, _)| cost < c) {
                        best = Some((cost, a, s));
                    }
                }
            }
            if let Some((_, a, s)) = best {
                let (cmin, sc) = (info.c[0][a], scale[a]);
                let mid = partition(refs, |r| bin_of(r.centre2(a), cmin, sc) < s);
                debug_assert!(mid > 0 && mid < n);
                let (left, right) = bins[a].split_at(s);
                return Some((mid, [NodeBounds::of_bins(left), NodeBounds::of_bins(right)]));
            }
        }
        // Object-median split on the axis of largest centre extent (ties: lowest axis, then
        // input index), which always splits and halves the count.
        let mut axis = 0;
        for a in 1..N {
            if info.centre_extent(a) > info.centre_extent(axis) {
                axis = a;
            }
        }
        let mid = n / 2;
        refs.select_nth_unstable_by(mid, |p, q| {
            p.centre2(axis)
                .total_cmp(&q.centre2(axis))
                .then(p.id.cmp(&q.id))
        });
        let (l, r) = refs.split_at(mid);
        Some((mid, [NodeBounds::of(l), NodeBounds::of(r)]))
    }

    fn node<const N: usize>(info: &NodeBounds<N>) -> BinaryNode<N> {
        BinaryNode {
            min: info.b[0],
            max: upper(&info.b),
            first: 0,
            count: 0,
        }
    }

    /// Sequential build of the subtree over `refs` (at position `offset` of the final order;
    /// `info` their bounds), appending to `out` with node indices relative to the start of `out`.
    fn build_seq<const N: usize>(
        &self,
        refs: &mut [Ref<N>],
        info: &NodeBounds<N>,
        offset: usize,
        depth: usize,
        out: &mut Vec<BinaryNode<N>>,
    ) {
        let me = out.len();
        out.push(Self::node(info));
        match self.split(refs, info, depth) {
            None => {
                out[me].first = offset as u32;
                out[me].count = refs.len() as u32;
            }
            Some((mid, [li, ri])) => {
                let (l, r) = refs.split_at_mut(mid);
                self.build_seq(l, &li, offset, depth + 1, out);
                out[me].first = out.len() as u32;
                self.build_seq(r, &ri, offset + mid, depth + 1, out);
            }
        }
    }

    /// Build of the subtree over `refs` (bounds `info`), forking with rayon for large nodes.
    fn build_par<const N: usize>(
        &self,
        refs: &mut [Ref<N>],
        info: &NodeBounds<N>,
        offset: usize,
        depth: usize,
    ) -> BuiltSubtree<N> {
        if refs.len() < self.par_min {
            let mut out = Vec::with_capacity(refs.len() / 2 + 1);
            self.build_seq(refs, info, offset, depth, &mut out);
            return BuiltSubtree::Flat(out);
        }
        let mut node = Self::node(info);
        match self.split(refs, info, depth) {
            None => {
                node.first = offset as u32;
                node.count = refs.len() as u32;
                BuiltSubtree::Flat(vec![node])
            }
            Some((mid, [li, ri])) => {
                let (l, r) = refs.split_at_mut(mid);
                let (bl, br) = rayon::join(
                    || self.build_par(l, &li, offset, depth + 1),
                    || self.build_par(r, &ri, offset + mid, depth + 1),
                );
                BuiltSubtree::Split(node, Box::new(bl), Box::new(br))
            }
        }
    }
}

/// Appends a built subtree in depth-first order, rebasing inner nodes' child indices.
fn flatten<const N: usize>(b: BuiltSubtree<N>, out: &mut Vec<BinaryNode<N>>) {
    match b {
        BuiltSubtree::Flat(v) => {
            let base = out.len() as u32;
            out.extend(v.into_iter().map(|mut nd| {
                if nd.count == 0 {
                    nd.first += base;
                }
                nd
            }));
        }
        BuiltSubtree::Split(node, l, r) => {
            let me = out.len();
            out.push(node);
            flatten(*l, out);
            out[me].first = out.len() as u32;
            flatten(*r, out);
        }
    }
}

/// The records of the boxes `bounds` ([`Ref::new`]), input i's with id i.
pub(super) fn refs_of<const N: usize>(bounds: &[Bounds<N>]) -> Vec<Ref<N>> {
    (bounds.par_iter().enumerate())
        .map(|(id, b)| Ref::new(id as u32, b))
        .collect()
}

/// The binary SAH tree over the records `refs`, in depth-first order, and the leaf order
/// (`idx[j]`: the id of the j-th record in leaf order). Forks with rayon above `par_min`
/// records. Records with ids from `cells_from` on are flat cells: each becomes a leaf alone.
pub(super) fn binary_tree<const N: usize>(
    mut refs: Vec<Ref<N>>,
    par_min: usize,
    cells_from: u32,
) -> (Vec<BinaryNode<N>>, Vec<u32>) {
    let builder = Builder {
        par_min: par_min.max(2),
        cells_from,
    };
    let info = builder.info(&refs);
    let built = builder.build_par(&mut refs, &info, 0, 0);
    let idx = refs.par_iter().map(|r| r.id).collect();
    drop(refs);
    let mut bin = Vec::new();
    flatten(built, &mut bin);
    (bin, idx)
}

impl<const N: usize> Bvh<N> {
    /// Builds over prepared simplices; `ids[i]` is the caller's id of `prims[i]` (returned in
    /// [`Hit::prim`](crate::ray::Hit::prim)) and `bounds[i]` the (min, max) corners of its vertices.
    /// The tree keeps `prims` (by id) as the source of its exact simplices ([`ExactSource`]);
    /// the builds of a scene read them from its meshes instead.
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

    pub(super) fn build_with(
        prims: Vec<PreparedSimplex<N>>,
        ids: Vec<u32>,
        bounds: Vec<([f64; N], [f64; N])>,
        par_min: usize,
    ) -> Self {
        assert!(
            prims.len() == ids.len(),
            "Bvh::build: prims, ids, bounds lengths differ"
        );
        let by_id: std::collections::HashMap<u32, PreparedSimplex<N>> =
            ids.iter().copied().zip(prims.iter().copied()).collect();
        let exact = ExactSource::new(move |id| by_id[&id]);
        let refs = refs_of(&bounds);
        drop(bounds);
        let fill = (|i, _| prims[i], |i, _| Lane::of(&prims[i]), |_, _, _| ());
        Self::build_from(ids, refs, Vec::new(), fill, exact, par_min)
    }

    /// [`Bvh::build`] without a list of prepared simplices: `prepare(id)` gives the one with
    /// id `id` (a simplex that [`PreparedSimplex::new`] accepts), called once per simplex, in
    /// parallel, when its block is filled, and kept as the tree's [`ExactSource`]. The same
    /// tree and blocks as `build` over the
    /// prepared simplices of `ids`, at the memory of the finished tree.
    ///
    /// # Panics
    /// If `ids` and `bounds` differ in length or hold 2³¹ or more simplices.
    pub fn build_lazily(
        ids: Vec<u32>,
        bounds: Vec<([f64; N], [f64; N])>,
        prepare: impl Fn(u32) -> PreparedSimplex<N> + Send + Sync + 'static,
    ) -> Self {
        Self::build_lazily_with_cells(ids, bounds, Vec::new(), prepare)
    }

    /// [`Bvh::build_lazily`], with the simplices of each of `cells` held as one flat cell (see
    /// `cell.rs`) when they form one: a ray that meets the cell is tested against the block of
    /// the simplex a walk finds, not against all of them. Hits and ids are bit for bit those of
    /// [`Bvh::build_lazily`]. The cells that do not pass the checks of `CellGeometry::new` are
    /// built as ordinary simplices.
    ///
    /// # Panics
    /// As [`Bvh::build_lazily`], and if a cell's member is out of range, or in two of the cells
    /// kept, or if its `points` and `members` differ in length.
    pub fn build_lazily_with_cells(
        ids: Vec<u32>,
        bounds: Vec<([f64; N], [f64; N])>,
        cells: Vec<FlatCell<N>>,
        prepare: impl Fn(u32) -> PreparedSimplex<N> + Send + Sync + 'static,
    ) -> Self {
        let exact = ExactSource::new(prepare);
        let prepare = exact.0.clone();
        assert!(
            bounds.len() == ids.len(),
            "Bvh::build: prims, ids, bounds lengths differ"
        );
        let refs = refs_of(&bounds);
        drop(bounds);
        let fill = (
            |_, id| prepare(id),
            |_, id| Lane::of(&prepare(id)),
            |_, _, _| (),
        );
        Self::build_from(ids, refs, cells, fill, exact, PAR_MIN)
    }

    /// [`Bvh::build_lazily_with_cells`] over the build records of the simplices (`refs[i]`
    /// input i's, with id i), with a `prepare`, `lane` and `warm` as `build_from` takes them,
    /// which may borrow: the tree has no exact source until [`Bvh::set_exact`] gives it one
    /// (the scene's, once its objects are shared).
    pub(crate) fn build_with_cells_borrowing(
        ids: Vec<u32>,
        refs: Vec<Ref<N>>,
        cells: Vec<FlatCell<N>>,
        fill: (
            impl Fn(usize, u32) -> PreparedSimplex<N> + Sync,
            impl Fn(usize, u32) -> Lane<N> + Sync,
            impl Fn(usize, u32, bool) + Sync,
        ),
    ) -> Self {
        Self::build_from(ids, refs, cells, fill, ExactSource::none(), PAR_MIN)
    }

    /// The build over `ids` and their records `refs` (`refs[i]` input i's, with id i) with
    /// the flat `cells`. `prepare(i, ids[i])` gives input i's prepared simplex (for the
    /// cells), `lane(i, ids[i])` what its block lane holds (the lane of that prepared simplex),
    /// and `warm(i, ids[i], near)` may ask for what `lane` reads ahead of the call (`near`:
    /// the simplex's reference was asked for before; see `wide_tree`).
    fn build_from(
        ids: Vec<u32>,
        refs: Vec<Ref<N>>,
        cells: Vec<FlatCell<N>>,
        (prepare, lane, warm): (
            impl Fn(usize, u32) -> PreparedSimplex<N> + Sync,
            impl Fn(usize, u32) -> Lane<N> + Sync,
            impl Fn(usize, u32, bool) + Sync,
        ),
        exact: ExactSource<N>,
        par_min: usize,
    ) -> Self {
        let n = ids.len();
        assert!(
            refs.len() == n,
            "Bvh::build: prims, ids, bounds lengths differ"
        );
        debug_assert!(refs.iter().enumerate().all(|(i, r)| r.id == i as u32));
        assert!(n < LEAF_TAG as usize, "Bvh::build: too many simplices");
        if n == 0 {
            return Bvh {
                nodes: Vec::new(),
                blocks: Vec::new(),
                len: 0,
                reach: 0.0,
                ranges: Vec::new(),
                cells: Vec::new(),
                cell_links: Vec::new(),
                cell_prepared: Vec::new(),
                exact,
                exact_rows: Vec::new(),
            };
        }
        // The cells that pass the checks; the binary tree is built over the other simplices
        // and one box per cell (after them).
        let cells: Vec<(Vec<u32>, CellGeometry<N>)> = cells
            .into_par_iter()
            .filter_map(|c| {
                assert_eq!(
                    c.members.len(),
                    c.points.len(),
                    "FlatCell: members and points differ in length"
                );
                let prepared = (c.members.iter())
                    .map(|&i| prepare(i as usize, ids[i as usize]))
                    .collect();
                CellGeometry::new(&c.points, prepared).map(|g| (c.members, g))
            })
            .collect();
        let (bin, order) = if cells.is_empty() {
            binary_tree(refs, par_min, u32::MAX)
        } else {
            let mut in_cell = vec![false; n];
            for &i in cells.iter().flat_map(|(m, _)| m) {
                assert!(
                    !std::mem::replace(&mut in_cell[i as usize], true),
                    "FlatCell: input {i} is in two cells"
                );
            }
            let plain: Vec<u32> = (0..n as u32).filter(|&i| !in_cell[i as usize]).collect();
            drop(in_cell);
            // The plain records renumbered, then one per cell: the union of its members'
            // (each contains its simplex's band, so the union contains all of them; a cell
            // that passed `CellGeometry::new` has at least 2 members).
            let mut prims: Vec<Ref<N>> = (plain.iter().enumerate())
                .map(|(p, &i)| Ref {
                    id: p as u32,
                    ..refs[i as usize]
                })
                .collect();
            for (members, _) in &cells {
                let first = refs[members[0] as usize];
                let b = (members[1..].iter()).fold(first, |b, &i| b.union(&refs[i as usize]));
                prims.push(Ref {
                    id: prims.len() as u32,
                    ..b
                });
            }
            drop(refs);
            let from = plain.len() as u32;
            let (bin, idx) = binary_tree(prims, par_min, from);
            let order = idx
                .into_iter()
                .map(|p| {
                    if p < from {
                        plain[p as usize]
                    } else {
                        CELL_MARK | (p - from)
                    }
                })
                .collect();
            (bin, order)
        };
        let root = &bin[0];
        let reach = (0..N)
            .map(|i| f64::from(root.min[i].abs()).max(f64::from(root.max[i].abs())))
            .fold(0.0, f64::max);
        let fill = (|i| lane(i, ids[i]), |i, near| warm(i, ids[i], near));
        let tree = wide_tree(bin, &order, fill, &ids, &cells);
        drop((ids, order));
        // Non-finite bounds only widen the slab test (and the shift saturates to infinity).
        let reach = if reach.is_finite() {
            reach
        } else {
            f64::from(f32::MAX)
        };
        let ranges = id_ranges(&tree.nodes, &tree.blocks, &tree.cells);
        Bvh {
            nodes: tree.nodes,
            blocks: tree.blocks,
            len: n,
            reach,
            ranges,
            cells: tree.cells,
            cell_links: tree.cell_links,
            cell_prepared: tree.cell_prepared,
            exact,
            exact_rows: Vec::new(),
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
}

#[cfg(test)]
mod tests;
