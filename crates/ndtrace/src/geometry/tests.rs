use super::*;
use crate::linalg::{add, det, mat_mul, transpose};
use crate::testutil::exact::det_bareiss;
use crate::testutil::*;
use rand::Rng;

const TOL: f64 = 1e-9;

fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= TOL * scale.max(1.0)
}

fn edge_vectors<const N: usize>(p: &[Vector<N>]) -> Vec<Vector<N>> {
    p[1..].iter().map(|x| sub(x, &p[0])).collect()
}

fn cross_product_identities<const N: usize>() {
    let mut r = rng(100 + N as u64);
    for _ in 0..200 {
        let e: Vec<Vector<N>> = random_points(&mut r, N - 1, 2.0);
        let n = generalized_cross(&e);
        // Orthogonal to each edge.
        for edge in &e {
            assert!(
                close(dot(&n, edge), 0.0, norm(&n) * norm(edge)),
                "N={N}: not orthogonal"
            );
        }
        // |N|² equals the Gram determinant ((N−1)!·V_{N−1})².
        let g = det_block(&gram(&e), N - 1);
        assert!(
            close(dot(&n, &n), g, g),
            "N={N}: |N|²={} Gram={g}",
            dot(&n, &n)
        );
        let x0 = random_vector::<N>(&mut r, 3.0);
        let mut pts = vec![x0];
        pts.extend(e.iter().map(|x| add(x, &x0)));
        let v = gram_volume(&pts) * factorial(N - 1);
        assert!(close(dot(&n, &n), v * v, g), "N={N}: |N|² vs ((N−1)!V)²");
        // det[edges | N] = |N|² > 0.
        let mut m: Matrix<N> = [[0.0; N]; N];
        for r_ in 0..N {
            for c in 0..N - 1 {
                m[r_][c] = e[c][r_];
            }
            m[r_][N - 1] = n[r_];
        }
        let d = det(&m);
        assert!(
            d > 0.0 && close(d, dot(&n, &n), d),
            "N={N}: det[edges|N]={d}"
        );
        // det[edges | v] = v·N for any v (the expansion that defines eq. 6).
        let v = random_vector::<N>(&mut r, 1.0);
        for r_ in 0..N {
            m[r_][N - 1] = v[r_];
        }
        assert!(
            close(det(&m), dot(&v, &n), d.abs() + 1.0),
            "N={N}: expansion"
        );
        // Eq. 8: N(a)·N(b) = det[a_i · b_j].
        let f: Vec<Vector<N>> = random_points(&mut r, N - 1, 2.0);
        let nf = generalized_cross(&f);
        let mut ab: Matrix<N> = [[0.0; N]; N];
        for i in 0..N - 1 {
            for j in 0..N - 1 {
                ab[i][j] = dot(&e[i], &f[j]);
            }
        }
        let want = det_block(&ab, N - 1);
        assert!(
            close(dot(&n, &nf), want, norm(&n) * norm(&nf)),
            "N={N}: eq. 8"
        );
    }
}

#[test]
fn generalized_cross_identities_in_every_dimension() {
    for_each_dim!(cross_product_identities);
}

fn unit_edges_give_last_axis<const N: usize>() {
    let e: Vec<Vector<N>> = (0..N - 1)
        .map(|k| std::array::from_fn(|i| if i == k { 1.0 } else { 0.0 }))
        .collect();
    let mut want = [0.0; N];
    want[N - 1] = 1.0;
    assert_eq!(generalized_cross(&e), want, "N={N}");
    // Standard simplex: +1/N!.
    let mut pts = vec![[0.0; N]];
    pts.extend((0..N).map(|k| std::array::from_fn(|i| if i == k { 1.0 } else { 0.0 })));
    assert!(
        (signed_volume(&pts) - 1.0 / factorial(N)).abs() < 1e-15,
        "N={N}"
    );
    // Dependent edges give the zero normal and a degenerate hyperplane.
    let mut dep = e.clone();
    if N > 2 {
        dep[1] = scale(&dep[0], 2.0);
    } else {
        dep[0] = [0.0; N];
    }
    assert_eq!(norm(&generalized_cross(&dep)), 0.0);
    let mut p = vec![[0.5; N]];
    p.extend(dep.iter().map(|x| add(x, &[0.5; N])));
    assert_eq!(hyperplane(&p), Err(Degenerate::Simplex));
    assert_eq!(side(&[7.0; N], &p), 0);
}

#[test]
fn unit_edges_and_standard_simplex() {
    for_each_dim!(unit_edges_give_last_axis);
    assert_eq!(generalized_cross::<2>(&[[3.0, 5.0]]), [-5.0, 3.0]);
    // 3D: the familiar cross product (eq. 9).
    assert_eq!(
        generalized_cross::<3>(&[[1., 2., 3.], [4., 5., 6.]]),
        [-3., 6., -3.]
    );
}

fn volume_identities<const N: usize>() {
    let mut r = rng(200 + N as u64);
    for _ in 0..200 {
        let pts: Vec<Vector<N>> = random_points(&mut r, N + 1, 2.0);
        let v = signed_volume(&pts);
        // Swapping two vertices flips the sign.
        let (i, j) = (r.random_range(0..=N), r.random_range(0..=N));
        if i != j {
            let mut sw = pts.clone();
            sw.swap(i, j);
            assert!(close(signed_volume(&sw), -v, v.abs()), "N={N}: swap {i}{j}");
        }
        // Invariance under rotation and translation; a reflection flips the sign.
        let q = random_rotation::<N>(&mut r);
        let t = random_vector::<N>(&mut r, 5.0);
        let moved: Vec<Vector<N>> = pts.iter().map(|x| add(&mat_vec(&q, x), &t)).collect();
        assert!(close(signed_volume(&moved), v, v.abs()), "N={N}: rotation");
        let f = random_reflection::<N>(&mut r);
        let refl: Vec<Vector<N>> = pts.iter().map(|x| mat_vec(&f, x)).collect();
        assert!(
            close(signed_volume(&refl), -v, v.abs()),
            "N={N}: reflection"
        );
        // |V_N| equals the Gram volume for K = N (eq. 4).
        assert!(
            close(gram_volume(&pts), v.abs(), v.abs()),
            "N={N}: gram K=N"
        );
        // Gram volumes of K-faces are rotation invariant and match the cross product for K = N−1.
        for k in 1..=N {
            let face = &pts[..=k];
            let moved_face = &moved[..=k];
            let a = gram_volume(face);
            assert!(close(gram_volume(moved_face), a, a), "N={N} K={k}");
        }
        let n = simplex_normal(&pts[..N]);
        assert!(close(
            norm(&n),
            factorial(N - 1) * gram_volume(&pts[..N]),
            norm(&n)
        ));
    }
}

#[test]
fn volume_identities_in_every_dimension() {
    for_each_dim!(volume_identities);
}

fn exact_integer_volumes<const N: usize>() {
    let mut r = rng(300 + N as u64);
    for trial in 0..300 {
        let mut ip: Vec<[i64; N]> = (0..=N)
            .map(|_| std::array::from_fn(|_| r.random_range(-3..=3)))
            .collect();
        if trial % 10 == 0 {
            // Make a third of these affinely dependent: x_N = x_1 + x_2 − x_0 (or x_1 = x_0).
            if N >= 2 {
                ip[N] = std::array::from_fn(|i| ip[1][i] + ip[N - 1][i] - ip[0][i]);
            }
        }
        let exact = det_bareiss(
            &(0..N)
                .map(|row| {
                    (0..N)
                        .map(|c| (ip[c + 1][row] - ip[0][row]) as i128)
                        .collect()
                })
                .collect::<Vec<Vec<i128>>>(),
        );
        let pts: Vec<Vector<N>> = ip
            .iter()
            .map(|p| std::array::from_fn(|i| p[i] as f64))
            .collect();
        let w = signed_volume(&pts) * factorial(N);
        assert_eq!(w.round() as i128, exact, "N={N}: f64 {w} vs exact {exact}");
        // Hadamard's bound on |det| sets the scale of f64 rounding.
        let hadamard: f64 = (1..=N).map(|c| norm(&sub(&pts[c], &pts[0]))).product();
        assert!(
            (w - exact as f64).abs() <= 1e-12 * hadamard.max(1.0),
            "N={N}: {w} vs {exact}"
        );
        if exact == 0 {
            assert!(w.abs() <= 1e-12 * hadamard.max(1.0));
        } else {
            assert_eq!(w.signum(), (exact as f64).signum(), "N={N}: sign");
        }
    }
}

#[test]
fn f64_volumes_equal_exact_integer_determinants() {
    for_each_dim!(exact_integer_volumes);
}

fn barycentric_identities<const N: usize>() {
    let mut r = rng(400 + N as u64);
    for _ in 0..100 {
        for k in 1..=N {
            let pts: Vec<Vector<N>> = random_points(&mut r, k + 1, 2.0);
            // A point in the affine hull, built from random weights summing to 1.
            let mut w: Vec<f64> = (0..=k).map(|_| r.random_range(-0.5..1.5)).collect();
            let s: f64 = w.iter().sum();
            w.iter_mut().for_each(|x| *x /= s);
            let mut x = [0.0; N];
            for (p, wi) in pts.iter().zip(&w) {
                x = add_scaled(&x, *wi, p);
            }
            let mut t = [0.0; 9];
            barycentric(&x, &pts, &mut t).unwrap();
            let sum: f64 = t[..=k].iter().sum();
            assert!(close(sum, 1.0, 1.0), "N={N} K={k}: sum {sum}");
            let mut rebuilt = [0.0; N];
            for (p, ti) in pts.iter().zip(&t) {
                rebuilt = add_scaled(&rebuilt, *ti, p);
            }
            for i in 0..N {
                assert!((rebuilt[i] - x[i]).abs() < 1e-7, "N={N} K={k}: rebuild");
            }
            for i in 0..=k {
                assert!((t[i] - w[i]).abs() < 1e-7, "N={N} K={k}: weights");
            }
            // Off the hull (K < N), the coordinates are those of the projection: moving x
            // along a direction orthogonal to the hull leaves them unchanged.
            if k < N {
                let e = edge_vectors(&pts);
                let mut off = random_vector::<N>(&mut r, 1.0);
                // Gram–Schmidt off against the edges.
                let mut basis: Vec<Vector<N>> = vec![];
                for edge in &e {
                    let mut b = *edge;
                    for q in &basis {
                        b = add_scaled(&b, -dot(&b, q), q);
                    }
                    basis.push(scale(&b, 1.0 / norm(&b)));
                }
                for q in &basis {
                    off = add_scaled(&off, -dot(&off, q), q);
                }
                let mut t2 = [0.0; 9];
                barycentric(&add(&x, &off), &pts, &mut t2).unwrap();
                for i in 0..=k {
                    assert!((t2[i] - t[i]).abs() < 1e-7, "N={N} K={k}: projection");
                }
            }
        }
    }
}

#[test]
fn barycentric_coordinates_rebuild_points_in_every_dimension() {
    for_each_dim!(barycentric_identities);
}

/// The inside test (all t_i ≥ 0) agrees with sampling: points drawn as convex combinations are
/// inside, and points of the hyperplane outside the simplex have a negative coordinate whose
/// vertex-opposite facet separates them (checked with `side` in the (N−1)-D hull).
fn inside_test_agrees_with_sampling<const N: usize>() {
    let mut r = rng(500 + N as u64);
    let pts: Vec<Vector<N>> = random_points(&mut r, N + 1, 2.0);
    let vol = signed_volume(&pts);
    let mut inside_hits = 0;
    for _ in 0..2000 {
        let x = random_vector::<N>(&mut r, 2.5);
        let mut t = [0.0; 9];
        barycentric(&x, &pts, &mut t).unwrap();
        let inside = t[..=N].iter().all(|&ti| ti >= 0.0);
        // Independent test: x is inside iff replacing any vertex by x keeps the sign of the
        // volume (each t_i is the volume ratio V(x replacing x_i)/V).
        let by_volumes = (0..=N).all(|i| {
            let mut q = pts.clone();
            q[i] = x;
            signed_volume(&q) * vol >= 0.0
        });
        assert_eq!(inside, by_volumes, "N={N}: inside test vs volume ratios");
        for i in 0..=N {
            let mut q = pts.clone();
            q[i] = x;
            assert!(
                close(t[i], signed_volume(&q) / vol, 1.0),
                "N={N}: t_i as volume ratio"
            );
        }
        inside_hits += inside as usize;
    }
    // And random convex combinations are always inside.
    for _ in 0..500 {
        let mut w: Vec<f64> = (0..=N).map(|_| r.random_range(0.0..1.0)).collect();
        let s: f64 = w.iter().sum();
        w.iter_mut().for_each(|x| *x /= s);
        let mut x = [0.0; N];
        for (p, wi) in pts.iter().zip(&w) {
            x = add_scaled(&x, *wi, p);
        }
        let mut t = [0.0; 9];
        barycentric(&x, &pts, &mut t).unwrap();
        assert!(
            t[..=N].iter().all(|&ti| ti >= -1e-12),
            "N={N}: sampled point outside"
        );
    }
    let _ = inside_hits;
}

#[test]
fn inside_test_in_every_dimension() {
    for_each_dim!(inside_test_agrees_with_sampling);
}

fn distance_identities<const N: usize>() {
    let mut r = rng(600 + N as u64);
    for _ in 0..200 {
        let pts: Vec<Vector<N>> = random_points(&mut r, N, 2.0);
        let x = random_vector::<N>(&mut r, 3.0);
        let (h, p) = point_hyperplane_distance(&x, &pts).unwrap();
        let plane = hyperplane(&pts).unwrap();
        // The foot point lies on the hyperplane, and x − p is along the normal.
        assert!(close(plane.distance(&p), 0.0, 1.0), "N={N}: foot");
        assert!(close(norm(&sub(&x, &p)), h.abs(), 1.0));
        // h = N·V_N/V_{N−1} (eq. 11).
        let mut full = pts.clone();
        full.push(x);
        let h11 = N as f64 * signed_volume(&full) / gram_volume(&pts);
        assert!(close(h, h11, h.abs()), "N={N}: eq. 11 {h} vs {h11}");
        // side agrees with the sign of h.
        assert_eq!(side(&x, &pts), if h > 0.0 { 1 } else { -1 });
        assert_eq!(side(&p, &pts), 0, "N={N}: foot point is on the plane");
        // Invariant under rotation and translation.
        let q = random_rotation::<N>(&mut r);
        let t = random_vector::<N>(&mut r, 5.0);
        let mv = |y: &Vector<N>| add(&mat_vec(&q, y), &t);
        let moved: Vec<Vector<N>> = pts.iter().map(mv).collect();
        let (h2, p2) = point_hyperplane_distance(&mv(&x), &moved).unwrap();
        assert!(close(h2, h, h.abs()), "N={N}: rotated distance");
        let pm = mv(&p);
        for i in 0..N {
            assert!((p2[i] - pm[i]).abs() < 1e-8, "N={N}: rotated foot point");
        }
    }
}

#[test]
fn point_hyperplane_distance_in_every_dimension() {
    for_each_dim!(distance_identities);
}

fn clipping_and_rays<const N: usize>() {
    let mut r = rng(700 + N as u64);
    for _ in 0..200 {
        let pts: Vec<Vector<N>> = random_points(&mut r, N, 2.0);
        let plane = hyperplane(&pts).unwrap();
        let a = random_vector::<N>(&mut r, 3.0);
        let b = random_vector::<N>(&mut r, 3.0);
        let t = clip_segment(&a, &b, &pts).unwrap();
        let x = add_scaled(&a, t, &sub(&b, &a));
        assert!(
            close(plane.distance(&x), 0.0, 1.0 + t.abs()),
            "N={N}: clip point on plane"
        );
        // The segment crosses iff its ends are on opposite sides.
        let crosses = side(&a, &pts) * side(&b, &pts) < 0;
        assert_eq!(crosses, (0.0..=1.0).contains(&t), "N={N}: t={t}");
        // The ray form gives the same point.
        let d = sub(&b, &a);
        let tr = ray_hyperplane(&a, &d, &pts).unwrap();
        assert!(close(tr, t, t.abs()), "N={N}: ray {tr} vs clip {t}");
        // A direction inside the hyperplane is parallel.
        let along = sub(&pts[1], &pts[0]);
        assert_eq!(ray_hyperplane(&a, &along, &pts), Err(Degenerate::Parallel));
        assert_eq!(
            clip_segment(&a, &add(&a, &along), &pts),
            Err(Degenerate::Parallel)
        );
        assert_eq!(clip_segment(&a, &a, &pts), Err(Degenerate::Parallel));
    }
}

#[test]
fn clipping_and_ray_hyperplane_in_every_dimension() {
    for_each_dim!(clipping_and_rays);
}

fn normals_are_pseudotensors<const N: usize>() {
    let mut r = rng(800 + N as u64);
    for case in 0..150 {
        let m: Matrix<N> = match case % 3 {
            0 => random_rotation(&mut r),
            1 => random_reflection(&mut r),
            _ => random_matrix(&mut r),
        };
        let e: Vec<Vector<N>> = random_points(&mut r, N - 1, 2.0);
        let n = generalized_cross(&e);
        let te: Vec<Vector<N>> = e.iter().map(|x| mat_vec(&m, x)).collect();
        let want = generalized_cross(&te);
        let got = transform_normal(&m, &n);
        for i in 0..N {
            assert!(
                close(got[i], want[i], norm(&want)),
                "N={N} case {case}: {got:?} {want:?}"
            );
        }
        if case % 3 < 2 {
            // Orthogonal: cof(R) = det(R)·R.
            let rn = scale(&mat_vec(&m, &n), det(&m));
            for i in 0..N {
                assert!(close(got[i], rn[i], norm(&n)), "N={N}: det(R)·R·N");
            }
            let _ = mat_mul(&m, &transpose(&m));
        }
    }
}

#[test]
fn transform_normal_matches_recomputed_cross_products() {
    for_each_dim!(normals_are_pseudotensors);
}

#[test]
fn degenerate_barycentric_is_reported() {
    let p = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
    let mut t = [0.0; 3];
    assert_eq!(
        barycentric(&[0.5, 0.0, 0.0], &p, &mut t),
        Err(Degenerate::Simplex)
    );
    let q = [[0.0, 0.0], [0.0, 0.0]];
    assert_eq!(hyperplane(&q), Err(Degenerate::Simplex));
    assert_eq!(gram_volume(&q), 0.0);
}

/// The example of the crate's documentation (`lib.rs`), which `cargo test` runs here (the crate's
/// doc examples are not compiled as doctests: one build of the crate for its tests).
#[test]
fn the_crate_doc_example_holds() {
    // The edges e_1, e_2, e_3 of R^4 give +e_4 (eq. 6).
    let n = generalized_cross::<4>(&[[1., 0., 0., 0.], [0., 1., 0., 0.], [0., 0., 1., 0.]]);
    assert_eq!(n, [0., 0., 0., 1.]);
    // The standard 2-simplex has area +1/2! (eqs. 2–3).
    assert_eq!(signed_volume::<2>(&[[0., 0.], [1., 0.], [0., 1.]]), 0.5);
}
