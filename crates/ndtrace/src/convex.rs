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

use crate::geometry::{barycentric, generalized_cross, hyperplane, Hyperplane};
use crate::linalg::{add, dot, norm, scale, sub, Vector};
use crate::mesh::{orientation::matched_ridges, Mesh};
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

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

/// An object's convexity certificate ([`convex_side`]) as its scene holds it: found the first
/// time something needs it (a trace that casts shadow rays, a picture's probe), not by the
/// build: finding it costs about as much as building the object's tree (it sorts the
/// ridges), and a scene loaded to be sliced, measured or drawn without shadows never needs it.
///
/// It is found from what the index holds of the object: its simplices with the vertices of
/// the space its tree holds it in (its own, before its transform, for an object held in its
/// own space: an affine map keeps a body convex), the exact unit normal n̂ (eq. 6) of each
/// simplex the tree holds and zero for each it drops (degenerate ones), and whether its shape
/// is known to be convex. For an object held in its own space through a map that reverses
/// handedness, the world normals are turned around with the simplices' order
/// ([`crate::accel::ToObject`]): the side found in its own space is flipped.
///
/// The clones share the value (the scenes of animation frames that do not move the object
/// share its certificate): it is found once. Finding it runs rayon's parallel loops, so it is
/// not found from inside one (a worker waiting in the search may take up a task of the outer
/// loop that asks for the same certificate): the traces and probes [`Certificate::find`] their
/// scene's certificates before their parallel loops ([`crate::scene::Scene::find_certificates`]),
/// and the loops only [`Certificate::get`] them.
#[derive(Debug, Clone)]
pub struct Certificate<const N: usize>(Arc<Lazy<N>>);

/// A [`Certificate`]'s value, once found, and what finding it takes.
#[derive(Debug)]
struct Lazy<const N: usize> {
    /// The value, once found (`None` inside: not convex, or never certified).
    found: OnceLock<Option<bool>>,
    /// What finding it takes; `None` for a certificate never found ([`Certificate::none`]).
    source: Option<Source<N>>,
}

/// What finding a [`Certificate`] takes besides the object's mesh and which of its simplices
/// its tree holds.
#[derive(Debug)]
struct Source<const N: usize> {
    /// The vertices the tree holds the object with, when it holds it in its own space.
    own: Option<Arc<Vec<Vector<N>>>>,
    /// Its map into its own space reverses handedness: the side found there is flipped.
    flip: bool,
    /// Its shape is known to be convex ([`convex_side`]'s `known_convex`).
    known_convex: bool,
}

impl<const N: usize> Default for Certificate<N> {
    fn default() -> Self {
        Self::none()
    }
}

impl<const N: usize> Certificate<N> {
    /// The certificate of an object that is never certified: `None` (no shadow rays will
    /// use it, or it is not worth finding: an elevation map, a clip's cap).
    pub fn none() -> Self {
        Certificate(Arc::new(Lazy {
            found: OnceLock::from(None),
            source: None,
        }))
    }

    /// The certificate of an object to be found on first need: held in world space
    /// (`own` = `None`) or in its own space with the vertices `own`, through a map that
    /// reverses handedness (`flip`) or not; `known_convex` as [`convex_side`] takes it.
    pub fn lazy(own: Option<Arc<Vec<Vector<N>>>>, flip: bool, known_convex: bool) -> Self {
        Certificate(Arc::new(Lazy {
            found: OnceLock::new(),
            source: Some(Source {
                own,
                flip,
                known_convex,
            }),
        }))
    }

    /// Whether it is still to be found.
    pub fn pending(&self) -> bool {
        self.0.found.get().is_none()
    }

    /// The side of the body ([`convex_side`], in world space), once found: `None` when the
    /// object is not convex or not certified. It only reads: [`Certificate::find`] it first.
    #[inline]
    pub fn get(&self) -> Option<bool> {
        debug_assert!(
            !self.pending(),
            "a convexity certificate read before it was found"
        );
        self.0.found.get().copied().flatten()
    }

    /// Finds it, unless it is found already, for the object of mesh `mesh` (in world space)
    /// whose simplex s its tree holds in slot `slots[s]` (`u32::MAX`: dropped, degenerate;
    /// [`crate::accel::Bvh::id_slots`]). Not from inside a parallel loop (see
    /// [`Certificate`]). Two threads finding it at once each find the same value (neither
    /// waits for the other).
    pub fn find(&self, mesh: &Mesh<N>, slots: &[u32]) {
        if let (Some(source), true) = (&self.0.source, self.pending()) {
            let side = source.find(mesh, slots);
            // (Set by another thread meanwhile: the same value.)
            let _ = self.0.found.set(side);
        }
    }
}

impl<const N: usize> Source<N> {
    /// The certificate of the object of mesh `mesh` whose tree holds its simplices in `slots`
    /// ([`Certificate::find`]). Kept out of the traces' code, which only call it once.
    #[cold]
    #[inline(never)]
    fn find(&self, mesh: &Mesh<N>, slots: &[u32]) -> Option<bool> {
        // The simplices with the vertices the tree holds them with (a copy, rather than the
        // build's swap: the scene shares its objects).
        let own_mesh;
        let mesh = match &self.own {
            None => mesh,
            Some(own) => {
                own_mesh = Mesh {
                    vertices: own.to_vec(),
                    simplices: mesh.simplices.clone(),
                };
                &own_mesh
            }
        };
        // The exact normals (the tree's are rounded to f32); the tree holds a simplex exactly
        // when it prepares ([`crate::accel::PreparedSimplex::new`]), whose normal this is.
        let normals: Vec<Vector<N>> = (0..mesh.simplices.len())
            .into_par_iter()
            .map(|s| match slots[s] {
                u32::MAX => [0.0; N],
                _ => hyperplane(&mesh.simplex_points(s)).map_or([0.0; N], |h| h.normal),
            })
            .collect();
        let side = convex_side(mesh, &normals, self.known_convex);
        side.map(|below| below != self.flip)
    }
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
mod tests;
