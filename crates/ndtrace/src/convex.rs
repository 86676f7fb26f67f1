//! Convexity certificates: which meshes bound a convex body, so that a shadow ray leaving one of
//! their simplices on the outer side can never meet them again.
//!
//! The generated shapes (simplex, hypercube, cross-polytope, sphere) and many user meshes are
//! boundaries of convex bodies. If K is convex and F one of its facets, K lies in the closed
//! inner half-space of F's hyperplane (section "Clipping": every vertex is on the inner side of
//! every facet), so a ray that starts on F's plane and runs into the open outer half-space never
//! meets K again: a shadow ray from a hit on F toward a light on F's outer side needs no test
//! against K (see [`crate::render`]). [`convex_centre`] decides whether a mesh bounds a convex
//! body, in time O(S·N²·log S), by checking:
//!
//! 1. **Star-shaped, strictly.** An interior point c (the mean of the simplex centroids) lies
//!    strictly on the same side of every simplex's hyperplane (`h = n̂·(c − x_0)`, eq. 11), by
//!    at least `MARGIN` times the mesh's diameter D.
//! 2. **Closed and consistently oriented.** Every ridge (set of N−1 vertex indices) belongs to
//!    exactly two simplices, and they induce opposite orientations on it (the orientation of a
//!    simplex is the order of its vertices, eq. 6).
//! 3. **Locally convex.** At every ridge, the vertex of either simplex opposite the ridge lies
//!    on the inner side of the other simplex's hyperplane (a vertex less than `FLAT`·D outside
//!    counts as on it, so that coplanar pieces such as the hypercube's facets pass).
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

use crate::geometry::{barycentric, Hyperplane};
use crate::linalg::{add, dot, norm, scale, sub, Vector};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// The interior point must lie at least `MARGIN`·D inside every simplex's hyperplane.
pub const MARGIN: f64 = 1e-9;
/// A vertex at most `FLAT`·D outside a neighbour's hyperplane counts as on it (coplanar).
pub const FLAT: f64 = 1e-10;
/// A probe ray that meets a hyperplane within `EDGE` (barycentric) of its simplex's boundary is
/// too close to a ridge to count on.
pub const EDGE: f64 = 1e-9;

/// Probe rays tried before giving up on a mesh whose every probe grazes a ridge.
const PROBES: usize = 8;
/// Simplices whose hyperplanes every vertex is checked against first.
const SAMPLES: usize = 32;

/// An interior point c of the convex body the mesh bounds, or `None` when the mesh is not (or
/// cannot be shown to be) the consistently oriented boundary of a convex body (see the module
/// docs). A simplex's hyperplane separates c from the outer side: a ray from a point of the
/// simplex into the open half-space not containing c never meets the mesh again.
///
/// `normals[i]` is the unit normal n̂ of simplex i (eq. 6, either sign; zero when it is
/// degenerate, which makes the mesh fail).
///
/// # Panics
/// If `normals` and the simplices differ in length, or an index is out of range.
pub fn convex_centre<const N: usize>(mesh: &Mesh<N>, normals: &[Vector<N>]) -> Option<Vector<N>> {
    let s = &mesh.simplices;
    assert_eq!(
        s.len(),
        normals.len(),
        "convex_centre: one normal per simplex"
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
    let flat = FLAT * d;
    // A quick necessary condition, which most non-convex meshes fail before the ridge sort:
    // every vertex (used or not) on the inner side of the hyperplanes of a few simplices spread
    // over the mesh.
    let sample: Vec<&Hyperplane<N>> = (0..SAMPLES)
        .map(|j| &planes[j * s.len() / SAMPLES])
        .collect();
    if !mesh
        .vertices
        .par_iter()
        .all(|v| sample.iter().all(|p| out * p.distance(v) <= flat))
    {
        return None;
    }
    // 2 and 3. Ridges, as (hash of the sorted vertex indices, simplex·N + omitted slot), sorted
    // so that the two simplices of a ridge are neighbours. A run of equal hashes must be one
    // ridge of two simplices (a hash collision only makes the certificate fail).
    let mut ridges: Vec<(u64, u64)> = (0..s.len() * N)
        .into_par_iter()
        .map(|r| (ridge(&s[r / N], r % N).0, r as u64))
        .collect();
    ridges.par_sort_unstable();
    // The vertex of simplex b's ridge slot opposite the ridge, against simplex a's hyperplane.
    let convex_pair = |a: usize, b: usize| {
        let opposite = &mesh.vertices[s[b / N][b % N] as usize];
        out * planes[a / N].distance(opposite) <= flat
    };
    let ok = ridges.par_chunk_by(|a, b| a.0 == b.0).all(|run| {
        let [(_, a), (_, b)] = run else {
            return false;
        };
        let (a, b) = (*a as usize, *b as usize);
        let ((_, ka, odd_a), (_, kb, odd_b)) = (ridge(&s[a / N], a % N), ridge(&s[b / N], b % N));
        ka == kb && odd_a != odd_b && convex_pair(a, b) && convex_pair(b, a)
    });
    drop(ridges);
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
            .map(|i| crossing(mesh, &planes[i], i, &c, &dir))
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        if grazed == 0 {
            return (inside == 1).then_some(c);
        }
    }
    None
}

/// The ridge of a simplex opposite its slot k: a hash of its sorted vertex indices, those
/// indices (padded with `u32::MAX`), and the orientation the simplex induces on it (the parity
/// of k plus that of the sort).
#[inline]
fn ridge<const N: usize>(idx: &[u32; N], k: usize) -> (u64, [u32; N], bool) {
    let mut key = [u32::MAX; N];
    let mut m = 0;
    for (j, &v) in idx.iter().enumerate() {
        if j != k {
            key[m] = v;
            m += 1;
        }
    }
    let mut odd = k % 2 == 1;
    for a in 0..N - 1 {
        for b in a + 1..N - 1 {
            odd ^= key[a] > key[b];
        }
    }
    key[..N - 1].sort_unstable();
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    for &v in &key[..N - 1] {
        h = (h ^ u64::from(v)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h ^= h >> 31;
    }
    (h, key, odd)
}

/// Whether the ray `c + t·dir`, t > 0, crosses simplex i: (1, 0) inside it, (0, 1) within
/// [`EDGE`] of its boundary, (0, 0) clear of it.
fn crossing<const N: usize>(
    mesh: &Mesh<N>,
    plane: &Hyperplane<N>,
    i: usize,
    c: &Vector<N>,
    dir: &Vector<N>,
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
        let pad = 1e-6 * (hi - lo) + 1e-12 * x[k].abs();
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
    use crate::shapes::{cross_polytope, hypercube, simplex_boundary, sphere};
    use crate::testutil::{for_each_dim, random_rotation, random_vector, rng};
    use rand::Rng;

    /// The brute-force definition: every vertex on the inner side (up to FLAT·D) of every
    /// simplex's hyperplane, the inner side being the one holding `c` (`None`: either side).
    fn supported_everywhere<const N: usize>(mesh: &Mesh<N>, c: Option<&Vector<N>>) -> bool {
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
            let below = |out: f64| {
                mesh.vertices
                    .iter()
                    .all(|v| out * p.distance(v) <= FLAT * d)
            };
            match c {
                Some(c) => below(-p.distance(c).signum()),
                None => below(1.0) || below(-1.0),
            }
        })
    }

    /// [`convex_centre`] with the normals of [`hyperplane`] (zero for a degenerate simplex).
    fn certify<const N: usize>(mesh: &Mesh<N>) -> Option<Vector<N>> {
        let normals: Vec<Vector<N>> = (0..mesh.simplices.len())
            .map(|i| hyperplane(&mesh.simplex_points(i)).map_or([0.0; N], |p| p.normal))
            .collect();
        convex_centre(mesh, &normals)
    }

    fn flipped<const N: usize>(mut m: Mesh<N>) -> Mesh<N> {
        m.simplices.iter_mut().for_each(|s| s.swap(0, 1));
        m
    }

    /// The icosphere: the icosahedron with every triangle split in four `subdivisions` times,
    /// new vertices pushed onto the unit sphere (a convex polyhedron, unlike [`sphere`], whose
    /// Kuhn diagonals are reflex on some lattice squares).
    fn icosphere(subdivisions: u32) -> Mesh<3> {
        let t = (1.0 + 5f64.sqrt()) / 2.0;
        let mut v: Vec<Vector<3>> = [
            [-1., t, 0.],
            [1., t, 0.],
            [-1., -t, 0.],
            [1., -t, 0.],
            [0., -1., t],
            [0., 1., t],
            [0., -1., -t],
            [0., 1., -t],
            [t, 0., -1.],
            [t, 0., 1.],
            [-t, 0., -1.],
            [-t, 0., 1.],
        ]
        .iter()
        .map(|p| scale(p, 1.0 / norm(p)))
        .collect();
        let mut f: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..subdivisions {
            let mut mid = std::collections::HashMap::new();
            let mut m = |a: u32, b: u32, v: &mut Vec<Vector<3>>| {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let p = add(&v[a as usize], &v[b as usize]);
                    v.push(scale(&p, 1.0 / norm(&p)));
                    (v.len() - 1) as u32
                })
            };
            f = f
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = (m(a, b, &mut v), m(b, c, &mut v), m(c, a, &mut v));
                    [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
                })
                .collect();
        }
        Mesh {
            vertices: v,
            simplices: f,
        }
    }

    /// `shape` and its images under a random affine map, each in both orientations.
    fn variants<const N: usize>(r: &mut crate::testutil::TestRng, shape: Mesh<N>) -> Vec<Mesh<N>> {
        let m = random_rotation::<N>(r);
        let stretch: Vector<N> = std::array::from_fn(|_| r.random_range(0.2..3.0));
        let shift = random_vector::<N>(r, 5.0);
        let mut moved = shape.clone();
        for v in &mut moved.vertices {
            let s: Vector<N> = std::array::from_fn(|i| v[i] * stretch[i]);
            *v = add(&mat_vec(&m, &s), &shift);
        }
        vec![shape.clone(), flipped(shape), moved.clone(), flipped(moved)]
    }

    fn generated_shapes_are_convex<const N: usize>() {
        let mut r = rng(4100 + N as u64);
        let shapes = [
            simplex_boundary::<N>(),
            hypercube::<N>(),
            cross_polytope::<N>(),
        ];
        for (k, shape) in shapes.into_iter().enumerate() {
            // Any affine map keeps a convex body convex (a reflection flips the orientation).
            for mesh in variants(&mut r, shape) {
                let c = certify(&mesh).unwrap_or_else(|| panic!("N={N} shape {k}"));
                assert!(supported_everywhere(&mesh, Some(&c)), "N={N} shape {k}");
            }
        }
        // The lattice sphere is convex as a polygon, not beyond (reflex Kuhn diagonals), except
        // unsubdivided (the hypercube).
        for s in 0..=[2, 2, 2, 2, 1, 0, 0][N - 2] {
            let sph = sphere::<N>(s);
            let convex = N == 2 || s == 0;
            assert_eq!(certify(&sph).is_some(), convex, "N={N} sphere {s}");
            assert_eq!(supported_everywhere(&sph, None), convex, "N={N} sphere {s}");
        }
    }

    #[test]
    fn convex_generated_shapes_are_certified_in_every_dimension() {
        for_each_dim!(generated_shapes_are_convex);
        let mut r = rng(4199);
        for s in 0..4 {
            for mesh in variants(&mut r, icosphere(s)) {
                let c = certify(&mesh).unwrap_or_else(|| panic!("icosphere {s}"));
                assert!(supported_everywhere(&mesh, Some(&c)), "icosphere {s}");
            }
        }
    }

    fn broken_shapes_are_rejected<const N: usize>() {
        let base = if N == 2 {
            sphere::<N>(2)
        } else {
            cross_polytope::<N>()
        };
        assert!(certify(&base).is_some(), "N={N}");
        // Open: one simplex missing.
        let mut open = base.clone();
        open.simplices.pop();
        assert!(certify(&open).is_none(), "N={N} open");
        // One simplex turned over.
        let mut turned = base.clone();
        turned.simplices[1].swap(0, 1);
        assert!(certify(&turned).is_none(), "N={N} turned");
        // A dent: one vertex pushed through the centre's side of its neighbours.
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
        // A degenerate simplex.
        let mut flat = simplex_boundary::<N>();
        flat.vertices.push(flat.vertices[0]);
        flat.simplices[0][1] = (flat.vertices.len() - 1) as u32;
        assert!(certify(&flat).is_none(), "N={N} degenerate");
    }

    #[test]
    fn open_turned_dented_doubled_and_degenerate_meshes_are_rejected() {
        for_each_dim!(broken_shapes_are_rejected);
    }

    #[test]
    fn doubly_wound_polygon_is_rejected() {
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
            if let Some(c) = got {
                assert!(supported_everywhere(&mesh, Some(&c)));
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
