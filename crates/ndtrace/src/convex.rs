//! Convexity certificates: which meshes bound a convex body, so that a shadow ray leaving one of
//! their simplices on the outer side can never meet them again.
//!
//! If K is convex and F one of its facets, K lies in the closed inner half-space of F's
//! hyperplane (section "Clipping": every vertex is on the inner side of every facet), so a ray
//! that starts on F's plane and runs into the open outer half-space never meets K again: a
//! shadow ray from a hit on F toward a light on F's outer side needs no test against K (see
//! [`crate::render`]). [`convex_side`] decides this for a mesh, in time O(S·N²) for meshes
//! whose vertices each lie in a bounded number of simplices.
//!
//! The generated simplex, hypercube and cross-polytope are convex by construction, and an
//! affine map keeps them so (up to the rounding of the mapped coordinates, ~10⁻¹⁶ of the scene,
//! far below the 2·10⁻⁷ by which shadow rays leave the surface); for them only step 1 runs. Any
//! other mesh must pass every step, each decided with a margin far above rounding error:
//!
//! 1. **Star-shaped, strictly.** An interior point c (the mean of the simplex centroids) lies
//!    on the same side of every simplex's hyperplane (`h = n̂·(c − x_0)`, eq. 11), by at least
//!    `MARGIN` times the mesh's diameter D; and no simplex is a sliver (`|n̂ × unit edges|`,
//!    the degeneracy measure of eq. 8, at least `QUALITY`), so that every normal is accurate.
//!    A quick necessary check follows: every vertex on the inner side of a few sampled planes.
//! 2. **Closed and consistently oriented.** Every ridge (set of N−1 vertex indices) belongs to
//!    exactly two simplices, and they induce opposite orientations on it (the orientation of a
//!    simplex is the order of its vertices, eq. 6).
//! 3. **Strictly convex at every ridge.** The vertex of either simplex opposite the ridge lies
//!    inside the other simplex's hyperplane by more than `STRICT`·D. No tolerance is granted
//!    the other way: coplanar or slightly reflex ridges fail, since tiny reflex folds could add
//!    up to a real dent over many ridges.
//! 4. **Covers once.** By 1, the radial projection from c maps the (closed, by 2) mesh onto
//!    the sphere of directions preserving orientation at every simplex, so the number of
//!    simplices a ray from c crosses is the same for every ray that avoids ridges (the map's
//!    degree); it must be 1. A ray from c through the centroid of a simplex is used; if it
//!    passes within `EDGE` (barycentric) of another simplex's boundary, another is tried.
//!
//! With 2 and 4 the projection is a homeomorphism (no folds, no branch points, no second
//! sheet: a doubly wound polygon or two nested spheres fail), so the mesh is an embedded
//! hypersurface, star-shaped about c; an embedded closed hypersurface that is convex at every
//! ridge is convex at every point (the links of its lower faces are locally convex, hence convex,
//! spherical polytopes), and a closed connected locally convex set is convex (Tietze–Nakajima).

use crate::geometry::{barycentric, generalized_cross, Hyperplane};
use crate::linalg::{add, dot, norm, scale, sub, Vector};
use crate::mesh::{orientation::matched_ridges, Mesh};
use rayon::prelude::*;

/// The interior point must lie at least `MARGIN`·D inside every simplex's hyperplane.
pub const MARGIN: f64 = 1e-9;
/// At every ridge, the opposite vertices must lie more than `STRICT`·D inside the neighbour's
/// hyperplane (far above the ~10⁻¹³·D error of the computed distance for a non-sliver).
pub const STRICT: f64 = 1e-11;
/// Smallest degeneracy measure `W_{N−1}/Π|e_k|` (eq. 8 over unit edges) of a simplex.
pub const QUALITY: f64 = 1e-4;
/// A probe ray that meets a hyperplane within `EDGE` (barycentric) of its simplex's boundary is
/// too close to a ridge to count on.
pub const EDGE: f64 = 1e-9;

/// Probe rays tried before giving up on a mesh whose every probe grazes a ridge.
const PROBES: usize = 8;
/// Simplices whose hyperplanes every vertex is checked against first.
const SAMPLES: usize = 32;

/// Which side of its simplices' hyperplanes the mesh's body lies on, when the mesh bounds a
/// convex body: `Some(true)` when the body lies on the side opposite every `normals[i]`
/// (outward normals), `Some(false)` when on their side (inward normals), `None` when the mesh is
/// not, or cannot be shown to be, the consistently oriented boundary of a convex body (see the
/// module docs). A ray from a point of simplex i into the open half-space away from the body
/// never meets the mesh again.
///
/// `normals[i]` is the unit normal n̂ of simplex i (eq. 6; zero when it is degenerate, which
/// makes the mesh fail). `known_convex`: the mesh is an affine image of a convex generated
/// shape, so only step 1's sides are checked.
///
/// # Panics
/// If `normals` and the simplices differ in length, or an index is out of range.
pub fn convex_side<const N: usize>(
    mesh: &Mesh<N>,
    normals: &[Vector<N>],
    known_convex: bool,
) -> Option<bool> {
    let s = &mesh.simplices;
    assert_eq!(
        s.len(),
        normals.len(),
        "convex_side: one normal per simplex"
    );
    if s.len() < N + 1 {
        return None;
    }
    // The centre and the diameter, summed in simplex order (the same bits for any number of
    // threads).
    let mut sum = [0.0; N];
    let (mut lo, mut hi) = ([f64::INFINITY; N], [f64::NEG_INFINITY; N]);
    for idx in s {
        for &v in idx {
            let x = &mesh.vertices[v as usize];
            sum = add(&sum, x);
            for k in 0..N {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
    }
    let c = scale(&sum, 1.0 / (s.len() * N) as f64);
    let d = norm(&sub(&hi, &lo));
    if !(d > 0.0 && d.is_finite()) {
        return None;
    }
    // 1. Every hyperplane has c strictly on the same side: `out` turns n̂ outward.
    let planes: Vec<Hyperplane<N>> = normals
        .par_iter()
        .zip(s)
        .map(|(&normal, idx)| Hyperplane {
            normal,
            offset: dot(&normal, &mesh.vertices[idx[0] as usize]),
        })
        .collect();
    let out = if planes[0].distance(&c) < 0.0 {
        1.0
    } else {
        -1.0
    };
    if !planes
        .par_iter()
        .all(|p| out * p.distance(&c) < -MARGIN * d)
    {
        return None;
    }
    let below = out > 0.0;
    if known_convex {
        return Some(below);
    }
    if !(0..s.len())
        .into_par_iter()
        .all(|i| quality(&mesh.simplex_points(i)) >= QUALITY)
    {
        return None;
    }
    // A quick necessary condition, which most non-convex meshes fail before the ridge sort:
    // every vertex (used or not) inside the hyperplanes of a few simplices spread over the mesh.
    let strict = STRICT * d;
    let sample: Vec<&Hyperplane<N>> = (0..SAMPLES)
        .map(|j| &planes[j * s.len() / SAMPLES])
        .collect();
    if !mesh
        .vertices
        .par_iter()
        .all(|v| sample.iter().all(|p| out * p.distance(v) <= strict))
    {
        return None;
    }
    // 2 and 3. Every ridge of exactly two simplices that agree on it (`matched_ridges`), and the
    // vertex of each opposite their ridge (the one the other lacks) strictly inside the other's
    // hyperplane.
    let r = matched_ridges(mesh).ok()?;
    if !r.closed() {
        return None;
    }
    let convex_pair = |a: usize, b: usize| {
        let lacked = s[b].iter().find(|v| !s[a].contains(v));
        lacked.is_some_and(|&v| out * planes[a].distance(&mesh.vertices[v as usize]) < -strict)
    };
    let ok = r.pairs.par_iter().all(|&(a, b, agree)| {
        let (a, b) = (a as usize, b as usize);
        agree && convex_pair(a, b) && convex_pair(b, a)
    });
    drop(r);
    if !ok {
        return None;
    }
    // 4. The degree of the radial projection, from rays through simplex centroids.
    for probe in 0..PROBES {
        let f = probe * s.len() / PROBES;
        let pts = mesh.simplex_points(f);
        let centroid = scale(
            &pts.iter().fold([0.0; N], |a, x| add(&a, x)),
            1.0 / N as f64,
        );
        let dir = sub(&centroid, &c);
        let (inside, grazed) = (0..s.len())
            .into_par_iter()
            .map(|i| crossing(mesh, &planes[i], i, &c, &dir, d))
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        if grazed == 0 {
            return (inside == 1).then_some(below);
        }
    }
    None
}

/// The degeneracy measure of a simplex: the length of the generalized cross product of its
/// unit edges, `W_{N−1}/Π|e_k|` (eq. 8), 1 for orthogonal edges and 0 for a flat simplex.
fn quality<const N: usize>(pts: &[Vector<N>; N]) -> f64 {
    let mut u = [[0.0; N]; N];
    for k in 1..N {
        let e = sub(&pts[k], &pts[0]);
        let l = norm(&e);
        if !(l > 0.0 && l.is_finite()) {
            return 0.0;
        }
        u[k - 1] = scale(&e, 1.0 / l);
    }
    norm(&generalized_cross(&u[..N - 1]))
}

/// Whether the ray `c + t·dir`, t > 0, crosses simplex i: (1, 0) inside it, (0, 1) within
/// [`EDGE`] of its boundary, (0, 0) clear of it.
fn crossing<const N: usize>(
    mesh: &Mesh<N>,
    plane: &Hyperplane<N>,
    i: usize,
    c: &Vector<N>,
    dir: &Vector<N>,
    d: f64,
) -> (usize, usize) {
    let den = dot(&plane.normal, dir);
    let t = -plane.distance(c) / den;
    if !(t > 0.0 && t.is_finite()) {
        return (0, 0);
    }
    let x: Vector<N> = std::array::from_fn(|k| c[k] + t * dir[k]);
    let pts = mesh.simplex_points(i);
    // Far outside the simplex's box: clear (saves the barycentric solve for most simplices).
    for k in 0..N {
        let (lo, hi) = pts
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p[k]), h.max(p[k]))
            });
        // Relative to the simplex, to the mesh (a simplex lying in a coordinate plane has a box
        // of zero width there) and to the rounding of x.
        let pad = 1e-6 * (hi - lo) + 1e-9 * d + 1e-12 * (c[k].abs() + (t * dir[k]).abs());
        if x[k] < lo - pad || x[k] > hi + pad {
            return (0, 0);
        }
    }
    let mut b = [0.0; N];
    if barycentric(&x, &pts, &mut b).is_err() {
        return (0, 1);
    }
    let min = b.iter().fold(f64::INFINITY, |m, &v| m.min(v));
    if min > EDGE {
        (1, 0)
    } else if min >= -EDGE {
        (0, 1)
    } else {
        (0, 0)
    }
}

#[cfg(test)]
mod tests {
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
}
