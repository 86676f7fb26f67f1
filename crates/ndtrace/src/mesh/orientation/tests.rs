use super::*;
use crate::linalg::{mat_vec, Vector};
use crate::shapes::{cross_polytope, hypercube, simplex_boundary, sphere};
use crate::testutil::{for_each_dim, random_rotation, rng};
use rand::Rng;

/// N!·V of the whole mesh as it stands.
fn volume<const N: usize>(mesh: &Mesh<N>) -> f64 {
    let all: Vec<usize> = (0..mesh.simplices.len()).collect();
    enclosed_volume(mesh, &all, &vec![false; all.len()])
}

fn shapes<const N: usize>() -> Vec<Mesh<N>> {
    let mut list = vec![
        simplex_boundary::<N>(),
        hypercube::<N>(),
        cross_polytope::<N>(),
    ];
    if N <= 6 {
        list.push(sphere::<N>(1));
    }
    list
}

fn generated_shapes_are_closed_consistent_and_outward<const N: usize>() {
    for mesh in shapes::<N>() {
        let r = ridges(&mesh).unwrap();
        assert!(r.closed() && r.consistent(), "N = {N}");
        assert_eq!(r.pairs.len(), mesh.simplices.len() * N / 2);
        assert!(volume(&mesh) > 0.0);
        let repair = orient(&mesh).unwrap();
        assert_eq!(repair.flipped(), 0, "N = {N}");
        assert_eq!(inconsistency(&mesh), None);
    }
}

#[test]
fn generated_shapes_need_no_repair() {
    for_each_dim!(generated_shapes_are_closed_consistent_and_outward);
}

/// The ridges by brute force: every ridge's simplices in a map keyed by its sorted
/// vertices, the orientation each induces counted as the parity of the permutation that
/// sorts `(omitted slot, the other slots)`, by counting swaps of a bubble sort.
fn brute_force_ridges<const N: usize>(mesh: &Mesh<N>) -> Result<Ridges, OrientError> {
    use std::collections::BTreeMap;
    let mut by_ridge: BTreeMap<Vec<u32>, Vec<(u32, bool)>> = BTreeMap::new();
    let mut degenerate = vec![];
    for (i, idx) in mesh.simplices.iter().enumerate() {
        let mut distinct = idx.to_vec();
        distinct.sort();
        distinct.dedup();
        if distinct.len() < N {
            degenerate.push(i as u32);
            continue;
        }
        for k in 0..N {
            // The simplex's vertices with slot k moved to the front: parity k.
            let mut seq: Vec<u32> = std::iter::once(idx[k])
                .chain((0..N).filter(|&j| j != k).map(|j| idx[j]))
                .collect();
            let mut swaps = k;
            for end in (2..N).rev() {
                for j in 1..end {
                    if seq[j] > seq[j + 1] {
                        seq.swap(j, j + 1);
                        swaps += 1;
                    }
                }
            }
            by_ridge
                .entry(seq[1..].to_vec())
                .or_default()
                .push((i as u32, swaps % 2 == 1));
        }
    }
    let (mut pairs, mut boundary) = (vec![], vec![]);
    for (key, list) in by_ridge {
        match list[..] {
            [(a, _)] => boundary.push(a),
            [(a, x), (b, y)] => pairs.push((a.min(b), a.max(b), x != y)),
            _ => {
                return Err(OrientError::NonManifold {
                    ridge: key,
                    simplices: list.len(),
                })
            }
        }
    }
    pairs.sort();
    boundary.sort();
    Ok(Ridges {
        pairs,
        boundary,
        degenerate,
    })
}

/// `ridges` agrees with the brute force on closed shapes, on shapes with simplices removed,
/// flipped and shuffled, and on random soups over few vertices (non-manifold ridges,
/// repeated indices, vertices in no simplex), in every dimension.
#[test]
fn ridges_agree_with_a_brute_force() {
    fn check<const N: usize>() {
        let mut r = rng(70 + N as u64);
        let mut meshes = shapes::<N>();
        for base in shapes::<N>() {
            let mut m = base.clone();
            m.simplices.retain(|_| r.random_bool(0.8));
            for idx in &mut m.simplices {
                if r.random_bool(0.3) {
                    idx.swap(0, N - 1);
                }
            }
            for i in (1..m.simplices.len()).rev() {
                m.simplices.swap(i, r.random_range(0..=i));
            }
            meshes.push(m);
            // Closed, some simplices flipped: what the load-time check flags.
            let mut flipped = base.clone();
            flipped.simplices[0].swap(0, 1);
            for idx in &mut flipped.simplices {
                if r.random_bool(0.3) {
                    idx.swap(0, 1);
                }
            }
            meshes.push(flipped);
        }
        for soup in 0..40 {
            // N distinct vertices of few, in random order, one in ten with a repeat.
            let verts = N + 1 + soup % 3;
            let simplices = (0..r.random_range(1..3 * verts))
                .map(|_| {
                    let mut pool: Vec<u32> = (0..verts as u32).collect();
                    let mut idx = [0u32; N];
                    for slot in &mut idx {
                        *slot = pool.swap_remove(r.random_range(0..pool.len()));
                    }
                    if r.random_bool(0.1) {
                        idx[N - 1] = idx[0];
                    }
                    idx
                })
                .collect();
            meshes.push(Mesh {
                vertices: vec![[0.0; N]; verts + 2],
                simplices,
            });
        }
        let (mut errors, mut flags) = (0, 0);
        for (k, m) in meshes.iter().enumerate() {
            let want = brute_force_ridges(m);
            errors += usize::from(want.is_err());
            // The matching splits its work by the number of threads: one and several.
            for threads in [1, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let got = pool.install(|| ridges(m));
                assert_eq!(got, want, "N = {N}, mesh {k}, {threads} threads");
                // The load-time check counts what the lists hold.
                let flagged = want.as_ref().is_ok_and(|r| r.closed() && !r.consistent());
                let check = pool.install(|| inconsistency(m));
                assert_eq!(
                    check.is_some(),
                    flagged,
                    "N = {N}, mesh {k}, {threads} threads"
                );
                flags += usize::from(flagged);
            }
            // The repair does not depend on the order of the pairs.
            if let Ok(want) = &want {
                let mut shuffled = want.clone();
                for i in (1..shuffled.pairs.len()).rev() {
                    shuffled.pairs.swap(i, r.random_range(0..=i));
                }
                shuffled.boundary.reverse();
                assert_eq!(
                    orient_along(m, &shuffled),
                    orient_along(m, want),
                    "N = {N}, mesh {k}"
                );
            }
        }
        // The soups do meet non-manifold ridges, and the others do not.
        assert!(errors > 0 && errors < meshes.len(), "N = {N}: {errors}");
        assert!(flags > 0, "N = {N}: no closed mesh was inconsistent");
    }
    for_each_dim!(check);
}

/// The hypercube's enclosed volume is 2^N: V = Σ N·(x_0 − c)/N! is the divergence theorem.
#[test]
fn enclosed_volume_is_the_volume() {
    fn check<const N: usize>() {
        let v = volume(&hypercube::<N>()) / (1..=N).map(|k| k as f64).product::<f64>();
        assert!((v - 2f64.powi(N as i32)).abs() < 1e-9, "N = {N}: {v}");
    }
    for_each_dim!(check);
}

fn scrambled_meshes_are_repaired<const N: usize>() {
    let mut r = rng(40 + N as u64);
    for (k, mut mesh) in shapes::<N>().into_iter().enumerate() {
        // A rotated, shifted copy, then a random set of simplices flipped (a random swap).
        let m = random_rotation::<N>(&mut r);
        for v in &mut mesh.vertices {
            *v = add(&mat_vec(&m, v), &[0.3; N]);
        }
        let good = mesh.clone();
        let mut flipped = 0;
        for idx in &mut mesh.simplices {
            if r.random_bool(0.4) {
                let a = r.random_range(0..N);
                let b = (a + r.random_range(1..N)) % N;
                idx.swap(a, b);
                flipped += 1;
            }
        }
        if flipped == 0 {
            continue;
        }
        assert_eq!(
            inconsistency(&mesh),
            (flipped < mesh.simplices.len()).then_some((flipped, mesh.simplices.len())),
            "N = {N}, shape {k}"
        );
        let repair = orient(&mesh).unwrap();
        assert_eq!(repair.flipped(), flipped);
        repair.apply(&mut mesh);
        // Every simplex has the orientation of the original (the same normal).
        for s in 0..mesh.simplices.len() {
            let (a, b) = (
                simplex_normal(&mesh.simplex_points(s)),
                simplex_normal(&good.simplex_points(s)),
            );
            assert!(dot(&a, &b) > 0.0, "N = {N}, shape {k}, simplex {s}");
        }
        assert_eq!(orient(&mesh).unwrap().flipped(), 0);
    }
}

#[test]
fn scrambled_orientations_are_found_and_repaired() {
    for_each_dim!(scrambled_meshes_are_repaired);
}

#[test]
fn an_inward_mesh_is_turned_and_pieces_are_separate() {
    // Two tetrahedra's boundaries apart: one inward (consistent), one outward.
    let a = simplex_boundary::<3>();
    let mut mesh = a.clone();
    for idx in &mut mesh.simplices {
        idx.swap(1, 2);
    }
    let offset = mesh.vertices.len() as u32;
    mesh.vertices
        .extend(a.vertices.iter().map(|v| add(v, &[5.0, 0.0, 0.0])));
    mesh.simplices
        .extend(a.simplices.iter().map(|s| s.map(|i| i + offset)));
    // Consistent (each piece is), so no warning; orient turns the first piece.
    assert_eq!(inconsistency(&mesh), None);
    let repair = orient(&mesh).unwrap();
    assert_eq!(repair.pieces.len(), 2);
    assert_eq!(
        repair.pieces[0],
        Piece {
            simplices: 4,
            closed: true,
            consistent: true,
            flipped: 4
        }
    );
    assert_eq!(repair.pieces[1].flipped, 0);
}

#[test]
fn open_meshes_keep_the_majority_and_odd_meshes_are_errors() {
    // A strip of three triangles, the middle one reversed: it is flipped back.
    let v: Vec<Vector<3>> = (0..5)
        .map(|i| [i as f64 * 0.5, (i % 2) as f64, 0.0])
        .collect();
    let mut mesh = Mesh {
        vertices: v,
        simplices: vec![[0, 1, 2], [2, 1, 3], [2, 3, 4]],
    };
    mesh.simplices[1].swap(0, 1);
    let r = ridges(&mesh).unwrap();
    assert!(!r.closed() && !r.consistent());
    assert_eq!(inconsistency(&mesh), None); // open: no warning
    let repair = orient(&mesh).unwrap();
    assert_eq!(repair.flip, vec![false, true, false]);
    // Three triangles on one edge.
    let fan = Mesh {
        vertices: vec![
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0],
        ],
        simplices: vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    };
    assert_eq!(
        orient(&fan),
        Err(OrientError::NonManifold {
            ridge: vec![0, 1],
            simplices: 3
        })
    );
    // A Möbius strip of 5 triangles.
    let n = 5u32;
    let mob = Mesh {
        vertices: (0..n)
            .map(|i| {
                let t = i as f64;
                [t.cos(), t.sin(), 0.0]
            })
            .collect(),
        simplices: (0..n).map(|i| [i, (i + 1) % n, (i + 2) % n]).collect(),
    };
    assert!(matches!(
        orient(&mob),
        Err(OrientError::NonOrientable { .. })
    ));
    // A repeated index leaves its simplex out: the mesh is no longer closed.
    let mut tet = simplex_boundary::<3>();
    tet.simplices.push([0, 0, 1]);
    let r = ridges(&tet).unwrap();
    assert_eq!(r.degenerate, vec![4]);
    assert!(!r.closed() && r.consistent());
    assert_eq!(orient(&tet).unwrap().flip, vec![false; 5]);
}
