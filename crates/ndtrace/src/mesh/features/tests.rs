use super::*;
use crate::linalg::mat_vec;
use crate::mesh::Mesh;
use crate::shapes::{cross_polytope, hypercube, simplex_boundary, sphere};
use crate::testutil::{random_rotation, rng, TestRng};
use rand::Rng;

/// The mesh under a random rotation, with a random half of its simplices flipped (two ids
/// swapped) and its simplices shuffled: none of this may change its polytope structure.
fn scrambled<const N: usize>(mesh: &Mesh<N>, r: &mut TestRng) -> Mesh<N> {
    let rot = random_rotation::<N>(r);
    let vertices = mesh.vertices.iter().map(|v| mat_vec(&rot, v)).collect();
    let mut simplices = mesh.simplices.clone();
    for s in simplices.iter_mut() {
        if r.random_bool(0.5) {
            s.swap(0, 1);
        }
    }
    for i in (1..simplices.len()).rev() {
        let j = r.random_range(0..=i);
        simplices.swap(i, j);
    }
    Mesh {
        vertices,
        simplices,
    }
}

/// Every simplex with its own copies of its vertices (a mesh written face by face).
fn unwelded<const N: usize>(mesh: &Mesh<N>) -> Mesh<N> {
    let mut vertices = Vec::new();
    let mut simplices = Vec::new();
    for s in &mesh.simplices {
        simplices.push(std::array::from_fn(|k| {
            vertices.push(mesh.vertices[s[k] as usize]);
            vertices.len() as u32 - 1
        }));
    }
    Mesh {
        vertices,
        simplices,
    }
}

fn edges_of<const N: usize>(mesh: &Mesh<N>) -> Vec<[u32; 2]> {
    feature_edges(&mesh.vertices, &mesh.simplices, 20.0).unwrap()
}

fn binomial(n: usize, k: usize) -> usize {
    (0..k).fold(1, |acc, i| acc * (n - i) / (i + 1))
}

/// Regular polytopes in N = 3 … 8: the true edge counts and edges, under rotation, flipped
/// orientation, shuffling and unwelded vertices.
fn regular_polytopes<const N: usize>() {
    if N < 3 {
        return;
    }
    let mut r = rng(N as u64 + 300);
    // Hypercube: N·2^(N−1) edges, each joining corners that differ in one coordinate.
    let cube = hypercube::<N>();
    let e = edges_of(&cube);
    assert_eq!(e.len(), N << (N - 1), "N = {N}: hypercube edges");
    for [i, j] in &e {
        let (a, b) = (cube.vertices[*i as usize], cube.vertices[*j as usize]);
        let differ = (0..N).filter(|&k| a[k] != b[k]).count();
        assert_eq!(differ, 1, "N = {N}: {a:?}–{b:?} is not a cube edge");
    }
    // Cross-polytope: 2N(N−1) edges, between ±e_i and ±e_j for i ≠ j.
    let cross = cross_polytope::<N>();
    let e = edges_of(&cross);
    assert_eq!(e.len(), 2 * N * (N - 1), "N = {N}: cross-polytope edges");
    assert!(
        e.iter().all(|[i, j]| i / 2 != j / 2),
        "N = {N}: an antipodal pair"
    );
    // Simplex: every pair of its N + 1 vertices.
    assert_eq!(edges_of(&simplex_boundary::<N>()).len(), binomial(N + 1, 2));

    for mesh in [cube, cross] {
        let want = edges_of(&mesh);
        let s = scrambled(&mesh, &mut r);
        assert_eq!(edges_of(&s), want, "N = {N}: rotated, flipped and shuffled");
        let u = unwelded(&s);
        let got: Vec<[u32; 2]> = edges_of(&u)
            .iter()
            .map(|&[i, j]| {
                // Back to the welded ids through the coordinates.
                let id = |v: u32| {
                    s.vertices
                        .iter()
                        .position(|w| *w == u.vertices[v as usize])
                        .unwrap() as u32
                };
                let (a, b) = (id(i), id(j));
                [a.min(b), a.max(b)]
            })
            .collect();
        let mut got = got;
        got.sort_unstable();
        assert_eq!(got, want, "N = {N}: unwelded vertices");
    }
}

#[test]
fn regular_polytopes_give_their_true_edges() {
    crate::testutil::for_each_dim!(regular_polytopes);
}

#[test]
fn a_finely_tessellated_sphere_has_no_feature_edges() {
    assert!(edges_of(&sphere::<3>(4)).is_empty());
    assert!(edges_of(&sphere::<4>(3)).is_empty());
    assert!(edges_of(&crate::shapes::icosphere(3)).is_empty());
    // …but at a small enough crease angle its lattice creases appear.
    let s = sphere::<4>(1);
    assert!(!feature_edges(&s.vertices, &s.simplices, 1.0)
        .unwrap()
        .is_empty());
}

#[test]
fn open_meshes_have_their_boundary_as_creases() {
    // Two triangles of a flat square in 3D: the four sides, not the diagonal.
    let v = vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]];
    let s = vec![[0, 1, 2], [0, 2, 3]];
    assert_eq!(
        feature_edges(&v, &s, 20.0).unwrap(),
        vec![[0, 1], [0, 3], [1, 2], [2, 3]]
    );
    // A folded pair: the fold is a crease above the angle only.
    // A pair folded by 45° along 0–1: a crease at 20°, not at 60°.
    let v = vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., -1., 1.]];
    let s = vec![[0, 1, 2], [0, 3, 1]];
    assert!(feature_edges(&v, &s, 20.0).unwrap().contains(&[0, 1]));
    assert!(!feature_edges(&v, &s, 60.0).unwrap().contains(&[0, 1]));
}

#[test]
fn a_zero_volume_simplex_glues_the_ridges_it_touches() {
    // A cube face (z = 1) split at a vertex M on its edge 0–1: the neighbouring face (y = 0)
    // keeps the whole edge, so the triangulation meets M only through the zero-area triangle
    // (0, M, 1). Without it the face z = 1 would show a boundary along 0–M–1.
    let v = vec![
        [0., 0., 1.],  // 0
        [1., 0., 1.],  // 1
        [1., 1., 1.],  // 2
        [0., 1., 1.],  // 3
        [0.5, 0., 1.], // 4 = M, on the edge 0–1
        [0., 0., 0.],  // 5
        [1., 0., 0.],  // 6
    ];
    let s = vec![
        [0, 4, 3],
        [4, 2, 3],
        [4, 1, 2], // face z = 1 (through M)
        [0, 5, 6],
        [0, 6, 1], // face y = 0 (the whole edge 0–1)
        [0, 4, 1], // zero area
    ];
    let e = feature_edges(&v, &s, 20.0).unwrap();
    // The fold between the two faces is a crease (0–M, M–1 and 0–1 all lie on it); the inner
    // diagonals M–2, M–3 are not.
    assert!(
        e.contains(&[0, 1]) && e.contains(&[0, 4]) && e.contains(&[1, 4]),
        "{e:?}"
    );
    assert!(!e.contains(&[2, 4]) && !e.contains(&[3, 4]), "{e:?}");
}

#[test]
fn bad_input_names_the_argument() {
    let v = vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]];
    let err = feature_edges(&v, &[[0, 1, 5]], 20.0)
        .unwrap_err()
        .to_string();
    assert!(err.contains("simplices") && err.contains('5'), "{err}");
    let err = feature_edges(&v, &[[0, 1, 2]], 120.0)
        .unwrap_err()
        .to_string();
    assert!(err.contains("angle"), "{err}");
    let nan = vec![[0., 0., f64::NAN], [1., 0., 0.], [0., 1., 0.]];
    let err = feature_edges(&nan, &[[0, 1, 2]], 20.0)
        .unwrap_err()
        .to_string();
    assert!(err.contains("vertices") && err.contains('0'), "{err}");
}

/// Ridges found once give a moved mesh's feature edges bit for bit as a search from scratch
/// (rotations, a uniform scale and a shear, which changes the angles; zero-volume simplices and
/// unwelded vertices included), and do not fit a mesh whose welding or simplices changed.
fn ridges_of_a_moved_mesh<const N: usize>() {
    let mut r = rng(N as u64 + 900);
    let mut meshes = vec![cross_polytope::<N>()];
    if N <= 6 {
        meshes.extend([hypercube::<N>(), unwelded(&hypercube::<N>())]);
    }
    if N == 3 || N == 4 {
        meshes.push(sphere::<N>(2));
    }
    if (3..=6).contains(&N) {
        // A zero-volume simplex gluing ridges: the cube's first simplex repeated flat.
        let mut glued = hypercube::<N>();
        let first = glued.simplices[0];
        glued
            .simplices
            .push(std::array::from_fn(|k| first[k.min(N - 2)]));
        meshes.push(glued);
    }
    for mesh in &meshes {
        let ridges = Ridges::new(&mesh.vertices, &mesh.simplices).unwrap();
        for step in 0..4 {
            let m: crate::linalg::Matrix<N> = match step {
                0 => crate::linalg::identity(),
                1 | 2 => random_rotation::<N>(&mut r),
                _ => std::array::from_fn(|i| {
                    std::array::from_fn(|j| {
                        f64::from(u8::from(i == j)) + 0.7 * f64::from(u8::from(j == i + 1))
                    })
                }),
            };
            let scale = if step == 2 { 3.5 } else { 1.0 };
            let moved: Vec<_> = mesh
                .vertices
                .iter()
                .map(|v| crate::linalg::scale(&mat_vec(&m, v), scale))
                .collect();
            assert!(ridges.fits(&moved, &mesh.simplices), "N = {N} step {step}");
            for angle in [1.0, 20.0, 50.0] {
                assert_eq!(
                    ridges.feature_edges(&moved, angle).unwrap(),
                    feature_edges(&moved, &mesh.simplices, angle).unwrap(),
                    "N = {N} step {step} angle {angle}"
                );
            }
        }
        // Two distinct vertices made one: the welding changed.
        let mut merged = mesh.vertices.clone();
        merged[1] = merged[0];
        assert!(!ridges.fits(&merged, &mesh.simplices), "N = {N}");
        // Other simplices, fewer vertices, ids out of range: no fit (and no panic).
        let mut other = mesh.simplices.clone();
        other[0].swap(0, 1);
        assert!(!ridges.fits(&mesh.vertices, &other));
        assert!(!ridges.fits(&mesh.vertices[1..], &mesh.simplices));
        let mut out_of_range = mesh.simplices.clone();
        out_of_range[0][0] = mesh.vertices.len() as u32;
        assert!(!ridges.fits(&mesh.vertices, &out_of_range));
    }
}

#[test]
fn ridges_found_once_give_the_feature_edges_of_the_moved_mesh() {
    crate::testutil::for_each_dim!(ridges_of_a_moved_mesh);
}
