//! Exact N-D hidden-line removal: the parts of every object's feature edges
//! ([`crate::mesh::feature_edges`]) that the N-D camera sees, and the parts it does not.
//!
//! Hollasch's 4D wireframes and the course's pictures draw a polytope through its edges; drawing
//! all of them ("a cube inside a cube joined by six frusta") loses which cells face the 4D eye.
//! Here every edge is split at the boundaries of what hides it in N-D:
//!
//! 1. **Field of view.** The segment A→B is clipped to the camera's viewing region: for
//!    perspective the pyramid `|c_k| ≤ h_k·c_N`, `c_N > 0` in camera coordinates
//!    `c = Oᵀ(x − C)` (h_k the half-extent of retina axis k at unit distance, the course's
//!    "N-dimensional Imaging" projection x_k ↦ x_k / x_N); for orthographic the prism
//!    `|c_k| ≤ h_k`, `c_N ≥ 0`. Both are half-spaces linear in x, so the clip is exact.
//! 2. **Occluders.** A point Q(s) = A + s(B − A) is hidden when the segment from the eye to Q
//!    (for orthographic, from the image plane along the view direction) crosses a simplex of the
//!    scene before reaching Q. All those segments sweep one 2-plane, the *visibility plane* of
//!    the edge; a simplex (in its hyperplane n·x = n·x_0, eq. 1) meets that plane in a line
//!    (eq. 1 restricted to the plane), and the simplex itself in the interval of that line where
//!    every barycentric coordinate (section "Barycentric Coordinates") is ≥ 0. The part of that
//!    interval strictly between the eye and the edge hides exactly an interval of s, found from
//!    its endpoints because s is monotone along a line of the plane.
//! 3. **Finding the occluders**: the simplices around the edge's two ends (which can hide slivers
//!    next to a vertex), and, with the BVH, rays from the eye toward sample points of the edge,
//!    spaced [`SAMPLES_PER_CELL`] to a retina cell of the edge's projection (at least
//!    [`MIN_SAMPLES`]); a sample not yet known to be hidden sends one ray, and the simplex it
//!    meets contributes its whole exact interval. The visible parts are then the complement of
//!    the union of those intervals.
//!
//! Tolerance: points within [`ON_EDGE`] (relative to their distance from the eye) of the edge
//! along the eye ray count as on the edge, so the simplices an edge lies on, or ends on, do not
//! hide it; an occluder that hides no sample point (narrower than an eighth of a retina cell in
//! projection, away from the edge's ends) can be missed; visible or hidden pieces shorter than [`ON_EDGE`] times the edge's
//! length are dropped.

use crate::camera::Camera;
use crate::camera::Projection;
use crate::composite::{RetinaEdge, MAX_RETINA_DIM};
use crate::linalg::{dot, mat_vec, sub, transpose, Rgb, Vector};
use crate::ray::Ray;
use crate::scene::Scene;
use crate::NdResult;

/// Sample rays per retina cell of an edge's projected length.
pub const SAMPLES_PER_CELL: f64 = 8.0;
/// Fewest sample rays along an edge in view.
pub const MIN_SAMPLES: usize = 16;
/// Relative tolerance of "on the edge" along an eye ray, and of the shortest piece kept.
pub const ON_EDGE: f64 = 1e-6;

/// A piece of a feature edge, in world coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeSegment<const N: usize> {
    /// One end.
    pub a: Vector<N>,
    /// The other end.
    pub b: Vector<N>,
    /// The object the edge belongs to.
    pub object: u32,
    /// Whether the N-D camera sees this piece (else it is hidden in N-D or outside the view).
    pub visible: bool,
}

/// The feature edges (crease angle `angle_degrees`) of every object of `scene`, split into the
/// pieces the camera sees and those it does not (see the module docs). Pieces come object by
/// object, edge by edge in [`crate::mesh::feature_edges`] order, along each edge from its first vertex; the
/// result is the same whatever the number of threads.
pub fn edge_segments<const N: usize>(
    scene: &Scene<N>,
    angle_degrees: f64,
) -> NdResult<Vec<EdgeSegment<N>>> {
    // Found when an object has edges (a smooth mesh has none).
    let culled_once = std::sync::OnceLock::new();
    let mut out = Vec::new();
    for (o, obj) in scene.objects.iter().enumerate() {
        let edges = scene.edge_cache.feature_edges(
            o,
            angle_degrees,
            &obj.mesh.vertices,
            &obj.mesh.simplices,
        )?;
        if edges.is_empty() {
            continue;
        }
        let culled = culled_once.get_or_init(|| culled(scene));
        let star = star(obj.mesh.vertices.len(), &obj.mesh.simplices);
        let first = scene.offsets[o];
        // `par::map_collect` rather than a rayon pipeline: one instantiation of rayon for
        // every N (this function is compiled per N).
        let pieces: Vec<Vec<EdgeSegment<N>>> = crate::par::map_collect(edges.len(), 1, |e| {
            let [i, j] = edges[e];
            let (a, b) = (obj.mesh.vertices[i as usize], obj.mesh.vertices[j as usize]);
            // The simplices around the edge's ends: occluders that can hide a sliver next
            // to a vertex, thinner than the ray samples' spacing.
            let near: Vec<u32> = star[i as usize]
                .iter()
                .chain(&star[j as usize])
                .map(|&s| first + s)
                .collect();
            split_edge(scene, culled, &near, &a, &b, o)
                .into_iter()
                .map(|(s0, s1, visible)| EdgeSegment {
                    a: lerp(&a, &b, s0),
                    b: lerp(&a, &b, s1),
                    object: o as u32,
                    visible,
                })
                .collect()
        });
        out.extend(pieces.into_iter().flatten());
    }
    Ok(out)
}

/// One direction of a scene's feature edges (`composite.edge_color_by = "direction"`): the
/// edges parallel to it share its colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeDirection<const N: usize> {
    /// The unit direction in the own space of the first object with such an edge (the sign
    /// making its first component beyond 10⁻⁶ positive): the tesseract's are its own axes.
    pub own: Vector<N>,
    /// That object.
    pub object: u32,
    /// The colour: that object's `material.palette` colour of the direction's index.
    pub color: Rgb,
}

/// Relative rounding of the directions that count as parallel.
const PARALLEL: f64 = 1e-6;

/// The key of the line of direction `d` (parallel lines, either way, share it), or `None` for
/// a zero vector.
fn direction_key<const N: usize>(d: &Vector<N>) -> Option<([i64; N], f64)> {
    let l = crate::linalg::norm(d);
    if !(l > 0.0 && l.is_finite()) {
        return None;
    }
    let sign = d
        .iter()
        .find(|x| x.abs() > PARALLEL * l)
        .map_or(1.0, |x| x.signum());
    Some((
        d.map(|x| (sign * x / l / PARALLEL).round() as i64),
        sign / l,
    ))
}

/// The directions of the feature edges (crease angle `angle_degrees`) of every object of
/// `scene`, numbered in the order of their first edge (object by object, in
/// [`crate::mesh::feature_edges`] order), with their keys.
fn directions<const N: usize>(
    scene: &Scene<N>,
    angle_degrees: f64,
) -> NdResult<Vec<([i64; N], EdgeDirection<N>)>> {
    let mut out: Vec<([i64; N], EdgeDirection<N>)> = Vec::new();
    for (o, obj) in scene.objects.iter().enumerate() {
        let edges = scene.edge_cache.feature_edges(
            o,
            angle_degrees,
            &obj.mesh.vertices,
            &obj.mesh.simplices,
        )?;
        for &[i, j] in edges.iter() {
            let d = sub(
                &obj.mesh.vertices[j as usize],
                &obj.mesh.vertices[i as usize],
            );
            let Some((key, _)) = direction_key(&d) else {
                continue;
            };
            if out.iter().any(|(k, _)| *k == key) {
                continue;
            }
            let own = mat_vec(&obj.own_from_world, &d);
            let (_, s) = direction_key(&own).unwrap_or(([0; N], 0.0));
            out.push((
                key,
                EdgeDirection {
                    own: own.map(|x| x * s),
                    object: o as u32,
                    color: [0.0; 3],
                },
            ));
        }
    }
    // In the order of the axes they are nearest (a tesseract's x, y, z, w), then coloured.
    out.sort_by(|a, b| axis_order(&a.1.own).total_cmp(&axis_order(&b.1.own)));
    for (k, (_, d)) in out.iter_mut().enumerate() {
        d.color = scene.objects[d.object as usize].material.palette.color(k);
    }
    Ok(out)
}

/// A direction's place in the order of the axes: the axis of its largest component, then the
/// directions nearer that axis first.
pub fn axis_order<const N: usize>(v: &Vector<N>) -> f64 {
    let (axis, big) = v.iter().enumerate().fold((0, 0.0f64), |(i, m), (k, x)| {
        if x.abs() > m + 1e-9 {
            (k, x.abs())
        } else {
            (i, m)
        }
    });
    let l = crate::linalg::norm(v).max(f64::MIN_POSITIVE);
    axis as f64 + (1.0 - big / l)
}

/// The directions of the feature edges of `scene` (see [`EdgeDirection`]), in the order of
/// their first edge: what the legend of `edge_color_by = "direction"` keys.
pub fn edge_directions<const N: usize>(
    scene: &Scene<N>,
    angle_degrees: f64,
) -> NdResult<Vec<EdgeDirection<N>>> {
    Ok(directions(scene, angle_degrees)?
        .into_iter()
        .map(|(_, d)| d)
        .collect())
}

/// The pieces of [`edge_segments`] in retina coordinates, for the compositor
/// ([`crate::composite::RetinaExtras::edges`]): each piece clipped to the camera's view (the
/// hidden pieces may leave it), its ends as continuous numpy-order cell coordinates
/// (`[ξ_{N−1}, …, ξ_1]`, cell i of an axis spanning [i, i + 1]) and their depths as the tracer
/// measures them (distance from the eye, or from the image plane for orthographic).
pub fn retina_edges<const N: usize>(
    scene: &Scene<N>,
    angle_degrees: f64,
) -> NdResult<Vec<RetinaEdge>> {
    let cam = &scene.camera;
    let depth = |x: &Vector<N>| match cam.projection {
        Projection::Perspective => crate::linalg::norm(&sub(x, &cam.position)),
        Projection::Orthographic => camera_coords(cam, x)[N - 1],
    };
    let directions = directions(scene, angle_degrees)?;
    let color_of = |d: &Vector<N>| {
        direction_key(d)
            .and_then(|(key, _)| directions.iter().find(|(k, _)| *k == key))
            .map_or([1.0; 3], |(_, e)| e.color.map(|c| c as f32))
    };
    let mut out = Vec::new();
    for seg in edge_segments(scene, angle_degrees)? {
        let (s0, s1) = view_interval(cam, &seg.a, &seg.b);
        if !(s1 - s0 > ON_EDGE) {
            continue;
        }
        let (a, b) = (lerp(&seg.a, &seg.b, s0), lerp(&seg.a, &seg.b, s1));
        let (Some(xa), Some(xb)) = (retina_coords(cam, &a), retina_coords(cam, &b)) else {
            continue;
        };
        let mut e = RetinaEdge {
            a: [0.0; MAX_RETINA_DIM],
            b: [0.0; MAX_RETINA_DIM],
            depth: [depth(&a), depth(&b)],
            visible: seg.visible,
            color: color_of(&sub(&seg.b, &seg.a)),
        };
        for k in 0..N - 1 {
            e.a[N - 2 - k] = xa[k];
            e.b[N - 2 - k] = xb[k];
        }
        out.push(e);
    }
    Ok(out)
}

/// For each vertex, the simplices that have it.
fn star<const N: usize>(vertices: usize, simplices: &[[u32; N]]) -> Vec<Vec<u32>> {
    let mut star = vec![Vec::new(); vertices];
    for (s, simplex) in simplices.iter().enumerate() {
        for &v in simplex {
            star[v as usize].push(s as u32);
        }
    }
    star
}

/// Per global simplex id, whether back-face culling removes it (as the tracer does).
fn culled<const N: usize>(scene: &Scene<N>) -> Vec<bool> {
    if !scene.render.cull_backfaces {
        return Vec::new();
    }
    scene.backfaces()
}

fn lerp<const N: usize>(a: &Vector<N>, b: &Vector<N>, s: f64) -> Vector<N> {
    std::array::from_fn(|k| a[k] + s * (b[k] - a[k]))
}

/// Camera coordinates `c = Oᵀ(x − C)` (c_N along the view direction).
fn camera_coords<const N: usize>(cam: &Camera<N>, x: &Vector<N>) -> Vector<N> {
    mat_vec(&transpose(&cam.orientation), &sub(x, &cam.position))
}

/// Continuous retina coordinates of a point in front of the camera, in the camera's axis order
/// (ξ_1 … ξ_{N−1}; cell i of an axis spans [i, i + 1]), or `None` behind the eye.
pub fn retina_coords<const N: usize>(cam: &Camera<N>, x: &Vector<N>) -> Option<Vector<N>> {
    let c = camera_coords(cam, x);
    let depth = match cam.projection {
        Projection::Perspective if c[N - 1] > 0.0 => c[N - 1],
        Projection::Perspective => return None,
        Projection::Orthographic => 1.0,
    };
    let mut xi = [0.0; N];
    for k in 0..N - 1 {
        let u = c[k] / depth / cam.cell;
        let half = cam.resolution[k] as f64 / 2.0;
        xi[k] = if k == 1 { half - u } else { half + u };
    }
    Some(xi)
}

/// The interval of s ∈ [0, 1] where `lo ≤ p + s·q` (exact for the linear constraint).
fn clip(range: &mut (f64, f64), p: f64, q: f64) {
    // p + s q ≥ 0
    if q > 0.0 {
        range.0 = range.0.max(-p / q);
    } else if q < 0.0 {
        range.1 = range.1.min(-p / q);
    } else if p < 0.0 {
        *range = (1.0, 0.0);
    }
}

/// The field-of-view interval of the edge (s0 > s1 when it is outside the view).
fn view_interval<const N: usize>(cam: &Camera<N>, a: &Vector<N>, b: &Vector<N>) -> (f64, f64) {
    let ca = camera_coords(cam, a);
    let cb = camera_coords(cam, b);
    let d: Vector<N> = std::array::from_fn(|k| cb[k] - ca[k]);
    let mut r = (0.0, 1.0);
    for k in 0..N - 1 {
        let h = cam.resolution[k] as f64 * cam.cell / 2.0;
        match cam.projection {
            Projection::Perspective => {
                // h·c_N − c_k ≥ 0 and h·c_N + c_k ≥ 0
                clip(&mut r, h * ca[N - 1] - ca[k], h * d[N - 1] - d[k]);
                clip(&mut r, h * ca[N - 1] + ca[k], h * d[N - 1] + d[k]);
            }
            Projection::Orthographic => {
                clip(&mut r, h - ca[k], -d[k]);
                clip(&mut r, h + ca[k], d[k]);
            }
        }
    }
    clip(&mut r, ca[N - 1], d[N - 1]);
    if cam.projection == Projection::Perspective && r.0 <= r.1 {
        // Strictly in front of the eye.
        let eps = ON_EDGE * (ca[N - 1].abs() + cb[N - 1].abs());
        clip(&mut r, ca[N - 1] - eps, d[N - 1]);
    }
    r
}

/// The visibility plane of an edge: x(p, q) = origin + p·e1 + q·e2, with the linear
/// constraints (α + β·p + γ·q ≥ 0) of the region strictly between the eye and the edge, and
/// the map from plane coordinates to the edge parameter s.
struct VisibilityPlane<const N: usize> {
    origin: Vector<N>,
    e1: Vector<N>,
    e2: Vector<N>,
    region: Vec<[f64; 3]>,
    perspective: bool,
}

impl<const N: usize> VisibilityPlane<N> {
    fn new(cam: &Camera<N>, a: &Vector<N>, b: &Vector<N>) -> Self {
        match cam.projection {
            // x = E + u (A − E) + v (B − E): λ = u + v is the fraction of the way to the edge
            // and s = v / (u + v).
            Projection::Perspective => Self {
                origin: cam.position,
                e1: sub(a, &cam.position),
                e2: sub(b, &cam.position),
                region: vec![
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                    [-ON_EDGE, 1.0, 1.0],
                    [1.0 - ON_EDGE, -1.0, -1.0],
                ],
                perspective: true,
            },
            // x = A + s (B − A) − μ·view, 0 < μ < (distance of Q(s) from the image plane).
            Projection::Orthographic => {
                let view = cam.axis(N - 1);
                let da = dot(&sub(a, &cam.position), &view);
                let db = dot(&sub(b, &cam.position), &view);
                let tol = ON_EDGE * (da.abs() + db.abs()).max(f64::MIN_POSITIVE);
                Self {
                    origin: *a,
                    e1: sub(b, a),
                    e2: std::array::from_fn(|k| -view[k]),
                    region: vec![
                        [0.0, 1.0, 0.0],
                        [1.0, -1.0, 0.0],
                        [-tol, 0.0, 1.0],
                        [da, db - da, -1.0],
                    ],
                    perspective: false,
                }
            }
        }
    }

    fn s_of(&self, p: f64, q: f64) -> f64 {
        if self.perspective {
            q / (p + q)
        } else {
            p
        }
    }

    fn point(&self, p: f64, q: f64) -> Vector<N> {
        std::array::from_fn(|k| self.origin[k] + p * self.e1[k] + q * self.e2[k])
    }

    /// The interval of s that simplex `points` hides, if any.
    fn hidden_by(&self, points: &[Vector<N>; N], normal: &Vector<N>) -> Option<(f64, f64)> {
        // The simplex's hyperplane on the plane: α + β p + γ q = 0.
        let alpha = dot(normal, &sub(&self.origin, &points[0]));
        let beta = dot(normal, &self.e1);
        let gamma = dot(normal, &self.e2);
        let len2 = beta * beta + gamma * gamma;
        let scale = alpha.abs() + beta.abs() + gamma.abs();
        if !(len2.sqrt() > 1e-12 * scale) {
            // The plane lies in (or parallel to) the hyperplane: seen edge-on, hides nothing.
            return None;
        }
        // The line: (p, q) = p0 + τ·(−γ, β).
        let (p0, q0) = (-alpha * beta / len2, -alpha * gamma / len2);
        let (dp, dq) = (-gamma, beta);
        let mut range = (f64::NEG_INFINITY, f64::INFINITY);
        for &[c0, c1, c2] in &self.region {
            clip(&mut range, c0 + c1 * p0 + c2 * q0, c1 * dp + c2 * dq);
        }
        if !(range.0 < range.1) {
            return None;
        }
        // Barycentric coordinates along the line are affine in τ: from two points.
        let x0 = self.point(p0, q0);
        let x1 = self.point(p0 + dp, q0 + dq);
        let b0 = barycentric(points, &x0)?;
        let b1 = barycentric(points, &x1)?;
        for k in 0..N {
            clip(&mut range, b0[k], b1[k] - b0[k]);
        }
        if !(range.0 < range.1) {
            return None;
        }
        let s0 = self.s_of(p0 + range.0 * dp, q0 + range.0 * dq);
        let s1 = self.s_of(p0 + range.1 * dp, q0 + range.1 * dq);
        Some((s0.min(s1).max(0.0), s0.max(s1).min(1.0)))
    }
}

/// Barycentric coordinates of `x`, a point of the simplex's hyperplane (section "Barycentric
/// Coordinates").
fn barycentric<const N: usize>(points: &[Vector<N>; N], x: &Vector<N>) -> Option<[f64; N]> {
    let mut out = [0.0; N];
    crate::geometry::barycentric(x, points, &mut out).ok()?;
    Some(out)
}

/// The pieces (s0, s1, visible) of the edge A→B, in order along it.
fn split_edge<const N: usize>(
    scene: &Scene<N>,
    culled: &[bool],
    near: &[u32],
    a: &Vector<N>,
    b: &Vector<N>,
    object: usize,
) -> Vec<(f64, f64, bool)> {
    let cam = &scene.camera;
    let (mut v0, mut v1) = view_interval(cam, a, b);
    let mut pieces = Vec::new();
    // Clip hyperplanes (`render/clip.rs`): the part of the edge beyond its object's is not
    // there (n̂·x ≤ c along the edge: the course's segment clip, eq. 10), and occluders count
    // only where their hits are kept. The part clipped away is dropped from the result.
    let clipped = scene.clips.active();
    let mut kept = (0.0, 1.0);
    if clipped {
        for (n, c) in &scene.clips.objects[object].planes {
            clip(&mut kept, c - dot(n, a), -dot(n, &sub(b, a)));
        }
        if !(kept.0 < kept.1) {
            return Vec::new();
        }
        (v0, v1) = (v0.max(kept.0), v1.min(kept.1));
    }
    if !(v0 < v1) {
        pieces.push((kept.0, kept.1, false));
        return pieces;
    }
    // Samples: SAMPLES_PER_CELL per retina cell of the projected length.
    let (qa, qb) = (lerp(a, b, v0), lerp(a, b, v1));
    let cells = match (retina_coords(cam, &qa), retina_coords(cam, &qb)) {
        (Some(x), Some(y)) => (0..N - 1)
            .map(|k| (x[k] - y[k]).powi(2))
            .sum::<f64>()
            .sqrt(),
        _ => 1.0,
    };
    let count = ((cells * SAMPLES_PER_CELL).ceil() as usize).clamp(MIN_SAMPLES, 1 << 16);
    let plane = VisibilityPlane::new(cam, a, b);
    let mut hidden: Vec<(f64, f64)> = Vec::new();
    let accept = |g: u32| culled.is_empty() || !culled[g as usize];
    let simplex = |g: u32| {
        let (o, p) = scene.locate(g);
        scene.objects[o].mesh.simplex_points(p)
    };
    for &g in near {
        // (With clips, an occluder may be cut: only the sample rays, whose hits are checked,
        // find them.)
        if accept(g) && !clipped {
            if let Some(h) = plane.hidden_by(&simplex(g), &scene.flat_normal(g)) {
                hidden.push(h);
            }
        }
    }
    for i in 0..=count {
        let s = v0 + (v1 - v0) * (i as f64 / count as f64);
        if hidden.iter().any(|&(h0, h1)| h0 <= s && s <= h1) {
            continue;
        }
        let q = lerp(a, b, s);
        let ray = match cam.projection {
            Projection::Perspective => Ray {
                origin: cam.position,
                dir: sub(&q, &cam.position),
            },
            Projection::Orthographic => {
                let view = cam.axis(N - 1);
                let d = dot(&sub(&q, &cam.position), &view);
                Ray {
                    origin: std::array::from_fn(|k| q[k] - d * view[k]),
                    dir: std::array::from_fn(|k| d * view[k]),
                }
            }
        };
        let first = scene
            .instances
            .closest_hit(&ray, 0.0, 1.0 - ON_EDGE, &accept);
        let Some(hit) = (if clipped {
            crate::render::clip::nearest_kept(scene, &ray, 0.0, 1.0 - ON_EDGE, &accept, first)
        } else {
            first
        }) else {
            continue;
        };
        if let Some(h) = plane.hidden_by(&simplex(hit.prim), &hit.normal) {
            hidden.push(h);
        }
    }
    // Visible = view interval minus the union of the hidden intervals.
    hidden.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut pieces = vec![(kept.0, v0, false)];
    let mut at = v0;
    for (h0, h1) in hidden {
        let (h0, h1) = (h0.max(v0), h1.min(v1));
        if h1 <= at {
            continue;
        }
        if h0 > at {
            pieces.push((at, h0, true));
            at = h0;
        }
        pieces.push((at, h1, false));
        at = h1;
    }
    pieces.push((at, v1, true));
    pieces.push((v1, kept.1, false));
    merge(pieces)
}

/// Drops empty pieces, gives pieces shorter than [`ON_EDGE`] the visibility of their longer
/// neighbour (they are below the tolerance), and joins neighbours of the same visibility: the
/// result tiles [0, 1] with alternating visibility.
fn merge(mut pieces: Vec<(f64, f64, bool)>) -> Vec<(f64, f64, bool)> {
    pieces.retain(|p| p.1 > p.0);
    let len = |p: &(f64, f64, bool)| p.1 - p.0;
    for i in 0..pieces.len() {
        if len(&pieces[i]) < ON_EDGE {
            let before = i.checked_sub(1).map(|j| pieces[j]);
            let after = pieces.get(i + 1).copied();
            let longer = match (before, after) {
                (Some(b), Some(a)) => Some(if len(&b) >= len(&a) { b } else { a }),
                (b, a) => b.or(a),
            };
            if let Some(n) = longer {
                pieces[i].2 = n.2;
            }
        }
    }
    let mut out: Vec<(f64, f64, bool)> = Vec::with_capacity(pieces.len());
    for p in pieces {
        match out.last_mut() {
            Some(last) if last.2 == p.2 => last.1 = p.1,
            _ => out.push(p),
        }
    }
    out
}

#[cfg(test)]
mod tests;
