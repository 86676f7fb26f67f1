//! `[slice]` and [`slice_desc`]: an N-dimensional scene cut by the hyperplane n̂·x = offset,
//! as a scene of dimension N−1 — the view of 4D Toys and tessexel, an object passing through
//! our space — traced and composited like any scene.
//!
//! ```toml
//! [slice]                      # `ndtrace scene.toml -o cut.png` renders the 3D slice
//! normal = [0, 0, 0, 1]        # the hyperplane w = 0.3 (normal need not be unit length)
//! offset = 0.3
//! ```
//!
//! ```python
//! cut = ndtrace.slice_scene(scene, [0, 0, 0, 1], 0.3)   # a Scene of dimension N − 1
//! ```
//!
//! What the slice scene holds, in the hyperplane's coordinates (`crate::mesh::slice`'s
//! basis and origin):
//!
//! - each object's world-space mesh sliced ([`crate::mesh::slice::slice`]), with its
//!   material and its per-vertex `values` interpolated along the cut edges (surfaces, which
//!   meet a hyperplane in points, and objects the hyperplane misses are left out);
//! - the lights projected into the hyperplane: a directional light's direction, a point
//!   light's position; a directional light along n̂ (none of it in the hyperplane) shines from
//!   the camera instead;
//! - a camera looking at the centre of the sliced objects from the N-D camera's distance, along
//!   its viewing direction projected into the hyperplane (or, when that direction is nearly
//!   n̂, from a fixed oblique direction), its retina axes from the N-D camera's projected
//!   ones; the same field of view or extent, and the first N−2 resolutions;
//! - the clip hyperplanes intersected with the slicing one (a clip parallel to it keeps the
//!   whole slice or none of it), the background, ambient light and `[render]` options; not the
//!   `[composite]` table (made for N dimensions) nor the `[animation]`.

use super::desc::{
    CameraDesc, ClipDesc, LightDesc, ObjectDesc, Resolution, Rows, SceneDesc, ShapeKind, SliceDesc,
    Table, UpDesc,
};
use super::fields::{slice_plane, R};
use super::Scene;
use crate::linalg::{dot, norm, sub, Vector};
use crate::mesh::slice::{slice, SlicePlane};

/// Directions of a fallback view (toward the camera), in the slice's coordinates.
const OBLIQUE: [f64; 8] = [1.2, 1.6, 2.0, 2.4, 2.8, 3.2, 3.6, 4.0];

/// The description of the (N−1)-dimensional scene that `scene` (built from `desc`) cuts from
/// the hyperplane of `cut` (the module documentation says what it holds). Errors name
/// `path.normal` or `path.offset`.
pub fn slice_desc<const N: usize>(
    desc: &SceneDesc,
    scene: &Scene<N>,
    cut: &SliceDesc,
    path: &str,
) -> R<SceneDesc> {
    let plane = slice_plane::<N>(cut, path)?;
    let m = N - 1;
    let lift = |y: &[f64]| -> Vector<N> {
        let mut x = plane.origin;
        for (k, b) in plane.basis.iter().enumerate() {
            x = std::array::from_fn(|i| x[i] + y[k] * b[i]);
        }
        x
    };
    let project_dir =
        |d: &Vector<N>| -> Vec<f64> { plane.basis.iter().map(|b| dot(b, d)).collect() };
    // 1. The objects.
    let mut objects = Vec::new();
    let (mut lo, mut hi) = (vec![f64::INFINITY; m], vec![f64::NEG_INFINITY; m]);
    for (o, d) in scene.objects.iter().zip(&desc.objects) {
        if d.shape == ShapeKind::Surface || o.mesh.simplices.is_empty() {
            continue;
        }
        let s = slice(&o.mesh, &plane);
        if s.is_empty() {
            continue;
        }
        let coords = s.coords();
        for p in coords.chunks(m) {
            for k in 0..m {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let values = o.texture.as_ref().and_then(|t| t.values.as_ref()).map(|v| {
            super::desc::Column::Inline(s.crossings.iter().map(|c| c.interpolate(v)).collect())
        });
        let table = |w: usize, v: Vec<f64>| Rows::Array(Table::new(w, v).expect("whole rows"));
        let simplices: Vec<i64> = s.simplices.iter().map(|&i| i64::from(i)).collect();
        objects.push(ObjectDesc {
            shape: ShapeKind::Mesh,
            vertices: Some(table(m, coords)),
            simplices: Some(Rows::Array(Table::new(m, simplices).expect("whole rows"))),
            triangles: None,
            width: None,
            line_width: None,
            file: None,
            subdivisions: None,
            field: None,
            key: None,
            extent: None,
            height: None,
            smooth: None,
            values,
            material: d.material.clone(),
            transform: Vec::new(),
            clip: clips_in(&d.clip, &plane),
            cap: d.cap,
            label: d.label.clone(),
        });
    }
    // 2. The camera.
    let centre: Vec<f64> = if lo[0].is_finite() {
        (0..m).map(|k| 0.5 * (lo[k] + hi[k])).collect()
    } else {
        plane
            .coords(&scene.camera.position)
            .iter()
            .map(|_| 0.0)
            .collect()
    };
    let target = lift(&centre);
    let distance = norm(&sub(&scene.camera.position, &target)).max(1e-9);
    let view = scene.camera.axis(N - 1);
    let pv = project_dir(&view);
    let toward = if norm_v(&pv) > 0.25 {
        pv.iter().map(|x| -x / norm_v(&pv)).collect::<Vec<_>>()
    } else {
        let o = &OBLIQUE[..m];
        o.iter().map(|x| x / norm_v(o)).collect()
    };
    let position: Vec<f64> = (0..m).map(|k| centre[k] + distance * toward[k]).collect();
    // Up vectors: the N-D retina axes u_2 … u_{N−1} projected, then the slice's axes, made
    // orthonormal to the view and each other; the first N−3 that are independent.
    let mut frame: Vec<Vec<f64>> = vec![toward.clone()];
    let mut up = Vec::new();
    let candidates = (1..N - 1)
        .map(|k| project_dir(&scene.camera.axis(k)))
        .chain(
            (0..m)
                .rev()
                .map(|k| (0..m).map(|i| if i == k { 1.0 } else { 0.0 }).collect()),
        );
    for c in candidates {
        if up.len() + 2 >= m {
            break;
        }
        let mut u = c.clone();
        for f in &frame {
            let p: f64 = u.iter().zip(f).map(|(a, b)| a * b).sum();
            u.iter_mut().zip(f).for_each(|(a, b)| *a -= p * b);
        }
        let l = norm_v(&u);
        if l > 0.3 * norm_v(&c).max(1e-300) && l > 1e-9 {
            let u: Vec<f64> = u.iter().map(|x| x / l).collect();
            frame.push(u.clone());
            up.push(u);
        }
    }
    let camera = CameraDesc {
        position,
        look_at: Some(centre.clone()),
        up: Some(UpDesc::List(up)),
        orientation: None,
        projection: desc.camera.projection,
        fov: desc.camera.fov,
        extent: desc.camera.extent,
        resolution: match &desc.camera.resolution {
            Resolution::Uniform(r) => Resolution::Uniform(*r),
            Resolution::PerAxis(r) => Resolution::PerAxis(r.iter().take(m - 1).copied().collect()),
        },
    };
    // 3. The lights.
    let lights = desc
        .lights
        .iter()
        .zip(&scene.lights)
        .map(|(d, l)| match (d, l) {
            (LightDesc::Directional { color, .. }, super::Light::Directional { direction, .. }) => {
                let p = project_dir(direction);
                let direction = if norm_v(&p) > 1e-9 { p } else { toward.clone() };
                LightDesc::Directional {
                    direction,
                    color: color.clone(),
                }
            }
            (LightDesc::Point { color, falloff, .. }, super::Light::Point { position, .. }) => {
                LightDesc::Point {
                    position: plane.coords(position),
                    color: color.clone(),
                    falloff: *falloff,
                }
            }
            _ => unreachable!("a light's description and its build agree"),
        })
        .collect();
    Ok(SceneDesc {
        dim: m,
        background: desc.background.clone(),
        ambient: desc.ambient.clone(),
        camera,
        lights,
        objects,
        render: desc.render.clone(),
        composite: None,
        animation: None,
        slice: None,
        clip: clips_in(&desc.clip, &plane),
        cap: desc.cap,
    })
}

fn norm_v(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Clip hyperplanes n̂_c·x = c in the slicing hyperplane's coordinates: with x = origin + Bᵀy,
/// n̂_c·x ≤ c becomes (B n̂_c)·y ≤ c − n̂_c·origin, normalized. A clip parallel to the slicing
/// hyperplane keeps everything (it is dropped) or nothing (a clip no point passes).
fn clips_in<const N: usize>(clips: &[ClipDesc], plane: &SlicePlane<N>) -> Vec<ClipDesc> {
    clips
        .iter()
        .filter_map(|c| {
            let n: Vector<N> = std::array::from_fn(|k| c.normal.get(k).copied().unwrap_or(0.0));
            let len = norm(&n);
            if c.normal.len() != N || !(len > 0.0) {
                return None;
            }
            let n: Vector<N> = std::array::from_fn(|k| n[k] / len);
            let offset = c.offset - dot(&n, &plane.origin);
            let p: Vec<f64> = plane.basis.iter().map(|b| dot(b, &n)).collect();
            let l = norm_v(&p);
            if l > 1e-12 {
                Some(ClipDesc {
                    normal: p.iter().map(|x| x / l).collect(),
                    offset: offset / l,
                })
            } else if offset >= 0.0 {
                None
            } else {
                let mut normal = vec![0.0; N - 1];
                normal[0] = 1.0;
                Some(ClipDesc {
                    normal,
                    offset: -f64::MAX,
                })
            }
        })
        .collect()
}
