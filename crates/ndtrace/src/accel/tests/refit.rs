//! Refitting: a tree refitted to moved simplices answers as a tree built over them, bit for
//! bit (SAH and Morton trees, flat cells included), and refuses simplices that became
//! degenerate or cells that are no longer flat.

use super::super::FlatCell;
use super::*;

fn refitted_trees_answer_as_built_ones<const N: usize>() {
    let mut r = rng(7400 + N as u64);
    // A soup, and the boundary of a cube whose facets are flat cells (N ≥ 3).
    let soup = soup::<N>(&mut r, 200);
    let k = if N <= 4 { 2 } else { 1 };
    let cube: Vec<[Vector<N>; N]> = cube_boundary::<N>(k)
        .iter()
        .map(|s| s.map(|v| v.map(|x| x as f64 / k as f64 - 0.5)))
        .collect();
    // Every simplex prepares (the soup's few degenerate ones are dropped).
    let mut points: Vec<[Vector<N>; N]> = (soup.iter().map(|(p, _)| *p))
        .filter(|p| PreparedSimplex::new(p).is_some())
        .collect();
    let first_cube = points.len();
    points.extend(cube.iter().copied());
    let ids: Vec<u32> = (0..points.len() as u32).map(|i| 2 * i + 5).collect();
    let index = |id: u32| ((id - 5) / 2) as usize;
    let cells = |pts: &[[Vector<N>; N]]| -> Vec<FlatCell<N>> {
        // The facets of the cube: the simplices whose vertices share a coordinate at ±0.5.
        (0..2 * N)
            .map(|f| {
                let (a, side) = (f / 2, if f % 2 == 0 { -0.5 } else { 0.5 });
                let members: Vec<u32> = (first_cube..pts.len())
                    .filter(|&i| cube[i - first_cube].iter().all(|v| v[a] == side))
                    .map(|i| i as u32)
                    .collect();
                let points = members.iter().map(|&i| pts[i as usize]).collect();
                FlatCell { members, points }
            })
            .collect()
    };
    let build = |pts: &[[Vector<N>; N]], morton: bool| {
        let bounds: Vec<_> = pts.iter().map(|p| simplex_bounds(p)).collect();
        let prepare = |id: u32| PreparedSimplex::new(&pts[index(id)]).unwrap();
        if morton {
            let domain = bounds.iter().fold(
                ([f64::INFINITY; N], [f64::NEG_INFINITY; N]),
                |(lo, hi), (a, b)| {
                    (
                        std::array::from_fn(|i| lo[i].min(a[i])),
                        std::array::from_fn(|i| hi[i].max(b[i])),
                    )
                },
            );
            Bvh::build_morton(pts.len(), domain, |g| pts[g])
        } else {
            Bvh::build_lazily_with_cells(ids.clone(), bounds, cells(pts), prepare)
        }
    };
    for morton in [false, true] {
        let tree = build(&points, morton);
        assert_eq!(tree.cell_count(), if morton { 0 } else { 2 * N });
        // A rigid motion, then a general affine map.
        for shape in 0..2 {
            let q = random_rotation::<N>(&mut r);
            let m: Matrix<N> = if shape == 0 {
                q
            } else {
                let d: Vector<N> = std::array::from_fn(|_| r.random_range(0.5..2.0));
                std::array::from_fn(|i| std::array::from_fn(|j| q[i][j] * d[j]))
            };
            let shift = random_vector::<N>(&mut r, 2.0);
            let moved: Vec<[Vector<N>; N]> = points
                .iter()
                .map(|s| s.map(|v| add(&mat_vec(&m, &v), &shift)))
                .collect();
            let fresh = build(&moved, morton);
            // The Morton build's ids are the indices.
            let refit = tree
                .refit(|id| moved[if morton { id as usize } else { index(id) }])
                .expect("nothing degenerates");
            assert_eq!(refit.cell_count(), tree.cell_count());
            for case in 0..400 {
                let origin = add(&random_vector::<N>(&mut r, 4.0), &shift);
                let target = if case % 2 == 0 {
                    let s = moved[r.random_range(0..moved.len())];
                    plane_point(&mut r, &s, 0.0, 1.0)
                } else {
                    add(&random_vector::<N>(&mut r, 1.0), &shift)
                };
                let ray = Ray {
                    origin,
                    dir: crate::linalg::sub(&target, &origin),
                };
                let (tmin, tmax) = [(0.0, f64::INFINITY), (0.2, 1.0)][case % 2];
                assert_eq!(
                    refit.closest_hit(&ray, tmin, tmax, |_| true),
                    fresh.closest_hit(&ray, tmin, tmax, |_| true),
                    "N={N} morton {morton} shape {shape} case {case}"
                );
                assert_eq!(
                    refit.any_hit(&ray, tmin, tmax, |id| id % 3 != 0, 0..0),
                    fresh.any_hit(&ray, tmin, tmax, |id| id % 3 != 0, 0..0)
                );
            }
        }
        // A simplex squashed flat: refused.
        let squashed = |id: u32| {
            let i = if morton { id as usize } else { index(id) };
            let mut s = points[i];
            if i == 0 {
                s[1] = s[0];
            }
            s
        };
        assert!(
            tree.refit(squashed).is_none(),
            "N={N}: a degenerate simplex"
        );
        if !morton {
            // A facet bent out of its hyperplane: its cell refuses.
            let bent = |id: u32| {
                let i = index(id);
                let mut s = points[i];
                for v in s.iter_mut() {
                    if v.iter().all(|&x| x == 0.5) {
                        v[0] += 0.01;
                    }
                }
                s
            };
            assert!(tree.refit(bent).is_none(), "N={N}: a cell that is not flat");
        }
    }
}

#[test]
fn accel_refitted_trees_answer_as_trees_built_over_the_moved_simplices() {
    for_each_dim!(refitted_trees_answer_as_built_ones);
}
