//! The kernels of the traversal: slab tests of a node's child boxes and block tests of a leaf's
//! simplices, for one ray and for packets, with bit-mask helpers. `x86_64.rs` holds the SIMD
//! versions (slab tests in SSE2, slab and block tests in AVX2 chosen at run time), `portable.rs`
//! the portable ones, which every
//! target compiles and the tests compare with the SIMD ones bit for bit. The functions here pick
//! one; `AVX` is only true in code compiled for AVX2 and run after an AVX2 check.

pub(in crate::accel) mod portable;
#[cfg(target_arch = "x86_64")]
pub(in crate::accel) mod x86_64;

use super::packet::{Frustum, Packet, TraversalRay};
use super::simplex::PreparedRay;
use super::stats;
use super::tree::{BlockHits, LeafBlock, WideNode, NODE_WIDTH};

impl<const N: usize> TraversalRay<N> {
    /// Slab test of the child boxes of a node against the parameter range [lo, hi]: a bit
    /// mask of the boxes met, and their entry parameters (+∞ for the boxes missed); see
    /// `slab_sse` (x86_64) and `slab_portable`.
    #[inline(always)]
    pub(in crate::accel) fn slab(
        &self,
        node: &WideNode<N>,
        lo: f32,
        hi: f32,
    ) -> (u32, [f32; NODE_WIDTH]) {
        #[cfg(target_arch = "x86_64")]
        let out = self.slab_sse(node, lo, hi);
        #[cfg(not(target_arch = "x86_64"))]
        let out = self.slab_portable(node, lo, hi);
        out
    }
}

impl<const N: usize> LeafBlock<N> {
    /// Intersects the ray with every lane (`hit_portable`; the traversal calls `hit_avx2` instead on
    /// x86_64 CPUs with AVX2).
    #[inline(always)]
    pub(in crate::accel) fn hit(&self, ray: &PreparedRay<N>, tmin: f64, tmax: f64) -> BlockHits<N> {
        self.hit_portable(ray, tmin, tmax)
    }
}

/// Slab tests of the children of `node` for the rays of the packet in the bit set `rays` (ray q
/// against `[lo, limit[q]]`): byte q of the first result holds the children ray q meets, and the
/// second the smallest entry parameter per child (+∞ for a child no ray meets).
#[inline(always)]
pub(in crate::accel) fn slabs<const N: usize, const AVX: bool, const P: usize>(
    packet: &Packet<N, P>,
    node: &WideNode<N>,
    rays: u32,
    lo: f32,
    limit: &[f32; P],
) -> (u64, [f32; NODE_WIDTH]) {
    #[cfg(target_arch = "x86_64")]
    if AVX && NODE_WIDTH == 8 {
        // SAFETY: `AVX` is only true in code running after an AVX2 check.
        return unsafe { x86_64::slabs_avx2(packet, node, rays, lo, limit) };
    }
    let pre = packet.pre();
    let mut met = 0u64;
    let mut tn = [f32::INFINITY; NODE_WIDTH];
    let mut left = rays;
    while left != 0 {
        let q = left.trailing_zeros() as usize;
        left &= left - 1;
        stats::count(2);
        let (mask, t) = pre[q].slab(node, lo, limit[q]);
        met |= u64::from(mask) << (8 * q);
        for l in 0..NODE_WIDTH {
            // Entry parameters of boxes met are never NaN.
            tn[l] = if t[l] < tn[l] { t[l] } else { tn[l] };
        }
    }
    (met, tn)
}

/// The frustum test of a coherent packet against the children of `node` (see [`Frustum`]): the
/// bit set of the children some ray of the packet may meet within `[lo, limit[q]]`, and a lower
/// bound of their entry parameters (+∞ for the children no ray meets). Every child a ray's own
/// slab test meets is in the set.
#[inline(always)]
pub(in crate::accel) fn frustum_slabs<const N: usize, const AVX: bool, const P: usize>(
    frustum: &Frustum<N>,
    node: &WideNode<N>,
    lo: f32,
    limit: &[f32; P],
) -> (u32, [f32; NODE_WIDTH]) {
    // The packet's reach: the largest of its rays' (never NaN).
    let mut hi = f32::NEG_INFINITY;
    for &l in limit {
        hi = if l > hi { l } else { hi };
    }
    #[cfg(target_arch = "x86_64")]
    if AVX && NODE_WIDTH == 8 {
        // SAFETY: `AVX` is only true in code running after an AVX2 check.
        return unsafe { x86_64::frustum_slabs_avx2(frustum, node, lo, hi) };
    }
    frustum.slabs_portable(node, lo, hi)
}

/// Prefetches the first `bytes` (1 ≤ bytes ≤ its size) bytes of a block: [`LeafBlock::HEAD`] (what
/// a test reads before its early exit) or all of it (408 bytes for N = 3: 7 or 8 cache lines,
/// depending on where it starts).
///
/// The blocks of a large mesh do not stay in the core's caches from one trace to the next, so
/// the first test of a block waits for memory, and once more for its last lines (the rows
/// `r_k`, the ids), read only after the t test passed. Three prefetches hide part of that
/// (they change no result):
/// - a block about to be tested is fetched whole, so that its lines arrive together;
/// - when a packet meets only leaves of a node, those pushed for later are fetched whole while
///   the first is tested;
/// - the heads of all the leaves of a node a packet enters are fetched, met or not: the next
///   packets of the tile, a few pixels away, mostly meet the same node's other leaves.
#[inline(always)]
pub(in crate::accel) fn prefetch_block<const N: usize>(block: *const LeafBlock<N>, bytes: usize) {
    debug_assert!((1..=size_of::<LeafBlock<N>>()).contains(&bytes));
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (block, bytes);
    #[cfg(target_arch = "x86_64")]
    x86_64::prefetch(block.cast::<i8>(), bytes);
}

/// Asks for the cache lines of `*x` ahead of its use (no result changes; nothing on other
/// targets than x86-64).
#[inline(always)]
pub(crate) fn prefetch_of<T>(x: &T) {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
    #[cfg(target_arch = "x86_64")]
    x86_64::prefetch((x as *const T).cast::<i8>(), size_of::<T>().max(1));
}

/// The bit sets of the slots of `child` holding a leaf or nothing (those whose reference has
/// the `LEAF_TAG` bit) and of those holding nothing.
#[inline(always)]
pub(in crate::accel) fn leaf_slots<const AVX: bool>(child: &[u32; NODE_WIDTH]) -> (u32, u32) {
    #[cfg(target_arch = "x86_64")]
    if AVX && NODE_WIDTH == 8 {
        // SAFETY: `AVX` is only true in code running after an AVX2 check.
        return unsafe { x86_64::leaf_slots_avx2(child) };
    }
    portable::leaf_slots(child)
}

/// The bit set of the rays q with `t ≤ limit[q]`.
#[inline(always)]
pub(in crate::accel) fn within<const AVX: bool, const P: usize>(t: f32, limit: &[f32; P]) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if AVX && P == 8 {
        // SAFETY: `AVX` is only true in code running after an AVX2 check; P == 8.
        return unsafe { x86_64::within8(t, limit.as_ptr()) };
    }
    portable::within(t, limit)
}

#[cfg(test)]
mod tests;
