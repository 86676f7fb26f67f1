//! The x86_64 kernels: the SSE/SSE2 slab and block tests (x86_64 baseline) and their AVX2
//! versions, the AVX2 packet slab test and bit-mask helpers, and prefetches. Each performs
//! exactly the arithmetic of its portable twin in `portable.rs` (the same operations in the same
//! order, no FMA), which the tests check bit for bit.

use super::super::packet::{Frustum, Packet, TraversalRay};
use super::super::simplex::{PreparedRay, F64_ROUNDING, ROUNDING};
use super::super::stats;
use super::super::tree::{BlockHits, ExactRows, LeafBlock, WideNode, BLOCK_WIDTH, NODE_WIDTH};
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

/// The pairwise sum of [`sum_pairwise`](super::super::simplex::sum_pairwise), 4 lanes at a time.
#[inline(always)]
fn sum4<const N: usize>(mut v: [__m256d; N]) -> __m256d {
    let mut m = N;
    while m > 1 {
        let half = m.div_ceil(2);
        for j in 0..m / 2 {
            // SAFETY: only reached from the block kernels, whose callers guarantee AVX2.
            v[j] = unsafe { _mm256_add_pd(v[j], v[j + half]) };
        }
        m = half;
    }
    v[0]
}

impl<const N: usize> LeafBlock<N> {
    /// The exact block test with the 4 lanes in one AVX register: per lane, exactly the
    /// arithmetic of [`PreparedSimplex::hit`](crate::accel::PreparedSimplex) (the same
    /// operations in the same order, no FMA, hence the same bits) on the lanes' exact rows
    /// `rows` ([`Bvh::keep_exact_rows`](crate::accel::Bvh::keep_exact_rows)); no lane is unsure.
    /// Returns early, before the inside test, when no lane has t in range.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::accel) unsafe fn hit_exact_avx2(
        &self,
        rows: &ExactRows<N>,
        ray: &PreparedRay<N>,
        tmin: f64,
        tmax: f64,
    ) -> BlockHits<N> {
        let ld = |a: &[f64; BLOCK_WIDTH]| _mm256_loadu_pd(a.as_ptr());
        let splat = _mm256_set1_pd;
        let mut out = BlockHits::NONE;
        let d: [__m256d; N] = std::array::from_fn(|i| splat(ray.d[i]));
        let n: [__m256d; N] = std::array::from_fn(|i| ld(&rows[0][i]));
        let den = sum4::<N>(std::array::from_fn(|i| _mm256_mul_pd(n[i], d[i])));
        let p: [__m256d; N] =
            std::array::from_fn(|i| _mm256_sub_pd(ld(&self.x0[i]), splat(ray.o[i])));
        let num = sum4::<N>(std::array::from_fn(|i| _mm256_mul_pd(n[i], p[i])));
        let t = _mm256_div_pd(num, den);
        let crossing = _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_mul_pd(den, den), splat(ray.par2));
        let above = _mm256_cmp_pd::<_CMP_GT_OQ>(t, splat(tmin));
        let below = _mm256_cmp_pd::<_CMP_LT_OQ>(t, splat(tmax));
        let mut ok = _mm256_and_pd(crossing, _mm256_and_pd(above, below));
        _mm256_storeu_pd(out.t.as_mut_ptr(), t);
        _mm256_storeu_pd(out.den.as_mut_ptr(), den);
        if _mm256_movemask_pd(ok) as u32 & self.used() == 0 {
            return out;
        }
        let sign = splat(-0.0);
        let w: [__m256d; N] = std::array::from_fn(|i| {
            _mm256_sub_pd(_mm256_mul_pd(num, d[i]), _mm256_mul_pd(den, p[i]))
        });
        let ad = _mm256_andnot_pd(sign, den);
        let thr = _mm256_mul_pd(splat(-BARY_SLACK), ad);
        let flip = _mm256_and_pd(sign, den);
        let mut sum = _mm256_setzero_pd();
        for k in 1..N {
            let u = sum4::<N>(std::array::from_fn(|i| {
                _mm256_mul_pd(ld(&rows[k][i]), w[i])
            }));
            _mm256_storeu_pd(out.u[k].as_mut_ptr(), u);
            // u_k·sign(n̂·d), exactly (a sign flip).
            let v = _mm256_xor_pd(u, flip);
            ok = _mm256_and_pd(ok, _mm256_cmp_pd::<_CMP_GE_OQ>(v, thr));
            sum = _mm256_add_pd(sum, v);
        }
        ok = _mm256_and_pd(ok, _mm256_cmp_pd::<_CMP_GE_OQ>(_mm256_sub_pd(ad, sum), thr));
        out.mask = _mm256_movemask_pd(ok) as u32 & self.used();
        out
    }

    /// The block test with the 4 lanes in one AVX register: per lane, exactly the arithmetic
    /// of [`PreparedSimplex::hit_rounded`](crate::accel::PreparedSimplex) (the same operations
    /// in the same order, no FMA, hence the same bits) on the rows widened from f32. Returns
    /// early, before the inside test, when the t test rules out every lane.
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
        // SAFETY (closures): only called here, where AVX2 is guaranteed; the pointers are
        // `[f32; 4]` and `[f64; 4]` read whole (unaligned loads).
        let row = |a: &[f32; BLOCK_WIDTH]| _mm256_cvtps_pd(_mm_loadu_ps(a.as_ptr()));
        let sign = _mm256_set1_pd(-0.0);
        let abs = |v: __m256d| _mm256_andnot_pd(sign, v);
        let splat = _mm256_set1_pd;
        let mut out = BlockHits::NONE;
        let d: [__m256d; N] = std::array::from_fn(|i| splat(ray.d[i]));
        let n: [__m256d; N] = std::array::from_fn(|i| row(&self.m[0][i]));
        let den = sum4::<N>(std::array::from_fn(|i| _mm256_mul_pd(n[i], d[i])));
        let p: [__m256d; N] = std::array::from_fn(|i| {
            _mm256_sub_pd(_mm256_loadu_pd(self.x0[i].as_ptr()), splat(ray.o[i]))
        });
        let num = sum4::<N>(std::array::from_fn(|i| _mm256_mul_pd(n[i], p[i])));
        let t = _mm256_div_pd(num, den);
        let ad = abs(den);
        let e_den = splat(ray.e_den);
        let p_1 = sum4::<N>(std::array::from_fn(|i| abs(p[i])));
        let e_num = _mm256_mul_pd(splat(ROUNDING), p_1);
        let lo = _mm256_sub_pd(ad, e_den);
        let hi = _mm256_add_pd(ad, e_den);
        let sure_sign = _mm256_cmp_pd::<_CMP_GT_OQ>(lo, _mm256_setzero_pd());
        let g = _mm256_mul_pd(
            splat(2.0),
            _mm256_add_pd(e_num, _mm256_mul_pd(abs(t), e_den)),
        );
        let (tmin, tmax, par2) = (splat(tmin), splat(tmax), splat(ray.par2));
        let far = _mm256_and_pd(
            sure_sign,
            _mm256_or_pd(
                _mm256_cmp_pd::<_CMP_GE_OQ>(_mm256_mul_pd(_mm256_sub_pd(tmin, t), lo), g),
                _mm256_cmp_pd::<_CMP_GE_OQ>(_mm256_mul_pd(_mm256_sub_pd(t, tmax), lo), g),
            ),
        );
        let parallel = _mm256_cmp_pd::<_CMP_NGT_UQ>(_mm256_mul_pd(hi, hi), par2);
        let crossing = _mm256_and_pd(
            sure_sign,
            _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_mul_pd(lo, lo), par2),
        );
        _mm256_storeu_pd(out.t.as_mut_ptr(), t);
        _mm256_storeu_pd(out.den.as_mut_ptr(), den);
        let used = self.used();
        if _mm256_movemask_pd(_mm256_or_pd(parallel, far)) as u32 & used == used {
            return out;
        }
        let w: [__m256d; N] = std::array::from_fn(|i| {
            _mm256_sub_pd(_mm256_mul_pd(num, d[i]), _mm256_mul_pd(den, p[i]))
        });
        let w_1 = sum4::<N>(std::array::from_fn(|i| abs(w[i])));
        let c = _mm256_add_pd(
            _mm256_mul_pd(
                w_1,
                _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(splat(ROUNDING), lo), e_den),
                    splat(ray.rd_max),
                ),
            ),
            _mm256_mul_pd(
                _mm256_mul_pd(
                    splat(F64_ROUNDING),
                    _mm256_add_pd(
                        _mm256_mul_pd(abs(num), splat(ray.d_max)),
                        _mm256_mul_pd(ad, p_1),
                    ),
                ),
                lo,
            ),
        );
        let thr_in = _mm256_mul_pd(_mm256_mul_pd(splat(-BARY_SLACK), lo), lo);
        let thr_out = _mm256_mul_pd(_mm256_mul_pd(splat(-BARY_SLACK), hi), lo);
        let flip = _mm256_and_pd(sign, den);
        let mut inside = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
        let mut outside = _mm256_setzero_pd();
        let (mut sum, mut r_sum) = (_mm256_setzero_pd(), _mm256_setzero_pd());
        for k in 1..N {
            let r: [__m256d; N] = std::array::from_fn(|i| row(&self.m[k][i]));
            let u = sum4::<N>(std::array::from_fn(|i| _mm256_mul_pd(r[i], w[i])));
            _mm256_storeu_pd(out.u[k].as_mut_ptr(), u);
            // u_k·sign(n̂·d), exactly (a sign flip).
            let v = _mm256_xor_pd(u, flip);
            let r_1 = sum4::<N>(std::array::from_fn(|i| abs(r[i])));
            let (vl, el) = (_mm256_mul_pd(v, lo), _mm256_mul_pd(r_1, c));
            inside = _mm256_and_pd(
                inside,
                _mm256_cmp_pd::<_CMP_GE_OQ>(_mm256_sub_pd(vl, el), thr_in),
            );
            outside = _mm256_or_pd(
                outside,
                _mm256_cmp_pd::<_CMP_LT_OQ>(_mm256_add_pd(vl, el), thr_out),
            );
            sum = _mm256_add_pd(sum, v);
            r_sum = _mm256_add_pd(r_sum, r_1);
        }
        let v0 = _mm256_mul_pd(_mm256_sub_pd(ad, sum), lo);
        let e0 = _mm256_add_pd(_mm256_mul_pd(r_sum, c), _mm256_mul_pd(e_den, lo));
        inside = _mm256_and_pd(
            inside,
            _mm256_cmp_pd::<_CMP_GE_OQ>(_mm256_sub_pd(v0, e0), thr_in),
        );
        outside = _mm256_or_pd(
            outside,
            _mm256_cmp_pd::<_CMP_LT_OQ>(_mm256_add_pd(v0, e0), thr_out),
        );
        let decided = _mm256_and_pd(crossing, inside);
        let in_range = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_GT_OQ>(t, tmin),
            _mm256_cmp_pd::<_CMP_LT_OQ>(t, tmax),
        );
        let hit = _mm256_and_pd(decided, in_range);
        let miss = _mm256_or_pd(
            _mm256_or_pd(parallel, far),
            _mm256_or_pd(
                _mm256_and_pd(sure_sign, outside),
                _mm256_andnot_pd(in_range, decided),
            ),
        );
        let (hit, miss) = (
            _mm256_movemask_pd(hit) as u32,
            _mm256_movemask_pd(miss) as u32,
        );
        out.mask = hit & used;
        out.unsure = !(hit | miss) & used;
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
        let pre = packet.pre();
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
                slab_planes(&pre[0], &bn, &bf, &mut dn, &mut df);
                while left != 0 {
                    let q = left.trailing_zeros() as usize;
                    left &= left - 1;
                    slab_ray(&pre[q], q, &dn, &df, lo, limit[q], &mut met, &mut tn);
                }
            } else {
                while left != 0 {
                    let q = left.trailing_zeros() as usize;
                    left &= left - 1;
                    slab_planes(&pre[q], &bn, &bf, &mut dn, &mut df);
                    slab_ray(&pre[q], q, &dn, &df, lo, limit[q], &mut met, &mut tn);
                }
            }
        } else {
            while left != 0 {
                let q = left.trailing_zeros() as usize;
                left &= left - 1;
                let side = &pre[q].near;
                for i in 0..N {
                    bn[i] = _mm256_loadu_ps(node.bounds[side[i] & 1][i].as_ptr());
                    bf[i] = _mm256_loadu_ps(node.bounds[(side[i] & 1) ^ 1][i].as_ptr());
                }
                slab_planes(&pre[q], &bn, &bf, &mut dn, &mut df);
                slab_ray(&pre[q], q, &dn, &df, lo, limit[q], &mut met, &mut tn);
            }
        }
        let mut out = [0.0f32; NODE_WIDTH];
        _mm256_storeu_ps(out.as_mut_ptr(), tn);
        (met, out)
    }
}

/// The frustum test of a coherent packet against the children of `node` in AVX2 registers:
/// [`Frustum::slabs_portable`] with the 8 children in the lanes (the same operations: min/max
/// pick as the portable comparisons do, and no NaN occurs). Always inlined, as
/// [`slabs_avx2`].
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
pub(in crate::accel) unsafe fn frustum_slabs_avx2<const N: usize>(
    f: &Frustum<N>,
    node: &WideNode<N>,
    lo: f32,
    hi: f32,
) -> (u32, [f32; NODE_WIDTH]) {
    // SAFETY (all the intrinsics below): the caller guarantees AVX2; every pointer loaded or
    // stored is a `[f32; NODE_WIDTH]` (unaligned accesses).
    unsafe {
        let mut near = _mm256_set1_ps(lo);
        let mut far = _mm256_set1_ps(hi);
        for i in 0..N {
            let s = f.near[i] & 1;
            let x = _mm256_sub_ps(
                _mm256_loadu_ps(node.bounds[s][i].as_ptr()),
                _mm256_set1_ps(f.o_near[i]),
            );
            let y = _mm256_sub_ps(
                _mm256_loadu_ps(node.bounds[s ^ 1][i].as_ptr()),
                _mm256_set1_ps(f.o_far[i]),
            );
            let (i0, i1) = (_mm256_set1_ps(f.inv_min[i]), _mm256_set1_ps(f.inv_max[i]));
            // minps/maxps return their second operand unless the first is smaller/larger: the
            // portable comparisons' picks.
            let a = _mm256_min_ps(_mm256_mul_ps(x, i0), _mm256_mul_ps(x, i1));
            let c = _mm256_max_ps(_mm256_mul_ps(y, i0), _mm256_mul_ps(y, i1));
            near = _mm256_max_ps(a, near);
            far = _mm256_min_ps(c, far);
        }
        let met = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
        let t = _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), near, met);
        let mut out = [0.0f32; NODE_WIDTH];
        _mm256_storeu_ps(out.as_mut_ptr(), t);
        (_mm256_movemask_ps(met) as u32, out)
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
