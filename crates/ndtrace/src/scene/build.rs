//! From a [`SceneDesc`] to a traceable [`Scene<N>`], in three steps: everything that can be
//! checked cheaply (colours, samples, the camera, lights, materials, transforms, the
//! animation and composite tables), then the objects in world space (`objects.rs`), then the
//! index over their simplices, which `accel/` builds ([`crate::accel::build_index`]).

use super::camera::build_camera;
use super::desc::{RenderDesc, SceneDesc, ShapeKind};
use super::errors::PathError;
use super::fields::{rgb, R};
use super::lights::{light, Light};
use super::material::material;
use super::mesh_file::{orientation_warning, MeshReader};
use super::objects::{hints, world_object, Object, WorldObject};
use super::transform::transform;
use crate::accel::{
    build_index, bvh_bytes, empty_box, held_box, merge_boxes, offsets_of, AccelObject,
    AccelOptions, Bounds, Instances, Meshes, ToObject, INSTANCE_MIN, MORTON_MIN,
};
use crate::camera::Camera;
use crate::linalg::{dot, norm, Rgb, Vector};
use crate::mesh::Mesh;
use rayon::prelude::*;
use std::path::Path;
use std::sync::Arc;

/// Largest number of rays per retina cell accepted.
pub const MAX_SAMPLES: u32 = 4096;

/// A scene ready to trace: world-space objects, the BVH over all their simplices (built once),
/// lights and the camera. Cloning is cheap: the objects, the BVH and the edge cache are shared.
#[derive(Clone)]
pub struct Scene<const N: usize> {
    /// The camera.
    pub camera: Camera<N>,
    /// Objects, indexed by object id (shared by the scenes [`Scene::with_camera`] makes). Their
    /// geometry must not change after the build: the BVH and the feature-edge cache describe it.
    pub objects: Arc<Vec<Object<N>>>,
    /// Lights.
    pub lights: Vec<Light<N>>,
    /// Ambient light colour.
    pub ambient: Rgb,
    /// Background colour.
    pub background: Rgb,
    /// Tracing options.
    pub render: RenderDesc,
    /// The BVHs over every non-degenerate simplex and the maps taking rays to them: a
    /// transformed object of [`crate::accel::INSTANCE_MIN`] simplices or more is prepared in its own space
    /// (before its transform), in a tree of its own; the others share one tree in world space
    /// (a frame that moves some of them gives those a tree built anew); hit ids are global ids (see
    /// [`Scene::locate`]), hit normals world normals. The trees are shared by the scenes
    /// [`Scene::with_camera`] and the frames that move objects make.
    pub instances: Instances<N>,
    /// First global id of each object's simplices.
    pub offsets: Vec<u32>,
    /// Simplices skipped because they have no volume.
    pub skipped_degenerate: usize,
    /// Diagonal of the scene's bounding box (sets ray epsilons).
    pub extent: f64,
    /// Warnings for the user (e.g. skipped degenerate simplices).
    pub warnings: Vec<String>,
    /// The objects' feature edges, found on first use (shared like the BVH).
    pub(crate) edge_cache: Arc<crate::mesh::EdgeCache<N>>,
    /// The clip hyperplanes of each object and the caps' inside tests (empty without clips:
    /// rays are not checked; `render/clip.rs`).
    pub clips: Arc<super::clip::Clips<N>>,
    /// Fewest simplices a transformed object needs to be traced in its own space
    /// ([`crate::accel::INSTANCE_MIN`]; tests lower it).
    pub(crate) instance_min: usize,
}

impl<const N: usize> Scene<N> {
    /// (object id, simplex index within the object) of a global simplex id.
    #[inline]
    pub fn locate(&self, global: u32) -> (usize, usize) {
        let obj = self.offsets.partition_point(|&o| o <= global) - 1;
        (obj, (global - self.offsets[obj]) as usize)
    }

    /// The global ids of object `obj`'s simplices.
    pub fn ids(&self, obj: usize) -> std::ops::Range<u32> {
        let end = self
            .offsets
            .get(obj + 1)
            .copied()
            .unwrap_or(self.simplex_count() as u32);
        self.offsets[obj]..end
    }

    /// Number of simplices of all objects (global ids are `0..simplex_count()`).
    pub fn simplex_count(&self) -> usize {
        self.instances.slots().len()
    }

    /// Unit flat normal (eq. 6) of global simplex `g` in world space, zero for a degenerate
    /// one: bit for bit the normal of its hits.
    #[inline]
    pub fn flat_normal(&self, g: u32) -> Vector<N> {
        self.instances.flat_normal(g)
    }

    /// Finds the objects' convexity certificates not found yet ([`crate::convex::Certificate`]:
    /// the build leaves them to the first trace or probe that needs them), one object after
    /// the other. Every trace and probe calls it before its parallel loops, which then only
    /// read them; not from inside a parallel loop.
    pub fn find_certificates(&self) {
        let slots = self.instances.slots();
        for (k, o) in self.objects.iter().enumerate() {
            let ids = self.ids(k);
            o.convex
                .find(&o.mesh, &slots[ids.start as usize..ids.end as usize]);
        }
    }

    /// Per global simplex id, whether back-face culling removes it for this camera (course
    /// notes: when det[x_1−x_0 … | C − x_0] < 0, i.e. when its normal points away from the eye).
    /// (Through [`crate::par`]: this is compiled per N.)
    pub fn backfaces(&self) -> Vec<bool> {
        crate::par::map_collect(self.simplex_count(), 1024, |g| {
            let g = g as u32;
            let (o, s) = self.locate(g);
            let obj = &self.objects[o];
            let x0 = obj.mesh.vertices[obj.mesh.simplices[s][0] as usize];
            dot(&self.flat_normal(g), &self.camera.toward_eye(&x0)) < 0.0
        })
    }
}

/// The `[composite]` options `composite` checked against the retina of `camera`.
pub(super) fn check_composite<const N: usize>(
    composite: Option<&crate::composite::CompositeOptions>,
    camera: &Camera<N>,
) -> R<()> {
    match composite {
        Some(c) => c
            .validate_for(&camera.numpy_shape(), true)
            .map_err(|e| PathError::new(format!("composite.{}", e.key), e.message)),
        None => Ok(()),
    }
}

/// The scene's objects are the meshes its index was built from.
impl<const N: usize> Meshes<N> for Vec<Object<N>> {
    fn mesh(&self, k: usize) -> &Mesh<N> {
        &self[k].mesh
    }
}

/// Checks a whole description and builds the scene for dimension N: validation first (errors
/// carry the field path), then the shapes, the world-space meshes and the BVH. Mesh files
/// resolve against `base`; only `.npz` ones can be read (see [`build_with`]).
pub fn build<const N: usize>(desc: &SceneDesc, base: Option<&Path>) -> R<Scene<N>> {
    build_with(desc, base, None)
}

/// [`build`], with `reader` reading the mesh files of formats other than `.npz`.
pub fn build_with<const N: usize>(
    desc: &SceneDesc,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
) -> R<Scene<N>> {
    build_using(desc, base, reader, (MORTON_MIN, INSTANCE_MIN))
}

/// [`build_with`], building trees of `morton_min` simplices or more with the Morton build and
/// holding transformed objects of `instance_min` simplices or more in their own space (tests
/// compare the builds on small scenes).
pub(crate) fn build_using<const N: usize>(
    desc: &SceneDesc,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
    (morton_min, instance_min): (usize, usize),
) -> R<Scene<N>> {
    let options = AccelOptions {
        shadows: desc.render.shadows && !desc.lights.is_empty(),
        morton_min,
        instance_min,
    };
    let Parts {
        background,
        ambient,
        camera,
        lights,
        mut objects,
        mut surface_warnings,
        mut maps,
        mut own,
    } = parts::<N>(desc, base, reader, (&options, true))?;
    // 2b. The clips, and the caps after the scene's objects.
    let mut clips = super::clip::clips(desc, &mut objects, &mut surface_warnings)?;
    maps.resize(objects.len(), None);
    own.resize(objects.len(), None);
    // 3. The index over every simplex.
    let (offsets, total) = offsets_of(objects.iter().map(|o| &o.mesh));
    if total >= 1 << 31 {
        return Err(PathError::new(
            "objects",
            format!(
                "{total} simplices in all: at most {} are supported",
                (1u64 << 31) - 1
            ),
        ));
    }
    crate::memory::check(
        bvh_bytes(N, total as f64),
        &format!("the BVH of {total} simplices"),
    )
    .map_err(|e| PathError::new("objects", e))?;
    // The orientation check matches ridges, which takes memory in proportion to the mesh:
    // done before the BVH is alive.
    let mut warnings: Vec<String> = (objects.iter().zip(&desc.objects).enumerate())
        .filter(|(_, (_, d))| d.shape == ShapeKind::Mesh)
        .filter_map(|(i, (o, _))| orientation_warning(&o.mesh, &format!("objects[{i}]")))
        .collect();
    let built = {
        // Caps are flat pieces: no certificate, no flat-cell search.
        let shapes = desc.objects.iter().map(|d| d.shape);
        let shapes = shapes.chain(std::iter::repeat(ShapeKind::Elevation));
        let mut index: Vec<AccelObject<'_, N>> = (objects.iter_mut().zip(shapes))
            .zip(maps.iter().zip(own))
            .map(|((o, shape), (map, own))| AccelObject {
                mesh: &mut o.mesh,
                own,
                map: *map,
                hints: hints(shape),
            })
            .collect();
        build_index(&mut index, &offsets, &options)
    };
    for (o, c) in objects.iter_mut().zip(built.certificates()) {
        o.convex = c.clone();
    }
    let skipped = built.skipped();
    let extent = extent_of(&objects, &offsets, built.slots());
    let boxes = world_boxes(&objects);
    // The trees find their exact simplices in the scene's objects.
    let objects = Arc::new(objects);
    let instances = built.finish(&objects, &boxes);
    // A cap's inside test looks at the global ids of the object it caps.
    for c in &mut clips.objects {
        if let Some(r) = &c.inside_of {
            let o = r.start as usize;
            let end = offsets.get(o + 1).copied().unwrap_or(total as u32);
            c.inside_of = Some(offsets[o]..end);
        }
    }
    warnings.extend(surface_warnings);
    if skipped > 0 {
        warnings.push(format!(
            "skipped {skipped} degenerate (zero-volume) simplices"
        ));
    }
    Ok(Scene {
        camera,
        objects,
        lights,
        ambient,
        background,
        render: desc.render.clone(),
        instances,
        offsets,
        skipped_degenerate: skipped,
        extent,
        warnings,
        edge_cache: Arc::default(),
        instance_min: options.instance_min,
        clips: Arc::new(clips),
    })
}

/// Per object, the box of its world vertices (exact in any order).
pub(super) fn world_boxes<const N: usize>(objects: &[Object<N>]) -> Vec<Bounds<N>> {
    objects
        .iter()
        .map(|o| {
            (o.mesh.vertices.par_iter())
                .map(|v| (*v, *v))
                .reduce(empty_box, merge_boxes)
        })
        .collect()
}

/// The diagonal of the box of the simplices the index holds (`slots` not `u32::MAX`) and of
/// the surfaces' vertices (it sets their shadow rays' offset); min and max are exact in any
/// order.
pub(super) fn extent_of<const N: usize>(
    objects: &[Object<N>],
    offsets: &[u32],
    slots: &[u32],
) -> f64 {
    let (mut lo, mut hi) = held_box(objects.iter().map(|o| &o.mesh), offsets, slots);
    for o in objects.iter().filter(|o| o.surface.is_some()) {
        for v in &o.mesh.vertices {
            for k in 0..N {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
    }
    if !lo[0].is_finite() {
        1.0
    } else {
        norm(&std::array::from_fn::<f64, N, _>(|k| hi[k] - lo[k])).max(1e-300)
    }
}

/// The colours of `material.color_by` that depend on the scene: `"object"` gives object k
/// the palette's colour k, and `"depth"` without a `range` maps the depths of the object's
/// vertices from `camera` (the distance from the eye, or from the image plane for
/// orthographic), nearest to farthest, onto its colormap.
fn structure_colors<const N: usize>(objects: &mut [Object<N>], camera: &Camera<N>) {
    let view = camera.axis(N - 1);
    let depth = |v: &Vector<N>| {
        let d: Vector<N> = std::array::from_fn(|k| v[k] - camera.position[k]);
        match camera.projection {
            crate::camera::Projection::Perspective => norm(&d),
            crate::camera::Projection::Orthographic => dot(&d, &view),
        }
    };
    for (k, o) in objects.iter_mut().enumerate() {
        if o.material.color_by == Some(super::desc::ColorBy::Object) {
            o.material.color = o.material.palette.color(k);
        }
        let vertices = &o.mesh.vertices;
        if let Some((_, range)) = o.texture.as_mut().and_then(|t| t.depth.as_mut()) {
            if range[0].is_nan() {
                let (lo, hi) = (vertices.par_iter().map(depth))
                    .fold(
                        || (f64::INFINITY, f64::NEG_INFINITY),
                        |(lo, hi), d| (lo.min(d), hi.max(d)),
                    )
                    .reduce(
                        || (f64::INFINITY, f64::NEG_INFINITY),
                        |a, b| (a.0.min(b.0), a.1.max(b.1)),
                    );
                *range = if hi > lo {
                    [lo, hi]
                } else if lo.is_finite() {
                    [lo - 1.0, lo + 1.0]
                } else {
                    [0.0, 1.0]
                };
            }
        }
    }
}

/// What a build makes before the BVH: the checked colours, camera and lights, and the objects
/// in world space (with the warnings about their surfaces).
pub(super) struct Parts<const N: usize> {
    pub background: Rgb,
    pub ambient: Rgb,
    pub camera: Camera<N>,
    pub lights: Vec<Light<N>>,
    pub objects: Vec<Object<N>>,
    pub surface_warnings: Vec<String>,
    /// Per object, the map from world space into its own ([`ToObject::of_transform`]).
    pub maps: Vec<Option<ToObject<N>>>,
    /// Per object with a map, when asked for, its vertices in its own space (before the
    /// transform).
    pub own: Vec<Option<Vec<Vector<N>>>>,
}

/// Steps 1 and 2 of a build: everything but the index. Transformed objects that `options`
/// holds in their own space get maps, and with `keep_own` their own vertices too.
pub(super) fn parts<const N: usize>(
    desc: &SceneDesc,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
    (options, keep_own): (&AccelOptions, bool),
) -> R<Parts<N>> {
    // 1. Everything that can be checked cheaply, before any heavy work.
    let background = rgb(&desc.background, "background")?;
    let ambient = rgb(&desc.ambient, "ambient")?;
    let r = &desc.render;
    if r.samples == 0 || r.samples > MAX_SAMPLES {
        return Err(PathError::new(
            "render.samples",
            format!("must be in 1..={MAX_SAMPLES}, got {}", r.samples),
        ));
    }
    let camera = build_camera::<N>(&desc.camera)?;
    let lights = desc
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| light::<N>(l, &format!("lights[{i}]")))
        .collect::<R<Vec<_>>>()?;
    let mut plans = Vec::with_capacity(desc.objects.len());
    for (i, o) in desc.objects.iter().enumerate() {
        let p = format!("objects[{i}]");
        plans.push((
            material(&o.material, &format!("{p}.material"))?,
            transform::<N>(&o.transform, &format!("{p}.transform"))?,
        ));
    }
    if let Some(a) = &desc.animation {
        super::animation::check::<N>(a, desc.objects.len())?;
    }
    if let Some(s) = &desc.slice {
        super::fields::slice_plane::<N>(s, "slice")?;
    }
    check_composite(desc.composite.as_ref(), &camera)?;
    // 2. The objects in world space.
    let mut objects = Vec::with_capacity(desc.objects.len());
    let (mut maps, mut own) = (Vec::new(), Vec::new());
    let mut surface_warnings = Vec::new();
    for (i, (o, plan)) in desc.objects.iter().zip(plans).enumerate() {
        let path = format!("objects[{i}]");
        let WorldObject {
            object,
            map,
            own: mine,
        } = world_object::<N>(
            (o, &path),
            plan,
            (base, reader),
            (options, keep_own),
            &mut surface_warnings,
        )?;
        objects.push(object);
        maps.push(map);
        own.push(mine);
    }
    structure_colors(&mut objects, &camera);
    Ok(Parts {
        background,
        ambient,
        camera,
        lights,
        objects,
        surface_warnings,
        maps,
        own,
    })
}
