//! The tracer's shading: a group of camera rays traced and shaded at once, giving each ray the
//! bits of [`super::shade_hit`] (tested cell by cell) with less work per ray.
//!
//! - The camera rays go to the BVH as packets ([`Bvh::closest_hits`](crate::accel::Bvh)).
//! - Per-object constants (k_a ∘ A ∘ C, k_d ∘ C, whether there is a specular term) are
//!   computed once per trace ([`ObjectShading`]).
//! - A ray's light terms are summed at once while none waits for a shadow ray; from the first
//!   that does on, they wait for the shadow pass, in which the shadow rays of the whole group go
//!   to the BVH as packets toward each light. Every ray's terms are still summed in light
//!   order, as [`super::shade_hit`] sums them.
//! - A shadow ray that leaves a convex object on its outer side cannot meet that object again
//!   ([`crate::convex`]): it skips the object's simplices, or is not traced at all when that
//!   object is the whole scene.

use super::shade::{
    blinn_phong, hit_color, id_color, light_term, shading_normal, shadow_ray, toward_light,
    vertex_factors, SHADOW_OFFSET,
};
use super::NearestHit;
use crate::linalg::{add_scaled, dot, norm, scale, Vector};
use crate::ray::{Hit, Ray};
use crate::scene::desc::{RenderMode, Shading};
use crate::scene::Scene;
use std::ops::Range;

/// The per-group buffers of a trace: the camera rays of a group of cells, their hits, and the
/// shadow rays their shading asks for, each traced as packets.
#[derive(Default)]
pub(super) struct GroupTracer<const N: usize> {
    pub(super) rays: Vec<Ray<N>>,
    hits: Vec<Option<Hit<N>>>,
    /// Per camera ray: its colour (ambient and the light terms added at once, then those
    /// added after the shadow pass; 0 on a miss) and its nearest-hit record
    /// ([`NearestHit::MISS`] on a miss).
    pub(super) color: Vec<[f64; 3]>,
    pub(super) nearest: Vec<NearestHit<N>>,
    /// Light contributions (camera ray, colour) added after the shadow pass (a ray's terms from
    /// its first that waits for a shadow ray on), in ray order then light order; `shadow[i]` is
    /// the index of the term's shadow ray, if it has one.
    terms: Vec<(usize, [f64; 3])>,
    shadow: Vec<Option<usize>>,
    /// Shadow rays in light order (coherent packets), their tmax and their results.
    shadow_rays: Vec<Ray<N>>,
    shadow_tmax: Vec<f64>,
    blocked: Vec<bool>,
    /// (light, term, shadow ray) as shading asks for them.
    requests: Vec<(usize, usize, ShadowRay<N>)>,
}

/// What shading needs of an object and its material, computed once per trace.
pub(super) struct ObjectShading {
    /// The ambient term: material ambient × scene ambient × material colour, per channel.
    ambient: [f64; 3],
    /// The diffuse coefficient: material diffuse × material colour, per channel.
    diffuse: [f64; 3],
    /// Whether the material has a specular term.
    specular: bool,
    /// The object's global simplex ids.
    ids: Range<u32>,
    /// Whether they are all the scene's.
    whole_scene: bool,
    /// Its convexity certificate, when shadow rays are cast ([`crate::convex::Certificate`]).
    convex: Option<bool>,
}

impl ObjectShading {
    /// The constants of every object of `scene`, in object order. When shadow rays will be
    /// cast, the objects' convexity certificates not found yet are found first (before the
    /// trace's parallel loops, [`Scene::find_certificates`]).
    pub(super) fn all<const N: usize>(scene: &Scene<N>) -> Vec<Self> {
        let all = 0..scene.simplex_count() as u32;
        let shadows = scene.render.mode == RenderMode::Shaded && scene.render.shadows;
        if shadows {
            scene.find_certificates();
        }
        (0..scene.objects.len())
            .map(|obj| {
                let o = &scene.objects[obj];
                let m = &o.material;
                let ids = scene.ids(obj);
                ObjectShading {
                    convex: shadows.then(|| o.convex.get()).flatten(),
                    ambient: std::array::from_fn(|k| m.ambient[k] * scene.ambient[k] * m.color[k]),
                    diffuse: std::array::from_fn(|k| m.diffuse[k] * m.color[k]),
                    specular: m.specular.iter().any(|&s| s > 0.0),
                    whole_scene: ids == all,
                    ids,
                }
            })
            .collect()
    }
}

/// A shadow ray: the light counts unless a simplex whose id lies outside `skip` is hit with t in
/// (0, tmax). `skip` holds the ids of the object hit when that object is convex and the ray
/// leaves it on the outer side ([`crate::convex`]), else it is empty.
#[derive(Clone, Debug)]
struct ShadowRay<const N: usize> {
    ray: Ray<N>,
    tmax: f64,
    skip: Range<u32>,
}

impl<const N: usize> GroupTracer<N> {
    /// Traces `self.rays` and shades their hits into `self.color` and `self.nearest`; `false`
    /// (and neither is written) when every ray misses.
    pub(super) fn trace_and_shade(
        &mut self,
        scene: &Scene<N>,
        accept: &(impl Fn(u32) -> bool + Sync),
        shading: &[ObjectShading],
        depth_range: (f64, f64),
    ) -> bool {
        let cam = &scene.camera;
        // 1. Nearest hits, sized to the rays (no clearing: `closest_hits` writes every element).
        self.hits.resize(self.rays.len(), None);
        scene
            .instances
            .closest_hits(&self.rays, 0.0, f64::INFINITY, accept, &mut self.hits);
        if scene.clips.active() {
            super::clip::clip_hits(scene, &self.rays, accept, &mut self.hits);
        }
        if self.hits.iter().all(Option::is_none) {
            return false;
        }
        self.color.clear();
        self.nearest.clear();
        self.terms.clear();
        self.shadow.clear();
        let requests = &mut self.requests;
        requests.clear();
        let gouraud = scene.render.shading == Shading::Gouraud;
        // 2. Each ray's colour, but for the light terms that wait for their shadow rays.
        for (r, (ray, hit)) in self.rays.iter().zip(&self.hits).enumerate() {
            let Some(hit) = hit else {
                self.color.push([0.0; 3]);
                self.nearest.push(NearestHit::MISS);
                continue;
            };
            let (obj, local) = scene.locate(hit.prim);
            let n = shading_normal(scene, hit, obj, local, ray);
            let dir_len = norm(&ray.dir);
            let depth = cam.depth(hit.t, dir_len);
            let c = match scene.render.mode {
                RenderMode::Shaded => {
                    let sh = &shading[obj];
                    // A texture's colour C at the hit, in the object's constants' place.
                    let textured = hit_color(scene, obj, local, hit, ray).map(|color| {
                        let m = &scene.objects[obj].material;
                        let ambient: [f64; 3] =
                            std::array::from_fn(|k| m.ambient[k] * scene.ambient[k] * color[k]);
                        let diffuse: [f64; 3] = std::array::from_fn(|k| m.diffuse[k] * color[k]);
                        (ambient, diffuse)
                    });
                    let (mut c, diffuse) = textured.unwrap_or((sh.ambient, sh.diffuse));
                    // Terms are summed in light order: directly until one waits for its shadow
                    // ray, then after the shadow pass.
                    let mut waiting = false;
                    let emit = |l, color: [f64; 3], shadow: Option<ShadowRay<N>>| {
                        if shadow.is_none() && !waiting {
                            for k in 0..3 {
                                c[k] += color[k];
                            }
                            return;
                        }
                        waiting = true;
                        if let Some(shadow) = shadow {
                            requests.push((l, self.terms.len(), shadow));
                        }
                        // Set to the shadow ray's index once the rays are in light order.
                        self.shadow.push(None);
                        self.terms.push((r, color));
                    };
                    let at = (obj, local);
                    // One branch per hit chooses the lighting model's loop.
                    if gouraud {
                        light_terms::<N, true>(
                            scene, ray, dir_len, hit, at, sh, &diffuse, &n, emit,
                        );
                    } else {
                        light_terms::<N, false>(
                            scene, ray, dir_len, hit, at, sh, &diffuse, &n, emit,
                        );
                    }
                    c
                }
                RenderMode::Depth => {
                    let g = 1.0
                        - 0.8
                            * ((depth - depth_range.0) / (depth_range.1 - depth_range.0))
                                .clamp(0.0, 1.0);
                    [g; 3]
                }
                RenderMode::Normal => {
                    std::array::from_fn(|k| if k < N { 0.5 + 0.5 * n[k] } else { 0.5 })
                }
                RenderMode::PrimitiveId => id_color(hit.prim),
                RenderMode::Barycentric => {
                    std::array::from_fn(|k| if k < N { hit.bary[k] } else { 0.0 })
                }
            };
            let nearest = NearestHit {
                depth,
                normal: n,
                object: obj as i32,
                primitive: local as i64,
            };
            self.color.push(c);
            self.nearest.push(nearest);
        }
        // 3. The shadow pass.
        if !requests.is_empty() {
            // Light order, so that each packet holds rays toward one light, then by the ids
            // skipped, which a packet shares.
            if scene.lights.len() > 1 || scene.objects.len() > 1 {
                requests.sort_by_key(|q| (q.0, q.2.skip.start, q.2.skip.end));
            }
            self.shadow_rays.clear();
            self.shadow_tmax.clear();
            for (i, (_, term, shadow)) in requests.iter().enumerate() {
                self.shadow[*term] = Some(i);
                self.shadow_rays.push(shadow.ray);
                self.shadow_tmax.push(shadow.tmax);
            }
            self.blocked.clear();
            self.blocked.resize(requests.len(), false);
            let mut first = 0;
            for run in requests.chunk_by(|a, b| a.2.skip == b.2.skip) {
                let all = first..first + run.len();
                scene.instances.any_hits(
                    &self.shadow_rays[all.clone()],
                    0.0,
                    &self.shadow_tmax[all.clone()],
                    |_| true,
                    run[0].2.skip.clone(),
                    &mut self.blocked[all],
                );
                first += run.len();
            }
            if scene.clips.active() {
                // Only a ray blocked by some hit may be blocked by a kept one.
                for (i, r) in requests.iter().enumerate() {
                    if self.blocked[i] {
                        self.blocked[i] = super::clip::blocks(scene, &r.2.ray, r.2.tmax, &r.2.skip);
                    }
                }
            }
        }
        // 4. The waiting terms, in light order per ray (the order of the sum, as for one ray
        //    alone).
        for (i, &(r, color)) in self.terms.iter().enumerate() {
            if self.shadow[i].is_some_and(|s| self.blocked[s]) {
                continue;
            }
            let c = &mut self.color[r];
            for k in 0..3 {
                c[k] += color[k];
            }
        }
        true
    }
}

/// The light terms of [`super::shade_hit`] for one hit, with the object's constants `sh` and
/// the diffuse coefficient times the colour at the hit `diffuse`:
/// calls `emit` per light that faces the surface, in light order, with its index, its colour
/// term and the shadow ray that decides whether it counts (none when nothing could block it).
/// Lights behind the surface contribute nothing and need no shadow ray. `dir_len` is
/// |ray.dir|. `GOURAUD`: the lighting factors at the simplex's vertices, interpolated
/// (`render.shading = "gouraud"`), else at the hit.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn light_terms<const N: usize, const GOURAUD: bool>(
    scene: &Scene<N>,
    ray: &Ray<N>,
    dir_len: f64,
    hit: &Hit<N>,
    (obj, local): (usize, usize),
    sh: &ObjectShading,
    diffuse: &[f64; 3],
    n: &Vector<N>,
    mut emit: impl FnMut(usize, [f64; 3], Option<ShadowRay<N>>),
) {
    let o = &scene.objects[obj];
    let m = &o.material;
    let x = add_scaled(&ray.origin, hit.t, &ray.dir);
    // The unit vector toward the viewer, for the specular term only.
    let v = sh.specular.then(|| scale(&ray.dir, -1.0 / dir_len));
    let flat = hit.normal;
    let eps = SHADOW_OFFSET * scene.extent;
    for (index, light) in scene.lights.iter().enumerate() {
        let Some(to_light) = toward_light(light, &x) else {
            continue;
        };
        let l = to_light.dir;
        let ndl = dot(n, &l);
        let gouraud = GOURAUD.then(|| {
            let flip = super::gouraud::flipped(scene, hit, ray);
            super::gouraud::factors(scene, (obj, local), hit, flip, |x, n| {
                vertex_factors(scene, light, x, n, m.shininess, sh.specular)
            })
        });
        if gouraud.map_or(ndl <= 0.0, |(d, s)| d <= 0.0 && s <= 0.0) {
            continue;
        }
        let shadow = if scene.render.shadows {
            // Leave the surface on the light's side of the simplex's hyperplane.
            let along = dot(&flat, &l) >= 0.0;
            // A convex object lies on one side of the hyperplane: a ray leaving on the other
            // side never meets it again (nor anything, when the object is all the scene).
            let skips = sh.convex == Some(along);
            (!(skips && sh.whole_scene)).then(|| {
                let (ray, tmax) = shadow_ray(&x, &flat, along, &l, to_light.dist, eps);
                ShadowRay {
                    ray,
                    tmax,
                    skip: if skips { sh.ids.clone() } else { 0..0 },
                }
            })
        } else {
            None
        };
        // Without a specular coefficient the term is k_d ∘ C · (n̂·l̂) + 0.
        let term = match gouraud {
            None => {
                let spec = match &v {
                    Some(v) => blinn_phong(n, &l, v, m.shininess),
                    None => 0.0,
                };
                light_term(&to_light, diffuse, ndl, &m.specular, spec)
            }
            // The factors carry the attenuation at each vertex.
            Some((d, spec)) => light_term(&to_light.unattenuated(), diffuse, d, &m.specular, spec),
        };
        emit(index, term, shadow);
    }
}
