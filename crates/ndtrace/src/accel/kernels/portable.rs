//! The portable kernels: the reference the x86_64 kernels are tested against bit for bit, and the
//! kernels of other targets. Compiled on every target.

use super::super::packet::{Frustum, TraversalRay};
use super::super::simplex::dot_pairwise;
use super::super::simplex::PreparedRay;
use super::super::tree::{
    BlockHits, ExactRows, LeafBlock, WideNode, EMPTY_SLOT, LEAF_TAG, NODE_WIDTH,
};
use super::super::PreparedSimplex;
use crate::linalg::sub;

impl<const N: usize> TraversalRay<N> {
    /// Portable version of the x86_64 slab test `slab_sse` (same arithmetic, same results).
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    #[inline(always)]
    pub(in crate::accel) fn slab_portable(
        &self,
        node: &WideNode<N>,
        lo: f32,
        hi: f32,
    ) -> (u32, [f32; NODE_WIDTH]) {
        let mut tn = [lo; NODE_WIDTH];
        let mut tf = [hi; NODE_WIDTH];
        for i in 0..N {
            let s = self.near[i] & 1;
            let (bn, bf) = (&node.bounds[s][i], &node.bounds[s ^ 1][i]);
            for l in 0..NODE_WIDTH {
                let a = (bn[l] - self.o_near[i]) * self.inv[i];
                let c = (bf[l] - self.o_far[i]) * self.inv[i];
                tn[l] = if a > tn[l] { a } else { tn[l] };
                tf[l] = if c < tf[l] { c } else { tf[l] };
            }
        }
        let mut mask = 0;
        for l in 0..NODE_WIDTH {
            let met = tn[l] <= tf[l];
            mask |= (met as u32) << l;
            if !met {
                tn[l] = f32::INFINITY;
            }
        }
        (mask, tn)
    }
}

impl<const N: usize> Frustum<N> {
    /// Portable version of the x86_64 frustum test `frustum_slabs_avx2` (same arithmetic, same
    /// results): per child, the packet's smallest entry and largest exit parameter on each
    /// axis (the products of `b − o'` with the ends of its range of `1/d`), against
    /// `[lo, hi]`.
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    #[inline(always)]
    pub(in crate::accel) fn slabs_portable(
        &self,
        node: &WideNode<N>,
        lo: f32,
        hi: f32,
    ) -> (u32, [f32; NODE_WIDTH]) {
        let mut tn = [lo; NODE_WIDTH];
        let mut tf = [hi; NODE_WIDTH];
        for i in 0..N {
            let s = self.near[i] & 1;
            let (bn, bf) = (&node.bounds[s][i], &node.bounds[s ^ 1][i]);
            for l in 0..NODE_WIDTH {
                let (x, y) = (bn[l] - self.o_near[i], bf[l] - self.o_far[i]);
                let (a0, a1) = (x * self.inv_min[i], x * self.inv_max[i]);
                let (c0, c1) = (y * self.inv_min[i], y * self.inv_max[i]);
                let a = if a0 < a1 { a0 } else { a1 };
                let c = if c0 > c1 { c0 } else { c1 };
                tn[l] = if a > tn[l] { a } else { tn[l] };
                tf[l] = if c < tf[l] { c } else { tf[l] };
            }
        }
        let mut mask = 0;
        for l in 0..NODE_WIDTH {
            let met = tn[l] <= tf[l];
            mask |= (met as u32) << l;
            if !met {
                tn[l] = f32::INFINITY;
            }
        }
        (mask, tn)
    }
}

impl<const N: usize> LeafBlock<N> {
    /// Portable version of the x86_64 block test `hit_avx2` (same arithmetic, same results):
    /// [`PreparedSimplex::hit_rounded`] lane by lane.
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    #[inline(always)]
    pub(in crate::accel) fn hit_portable(
        &self,
        ray: &PreparedRay<N>,
        tmin: f64,
        tmax: f64,
    ) -> BlockHits<N> {
        let mut out = BlockHits::NONE;
        for l in 0..self.count() {
            let m = std::array::from_fn(|k| std::array::from_fn(|i| f64::from(self.m[k][i][l])));
            let x0 = std::array::from_fn(|i| self.x0[i][l]);
            let r = PreparedSimplex::hit_rounded(&m, &x0, ray, tmin, tmax);
            out.t[l] = r.t;
            out.den[l] = r.den;
            for k in 1..N {
                out.u[k][l] = r.u[k];
            }
            out.mask |= u32::from(r.hit) << l;
            out.unsure |= u32::from(r.unsure) << l;
        }
        out
    }
}

impl<const N: usize> LeafBlock<N> {
    /// Portable version of the x86_64 exact block test `hit_exact_avx2` (same arithmetic, same
    /// results): the exact test [`PreparedSimplex::hit`] lane by lane, with the lanes' exact
    /// rows `rows` instead of the block's rounded ones; no lane is unsure. t and `n̂·d` are
    /// those of every lane, `u` those of the lanes hit.
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    #[inline(always)]
    pub(in crate::accel) fn hit_exact_portable(
        &self,
        rows: &ExactRows<N>,
        ray: &PreparedRay<N>,
        tmin: f64,
        tmax: f64,
    ) -> BlockHits<N> {
        let mut out = BlockHits::NONE;
        for l in 0..self.count() {
            let m: [[f64; N]; N] = std::array::from_fn(|k| std::array::from_fn(|i| rows[k][i][l]));
            let x0 = std::array::from_fn(|i| self.x0[i][l]);
            // The values `PreparedSimplex::hit` computes, kept for the traversal.
            let den = dot_pairwise(&m[0], &ray.d);
            let p = sub(&x0, &ray.o);
            let num = dot_pairwise(&m[0], &p);
            out.t[l] = num / den;
            out.den[l] = den;
            if let Some((t, _)) = (PreparedSimplex { m, x0 }).hit(ray, tmin, tmax) {
                debug_assert_eq!(t.to_bits(), out.t[l].to_bits());
                let w: [f64; N] = std::array::from_fn(|i| num * ray.d[i] - den * p[i]);
                for k in 1..N {
                    out.u[k][l] = dot_pairwise(&m[k], &w);
                }
                out.mask |= 1 << l;
            }
        }
        out
    }
}

/// The bit sets of the slots of `child` holding a leaf or nothing and of those holding nothing.
#[inline(always)]
pub(in crate::accel) fn leaf_slots(child: &[u32; NODE_WIDTH]) -> (u32, u32) {
    let (mut leafy, mut empty) = (0, 0);
    for (l, &c) in child.iter().enumerate() {
        leafy |= u32::from(c & LEAF_TAG != 0) << l;
        empty |= u32::from(c == EMPTY_SLOT) << l;
    }
    (leafy, empty)
}

/// The bit set of the rays q with `t ≤ limit[q]`.
#[inline(always)]
pub(in crate::accel) fn within<const P: usize>(t: f32, limit: &[f32; P]) -> u32 {
    let mut near = 0u32;
    for (q, &l) in limit.iter().enumerate() {
        near |= u32::from(t <= l) << q;
    }
    near
}
