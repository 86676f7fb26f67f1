use super::*;
use crate::geometry::hyperplane;
use crate::linalg::mat_vec;
use crate::shapes::{cross_polytope, hypercube, icosphere, simplex_boundary, sphere};
use crate::testutil::{for_each_dim, random_rotation, random_vector, rng, TestRng};
use rand::Rng;

/// The normals of [`hyperplane`] (zero for a degenerate simplex).
fn normals<const N: usize>(mesh: &Mesh<N>) -> Vec<Vector<N>> {
    (0..mesh.simplices.len())
        .map(|i| hyperplane(&mesh.simplex_points(i)).map_or([0.0; N], |p| p.normal))
        .collect()
}

/// [`convex_side`] of a mesh not known to be convex.
fn certify<const N: usize>(mesh: &Mesh<N>) -> Option<bool> {
    convex_side(mesh, &normals(mesh), false)
}

/// The brute-force definition: every vertex on the body's side (up to 1e-10·D) of every
/// simplex's hyperplane: the side opposite n̂ (`Some(true)`), along n̂ (`Some(false)`), or
/// either, per simplex (`None`).
fn supported_everywhere<const N: usize>(mesh: &Mesh<N>, below: Option<bool>) -> bool {
    let (mut lo, mut hi) = ([f64::INFINITY; N], [f64::NEG_INFINITY; N]);
    for v in &mesh.vertices {
        for k in 0..N {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    let d = norm(&sub(&hi, &lo));
    (0..mesh.simplices.len()).all(|i| {
        let Ok(p) = hyperplane(&mesh.simplex_points(i)) else {
            return false;
        };
        let side = |out: f64| {
            mesh.vertices
                .iter()
                .all(|v| out * p.distance(v) <= 1e-10 * d)
        };
        match below {
            Some(b) => side(if b { 1.0 } else { -1.0 }),
            None => side(1.0) || side(-1.0),
        }
    })
}

fn flipped<const N: usize>(mut m: Mesh<N>) -> Mesh<N> {
    m.simplices.iter_mut().for_each(|s| s.swap(0, 1));
    m
}

/// `shape` and its image under a random affine map, each in both orientations, with the
/// side of the body for the first (outward) orientation flipped accordingly.
fn variants<const N: usize>(r: &mut TestRng, shape: Mesh<N>) -> Vec<(Mesh<N>, bool)> {
    let m = random_rotation::<N>(r);
    let stretch: Vector<N> = std::array::from_fn(|_| r.random_range(0.2..3.0));
    let shift = random_vector::<N>(r, 5.0);
    let mut moved = shape.clone();
    for v in &mut moved.vertices {
        let s: Vector<N> = std::array::from_fn(|i| v[i] * stretch[i]);
        *v = add(&mat_vec(&m, &s), &shift);
    }
    vec![
        (shape.clone(), true),
        (flipped(shape), false),
        (moved.clone(), true),
        (flipped(moved), false),
    ]
}

fn generated_shapes_are_convex<const N: usize>() {
    let mut r = rng(4100 + N as u64);
    // Strictly convex at every ridge: certified from the mesh alone. The hypercube's facets
    // are cut into coplanar simplices: convex by construction only.
    for (k, shape) in [
        simplex_boundary::<N>(),
        cross_polytope::<N>(),
        hypercube::<N>(),
    ]
    .into_iter()
    .enumerate()
    {
        for (mesh, below) in variants(&mut r, shape) {
            assert!(supported_everywhere(&mesh, Some(below)), "N={N} shape {k}");
            let n = normals(&mesh);
            assert_eq!(convex_side(&mesh, &n, true), Some(below), "N={N} shape {k}");
            let strict = k < 2 || N == 2;
            let want = strict.then_some(below);
            assert_eq!(convex_side(&mesh, &n, false), want, "N={N} shape {k}");
        }
    }
    // The lattice sphere is convex as a polygon, not beyond (reflex Kuhn diagonals).
    for s in 0..=[2, 2, 2, 2, 1, 0, 0][N - 2] {
        let sph = sphere::<N>(s);
        assert_eq!(certify(&sph), (N == 2).then_some(true), "N={N} sphere {s}");
        let brute = supported_everywhere(&sph, None);
        assert_eq!(brute, N == 2 || s == 0, "N={N} sphere {s}");
    }
}

#[test]
fn convex_generated_shapes_are_certified_in_every_dimension() {
    for_each_dim!(generated_shapes_are_convex);
    let mut r = rng(4199);
    for s in 0..4 {
        let ico = icosphere(s);
        assert_eq!(ico.simplices.len(), 20 << (2 * s));
        assert!(ico.vertices.iter().all(|v| (norm(v) - 1.0).abs() < 1e-15));
        for (mesh, below) in variants(&mut r, ico) {
            assert_eq!(certify(&mesh), Some(below), "icosphere {s}");
            assert!(supported_everywhere(&mesh, Some(below)), "icosphere {s}");
        }
    }
}

fn broken_shapes_are_rejected<const N: usize>() {
    let base = if N == 2 {
        sphere::<N>(2)
    } else {
        cross_polytope::<N>()
    };
    assert_eq!(certify(&base), Some(true), "N={N}");
    // Open: one simplex missing.
    let mut open = base.clone();
    open.simplices.pop();
    assert!(certify(&open).is_none(), "N={N} open");
    // One simplex turned over.
    let mut turned = base.clone();
    turned.simplices[1].swap(0, 1);
    assert!(certify(&turned).is_none(), "N={N} turned");
    // A dent: one vertex pushed through its neighbours' side of the centre.
    let mut dent = base.clone();
    let v = base.simplices[0][0] as usize;
    dent.vertices[v] = scale(&dent.vertices[v], if N == 2 { 0.5 } else { -0.2 });
    assert!(certify(&dent).is_none(), "N={N} dent");
    // Two disjoint copies, and two nested ones, as one mesh.
    for (shift, size) in [(3.0, 1.0), (0.0, 0.5)] {
        let mut two = base.clone();
        let first = two.vertices.len() as u32;
        two.vertices.extend(base.vertices.iter().map(|v| {
            let mut w = scale(v, size);
            w[0] += shift;
            w
        }));
        two.simplices
            .extend(base.simplices.iter().map(|s| s.map(|i| i + first)));
        assert!(certify(&two).is_none(), "N={N} two, shift {shift}");
    }
    // A degenerate simplex, and a sliver.
    let mut flat = simplex_boundary::<N>();
    flat.vertices.push(flat.vertices[0]);
    flat.simplices[0][1] = (flat.vertices.len() - 1) as u32;
    assert!(certify(&flat).is_none(), "N={N} degenerate");
    assert!(convex_side(&flat, &normals(&flat), true).is_none());
}

#[test]
fn open_turned_dented_doubled_and_degenerate_meshes_are_rejected() {
    for_each_dim!(broken_shapes_are_rejected);
}

/// Reorders `keep` onto the sampled positions j·S/SAMPLES (and probe 0's position 0), the
/// rest elsewhere: the quick sampled check then sees only `keep`.
fn dodge_samples<const N: usize>(keep: Vec<[u32; N]>, rest: Vec<[u32; N]>) -> Vec<[u32; N]> {
    let s = keep.len() + rest.len();
    let pos: std::collections::HashSet<usize> = (0..SAMPLES).map(|j| j * s / SAMPLES).collect();
    let (mut k, mut r) = (keep.into_iter(), rest.into_iter());
    (0..s)
        .map(|i| {
            if pos.contains(&i) {
                k.next().unwrap()
            } else {
                r.next().or_else(|| k.next()).unwrap()
            }
        })
        .collect()
}

#[test]
fn many_tiny_reflex_folds_are_rejected() {
    // A box whose top is a shallow trough of 20 000 strips: each fold is reflex by ~1e-10
    // of the box, the trough 0.05 deep; the sampled check only sees the other faces.
    let (k, a) = (20_000usize, 0.05);
    let mut prof: Vec<[f64; 2]> = (0..=k)
        .map(|i| {
            let x = -1.0 + 2.0 * i as f64 / k as f64;
            [x, -a * (1.0 - x * x)]
        })
        .collect();
    prof.push([1.0, -1.0]);
    prof.push([-1.0, -1.0]);
    let p = prof.len() as u32;
    let mut v: Vec<Vector<3>> = vec![];
    for y in [0.0, 1.0] {
        v.extend(prof.iter().map(|q| [q[0], y, q[1]]));
    }
    let (mut trough, mut other) = (vec![], vec![]);
    for i in 0..p {
        let j = (i + 1) % p;
        let quad = [[i, j, j + p], [i, j + p, i + p]];
        if (i as usize) < k {
            trough.extend(quad)
        } else {
            other.extend(quad)
        }
    }
    let b = p - 1;
    for off in [0, p] {
        for i in 0..p - 2 {
            other.push([b + off, i + off, i + 1 + off]);
        }
    }
    let cen = [0.0, 0.5, -0.5];
    for t in trough.iter_mut().chain(other.iter_mut()) {
        let pts = [v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]];
        if hyperplane(&pts).unwrap().distance(&cen) > 0.0 {
            t.swap(0, 1);
        }
    }
    let mesh = Mesh {
        vertices: v,
        simplices: dodge_samples(other, trough),
    };
    assert!(!supported_everywhere(&mesh, Some(true)));
    assert!(certify(&mesh).is_none());
}

#[test]
fn doubly_wound_polygons_are_rejected() {
    // A pentagram: every edge faces away from the centre and turns the same way (closed,
    // consistently oriented, locally convex), but it winds twice around the centre.
    let n = 5;
    let vertices: Vec<Vector<2>> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [a.cos(), a.sin()]
        })
        .collect();
    let star = |step: usize| Mesh {
        vertices: vertices.clone(),
        simplices: (0..n)
            .map(|i| [((i * step) % n) as u32, (((i + 1) * step) % n) as u32])
            .collect(),
    };
    assert!(certify(&star(1)).is_some() && certify(&flipped(star(1))).is_some());
    assert!(certify(&star(2)).is_none());
    assert!(certify(&flipped(star(2))).is_none());
    // r = 1 + 0.1·cos(φ/2), φ in [0, 4π): a smooth, locally convex curve winding twice.
    // The sampled edges and probe 0 lie on the outer sheet near φ = 0, so only the degree
    // of the projection (step 4) can tell; some variants put the edge of the inner sheet
    // that probe 0 crosses on a coordinate axis (a box of zero width).
    let n = 2001;
    let v: Vec<Vector<2>> = (0..n)
        .map(|i| {
            let f = 4.0 * std::f64::consts::PI * i as f64 / n as f64;
            let r = 1.0 + 0.1 * (f / 2.0).cos();
            [r * f.cos(), r * f.sin()]
        })
        .collect();
    let edges: Vec<[u32; 2]> = (0..n as u32).map(|i| [i, (i + 1) % n as u32]).collect();
    let w = n / 40;
    for first in 0..20 {
        let mut keep = vec![edges[first]];
        keep.extend(
            (0..w)
                .chain(n - w..n)
                .filter(|&i| i != first)
                .map(|i| edges[i]),
        );
        let rest = (w..n - w)
            .filter(|&i| i != first)
            .map(|i| edges[i])
            .collect();
        let simplices = dodge_samples(keep, rest);
        assert_eq!(simplices[0], edges[first]);
        // Rotate so that the other sheet's edge near the probe's direction is horizontal.
        let (a, b) = (v[first], v[first + 1]);
        let dir = scale(&add(&a, &b), 0.5);
        let g = (w..n - w)
            .min_by(|&i, &j| {
                let ang = |e: usize| {
                    let m = scale(&add(&v[e], &v[(e + 1) % n]), 0.5);
                    -dot(&m, &dir) / (norm(&m) * norm(&dir))
                };
                ang(i).total_cmp(&ang(j))
            })
            .unwrap();
        let (p, q) = (v[g], v[(g + 1) % n]);
        let ang = (q[1] - p[1]).atan2(q[0] - p[0]);
        let (co, si) = (ang.cos(), ang.sin());
        let mut moved: Vec<Vector<2>> = v
            .iter()
            .map(|x| {
                [
                    co * x[0] + si * x[1],
                    -si * x[0] + co * x[1] - (-si * p[0] + co * p[1]),
                ]
            })
            .collect();
        if first % 2 == 1 {
            moved[g][1] = 0.0;
            moved[(g + 1) % n][1] = 0.0;
        }
        let mesh = Mesh {
            vertices: moved,
            simplices,
        };
        assert!(certify(&mesh).is_none(), "first {first}");
    }
}

/// Polytopes with randomly moved vertices (a 24-gon in 2D, the 2-times subdivided
/// icosphere, cross-polytopes), some convex and some not: the certificate agrees with the
/// brute-force definition both ways.
fn perturbed_shapes_agree_with_brute_force<const N: usize>(base: &Mesh<N>, amps: [f64; 4]) {
    let mut r = rng(4200 + N as u64 + base.simplices.len() as u64);
    let (mut yes, mut no) = (0, 0);
    for case in 0..60 {
        let amp = amps[case % 4];
        let mut mesh = base.clone();
        for v in &mut mesh.vertices {
            *v = add(v, &random_vector::<N>(&mut r, amp));
        }
        let got = certify(&mesh);
        assert_eq!(
            got.is_some(),
            supported_everywhere(&mesh, None),
            "N={N} case {case} amplitude {amp}"
        );
        if got.is_some() {
            assert!(supported_everywhere(&mesh, got));
            yes += 1;
        } else {
            no += 1;
        }
    }
    let s = base.simplices.len();
    assert!(
        yes > 5 && no > 5,
        "N={N}, {s} simplices: {yes} convex, {no} not"
    );
}

#[test]
fn convexity_certificate_agrees_with_brute_force_on_perturbed_shapes() {
    let polygon = Mesh::<2> {
        vertices: (0..24)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / 24.0;
                [a.cos(), a.sin()]
            })
            .collect(),
        simplices: (0..24).map(|i| [i, (i + 1) % 24]).collect(),
    };
    perturbed_shapes_agree_with_brute_force(&polygon, [0.0, 0.001, 0.01, 0.05]);
    perturbed_shapes_agree_with_brute_force(&icosphere(2), [0.0, 0.001, 0.01, 0.05]);
    let amps = [0.0, 0.3, 0.6, 0.9];
    perturbed_shapes_agree_with_brute_force(&cross_polytope::<3>(), amps);
    perturbed_shapes_agree_with_brute_force(&cross_polytope::<4>(), amps);
    perturbed_shapes_agree_with_brute_force(&cross_polytope::<5>(), amps);
    perturbed_shapes_agree_with_brute_force(&cross_polytope::<6>(), amps);
}
