//! The queries: nearest-first traversal of the wide tree by packets of rays, closest hit and any
//! hit, with the SIMD kernels chosen once per query.

use super::build::MAX_SAH_DEPTH;
use super::cell::{Cell, Pick};
use super::kernels::{frustum_slabs, leaf_slots, prefetch_block, slabs, within};
use super::packet::{Packet, PACKET};
use super::simplex::PreparedRay;
use super::stats;
use super::tree::{
    f32_down, f32_up, BlockHits, Bvh, LeafBlock, BLOCK_WIDTH, CELL_TAG, EMPTY_SLOT, LEAF_TAG,
    NODE_WIDTH,
};
use crate::ray::{Hit, Ray};
use std::mem::MaybeUninit;
use std::ops::Range;

/// Traversal stack size: a node pushes at most NODE_WIDTH − 1 entries, and the wide tree is no deeper
/// than the binary one.
const STACK_SIZE: usize = (NODE_WIDTH - 1) * (MAX_SAH_DEPTH + 34) + 2;
/// Relative widening of the parameter range used for box culling: covers the rounding of a
/// simplex's computed t (~N·ε·|x_0 − C| over the distance of C to its hyperplane), so that box
/// culling never rejects a node holding a simplex whose computed t is within range.
const T_PAD: f64 = 1e-9;

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

/// The best hit so far of one ray of a closest-hit traversal.
#[derive(Clone, Copy)]
struct BestHit<const N: usize> {
    t: f64,
    id: u32,
    bary: [f64; N],
    found: bool,
    /// Where the simplex hit is: its block and lane.
    block: u32,
    lane: u32,
}

impl<const N: usize> Bvh<N> {
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

    /// Calls `test` with each block a ray must be tested against at leaf reference `leaf`: the
    /// leaf's block, or for a flat cell the blocks [`Cell::pick`] chooses.
    #[inline(always)]
    fn leaf_blocks(&self, leaf: u32, ray: &PreparedRay<N>, test: &mut impl FnMut(u32)) {
        if leaf & CELL_TAG == 0 {
            return test(leaf & !LEAF_TAG);
        }
        let cell = &self.cells[(leaf & !(LEAF_TAG | CELL_TAG)) as usize];
        stats::count(1);
        match self.cell_pick(cell, ray) {
            Pick::Miss => {}
            Pick::Simplex(s) => test(cell.first_block + s / BLOCK_WIDTH as u32),
            Pick::All => cell.blocks().for_each(test),
        }
    }

    /// [`Cell::pick`] over the cell's simplices, exact (as the module docs of `cell.rs` need).
    #[inline]
    pub(super) fn cell_pick(&self, cell: &Cell, ray: &PreparedRay<N>) -> Pick {
        let prepared = &self.cell_prepared[cell.links as usize..][..cell.count as usize];
        let start = &prepared[cell.start as usize];
        let plane = (start.normal(), start.origin());
        cell.pick(&self.cell_links, ray, plane, |s, x| {
            prepared[s as usize].barycentric(x)
        })
    }

    /// The exact test of simplex `id`, for a lane its block's rounded rows leave unsure.
    #[cold]
    #[inline(never)]
    fn exact_hit(
        &self,
        id: u32,
        ray: &PreparedRay<N>,
        tmin: f64,
        tmax: f64,
    ) -> Option<(f64, [f64; N])> {
        stats::count(3);
        (self.exact.0)(id).hit(ray, tmin, tmax)
    }

    /// The address of a leaf's block for prefetching: no bounds check (a prefetch never
    /// faults), which a few prefetches per node visit would pay for. Not for flat cells.
    #[inline(always)]
    fn block_ptr(&self, child: u32) -> *const LeafBlock<N> {
        self.blocks
            .as_ptr()
            .wrapping_add((child & !LEAF_TAG) as usize)
    }

    /// Fetches a leaf's block whole, about to be tested (a flat cell's are found by its walk).
    #[inline(always)]
    fn prefetch_leaf(&self, leaf: u32) {
        if leaf & CELL_TAG == 0 {
            prefetch_block(self.block_ptr(leaf), size_of::<LeafBlock<N>>());
        }
    }

    /// Tests block `b`, with its exact rows when the tree keeps them (see
    /// [`Bvh::keep_exact_rows`]), else with its rounded rows; with the AVX2 kernels when `AVX`
    /// (only instantiated inside functions compiled for AVX2).
    #[inline(always)]
    fn block_hit<const AVX: bool>(
        &self,
        b: u32,
        ray: &PreparedRay<N>,
        tmin: f64,
        tmax: f64,
    ) -> BlockHits<N> {
        stats::count(1);
        let block = &self.blocks[b as usize];
        let exact = self.exact_rows.get(b as usize);
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: `AVX` is only true in code running after an AVX2 check.
            return unsafe {
                match exact {
                    Some(rows) => block.hit_exact_avx2(rows, ray, tmin, tmax),
                    None => block.hit_avx2(ray, tmin, tmax),
                }
            };
        }
        match exact {
            Some(rows) => block.hit_exact_portable(rows, ray, tmin, tmax),
            None => block.hit(ray, tmin, tmax),
        }
    }

    /// Tests the children of inner node `cur` against the rays of the packet in the bit set
    /// `rays` (ray q against `[lo, limit[q]]`) and returns the nearest child met with the rays
    /// that met it (`EMPTY_SLOT` if none), after pushing the other children met, farthest first (so
    /// they are popped nearest first). A child's entry parameter is the smallest among its rays.
    /// Without `NEAREST_FIRST` (any-hit queries, whose answer does not depend on the order) the
    /// children go in slot order, unsorted, and those whose ids all lie in `skip` are dropped.
    /// Leaves met are not sorted either when no inner node or flat cell is met with them: the
    /// nearest hit does not depend on the order (see [`Bvh::closest_hit`]), sorting a few
    /// leaves costs unpredictable branches, and it saves few block tests.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn descend<const AVX: bool, const P: usize, const NEAREST_FIRST: bool>(
        &self,
        (packet, originals): (&mut Packet<N, P>, &[Ray<N>]),
        cur: u32,
        rays: u32,
        lo: f32,
        limit: &[f32; P],
        skip: &Range<u32>,
        stack: &mut [MaybeUninit<StackEntry>; STACK_SIZE],
        sp: &mut usize,
    ) -> (u32, u32) {
        let nd = &self.nodes[cur as usize];
        stats::count(0);
        // The slots holding leaves (or nothing), those holding nothing, and the flat cells.
        let (leafy, empty) = leaf_slots::<AVX>(&nd.child);
        // A coherent packet's frustum first: the children no ray can meet, and when it meets
        // only inner nodes, which of them every ray of `rays` goes on to (the rays' own tests
        // are left to the nodes whose leaves the frustum meets).
        let mut shared = None;
        if let Some(f) = &packet.frustum {
            let (m, t) = frustum_slabs::<N, AVX, P>(f, nd, lo, limit);
            if m == 0 {
                return (EMPTY_SLOT, 0);
            }
            if m & leafy == 0 {
                shared = Some((m, t));
            }
        }
        // Byte l of `by_child`: the rays that meet child l; `tn`: the smallest entry per child
        // (for a frustum, a lower bound of its rays').
        let (by_child, tn, mut mask) = match shared {
            Some((m, t)) => (spread(m) * u64::from(rays), t, m),
            None => {
                packet.prepare(originals, self.reach);
                // Byte q of `met`: the children ray q meets.
                let (met, tn) = slabs::<N, AVX, P>(packet, nd, rays, lo, limit);
                let mut any = met;
                any |= any >> 32;
                any |= any >> 16;
                any |= any >> 8;
                (transpose8(met), tn, (any & 0xff) as u32)
            }
        };
        if !NEAREST_FIRST && !skip.is_empty() {
            let r = &self.ranges[cur as usize];
            for l in 0..NODE_WIDTH {
                let inside = skip.start <= r[0][l] && r[1][l] < skip.end;
                mask &= !((inside as u32) << l);
            }
        }
        if mask == 0 {
            return (EMPTY_SLOT, 0);
        }
        let cells = if self.cells.is_empty() {
            0
        } else {
            cell_slots(&nd.child)
        };
        if NEAREST_FIRST {
            // The leaves the next packets will likely meet (see `prefetch_block`).
            let mut leaves = leafy & !empty & !cells;
            while leaves != 0 {
                let l = leaves.trailing_zeros() as usize;
                leaves &= leaves - 1;
                prefetch_block(self.block_ptr(nd.child[l]), LeafBlock::<N>::HEAD);
            }
        }
        let rays_of = |l: usize| ((by_child >> (8 * l)) & 0xff) as u32;
        if mask & (mask - 1) == 0 {
            let l = mask.trailing_zeros() as usize;
            return (nd.child[l], rays_of(l));
        }
        // Flat cells cost a walk each: sorted like inner nodes, so that the nearest is met
        // first and its hit culls the others.
        if !NEAREST_FIRST || mask & (!leafy | cells) == 0 {
            // Any order finds the same answer (shadow rays, leaves): children in slot order.
            let mut rest = mask & (mask - 1);
            while rest != 0 {
                let l = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                if NEAREST_FIRST {
                    // Tested soon (unless a hit culls them): fetch them whole now.
                    prefetch_block(self.block_ptr(nd.child[l]), size_of::<LeafBlock<N>>());
                }
                stack[*sp].write(StackEntry {
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
        let mut hits = [(0.0f32, 0usize); NODE_WIDTH];
        let mut c = 0;
        for l in 0..NODE_WIDTH {
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
            stack[*sp].write(StackEntry {
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
        stack: &[MaybeUninit<StackEntry>; STACK_SIZE],
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
    pub(super) fn closest_hits_impl<const AVX: bool, const P: usize>(
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
        // Boxes are culled against [tmin, best] widened (T_PAD, then outward to f32); simplices
        // use the exact open interval.
        let lo = f32_down(pad_down(tmin));
        let hi = f32_up(pad_up(tmax));
        let mut slot = MaybeUninit::uninit();
        let packet = Packet::<N, P>::init(&mut slot, rays, self.reach);
        let mut limit = [f32::NEG_INFINITY; P];
        limit[..k].fill(hi);
        let mut best = [BestHit {
            t: tmax,
            id: u32::MAX,
            bary: [0.0; N],
            found: false,
            block: 0,
            lane: 0,
        }; P];
        // Blocks accept t < tmax, then, while a hit is held, t ≤ best.t (ties are settled by id).
        let mut tmax_b = [tmax; P];
        let mut stack = [MaybeUninit::<StackEntry>::uninit(); STACK_SIZE];
        let mut sp = 0usize;
        let (mut cur, mut cur_rays) = (0u32, (1u32 << k) - 1);
        loop {
            // Descend through inner nodes, nearest child first.
            while cur & LEAF_TAG == 0 {
                (cur, cur_rays) = self.descend::<AVX, P, true>(
                    (&mut *packet, rays),
                    cur,
                    cur_rays,
                    lo,
                    &limit,
                    &(0..0),
                    &mut stack,
                    &mut sp,
                );
            }
            if cur != EMPTY_SLOT {
                self.prefetch_leaf(cur);
                let mut left = cur_rays;
                while left != 0 {
                    let q = left.trailing_zeros() as usize;
                    left &= left - 1;
                    let ray = &packet.pre()[q].prepared;
                    let mut test = |b: u32| {
                        let block = &self.blocks[b as usize];
                        let hits = self.block_hit::<AVX>(b, ray, tmin, tmax_b[q]);
                        let mut mask = hits.mask | hits.unsure;
                        let best = &mut best[q];
                        while mask != 0 {
                            let l = mask.trailing_zeros() as usize;
                            mask &= mask - 1;
                            let id = block.ids[l];
                            let (t, bary) = if hits.unsure & (1 << l) == 0 {
                                (hits.t[l], None)
                            } else {
                                match self.exact_hit(id, ray, tmin, tmax_b[q]) {
                                    Some((t, b)) => (t, Some(b)),
                                    None => continue,
                                }
                            };
                            if (!best.found || t < best.t || (t == best.t && id < best.id))
                                && accept(id)
                            {
                                *best = BestHit {
                                    t,
                                    id,
                                    bary: bary.unwrap_or_else(|| hits.bary(l)),
                                    found: true,
                                    block: b,
                                    lane: l as u32,
                                };
                                limit[q] = f32_up(pad_up(t));
                                // `t.next_up()`, by one step when t > 0 (then finite: the
                                // block tests accept only t < tmax_b, strictly).
                                debug_assert!(t < f64::INFINITY);
                                tmax_b[q] = if t > 0.0 {
                                    f64::from_bits(t.to_bits() + 1)
                                } else {
                                    t.next_up()
                                };
                            }
                        }
                    };
                    self.leaf_blocks(cur, ray, &mut test);
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
                    normal: std::array::from_fn(|i| f64::from(m[i][b.lane as usize])),
                }
            });
        }
    }

    #[inline(always)]
    pub(super) fn any_hits_impl<const AVX: bool, const P: usize>(
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
        let mut stack = [MaybeUninit::<StackEntry>::uninit(); STACK_SIZE];
        let mut sp = 0usize;
        let (mut cur, mut cur_rays) = (0u32, alive);
        while alive != 0 {
            while cur & LEAF_TAG == 0 {
                (cur, cur_rays) = self.descend::<AVX, P, false>(
                    (&mut *packet, rays),
                    cur,
                    cur_rays,
                    lo,
                    &limit,
                    skip,
                    &mut stack,
                    &mut sp,
                );
            }
            if cur != EMPTY_SLOT {
                self.prefetch_leaf(cur);
                let mut left = cur_rays & alive;
                while left != 0 {
                    let q = left.trailing_zeros() as usize;
                    left &= left - 1;
                    let ray = &packet.pre()[q].prepared;
                    let mut hit = false;
                    self.leaf_blocks(cur, ray, &mut |b: u32| {
                        if hit {
                            return;
                        }
                        let block = &self.blocks[b as usize];
                        let hits = self.block_hit::<AVX>(b, ray, tmin, tmax[q]);
                        let counts = |l: usize| {
                            let id = block.ids[l];
                            accept(id) && !skip.contains(&id)
                        };
                        // The lanes the rounded rows decide first: the exact tests of the
                        // unsure ones (a shadow ray leaving a simplex is often unsure of its
                        // neighbours, which it leaves at t ≈ 0) only when none of them counts.
                        let mut mask = hits.mask;
                        while mask != 0 {
                            let l = mask.trailing_zeros() as usize;
                            mask &= mask - 1;
                            if counts(l) {
                                hit = true;
                                return;
                            }
                        }
                        let mut mask = hits.unsure;
                        while mask != 0 {
                            let l = mask.trailing_zeros() as usize;
                            mask &= mask - 1;
                            if counts(l)
                                && self.exact_hit(block.ids[l], ray, tmin, tmax[q]).is_some()
                            {
                                hit = true;
                                return;
                            }
                        }
                    });
                    if hit {
                        out[q] = true;
                        alive &= !(1 << q);
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

/// The bit set of the slots of `child` that hold flat cells.
#[inline(always)]
fn cell_slots(child: &[u32; NODE_WIDTH]) -> u32 {
    let mut m = 0;
    for (l, &c) in child.iter().enumerate() {
        m |= u32::from(c & (LEAF_TAG | CELL_TAG) == LEAF_TAG | CELL_TAG && c != EMPTY_SLOT) << l;
    }
    m
}

/// A traversal stack entry: a subtree, the rays of the packet that met its box, and the
/// smallest of their entry parameters.
#[derive(Clone, Copy)]
struct StackEntry {
    node: u32,
    rays: u32,
    t: f32,
}

/// The bits of `m` (< 256) spread to the bytes of the result: byte l is 1 when bit l is set.
#[inline(always)]
fn spread(m: u32) -> u64 {
    // Bits 0–6: the product holds 8 copies of them 7 bits apart (disjoint, so no carries),
    // copy l putting bit l at bit 8l; bit 7 goes to bit 56 apart.
    let m = u64::from(m);
    (((m & 0x7f) * 0x0002_0408_1020_4081) | (m >> 7 & 1) << 56) & 0x0101_0101_0101_0101
}

/// Transposes the 8×8 bit matrix whose row r is byte r of `x` (bit c of the byte is column c):
/// bit `8r + c` moves to bit `8c + r` (Hacker's Delight, §7-3).
#[inline(always)]
pub(super) fn transpose8(mut x: u64) -> u64 {
    let t = (x ^ (x >> 7)) & 0x00aa_00aa_00aa_00aa;
    x ^= t ^ (t << 7);
    let t = (x ^ (x >> 14)) & 0x0000_cccc_0000_cccc;
    x ^= t ^ (t << 14);
    let t = (x ^ (x >> 28)) & 0x0000_0000_f0f0_f0f0;
    x ^ t ^ (t << 28)
}

#[cfg(test)]
mod tests;
