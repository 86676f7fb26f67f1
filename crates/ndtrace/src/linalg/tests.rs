use super::*;
use crate::testutil::{for_each_dim, random_matrix, random_rotation, random_vector, rng};

fn det_and_solve_agree<const N: usize>() {
    let mut r = rng(N as u64);
    for _ in 0..50 {
        let a = random_matrix::<N>(&mut r);
        let x = random_vector::<N>(&mut r, 1.0);
        let b = mat_vec(&a, &x);
        let y = solve_block(a, b, N).unwrap();
        for i in 0..N {
            assert!((x[i] - y[i]).abs() < 1e-8, "N={N}: solve {x:?} vs {y:?}");
        }
        // The rows of inverse_rows_block are solve_block's solutions for the unit vectors,
        // bit for bit, in every leading block.
        for k in 1..=N {
            let inv = inverse_rows_block(a, k).unwrap();
            for j in 0..k {
                let mut unit = [0.0; N];
                unit[j] = 1.0;
                let y = solve_block(a, unit, k).unwrap();
                assert_eq!(inv[j][..k], y[..k], "N={N}, k={k}, row {j}");
            }
        }
        // det(a)·a^(−1) = adj(a) = cof(a)^T, so a · cof(a)^T = det(a)·I.
        let d = det(&a);
        let p = mat_mul(&a, &transpose(&cofactor_matrix(&a)));
        for i in 0..N {
            for j in 0..N {
                let want = if i == j { d } else { 0.0 };
                assert!((p[i][j] - want).abs() < 1e-9 * (1.0 + d.abs()), "N={N}");
            }
        }
        // det is multiplicative and rotations have det +1.
        let q = random_rotation::<N>(&mut r);
        assert!((det(&q) - 1.0).abs() < 1e-12);
        assert!((det(&mat_mul(&q, &a)) - d).abs() < 1e-9 * (1.0 + d.abs()));
    }
}

#[test]
fn determinants_solves_and_cofactors_in_every_dimension() {
    for_each_dim!(det_and_solve_agree);
}

#[test]
fn singular_systems_are_reported() {
    let a: Matrix<3> = [[1., 2., 3.], [2., 4., 6.], [0., 0., 1.]];
    assert_eq!(det(&a), 0.0);
    assert!(solve_block(a, [1., 2., 3.], 3).is_none());
    assert!(inverse_rows_block(a, 3).is_none());
}
