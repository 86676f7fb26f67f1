//! Identities of the rotation toolkit on seeded random inputs, for every N where meaningful.

use super::*;
use crate::linalg::{add_scaled, mat_vec, sub};
use crate::testutil::*;
use rand::Rng;

fn max_diff<const N: usize>(a: &Matrix<N>, b: &Matrix<N>) -> f64 {
    let mut d: f64 = 0.0;
    for i in 0..N {
        for j in 0..N {
            d = d.max((a[i][j] - b[i][j]).abs());
        }
    }
    d
}

fn assert_rotation<const N: usize>(m: &Matrix<N>, what: &str) {
    let g = mat_mul(&transpose(m), m);
    assert!(
        max_diff(&g, &identity()) < 1e-12,
        "N={N} {what}: not orthonormal {m:?}"
    );
    assert!((det(m) - 1.0).abs() < 1e-12, "N={N} {what}: det {}", det(m));
}

fn random_unit<const N: usize>(r: &mut TestRng) -> Vector<N> {
    loop {
        let v = random_vector::<N>(r, 1.0);
        let l = norm(&v);
        if l > 0.1 {
            return scale(&v, 1.0 / l);
        }
    }
}

fn angle<const N: usize>(a: &Vector<N>, b: &Vector<N>) -> f64 {
    let c = dot(a, b);
    norm(&add_scaled(b, -c, a)).atan2(c)
}

fn col<const N: usize>(m: &Matrix<N>, k: usize) -> Vector<N> {
    std::array::from_fn(|r| m[r][k])
}

// -- plane rotations and compose ---------------------------------------------------------------

fn plane_rotations_turn_i_toward_j<const N: usize>() {
    for i in 0..N {
        for j in 0..N {
            if i == j {
                continue;
            }
            let th = 0.3;
            let m = plane_rotation::<N>(i, j, th);
            assert_rotation(&m, "plane_rotation");
            let mut e = [0.0; N];
            e[i] = 1.0;
            let v = mat_vec(&m, &e);
            // e_i ↦ cos θ e_i + sin θ e_j: a small positive angle moves e_i toward +e_j.
            assert!((v[i] - th.cos()).abs() < 1e-15 && (v[j] - th.sin()).abs() < 1e-15);
            assert_eq!(
                m,
                transpose(&plane_rotation::<N>(j, i, th)),
                "R_ij(θ) = R_ji(θ)ᵀ"
            );
        }
    }
}

#[test]
fn plane_rotation_sense_in_every_dimension() {
    for_each_dim!(plane_rotations_turn_i_toward_j);
}

#[test]
fn compose_applies_the_first_rotation_first() {
    let a = plane_rotation::<3>(0, 1, std::f64::consts::FRAC_PI_2); // x → y
    let b = plane_rotation::<3>(1, 2, std::f64::consts::FRAC_PI_2); // y → z
    let x = mat_vec(&compose(&[a, b]), &[1.0, 0.0, 0.0]);
    assert!((x[2] - 1.0).abs() < 1e-15, "{x:?}");
    let x = mat_vec(&compose(&[b, a]), &[1.0, 0.0, 0.0]);
    assert!((x[1] - 1.0).abs() < 1e-15, "{x:?}");
    assert_eq!(compose::<3>(&[]), identity());
    assert_eq!(compose(&[a, b]), mat_mul(&b, &a));
}

// -- rolling ball ------------------------------------------------------------------------------

fn rolling_ball_is_its_conjugation<const N: usize>() {
    let mut r = rng(7000 + N as u64);
    for _ in 0..40 {
        let d: Vec<f64> = (0..N - 1).map(|_| r.random_range(-2.0..2.0)).collect();
        let radius = r.random_range(0.3..3.0);
        let len = d.iter().map(|x| x * x).sum::<f64>().sqrt();
        for mode in [RollingAngle::Course, RollingAngle::Arc] {
            let m = rolling_ball::<N>(&d, radius, mode);
            assert_rotation(&m, "rolling_ball");
            let theta = match mode {
                RollingAngle::Course => len.atan2(radius),
                RollingAngle::Arc => len / radius,
            };
            // R·R_0(θ)·R⁻¹ with R taking e_1 to n̂ inside the first N − 1 axes and R_0 turning
            // the pole (last axis) toward e_1.
            let mut n = [0.0; N];
            for k in 0..N - 1 {
                n[k] = d[k] / len;
            }
            let mut e0 = [0.0; N];
            e0[0] = 1.0;
            let rot = if N == 2 {
                // In one controller axis n̂ = ±e_1: R_0(±θ) directly.
                let s = n[0].signum();
                let want = plane_rotation::<N>(N - 1, 0, s * theta);
                assert!(max_diff(&m, &want) < 1e-14, "N=2 {mode:?}");
                continue;
            } else {
                rotation_between(&e0, &n)
            };
            assert!((rot[N - 1][N - 1] - 1.0).abs() < 1e-15, "R fixes the pole");
            let want = mat_mul(
                &mat_mul(&rot, &plane_rotation::<N>(N - 1, 0, theta)),
                &transpose(&rot),
            );
            assert!(
                max_diff(&m, &want) < 1e-13,
                "N={N} {mode:?}: {m:?} vs {want:?}"
            );
            // The pole is pulled toward n̂.
            let pole = col(&m, N - 1);
            assert!((pole[N - 1] - theta.cos()).abs() < 1e-14);
            assert!((dot(&pole, &n) - theta.sin()).abs() < 1e-14);
        }
    }
    assert_eq!(
        rolling_ball::<N>(&vec![0.0; N - 1], 1.0, RollingAngle::Course),
        identity()
    );
}

#[test]
fn rolling_ball_matches_the_conjugation_construction() {
    for_each_dim!(rolling_ball_is_its_conjugation);
}

#[test]
fn rolling_ball_course_angle_is_atan_r_over_big_r() {
    // c = R/D, s = r/D with D² = R² + r²: r = 3, R = 4 gives c = 4/5, s = 3/5 (eq. 5).
    let m = rolling_ball::<3>(&[3.0, 0.0], 4.0, RollingAngle::Course);
    assert!((m[2][2] - 0.8).abs() < 1e-15 && (m[0][2] - 0.6).abs() < 1e-15);
    assert!((m[2][0] + 0.6).abs() < 1e-15 && (m[0][0] - 0.8).abs() < 1e-15);
    // The notes' 3D matrix: M_3[0][1] = −n_x n_y (1 − c).
    let (nx, ny) = (0.6, 0.8);
    let m = rolling_ball::<3>(&[nx * 5.0, ny * 5.0], 5.0, RollingAngle::Arc);
    let c = 1f64.cos();
    assert!((m[0][1] + nx * ny * (1.0 - c)).abs() < 1e-15);
    assert!((m[1][1] - (c + nx * nx * (1.0 - c))).abs() < 1e-15);
}

fn commutator_sense<const N: usize>() {
    if N < 3 {
        return;
    }
    let eps = 1e-3;
    for radius in [1.0, 2.0] {
        for i in 0..N - 1 {
            for j in 0..N - 1 {
                if i == j {
                    continue;
                }
                // Counterclockwise loop in the controller's (i, j) plane: +e_i, +e_j, −e_i, −e_j.
                let step = |k: usize, s: f64| {
                    let mut d = vec![0.0; N - 1];
                    d[k] = s * eps;
                    rolling_ball::<N>(&d, radius, RollingAngle::Arc)
                };
                let steps = [step(i, 1.0), step(j, 1.0), step(i, -1.0), step(j, -1.0)];
                let net = compose(&steps); // M_4 M_3 M_2 M_1
                let area = eps * eps / (radius * radius);
                // Second order: the net rotation turns j toward i by the loop's area.
                let want = plane_rotation::<N>(i, j, -area);
                assert!(
                    max_diff(&net, &want) < 3.0 * eps * area,
                    "N={N} ({i},{j}) R={radius}: {net:?}"
                );
                assert!(
                    (net[j][i] / area + 1.0).abs() < 1e-2,
                    "N={N} ({i},{j}): sense {}",
                    net[j][i] / area
                );
            }
        }
    }
}

#[test]
fn small_controller_loops_rotate_against_their_sense() {
    for_each_dim!(commutator_sense);
}

// -- frames, look_at, slerp --------------------------------------------------------------------

fn frames_are_rotations<const N: usize>() {
    let mut r = rng(7100 + N as u64);
    for k in 0..=N {
        for _ in 0..20 {
            let vs: Vec<Vector<N>> = random_points(&mut r, k, 1.0);
            let m = match frame(&vs) {
                Ok(m) => m,
                Err(e) => {
                    // Only a left-handed full set may fail.
                    assert_eq!(k, N, "N={N} k={k}: {e}");
                    let mut flipped = vs.clone();
                    flipped[0] = scale(&flipped[0], -1.0);
                    frame(&flipped).unwrap()
                }
            };
            assert_rotation(&m, "frame");
            // Gram–Schmidt: column c is in span(v_0..v_c) with a positive component along v_c,
            // and orthogonal to v_0..v_{c−1}.
            for c in 0..k.min(N) {
                let a = col(&m, c);
                for v in &vs[..c] {
                    assert!(dot(&a, v).abs() < 1e-12);
                }
                if k < N || c > 0 {
                    assert!(dot(&a, &vs[c]) > 0.0, "N={N} k={k} c={c}");
                }
            }
        }
    }
    let mut left: Vec<Vector<N>> = (0..N)
        .map(|i| std::array::from_fn(|j| if i == j { 1.0 } else { 0.0 }))
        .collect();
    assert_eq!(frame(&left).unwrap(), identity());
    left[0][0] = -1.0;
    let e = frame(&left).unwrap_err().to_string();
    assert!(e.contains("left-handed"), "{e}");
    let dep: Vec<Vector<N>> = vec![left[1], scale(&left[1], 2.0)];
    let e = frame(&dep).unwrap_err().to_string();
    assert!(
        e.starts_with("vectors[1]: ") && e.contains("dependent"),
        "{e}"
    );
}

#[test]
fn frames_are_right_handed_gram_schmidt() {
    for_each_dim!(frames_are_rotations);
}

fn look_at_is_the_camera<const N: usize>() {
    if N < 2 {
        return;
    }
    let mut r = rng(7200 + N as u64);
    let p = random_vector::<N>(&mut r, 3.0);
    let t = random_vector::<N>(&mut r, 3.0);
    let up: Vec<Vector<N>> = random_points(&mut r, N - 2, 1.0);
    assert_eq!(
        look_at(&p, &t, &up).unwrap(),
        look_at_orientation(&p, &t, &up).unwrap()
    );
    assert!(look_at(&p, &p, &up).is_err());
    assert!(look_at(&p, &t, &up[..0]).is_err() || N == 2);
}

#[test]
fn look_at_reuses_the_camera_orientation() {
    for_each_dim!(look_at_is_the_camera);
}

fn slerp_constant_speed<const N: usize>() {
    let mut r = rng(7300 + N as u64);
    for _ in 0..40 {
        let a = random_unit::<N>(&mut r);
        let b = random_unit::<N>(&mut r);
        let th = angle(&a, &b);
        let at0 = slerp(&a, &b, 0.0);
        let at1 = slerp(&a, &b, 1.0);
        assert!(norm(&sub(&at0, &a)) < 1e-15 && norm(&sub(&at1, &b)) < 1e-14);
        for _ in 0..5 {
            let (t1, t2) = (r.random_range(-0.2..1.2), r.random_range(-0.2..1.2));
            let (x, y) = (slerp(&a, &b, t1), slerp(&a, &b, t2));
            assert!((norm(&x) - 1.0).abs() < 1e-14);
            // Constant speed along the great circle (both angles below π here).
            if ((t2 - t1) * th).abs() < 3.0 {
                assert!(
                    (angle(&x, &y) - (t2 - t1).abs() * th).abs() < 1e-12,
                    "N={N}"
                );
            }
        }
    }
    // Nearly equal vectors: no blow-up, stays on the sphere between them.
    let a = random_unit::<N>(&mut r);
    let mut b = a;
    b[0] += 1e-13;
    let b = scale(&b, 1.0 / norm(&b));
    let m = slerp(&a, &b, 0.5);
    assert!((norm(&m) - 1.0).abs() < 1e-15 && norm(&sub(&m, &a)) < 1e-13);
    assert_eq!(slerp(&a, &a, 0.7), a);
    // Antipodal: the documented choice is still a unit-speed great circle.
    let na = scale(&a, -1.0);
    let h = slerp(&a, &na, 0.5);
    assert!(dot(&h, &a).abs() < 1e-15 && (norm(&h) - 1.0).abs() < 1e-15);
    assert!(norm(&sub(&slerp(&a, &na, 1.0), &na)) < 1e-15);
}

#[test]
fn slerp_has_constant_angular_speed() {
    for_each_dim!(slerp_constant_speed);
}

// -- nested spheres ----------------------------------------------------------------------------

fn nested_round_trip<const N: usize>() {
    let mut r = rng(7400 + N as u64);
    let mut cases: Vec<Matrix<N>> = (0..40).map(|_| random_rotation::<N>(&mut r)).collect();
    // The chart's singular points: the last axis sent to −e_N, and the identity.
    cases.push(plane_rotation::<N>(0, N - 1, std::f64::consts::PI));
    cases.push(identity());
    for m in &cases {
        let vs = to_nested_spheres(m);
        assert_eq!(vs.len(), N - 1);
        for (idx, v) in vs.iter().enumerate() {
            assert_eq!(v.len(), N - idx);
            assert!((v.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-14);
        }
        for k in 0..N {
            assert!(
                (vs[0][k] - m[k][N - 1]).abs() < 1e-14,
                "v_N is the last column: {:?} vs {:?}",
                vs[0],
                col(m, N - 1)
            );
        }
        let back = from_nested_spheres::<N>(&vs).unwrap();
        assert!(max_diff(&back, m) < 1e-12, "N={N}: {}", max_diff(&back, m));
    }
    // Interpolation: endpoints, rotations in between, the last axis on a great circle.
    for w in cases[..20].windows(2) {
        let (a, b) = (&w[0], &w[1]);
        assert!(max_diff(&nested_slerp(a, b, 0.0), a) < 1e-12);
        assert!(max_diff(&nested_slerp(a, b, 1.0), b) < 1e-12);
        let th = angle(&col(a, N - 1), &col(b, N - 1));
        for t in [0.25, 0.5, 0.9] {
            let m = nested_slerp(a, b, t);
            assert_rotation(&m, "nested_slerp");
            assert!((angle(&col(a, N - 1), &col(&m, N - 1)) - t * th).abs() < 1e-12);
        }
    }
    let e = from_nested_spheres::<N>(&[vec![1.0; N]])
        .unwrap_err()
        .to_string();
    assert!(e.contains("vectors") || N == 2, "{e}");
}

#[test]
fn nested_spheres_round_trip_exactly() {
    for_each_dim!(nested_round_trip);
}

#[test]
fn nested_sphere_errors_name_the_vector() {
    let e = from_nested_spheres::<3>(&[vec![0.0, 0.0, 2.0], vec![1.0, 0.0]]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "vectors[0]: not a unit vector (|vectors[0]| = 2)"
    );
    let e = from_nested_spheres::<3>(&[vec![0.0, 0.0, 1.0], vec![1.0, 0.0, 0.0]]).unwrap_err();
    assert!(
        e.to_string().starts_with("vectors[1]: expected shape (2,)"),
        "{e}"
    );
}

// -- quaternions -------------------------------------------------------------------------------

fn random_quat(r: &mut TestRng) -> Quat {
    random_unit::<4>(r)
}

fn pure(v: &Vector<3>) -> Quat {
    [0.0, v[0], v[1], v[2]]
}

#[test]
fn quat_to_matrix_is_the_sandwich_product() {
    let mut r = rng(7500);
    for _ in 0..100 {
        let q = random_quat(&mut r);
        let m = quat_to_matrix(&q);
        assert_rotation(&m, "quat_to_matrix");
        let v = random_vector::<3>(&mut r, 1.0);
        let rv = quat_mul(&quat_mul(&q, &pure(&v)), &quat_conjugate(&q));
        let mv = mat_vec(&m, &v);
        assert!(rv[0].abs() < 1e-15);
        for k in 0..3 {
            assert!((rv[k + 1] - mv[k]).abs() < 1e-14);
        }
        assert_eq!(quat_to_matrix(&q.map(|x| -x)), m);
    }
    // q = (cos θ/2, ẑ sin θ/2) turns x toward y by θ (right-handed about z).
    let th = 0.7f64;
    let q = [(th / 2.0).cos(), 0.0, 0.0, (th / 2.0).sin()];
    assert!(max_diff(&quat_to_matrix(&q), &plane_rotation::<3>(0, 1, th)) < 1e-15);
}

#[test]
fn matrix_to_quat_inverts_eq_9_everywhere() {
    let mut r = rng(7600);
    let mut qs: Vec<Quat> = (0..200).map(|_| random_quat(&mut r)).collect();
    // Near and at 180° (q0 ≈ 0), and the identity.
    for &eps in &[0.0, 1e-9, 1e-5] {
        let n = random_unit::<3>(&mut r);
        qs.push([eps, n[0], n[1], n[2]]);
        qs.push([0.0, 0.0, 0.0, 1.0]);
    }
    qs.push([1.0, 0.0, 0.0, 0.0]);
    for q in qs {
        let q = scale(&q, 1.0 / norm(&q));
        let back = matrix_to_quat(&quat_to_matrix(&q));
        let s = dot(&q, &back).signum();
        for k in 0..4 {
            assert!((back[k] - s * q[k]).abs() < 1e-14, "{q:?} vs {back:?}");
        }
        assert!(back[0] >= 0.0);
    }
}

#[test]
fn quaternion_sequences_are_continuous() {
    // A rotation about a fixed axis through 0 … 4π: the canonical q0 ≥ 0 jumps at 2π, the
    // sequence does not.
    let n = [0.6, 0.0, 0.8];
    let ms: Vec<Matrix<3>> = (0..=400)
        .map(|k| {
            let th = k as f64 * 0.0314159;
            let (s, c) = (th / 2.0).sin_cos();
            quat_to_matrix(&[c, s * n[0], s * n[1], s * n[2]])
        })
        .collect();
    let qs = matrix_to_quat_sequence(&ms);
    assert!(qs.windows(2).all(|w| dot(&w[0], &w[1]) > 0.99));
    let single: Vec<Quat> = ms.iter().map(matrix_to_quat).collect();
    assert!(single.windows(2).any(|w| dot(&w[0], &w[1]) < 0.0));
    for (q, m) in qs.iter().zip(&ms) {
        assert!(max_diff(&quat_to_matrix(q), m) < 1e-14);
    }
}

#[test]
fn so4_is_the_double_quaternion_product() {
    let mut r = rng(7700);
    for _ in 0..100 {
        let (q, p) = (random_quat(&mut r), random_quat(&mut r));
        let m = so4_from_quaternions(&q, &p);
        assert_rotation(&m, "so4");
        let v = random_vector::<4>(&mut r, 1.0);
        let want = quat_mul(&quat_mul(&q, &v), &quat_conjugate(&p));
        assert!(norm(&sub(&mat_vec(&m, &v), &want)) < 1e-14);
        // p = q: fixes e_0, eq. 9 in the lower-right block.
        let m = so4_from_quaternions(&q, &q);
        let r3 = quat_to_matrix(&q);
        assert!((m[0][0] - 1.0).abs() < 1e-15);
        for k in 0..3 {
            assert!(m[0][k + 1].abs() < 1e-15 && m[k + 1][0].abs() < 1e-15);
            for l in 0..3 {
                assert!((m[k + 1][l + 1] - r3[k][l]).abs() < 1e-15);
            }
        }
    }
}

#[test]
fn so4_basis_is_orthogonal() {
    // ⟨C_ij, C_kl⟩ = 4 δ_ik δ_jl, which quaternions_from_so4 relies on.
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..4 {
                for l in 0..4 {
                    let a = so4_from_quaternions(&basis(i), &basis(j));
                    let b = so4_from_quaternions(&basis(k), &basis(l));
                    let ip: f64 = (0..4)
                        .map(|r| (0..4).map(|c| a[r][c] * b[r][c]).sum::<f64>())
                        .sum();
                    let want = if (i, j) == (k, l) { 4.0 } else { 0.0 };
                    assert_eq!(ip, want, "({i}{j}), ({k}{l})");
                }
            }
        }
    }
}

#[test]
fn so4_round_trips_through_quaternion_pairs() {
    let mut r = rng(7800);
    for _ in 0..200 {
        let m = random_rotation::<4>(&mut r);
        let (q, p) = quaternions_from_so4(&m);
        assert!((norm(&q) - 1.0).abs() < 1e-14 && (norm(&p) - 1.0).abs() < 1e-14);
        assert!(max_diff(&so4_from_quaternions(&q, &p), &m) < 1e-13);
        let (q0, p0) = (random_quat(&mut r), random_quat(&mut r));
        let (q1, p1) = quaternions_from_so4(&so4_from_quaternions(&q0, &p0));
        let s = dot(&q0, &q1).signum();
        for k in 0..4 {
            assert!((q1[k] - s * q0[k]).abs() < 1e-13, "q up to the shared sign");
            assert!((p1[k] - s * p0[k]).abs() < 1e-13, "p with the same sign");
        }
    }
}

#[test]
fn slerp_so4_interpolates_frames_the_short_way() {
    let mut r = rng(7900);
    for _ in 0..50 {
        let (q0, p0, q1, p1) = (
            random_quat(&mut r),
            random_quat(&mut r),
            random_quat(&mut r),
            random_quat(&mut r),
        );
        let m0 = so4_from_quaternions(&q0, &p0);
        let m1 = so4_from_quaternions(&q1, &p1);
        let at = |t: f64, q1: &Quat, p1: &Quat| {
            let (q, p) = slerp_so4((&q0, &p0), (q1, p1), t);
            so4_from_quaternions(&q, &p)
        };
        assert!(max_diff(&at(0.0, &q1, &p1), &m0) < 1e-14);
        assert!(max_diff(&at(1.0, &q1, &p1), &m1) < 1e-13);
        // The lift of the second frame does not matter.
        let (nq1, np1) = (q1.map(|x| -x), p1.map(|x| -x));
        for t in [0.3, 0.6] {
            assert!(max_diff(&at(t, &q1, &p1), &at(t, &nq1, &np1)) < 1e-13);
            assert_rotation(&at(t, &q1, &p1), "slerp_so4");
        }
        // Short way: the chosen lift has the smaller total angle.
        let (q, p) = slerp_so4((&q0, &p0), (&q1, &p1), 1.0);
        let chosen = angle(&q0, &q).powi(2) + angle(&p0, &p).powi(2);
        let other = angle(&q0, &q.map(|x| -x)).powi(2) + angle(&p0, &p.map(|x| -x)).powi(2);
        assert!(chosen <= other + 1e-12);
        // Constant speed in both factors.
        let (qa, pa) = slerp_so4((&q0, &p0), (&q1, &p1), 0.2);
        let (qb, pb) = slerp_so4((&q0, &p0), (&q1, &p1), 0.7);
        assert!((angle(&qa, &qb) - 0.5 * angle(&q0, &q)).abs() < 1e-12);
        assert!((angle(&pa, &pb) - 0.5 * angle(&p0, &p)).abs() < 1e-12);
    }
}

#[test]
fn arcball_4d_maps_the_point_pairs() {
    let mut r = rng(8000);
    for _ in 0..50 {
        let (a0, a1, b0, b1) = (
            random_quat(&mut r),
            random_quat(&mut r),
            random_quat(&mut r),
            random_quat(&mut r),
        );
        let m = arcball_4d(&a0, &a1, &b0, &b1);
        assert_rotation(&m, "arcball_4d");
        let from = quat_mul(&a0, &quat_conjugate(&b0));
        let to = quat_mul(&a1, &quat_conjugate(&b1));
        assert!(norm(&sub(&mat_vec(&m, &from), &to)) < 1e-14);
        // b0 = b1: left multiplication, taking a0 to a1.
        let m = arcball_4d(&a0, &a1, &b0, &b0);
        assert!(norm(&sub(&mat_vec(&m, &a0), &a1)) < 1e-14);
        // Equal pure pairs: Shoemake's 3D arcball on axes 1–3, twice the arc about a0 × a1.
        let (u0, u1) = (random_unit::<3>(&mut r), random_unit::<3>(&mut r));
        let (x0, x1) = (pure(&u0), pure(&u1));
        let m = arcball_4d(&x0, &x1, &x0, &x1);
        assert!((m[0][0] - 1.0).abs() < 1e-15);
        let img: Vector<3> = std::array::from_fn(|k| (1..4).map(|l| m[k + 1][l] * u0[l - 1]).sum());
        let phi = angle(&u0, &u1);
        let w = add_scaled(&u1, -dot(&u0, &u1), &u0);
        let w = scale(&w, 1.0 / norm(&w));
        let want: Vector<3> =
            std::array::from_fn(|k| (2.0 * phi).cos() * u0[k] + (2.0 * phi).sin() * w[k]);
        assert!(norm(&sub(&img, &want)) < 1e-14);
    }
}

// -- validation --------------------------------------------------------------------------------

#[test]
fn validation_names_the_problem() {
    assert_eq!(unit_problem(&[1.0, 0.0, 0.0, 0.0], "quaternion", "q"), None);
    assert_eq!(
        unit_problem(&[1.3, 0.0, 0.0, 0.0], "quaternion", "p").unwrap(),
        "not a unit quaternion (|p| = 1.3)"
    );
    assert!(unit_problem(&[f64::NAN, 0.0], "vector", "v")
        .unwrap()
        .contains("non-finite"));
    let mut r = rng(8100);
    let refl = random_reflection::<5>(&mut r);
    assert!(check_rotation(&refl, "R")
        .unwrap_err()
        .to_string()
        .starts_with("R: is a reflection"));
    let mut m = random_rotation::<5>(&mut r);
    assert!(check_rotation(&m, "R").is_ok());
    m[1][2] += 1e-6;
    let e = check_rotation(&m, "R").unwrap_err().to_string();
    assert!(e.starts_with("R: not orthogonal"), "{e}");
    m[0][0] = f64::NAN;
    assert!(check_rotation(&m, "R")
        .unwrap_err()
        .to_string()
        .contains("non-finite"));
}
