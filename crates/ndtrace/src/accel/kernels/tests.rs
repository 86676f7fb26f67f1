//! The kernels against each other: every x86_64 kernel (SSE2 and, where the CPU has it, AVX2)
//! gives the bits of its portable twin, which is compiled and tested on x86_64 too, on random
//! inputs in every dimension and on the edge cases (infinite bounds and parameter ranges, zero
//! direction components, origins on slab planes, rays parallel to a simplex, empty and leaf
//! slots, partly filled blocks).

use super::*;
use crate::accel::kernels::frustum_slabs;
use crate::accel::kernels::portable;
#[cfg(target_arch = "x86_64")]
use crate::accel::kernels::x86_64::{leaf_slots_avx2, slabs_avx2, within8};
use crate::accel::packet::Frustum;
use crate::accel::tests::*;

#[test]
fn leaf_slots_agree_with_the_portable_version() {
    let mut r = rng(17);
    for _ in 0..200 {
        let child: [u32; NODE_WIDTH] = std::array::from_fn(|_| match r.random_range(0..3) {
            0 => EMPTY_SLOT,
            1 => LEAF_TAG | r.random_range(0..1000u32),
            _ => r.random_range(0..1000u32),
        });
        let (leafy, empty) = leaf_slots::<false>(&child);
        for (l, &c) in child.iter().enumerate() {
            assert_eq!(leafy >> l & 1 == 1, c == EMPTY_SLOT || c & LEAF_TAG != 0);
            assert_eq!(empty >> l & 1 == 1, c == EMPTY_SLOT);
        }
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            assert_eq!(leaf_slots::<true>(&child), (leafy, empty));
        }
    }
}

#[test]
fn accel_slab_test_treats_boxes_as_closed() {
    let mut node = WideNode::<3>::EMPTY;
    for i in 0..3 {
        node.bounds[0][i][0] = 0.0;
        node.bounds[1][i][0] = 1.0;
    }
    let hit = |origin: [f64; 3], dir: [f64; 3]| {
        let pre = TraversalRay::new(&Ray { origin, dir }, 1.0);
        let (mask, tn) = pre.slab(&node, 0.0, f32::INFINITY);
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 is available.
            // Planes picked per ray and once per packet, origin differences per ray and
            // once per packet.
            for (octant, shared_origin) in [
                (None, false),
                (Some(pre.near), false),
                (Some(pre.near), true),
            ] {
                let packet = Packet::<3, 1>::of_prepared([pre], octant, shared_origin);
                let (m2, t2) = unsafe { slabs_avx2(&packet, &node, 1, 0.0, &[f32::INFINITY]) };
                assert_eq!(
                    (mask as u64, tn.map(f32::to_bits)),
                    (m2, t2.map(f32::to_bits))
                );
            }
        }
        mask
    };
    // Along a face, along an edge, from a face plane with zero components of both signs.
    assert_eq!(hit([-1.0, 0.0, 0.5], [1.0, 0.0, 0.0]), 1);
    assert_eq!(hit([-1.0, 1.0, 1.0], [1.0, 0.0, -0.0]), 1);
    assert_eq!(hit([0.5, 1.0, 0.5], [0.0, -0.0, 0.0]), 1);
    // Exactly at a corner, from outside.
    assert_eq!(hit([-1.0, -2.0, -3.0], [1.0, 2.0, 3.0]), 1);
    assert_eq!(
        hit([1.0 + 1.0 / 3.0, 2.0, 3.0], [-1.0 / 3.0, -1.0, -2.0]),
        1
    );
    // Misses, and the empty slots never hit.
    assert_eq!(hit([-1.0, 1.5, 0.5], [1.0, 0.0, 0.0]), 0);
    assert_eq!(hit([-1.0, 0.5, 0.5], [-1.0, 0.0, 0.0]), 0);
    assert_eq!(hit([0.5, 0.5, 0.5], [0.0, 0.0, 0.0]), 1);
}

/// Every SIMD block kernel gives, lane by lane, the bits of `PreparedSimplex::intersect`.
/// `count` random simplices near one point (their points, prepared, and the tree of the one
/// block they fill), or `None` when one is degenerate.
type RandomBlock<const N: usize> = (Vec<[[f64; N]; N]>, Vec<PreparedSimplex<N>>, Bvh<N>);
fn random_block<const N: usize>(r: &mut TestRng, count: usize) -> Option<RandomBlock<N>> {
    let c = random_vector::<N>(r, 1.0);
    let pts: Vec<[[f64; N]; N]> = (0..count).map(|_| random_simplex(r, &c, 1.0)).collect();
    let prims: Vec<PreparedSimplex<N>> = pts.iter().filter_map(PreparedSimplex::new).collect();
    if prims.len() != count {
        return None;
    }
    let ids: Vec<u32> = (0..count as u32).collect();
    let bounds = pts.iter().map(|p| simplex_bounds(p)).collect();
    let bvh = Bvh::build(prims.clone(), ids, bounds);
    Some((pts, prims, bvh))
}

fn block_kernels_agree<const N: usize>() {
    let mut r = rng(5000 + N as u64);
    for case in 0..400 {
        let count = 1 + case % BLOCK_WIDTH;
        let Some((pts, prims, bvh)) = random_block::<N>(&mut r, count) else {
            continue;
        };
        assert_eq!(bvh.blocks.len(), 1);
        let block = &bvh.blocks[0];
        for _ in 0..20 {
            let origin = random_vector::<N>(&mut r, 3.0);
            let (pts_l, _) = (&pts[r.random_range(0..count)], 0);
            let dir = crate::linalg::sub(&plane_point(&mut r, pts_l, -0.2, 1.0), &origin);
            let ray = Ray { origin, dir };
            let local = PreparedRay::new(&ray);
            let mut kernels = vec![
                block.hit(&local, 0.0, f64::INFINITY),
                block.hit_portable(&local, 0.0, f64::INFINITY),
            ];
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx2") {
                // SAFETY: AVX2 is available.
                kernels.push(unsafe { block.hit_avx2(&local, 0.0, f64::INFINITY) });
            }
            for hits in kernels {
                for l in 0..count {
                    let id = block.ids[l] as usize;
                    let want = prims[id].intersect_stored(&ray, 0.0, f64::INFINITY);
                    let got = if hits.unsure >> l & 1 == 1 {
                        prims[id].intersect(&ray, 0.0, f64::INFINITY)
                    } else {
                        (hits.mask >> l & 1 == 1).then(|| (hits.t[l], hits.bary(l)))
                    };
                    let bits = |h: Option<(f64, [f64; N])>| {
                        h.map(|(t, b)| (t.to_bits(), b.map(f64::to_bits)))
                    };
                    assert_eq!(bits(got), bits(want), "N={N} lane {l}");
                }
                assert_eq!(hits.mask >> count, 0);
            }
        }
    }
}

#[test]
fn accel_simd_block_kernels_match_the_scalar_test_bit_for_bit() {
    for_each_dim!(block_kernels_agree);
}

/// Whether the AVX2 kernels can be run here.
fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    let available = std::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    let available = false;
    available
}

/// A box coordinate or origin: half the time from a small grid (so that origins and planes
/// coincide), else uniform.
fn coordinate(r: &mut TestRng) -> f32 {
    const GRID: [f32; 7] = [-2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0];
    if r.random_bool(0.5) {
        GRID[r.random_range(0..GRID.len())]
    } else {
        r.random_range(-3.0..3.0)
    }
}

/// A node whose slots hold, at random, nothing (an empty box), a box, a box flat along some
/// axes, a box unbounded along some axes, or a box around most origins (so that boxes are met
/// in every dimension).
fn random_node<const N: usize>(r: &mut TestRng) -> WideNode<N> {
    let mut node = WideNode::<N>::EMPTY;
    for l in 0..NODE_WIDTH {
        let kind = r.random_range(0..5);
        if kind == 0 {
            continue;
        }
        for i in 0..N {
            let (a, b) = if kind == 4 {
                (r.random_range(-3.5..-2.0), r.random_range(2.0..3.5))
            } else {
                (coordinate(r), coordinate(r))
            };
            let (mut lo, mut hi) = (a.min(b), a.max(b));
            if kind == 2 && r.random_bool(0.4) {
                hi = lo;
            }
            if kind == 3 && r.random_bool(0.4) {
                if r.random_bool(0.5) {
                    lo = f32::NEG_INFINITY;
                } else {
                    hi = f32::INFINITY;
                }
            }
            node.bounds[0][i][l] = lo;
            node.bounds[1][i][l] = hi;
        }
        node.child[l] = l as u32;
    }
    node
}

/// A direction whose components are, at random, zero of either sign (the ray is parallel to
/// those slabs: 1/d = ±∞), tiny, or uniform.
fn random_dir<const N: usize>(r: &mut TestRng) -> Vector<N> {
    std::array::from_fn(|_| match r.random_range(0..6) {
        0 => 0.0,
        1 => -0.0,
        2 => r.random_range(-1.0..1.0) * 1e-30,
        _ => r.random_range(-1.0..1.0),
    })
}

/// Entry parameters agree bit for bit, except that a zero may carry either sign: max and min of
/// +0 and −0 return the operand in a fixed position, and the SSE kernel reduces the axes
/// pairwise where the others go in axis order. The traversal only compares entry parameters,
/// and +0 == −0.
fn same_entry(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a == 0.0 && b == 0.0)
}

/// The slab tests: SSE (one ray) and AVX2 (a packet, with the planes picked per ray, once per
/// packet, and the origin differences once per packet) against the portable one, ray by ray.
fn slab_kernels_agree<const N: usize>() {
    let mut r = rng(6000 + N as u64);
    // Boxes met and missed; AVX2 runs per mode (planes per ray, per packet, and one origin).
    let (mut met, mut missed, mut modes) = (0, 0, [0; 3]);
    for case in 0..3000 {
        let node = random_node::<N>(&mut r);
        let lo = [0.0, -0.0, f32::NEG_INFINITY, -1.5, 0.7][r.random_range(0..5)];
        // Kind 0: rays in any directions; 1: the same direction signs; 2: and one origin.
        let kind = case % 3;
        let count = r.random_range(1..=PACKET);
        let origin: Vector<N> = std::array::from_fn(|_| coordinate(&mut r) as f64);
        let dir0 = random_dir::<N>(&mut r);
        // Axes along which every ray's shifted origins lie on one (often grid) plane.
        let planes: Vec<Option<f32>> = (0..N)
            .map(|_| r.random_bool(0.25).then(|| coordinate(&mut r)))
            .collect();
        let rays: Vec<TraversalRay<N>> = (0..count)
            .map(|_| {
                let o = if kind == 2 {
                    origin
                } else {
                    std::array::from_fn(|_| coordinate(&mut r) as f64)
                };
                let d = if kind == 0 {
                    random_dir(&mut r)
                } else {
                    // Same signs as dir0, zeros included (their sign too).
                    std::array::from_fn(|i| dir0[i] * r.random_range(0.1..2.0))
                };
                let mut pre = TraversalRay::new(&Ray { origin: o, dir: d }, 3.0);
                for (i, p) in planes.iter().enumerate() {
                    if let Some(p) = *p {
                        (pre.o_near[i], pre.o_far[i]) = (p, p);
                    }
                }
                pre
            })
            .collect();
        let limit: [f32; PACKET] =
            std::array::from_fn(|_| [f32::INFINITY, 2.5, 0.3, 0.0, -1.0][r.random_range(0..5)]);
        let (mut want_met, mut want_tn) = (0u64, [f32::INFINITY; NODE_WIDTH]);
        for (q, pre) in rays.iter().enumerate() {
            let (mask, tn) = pre.slab_portable(&node, lo, limit[q]);
            for l in 0..NODE_WIDTH {
                let hit = mask >> l & 1 == 1;
                assert!(
                    !hit || node.child[l] != EMPTY_SLOT,
                    "N={N}: an empty slot met"
                );
                assert!(
                    hit || tn[l] == f32::INFINITY,
                    "N={N}: a box missed has an entry"
                );
                (met, missed) = (met + hit as usize, missed + !hit as usize);
            }
            #[cfg(target_arch = "x86_64")]
            {
                let (m2, t2) = pre.slab_sse(&node, lo, limit[q]);
                assert_eq!(m2, mask, "N={N} case {case}: SSE slab mask");
                for l in 0..NODE_WIDTH {
                    assert!(same_entry(t2[l], tn[l]), "N={N} case {case}: SSE entry");
                }
            }
            want_met |= u64::from(mask) << (8 * q);
            for l in 0..NODE_WIDTH {
                want_tn[l] = if tn[l] < want_tn[l] {
                    tn[l]
                } else {
                    want_tn[l]
                };
            }
        }
        if !avx2() {
            continue;
        }
        #[cfg(target_arch = "x86_64")]
        {
            let mut pre = [rays[0]; PACKET];
            pre[..count].copy_from_slice(&rays);
            let octant = rays.iter().all(|p| p.near == rays[0].near);
            let bits = |v: &[f32; N]| v.map(f32::to_bits);
            let shared = rays.iter().all(|p| {
                bits(&p.o_near) == bits(&rays[0].o_near) && bits(&p.o_far) == bits(&rays[0].o_far)
            });
            assert!(kind == 0 || octant, "N={N}: one octant");
            assert!(kind < 2 || shared, "N={N}: one origin");
            for (mode, ok) in [(0, true), (1, octant), (2, octant && shared)] {
                if !ok {
                    continue;
                }
                modes[mode] += 1;
                let packet = Packet::<N, PACKET>::of_prepared(
                    pre,
                    (mode > 0).then_some(rays[0].near),
                    mode == 2,
                );
                // SAFETY: AVX2 is available.
                let (m, t) = unsafe { slabs_avx2(&packet, &node, (1 << count) - 1, lo, &limit) };
                assert_eq!(m, want_met, "N={N} case {case}: AVX2 masks, mode {mode}");
                for l in 0..NODE_WIDTH {
                    assert!(
                        same_entry(t[l], want_tn[l]),
                        "N={N} case {case}: AVX2 entry"
                    );
                }
            }
        }
    }
    assert!(
        met > 2000 && missed > 2000,
        "N={N}: {met} boxes met, {missed} missed"
    );
    assert!(
        !avx2() || modes.iter().all(|&m| m > 500),
        "N={N}: AVX2 modes {modes:?}"
    );
}

#[test]
fn accel_slab_kernels_match_the_portable_one_bit_for_bit() {
    for_each_dim!(slab_kernels_agree);
}

/// The block tests: SSE2 and AVX2 against the portable one, for blocks of 1 to 4 simplices and
/// rays aimed at them, random, parallel to a simplex, with zero components or none at all,
/// over finite, half-infinite and infinite ranges.
fn block_kernels_agree_with_portable<const N: usize>() {
    let mut r = rng(6500 + N as u64);
    let (mut hit, mut missed, mut early) = (0, 0, 0);
    for case in 0..500 {
        let count = 1 + case % BLOCK_WIDTH;
        let Some((pts, _, bvh)) = random_block::<N>(&mut r, count) else {
            continue;
        };
        let block = &bvh.blocks[0];
        for k in 0..40 {
            let origin = random_vector::<N>(&mut r, 3.0);
            let pts_l = &pts[r.random_range(0..count)];
            let aim = crate::linalg::sub(&plane_point(&mut r, pts_l, -0.2, 1.0), &origin);
            let dir = match k % 6 {
                0 | 1 => aim,
                2 => random_vector::<N>(&mut r, 1.0),
                // Parallel to the simplex's hyperplane.
                3 => crate::linalg::sub(&pts_l[1], &pts_l[0]),
                4 => {
                    let mut d = aim;
                    d[r.random_range(0..N)] = [0.0, -0.0][r.random_range(0..2)];
                    d
                }
                _ => [0.0; N],
            };
            let (tmin, tmax) = [
                (0.0, f64::INFINITY),
                (f64::NEG_INFINITY, f64::INFINITY),
                (0.5, 1.5),
                (-1.0, 0.8),
                (f64::NEG_INFINITY, 0.0),
            ][r.random_range(0..5)];
            let ray = PreparedRay::new(&Ray { origin, dir });
            let want = block.hit_portable(&ray, tmin, tmax);
            assert_eq!(want.mask >> count, 0, "N={N}: an unused lane hit");
            hit += want.mask.count_ones();
            missed += count as u32 - want.mask.count_ones();
            #[allow(unused_mut)]
            let mut kernels: Vec<(&str, BlockHits<N>)> = vec![];
            #[cfg(target_arch = "x86_64")]
            if avx2() {
                // SAFETY: AVX2 is available.
                kernels.push(("AVX2", unsafe { block.hit_avx2(&ray, tmin, tmax) }));
            }
            for (name, got) in kernels {
                assert_eq!(got.mask, want.mask, "N={N} case {case}: {name} mask");
                assert_eq!(got.unsure, want.unsure, "N={N} case {case}: {name} unsure");
                for l in 0..count {
                    let tb = |h: &BlockHits<N>| (h.t[l].to_bits(), h.den[l].to_bits());
                    assert_eq!(tb(&got), tb(&want), "N={N} case {case}: {name} t, n·d");
                    if want.mask >> l & 1 == 1 {
                        for j in 1..N {
                            assert_eq!(got.u[j][l].to_bits(), want.u[j][l].to_bits(), "{name}");
                        }
                        assert_eq!(
                            got.bary(l).map(f64::to_bits),
                            want.bary(l).map(f64::to_bits)
                        );
                    }
                }
            }
            // The early return (no lane has t in range) is taken too.
            early += (0..count).all(|l| !(want.t[l] > tmin && want.t[l] < tmax)) as u32;
        }
    }
    assert!(
        hit > 500 && missed > 500 && early > 500,
        "N={N}: {hit} lanes hit, {missed} missed, {early} early returns"
    );
}

#[test]
fn accel_block_kernels_match_the_portable_one_bit_for_bit() {
    for_each_dim!(block_kernels_agree_with_portable);
}

/// The exact block kernels (a tree's exact rows, [`Bvh::keep_exact_rows`]): the AVX2 one gives
/// the portable one's bits, and both decide every lane as the exact test of its simplex does,
/// with its t and coordinates bit for bit, and leave no lane unsure.
fn exact_block_kernels_agree<const N: usize>() {
    let mut r = rng(7100 + N as u64);
    let (mut hit, mut missed) = (0, 0);
    for case in 0..400 {
        let count = 1 + case % BLOCK_WIDTH;
        let Some((pts, prims, mut bvh)) = random_block::<N>(&mut r, count) else {
            continue;
        };
        bvh.keep_exact_rows();
        let (block, rows) = (&bvh.blocks[0], &bvh.exact_rows[0]);
        for k in 0..30 {
            let origin = random_vector::<N>(&mut r, 3.0);
            let pts_l = &pts[r.random_range(0..count)];
            let aim = crate::linalg::sub(&plane_point(&mut r, pts_l, -0.2, 1.0), &origin);
            let dir = match k % 5 {
                0 | 1 => aim,
                2 => random_vector::<N>(&mut r, 1.0),
                // Parallel to the simplex's hyperplane, and no direction at all.
                3 => crate::linalg::sub(&pts_l[1], &pts_l[0]),
                _ => [0.0; N],
            };
            let (tmin, tmax) = [(0.0, f64::INFINITY), (f64::NEG_INFINITY, 0.0), (0.5, 1.5)][k % 3];
            let ray = Ray { origin, dir };
            let pre = PreparedRay::new(&ray);
            let want = block.hit_exact_portable(rows, &pre, tmin, tmax);
            assert_eq!(want.unsure, 0);
            for l in 0..count {
                let id = block.ids[l] as usize;
                let exact = prims[id].intersect(&ray, tmin, tmax);
                let got = (want.mask >> l & 1 == 1).then(|| (want.t[l], want.bary(l)));
                let bits =
                    |h: Option<(f64, [f64; N])>| h.map(|(t, b)| (t.to_bits(), b.map(f64::to_bits)));
                assert_eq!(bits(got), bits(exact), "N={N} case {case} lane {l}");
            }
            assert_eq!(want.mask >> count, 0, "N={N}: an unused lane hit");
            hit += want.mask.count_ones();
            missed += count as u32 - want.mask.count_ones();
            #[cfg(target_arch = "x86_64")]
            if avx2() {
                // SAFETY: AVX2 is available.
                let got = unsafe { block.hit_exact_avx2(rows, &pre, tmin, tmax) };
                assert_eq!((got.mask, got.unsure), (want.mask, 0), "N={N} case {case}");
                for l in 0..count {
                    let tb = |h: &BlockHits<N>| (h.t[l].to_bits(), h.den[l].to_bits());
                    assert_eq!(tb(&got), tb(&want), "N={N} case {case}: t, n·d");
                    if want.mask >> l & 1 == 1 {
                        for j in 1..N {
                            assert_eq!(got.u[j][l].to_bits(), want.u[j][l].to_bits());
                        }
                    }
                }
            }
        }
    }
    assert!(
        hit > 300 && missed > 300,
        "N={N}: {hit} lanes hit, {missed} missed"
    );
}

#[test]
fn accel_exact_block_kernels_match_the_exact_test_bit_for_bit() {
    for_each_dim!(exact_block_kernels_agree);
}

#[test]
fn accel_leaf_slot_and_within_kernels_match_the_portable_ones() {
    let mut r = rng(19);
    // Slots all empty, all leaves (the largest block index included), all inner nodes, mixed.
    let mut children = vec![
        [EMPTY_SLOT; NODE_WIDTH],
        [LEAF_TAG | (EMPTY_SLOT - 1 - LEAF_TAG); NODE_WIDTH],
        [0; NODE_WIDTH],
        std::array::from_fn(|l| [0, LEAF_TAG, EMPTY_SLOT, LEAF_TAG - 1][l % 4]),
    ];
    for _ in 0..500 {
        children.push(std::array::from_fn(|_| match r.random_range(0..3) {
            0 => EMPTY_SLOT,
            1 => LEAF_TAG | r.random_range(0..LEAF_TAG - 1),
            _ => r.random_range(0..LEAF_TAG),
        }));
    }
    for child in &children {
        let (leafy, empty) = portable::leaf_slots(child);
        for (l, &c) in child.iter().enumerate() {
            assert_eq!(leafy >> l & 1 == 1, c == EMPTY_SLOT || c & LEAF_TAG != 0);
            assert_eq!(empty >> l & 1 == 1, c == EMPTY_SLOT);
        }
        #[cfg(target_arch = "x86_64")]
        if avx2() {
            // SAFETY: AVX2 is available.
            assert_eq!(unsafe { leaf_slots_avx2(child) }, (leafy, empty));
        }
    }
    // Rays within reach: infinities, zeros of both signs, equal values.
    let special = [f32::NEG_INFINITY, -1.0, -0.0, 0.0, 0.5, 1.0, f32::INFINITY];
    let pick = |r: &mut TestRng| {
        if r.random_bool(0.6) {
            special[r.random_range(0..special.len())]
        } else {
            r.random_range(-2.0..2.0)
        }
    };
    for _ in 0..5000 {
        let t = pick(&mut r);
        let limit: [f32; PACKET] = std::array::from_fn(|_| pick(&mut r));
        let want = portable::within(t, &limit);
        for (q, &l) in limit.iter().enumerate() {
            assert_eq!(want >> q & 1 == 1, t <= l);
        }
        #[cfg(target_arch = "x86_64")]
        if avx2() {
            // SAFETY: AVX2 is available; `limit` holds 8 f32.
            assert_eq!(unsafe { within8(t, limit.as_ptr()) }, want);
        }
    }
}

/// The frustum of a coherent packet (`Frustum`) against the slab test of each of its rays: it
/// meets every child box a ray meets, with an entry no later than the ray's (in every dimension,
/// with tiny direction components, infinite and empty bounds, origins on slab planes); it
/// culls most children no ray meets; the AVX2 kernel gives the portable one's bits; and packets
/// without one origin, one octant, or with a zero, NaN or infinite component have no frustum.
fn frustum_is_conservative<const N: usize>() {
    let mut r = rng(6900 + N as u64);
    let (mut culled, mut met_by_none, mut refused) = (0, 0, 0);
    for case in 0..4000 {
        let node = random_node::<N>(&mut r);
        let lo = [0.0, -0.0, f32::NEG_INFINITY, -1.5, 0.7][r.random_range(0..5)];
        let limit: [f32; PACKET] =
            std::array::from_fn(|_| [f32::INFINITY, 2.5, 0.3, 0.0, -1.0][r.random_range(0..5)]);
        let count = r.random_range(1..=PACKET);
        let scale = [1.0, 3.0][r.random_range(0..2)];
        let origin: Vector<N> = std::array::from_fn(|_| coordinate(&mut r) as f64 * scale);
        // Nonzero components (a zero has no frustum), some tiny.
        let dir0: Vector<N> = std::array::from_fn(|_| {
            let d = r.random_range(0.05..1.0) * [1.0, -1.0][r.random_range(0..2)];
            if r.random_bool(0.1) {
                d * 1e-30
            } else {
                d
            }
        });
        let spread = [0.0, 1e-3, 0.05, 0.5][r.random_range(0..4)];
        let mut rays: Vec<Ray<N>> = (0..count)
            .map(|_| Ray {
                origin,
                dir: std::array::from_fn(|i| dir0[i] * (1.0 + spread * r.random_range(-0.9..1.0))),
            })
            .collect();
        let reach = 3.0 * scale;
        let f = Frustum::of(&rays, reach).expect("a coherent packet has a frustum");
        let hi = limit.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let (mask, tn) = f.slabs_portable(&node, lo, hi);
        #[cfg(target_arch = "x86_64")]
        if avx2() {
            let (m2, t2) = frustum_slabs::<N, true, PACKET>(&f, &node, lo, &limit);
            assert_eq!(
                (m2, t2.map(f32::to_bits)),
                (mask, tn.map(f32::to_bits)),
                "N={N} case {case}"
            );
        }
        assert_eq!(
            frustum_slabs::<N, false, PACKET>(&f, &node, lo, &limit),
            (mask, tn)
        );
        let mut met_any = 0;
        let (mut inv_min, mut inv_max) = ([f32::INFINITY; N], [f32::NEG_INFINITY; N]);
        for (q, ray) in rays.iter().enumerate() {
            let pre = TraversalRay::new(ray, reach);
            assert_eq!(
                (pre.near, pre.o_near, pre.o_far),
                (f.near, f.o_near, f.o_far)
            );
            for i in 0..N {
                (inv_min[i], inv_max[i]) = (inv_min[i].min(pre.inv[i]), inv_max[i].max(pre.inv[i]));
            }
            let (m, t) = pre.slab_portable(&node, lo, limit[q]);
            assert_eq!(
                m & !mask,
                0,
                "N={N} case {case}: a box a ray meets is culled"
            );
            for l in 0..NODE_WIDTH {
                assert!(
                    m >> l & 1 == 0 || tn[l] <= t[l],
                    "N={N} case {case}: a later entry"
                );
            }
            met_any |= m;
        }
        // The ends of the rays' own `1/d`, bit for bit.
        assert_eq!(
            (f.inv_min.map(f32::to_bits), f.inv_max.map(f32::to_bits)),
            (inv_min.map(f32::to_bits), inv_max.map(f32::to_bits)),
            "N={N} case {case}"
        );
        // Children no ray meets, and those of them the frustum culls.
        met_by_none += (!met_any & 0xff).count_ones() as usize;
        culled += (!mask & !met_any & 0xff).count_ones() as usize;
        // One ray from elsewhere, of another octant, or with a zero, NaN or infinite component:
        // no frustum.
        if count > 1 {
            let q = r.random_range(0..count);
            let i = r.random_range(0..N);
            match r.random_range(0..6) {
                0 => rays[q].origin[i] += 0.25,
                1 => rays[q].dir[i] = -rays[q].dir[i],
                2 => rays[q].dir[i] = [0.0, -0.0][r.random_range(0..2)],
                3 => rays[q].dir[i] = f64::NAN,
                4 => rays[q].dir[i] = 1e-300 * dir0[i].signum(),
                _ => rays[q].dir[i] = f64::INFINITY,
            }
            let same_signs =
                rays[q].dir.map(f64::is_sign_negative) == dir0.map(f64::is_sign_negative);
            let d = rays[q].dir[i];
            if rays[q].origin != origin || !same_signs || !(d as f32).is_normal() {
                refused += 1;
                assert!(Frustum::of(&rays, reach).is_none(), "N={N} case {case}");
            }
        }
    }
    assert!(
        culled * 10 > met_by_none * 7 && refused > 2000,
        "N={N}: {culled} children culled of {met_by_none} that no ray meets, {refused} refused"
    );
}

#[test]
fn accel_frustum_meets_every_box_its_rays_meet() {
    for_each_dim!(frustum_is_conservative);
}
