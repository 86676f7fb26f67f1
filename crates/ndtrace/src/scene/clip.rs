//! `clip` and `cap`: the clip hyperplanes of each object (its own and the scene's) and the caps
//! that fill their cuts, as the tracer uses them (`render/clip.rs` traces the rays).
//!
//! ```toml
//! clip = [{ normal = [0, 0, 1, 1], offset = 0.2 }]      # the whole scene: keep n̂·x ≤ 0.2
//! [[objects]]
//! shape = "sphere"
//! clip = [{ normal = [1, 0, 0, 0], offset = 0 }]       # this object too
//! cap = true                                           # fill its cuts
//! ```
//!
//! A hyperplane n̂·x = c (n̂ the unit `normal`) keeps what lies on its near side, n̂·x ≤ c, in
//! world space. A cap is an extra object after the scene's objects, with its object's material
//! (flat): the cone from their centroid over the object's slice by the hyperplane
//! ([`crate::mesh::slice`]), oriented along +n̂ (outward of what is kept), clipped by the
//! object's other hyperplanes.

use super::desc::{ClipDesc, SceneDesc, ShapeKind};
use super::errors::PathError;
use super::fields::R;
use super::objects::Object;
use crate::geometry::simplex_normal;
use crate::linalg::{dot, norm, sub, Vector};
use crate::mesh::slice::{slice, SlicePlane};
use crate::mesh::Mesh;
use std::collections::HashMap;
use std::ops::Range;

/// The clips of one object: its hyperplanes (n̂, c), keeping n̂·x ≤ c, and, for a cap, what it
/// caps.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObjectClips<const N: usize> {
    /// The clip hyperplanes acting on the object (its own and the scene's).
    pub planes: Vec<(Vector<N>, f64)>,
    /// For a cap of an object not known to be convex: the index of that object, whose
    /// simplices decide where the cap lies inside it (filled in with global ids by the build).
    pub inside_of: Option<Range<u32>>,
    /// For a cap: the object it caps.
    pub cap_of: Option<usize>,
}

impl<const N: usize> ObjectClips<N> {
    /// Whether the point `x` is kept: on the near side of every hyperplane (n̂·x ≤ c).
    #[inline]
    pub fn keeps_point(&self, x: &Vector<N>) -> bool {
        self.planes.iter().all(|(n, c)| dot(n, x) <= *c)
    }
}

/// The clips of a scene, per object id (empty when no object has any: then rays are not
/// checked).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Clips<const N: usize> {
    /// Per object id (the caps' too).
    pub objects: Vec<ObjectClips<N>>,
}

impl<const N: usize> Clips<N> {
    /// Whether any object has clips: rays are checked only then.
    #[inline]
    pub fn active(&self) -> bool {
        !self.objects.is_empty()
    }
}

/// The hyperplanes of a `clip` list at `path` (errors name `path[k].normal` / `.offset`).
pub(crate) fn planes<const N: usize>(clips: &[ClipDesc], path: &str) -> R<Vec<(Vector<N>, f64)>> {
    clips
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let p = format!("{path}[{k}]");
            if c.normal.len() != N {
                return Err(PathError::new(
                    format!("{p}.normal"),
                    format!("expected {N} numbers, got {}", c.normal.len()),
                ));
            }
            let plane = SlicePlane::<N>::new(&c.normal, c.offset).map_err(|e| match e {
                crate::NdError::Value { arg, message } => {
                    PathError::new(format!("{p}.{arg}"), message)
                }
                e => PathError::new(p.clone(), e.to_string()),
            })?;
            Ok((plane.normal, plane.offset))
        })
        .collect()
}

/// The cap of `mesh` in the hyperplane (n̂, c): the cone from the centroid of its slice over
/// the slice's pieces, each simplex oriented along +n̂; `None` when the slice is empty or not
/// closed (the mesh is not closed where it is cut).
pub(crate) fn cap_mesh<const N: usize>(mesh: &Mesh<N>, n: &Vector<N>, c: f64) -> Option<Mesh<N>> {
    let plane = SlicePlane::<N>::new(n, c).ok()?;
    let s = slice(mesh, &plane);
    if s.is_empty() || !closed(&s.simplices, N - 1) {
        return None;
    }
    let count = s.points.len() as f64;
    let apex: Vector<N> =
        std::array::from_fn(|k| s.points.iter().map(|p| p[k]).sum::<f64>() / count);
    let mut vertices = s.points.clone();
    let a = vertices.len() as u32;
    vertices.push(apex);
    let mut simplices = Vec::with_capacity(s.len());
    for piece in s.simplices.chunks(N - 1) {
        let mut idx: [u32; N] = std::array::from_fn(|k| if k == 0 { a } else { piece[k - 1] });
        let pts: [Vector<N>; N] = std::array::from_fn(|k| vertices[idx[k] as usize]);
        let normal = simplex_normal(&pts);
        let d = dot(&normal, n);
        // A piece seen edge-on from the apex has no volume: leave it out.
        let edges: f64 = pts[1..].iter().map(|p| norm(&sub(p, &pts[0]))).product();
        if !(norm(&normal) > 1e-12 * edges) {
            continue;
        }
        if d < 0.0 {
            idx.swap(1, 2.min(N - 1));
            if N == 2 {
                idx.swap(0, 1);
            }
        }
        simplices.push(idx);
    }
    (!simplices.is_empty()).then_some(Mesh {
        vertices,
        simplices,
    })
}

/// Whether the (N−2)-chain of `pieces` (`width` indices each) has no boundary.
fn closed(pieces: &[u32], width: usize) -> bool {
    let mut sum: HashMap<Vec<u32>, i32> = HashMap::new();
    for p in pieces.chunks(width) {
        for k in 0..width {
            let mut face: Vec<u32> = (0..width).filter(|&i| i != k).map(|i| p[i]).collect();
            let mut sign = if k % 2 == 0 { 1 } else { -1 };
            for i in 1..face.len() {
                let mut j = i;
                while j > 0 && face[j - 1] > face[j] {
                    face.swap(j - 1, j);
                    sign = -sign;
                    j -= 1;
                }
            }
            *sum.entry(face).or_default() += sign;
        }
    }
    sum.values().all(|&v| v == 0)
}

/// Step 2b of a build: the clips of every object of `desc` (built as `objects`), and the caps
/// appended to `objects`; warnings for caps that cannot be made. The caps' `inside_of` holds
/// object indices until the build knows the global ids.
pub(crate) fn clips<const N: usize>(
    desc: &SceneDesc,
    objects: &mut Vec<Object<N>>,
    warnings: &mut Vec<String>,
) -> R<Clips<N>> {
    let scene_planes = planes::<N>(&desc.clip, "clip")?;
    let mut per: Vec<ObjectClips<N>> = Vec::with_capacity(objects.len());
    for (i, o) in desc.objects.iter().enumerate() {
        let mut p = scene_planes.clone();
        p.extend(planes::<N>(&o.clip, &format!("objects[{i}].clip"))?);
        per.push(ObjectClips {
            planes: p,
            ..Default::default()
        });
    }
    if per.iter().all(|c| c.planes.is_empty()) {
        return Ok(Clips::default());
    }
    let given = objects.len();
    for i in 0..given {
        let d = &desc.objects[i];
        if !d.cap.unwrap_or(desc.cap) || d.shape == ShapeKind::Surface {
            continue;
        }
        let convex = matches!(
            d.shape,
            ShapeKind::Simplex | ShapeKind::Hypercube | ShapeKind::CrossPolytope
        );
        for (k, (n, c)) in per[i].planes.clone().iter().enumerate() {
            let Some(mesh) = cap_mesh(&objects[i].mesh, n, *c) else {
                if !objects[i].mesh.simplices.is_empty() {
                    warnings.push(format!(
                        "objects[{i}].cap: the clip hyperplane {k} does not cut a closed part of \
                         the object; no cap there"
                    ));
                }
                continue;
            };
            let planes = per[i]
                .planes
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != k)
                .map(|(_, p)| *p)
                .collect();
            let parent = &objects[i];
            let mut material = parent.material.clone();
            material.smooth = false;
            material.texture = None;
            objects.push(Object {
                mesh,
                material,
                vertex_normals: None,
                convex: crate::convex::Certificate::none(),
                surface: None,
                texture: None,
                own_from_world: parent.own_from_world,
            });
            per.push(ObjectClips {
                planes,
                inside_of: (!convex).then_some(i as u32..i as u32 + 1),
                cap_of: Some(i),
            });
        }
    }
    Ok(Clips { objects: per })
}
