use super::*;
use crate::geometry::simplex_normal;
use crate::linalg::{det, dot, sub, Matrix};
use crate::testutil::rng;
use rand::Rng;

fn random_field(r: &mut crate::testutil::TestRng, shape: [usize; 3]) -> Vec<f64> {
    (0..shape.iter().product::<usize>())
        .map(|_| r.random_range(-1.0..1.0))
        .collect()
}

/// The 3D determinant of a tetrahedron's projection to xyz (6 × its signed volume).
fn det3(m: &Mesh<4>, s: usize) -> f64 {
    let p = m.simplex_points(s);
    let mut a: Matrix<3> = [[0.0; 3]; 3];
    for k in 0..3 {
        for j in 0..3 {
            a[k][j] = p[k + 1][j] - p[0][j];
        }
    }
    det(&a)
}

#[test]
fn vertices_are_the_grid_and_w_is_exactly_height_times_f() {
    let mut r = rng(1);
    let shape = [3, 4, 5];
    let f = random_field(&mut r, shape);
    let e = elevation_map::<4>(&Field { values: &f, shape }, None, 0.7).unwrap();
    assert_eq!(e.mesh.vertices.len(), 60);
    assert_eq!(e.mesh.simplices.len(), 6 * 2 * 3 * 4);
    assert_eq!(e.holes, 0);
    // Default extent: cubic voxels, the longest side (z, 5 points) spans [−1, 1].
    assert_eq!(e.extent, [[-0.5, 0.5], [-0.75, 0.75], [-1.0, 1.0]]);
    for (g, v) in e.mesh.vertices.iter().enumerate() {
        let (x, y, z) = (g / 20, g / 5 % 4, g % 5);
        assert_eq!(v[3], 0.7 * f[g]);
        assert_eq!(e.values[g], f[g]);
        let expect = [
            -0.5 + 0.5 * x as f64,
            -0.75 + 0.5 * y as f64,
            -1.0 + 0.5 * z as f64,
        ];
        for k in 0..3 {
            assert!((v[k] - expect[k]).abs() < 1e-15, "{v:?} {expect:?}");
        }
    }
}

#[test]
fn tetrahedra_tile_the_box_and_face_up() {
    let mut r = rng(2);
    let shape = [4, 3, 5];
    let f = random_field(&mut r, shape);
    let extent = [[-1.0, 2.0], [0.5, 1.5], [-0.25, 0.75]];
    let e = elevation_map::<4>(&Field { values: &f, shape }, Some(&extent), 1.3).unwrap();
    let m = &e.mesh;
    // Positive 3D orientation; the volumes sum to the box's.
    let total: f64 = (0..m.simplices.len())
        .map(|s| {
            let d = det3(m, s);
            assert!(d > 0.0);
            d / 6.0
        })
        .sum();
    assert!((total - 3.0).abs() < 1e-12, "{total}");
    // No overlap: random points lie in exactly one tetrahedron's projection.
    for _ in 0..2000 {
        let q = [
            r.random_range(-1.0..2.0),
            r.random_range(0.5..1.5),
            r.random_range(-0.25..0.75),
        ];
        let inside = (0..m.simplices.len())
            .filter(|&s| {
                let p = m.simplex_points(s);
                // Barycentric coordinates of q in the projected tetrahedron.
                let mut a: Matrix<3> = [[0.0; 3]; 3];
                let mut b = [0.0; 3];
                for j in 0..3 {
                    for k in 0..3 {
                        a[j][k] = p[k + 1][j] - p[0][j];
                    }
                    b[j] = q[j] - p[0][j];
                }
                let l = crate::linalg::solve_block(a, b, 3).unwrap();
                l.iter().all(|&x| x > 1e-12) && l.iter().sum::<f64>() < 1.0 - 1e-12
            })
            .count();
        assert_eq!(inside, 1, "{q:?}");
    }
    // The 4D normal of every tetrahedron points to +w.
    for s in 0..m.simplices.len() {
        let n = simplex_normal(&m.simplex_points(s));
        assert!(n[3] > 0.0, "{n:?}");
    }
}

#[test]
fn a_linear_field_has_exact_flat_and_gradient_normals() {
    let shape = [4, 5, 3];
    let (a, b, c, d) = (0.3, -0.8, 0.5, 0.1);
    let extent = [[-1.0, 1.0], [-2.0, 0.0], [0.0, 0.5]];
    let h = 1.7;
    let mut f = Vec::new();
    for x in 0..4 {
        for y in 0..5 {
            for z in 0..3 {
                let p = [
                    -1.0 + 2.0 * x as f64 / 3.0,
                    -2.0 + 2.0 * y as f64 / 4.0,
                    0.5 * z as f64 / 2.0,
                ];
                f.push(a * p[0] + b * p[1] + c * p[2] + d);
            }
        }
    }
    let field = Field { values: &f, shape };
    let e = elevation_map::<4>(&field, Some(&extent), h).unwrap();
    let v = [-h * a, -h * b, -h * c, 1.0];
    let expect = scale(&v, 1.0 / norm(&v));
    for s in 0..e.mesh.simplices.len() {
        let n = simplex_normal(&e.mesh.simplex_points(s));
        let n = scale(&n, 1.0 / norm(&n));
        assert!(sub(&n, &expect).iter().all(|x| x.abs() < 1e-12), "{n:?}");
    }
    for n in gradient_normals(&field, &e, h) {
        assert!(sub(&n, &expect).iter().all(|x| x.abs() < 1e-12), "{n:?}");
        assert!((dot(&n, &n) - 1.0).abs() < 1e-15);
    }
}

#[test]
fn nan_cubes_are_holes_and_unused_vertices_are_dropped() {
    let shape = [3, 3, 3];
    let mut f: Vec<f64> = (0..27).map(|i| i as f64 * 0.01).collect();
    // The corner grid point (0, 0, 0) is in one cube only; the centre is in all eight.
    f[0] = f64::NAN;
    let e = elevation_map::<4>(&Field { values: &f, shape }, None, 1.0).unwrap();
    assert_eq!(e.holes, 1);
    assert_eq!(e.mesh.simplices.len(), 6 * 7);
    assert_eq!(e.mesh.vertices.len(), 26);
    assert_eq!(e.grid[0], 1);
    for (k, &g) in e.grid.iter().enumerate() {
        assert_eq!(e.values[k], f[g as usize]);
        assert_eq!(e.mesh.vertices[k][3], f[g as usize]);
    }
    for s in &e.mesh.simplices {
        assert!(s.iter().all(|&i| (i as usize) < 26));
    }
    f[13] = f64::NAN;
    let e = elevation_map::<4>(&Field { values: &f, shape }, None, 1.0).unwrap_err();
    assert!(e.contains("no grid cube with 8 finite corners"), "{e}");
}

#[test]
fn bad_fields_are_refused_with_what_is_wrong() {
    let f = vec![0.0; 8];
    let field = Field {
        values: &f,
        shape: [2, 2, 2],
    };
    let err = |e: Result<Elevation<4>, String>| e.unwrap_err();
    assert!(err(elevation_map(
        &Field {
            values: &f,
            shape: [1, 2, 4]
        },
        None,
        1.0
    ))
    .contains("at least 2 grid points"));
    assert!(err(elevation_map(
        &Field {
            values: &f,
            shape: [2, 2, 3]
        },
        None,
        1.0
    ))
    .contains("needs 12 values, got 8"));
    assert!(err(elevation_map(
        &field,
        Some(&[[0.0, 1.0], [1.0, 1.0], [0.0, 1.0]]),
        1.0
    ))
    .contains("y range [1, 1]"));
    assert!(err(elevation_map(&field, None, f64::NAN)).contains("height"));
    let mut g = f.clone();
    g[5] = f64::INFINITY;
    assert!(err(elevation_map(
        &Field {
            values: &g,
            shape: [2, 2, 2]
        },
        None,
        1.0
    ))
    .contains("field[1, 0, 1] is inf"));
    assert!(elevation_map::<5>(&field, None, 1.0)
        .unwrap_err()
        .contains("dim = 4"));
}
