use super::*;
use crate::accel::tests::*;

fn bvh_agrees_with_brute_force<const N: usize>() {
    let mut r = rng(2000 + N as u64);
    for (round, count) in [1usize, 3, 5, 17, 300].into_iter().enumerate() {
        let s = soup::<N>(&mut r, count);
        let prims = prepare(&s);
        let bvh = build_soup(&s, PAR_MIN);
        assert_eq!(bvh.len(), prims.len());
        assert!(bvh
            .blocks
            .iter()
            .all(|b| (1..=BLOCK_WIDTH as u32).contains(&(b.count() as u32))));
        let (mut hits, mut ties) = (0, 0);
        for case in 0..1500 {
            let origin = random_vector::<N>(&mut r, 3.5);
            let dir = if case % 2 == 0 {
                // Aim at a point of a random simplex, so that most rays hit something.
                let (pts, _) = &s[r.random_range(0..s.len())];
                crate::linalg::sub(&plane_point(&mut r, pts, 0.0, 1.0), &origin)
            } else {
                random_vector::<N>(&mut r, 1.0)
            };
            let ray = Ray { origin, dir };
            let (tmin, tmax) = match case % 5 {
                0 => (0.0, f64::INFINITY),
                1 => (0.3, 0.9),
                2 => (-1.0, 1.0),
                3 => (0.0, 1.0),
                _ => (0.5, f64::INFINITY),
            };
            let filters: [&dyn Fn(u32) -> bool; 3] =
                [&|_| true, &|id| id % 3 != 0, &|id| id & 0x1000 == 0];
            // Ids skipped by the any-hit queries: none, a random range, or all.
            let a = r.random_range(0..2200);
            let skip = [0..0, a..a + r.random_range(0..1100), 0..u32::MAX][case % 3].clone();
            for (fi, f) in filters.iter().enumerate() {
                let want = brute(&prims, &ray, tmin, tmax, f);
                let got = bvh.closest_hit(&ray, tmin, tmax, f);
                assert_eq!(got, want, "N={N} round {round} case {case} filter {fi}");
                let kept = |id| f(id) && !skip.contains(&id);
                let want_any = brute(&prims, &ray, tmin, tmax, kept).is_some();
                assert_eq!(
                    bvh.any_hit(&ray, tmin, tmax, f, skip.clone()),
                    want_any,
                    "N={N} any_hit, skipping {skip:?}"
                );
                // The portable/SSE path too (the public calls take AVX2 when available).
                let (mut sse, mut blocked) = ([None], [false]);
                let one = std::slice::from_ref(&ray);
                bvh.closest_hits_impl::<false, 1>(one, tmin, tmax, f, &mut sse);
                assert_eq!(
                    sse[0], want,
                    "N={N} round {round} case {case} filter {fi}: SSE path"
                );
                bvh.any_hits_impl::<false, 1>(one, tmin, &[tmax], f, &skip, &mut blocked);
                assert_eq!(blocked[0], want_any);
                if let Some(h) = want {
                    hits += 1;
                    let same_t = prims.iter().filter(|(p, id)| {
                        f(*id)
                            && p.intersect_stored(&ray, tmin, tmax)
                                .is_some_and(|(t, _)| t == h.t)
                    });
                    ties += (same_t.count() > 1) as usize;
                }
            }
        }
        if count == 300 {
            assert!(
                hits > 1000 && ties > 10,
                "N={N}: {hits} hits, {ties} exact ties"
            );
        }
    }
}

#[test]
fn accel_bvh_closest_and_any_hit_equal_brute_force() {
    for_each_dim!(bvh_agrees_with_brute_force);
}

/// A tree that keeps exact rows ([`Bvh::keep_exact_rows`]) finds the hits of the exact test of
/// every simplex, bit for bit, one ray at a time and in packets, on the AVX2 and the portable
/// paths; and its memory counts the rows.
fn exact_rows_agree_with_brute_force<const N: usize>() {
    let mut r = rng(2700 + N as u64);
    let s = soup::<N>(&mut r, 300);
    let prims = prepare(&s);
    let mut bvh = build_soup(&s, PAR_MIN);
    assert!(!bvh.has_exact_rows());
    let rounded_bytes = bvh.memory_bytes();
    bvh.keep_exact_rows();
    assert!(bvh.has_exact_rows());
    assert_eq!(bvh.exact_rows.len(), bvh.blocks.len());
    assert_eq!(bvh.memory_bytes() - rounded_bytes, bvh.exact_rows_bytes());
    assert_eq!(
        bvh.exact_rows_bytes(),
        bvh.blocks.len() * size_of::<[[[f64; BLOCK_WIDTH]; N]; N]>()
    );
    let (mut hits, mut differ) = (0, 0);
    for case in 0..300 {
        let count = 1 + case % 11;
        let rays = packet_rays(&mut r, &s, case % 4, count);
        let (tmin, tmax) = [(0.0, f64::INFINITY), (0.2, 1.0)][case % 2];
        let f = |id: u32| !id.is_multiple_of(5);
        let want: Vec<_> = rays
            .iter()
            .map(|ray| brute_exact(&prims, ray, tmin, tmax, f))
            .collect();
        for (ray, w) in rays.iter().zip(&want) {
            assert_eq!(bvh.closest_hit(ray, tmin, tmax, f), *w, "N={N} case {case}");
            let mut portable = [None];
            bvh.closest_hits_impl::<false, 1>(
                std::slice::from_ref(ray),
                tmin,
                tmax,
                &f,
                &mut portable,
            );
            assert_eq!(portable[0], *w, "N={N} case {case}: portable path");
            // The rounded rows' hits differ in the last bits of t (or not at all).
            let rounded = brute(&prims, ray, tmin, tmax, f);
            assert_eq!(rounded.map(|h| h.prim), w.map(|h| h.prim));
            differ += (rounded.map(|h| h.t) != w.map(|h| h.t)) as usize;
        }
        let mut got = vec![None; count];
        bvh.closest_hits(&rays, tmin, tmax, f, &mut got);
        assert_eq!(got, want, "N={N} case {case}: packets");
        hits += want.iter().filter(|h| h.is_some()).count();
        let tmaxes: Vec<f64> = (0..count).map(|_| r.random_range(0.1..2.0)).collect();
        let want: Vec<bool> = rays
            .iter()
            .zip(&tmaxes)
            .map(|(ray, &t)| brute_exact(&prims, ray, tmin, t, f).is_some())
            .collect();
        let mut got = vec![false; count];
        bvh.any_hits(&rays, tmin, &tmaxes, f, 0..0, &mut got);
        assert_eq!(got, want, "N={N} case {case}: any_hits");
        let mut portable = vec![false; count];
        bvh.any_hits_impl::<false, PACKET>(
            &rays[..count.min(PACKET)],
            tmin,
            &tmaxes[..count.min(PACKET)],
            &f,
            &(0..0),
            &mut portable[..count.min(PACKET)],
        );
        assert_eq!(
            portable[..count.min(PACKET)],
            want[..count.min(PACKET)],
            "N={N}: portable any_hits"
        );
    }
    assert!(hits > 40, "N={N}: only {hits} hits");
    assert!(
        differ > 0,
        "N={N}: the exact rows changed no t (the test tests nothing)"
    );
}

#[test]
fn accel_trees_with_exact_rows_equal_the_exact_brute_force() {
    for_each_dim!(exact_rows_agree_with_brute_force);
}

fn packets_agree_with_brute_force<const N: usize>() {
    let mut r = rng(2500 + N as u64);
    let s = soup::<N>(&mut r, 300);
    let prims = prepare(&s);
    let bvh = build_soup(&s, PAR_MIN);
    let mut hits = 0;
    // Packets of mixed octants, of one octant (slab planes picked once per node), and of one
    // octant and one origin (plane differences computed once per node).
    let mut octants = [0; 3];
    for case in 0..400 {
        let kind = case % 4;
        let count = 1 + case % 11;
        let rays = packet_rays(&mut r, &s, kind, count);
        for rs in rays.chunks(PACKET) {
            let mut slot = MaybeUninit::uninit();
            let packet = Packet::<N, PACKET>::init(&mut slot, rs, bvh.reach);
            let kind = match (packet.octant, packet.shared_origin) {
                (None, _) => 0,
                (Some(_), false) => 1,
                (Some(_), true) => 2,
            };
            octants[kind] += 1;
        }
        let (tmin, tmax) = [(0.0, f64::INFINITY), (0.2, 1.0)][case % 2];
        let tmaxes: Vec<f64> = (0..count).map(|_| r.random_range(0.1..2.0)).collect();
        let filters: [&dyn Fn(u32) -> bool; 2] = [&|_| true, &|id| id % 3 != 0];
        for f in filters {
            let want: Vec<_> = rays
                .iter()
                .map(|ray| brute(&prims, ray, tmin, tmax, f))
                .collect();
            // Stale results, which every element's write must replace.
            let stale = Some(Hit {
                t: -1.0,
                prim: u32::MAX,
                bary: [f64::NAN; N],
                normal: [0.0; N],
            });
            let mut got = vec![stale; count];
            bvh.closest_hits(&rays, tmin, tmax, f, &mut got);
            assert_eq!(got, want, "N={N} case {case}");
            let mut portable = vec![stale; count];
            for (rs, out) in rays.chunks(PACKET).zip(portable.chunks_mut(PACKET)) {
                bvh.closest_hits_impl::<false, PACKET>(rs, tmin, tmax, &f, out);
            }
            assert_eq!(portable, want, "N={N} case {case}: portable path");
            hits += want.iter().filter(|h| h.is_some()).count();

            let want: Vec<bool> = rays
                .iter()
                .zip(&tmaxes)
                .map(|(ray, &t)| brute(&prims, ray, tmin, t, f).is_some())
                .collect();
            let mut got = vec![false; count];
            bvh.any_hits(&rays, tmin, &tmaxes, f, 0..0, &mut got);
            assert_eq!(got, want, "N={N} case {case}: any_hits");
            let mut portable = vec![false; count];
            let chunks = rays.chunks(PACKET).zip(tmaxes.chunks(PACKET));
            for ((rs, ts), out) in chunks.zip(portable.chunks_mut(PACKET)) {
                bvh.any_hits_impl::<false, PACKET>(rs, tmin, ts, &f, &(0..0), out);
            }
            assert_eq!(portable, want, "N={N} case {case}: portable any_hits");
        }
    }
    assert!(hits > 250, "N={N}: only {hits} hits");
    assert!(
        octants.iter().all(|&c| c > 50),
        "N={N}: packets of mixed octants, one octant, one octant and origin: {octants:?}"
    );
}

#[test]
fn accel_packets_equal_brute_force_ray_by_ray() {
    for_each_dim!(packets_agree_with_brute_force);
}

/// A pinhole's rays in groups of four packets over a cluster of simplices, from outside its
/// box: packets whose frustum leaves the tree before its leaves are done without their rays'
/// own tests, those along the cluster's silhouette are traced, and every ray's closest hit is
/// brute force's, on the AVX2 and portable paths.
fn pinhole_groups_agree_with_brute_force<const N: usize>() {
    let mut r = rng(2700 + N as u64);
    let s = soup::<N>(&mut r, 200);
    let prims = prepare(&s);
    let bvh = build_soup(&s, PAR_MIN);
    let (mut hits, mut misses) = (0, 0);
    for case in 0..300 {
        let origin = scale(&random_unit::<N>(&mut r), 9.0);
        // Even cases: directions in a narrow cone around one through the centroid of one of
        // the cluster's simplices (hits in every dimension, though the cluster is sparse in 8);
        // odd cases: a wider cone toward a point near the cluster, often off it (misses even in
        // 2, where the cluster is dense). Four packets of one origin and one octant each.
        let (aim, spread) = if case % 2 == 0 {
            let (pts, _) = &s[r.random_range(0..s.len())];
            let centre = pts
                .iter()
                .fold([0.0; N], |c, p| add(&c, &scale(p, 1.0 / N as f64)));
            (add(&centre, &random_vector::<N>(&mut r, 0.05)), 0.05)
        } else {
            (random_vector::<N>(&mut r, 4.0), 0.3)
        };
        let axis = crate::linalg::sub(&aim, &origin);
        let rays: Vec<Ray<N>> = (0..4 * PACKET)
            .map(|_| Ray {
                origin,
                dir: add(&axis, &random_vector::<N>(&mut r, spread)),
            })
            .collect();
        let want: Vec<_> = rays
            .iter()
            .map(|ray| brute(&prims, ray, 0.0, f64::INFINITY, |_| true))
            .collect();
        let mut got = vec![None; rays.len()];
        bvh.closest_hits(&rays, 0.0, f64::INFINITY, |_| true, &mut got);
        assert_eq!(got, want, "N={N} case {case}");
        let mut portable = vec![None; rays.len()];
        for (rs, out) in rays.chunks(PACKET).zip(portable.chunks_mut(PACKET)) {
            bvh.closest_hits_impl::<false, PACKET>(rs, 0.0, f64::INFINITY, &|_| true, out);
        }
        assert_eq!(portable, want, "N={N} case {case}: portable path");
        let h = want.iter().filter(|h| h.is_some()).count();
        hits += h;
        misses += want.len() - h;
    }
    assert!(
        hits > 150 && misses > 150,
        "N={N}: {hits} hits, {misses} misses"
    );
}

#[test]
fn accel_pinhole_groups_equal_brute_force() {
    for_each_dim!(pinhole_groups_agree_with_brute_force);
}

/// Two clusters of simplices with ids 0..150 and 150..300: the id range of every child slot
/// is the min/max over its subtree, whole subtrees of one cluster can be skipped, and
/// any-hit queries that skip ids agree with brute force over the ids they keep.
fn skipping_ids_agrees_with_brute_force<const N: usize>() {
    let mut r = rng(2700 + N as u64);
    let mut s = vec![];
    for i in 0..300u32 {
        let mut c = random_vector::<N>(&mut r, 1.0);
        c[0] += if i < 150 { -2.0 } else { 2.0 };
        s.push((random_simplex(&mut r, &c, 0.4), i));
    }
    let prims = prepare(&s);
    let bvh = build_soup(&s, PAR_MIN);
    fn subtree<const N: usize>(bvh: &Bvh<N>, c: u32) -> (u32, u32) {
        if c == EMPTY_SLOT {
            return (u32::MAX, 0);
        }
        if c & LEAF_TAG != 0 {
            let b = &bvh.blocks[(c & !LEAF_TAG) as usize];
            let ids = &b.ids[..b.count()];
            return (*ids.iter().min().unwrap(), *ids.iter().max().unwrap());
        }
        bvh.nodes[c as usize]
            .child
            .iter()
            .map(|&k| subtree(bvh, k))
            .fold((u32::MAX, 0), |a, b| (a.0.min(b.0), a.1.max(b.1)))
    }
    let mut pure = 0;
    for (i, nd) in bvh.nodes.iter().enumerate() {
        for l in 0..NODE_WIDTH {
            let want = subtree(&bvh, nd.child[l]);
            assert_eq!((bvh.ranges[i][0][l], bvh.ranges[i][1][l]), want, "N={N}");
            pure += (nd.child[l] & LEAF_TAG == 0 && want.1 < 150) as usize;
        }
    }
    assert!(
        pure > 0,
        "N={N}: no inner subtree holds only the first cluster"
    );
    let mut blocked = [0; 3];
    // Nodes visited plus blocks tested, skipping the first cluster by id range (pruned)
    // and by filter (not pruned): the same answers, less work.
    let mut work = [0u64; 2];
    let visits = || stats::LOCAL.with(|c| c.get()[0] + c.get()[1]);
    for case in 0..200 {
        let rays = packet_rays(&mut r, &s, case % 3, 1 + case % PACKET);
        let tmax: Vec<f64> = rays.iter().map(|_| r.random_range(0.5..3.0)).collect();
        let ranges = [
            0..0,
            0..150,
            150..300,
            0..300,
            100..200,
            0..149,
            1..150,
            150..299,
        ];
        for (k, skip) in ranges.into_iter().enumerate() {
            let want: Vec<bool> = rays
                .iter()
                .zip(&tmax)
                .map(|(ray, &t)| brute(&prims, ray, 0.0, t, |id| !skip.contains(&id)).is_some())
                .collect();
            let mut got = vec![false; rays.len()];
            bvh.any_hits(&rays, 0.0, &tmax, |_| true, skip.clone(), &mut got);
            assert_eq!(got, want, "N={N} case {case}, skipping {skip:?}");
            for ((ray, &t), &w) in rays.iter().zip(&tmax).zip(&want) {
                assert_eq!(bvh.any_hit(ray, 0.0, t, |_| true, skip.clone()), w);
            }
            if k < 3 {
                blocked[k] += want.iter().filter(|&&b| b).count();
            }
            if skip == (0..150) {
                let mut filtered = vec![false; rays.len()];
                let before = visits();
                bvh.any_hits(&rays, 0.0, &tmax, |id| id >= 150, 0..0, &mut filtered);
                let between = visits();
                bvh.any_hits(&rays, 0.0, &tmax, |_| true, skip.clone(), &mut got);
                work[0] += visits() - between;
                work[1] += between - before;
                assert_eq!(filtered, want);
            }
        }
    }
    assert!(
        blocked.iter().all(|&b| b > 20),
        "N={N}: {blocked:?} rays blocked"
    );
    assert!(
        work[0] * 4 < work[1] * 3,
        "N={N}: {} nodes and blocks visited when skipping ids 0..150, {} when filtering them",
        work[0],
        work[1]
    );
}

#[test]
fn accel_any_hits_skipping_ids_equal_brute_force() {
    for_each_dim!(skipping_ids_agrees_with_brute_force);
}

#[test]
fn accel_transpose8_transposes_the_bit_matrix() {
    let mut r = rng(2700);
    for _ in 0..1000 {
        let x: u64 = r.random();
        let mut want = 0u64;
        for row in 0..8 {
            for col in 0..8 {
                want |= ((x >> (8 * row + col)) & 1) << (8 * col + row);
            }
        }
        assert_eq!(transpose8(x), want);
    }
}

#[test]
fn accel_spread_moves_bit_l_to_byte_l() {
    for m in 0..256u32 {
        let want = (0..8).fold(0u64, |w, l| w | u64::from(m >> l & 1) << (8 * l));
        assert_eq!(spread(m), want, "{m:#010b}");
    }
}

#[test]
fn accel_empty_bvh_misses() {
    let bvh = Bvh::<3>::build(vec![], vec![], vec![]);
    assert!(bvh.is_empty() && bvh.node_count() == 0 && bvh.depth() == 0);
    assert_eq!(bvh.len(), 0);
    let ray = Ray {
        origin: [0.0; 3],
        dir: [1.0, 0.0, 0.0],
    };
    assert_eq!(bvh.closest_hit(&ray, 0.0, f64::INFINITY, |_| true), None);
    assert!(!bvh.any_hit(&ray, 0.0, f64::INFINITY, |_| true, 0..0));
}

fn closed_mesh_is_watertight<const N: usize>() {
    let mut r = rng(3000 + N as u64);
    let k = if N <= 4 { 2 } else { 1 };
    let cells = cube_boundary::<N>(k);
    // Targets: every vertex and every edge midpoint of the mesh (on the integer grid ×2).
    let mut targets: HashSet<[i64; N]> = HashSet::new();
    for s in &cells {
        for a in 0..N {
            targets.insert(s[a].map(|x| 2 * x));
            for b in a + 1..N {
                targets.insert(std::array::from_fn(|i| s[a][i] + s[b][i]));
            }
        }
    }
    // Every vertex (all coordinates even) and up to 400 edge midpoints (in 8D a Kuhn
    // simplex's box is its whole facet, so each ray tests thousands of simplices).
    let mut targets: Vec<[i64; N]> = targets.into_iter().collect();
    targets.sort();
    let (mut targets, mut mids): (Vec<_>, Vec<_>) = targets
        .into_iter()
        .partition(|g| g.iter().all(|x| x % 2 == 0));
    for j in 0..mids.len().min(400) {
        let pick = r.random_range(j..mids.len());
        mids.swap(j, pick);
        targets.push(mids[j]);
    }
    for shape in 0..2 {
        // 0: the cube [−1, 1]^N itself (box faces on the mesh, zero direction components);
        // 1: a random affine image of it.
        let (m, shift) = random_affine::<N>(&mut r, shape);
        let map = |g: &[i64; N], den: f64| -> Vector<N> {
            let x: Vector<N> = std::array::from_fn(|i| 2.0 * g[i] as f64 / (den * k as f64) - 1.0);
            add(&mat_vec(&m, &x), &shift)
        };
        let simplices: Vec<[[f64; N]; N]> = cells.iter().map(|s| s.map(|v| map(&v, 1.0))).collect();
        let ids: Vec<u32> = (0..simplices.len() as u32).collect();
        let rounded = Bvh::from_simplices(&simplices, &ids);
        let mut exact = rounded.clone();
        exact.keep_exact_rows();
        for bvh in [&rounded, &exact] {
            assert_eq!(bvh.len(), simplices.len());
            let center = shift;
            for g in &targets {
                let target = map(g, 2.0);
                // From the inside: the one crossing is at the target, t = 1.
                let ray = Ray {
                    origin: center,
                    dir: crate::linalg::sub(&target, &center),
                };
                let h = bvh.closest_hit(&ray, 0.0, f64::INFINITY, |_| true);
                assert!(
                    // (t within the rounding of the blocks' f32 rows, ~10⁻⁷.)
                    h.is_some_and(|h| (h.t - 1.0).abs() < 1e-6),
                    "N={N} shape {shape}: from inside to {g:?}: {h:?}"
                );
                // From outside, along a random direction and (axis-aligned cube) along an axis:
                // the first crossing is at or before the target.
                let mut origins = vec![add_scaled(&target, 4.0, &random_unit::<N>(&mut r))];
                if shape == 0 {
                    let axis = r.random_range(0..N);
                    let mut o = target;
                    o[axis] += if target[axis] >= 0.0 { 3.0 } else { -3.0 };
                    origins.push(o);
                }
                for origin in origins {
                    let ray = Ray {
                        origin,
                        dir: crate::linalg::sub(&target, &origin),
                    };
                    let h = bvh.closest_hit(&ray, 0.0, f64::INFINITY, |_| true);
                    let ok = h.is_some_and(|h| h.t <= 1.0 + 1e-6);
                    assert!(
                        ok,
                        "N={N} shape {shape}: outside {origin:?} to {g:?}: {h:?}"
                    );
                    assert!(bvh.any_hit(&ray, 0.0, f64::INFINITY, |_| true, 0..0));
                }
            }
        }
    }
}

#[test]
fn accel_closed_meshes_are_watertight_at_vertices_and_edges() {
    for_each_dim!(closed_mesh_is_watertight);
}

/// The exact test of unsure lanes is rare: camera rays over a finely tessellated sphere (N = 3
/// and 4), every ray aimed somewhere on it, ask for fewer than one exact test in 10 000 rays,
/// and every hit they find is the closest one by brute force.
#[test]
fn accel_exact_tests_of_unsure_lanes_are_rare() {
    fn check<const N: usize>(subdivisions: u32) {
        let mesh = crate::shapes::sphere::<N>(subdivisions);
        let bvh = Bvh::from_mesh(&mesh);
        let prims = prepare(
            &(0..mesh.simplices.len())
                .map(|s| (mesh.simplex_points(s), s as u32))
                .collect::<Vec<_>>(),
        );
        let mut r = rng(8800 + N as u64);
        let eye = add_scaled(&[0.0; N], 3.0, &random_unit::<N>(&mut r));
        let rays: Vec<Ray<N>> = (0..20_000)
            .map(|_| {
                let target = scale(&random_unit::<N>(&mut r), 0.9);
                Ray {
                    origin: eye,
                    dir: crate::linalg::sub(&target, &eye),
                }
            })
            .collect();
        stats::LOCAL.with(|c| c.set([0; 4]));
        let hits: Vec<Option<Hit<N>>> = rays
            .iter()
            .map(|ray| bvh.closest_hit(ray, 0.0, f64::INFINITY, |_| true))
            .collect();
        let exact = stats::LOCAL.with(|c| c.get()[3]);
        assert!(
            exact * 10_000 < rays.len() as u64,
            "N={N}: {exact} exact tests for {} rays",
            rays.len()
        );
        for (ray, h) in rays.iter().zip(&hits).step_by(10) {
            assert!(h.is_some(), "N={N}: a ray aimed at the sphere missed");
            assert_eq!(*h, brute(&prims, ray, 0.0, f64::INFINITY, |_| true));
        }
    }
    check::<3>(5);
    check::<4>(3);
}
