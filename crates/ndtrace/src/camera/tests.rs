use super::*;
use crate::linalg::{det, mat_mul, transpose};
use crate::testutil::*;

fn look_at_frame<const N: usize>() {
    let mut r = rng(900 + N as u64);
    for _ in 0..50 {
        let p = random_vector::<N>(&mut r, 5.0);
        let t = random_vector::<N>(&mut r, 5.0);
        let up: Vec<Vector<N>> = random_points(&mut r, N - 2, 1.0);
        let o = look_at_orientation(&p, &t, &up).unwrap();
        // Orthonormal.
        let g = mat_mul(&transpose(&o), &o);
        for i in 0..N {
            for j in 0..N {
                assert!((g[i][j] - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        // det[u_1 … u_{N−1}, −view] = +1, i.e. det(O) = −1.
        assert!((det(&o) + 1.0).abs() < 1e-12, "N={N}: det {}", det(&o));
        // The last column is the normalized view direction.
        let v = sub(&t, &p);
        for i in 0..N {
            assert!((o[i][N - 1] - v[i] / norm(&v)).abs() < 1e-12);
        }
        // u_2 lies in the plane of view and up[0], on up[0]'s side.
        if N > 2 {
            let u2: Vector<N> = std::array::from_fn(|i| o[i][1]);
            assert!(dot(&u2, &up[0]) > 0.0);
        }
    }
}

#[test]
fn look_at_frames_in_every_dimension() {
    for_each_dim!(look_at_frame);
}

/// [`CentreRays`] gives, bit for bit, the ray of [`Camera::cell_point`] at the centre then
/// [`Camera::ray`], for every cell of small retinas of unequal sides, both projections and
/// random frames.
fn centre_rays_match<const N: usize>() {
    let mut r = rng(950 + N as u64);
    for projection in [Projection::Perspective, Projection::Orthographic] {
        let cam = Camera::<N> {
            position: random_vector(&mut r, 3.0),
            orientation: random_rotation(&mut r),
            projection,
            cell: 0.37,
            resolution: (0..N - 1).map(|k| [5, 4, 1, 3][k % 4]).collect(),
        };
        let rays = CentreRays::new(&cam);
        let (mut idx, mut u) = ([0; N], [0.0; N]);
        for cell in 0..cam.cell_count() {
            cam.cell_index(cell, &mut idx);
            cam.cell_point(&idx, &[0.5; N][..N - 1], &mut u);
            let (a, b) = (rays.ray(&idx), cam.ray(&u[..N - 1]));
            let bits = |v: &Vector<N>| v.map(f64::to_bits);
            assert_eq!(
                bits(&a.origin),
                bits(&b.origin),
                "N={N} {projection:?} cell {cell}"
            );
            assert_eq!(
                bits(&a.dir),
                bits(&b.dir),
                "N={N} {projection:?} cell {cell}"
            );
        }
    }
}

#[test]
fn centre_rays_are_the_rays_through_cell_centres() {
    for_each_dim!(centre_rays_match);
}

#[test]
fn three_d_look_at_is_the_usual_camera() {
    let o = look_at_orientation(&[0.0, 0.0, 5.0], &[0.0, 0.0, 0.0], &[[0.0, 1.0, 0.0]]).unwrap();
    // right = +x, up = +y, view = −z.
    assert_eq!(o, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]);
    assert_eq!(
        look_at_orientation(&[0.0; 3], &[0.0; 3], &[[0.0, 1.0, 0.0]]),
        Err(None)
    );
    assert_eq!(
        look_at_orientation(&[0.0; 3], &[0.0, 1.0, 0.0], &[[0.0, 2.0, 0.0]]),
        Err(Some(0))
    );
}

#[test]
fn cells_are_centred_and_rows_go_down() {
    let cam = Camera::<3> {
        position: [0.0, 0.0, 0.0],
        orientation: crate::linalg::identity(),
        projection: Projection::Orthographic,
        cell: 0.5,
        resolution: vec![4, 2],
    };
    let mut u = [0.0; 3];
    cam.retina_point(0, &[0.5, 0.5], &mut u);
    assert_eq!(&u[..2], &[-0.75, 0.25]); // top-left cell
    cam.retina_point(7, &[0.5, 0.5], &mut u);
    assert_eq!(&u[..2], &[0.75, -0.25]); // bottom-right cell
    assert_eq!(cam.numpy_shape(), vec![2, 4]);
}
