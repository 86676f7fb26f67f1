use super::*;
use crate::dim::MAX_POINTS;
use crate::geometry::{hyperplane, signed_volume};
use crate::linalg::factorial;
use crate::testutil::{for_each_dim, rng};
use rand::Rng;

/// Subdivision levels used per N (indexed by N), chosen to keep the tests fast.
const COUNT_SUBDIVISIONS: [u32; 9] = [0, 0, 6, 4, 3, 2, 1, 0, 0];
const CLOSED_SUBDIVISIONS: [u32; 9] = [0, 0, 4, 3, 2, 2, 1, 0, 0];
const VOLUME_SUBDIVISIONS: [u32; 9] = [0, 0, 6, 4, 3, 3, 1, 1, 0];

fn all_shapes<const N: usize>(sphere_subdivisions: u32) -> Vec<(String, Mesh<N>)> {
    vec![
        ("simplex".to_string(), simplex_boundary::<N>()),
        ("hypercube".to_string(), hypercube::<N>()),
        ("cross-polytope".to_string(), cross_polytope::<N>()),
        (
            format!("sphere({sphere_subdivisions})"),
            sphere::<N>(sphere_subdivisions),
        ),
    ]
}

/// Every (N−2)-face is shared by exactly two simplices that induce opposite orientations.
///
/// The face of `[v_0 … v_{N−1}]` opposite `v_j` carries the boundary orientation
/// `(−1)^j [v_0 … v̂_j … v_{N−1}]`; relative to the face's sorted vertex list that is the
/// parity of j plus the inversions of the remaining sequence — equivalently the parity of the
/// permutation that moves `v_j` to the front and sorts the rest. Two consistently oriented
/// neighbours must disagree on it.
fn check_closed_oriented<const N: usize>(mesh: &Mesh<N>) -> Result<(), String> {
    let mut faces: Vec<([u32; N], bool)> = Vec::with_capacity(mesh.simplices.len() * N);
    for (s, idx) in mesh.simplices.iter().enumerate() {
        if idx.iter().any(|&v| v as usize >= mesh.vertices.len()) {
            return Err(format!("simplex {s} {idx:?}: index out of range"));
        }
        for j in 0..N {
            let mut rest = [u32::MAX; N];
            for (slot, m) in (0..N).filter(|&m| m != j).enumerate() {
                rest[slot] = idx[m];
            }
            let mut inversions = 0;
            for p in 0..N - 1 {
                for q in p + 1..N - 1 {
                    if rest[p] == rest[q] {
                        return Err(format!("simplex {s} {idx:?}: repeated vertex"));
                    }
                    inversions += (rest[p] > rest[q]) as usize;
                }
            }
            rest.sort_unstable();
            faces.push((rest, (j + inversions) % 2 == 1));
        }
    }
    faces.sort_unstable();
    let mut i = 0;
    while i < faces.len() {
        let mut j = i;
        while j < faces.len() && faces[j].0 == faces[i].0 {
            j += 1;
        }
        if j - i != 2 {
            return Err(format!(
                "face {:?} shared by {} simplices",
                faces[i].0,
                j - i
            ));
        }
        if faces[i].1 == faces[i + 1].1 {
            return Err(format!(
                "face {:?}: neighbours induce the same orientation",
                faces[i].0
            ));
        }
        i = j;
    }
    Ok(())
}

/// No degenerate simplex, and every normal points away from the origin. Reports the first
/// offending simplex (checked in parallel: the N = 8 meshes have 80640 simplices).
fn check_outward<const N: usize>(mesh: &Mesh<N>) -> Result<(), String> {
    let bad = (0..mesh.simplices.len())
        .into_par_iter()
        .find_map_first(|s| {
            let p = mesh.simplex_points(s);
            let Ok(plane) = hyperplane(&p) else {
                return Some(format!("simplex {s} is degenerate: {p:?}"));
            };
            let centroid = p.iter().fold([0.0; N], |acc, x| add(&acc, x));
            // `hyperplane`'s unit normal has the direction of `simplex_normal` (eq. 6).
            (!(dot(&plane.normal, &centroid) > 0.0))
                .then(|| format!("simplex {s} points inward: {p:?}"))
        });
    bad.map_or(Ok(()), Err)
}

/// Divergence theorem: V = (−1)^(N−1) Σ V_N(0, x_0, …, x_{N−1}) (see the module docs).
fn enclosed_volume<const N: usize>(mesh: &Mesh<N>) -> f64 {
    let mut pts = [[0.0; N]; MAX_POINTS];
    let sum: f64 = (0..mesh.simplices.len())
        .map(|s| {
            pts[1..=N].copy_from_slice(&mesh.simplex_points(s));
            signed_volume(&pts[..=N])
        })
        .sum();
    if N % 2 == 1 {
        sum
    } else {
        -sum
    }
}

/// Volume of the unit N-ball, π^(N/2)/Γ(N/2 + 1), by V_n = 2π/n · V_(n−2).
fn unit_ball_volume(n: usize) -> f64 {
    match n {
        0 => 1.0,
        1 => 2.0,
        _ => 2.0 * std::f64::consts::PI / n as f64 * unit_ball_volume(n - 2),
    }
}

fn counts<const N: usize>() {
    let fact = factorial(N - 1) as usize;
    let m = simplex_boundary::<N>();
    assert_eq!(
        (m.vertices.len(), m.simplices.len()),
        (N + 1, N + 1),
        "N={N} simplex"
    );
    let m = hypercube::<N>();
    assert_eq!(
        (m.vertices.len(), m.simplices.len()),
        (1 << N, 2 * N * fact),
        "N={N} cube"
    );
    for v in &m.vertices {
        assert!(
            v.iter().all(|&c| c == 1.0 || c == -1.0),
            "N={N}: cube vertex {v:?}"
        );
    }
    let m = cross_polytope::<N>();
    assert_eq!(
        (m.vertices.len(), m.simplices.len()),
        (2 * N, 1 << N),
        "N={N} cross"
    );
    for s in 0..=COUNT_SUBDIVISIONS[N] {
        let k = 1usize << s;
        let m = sphere::<N>(s);
        let verts = (k + 1).pow(N as u32) - (k - 1).pow(N as u32);
        let simps = 2 * N * k.pow(N as u32 - 1) * fact;
        assert_eq!(m.vertices.len(), verts, "N={N} s={s}: sphere vertices");
        assert_eq!(m.simplices.len(), simps, "N={N} s={s}: sphere simplices");
        // Exact deduplication: every vertex is used and no two coincide.
        let mut used = vec![false; m.vertices.len()];
        m.simplices
            .iter()
            .flatten()
            .for_each(|&v| used[v as usize] = true);
        assert!(used.iter().all(|&u| u), "N={N} s={s}: unused vertex");
        let mut bits: Vec<[u64; N]> = m.vertices.iter().map(|v| v.map(f64::to_bits)).collect();
        bits.sort_unstable();
        bits.dedup();
        assert_eq!(bits.len(), verts, "N={N} s={s}: duplicate vertices");
    }
}

#[test]
fn vertex_and_simplex_counts_match_the_formulas() {
    for_each_dim!(counts);
    assert_eq!(hypercube::<4>().simplices.len(), 48);
    assert_eq!(sphere::<4>(2).simplices.len(), 3072);
}

fn lattice_numbering<const N: usize>() {
    for k in 1..=3u32 {
        let lattice = SurfaceLattice::<N>::new(k);
        let total = (k as usize + 1).pow(N as u32);
        let mut seen = vec![false; lattice.len as usize];
        for flat in 0..total {
            let mut rem = flat;
            let g: [u32; N] = std::array::from_fn(|_| {
                let d = rem % (k as usize + 1);
                rem /= k as usize + 1;
                d as u32
            });
            if !g.iter().any(|&c| c == 0 || c == k) {
                continue;
            }
            let i = lattice.index(&g) as usize;
            assert!(i < seen.len() && !seen[i], "N={N} k={k}: {g:?} -> {i}");
            seen[i] = true;
            let a = (0..N).find(|&b| g[b] == 0 || g[b] == k).unwrap();
            let side = (g[a] == k) as usize;
            let local = i as u32 - lattice.offset[a][side];
            assert_eq!(lattice.point(a, side, local), g, "N={N} k={k}: round trip");
        }
        assert!(seen.iter().all(|&s| s), "N={N} k={k}: numbering not onto");
    }
}

#[test]
fn surface_lattice_numbering_is_a_bijection() {
    for_each_dim!(lattice_numbering);
}

fn closed_and_oriented<const N: usize>() {
    for (name, mesh) in all_shapes::<N>(CLOSED_SUBDIVISIONS[N]) {
        check_closed_oriented(&mesh).unwrap_or_else(|e| panic!("N={N} {name}: {e}"));
        check_outward(&mesh).unwrap_or_else(|e| panic!("N={N} {name}: {e}"));
    }
}

#[test]
fn shapes_are_closed_consistently_oriented_nondegenerate_and_outward() {
    for_each_dim!(closed_and_oriented);
}

fn checkers_reject_broken_meshes<const N: usize>() {
    let mut r = rng(0x5ba9e5 + N as u64);
    // (Meshes over 50000 simplices, the N = 8 hypercube and sphere(0), are skipped for speed.)
    let shapes = all_shapes::<N>(1.min(CLOSED_SUBDIVISIONS[N]));
    for (name, mesh) in shapes
        .into_iter()
        .filter(|(_, m)| m.simplices.len() <= 50_000)
    {
        let s = r.random_range(0..mesh.simplices.len());
        let mut flipped = mesh.clone();
        flipped.simplices[s].swap(0, N - 1);
        assert!(
            check_closed_oriented(&flipped).is_err(),
            "N={N} {name}: flip undetected"
        );
        assert!(
            check_outward(&flipped).is_err(),
            "N={N} {name}: inward undetected"
        );
        let mut holed = mesh.clone();
        holed.simplices.swap_remove(s);
        assert!(
            check_closed_oriented(&holed).is_err(),
            "N={N} {name}: hole undetected"
        );
        let mut flat = mesh.clone();
        let i = flat.simplices[s][0] as usize;
        flat.vertices[i] = flat.vertices[flat.simplices[s][1] as usize];
        assert!(
            check_outward(&flat).is_err(),
            "N={N} {name}: degeneracy undetected"
        );
    }
}

#[test]
fn mesh_checkers_reject_flipped_missing_and_degenerate_simplices() {
    for_each_dim!(checkers_reject_broken_meshes);
}

fn volumes<const N: usize>() {
    let n = N as f64;
    let close = |got: f64, want: f64| (got - want).abs() <= 1e-10 * want;
    let cube = enclosed_volume(&hypercube::<N>());
    assert!(
        close(cube, 2f64.powi(N as i32)),
        "N={N}: cube volume {cube}"
    );
    let cross = enclosed_volume(&cross_polytope::<N>());
    assert!(
        close(cross, 2f64.powi(N as i32) / factorial(N)),
        "N={N}: cross {cross}"
    );
    // Regular simplex with circumradius 1: V = (N+1)^((N+1)/2) / (N!·N^(N/2)).
    let simplex = enclosed_volume(&simplex_boundary::<N>());
    let want = (n + 1.0).powf((n + 1.0) / 2.0) / (factorial(N) * n.powf(n / 2.0));
    assert!(close(simplex, want), "N={N}: simplex {simplex} vs {want}");

    // The inscribed sphere tessellations: s = 0 is the hypercube scaled by 1/√N; the volume
    // grows with s towards the ball's, with second-order convergence (error ~ k^(−2)).
    let ball = unit_ball_volume(N);
    let mut errors = vec![];
    for s in 0..=VOLUME_SUBDIVISIONS[N] {
        let v = enclosed_volume(&sphere::<N>(s));
        if s == 0 {
            let want = (2.0 / n.sqrt()).powi(N as i32);
            assert!(close(v, want), "N={N}: sphere(0) {v} vs {want}");
        }
        let err = (ball - v) / ball;
        assert!(
            err > 0.0,
            "N={N} s={s}: inscribed volume {v} exceeds the ball's {ball}"
        );
        if let Some(&prev) = errors.last() {
            assert!(err < prev, "N={N} s={s}: volume {v} did not grow");
            if s >= 3 {
                assert!(err < 0.35 * prev, "N={N} s={s}: error {err} vs {prev}");
            }
        }
        if s == 3 {
            // Relative error at k = 8 is about 0.7 %, 1.9 %, 3.3 %, 5.0 % for N = 2 … 5.
            let tol = [0.0, 0.0, 0.01, 0.025, 0.04, 0.06][N];
            assert!(
                err < tol,
                "N={N}: sphere(3) volume {v} vs ball {ball} ({err})"
            );
        }
        errors.push(err);
    }
}

#[test]
fn enclosed_volumes_by_the_divergence_theorem() {
    assert!((unit_ball_volume(3) - 4.0 / 3.0 * std::f64::consts::PI).abs() < 1e-15);
    assert!((unit_ball_volume(4) - std::f64::consts::PI.powi(2) / 2.0).abs() < 1e-15);
    for_each_dim!(volumes);
}

fn regular_simplex<const N: usize>() {
    let m = simplex_boundary::<N>();
    let mut sum = [0.0; N];
    for (i, a) in m.vertices.iter().enumerate() {
        sum = add(&sum, a);
        for (j, b) in m.vertices.iter().enumerate() {
            let want = if i == j { 1.0 } else { -1.0 / N as f64 };
            assert!(
                (dot(a, b) - want).abs() < 1e-14,
                "N={N}: v{i}·v{j} = {}",
                dot(a, b)
            );
        }
    }
    assert!(norm(&sum) < 1e-14, "N={N}: centroid {sum:?}");
}

#[test]
fn simplex_vertices_are_regular_and_on_the_unit_sphere() {
    for_each_dim!(regular_simplex);
}

fn normals<const N: usize>() {
    // Sphere: unit vertices, unit vertex normals within O(1/k) of radial (the lattice step
    // subtends about 2/k radians; the Kuhn triangulation is not symmetric, so the
    // area-weighted normal is off by a fraction of that: ~0.5/k at k = 8, ≤ 1/k before).
    for s in 0..=COUNT_SUBDIVISIONS[N] {
        let m = sphere::<N>(s);
        let vn = vertex_normals(&m);
        let mut max_angle: f64 = 0.0;
        for (x, nv) in m.vertices.iter().zip(&vn) {
            assert!(
                (norm(x) - 1.0).abs() < 1e-14,
                "N={N} s={s}: |x| = {}",
                norm(x)
            );
            assert!(
                (norm(nv) - 1.0).abs() < 1e-12,
                "N={N} s={s}: |n| = {}",
                norm(nv)
            );
            max_angle = max_angle.max(dot(x, nv).clamp(-1.0, 1.0).acos());
        }
        let k = f64::from(1u32 << s);
        let bound = if s >= 3 { 0.6 / k } else { 1.2 / k };
        assert!(
            max_angle < bound,
            "N={N} s={s}: vertex normal {max_angle} rad off radial"
        );
    }
    // The polytopes: unit vertex normals pointing away from the origin.
    for (name, m) in all_shapes::<N>(0)
        .into_iter()
        .filter(|(name, _)| name != "sphere(0)")
    {
        for (x, nv) in m.vertices.iter().zip(vertex_normals(&m)) {
            assert!(
                (norm(&nv) - 1.0).abs() < 1e-12,
                "N={N} {name}: |n| = {}",
                norm(&nv)
            );
            assert!(
                dot(x, &nv) > 0.0,
                "N={N} {name}: vertex normal points inward"
            );
        }
    }
    // By symmetry the simplex's and cross-polytope's vertex normals are radial.
    for m in [simplex_boundary::<N>(), cross_polytope::<N>()] {
        for (x, nv) in m.vertices.iter().zip(vertex_normals(&m)) {
            assert!((dot(x, &nv) - 1.0).abs() < 1e-12, "N={N}: not radial");
        }
    }
}

#[test]
fn vertex_normals_are_unit_and_radial_on_the_sphere() {
    for_each_dim!(normals);
}

fn zero_normal_sums<const N: usize>() {
    // The simplex (0, e_1, …, e_{N−1}) twice with opposite orientations, plus an unused
    // vertex: integer coordinates make the cancellation exact.
    let mut vertices = vec![[0.0; N]];
    for i in 0..N - 1 {
        let mut e = [0.0; N];
        e[i] = 1.0;
        vertices.push(e);
    }
    vertices.push([1.0; N]);
    let s: [u32; N] = std::array::from_fn(|i| i as u32);
    let mut t = s;
    t.swap(0, 1);
    let pair = Mesh {
        vertices: vertices.clone(),
        simplices: vec![s, t],
    };
    assert!(
        vertex_normals(&pair).iter().all(|n| *n == [0.0; N]),
        "N={N}: nonzero"
    );
    // A single simplex: its vertices get its unit normal +e_N·(sign), the unused one zero.
    let single = Mesh {
        vertices,
        simplices: vec![s],
    };
    let vn = vertex_normals(&single);
    let mut want = [0.0; N];
    want[N - 1] = 1.0;
    for v in 0..N {
        assert!(norm(&sub(&vn[v], &want)) < 1e-15, "N={N}: {:?}", vn[v]);
    }
    assert_eq!(vn[N], [0.0; N], "N={N}: unused vertex");
}

#[test]
fn vertex_normals_of_cancelling_or_unused_vertices_are_zero() {
    for_each_dim!(zero_normal_sums);
}

fn orientation_repair<const N: usize>() {
    let mut r = rng(0x0e1e7 + N as u64);
    // (The 80640-simplex N = 8 hypercube and sphere(0) are skipped for speed; their
    // orientation is checked by `shapes_are_closed_…`.)
    let shapes = all_shapes::<N>(1.min(CLOSED_SUBDIVISIONS[N]));
    for (name, mesh) in shapes
        .into_iter()
        .filter(|(_, m)| m.simplices.len() <= 50_000)
    {
        // Already outward: unchanged.
        let mut same = mesh.clone();
        orient_outward(&mut same, [0.0; N]);
        assert_eq!(
            same, mesh,
            "N={N} {name}: orient_outward changed an outward mesh"
        );
        // Random flips are undone exactly (swapping 0 and 1 twice is the identity).
        let mut flipped = mesh.clone();
        let mut count = 0;
        for s in &mut flipped.simplices {
            if r.random_bool(0.5) {
                s.swap(0, 1);
                count += 1;
            }
        }
        assert!(count > 0 || mesh.simplices.len() < 8);
        orient_outward(&mut flipped, [0.0; N]);
        assert_eq!(flipped, mesh, "N={N} {name}: flips not repaired");
        // A far-away center flips the facets facing it.
        let mut far = mesh.clone();
        let mut center = [0.0; N];
        center[0] = 100.0;
        orient_outward(&mut far, center);
        assert_ne!(far, mesh, "N={N} {name}: far center changed nothing");
    }
}

#[test]
fn orient_outward_repairs_random_flips() {
    for_each_dim!(orientation_repair);
}
