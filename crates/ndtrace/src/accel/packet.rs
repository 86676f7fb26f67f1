//! Rays prepared for traversal: each ray's simplex-test data plus its conservative `f32` slab-test
//! data, and packets of up to [`PACKET`] of them, with the frustum of a coherent packet.

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
            let neg = d.is_sign_negative();
            pre.near[i] = neg as usize;
            pre.inv[i] = 1.0 / d as f32;
            (pre.o_near[i], pre.o_far[i]) = shifted_origin(o, neg, reach);
        }
        pre
    }
}

/// The origin coordinate `o` moved and rounded to f32 for the slab test of a ray whose
/// direction component has the sign bit `neg`: `(o_near, o_far)` of [`TraversalRay`].
///
/// The f32 slab parameters `(b − o')·inv` carry four roundings (o' to f32 aside: the
/// difference, the product, and d and 1/d to f32), each ≤ 2⁻²⁴ relative, i.e. an absolute
/// error below 2⁻²²·|b − o'|·|1/d| with |b − o'| ≲ reach + |o|. Moving the origin by 2δ,
/// δ = 2⁻²⁰·(reach + |o|), towards the side that lowers the near parameter (and, separately,
/// raises the far one) more than covers that, and the rounding of o ± 2δ to f32
/// (≤ 2⁻²⁴·|o ± 2δ| < δ) cannot undo it. So the test is conservative without per-node
/// padding; boxes are widened by ~1e-6 of the scene.
#[inline(always)]
fn shifted_origin(o: f64, neg: bool, reach: f64) -> (f32, f32) {
    let delta2 = 2.0 * (reach + o.abs()) * SLAB_REL;
    // (b − o')·inv ≤ (b − o)·inv needs o' ≥ o when inv ≥ 0, o' ≤ o when inv < 0.
    let (lo, hi) = ((o - delta2) as f32, (o + delta2) as f32);
    if neg {
        (lo, hi)
    } else {
        (hi, lo)
    }
}

/// What the rays of a coherent packet share: one origin (bit for bit) and the signs of their
/// direction components, with finite, nonzero `1/d` in f32 (a pinhole camera's rays through a
/// few neighbouring cells). Their slab tests then differ only in `inv`, and a node's children
/// are tested for the whole packet at once by interval arithmetic (`frustum_slabs`): a child no
/// ray can meet is dropped without preparing or testing the rays one by one.
///
/// Every ray's slab parameters are `(b − o')·inv_q` with the same `b − o'` (the shifted origin
/// of [`TraversalRay`]), and for a fixed `x = b − o'` the rounded product `x·inv` is monotone
/// in `inv`; so the smallest entry and largest exit over the packet are products with the ends
/// `inv_min`, `inv_max` of its range, bit for bit a ray's own values. No NaN can occur (`x` is
/// finite or infinite, `inv` finite and nonzero). A ray that meets a box has entry ≤ exit, so
/// the packet's smallest entry is ≤ its largest exit: the frustum test meets every child a ray
/// of the packet meets, with an entry no later than that ray's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Frustum<const N: usize> {
    /// The rays' [`TraversalRay::near`] sides.
    pub(super) near: [usize; N],
    /// Their shifted origins ([`TraversalRay::o_near`], `o_far`).
    pub(super) o_near: [f32; N],
    pub(super) o_far: [f32; N],
    /// The least and greatest of their [`TraversalRay::inv`].
    pub(super) inv_min: [f32; N],
    pub(super) inv_max: [f32; N],
}

impl<const N: usize> Frustum<N> {
    /// The frustum of `rays` (at least one), when they are coherent (see [`Frustum`]).
    #[inline(always)]
    pub(super) fn of(rays: &[Ray<N>], reach: f64) -> Option<Self> {
        let first = &rays[0];
        let origin = first.origin.map(f64::to_bits);
        // Per axis over the rays: the least and greatest `1/d` (as `TraversalRay::new` computes
        // it), the least |1/d|, and Σ 0·(1/d), which is 0 when every `1/d` is finite and NaN
        // when one is infinite or NaN. Branch-free float operations on all axes at once, so
        // that a ray costs a few vector instructions.
        let mut inv_min = [f32::INFINITY; N];
        let mut inv_max = [f32::NEG_INFINITY; N];
        let mut abs_min = [f32::INFINITY; N];
        let mut poison = [0.0f32; N];
        let mut same_origin = true;
        for r in rays {
            same_origin &= r.origin.map(f64::to_bits) == origin;
            let inv: [f32; N] = std::array::from_fn(|i| 1.0 / r.dir[i] as f32);
            for i in 0..N {
                let a = inv[i].abs();
                poison[i] += 0.0 * inv[i];
                abs_min[i] = if a < abs_min[i] { a } else { abs_min[i] };
                inv_min[i] = if inv[i] < inv_min[i] {
                    inv[i]
                } else {
                    inv_min[i]
                };
                inv_max[i] = if inv[i] > inv_max[i] {
                    inv[i]
                } else {
                    inv_max[i]
                };
            }
        }
        // Coherent: one origin, every `1/d` finite (no poison) and nonzero, and one sign per
        // axis. A finite nonzero `1/d` has the sign of d, so the rays' direction signs agree on
        // an axis exactly when its least and greatest `1/d` do.
        let mut ok = same_origin;
        let mut neg = 0u32;
        for i in 0..N {
            ok &= poison[i] == 0.0 && abs_min[i] > 0.0;
            ok &= (inv_min[i] > 0.0) | (inv_max[i] < 0.0);
            neg |= ((inv_max[i] < 0.0) as u32) << i;
        }
        if !ok {
            return None;
        }
        let mut f = Frustum {
            near: [0; N],
            o_near: [0.0; N],
            o_far: [0.0; N],
            inv_min,
            inv_max,
        };
        for i in 0..N {
            let n = neg >> i & 1 == 1;
            f.near[i] = n as usize;
            (f.o_near[i], f.o_far[i]) = shifted_origin(first.origin[i], n, reach);
        }
        Some(f)
    }
}

/// The rays of a packet, prepared for traversal: at once, or for a coherent packet ([`Frustum`])
/// when a node first needs their own slab tests ([`Packet::prepare`]; many packets of a
/// pinhole's rays leave the tree before).
pub(super) struct Packet<const N: usize, const P: usize> {
    /// The rays' traversal data, once prepared.
    pre: [MaybeUninit<TraversalRay<N>>; P],
    prepared: bool,
    /// The rays' common [`TraversalRay::near`] sides, when they all have the same.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    pub(super) octant: Option<[usize; N]>,
    /// Whether every ray has the same shifted f32 origins ([`TraversalRay::o_near`], `o_far`): the
    /// slab planes relative to the origin are then computed once per node (bit-identical).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    pub(super) shared_origin: bool,
    /// What the rays share, when they are coherent.
    pub(super) frustum: Option<Frustum<N>>,
}

impl<const N: usize, const P: usize> Packet<N, P> {
    /// Starts a packet of 1 ≤ `rays.len()` ≤ P ≤ [`PACKET`] rays in `slot` (unused slots repeat
    /// the first ray; no traversal mask ever names them): a coherent packet gets its frustum,
    /// and its rays are prepared later ([`Packet::prepare`]); the others' rays at once. In
    /// place, so that no packet is built apart and copied.
    #[inline(always)]
    pub(super) fn init<'a>(
        slot: &'a mut MaybeUninit<Self>,
        rays: &[Ray<N>],
        reach: f64,
    ) -> &'a mut Self {
        let frustum = Frustum::of(rays, reach);
        let p = slot.as_mut_ptr();
        // SAFETY: the pointers are to fields of `slot`, and every field but `pre` (an array of
        // `MaybeUninit`) is written before the packet is referenced.
        let packet = unsafe {
            (&raw mut (*p).prepared).write(false);
            (&raw mut (*p).frustum).write(frustum);
            (&raw mut (*p).octant).write(frustum.map(|f| f.near));
            (&raw mut (*p).shared_origin).write(frustum.is_some());
            // Every field above: this pattern stops compiling if a field is added.
            let Packet {
                pre: _,
                prepared: _,
                octant: _,
                shared_origin: _,
                frustum: _,
            } = slot.assume_init_ref();
            slot.assume_init_mut()
        };
        if frustum.is_none() {
            packet.prepare(rays, reach);
        }
        packet
    }

    /// Prepares the rays (`rays`, `reach`: those of [`Packet::init`]) if they are not yet. A
    /// coherent packet keeps the octant and shared origin of its frustum, which its rays have.
    #[inline(always)]
    pub(super) fn prepare(&mut self, rays: &[Ray<N>], reach: f64) {
        if self.prepared {
            return;
        }
        for q in 0..P {
            self.pre[q].write(TraversalRay::new(rays.get(q).unwrap_or(&rays[0]), reach));
        }
        self.prepared = true;
        if self.frustum.is_none() {
            let pre = self.pre();
            let octant = pre
                .iter()
                .all(|p| p.near == pre[0].near)
                .then_some(pre[0].near);
            let shared_origin = pre.iter().all(|p| {
                p.o_near.map(f32::to_bits) == pre[0].o_near.map(f32::to_bits)
                    && p.o_far.map(f32::to_bits) == pre[0].o_far.map(f32::to_bits)
            });
            (self.octant, self.shared_origin) = (octant, shared_origin);
        }
    }

    /// The prepared rays.
    ///
    /// # Panics
    /// In debug builds, if the rays are not prepared ([`Packet::prepare`]).
    #[inline(always)]
    pub(super) fn pre(&self) -> &[TraversalRay<N>; P] {
        debug_assert!(self.prepared, "the packet's rays are not prepared");
        // SAFETY: `prepare` wrote every element before setting `prepared`, and the traversal
        // reads them only after a node's per-ray tests, which prepare them first.
        unsafe { &*(&raw const self.pre).cast::<[TraversalRay<N>; P]>() }
    }

    /// A packet of prepared rays with the given octant and shared origin (tests of the slab
    /// kernels, which pick their planes and differences by them).
    #[cfg(test)]
    pub(super) fn of_prepared(
        pre: [TraversalRay<N>; P],
        octant: Option<[usize; N]>,
        shared_origin: bool,
    ) -> Self {
        Packet {
            pre: pre.map(MaybeUninit::new),
            prepared: true,
            octant,
            shared_origin,
            frustum: None,
        }
    }
}
