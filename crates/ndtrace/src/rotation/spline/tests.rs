//! Splines through keys: interpolation, unit length, C¹ by finite differences, slerp for two
//! keys, SO(4) as the factors' splines, SO(N) orthonormal and equal to the quaternion form in 3D.

use super::*;
use crate::rotation::{quat_to_matrix, so4_from_quaternions};
use crate::testutil::rng;
use rand::Rng;

fn random_quat(r: &mut crate::testutil::TestRng) -> Quat {
    let q: Quat = std::array::from_fn(|_| r.random_range(-1.0..1.0));
    let n = norm(&q);
    q.map(|x| x / n)
}

fn keys_and_times(seed: u64, k: usize) -> (Vec<Quat>, Vec<f64>) {
    let mut r = rng(seed);
    let keys = (0..k).map(|_| random_quat(&mut r)).collect();
    let mut t = 0.0;
    let times = (0..k)
        .map(|_| {
            t += r.random_range(0.3..2.0);
            t
        })
        .collect();
    (keys, times)
}

fn dist(a: &Quat, b: &Quat) -> f64 {
    norm(&std::array::from_fn::<f64, 4, _>(|i| a[i] - b[i]))
}

#[test]
fn passes_through_every_key_with_unit_length() {
    let (keys, times) = keys_and_times(1, 6);
    let q = quaternion_spline(&keys, &times, &times, true).unwrap();
    let mut signed = keys.clone();
    crate::rotation::continuous_signs(&mut signed, 1);
    for (a, b) in q.iter().zip(&signed) {
        assert!(dist(a, b) < 1e-12, "{a:?} {b:?}");
    }
    let ts: Vec<f64> = (0..200)
        .map(|i| times[0] + (times[5] - times[0]) * i as f64 / 199.0)
        .collect();
    for q in quaternion_spline(&keys, &times, &ts, true).unwrap() {
        assert!((norm(&q) - 1.0).abs() < 1e-14);
    }
}

#[test]
fn is_c1_at_interior_keys() {
    let (keys, times) = keys_and_times(2, 5);
    let h = 1e-6;
    for &t in &times[1..4] {
        let q = quaternion_spline(
            &keys,
            &times,
            &[t - 2.0 * h, t - h, t, t + h, t + 2.0 * h],
            true,
        )
        .unwrap();
        // One-sided derivatives on each side agree (second-order differences).
        let left: Quat =
            std::array::from_fn(|c| (3.0 * q[2][c] - 4.0 * q[1][c] + q[0][c]) / (2.0 * h));
        let right: Quat =
            std::array::from_fn(|c| (-3.0 * q[2][c] + 4.0 * q[3][c] - q[4][c]) / (2.0 * h));
        assert!(
            dist(&left, &right) < 1e-4 * norm(&left).max(1.0),
            "{left:?} {right:?}"
        );
    }
}

#[test]
fn two_keys_give_the_slerp() {
    let (keys, times) = keys_and_times(3, 2);
    let mut b = keys[1];
    if dot(&keys[0], &b) < 0.0 {
        b = b.map(|x| -x);
    }
    for i in 0..=10 {
        let u = i as f64 / 10.0;
        let t = times[0] + u * (times[1] - times[0]);
        let q = quaternion_spline(&keys, &times, &[t], true).unwrap()[0];
        assert!(dist(&q, &slerp(&keys[0], &b, u)) < 1e-12);
    }
}

#[test]
fn so4_spline_is_the_double_quaternion_of_the_factor_splines() {
    let (mut left, times) = keys_and_times(4, 5);
    let (mut right, _) = keys_and_times(5, 5);
    crate::rotation::continuous_signs(&mut left, 1);
    crate::rotation::continuous_signs(&mut right, 1);
    let ts: Vec<f64> = (0..50)
        .map(|i| times[0] + (times[4] - times[0]) * i as f64 / 49.0)
        .collect();
    let m = so4_spline(&left, &right, &times, &ts).unwrap();
    let q = quaternion_spline(&left, &times, &ts, false).unwrap();
    let p = quaternion_spline(&right, &times, &ts, false).unwrap();
    for k in 0..ts.len() {
        let expected = so4_from_quaternions(&q[k], &p[k]);
        let r = m[k];
        assert!((det(&r) - 1.0).abs() < 1e-12);
        let rtr = mat_mul(&transpose(&r), &r);
        for i in 0..4 {
            for j in 0..4 {
                assert!((rtr[i][j] - f64::from(u8::from(i == j))).abs() < 1e-12);
                assert!((r[i][j] - expected[i][j]).abs() < 1e-14);
            }
        }
    }
}

#[test]
fn matrix_log_and_exp_are_inverse_on_rotations() {
    let mut r = rng(6);
    for _ in 0..20 {
        let m: Matrix<5> = crate::testutil::random_matrix(&mut r);
        let a: Matrix<5> = std::array::from_fn(|i| std::array::from_fn(|j| m[i][j] - m[j][i]));
        let rot = expm(&a.map(|x| x.map(|v| v * 0.4)));
        let back = expm(&logm(&rot));
        for i in 0..5 {
            for j in 0..5 {
                assert!((back[i][j] - rot[i][j]).abs() < 1e-10);
            }
        }
    }
}

#[test]
fn so_n_spline_is_orthonormal_through_its_keys_and_equals_the_quaternion_form_in_3d() {
    let (keys, times) = keys_and_times(7, 4);
    let mut q = keys.clone();
    crate::rotation::continuous_signs(&mut q, 1);
    let mats: Vec<Matrix<3>> = q.iter().map(quat_to_matrix).collect();
    let ts: Vec<f64> = (0..25)
        .map(|i| times[0] + (times[3] - times[0]) * i as f64 / 24.0)
        .collect();
    let a = so_n_spline(&mats, &times, &ts).unwrap();
    let b = quaternion_spline(&q, &times, &ts, true).unwrap();
    for (m, q) in a.iter().zip(&b) {
        let e = quat_to_matrix(q);
        for i in 0..3 {
            for j in 0..3 {
                assert!((m[i][j] - e[i][j]).abs() < 1e-9, "{m:?} {e:?}");
            }
        }
    }
    // In 5D: through the keys, orthonormal, det +1.
    let mut r = rng(8);
    let keys5: Vec<Matrix<5>> = (0..4)
        .map(|_| {
            let m: Matrix<5> = crate::testutil::random_matrix(&mut r);
            let a: Matrix<5> = std::array::from_fn(|i| std::array::from_fn(|j| m[i][j] - m[j][i]));
            expm(&a.map(|x| x.map(|v| v * 0.5)))
        })
        .collect();
    let at_keys = so_n_spline(&keys5, &times, &times).unwrap();
    for (a, b) in at_keys.iter().zip(&keys5) {
        assert!(a
            .iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(x, y)| (x - y).abs() < 1e-10));
    }
    for m in so_n_spline(&keys5, &times, &ts).unwrap() {
        assert!((det(&m) - 1.0).abs() < 1e-10);
    }
}

#[test]
fn bad_times_name_the_argument() {
    let (keys, _) = keys_and_times(9, 3);
    let arg = |e: NdError| match e {
        NdError::Value { arg, .. } => arg,
        e => panic!("{e}"),
    };
    assert_eq!(
        arg(quaternion_spline(&keys, &[0.0, 1.0, 1.0], &[0.5], true).unwrap_err()),
        "times"
    );
    assert_eq!(
        arg(quaternion_spline(&keys, &[0.0, f64::NAN, 2.0], &[0.5], true).unwrap_err()),
        "times"
    );
    assert_eq!(
        arg(quaternion_spline(&keys, &[0.0, 1.0], &[0.5], true).unwrap_err()),
        "times"
    );
    assert_eq!(
        arg(quaternion_spline(&keys[..1], &[0.0], &[0.5], true).unwrap_err()),
        "keys"
    );
}
