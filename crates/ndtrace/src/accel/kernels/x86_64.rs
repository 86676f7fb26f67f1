//! The x86_64 kernels: the SSE/SSE2 slab and block tests (x86_64 baseline) and their AVX2
//! versions, the AVX2 packet slab test and bit-mask helpers, and prefetches. Each performs
//! exactly the arithmetic of its portable twin in `portable.rs` (the same operations in the same
//! order, no FMA), which the tests check bit for bit.

use super::super::packet::{Packet, TraversalRay};
use super::super::simplex::PreparedRay;
use super::super::stats;
use super::super::tree::{BlockHits, LeafBlock, WideNode, BLOCK_WIDTH, NODE_WIDTH};
use crate::accel::BARY_SLACK;
use std::arch::x86_64::*;

impl<const N: usize> TraversalRay<N> {
    /// Slab test of the child boxes of a node against the parameter range [lo, hi]: a bit
    /// mask of the boxes met, and their entry parameters (+∞ for the boxes missed).
    ///
    /// Conservative: the near and far planes of each slab are chosen by the sign of the
    /// direction and evaluated with the origin moved and rounded to f32 in the safe direction
    /// (see [`TraversalRay::new`](super::super::packet::TraversalRay::new)). A zero direction component (inv = ±∞) gives −∞/+∞ for an origin
    /// strictly inside the slab and equal-signed infinities outside it; the one NaN case, `0·∞`
    /// for an origin exactly on a slab plane, is ignored by the running max/min (which keep the
    /// other operand), leaving the slab unrestricted: boxes are closed, and a ray running along
    /// a face is inside.
    #[inline(always)]
    pub(in crate::accel) fn slab_sse(
        &self,
        node: &WideNode<N>,
        lo: f32,
        hi: f32,
    ) -> (u32, [f32; NODE_WIDTH]) {
        use std::arch::x86_64::*;
        let mut mask = 0;
        let mut out = [0.0f32; NODE_WIDTH];
        // SAFETY: SSE is part of the x86_64 baseline; every pointer loaded or stored is a
        // `[f32; NODE_WIDTH]` accessed in quarters of 16 valid bytes (unaligned accesses).
        unsafe {
            for q in 0..NODE_WIDTH / 4 {
                let ld = |a: &[f32; NODE_WIDTH]| _mm_loadu_ps(a.as_ptr().add(4 * q));
                let mut near = [_mm_set1_ps(lo); N];
                let mut far = [_mm_set1_ps(hi); N];
                for i in 0..N {
                    let s = self.near[i] & 1;
                    let inv = _mm_set1_ps(self.inv[i]);
                    let (on, of) = (_mm_set1_ps(self.o_near[i]), _mm_set1_ps(self.o_far[i]));
                    let a = _mm_mul_ps(_mm_sub_ps(ld(&node.bounds[s][i]), on), inv);
                    let c = _mm_mul_ps(_mm_sub_ps(ld(&node.bounds[s ^ 1][i]), of), inv);
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
}

impl<const N: usize> LeafBlock<N> {
    /// Intersects the ray with every lane: which lanes are hit with t in (tmin, tmax), and
    /// their data. Per lane, exactly the arithmetic of [`PreparedSimplex::intersect`](crate::accel::PreparedSimplex::intersect) (the same
    /// operations in the same order, hence the same bits). Returns early, before the inside
    /// test, when no lane has t in range.
    #[inline(always)]
    pub(in crate::accel) fn hit_sse2(
        &self,
        ray: &PreparedRay<N>,
        tmin: f64,
        tmax: f64,
    ) -> BlockHits<N> {
        use std::arch::x86_64::*;
        const H: usize = BLOCK_WIDTH / 2;
        /// Pairwise sum in the order of `simplex::sum_pairwise`.
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
            let ld = |a: &[f64; BLOCK_WIDTH], h: usize| _mm_loadu_pd(a.as_ptr().add(2 * h));
            let zero = _mm_setzero_pd();
            let d: [__m128d; N] = std::array::from_fn(|i| _mm_set1_pd(ray.d[i]));
            let mut out = BlockHits {
                mask: 0,
                t: [0.0; BLOCK_WIDTH],
                den: [0.0; BLOCK_WIDTH],
                u: [[0.0; BLOCK_WIDTH]; N],
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

    /// The block test of [`LeafBlock::hit_sse2`] with the 4 lanes in one AVX register: the same
    /// operations in the same order (no FMA), hence the same bits, and the same early return.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::accel) unsafe fn hit_avx2(
        &self,
        ray: &PreparedRay<N>,
        tmin: f64,
        tmax: f64,
    ) -> BlockHits<N> {
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
        let ld = |a: &[f64; BLOCK_WIDTH]| _mm256_loadu_pd(a.as_ptr());
        let d: [__m256d; N] = std::array::from_fn(|i| _mm256_set1_pd(ray.d[i]));
        let mut out = BlockHits {
            mask: 0,
            t: [0.0; BLOCK_WIDTH],
            den: [0.0; BLOCK_WIDTH],
            u: [[0.0; BLOCK_WIDTH]; N],
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
}

/// [`slabs`](super::slabs) with each ray's test in AVX2 registers (the node's boxes loaded once; when every
/// ray of the packet has the same direction signs, its near and far planes are picked once).
///
/// Not itself compiled for AVX2 but always inlined, as are its helpers (closures would not be),
/// so that its intrinsics end up inlined into the AVX2-compiled traversal (a `target_feature`
/// function stays a call per node visit, returning through memory).
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
pub(in crate::accel) unsafe fn slabs_avx2<const N: usize, const P: usize>(
    packet: &Packet<N, P>,
    node: &WideNode<N>,
    rays: u32,
    lo: f32,
    limit: &[f32; P],
) -> (u64, [f32; NODE_WIDTH]) {
    use std::arch::x86_64::*;
    // SAFETY (all the intrinsics below): the caller guarantees AVX2; every pointer loaded or
    // stored is a `[f32; NODE_WIDTH]` (unaligned accesses).
    unsafe {
        let mut tn = _mm256_set1_ps(f32::INFINITY);
        let mut met = 0u64;
        let mut left = rays;
        let (mut bn, mut bf) = ([_mm256_setzero_ps(); N], [_mm256_setzero_ps(); N]);
        let (mut dn, mut df) = ([_mm256_setzero_ps(); N], [_mm256_setzero_ps(); N]);
        if let Some(side) = &packet.octant {
            for i in 0..N {
                bn[i] = _mm256_loadu_ps(node.bounds[side[i] & 1][i].as_ptr());
                bf[i] = _mm256_loadu_ps(node.bounds[(side[i] & 1) ^ 1][i].as_ptr());
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
                    bn[i] = _mm256_loadu_ps(node.bounds[side[i] & 1][i].as_ptr());
                    bf[i] = _mm256_loadu_ps(node.bounds[(side[i] & 1) ^ 1][i].as_ptr());
                }
                slab_planes(&packet.pre[q], &bn, &bf, &mut dn, &mut df);
                slab_ray(&packet.pre[q], q, &dn, &df, lo, limit[q], &mut met, &mut tn);
            }
        }
        let mut out = [0.0f32; NODE_WIDTH];
        _mm256_storeu_ps(out.as_mut_ptr(), tn);
        (met, out)
    }
}

/// The planes `bn` (entered) and `bf` (left) relative to the shifted origins of ray `p`, into
/// `dn` and `df`. Part of [`slabs_avx2`] (always inlined, no closures: see there).
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn slab_planes<const N: usize>(
    p: &TraversalRay<N>,
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
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn slab_ray<const N: usize>(
    p: &TraversalRay<N>,
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
        // either is NaN, so a NaN parameter leaves its slab unrestricted, as in `TraversalRay::slab_sse`
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

/// Prefetches the first `bytes` bytes from `p`: every 64 bytes from the start, then the last
/// byte (a fixed count: unrolled).
#[inline(always)]
pub(in crate::accel) fn prefetch(p: *const i8, bytes: usize) {
    for k in 0..=(bytes - 1) / 64 + 1 {
        // SAFETY: a prefetch never faults, whatever the address.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add((64 * k).min(bytes - 1))) };
    }
}

/// [`leaf_slots`](super::leaf_slots) from one AVX2 compare.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
pub(in crate::accel) unsafe fn leaf_slots_avx2(child: &[u32; NODE_WIDTH]) -> (u32, u32) {
    // SAFETY: `AVX` is only true in code running after an AVX2 check; `child` holds 8 u32
    // (unaligned load).
    unsafe {
        let c = _mm256_loadu_si256(child.as_ptr().cast());
        let leafy = _mm256_movemask_ps(_mm256_castsi256_ps(c)) as u32;
        let none = _mm256_cmpeq_epi32(c, _mm256_set1_epi32(-1));
        (leafy, _mm256_movemask_ps(_mm256_castsi256_ps(none)) as u32)
    }
}

/// # Safety
/// The CPU must support AVX2.
#[target_feature(enable = "avx2")]
#[inline]
pub(in crate::accel) unsafe fn within8(t: f32, limit: *const f32) -> u32 {
    // SAFETY: the caller passes 8 valid f32 (unaligned load).
    let l = unsafe { _mm256_loadu_ps(limit) };
    _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_set1_ps(t), l)) as u32
}
