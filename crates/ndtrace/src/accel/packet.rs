//! Rays prepared for traversal: each ray's simplex-test data plus its conservative `f32` slab-test
//! data, and packets of up to [`PACKET`] of them.

use super::simplex::PreparedRay;
use super::tree::NODE_WIDTH;
use crate::ray::Ray;
use std::mem::MaybeUninit;

/// Rays traced together by [`Bvh::closest_hits`](super::Bvh::closest_hits) and
/// [`Bvh::any_hits`](super::Bvh::any_hits): one bit each in the
/// ray masks of the traversal, transposed with the children's masks as an 8×8 bit matrix.
pub const PACKET: usize = 8;
const _: () = assert!(
    PACKET == 8 && NODE_WIDTH == 8,
    "transpose8 needs 8 rays × 8 children"
);
/// Relative shift of the ray origin that makes the `f32` slab test conservative (see
/// [`TraversalRay::new`]); 2⁻²⁰ covers the test's four roundings of ≤ 2⁻²⁴ each with a wide margin.
const SLAB_REL: f64 = 1.0 / (1u32 << 20) as f64;

/// Per-ray data of a traversal: the simplex-test data plus the `f32` slab-test data.
#[derive(Clone, Copy)]
pub(super) struct TraversalRay<const N: usize> {
    pub(super) prepared: PreparedRay<N>,
    /// 1 when the ray enters slab i through its max side (`d_i` negative, including −0), else 0.
    pub(super) near: [usize; N],
    /// `1/d_i` in f32 (±∞ for a ±0 or tiny component).
    pub(super) inv: [f32; N],
    /// Origin moved and rounded to f32 towards the side that makes the near parameter smaller…
    pub(super) o_near: [f32; N],
    /// …and the far parameter larger.
    pub(super) o_far: [f32; N],
}

impl<const N: usize> TraversalRay<N> {
    /// `reach` bounds the absolute value of every box coordinate of the tree.
    #[inline(always)]
    pub(super) fn new(ray: &Ray<N>, reach: f64) -> Self {
        let mut pre = TraversalRay {
            prepared: PreparedRay::new(ray),
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
}

/// The rays of a packet, prepared for traversal.
pub(super) struct Packet<const N: usize, const P: usize> {
    pub(super) pre: [TraversalRay<N>; P],
    /// The rays' common [`TraversalRay::near`] sides, when they all have the same.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    pub(super) octant: Option<[usize; N]>,
    /// Whether every ray has the same shifted f32 origins ([`TraversalRay::o_near`], `o_far`): the
    /// slab planes relative to the origin are then computed once per node (bit-identical).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    pub(super) shared_origin: bool,
}

impl<const N: usize, const P: usize> Packet<N, P> {
    /// Prepares 1 ≤ `rays.len()` ≤ P ≤ [`PACKET`] rays in `slot` (unused slots repeat the
    /// first ray; no traversal mask ever names them). In place, so that no packet is built apart
    /// and copied.
    #[inline(always)]
    pub(super) fn init<'a>(
        slot: &'a mut MaybeUninit<Self>,
        rays: &[Ray<N>],
        reach: f64,
    ) -> &'a Self {
        let p = slot.as_mut_ptr();
        // SAFETY: the pointers are to fields of `slot`, in bounds (q < P), and every field is
        // written before the packet is referenced.
        unsafe {
            let pre = (&raw mut (*p).pre).cast::<TraversalRay<N>>();
            for q in 0..P {
                pre.add(q)
                    .write(TraversalRay::new(rays.get(q).unwrap_or(&rays[0]), reach));
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
