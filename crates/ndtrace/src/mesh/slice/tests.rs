//! Slices checked against what they must be: the cube's polygons, the tesseract's and cross
//! polytope's sections as closed outward chains of the right volume, degenerate cuts.

use super::*;
use crate::shapes::{cross_polytope, hypercube};

/// Determinant of a small square matrix given as rows (Gaussian elimination, partial pivoting).
fn det_rows(mut a: Vec<Vec<f64>>) -> f64 {
    let n = a.len();
    let mut d = 1.0;
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        if a[p][c] == 0.0 {
            return 0.0;
        }
        if p != c {
            a.swap(p, c);
            d = -d;
        }
        d *= a[c][c];
        for r in c + 1..n {
            let f = a[r][c] / a[c][c];
            for k in c..n {
                a[r][k] -= f * a[c][k];
            }
        }
    }
    d
}

/// The (N−1)-volume the slice encloses: Σ N_s·y_0 / (N−1)! = Σ det[y_1−y_0 … | y_0] / (N−1)!
/// over its pieces (eq. 6's normal N_s; the cones from the origin of the hyperplane's
/// coordinates), positive for an outward slice.
fn enclosed_volume<const N: usize>(s: &Slice<N>) -> f64 {
    let y = s.coords();
    let m = N - 1;
    let fact: f64 = (1..=m).map(|k| k as f64).product();
    s.simplices
        .chunks(m)
        .map(|p| {
            let row = |i: u32| &y[i as usize * m..(i as usize + 1) * m];
            let mut rows: Vec<Vec<f64>> = p[1..]
                .iter()
                .map(|&i| row(i).iter().zip(row(p[0])).map(|(a, b)| a - b).collect())
                .collect();
            rows.push(row(p[0]).to_vec());
            det_rows(rows)
        })
        .sum::<f64>()
        / fact
}

/// The boundary of the slice as a chain: every (N−3)-face with its summed orientation; a
/// closed slice has none left.
fn open_faces<const N: usize>(s: &Slice<N>) -> usize {
    let mut sum: HashMap<Vec<u32>, i32> = HashMap::new();
    for p in s.simplices.chunks(N - 1) {
        for k in 0..p.len() {
            let face: Vec<u32> = (0..p.len()).filter(|&i| i != k).map(|i| p[i]).collect();
            let (sorted, parity) = sorted_with_parity(&face);
            let sign = if k % 2 == 0 { 1 } else { -1 };
            *sum.entry(sorted).or_default() += sign * parity;
        }
    }
    sum.values().filter(|&&v| v != 0).count()
}

#[test]
fn a_cube_sliced_across_an_axis_is_a_square() {
    let cube = hypercube::<3>();
    let plane = SlicePlane::<3>::new(&[0.0, 0.0, 2.0], 0.3).unwrap();
    assert_eq!(plane.basis, vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let s = slice(&cube, &plane);
    assert_eq!(open_faces(&s), 0);
    // The square [−1, 1]², outward: area +4.
    assert!(
        (enclosed_volume(&s) - 4.0).abs() < 1e-12,
        "{}",
        enclosed_volume(&s)
    );
    for p in &s.points {
        assert!((p[2] - 0.3).abs() < 1e-15);
    }
}

#[test]
fn a_cube_sliced_through_its_centre_diagonally_is_a_hexagon() {
    let cube = hypercube::<3>();
    let plane = SlicePlane::<3>::new(&[1.0, 1.0, 1.0], 0.0).unwrap();
    let s = slice(&cube, &plane);
    assert_eq!(open_faces(&s), 0);
    // The regular hexagon of side √2: area 3√3.
    assert!((enclosed_volume(&s) - 3.0 * 3f64.sqrt()).abs() < 1e-12);
    // Six corners on the cube's edges (and crossings of face diagonals between them).
    let corners = s.crossings.iter().filter(|c| c.t == 0.0).count();
    assert_eq!(corners, 0);
}

#[test]
fn a_tesseract_slice_is_a_closed_outward_cube() {
    let t = hypercube::<4>();
    let s = slice(
        &t,
        &SlicePlane::<4>::new(&[0.0, 0.0, 0.0, 1.0], 0.3).unwrap(),
    );
    assert_eq!(open_faces(&s), 0);
    assert!((enclosed_volume(&s) - 8.0).abs() < 1e-12);
}

#[test]
fn cuts_through_vertices_and_along_facets_give_no_degenerate_or_duplicate_pieces() {
    let t = hypercube::<4>();
    let check = |normal: &[f64], offset: f64, volume: Option<f64>| {
        let s = slice(&t, &SlicePlane::<4>::new(normal, offset).unwrap());
        assert_eq!(open_faces(&s), 0, "{normal:?} {offset}");
        if let Some(volume) = volume {
            let got = enclosed_volume(&s);
            assert!((got - volume).abs() < 1e-12, "{normal:?} {offset}: {got}");
        }
        // No piece repeats a vertex set, and none has zero area.
        let mut seen = std::collections::HashSet::new();
        let y = s.coords();
        for p in s.simplices.chunks(3) {
            assert!(seen.insert(sorted_with_parity(p).0), "duplicate piece");
            let v: Vec<[f64; 3]> = p
                .iter()
                .map(|&i| std::array::from_fn(|k| y[i as usize * 3 + k]))
                .collect();
            let e1 = sub(&v[1], &v[0]);
            let e2 = sub(&v[2], &v[0]);
            let c = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            assert!(norm(&c) > 1e-9, "zero-area piece");
        }
        // Output vertices are distinct points.
        for (i, a) in s.points.iter().enumerate() {
            for b in &s.points[..i] {
                assert!(norm(&sub(a, b)) > 1e-12, "duplicate vertex");
            }
        }
        s
    };
    // Through the facet w = 1: the limit from below is the facet itself, a cube.
    check(&[0.0, 0.0, 0.0, 1.0], 1.0, Some(8.0));
    // Touching the facet w = −1 from outside: nothing.
    assert!(check(&[0.0, 0.0, 0.0, 1.0], -1.0, Some(0.0)).is_empty());
    // Through the vertex (1, 1, 1, 1) only: nothing.
    assert!(check(&[1.0, 1.0, 1.0, 1.0], 4.0 / 2.0, Some(0.0)).is_empty());
    // Through the centre and eight vertices (x + y + z + w = 0): the section's volume, by the
    // convex hull in the Python tests; here closed and outward.
    let s = check(&[1.0, 1.0, 1.0, 1.0], 0.0, None);
    assert!(enclosed_volume(&s) > 0.0);
    // Through a ridge (x + y = 2 meets the tesseract in the square x = y = 1): zero volume.
    assert!(check(&[1.0, 1.0, 0.0, 0.0], 2f64.sqrt(), Some(0.0)).is_empty());
}

#[test]
fn the_cross_polytope_through_its_centre_is_an_octahedron() {
    let c = cross_polytope::<4>();
    // w = 0 meets it in the octahedron |x| + |y| + |z| ≤ 1 (volume 4/3), through six of its
    // vertices.
    let s = slice(
        &c,
        &SlicePlane::<4>::new(&[0.0, 0.0, 0.0, 1.0], 0.0).unwrap(),
    );
    assert_eq!(open_faces(&s), 0);
    assert!(
        (enclosed_volume(&s) - 4.0 / 3.0).abs() < 1e-12,
        "{}",
        enclosed_volume(&s)
    );
}

#[test]
fn values_are_interpolated_and_bad_input_names_its_argument() {
    let cube = hypercube::<3>();
    let v: Vec<f64> = cube.vertices.iter().flatten().copied().collect();
    let s: Vec<u32> = cube.simplices.iter().flatten().copied().collect();
    let z: Vec<f64> = cube.vertices.iter().map(|p| p[2]).collect();
    let r = slice_rows(3, &v, &s, &[0.0, 0.0, 1.0], 0.25, Some(&z)).unwrap();
    assert!(r.values.iter().all(|&x| (x - 0.25).abs() < 1e-15));
    assert_eq!(r.origin, vec![0.0, 0.0, 0.25]);
    let arg = |e: NdError| match e {
        NdError::Value { arg, .. } | NdError::Shape { arg, .. } => arg,
        e => panic!("{e}"),
    };
    assert_eq!(
        arg(slice_rows(3, &v, &s, &[0.0, 0.0, 0.0], 0.0, None).unwrap_err()),
        "normal"
    );
    assert_eq!(
        arg(slice_rows(3, &v, &s, &[0.0, f64::NAN, 1.0], 0.0, None).unwrap_err()),
        "normal"
    );
    assert_eq!(
        arg(slice_rows(3, &v, &s, &[0.0, 1.0], 0.0, None).unwrap_err()),
        "normal"
    );
    assert_eq!(
        arg(slice_rows(3, &v, &s, &[0.0, 0.0, 1.0], f64::INFINITY, None).unwrap_err()),
        "offset"
    );
    assert_eq!(
        arg(slice_rows(3, &v, &s, &[0.0, 0.0, 1.0], 0.0, Some(&z[1..])).unwrap_err()),
        "values"
    );
}
