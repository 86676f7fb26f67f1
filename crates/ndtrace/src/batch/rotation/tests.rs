use super::*;

#[test]
fn batch_errors_name_argument_and_item() {
    let mut out = vec![0.0; 32];
    let q = [1.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0];
    let e = quat_to_matrix(&q, &mut out[..18]).unwrap_err().to_string();
    assert_eq!(e, "q: not a unit quaternion (|q| = 2) at batch index 1");
    let e = so4_from_quaternions(&q[..4], &q[4..], &mut out[..16])
        .unwrap_err()
        .to_string();
    assert_eq!(e, "p: not a unit quaternion (|p| = 2)");
    let e = rolling_ball(3, &[1.0, 2.0, 3.0], 1.0, RollingAngle::Arc, &mut out[..9])
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("displacement: expected shape"), "{e}");
    let e = rolling_ball(3, &[1.0, 2.0], 0.0, RollingAngle::Arc, &mut out[..9])
        .unwrap_err()
        .to_string();
    assert_eq!(e, "radius: must be a positive number, got 0");
    let e = plane_rotation(3, 1, 1, &[0.0], &mut out[..9])
        .unwrap_err()
        .to_string();
    assert!(e.contains("two different axes"), "{e}");
    let bad = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0];
    let e = matrix_to_quat(&bad, 0, &mut out[..4])
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("R: is a reflection"), "{e}");
}

#[test]
fn checks_and_rotation_between_name_the_item() {
    let e = plane_rotation(4, 2, 2, &[0.0], &mut [0.0; 16])
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "i, j: expected two different axes in 0..3 (dim = 4), got [2, 2]"
    );
    let a = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let b = [0.0, 1.0, 0.0, 0.0, 1.0, 1e-4];
    let e = rotation_between(3, &a, &b, &mut [0.0; 18])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("b: not a unit vector (|b| = 1.000000005") && e.ends_with("at batch index 1"),
        "{e}"
    );
    let mut out = [0.0; 18];
    rotation_between(3, &a, &[0.0, 1.0, 0.0, 0.0, -1.0, 0.0], &mut out).unwrap();
    let want = [0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
    assert!(
        out[..9]
            .iter()
            .zip(want)
            .all(|(x, y)| (x - y).abs() < 1e-15),
        "{out:?}"
    );
    // The antipodal pair turns by π in the plane of e_1 and e_0 (its least aligned axis).
    let want = [-1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0];
    assert!(
        out[9..]
            .iter()
            .zip(want)
            .all(|(x, y)| (x - y).abs() < 1e-15),
        "{out:?}"
    );
    assert!(check_units("q", &[1.0, 0.0, 0.0, 0.0], 4, "quaternion").is_ok());
    let e = check_units("q", &[1.0, 0.0, 0.0], 4, "quaternion")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("q: expected shape"), "{e}");
    let refl = [1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, -1.0];
    let e = check_rotations("R", 2, &refl).unwrap_err().to_string();
    assert_eq!(
        e,
        "R: is a reflection (det = −1), not a rotation (det = +1) at batch index 1"
    );
}

#[test]
fn continuity_runs_along_the_stride() {
    // Two interleaved tracks; each item is the canonical quaternion, flipped as needed.
    let rot = |th: f64| crate::rotation::plane_rotation::<3>(0, 1, th);
    let ms: Vec<Matrix<3>> = [3.0, 0.1, 3.3, 0.2].iter().map(|&t| rot(t)).collect();
    let flat: Vec<f64> = ms.iter().flat_map(|m| m.as_flattened().to_vec()).collect();
    let mut out = vec![0.0; 16];
    matrix_to_quat(&flat, 2, &mut out).unwrap();
    let q: Vec<&[f64]> = out.chunks(4).collect();
    let d = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    assert!(d(q[0], q[2]) > 0.9 && d(q[1], q[3]) > 0.9);
    // Without continuity, angle 3.3 > π comes back with q0 ≥ 0, opposite to angle 3.0's.
    matrix_to_quat(&flat, 0, &mut out).unwrap();
    let q: Vec<&[f64]> = out.chunks(4).collect();
    assert!(d(q[0], q[2]) < 0.0);
}
