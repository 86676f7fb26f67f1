//! [`splat`]: the surfaces of a 4D scene ([`crate::surface`]) projected into its traced 3D
//! retina.
//!
//! Each triangle is projected through the camera (its vertices' retina coordinates; inside the
//! triangle, perspective-correct barycentric coordinates), and every retina cell whose centre
//! lies within `width/2` cells of the projected triangle receives a fragment at the triangle's
//! closest point, unless the traced scene is nearer there. Per cell, the fragments are sorted
//! by depth (then object and triangle, so the result does not depend on the thread count),
//! fragments of neighbouring triangles of one surface count as one layer, and the layers are
//! blended front to back with their opacity over what the tracer saw.

use super::surface::{surface_color, SurfacePoint};
use super::{Progress, Retina};
use crate::camera::{Camera, Projection};
use crate::linalg::{dot, norm, sub, Vector};
use crate::scene::Scene;
use crate::surface::MAX_LAYERS;
use crate::{NdError, NdResult};
use rayon::prelude::*;
use std::sync::atomic::Ordering;

/// Triangles per parallel work item.
const CHUNK: usize = 2048;

/// A cell's candidate: the depth of a triangle's closest point to the cell's centre, which
/// triangle, and its barycentric coordinates (in the triangle's own, 4D, parametrisation).
#[derive(Clone, Copy, Debug)]
struct Fragment {
    cell: usize,
    depth: f64,
    obj: u32,
    tri: u32,
    bary: [f64; 3],
}

/// The retina's cell geometry for 3D retinas: resolution and the map from camera-frame
/// coordinates to continuous cell coordinates (cell i spans [i, i + 1) along each axis).
struct RetinaMap<'a, const N: usize> {
    cam: &'a Camera<N>,
    res: [usize; 3],
}

impl<const N: usize> RetinaMap<'_, N> {
    /// Continuous cell coordinates of `x` and its camera-frame view coordinate z (1 for an
    /// orthographic camera); `None` at or behind the eye.
    fn project(&self, x: &Vector<N>) -> Option<([f64; 3], f64)> {
        let rel = sub(x, &self.cam.position);
        let z = dot(&rel, &self.cam.axis(N - 1));
        let zd = match self.cam.projection {
            Projection::Perspective if !(z > 0.0) => return None,
            Projection::Perspective => z,
            Projection::Orthographic => 1.0,
        };
        let mut g = [0.0; 3];
        for k in 0..3 {
            let u = dot(&rel, &self.cam.axis(k)) / zd / self.cam.cell;
            let half = self.res[k] as f64 / 2.0;
            g[k] = if k == 1 { half - u } else { u + half };
        }
        g.iter().all(|v| v.is_finite()).then_some((g, zd))
    }

    /// The depth of `x` as the retina records it ([`Camera::depth`]).
    fn depth(&self, x: &Vector<N>) -> f64 {
        let rel = sub(x, &self.cam.position);
        match self.cam.projection {
            Projection::Perspective => norm(&rel),
            Projection::Orthographic => dot(&rel, &self.cam.axis(N - 1)),
        }
    }

    /// The unit direction from the eye toward `x`.
    fn direction(&self, x: &Vector<N>) -> Vector<N> {
        match self.cam.projection {
            Projection::Perspective => {
                let rel = sub(x, &self.cam.position);
                let l = norm(&rel);
                std::array::from_fn(|i| rel[i] / l)
            }
            Projection::Orthographic => self.cam.axis(N - 1),
        }
    }

    fn cell(&self, i: [usize; 3]) -> usize {
        i[0] + self.res[0] * (i[1] + self.res[1] * i[2])
    }
}

fn sub3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The point of segment `a b` closest to `p`, as the weight t of `b` (0 ≤ t ≤ 1).
fn closest_on_segment(p: &[f64; 3], a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let ab = sub3(b, a);
    let l = dot3(&ab, &ab);
    if !(l > 0.0) {
        return 0.0;
    }
    (dot3(&sub3(p, a), &ab) / l).clamp(0.0, 1.0)
}

/// The barycentric coordinates of the point of triangle `t` closest to `p` (Ericson, *Real-Time
/// Collision Detection*, §5.1.5, by Voronoi regions; a triangle without area falls back to its
/// nearest edge).
pub(super) fn closest_on_triangle(p: &[f64; 3], t: &[[f64; 3]; 3]) -> [f64; 3] {
    let [a, b, c] = t;
    let ab = sub3(b, a);
    let ac = sub3(c, a);
    let n = cross3(&ab, &ac);
    if !(dot3(&n, &n) > 1e-20 * dot3(&ab, &ab) * dot3(&ac, &ac)) {
        return closest_on_edges(p, t);
    }
    let ap = sub3(p, a);
    let (d1, d2) = (dot3(&ab, &ap), dot3(&ac, &ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = sub3(p, b);
    let (d3, d4) = (dot3(&ab, &bp), dot3(&ac, &bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = sub3(p, c);
    let (d5, d6) = (dot3(&ab, &cp), dot3(&ac, &cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let sum = va + vb + vc;
    let (v, w) = (vb / sum, vc / sum);
    [1.0 - v - w, v, w]
}

/// [`closest_on_triangle`] for a triangle without area: the nearest point of its three edges.
fn closest_on_edges(p: &[f64; 3], t: &[[f64; 3]; 3]) -> [f64; 3] {
    let edges = [(0, 1), (1, 2), (2, 0)];
    let mut best = ([1.0, 0.0, 0.0], f64::INFINITY);
    for (i, j) in edges {
        let s = closest_on_segment(p, &t[i], &t[j]);
        let q: [f64; 3] = std::array::from_fn(|k| t[i][k] + s * (t[j][k] - t[i][k]));
        let d = dot3(&sub3(p, &q), &sub3(p, &q));
        if d < best.1 {
            let mut w = [0.0; 3];
            w[i] = 1.0 - s;
            w[j] = s;
            best = (w, d);
        }
    }
    best.0
}

/// Range of cells along an axis of `r` cells whose centres (i + ½) lie in [lo, hi].
fn cells_in(lo: f64, hi: f64, r: usize) -> Option<(usize, usize)> {
    let a = (lo - 0.5).ceil().max(0.0);
    let b = (hi - 0.5).floor().min(r as f64 - 1.0);
    (a <= b).then_some((a as usize, b as usize))
}

/// The fragments of one triangle (world vertices `p`) of sheet width `width`, those on the
/// traced cells (`depth` of the cells from `first` on) and nearer than their hits, appended to
/// `out`.
#[allow(clippy::too_many_arguments)]
fn triangle_fragments<const N: usize>(
    map: &RetinaMap<'_, N>,
    (first, depth): (usize, &[f32]),
    p: [Vector<N>; 3],
    width: f64,
    obj: u32,
    tri: u32,
    out: &mut Vec<Fragment>,
) {
    let mut q = [[0.0; 3]; 3];
    let mut z = [0.0; 3];
    for i in 0..3 {
        let Some((g, zi)) = map.project(&p[i]) else {
            return;
        };
        q[i] = g;
        z[i] = zi;
    }
    let h = width / 2.0;
    let mut range = [(0, 0); 3];
    for k in 0..3 {
        let lo = q[0][k].min(q[1][k]).min(q[2][k]) - h;
        let hi = q[0][k].max(q[1][k]).max(q[2][k]) + h;
        match cells_in(lo, hi, map.res[k]) {
            Some(r) => range[k] = r,
            None => return,
        }
    }
    let mut test = |i: [usize; 3]| {
        let c = [i[0] as f64 + 0.5, i[1] as f64 + 0.5, i[2] as f64 + 0.5];
        let b = closest_on_triangle(&c, &q);
        let x: [f64; 3] = std::array::from_fn(|k| b[0] * q[0][k] + b[1] * q[1][k] + b[2] * q[2][k]);
        let d = sub3(&c, &x);
        if dot3(&d, &d) > h * h {
            return;
        }
        // Perspective-correct: the retina point Σ b'_i g_i is the image of Σ b_i p_i with
        // b_i ∝ b'_i / z_i.
        let w: [f64; 3] = std::array::from_fn(|k| b[k] / z[k]);
        let s = w[0] + w[1] + w[2];
        let bary = w.map(|x| x / s);
        let pt: Vector<N> =
            std::array::from_fn(|k| bary[0] * p[0][k] + bary[1] * p[1][k] + bary[2] * p[2][k]);
        let dep = map.depth(&pt);
        let cell = map.cell(i);
        let on_slab = cell.checked_sub(first).filter(|&c| c < depth.len());
        if on_slab.is_some_and(|c| dep < depth[c] as f64) {
            out.push(Fragment {
                cell,
                depth: dep,
                obj,
                tri,
                bary,
            });
        }
    };
    // The cells within h of the triangle lie within h of its plane: along the axis the plane's
    // normal m is most aligned with, each column of cells meets that slab in a short run.
    let m = cross3(&sub3(&q[1], &q[0]), &sub3(&q[2], &q[0]));
    let a = (0..3)
        .max_by(|&i, &j| m[i].abs().total_cmp(&m[j].abs()))
        .unwrap_or(0);
    let ml = dot3(&m, &m).sqrt();
    let scale_len = dot3(&sub3(&q[1], &q[0]), &sub3(&q[1], &q[0]))
        .max(dot3(&sub3(&q[2], &q[0]), &sub3(&q[2], &q[0])));
    if !(m[a].abs() > 1e-9 * scale_len) {
        for i2 in range[2].0..=range[2].1 {
            for i1 in range[1].0..=range[1].1 {
                for i0 in range[0].0..=range[0].1 {
                    test([i0, i1, i2]);
                }
            }
        }
        return;
    }
    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
    let half = h * ml / m[a].abs();
    for ic in range[c].0..=range[c].1 {
        for ib in range[b].0..=range[b].1 {
            let (xb, xc) = (ib as f64 + 0.5, ic as f64 + 0.5);
            let xa = q[0][a] - (m[b] * (xb - q[0][b]) + m[c] * (xc - q[0][c])) / m[a];
            let Some((lo, hi)) = cells_in(xa - half, xa + half, map.res[a]) else {
                continue;
            };
            let (lo, hi) = (lo.max(range[a].0), hi.min(range[a].1));
            for ia in lo..=hi {
                let mut i = [0; 3];
                i[a] = ia;
                i[b] = ib;
                i[c] = ic;
                test(i);
            }
        }
    }
}

/// A rough upper bound of the fragments of `scene`'s surfaces (for the memory guard): each
/// triangle's bounding box of cells.
fn fragment_bound<const N: usize>(map: &RetinaMap<'_, N>, scene: &Scene<N>) -> f64 {
    let mut total = 0.0;
    for o in scene.objects.iter() {
        let Some(s) = &o.surface else { continue };
        total += s
            .triangles
            .par_iter()
            .map(|t| {
                let mut cells = 1.0;
                let g: Vec<[f64; 3]> = t
                    .iter()
                    .filter_map(|&i| map.project(&o.mesh.vertices[i as usize]).map(|x| x.0))
                    .collect();
                if g.len() < 3 {
                    return 0.0;
                }
                for k in 0..3 {
                    let lo = g.iter().map(|x| x[k]).fold(f64::INFINITY, f64::min) - s.width / 2.0;
                    let hi =
                        g.iter().map(|x| x[k]).fold(f64::NEG_INFINITY, f64::max) + s.width / 2.0;
                    let span = (hi.min(map.res[k] as f64) - lo.max(0.0)).max(0.0);
                    cells *= span + 1.0;
                }
                cells
            })
            .sum::<f64>();
    }
    total
}

/// Projects the surface objects of `scene` (N = 4) into its traced `retina`: their fragments
/// nearer than the traced hits, blended over them front to back (module docs); the retina's
/// depth, normal (the unit normal facing the eye, [`super::shade`]) and ids become those of the
/// nearest surface where one is in front. Does nothing for scenes without surfaces. `retina`
/// may be a slab of the retina, its cells from `first` on (fragments on other cells are
/// dropped; each cell gets the bits it gets in the whole retina).
pub fn splat<const N: usize>(
    scene: &Scene<N>,
    retina: &mut Retina,
    first: usize,
    progress: &Progress,
) -> NdResult<()> {
    match crate::dim::same_ref::<_, Scene<4>>(scene) {
        Some(scene) if scene.objects.iter().any(|o| o.surface.is_some()) => {
            splat_4d(scene, retina, first, progress)
        }
        _ => Ok(()),
    }
}

/// [`splat`] in R^4 (surfaces live there), compiled once.
fn splat_4d(
    scene: &Scene<4>,
    retina: &mut Retina,
    first: usize,
    progress: &Progress,
) -> NdResult<()> {
    const N: usize = 4;
    let cam = &scene.camera;
    let map = RetinaMap {
        cam,
        res: [cam.resolution[0], cam.resolution[1], cam.resolution[2]],
    };
    let bound = fragment_bound(&map, scene);
    crate::memory::check(
        bound * std::mem::size_of::<Fragment>() as f64 * 1.5,
        &format!("the surfaces' retina fragments (up to {bound:.3e})"),
    )
    .map_err(|message| NdError::Value {
        arg: "surface objects".into(),
        message,
    })?;
    // 1. Fragments, triangle chunk by chunk, concatenated in object and triangle order.
    let jobs: Vec<(usize, usize)> = scene
        .objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| o.surface.as_ref().map(|s| (i, s.triangles.len())))
        .flat_map(|(i, n)| (0..n.div_ceil(CHUNK)).map(move |c| (i, c)))
        .collect();
    let depth = &retina.depth;
    let parts: Vec<Vec<Fragment>> = jobs
        .par_iter()
        .map(|&(oi, chunk)| {
            let mut out = Vec::new();
            if progress.cancel.load(Ordering::Relaxed) {
                return out;
            }
            let o = &scene.objects[oi];
            let s = o.surface.as_ref().expect("a surface job");
            let end = ((chunk + 1) * CHUNK).min(s.triangles.len());
            for t in chunk * CHUNK..end {
                let p = s.triangles[t].map(|i| o.mesh.vertices[i as usize]);
                triangle_fragments(
                    &map,
                    (first, depth),
                    p,
                    s.width,
                    oi as u32,
                    t as u32,
                    &mut out,
                );
            }
            out
        })
        .collect();
    if progress.cancel.load(Ordering::Relaxed) {
        return Err(NdError::Cancelled);
    }
    let mut frags: Vec<Fragment> = parts.into_iter().flatten().collect();
    frags.par_sort_unstable_by(|a, b| {
        (a.cell, a.depth, a.obj, a.tri)
            .partial_cmp(&(b.cell, b.depth, b.obj, b.tri))
            .expect("finite depths")
    });
    // 2. Each cell's layers, shaded and blended.
    let mut groups = Vec::new();
    let mut start = 0;
    for i in 1..=frags.len() {
        if i == frags.len() || frags[i].cell != frags[start].cell {
            groups.push(start..i);
            start = i;
        }
    }
    let depth_range = match scene.render.mode {
        crate::scene::desc::RenderMode::Depth => crate::render::shade::depth_range(scene),
        _ => (0.0, 1.0),
    };
    let shared = |a: &Fragment, b: &Fragment| {
        a.obj == b.obj && {
            let s = scene.objects[a.obj as usize]
                .surface
                .as_ref()
                .expect("a surface");
            let (ta, tb) = (s.triangles[a.tri as usize], s.triangles[b.tri as usize]);
            ta.iter().any(|v| tb.contains(v))
        }
    };
    let rgba_in = &retina.rgba;
    let results: Vec<(usize, [f32; 4], f32, Vector<N>, i32, i64)> = groups
        .into_par_iter()
        .map(|g| {
            let cell_frags = &frags[g];
            let mut layers: Vec<&Fragment> = Vec::new();
            for f in cell_frags {
                if layers.len() == MAX_LAYERS {
                    break;
                }
                if !layers.iter().any(|l| shared(l, f)) {
                    layers.push(f);
                }
            }
            let mut acc = [0.0f64; 4];
            let mut through = 1.0;
            let mut front = ([0.0; N], 0.0);
            for (k, f) in layers.iter().enumerate() {
                let o = &scene.objects[f.obj as usize];
                let s = o.surface.as_ref().expect("a surface");
                let t = s.triangles[f.tri as usize];
                let x: Vector<N> = std::array::from_fn(|i| {
                    (0..3)
                        .map(|j| f.bary[j] * o.mesh.vertices[t[j] as usize][i])
                        .sum()
                });
                let pt = SurfacePoint {
                    obj: f.obj as usize,
                    tri: f.tri as usize,
                    bary: f.bary,
                    x,
                    dir: map.direction(&x),
                    depth: f.depth,
                };
                let (c, e) = surface_color(scene, s, &pt, depth_range);
                if k == 0 {
                    front = (e, f.depth);
                }
                let alpha = o.material.opacity;
                for j in 0..3 {
                    acc[j] += through * alpha * c[j];
                }
                acc[3] += through * alpha;
                through *= 1.0 - alpha;
                if through <= 0.0 {
                    break;
                }
            }
            let cell = cell_frags[0].cell - first;
            let px: [f32; 4] =
                std::array::from_fn(|j| (acc[j] + through * rgba_in[cell * 4 + j] as f64) as f32);
            let nearest = layers[0];
            (
                cell,
                px,
                front.1 as f32,
                front.0,
                nearest.obj as i32,
                nearest.tri as i64,
            )
        })
        .collect();
    for (cell, px, d, e, obj, tri) in results {
        retina.rgba[cell * 4..cell * 4 + 4].copy_from_slice(&px);
        retina.depth[cell] = d;
        for k in 0..N {
            retina.normal[cell * N + k] = e[k] as f32;
        }
        retina.object_id[cell] = obj;
        retina.primitive_id[cell] = tri;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
