use super::*;
#[cfg(target_arch = "x86_64")]
use crate::accel::kernels::x86_64::slabs_avx2;

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
                let packet = Packet::<3, 1> {
                    pre: [pre],
                    octant,
                    shared_origin,
                };
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
fn block_kernels_agree<const N: usize>() {
    let mut r = rng(5000 + N as u64);
    for case in 0..400 {
        let count = 1 + case % BLOCK_WIDTH;
        let c = random_vector::<N>(&mut r, 1.0);
        let pts: Vec<[[f64; N]; N]> = (0..count)
            .map(|_| random_simplex(&mut r, &c, 1.0))
            .collect();
        let prims: Vec<PreparedSimplex<N>> = pts.iter().filter_map(PreparedSimplex::new).collect();
        if prims.len() != count {
            continue;
        }
        let ids: Vec<u32> = (0..count as u32).collect();
        let bounds = pts.iter().map(|p| simplex_bounds(p)).collect();
        let bvh = Bvh::build(prims.clone(), ids, bounds);
        assert_eq!(bvh.blocks.len(), 1);
        let block = &bvh.blocks[0];
        for _ in 0..20 {
            let origin = random_vector::<N>(&mut r, 3.0);
            let (pts_l, _) = (&pts[r.random_range(0..count)], 0);
            let dir = crate::linalg::sub(&plane_point(&mut r, pts_l, -0.2, 1.0), &origin);
            let ray = Ray { origin, dir };
            let local = PreparedRay::new(&ray);
            let mut kernels = vec![block.hit(&local, 0.0, f64::INFINITY)];
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx2") {
                // SAFETY: AVX2 is available.
                kernels.push(unsafe { block.hit_avx2(&local, 0.0, f64::INFINITY) });
            }
            for hits in kernels {
                for l in 0..count {
                    let id = block.ids[l] as usize;
                    let want = prims[id].intersect(&ray, 0.0, f64::INFINITY);
                    let got = (hits.mask >> l & 1 == 1).then(|| (hits.t[l], hits.bary(l)));
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
