//! Flat cells: a tree that holds the facets of N-cubes as cells gives the hits of the tree over
//! their simplices bit for bit, the walk finds the simplex hit, and pieces that are not flat
//! convex cells stay ordinary simplices.

use super::super::cell::{CellGeometry, Pick};
use super::super::FlatCell;
use super::*;
use crate::accel::tests::*;

/// The simplices of `cube_boundary(k)` mapped by `map`, and the facet (axis·2 + side) of each.
fn cube<const N: usize>(
    k: i64,
    map: &impl Fn(&[i64; N]) -> Vector<N>,
) -> (Vec<[Vector<N>; N]>, Vec<usize>) {
    let grid = cube_boundary::<N>(k);
    let facet = |s: &[[i64; N]; N]| {
        (0..N)
            .find_map(|a| {
                [0, k]
                    .iter()
                    .position(|&side| s.iter().all(|v| v[a] == side))
                    .map(|side| 2 * a + side)
            })
            .unwrap()
    };
    (
        grid.iter().map(|s| s.map(|v| map(&v))).collect(),
        grid.iter().map(facet).collect(),
    )
}

/// The tree over `simplices` (ids = `id_of(i)`), with the facets as cells when `cells`.
fn tree<const N: usize>(simplices: &[[Vector<N>; N]], facets: &[usize], cells: bool) -> Bvh<N> {
    let ids: Vec<u32> = (0..simplices.len() as u32).map(|i| 3 * i + 1).collect();
    let bounds = simplices.iter().map(|s| simplex_bounds(s)).collect();
    let owned = simplices.to_vec();
    let prepare = move |id: u32| PreparedSimplex::new(&owned[(id / 3) as usize]).unwrap();
    if !cells {
        return Bvh::build_lazily(ids, bounds, prepare);
    }
    let cells = (0..2 * N)
        .map(|f| {
            let members: Vec<u32> = (0..simplices.len() as u32)
                .filter(|&i| facets[i as usize] == f)
                .collect();
            let points = members.iter().map(|&i| simplices[i as usize]).collect();
            FlatCell { members, points }
        })
        .collect();
    Bvh::build_lazily_with_cells(ids, bounds, cells, prepare)
}

fn cells_hit_as_their_simplices<const N: usize>() {
    let mut r = rng(7100 + N as u64);
    let k = if N <= 4 {
        3
    } else if N <= 6 {
        2
    } else {
        1
    };
    for shape in 0..2 {
        let (m, shift) = random_affine::<N>(&mut r, shape);
        let map = |g: &[i64; N], den: f64| -> Vector<N> {
            let x: Vector<N> = std::array::from_fn(|i| 2.0 * g[i] as f64 / (den * k as f64) - 1.0);
            add(&mat_vec(&m, &x), &shift)
        };
        let (simplices, facets) = cube::<N>(k, &|g| map(g, 1.0));
        let plain = tree(&simplices, &facets, false);
        let celled = tree(&simplices, &facets, true);
        assert_eq!(celled.cell_count(), 2 * N, "N={N}: every facet is a cell");
        assert_eq!(
            (celled.len(), plain.len()),
            (simplices.len(), simplices.len())
        );
        // Targets: vertices, edge midpoints and other lattice points of the doubled grid
        // (ridges, diagonals), and random points of random simplices.
        let mut targets: Vec<Vector<N>> = Vec::new();
        let grid = cube_boundary::<N>(k);
        // Fewer rays in 7D and 8D, where the tree without cells tests thousands of simplices
        // per ray.
        for _ in 0..[150, 150, 150, 150, 150, 60, 25][N - 2] {
            let s = &grid[r.random_range(0..grid.len())];
            let (a, b) = (r.random_range(0..N), r.random_range(0..N));
            targets.push(map(&std::array::from_fn(|i| s[a][i] + s[b][i]), 2.0));
            let pts = &simplices[r.random_range(0..simplices.len())];
            targets.push(plane_point(&mut r, pts, 0.0, 1.0));
            targets.push(plane_point(&mut r, pts, -0.01, 1.0));
        }
        let mut rays = Vec::new();
        for target in &targets {
            // From outside, from the inside, and grazing along a facet.
            let out = add_scaled(target, 4.0, &random_unit::<N>(&mut r));
            rays.push(Ray {
                origin: out,
                dir: crate::linalg::sub(target, &out),
            });
            rays.push(Ray {
                origin: shift,
                dir: crate::linalg::sub(target, &shift),
            });
            let f = r.random_range(0..simplices.len());
            let n = PreparedSimplex::new(&simplices[f]).unwrap().normal();
            let along = crate::linalg::sub(&simplices[f][1], &simplices[f][0]);
            let tilt = [0.0, 1e-12, 1e-7, 1e-3][r.random_range(0..4)];
            let dir = add_scaled(&along, tilt, &n);
            rays.push(Ray {
                origin: add_scaled(target, -2.0, &dir),
                dir,
            });
        }
        let mut picks = [0usize; 3];
        for (case, ray) in rays.iter().enumerate() {
            let (tmin, tmax) = [(0.0, f64::INFINITY), (0.5, 1.5), (1e-9, 1.0)][case % 3];
            let filters: [&dyn Fn(u32) -> bool; 2] = [&|_| true, &|id| id % 7 != 0];
            let a = r.random_range(0..3 * simplices.len() as u32);
            let skip = [0..0, a..a + 200, 0..u32::MAX][case % 3].clone();
            for f in filters {
                let want = plain.closest_hit(ray, tmin, tmax, f);
                assert_eq!(
                    celled.closest_hit(ray, tmin, tmax, f),
                    want,
                    "N={N} shape {shape} case {case}"
                );
                let mut sse = [None];
                celled.closest_hits_impl::<false, 1>(
                    std::slice::from_ref(ray),
                    tmin,
                    tmax,
                    &f,
                    &mut sse,
                );
                assert_eq!(sse[0], want, "N={N} case {case}: SSE path");
                let any = plain.any_hit(ray, tmin, tmax, f, skip.clone());
                assert_eq!(
                    celled.any_hit(ray, tmin, tmax, f, skip.clone()),
                    any,
                    "N={N} case {case}: any"
                );
            }
            for cell in &celled.cells {
                picks[match celled.cell_pick(cell, &PreparedRay::new(ray)) {
                    Pick::Miss => 0,
                    Pick::Simplex(_) => 1,
                    Pick::All => 2,
                }] += 1;
            }
        }
        // Packets: every ray's result is the one it gets alone.
        let mut got = vec![None; rays.len()];
        celled.closest_hits(&rays, 0.0, f64::INFINITY, |_| true, &mut got);
        for (ray, g) in rays.iter().zip(&got) {
            assert_eq!(
                *g,
                plain.closest_hit(ray, 0.0, f64::INFINITY, |_| true),
                "N={N}: packets"
            );
        }
        // Every outcome of the walk is met (these rays aim at ridges and graze facets on
        // purpose, so many cells are tested whole; `walk_finds_the_simplex_hit` checks that
        // rays through the middle of a simplex are not).
        let [miss, block, all] = picks;
        assert!(block > 0 && miss > 0 && all > 0, "N={N}: {picks:?}");
        assert!(all < miss + block, "N={N}: {picks:?}");
    }
}

#[test]
fn accel_flat_cells_give_the_hits_of_their_simplices_bit_for_bit() {
    for_each_dim!(cells_hit_as_their_simplices);
}

fn walk_finds_the_simplex_hit<const N: usize>() {
    let mut r = rng(7200 + N as u64);
    let k = if N <= 5 { 2 } else { 1 };
    let q = random_rotation::<N>(&mut r);
    let map = |g: &[i64; N]| mat_vec(&q, &g.map(|x| x as f64 - 0.5 * k as f64));
    let (simplices, facets) = cube::<N>(k, &map);
    let celled = tree(&simplices, &facets, true);
    for _ in 0..300 {
        let s = r.random_range(0..simplices.len());
        // Well inside simplex s (every barycentric coordinate ≥ 0.05).
        let target = plane_point(&mut r, &simplices[s], 0.05, 1.0);
        let origin = add_scaled(&target, 3.0, &random_unit::<N>(&mut r));
        let ray = Ray {
            origin,
            dir: crate::linalg::sub(&target, &origin),
        };
        let cell = celled
            .cells
            .iter()
            .find(|c| {
                c.blocks().any(|b| {
                    let blk = &celled.blocks[b as usize];
                    blk.ids[..blk.count()].contains(&(3 * s as u32 + 1))
                })
            })
            .unwrap();
        match celled.cell_pick(cell, &PreparedRay::new(&ray)) {
            Pick::Simplex(j) => {
                let slot = cell.first_block as usize * BLOCK_WIDTH + j as usize;
                let id = celled.blocks[slot / BLOCK_WIDTH].ids[slot % BLOCK_WIDTH];
                assert_eq!(
                    id,
                    3 * s as u32 + 1,
                    "N={N}: the walk stopped in another simplex"
                );
            }
            other => panic!("N={N}: {other:?} for a ray through the middle of simplex {s}"),
        }
    }
}

#[test]
fn accel_the_walk_stops_in_the_block_of_the_simplex_hit() {
    for_each_dim!(walk_finds_the_simplex_hit);
}

/// The geometry of the cell of `points` (none of them degenerate).
fn geometry<const N: usize>(points: &[[Vector<N>; N]]) -> Option<CellGeometry<N>> {
    let prepared = points
        .iter()
        .map(|p| PreparedSimplex::new(p).unwrap())
        .collect();
    CellGeometry::new(points, prepared)
}

#[test]
fn accel_pieces_that_are_not_flat_convex_cells_stay_simplices() {
    // A square [0, 2]² of the plane z = 0 in R³, cut into 8 triangles; an L of 6 of them; the
    // square with one vertex lifted; the square with a triangle twice; two separate squares.
    let tri = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| -> [Vector<3>; 3] {
        [[a[0], a[1], 0.0], [b[0], b[1], 0.0], [c[0], c[1], 0.0]]
    };
    let mut square = Vec::new();
    for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        square.push(tri([x, y], [x + 1.0, y], [x + 1.0, y + 1.0]));
        square.push(tri([x, y], [x + 1.0, y + 1.0], [x, y + 1.0]));
    }
    assert!(geometry(&square).is_some());
    let l_shape = square[..6].to_vec();
    assert!(geometry(&l_shape).is_none(), "not convex");
    let mut lifted = square.clone();
    for s in &mut lifted {
        for v in s.iter_mut() {
            if v[0] == 1.0 && v[1] == 1.0 {
                v[2] = 1e-3;
            }
        }
    }
    assert!(geometry(&lifted).is_none(), "not flat");
    let mut twice = square.clone();
    twice.push(square[3]);
    assert!(geometry(&twice).is_none(), "a ridge of three simplices");
    let far = square.iter().map(|s| s.map(|v| [v[0] + 5.0, v[1], v[2]]));
    let two: Vec<_> = square.iter().copied().chain(far).collect();
    assert!(geometry(&two).is_none(), "not connected");
    // Triangle 7 folded over its neighbour 6 across their common edge (no ridge of three).
    let mut folded = square.clone();
    folded[7] = tri([1.0, 1.0], [2.0, 2.0], [1.5, 0.5]);
    assert!(geometry(&folded).is_none(), "overlapping simplices");
    // A floor of 2 × 20² triangles: walks could be long, the tree serves it better.
    let mut floor = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            let (x, y) = (i as f64, j as f64);
            floor.push(tri([x, y], [x + 1.0, y], [x + 1.0, y + 1.0]));
            floor.push(tri([x, y], [x + 1.0, y + 1.0], [x, y + 1.0]));
        }
    }
    assert!(geometry(&floor).is_none(), "too far to walk");
    assert!(geometry(&floor[..2 * 4]).is_some());
    // The build keeps them as simplices, with the same hits.
    let mut r = rng(7300);
    for piece in [l_shape, lifted, twice] {
        let ids: Vec<u32> = (0..piece.len() as u32).collect();
        let bounds = piece.iter().map(|s| simplex_bounds(s)).collect::<Vec<_>>();
        let owned = piece.clone();
        let prepare = move |id: u32| PreparedSimplex::new(&owned[id as usize]).unwrap();
        let cells = vec![FlatCell {
            members: ids.clone(),
            points: piece.clone(),
        }];
        let celled =
            Bvh::build_lazily_with_cells(ids.clone(), bounds.clone(), cells, prepare.clone());
        let plain = Bvh::build_lazily(ids, bounds, prepare.clone());
        assert_eq!(celled.cell_count(), 0);
        for _ in 0..200 {
            let origin = add(&random_vector::<3>(&mut r, 1.0), &[1.0, 1.0, 2.0]);
            let target = [r.random_range(-0.2..2.2), r.random_range(-0.2..2.2), 0.0];
            let ray = Ray {
                origin,
                dir: crate::linalg::sub(&target, &origin),
            };
            assert_eq!(
                celled.closest_hit(&ray, 0.0, f64::INFINITY, |_| true),
                plain.closest_hit(&ray, 0.0, f64::INFINITY, |_| true)
            );
        }
    }
}
