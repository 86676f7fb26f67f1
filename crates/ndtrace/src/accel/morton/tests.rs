use super::*;
use crate::accel::tests::*;

/// The soup's simplices with ids 0…, plus degenerate ones (a repeated vertex) and a run of
/// exact copies long enough to give more than 8 blocks with one Morton code.
fn morton_input<const N: usize>(r: &mut TestRng, count: usize) -> Vec<[[f64; N]; N]> {
    let mut pts: Vec<[[f64; N]; N]> = soup::<N>(r, count).into_iter().map(|(p, _)| p).collect();
    for j in 0..count / 40 {
        let mut p = pts[j * 13 % pts.len()];
        p[1] = p[0];
        pts.push(p);
    }
    let copy = pts[5];
    pts.extend(std::iter::repeat_n(copy, 9 * NODE_WIDTH * BLOCK_WIDTH));
    pts
}

/// The box of all vertices.
fn domain<const N: usize>(pts: &[[[f64; N]; N]]) -> Bounds<N> {
    let all: Vec<[f64; N]> = pts.iter().flatten().copied().collect();
    simplex_bounds(&all)
}

#[test]
fn accel_morton_build_matches_brute_force_in_every_dimension() {
    fn check<const N: usize>() {
        let mut r = rng(9100 + N as u64);
        let pts = morton_input::<N>(&mut r, 700);
        let bvh = morton_of(&pts);
        let prims: Vec<(PreparedSimplex<N>, u32)> = (0..pts.len())
            .filter_map(|i| Some((PreparedSimplex::new(&pts[i])?, i as u32)))
            .collect();
        assert_eq!(bvh.len(), prims.len(), "N={N}: degenerate ones left out");
        assert!(prims.len() < pts.len());
        // Every kept id lies in exactly one lane; all blocks but the last are full except
        // where degenerate simplices were dropped.
        let mut seen = HashSet::new();
        for b in &bvh.blocks {
            for &id in &b.ids[..b.count()] {
                assert!(seen.insert(id), "N={N}: id {id} twice");
            }
        }
        assert_eq!(seen.len(), prims.len());
        let full = bvh
            .blocks
            .iter()
            .filter(|b| b.count() == BLOCK_WIDTH)
            .count();
        assert!(full + pts.len().div_ceil(BLOCK_WIDTH) / 10 >= bvh.blocks.len());
        let sah = {
            let ids: Vec<u32> = prims.iter().map(|p| p.1).collect();
            let bounds = ids
                .iter()
                .map(|&i| simplex_bounds(&pts[i as usize]))
                .collect();
            Bvh::build(prims.iter().map(|p| p.0).collect(), ids, bounds)
        };
        let accept = |id: u32| id % 11 != 3;
        for q in 0..400 {
            let ray = if q % 2 == 0 {
                // Aimed at a simplex, often exactly at shared points of the copies.
                let target = &pts[r.random_range(0..pts.len())];
                let origin = random_vector::<N>(&mut r, 4.0);
                let aim = plane_point(&mut r, target, 0.0, 1.0);
                Ray {
                    origin,
                    dir: crate::linalg::sub(&aim, &origin),
                }
            } else {
                Ray {
                    origin: random_vector::<N>(&mut r, 3.0),
                    dir: random_vector::<N>(&mut r, 1.0),
                }
            };
            let want = brute(&prims, &ray, 1e-9, f64::INFINITY, accept);
            let got = bvh.closest_hit(&ray, 1e-9, f64::INFINITY, accept);
            assert_eq!(got, want, "N={N}: ray {q}");
            assert_eq!(got, sah.closest_hit(&ray, 1e-9, f64::INFINITY, accept));
            let any = bvh.any_hit(&ray, 1e-9, f64::INFINITY, accept, 0..0);
            assert_eq!(any, want.is_some(), "N={N}: any-hit of ray {q}");
            // Skipping a range of ids (a convex object's own simplices) leaves out exactly them.
            let skip = 100..400;
            let want = brute(&prims, &ray, 1e-9, f64::INFINITY, |id| {
                accept(id) && !skip.contains(&id)
            });
            assert_eq!(
                bvh.any_hit(&ray, 1e-9, f64::INFINITY, accept, skip),
                want.is_some()
            );
        }
    }
    for_each_dim!(check);
}

#[test]
fn accel_morton_build_is_deterministic_for_any_thread_count() {
    fn check<const N: usize>() {
        let mut r = rng(9200 + N as u64);
        let pts = morton_input::<N>(&mut r, 3000);
        let a = morton_of(&pts);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(|| morton_of(&pts));
        assert!(a == b, "N={N}: one-thread build differs");
        assert!(a.node_count() > 1 && a.depth() > 2);
    }
    for_each_dim!(check);
}

#[test]
fn accel_morton_build_of_nothing_and_of_degenerate_simplices_only() {
    let empty = Bvh::<4>::build_morton(0, ([0.0; 4], [0.0; 4]), |_| unreachable!());
    assert!(empty.is_empty() && empty.node_count() == 0);
    let flat = Bvh::<3>::build_morton(40, ([0.0; 3], [40.0, 0.0, 0.0]), |i| {
        [[i as f64, 0.0, 0.0]; 3]
    });
    assert!(flat.is_empty());
    let ray = Ray {
        origin: [0.0; 3],
        dir: [1.0, 0.0, 0.0],
    };
    assert!(flat
        .closest_hit(&ray, 0.0, f64::INFINITY, |_| true)
        .is_none());
    // One simplex: a root with one block.
    let one = Bvh::<3>::build_morton(1, ([0.0; 3], [1.0; 3]), |_| {
        [[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]
    });
    let ray = Ray {
        origin: [0.2, 0.2, 0.0],
        dir: [0.0, 0.0, 1.0],
    };
    assert_eq!(
        one.closest_hit(&ray, 0.0, f64::INFINITY, |_| true)
            .map(|h| h.prim),
        Some(0)
    );
}

#[test]
fn accel_morton_codes_interleave_the_quantised_coordinates_bit_by_bit() {
    fn check<const N: usize>() {
        let mut r = rng(9300 + N as u64);
        let bits = 64 / N;
        let top = ((1u128 << bits) - 1) as f64;
        for _ in 0..500 {
            let c = random_vector::<N>(&mut r, 1.0);
            let (lo, scale) = ([-1.0; N], [top / 2.0; N]);
            let q: [u64; N] = std::array::from_fn(|a| ((c[a] + 1.0) * top / 2.0) as u64);
            // Most significant first: bit j of axis a lands at j·N + (N − 1 − a).
            let mut want = 0u64;
            for j in (0..bits).rev() {
                for qa in &q {
                    want = (want << 1) | ((qa >> j) & 1);
                }
            }
            assert_eq!(
                super::super::morton::morton(&c, &lo, &scale, bits),
                want,
                "N={N}"
            );
        }
        // Outside the box: clamped to the nearest face.
        let far = [5.0; N];
        assert_eq!(
            super::super::morton::morton(&far, &[-1.0; N], &[top / 2.0; N], bits),
            u64::MAX >> (64 - bits * N)
        );
    }
    for_each_dim!(check);
}

#[test]
fn accel_morton_build_of_a_large_soup_groups_in_parallel_and_matches_brute_force() {
    // More than PAR_BLOCKS blocks: the top of the grouping runs in parallel.
    let mut r = rng(9400);
    let pts: Vec<[[f64; 4]; 4]> = soup::<4>(&mut r, 70_000)
        .into_iter()
        .map(|(p, _)| p)
        .collect();
    let bvh = morton_of(&pts);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    assert!(bvh == pool.install(|| morton_of(&pts)));
    let prims: Vec<(PreparedSimplex<4>, u32)> = (0..pts.len())
        .filter_map(|i| Some((PreparedSimplex::new(&pts[i])?, i as u32)))
        .collect();
    for q in 0..60 {
        let target = &pts[r.random_range(0..pts.len())];
        let origin = random_vector::<4>(&mut r, 4.0);
        let aim = plane_point(&mut r, target, 0.0, 1.0);
        let ray = Ray {
            origin,
            dir: crate::linalg::sub(&aim, &origin),
        };
        let want = brute(&prims, &ray, 0.0, f64::INFINITY, |_| true);
        assert_eq!(
            bvh.closest_hit(&ray, 0.0, f64::INFINITY, |_| true),
            want,
            "ray {q}"
        );
    }
}

#[test]
fn accel_morton_nodes_are_nearly_full_even_on_a_thin_slab() {
    // Small simplices filling a box that is thin along w (an elevation map's shape): the code's
    // w bits divide almost nothing, and a grouping by fixed bit levels left most nodes half
    // empty (4.2 children on average at 128³). 80 k simplices: more than PAR_BLOCKS blocks, so the parallel grouping is counted too.
    let mut r = rng(9500);
    let pts: Vec<[[f64; 4]; 4]> = (0..80_000)
        .map(|_| {
            let mut c = random_vector::<4>(&mut r, 1.0);
            c[3] *= 0.01;
            random_simplex(&mut r, &c, 0.03)
        })
        .collect();
    let bvh = morton_of(&pts);
    let blocks = bvh.blocks.len();
    let children: usize = (bvh.nodes.iter())
        .map(|n| n.child.iter().filter(|&&c| c != EMPTY_SLOT).count())
        .sum();
    assert_eq!(
        children,
        blocks + bvh.nodes.len() - 1,
        "every block and node but the root is a child once"
    );
    let mean = children as f64 / bvh.nodes.len() as f64;
    assert!(
        mean >= 6.0,
        "{mean:.2} children per node ({} nodes, {blocks} blocks)",
        bvh.nodes.len()
    );
}

/// The Morton build over `pts` (ids = indices).
fn morton_of<const N: usize>(pts: &[[[f64; N]; N]]) -> Bvh<N> {
    let owned = pts.to_vec();
    Bvh::build_morton(pts.len(), domain(pts), move |i| owned[i])
}
