//! The scene side of pictures drawn at their own resolution (N = 4; see
//! [`crate::composite::probe`]): [`ScenePicture`] gives the compositor the scene's structure in
//! the retina and answers its 4D rays, with the tracer's own shading.
//!
//! The structure of a mesh comes from its ridges ([`crate::mesh::features::Ridges`], found once
//! per object and shared with the feature edges): each ridge's triangle and the simplices
//! around it are projected into the retina (cell coordinates, through the camera's
//! perspective), and the ridge becomes a count sheet when its simplices' far vertices are not
//! split evenly by its plane (δ = the simplices on its normal's side less those on the other:
//! a contour, where the hypersurface folds away from the eye, or an open boundary), and a
//! crease sheet when its two simplices' normals differ by more than the crease angle. Whether
//! a mesh is smooth ([`ObjectLook::smooth`]) is the share of its bends that are creases: fewer
//! than half of its ridges bent by more than a degree.

use super::shade::{
    blinn_phong, depth_range, id_color, shade_hit, shading_normal, shadow_ray, toward_light,
    SHADOW_OFFSET,
};
use super::surface::{surface_color, SurfacePoint};
use crate::camera::{Camera, Projection};
use crate::composite::{
    ObjectLook, Probe, SceneProbe, Sheet, SheetKind, SheetVertex, Structure, TextureLines,
    MAX_TEXTURE_LINES,
};
use crate::linalg::{add, dot, mat_vec, norm, scale, sub, Rgb, Vector};
use crate::ray::{Hit, Ray};
use crate::scene::desc::{RenderMode, Shading};
use crate::scene::Scene;
use rayon::prelude::*;

/// Ridges bent by more than this (degrees) count toward an object's share of creases.
const BENT: f64 = 1.0;

/// The dimension of the scenes pictures ask (a 3D retina): the code below is compiled once,
/// for it ([`crate::dim::same_ref`]).
const N: usize = 4;

/// A 4D scene as its pictures ask it ([`SceneProbe`]): the structure of its objects in its
/// retina, and the nearest hit of the ray through any retina point.
pub struct ScenePicture<'a> {
    scene: &'a Scene<N>,
    /// Per global simplex id: back-face culling removes it (when the scene culls).
    culled: Option<Vec<bool>>,
    /// The depth mode's near and far depths.
    depth_range: (f64, f64),
}

impl<'a> ScenePicture<'a> {
    /// The pictures' view of `scene`; `None` unless it is 4D (a 3D retina) and without clip
    /// hyperplanes (a clipped object is open where its clips cut it, which its sheets do not
    /// say: its pictures are drawn from the retina's cells).
    pub fn new<const M: usize>(scene: &'a Scene<M>) -> Option<Self> {
        let scene = crate::dim::same_ref::<Scene<M>, Scene<N>>(scene)?;
        if scene.clips.active() {
            return None;
        }
        // The crease visibility of a convex object alone asks for its certificate: found
        // here, before the parallel loops.
        scene.find_certificates();
        Some(ScenePicture {
            scene,
            culled: scene.render.cull_backfaces.then(|| scene.backfaces()),
            depth_range: match scene.render.mode {
                RenderMode::Depth => depth_range(scene),
                _ => (0.0, 1.0),
            },
        })
    }

    fn camera(&self) -> &Camera<N> {
        &self.scene.camera
    }

    /// The ray through the retina point `p` (cell coordinates: column, row, slice).
    fn ray_at(&self, p: [f64; 3]) -> Ray<N> {
        let cam = self.camera();
        let mut u = [0.0; N];
        for k in 0..3 {
            let half = cam.resolution[k] as f64 / 2.0;
            u[k] = if k == 1 {
                (half - p[k]) * cam.cell
            } else {
                (p[k] - half) * cam.cell
            };
        }
        cam.ray(&u[..N - 1])
    }

    fn accepts(&self, id: u32) -> bool {
        self.culled.as_ref().is_none_or(|c| !c[id as usize])
    }

    /// Retina position (cell coordinates) and view coordinate Z of the world point `x`; `None`
    /// at or behind a perspective eye.
    fn project(&self, x: &Vector<N>) -> Option<SheetVertex> {
        let cam = self.camera();
        let rel = sub(x, &cam.position);
        let z = dot(&rel, &cam.axis(N - 1));
        let zd = match cam.projection {
            Projection::Perspective if !(z > 1e-12 * norm(&rel)) => return None,
            Projection::Perspective => z,
            Projection::Orthographic => 1.0,
        };
        let mut p = [0.0; 3];
        for (k, pk) in p.iter_mut().enumerate() {
            let u = dot(&rel, &cam.axis(k)) / zd / cam.cell;
            let half = cam.resolution[k] as f64 / 2.0;
            *pk = if k == 1 { half - u } else { u + half };
        }
        p.iter()
            .all(|v| v.is_finite())
            .then_some(SheetVertex { p, z })
    }

    /// The colour of a camera ray's nearest hit, as the tracer shades it in the scene's render
    /// mode.
    fn color(&self, ray: &Ray<N>, hit: &Hit<N>) -> [f64; 3] {
        let scene = self.scene;
        match scene.render.mode {
            RenderMode::Shaded => shade_hit(scene, ray, hit),
            RenderMode::Depth => {
                let depth = scene.camera.depth(hit.t, norm(&ray.dir));
                let (lo, hi) = self.depth_range;
                [1.0 - 0.8 * ((depth - lo) / (hi - lo)).clamp(0.0, 1.0); 3]
            }
            RenderMode::Normal => {
                let (obj, local) = scene.locate(hit.prim);
                let n = shading_normal(scene, hit, obj, local, ray);
                std::array::from_fn(|k| if k < N { 0.5 + 0.5 * n[k] } else { 0.5 })
            }
            RenderMode::PrimitiveId => id_color(hit.prim),
            RenderMode::Barycentric => {
                std::array::from_fn(|k| if k < N { hit.bary[k] } else { 0.0 })
            }
        }
    }
}

impl ScenePicture<'_> {
    /// The lighting of [`shade_hit`] split by its linearity in the colour C: (F, S) with
    /// c(C) = C ∘ F + S — the same lights, shadows and terms, so that a texture line's colour
    /// is shaded as the hit is.
    fn lighting(&self, ray: &Ray<N>, hit: &Hit<N>, obj: usize, local: usize) -> (Rgb, Rgb) {
        let scene = self.scene;
        let m = &scene.objects[obj].material;
        let n = shading_normal(scene, hit, obj, local, ray);
        let x = ray.at(hit.t);
        let v = scale(&ray.dir, -1.0 / norm(&ray.dir));
        let eps = SHADOW_OFFSET * scene.extent;
        let mut f: Rgb = std::array::from_fn(|k| m.ambient[k] * scene.ambient[k]);
        let mut s: Rgb = [0.0; 3];
        for light in &scene.lights {
            let Some(to) = toward_light(light, &x) else {
                continue;
            };
            let ndl = dot(&n, &to.dir);
            if ndl <= 0.0 {
                continue;
            }
            if scene.render.shadows {
                let along = dot(&hit.normal, &to.dir) >= 0.0;
                let (shadow, tmax) = shadow_ray(&x, &hit.normal, along, &to.dir, to.dist, eps);
                if scene.instances.any_hit(&shadow, 0.0, tmax, &|_| true, 0..0) {
                    continue;
                }
            }
            let spec = blinn_phong(&n, &to.dir, &v, m.shininess);
            for k in 0..3 {
                f[k] += to.atten * to.color[k] * m.diffuse[k] * ndl;
                s[k] += to.atten * to.color[k] * m.specular[k] * spec;
            }
        }
        (f, s)
    }

    /// The texture lines at a hit on simplex `local` of object `obj` (isolines: the nearest
    /// level of its values; the lattice: each of the first three object-space coordinates and
    /// its nearest plane), `None` when the object has neither.
    fn lines(&self, ray: &Ray<N>, hit: &Hit<N>, obj: usize, local: usize) -> Option<TextureLines> {
        let o = &self.scene.objects[obj];
        let t = o.texture.as_ref()?;
        // Gouraud's lighting is not linear in the colour at a point: its lines stay the
        // tracer's own.
        if self.scene.render.shading == Shading::Gouraud {
            return None;
        }
        if t.isolines.is_none() && t.lattice.is_none() {
            return None;
        }
        let idx = &o.mesh.simplices[local];
        let value = t.values.as_ref().map(|vals| {
            (0..N)
                .map(|k| hit.bary[k] * vals[idx[k] as usize])
                .sum::<f64>()
        });
        let base = match (value, &t.colormap) {
            (Some(v), Some((map, [lo, hi]))) => map.at((v - lo) / (hi - lo)),
            _ => o.material.color,
        };
        let (f, s) = self.lighting(ray, hit, obj, local);
        let shade = |c: &Rgb| -> [f32; 3] { std::array::from_fn(|k| (c[k] * f[k] + s[k]) as f32) };
        let mut out = TextureLines {
            count: 0,
            value: [0.0; MAX_TEXTURE_LINES],
            level: [0.0; MAX_TEXTURE_LINES],
            color: [[0.0; 3]; MAX_TEXTURE_LINES],
            base: shade(&base),
        };
        let mut push = |value: f64, level: f64, color: [f32; 3]| {
            if out.count < MAX_TEXTURE_LINES {
                out.value[out.count] = value;
                out.level[out.count] = level;
                out.color[out.count] = color;
                out.count += 1;
            }
        };
        if let (Some(v), Some(iso)) = (value, &t.isolines) {
            let nearest = iso
                .values
                .iter()
                .copied()
                .min_by(|a, b| (a - v).abs().total_cmp(&(b - v).abs()));
            if let Some(level) = nearest {
                push(v, level, shade(&iso.color));
            }
        }
        if let Some(lat) = &t.lattice {
            let p = add(&mat_vec(&t.to_object.0, &ray.at(hit.t)), &t.to_object.1);
            for &u in p.iter().take(3) {
                push(
                    u,
                    lat.spacing * (u / lat.spacing).round(),
                    shade(&lat.color),
                );
            }
        }
        Some(out)
    }
}

impl SceneProbe for ScenePicture<'_> {
    fn structure(&self, crease_angle: f64) -> Structure {
        let scene = self.scene;
        let cam = self.camera();
        let res = [cam.resolution[0], cam.resolution[1], cam.resolution[2]];
        let cos_crease = crease_angle.to_radians().cos();
        let cos_bent = BENT.to_radians().cos();
        let meshes = scene
            .objects
            .iter()
            .filter(|o| o.surface.is_none() && !o.mesh.simplices.is_empty())
            .count();
        let mut out = Structure {
            res,
            cell: cam.cell,
            projection: cam.projection,
            counted: scene.skipped_degenerate == 0,
            ..Structure::default()
        };
        let in_box = |v: &SheetVertex| (0..3).all(|k| v.p[k] >= 0.0 && v.p[k] <= res[k] as f64);
        for (o, obj) in scene.objects.iter().enumerate() {
            let base = out.vertices.len() as u32;
            let projected: Vec<Option<SheetVertex>> = obj
                .mesh
                .vertices
                .par_iter()
                .map(|x| self.project(x))
                .collect();
            let vertex = |i: u32| projected[i as usize];
            out.vertices.extend(projected.iter().map(|v| {
                v.unwrap_or(SheetVertex {
                    p: [f64::NAN; 3],
                    z: f64::NAN,
                })
            }));
            if let Some(s) = &obj.surface {
                out.looks.push(ObjectLook {
                    smooth: true,
                    line_width: s.line_width,
                    opacity: obj.material.opacity,
                });
                for (t, tri) in s.triangles.iter().enumerate() {
                    if tri.iter().all(|&i| vertex(i).is_some()) {
                        out.sheets.push(Sheet {
                            v: tri.map(|i| base + i),
                            object: o as u32,
                            kind: SheetKind::Surface { triangle: t as u32 },
                            visible: None,
                        });
                    }
                }
                continue;
            }
            // A mesh: its simplices' projections must lie in front of the eye, and (for the
            // layers to be counted from outside) inside the retina.
            let ids = scene.ids(o);
            let first = ids.start;
            let used: Vec<bool> = (0..obj.mesh.simplices.len())
                .into_par_iter()
                .map(|s| {
                    let g = first + s as u32;
                    self.accepts(g) && norm(&scene.flat_normal(g)) > 0.0
                })
                .collect();
            let outside = obj
                .mesh
                .simplices
                .par_iter()
                .zip(&used)
                .any(|(s, &u)| u && s.iter().any(|&i| vertex(i).is_none_or(|v| !in_box(&v))));
            if outside {
                out.counted = false;
            }
            let Ok(ridges) = scene
                .edge_cache
                .ridges(o, &obj.mesh.vertices, &obj.mesh.simplices)
            else {
                out.counted = false;
                out.looks.push(ObjectLook {
                    smooth: false,
                    line_width: 0.0,
                    opacity: 1.0,
                });
                continue;
            };
            // The known visibility of creases: a convex object alone among the meshes.
            let convex = (meshes == 1).then(|| obj.convex.get()).flatten();
            let facing = |g: u32| -> bool {
                let s = &obj.mesh.simplices[(g - first) as usize];
                let x0 = obj.mesh.vertices[s[0] as usize];
                let side = dot(&scene.flat_normal(g), &cam.toward_eye(&x0));
                // The body lies opposite the normal (true) or along it.
                match convex {
                    Some(true) => side > 0.0,
                    _ => side < 0.0,
                }
            };
            // Per ridge: its sheet, and whether it is bent and a crease.
            let per_ridge: Vec<(Option<Sheet>, bool, bool)> = (0..ridges.ridge_count())
                .into_par_iter()
                .map(|r| {
                    let group = ridges.group(r);
                    let own: Vec<(u32, usize)> = group
                        .iter()
                        .map(|&i| ((i as usize / N) as u32, i as usize % N))
                        .filter(|&(s, _)| used[s as usize])
                        .collect();
                    let Some(&(s0, skip0)) = own.first() else {
                        return (None, false, false);
                    };
                    let simplex = ridges.welded(s0 as usize);
                    let mut v = [0u32; 3];
                    let mut k = 0;
                    for (j, &id) in simplex.iter().enumerate() {
                        if j != skip0 && k < 3 {
                            v[k] = id;
                            k += 1;
                        }
                    }
                    v.sort_unstable();
                    let (mut bent, mut crease) = (false, false);
                    if own.len() == 2 {
                        let na = scene.flat_normal(first + own[0].0);
                        let nb = scene.flat_normal(first + own[1].0);
                        let c = dot(&na, &nb).abs();
                        bent = c < cos_bent;
                        crease = c < cos_crease;
                    }
                    let pv = v.map(vertex);
                    let Some([a, b, c]) = pv
                        .iter()
                        .copied()
                        .collect::<Option<Vec<_>>>()
                        .map(|x| [x[0], x[1], x[2]])
                    else {
                        return (None, bent, crease);
                    };
                    let pa = glam::DVec3::from_array(a.p);
                    let normal = (glam::DVec3::from_array(b.p) - pa)
                        .cross(glam::DVec3::from_array(c.p) - pa);
                    let mut delta = 0i32;
                    for &(s, skip) in &own {
                        let far = ridges.welded(s as usize)[skip];
                        if let Some(f) = vertex(far) {
                            let side = normal.dot(glam::DVec3::from_array(f.p) - pa);
                            delta += if side > 0.0 {
                                1
                            } else if side < 0.0 {
                                -1
                            } else {
                                0
                            };
                        }
                    }
                    if delta == 0 && !crease {
                        return (None, bent, crease);
                    }
                    // A convex object alone: a crease between simplices facing the eye is
                    // seen, one between simplices facing away is not, and a contour (one of
                    // each) is seen edge-on, on the outline.
                    let visible = match convex {
                        Some(_) if own.len() == 2 => {
                            let (fa, fb) = (facing(first + own[0].0), facing(first + own[1].0));
                            Some(fa || fb)
                        }
                        _ => None,
                    };
                    (
                        Some(Sheet {
                            v: v.map(|i| base + i),
                            object: o as u32,
                            kind: SheetKind::Mesh {
                                delta: delta.clamp(-127, 127) as i8,
                                crease,
                            },
                            visible,
                        }),
                        bent,
                        crease,
                    )
                })
                .collect();
            let (bent, creases) = per_ridge.iter().fold((0usize, 0usize), |(b, c), r| {
                (b + usize::from(r.1), c + usize::from(r.2))
            });
            out.looks.push(ObjectLook {
                smooth: bent > 0 && 2 * creases < bent,
                line_width: 0.0,
                opacity: 1.0,
            });
            out.sheets.extend(per_ridge.into_iter().filter_map(|r| r.0));
        }
        out
    }

    fn probe(&self, p: [f64; 3]) -> Probe {
        let ray = self.ray_at(p);
        let scene = self.scene;
        match scene
            .instances
            .closest_hit(&ray, 0.0, f64::INFINITY, &|id| self.accepts(id))
        {
            None => Probe::MISS,
            Some(hit) => {
                let c = self.color(&ray, &hit);
                let (obj, local) = scene.locate(hit.prim);
                let lines = match scene.render.mode {
                    RenderMode::Shaded => self.lines(&ray, &hit, obj, local),
                    _ => None,
                };
                Probe {
                    hit: true,
                    depth: scene.camera.depth(hit.t, norm(&ray.dir)),
                    object: obj as i32,
                    color: c.map(|v| v as f32),
                    lines,
                }
            }
        }
    }

    fn covered(&self, p: [f64; 3]) -> bool {
        let ray = self.ray_at(p);
        self.scene
            .instances
            .any_hit(&ray, 0.0, f64::INFINITY, &|id| self.accepts(id), 0..0)
    }

    fn surface(&self, object: u32, triangle: u32, b: [f64; 3]) -> Option<([f32; 3], f64)> {
        let scene = self.scene;
        let obj = scene.objects.get(object as usize)?;
        let s = obj.surface.as_ref()?;
        let tri = *s.triangles.get(triangle as usize)?;
        let x = tri.map(|i| obj.mesh.vertices[i as usize]);
        // Retina weights → world weights: b_k / Z_k for a perspective camera.
        let w = match self.camera().projection {
            Projection::Perspective => {
                let z = x.map(|v| self.project(&v).map_or(f64::NAN, |p| p.z));
                let w = [0, 1, 2].map(|k| b[k] / z[k]);
                let sum = w[0] + w[1] + w[2];
                if !(sum > 0.0) {
                    return None;
                }
                w.map(|v| v / sum)
            }
            Projection::Orthographic => b,
        };
        let point: Vector<N> =
            std::array::from_fn(|i| w[0] * x[0][i] + w[1] * x[1][i] + w[2] * x[2][i]);
        let cam = self.camera();
        let (dir, depth, ray) = match cam.projection {
            Projection::Perspective => {
                let rel = sub(&point, &cam.position);
                let l = norm(&rel);
                let dir: Vector<N> = std::array::from_fn(|i| rel[i] / l);
                (
                    dir,
                    l,
                    Ray {
                        origin: cam.position,
                        dir,
                    },
                )
            }
            Projection::Orthographic => {
                let view = cam.axis(N - 1);
                let d = dot(&sub(&point, &cam.position), &view);
                let origin: Vector<N> = std::array::from_fn(|i| point[i] - d * view[i]);
                (view, d, Ray { origin, dir: view })
            }
        };
        // A mesh nearer along the point's ray hides it (4D occlusion).
        if depth > 0.0
            && scene.instances.any_hit(
                &ray,
                0.0,
                depth * (1.0 - 1e-9),
                &|id| self.accepts(id),
                0..0,
            )
        {
            return None;
        }
        let pt = SurfacePoint {
            obj: object as usize,
            tri: triangle as usize,
            bary: w,
            x: point,
            dir,
            depth,
        };
        let (c, _) = surface_color(scene, s, &pt, self.depth_range);
        Some((c.map(|v| v as f32), depth))
    }
}
