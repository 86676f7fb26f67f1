//! From a [`SceneDesc`] to a traceable [`Scene<N>`]: every dimension-dependent check, the
//! generated shapes, object transforms, materials, lights, the camera and the BVH.

use super::desc::*;
use super::elevation::{elevation_object, reject_elevation_keys};
use super::errors::PathError;
pub use super::fields::Rgb;
use super::fields::{coefficient, matrix_rows, mesh_from_rows, rgb, vec_n, R};
use super::mesh_file::{orientation_warning, read_mesh, MeshReader};
use super::transform::transform;
use crate::accel::{
    prefetch_of, simplex_bounds, Bounds, BuildRef, Bvh, ExactSource, FlatCell, Instances, Lane,
    PreparedSimplex, ToObject, MORTON_MIN,
};
use crate::camera::{look_at_orientation, Camera};
use crate::linalg::{
    add, cofactor_matrix, det, dot, identity, mat_mul, mat_vec, norm, scale, transpose, Matrix,
    Vector,
};
use crate::mesh::Mesh;
use crate::shapes;
use rayon::prelude::*;
use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

/// Largest number of rays per retina cell accepted.
pub const MAX_SAMPLES: u32 = 4096;
/// Largest number of simplices a generated sphere may have.
pub const MAX_GENERATED_SIMPLICES: u64 = 50_000_000;
/// Bytes of retina output per cell for dimension N: rgba f32×4, depth f32, normal f32×N,
/// object id i32, primitive id i64.
pub const fn retina_bytes_per_cell(n: usize) -> usize {
    16 + 4 + 4 * n + 4 + 8
}

fn scale_matrix<const N: usize>(m: &Matrix<N>, s: f64) -> Matrix<N> {
    m.map(|row| scale(&row, s))
}

/// Surface appearance with every coefficient resolved to RGB.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Base colour.
    pub color: Rgb,
    /// Ambient coefficient.
    pub ambient: Rgb,
    /// Diffuse coefficient.
    pub diffuse: Rgb,
    /// Specular coefficient.
    pub specular: Rgb,
    /// Blinn–Phong exponent.
    pub shininess: f64,
    /// Interpolated vertex normals (surfaces: tangent planes).
    pub smooth: bool,
    /// Fraction of light stopped (surface objects; 1 for every other object).
    pub opacity: f64,
    /// Colour varying over the object: colormap, isolines, lattice.
    pub texture: Option<crate::texture::TextureSpec>,
}

/// A light ready for shading.
#[derive(Debug, Clone, PartialEq)]
pub enum Light<const N: usize> {
    /// Unit direction toward the light.
    Directional { direction: Vector<N>, color: Rgb },
    /// Position, colour and falloff exponent.
    Point {
        position: Vector<N>,
        color: Rgb,
        falloff: f64,
    },
}

/// An object in world space.
#[derive(Debug, Clone)]
pub struct Object<const N: usize> {
    /// World-space mesh, simplices in the order given (ids refer to it).
    pub mesh: Mesh<N>,
    /// Appearance.
    pub material: Material,
    /// Per-vertex unit normals when the material is smooth.
    pub vertex_normals: Option<Vec<Vector<N>>>,
    /// When the mesh bounds a convex body (checked only for scenes with shadows and lights):
    /// whether the body lies on the side of every simplex's hyperplane opposite its normal n̂
    /// ([`crate::convex::convex_side`]). Shadow rays leaving a simplex away from the body skip
    /// the object.
    pub convex: Option<bool>,
    /// For a `surface` object: its triangles (into `mesh.vertices`; `mesh` has no simplices)
    /// and how they are drawn.
    pub surface: Option<crate::surface::Surface<N>>,
    /// Colour varying over the object ([`crate::texture`]).
    pub texture: Option<crate::texture::Texture<N>>,
}

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
    /// transformed object of [`INSTANCE_MIN`] simplices or more is prepared in its own space
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
    pub(crate) edge_cache: Arc<crate::edges::EdgeCache<N>>,
    /// Fewest simplices a transformed object needs to be traced in its own space
    /// ([`INSTANCE_MIN`]; tests lower it).
    pub(crate) instance_min: usize,
}

/// The `[composite]` options `composite` checked against the retina of `camera`.
fn check_composite<const N: usize>(
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

impl<const N: usize> Scene<N> {
    /// This scene seen by the camera `camera` (with the `[composite]` options `composite`
    /// checked against its retina): what building the description with that camera gives,
    /// bit for bit — nothing of a build but the camera and that check depends on the camera —
    /// sharing the objects and the BVH instead of building them again (animation frames that
    /// move only the camera).
    pub fn with_camera(
        &self,
        camera: &CameraDesc,
        composite: Option<&crate::composite::CompositeOptions>,
    ) -> R<Scene<N>> {
        let camera = self::camera::<N>(camera, self.render.samples)?;
        check_composite(composite, &camera)?;
        Ok(Scene {
            camera,
            ..self.clone()
        })
    }

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

    /// Per global simplex id, whether back-face culling removes it for this camera (course
    /// notes: when det[x_1−x_0 … | C − x_0] < 0, i.e. when its normal points away from the eye).
    pub fn backfaces(&self) -> Vec<bool> {
        (0..self.simplex_count() as u32)
            .into_par_iter()
            .map(|g| {
                let (o, s) = self.locate(g);
                let obj = &self.objects[o];
                let x0 = obj.mesh.vertices[obj.mesh.simplices[s][0] as usize];
                dot(&self.flat_normal(g), &self.camera.toward_eye(&x0)) < 0.0
            })
            .collect()
    }
}

fn camera<const N: usize>(c: &CameraDesc, samples: u32) -> R<Camera<N>> {
    let position = vec_n::<N>(&c.position, "camera.position")?;
    let orientation = match (&c.look_at, &c.orientation) {
        (Some(_), Some(_)) => {
            return Err(PathError::new(
                "camera",
                "give either look_at (with up) or orientation, not both",
            ))
        }
        (None, None) => {
            return Err(PathError::new(
                "camera",
                "missing orientation: give look_at (with up) or orientation",
            ))
        }
        (Some(target), None) => {
            let target = vec_n::<N>(target, "camera.look_at")?;
            let up: Vec<Vec<f64>> = match &c.up {
                None => vec![],
                Some(UpDesc::List(l)) => l.clone(),
                Some(UpDesc::Single(v)) if N == 3 => vec![v.clone()],
                Some(UpDesc::Single(_)) => {
                    return Err(PathError::new(
                        "camera.up",
                        format!("expected a list of {} vectors", N - 2),
                    ))
                }
            };
            if up.len() != N - 2 {
                return Err(PathError::new(
                    "camera.up",
                    format!(
                        "expected {} vector(s) of {N} numbers (dim = {N}), got {}",
                        N - 2,
                        up.len()
                    ),
                ));
            }
            let up: Vec<Vector<N>> = up
                .iter()
                .enumerate()
                .map(|(k, u)| vec_n::<N>(u, &format!("camera.up[{k}]")))
                .collect::<R<_>>()?;
            look_at_orientation(&position, &target, &up).map_err(|bad| match bad {
                None => PathError::new(
                    "camera.look_at",
                    "equals camera.position: no view direction",
                ),
                Some(k) => PathError::new(
                    format!("camera.up[{k}]"),
                    "is a combination of the view direction and the up vectors before it",
                ),
            })?
        }
        (None, Some(rows)) => {
            if c.up.is_some() {
                return Err(PathError::new(
                    "camera.up",
                    "up goes with look_at, not with orientation",
                ));
            }
            let m = matrix_rows::<N>(rows, "camera.orientation")?;
            let g = mat_mul(&crate::linalg::transpose(&m), &m);
            let id: Matrix<N> = identity();
            let err = (0..N)
                .flat_map(|i| (0..N).map(move |j| (i, j)))
                .map(|(i, j)| (g[i][j] - id[i][j]).abs())
                .fold(0.0, f64::max);
            if err > 1e-6 {
                return Err(PathError::new(
                    "camera.orientation",
                    format!("must be orthonormal (OᵀO = I), but OᵀO differs from I by {err:.3e}"),
                ));
            }
            m
        }
    };
    let cell_unit = match c.projection {
        Projection::Perspective => {
            if c.extent.is_some() {
                return Err(PathError::new(
                    "camera.extent",
                    "extent is for orthographic cameras; use fov",
                ));
            }
            let fov = c.fov.ok_or_else(|| {
                PathError::new("camera", "perspective camera needs fov (degrees)")
            })?;
            if !(fov > 0.0 && fov < 180.0) {
                return Err(PathError::new(
                    "camera.fov",
                    format!("must be between 0 and 180 degrees, got {fov}"),
                ));
            }
            2.0 * (fov.to_radians() / 2.0).tan()
        }
        Projection::Orthographic => {
            if c.fov.is_some() {
                return Err(PathError::new(
                    "camera.fov",
                    "fov is for perspective cameras; use extent",
                ));
            }
            let e = c
                .extent
                .ok_or_else(|| PathError::new("camera", "orthographic camera needs extent"))?;
            if !(e > 0.0 && e.is_finite()) {
                return Err(PathError::new(
                    "camera.extent",
                    format!("must be a positive number, got {e}"),
                ));
            }
            2.0 * e
        }
    };
    let resolution: Vec<u64> = match &c.resolution {
        Resolution::Uniform(r) => vec![*r; N - 1],
        Resolution::PerAxis(v) => {
            if v.len() != N - 1 {
                return Err(PathError::new(
                    "camera.resolution",
                    format!(
                        "expected one integer or {} integers (dim = {N}), got {}",
                        N - 1,
                        v.len()
                    ),
                ));
            }
            v.clone()
        }
    };
    if let Some(k) = resolution.iter().position(|&r| r == 0) {
        return Err(PathError::new(
            "camera.resolution",
            format!("axis {} has zero cells", k + 1),
        ));
    }
    // Exact cell count (u128 holds any 7 axes of u64 up to 2^128; beyond that, f64).
    let cells: f64 = resolution.iter().map(|&r| r as f64).product();
    let cells_text = match resolution
        .iter()
        .try_fold(1u128, |a, &r| a.checked_mul(r as u128))
    {
        Some(c) => c.to_string(),
        None => format!("{cells:.3e}"),
    };
    let bytes = cells * retina_bytes_per_cell(N) as f64;
    crate::memory::check(bytes, &format!("a retina of {cells_text} cells"))
        .map_err(|e| PathError::new("camera.resolution", e))?;
    let _ = samples;
    Ok(Camera {
        position,
        orientation,
        projection: c.projection,
        cell: cell_unit / resolution[0] as f64,
        resolution: resolution.iter().map(|&r| r as usize).collect(),
    })
}

/// Bytes the BVH of `count` simplices in R^n needs at the peak of its build. The SAH build
/// holds each simplex's record (prepared matrix and origin, normal, bounds), the copies handed
/// to the BVH and the leaf blocks; the Morton build (from [`MORTON_MIN`] simplices) the blocks,
/// the sort keys, the blocks' boxes and the nodes.
pub(crate) fn bvh_bytes(n: usize, count: f64) -> f64 {
    let prepared = ((n * n + n) * 8) as f64;
    let per_simplex = if count >= MORTON_MIN as f64 {
        prepared + (24 + 4 * n) as f64
    } else {
        3.0 * prepared + (5 * n * 8 + 16) as f64
    };
    count * per_simplex
}

/// Only surface objects may be transparent.
fn opaque(o: &ObjectDesc, path: &str) -> R<()> {
    if o.material.opacity != 1.0 {
        return Err(PathError::new(
            format!("{path}.material.opacity"),
            "only surface objects can be transparent (opacity < 1)",
        ));
    }
    Ok(())
}

fn object_mesh<const N: usize>(
    o: &ObjectDesc,
    path: &str,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
) -> R<Mesh<N>> {
    let extra = |key: &str, present: bool| -> R<()> {
        if present {
            Err(PathError::new(
                format!("{path}.{key}"),
                format!("\"{key}\" is not used by shape \"{}\"", shape_name(o.shape)),
            ))
        } else {
            Ok(())
        }
    };
    if o.shape != ShapeKind::Mesh {
        extra("vertices", o.vertices.is_some())?;
        extra("simplices", o.simplices.is_some())?;
        extra("file", o.file.is_some())?;
    }
    if o.shape != ShapeKind::Sphere {
        extra("subdivisions", o.subdivisions.is_some())?;
    }
    extra("triangles", o.triangles.is_some())?;
    extra("width", o.width.is_some())?;
    opaque(o, path)?;
    Ok(match o.shape {
        ShapeKind::Surface | ShapeKind::Elevation => {
            unreachable!("surfaces and elevation maps have their own builders")
        }
        ShapeKind::Simplex => shapes::simplex_boundary::<N>(),
        ShapeKind::Hypercube => shapes::hypercube::<N>(),
        ShapeKind::CrossPolytope => shapes::cross_polytope::<N>(),
        ShapeKind::Sphere => {
            let s = o.subdivisions.unwrap_or(2);
            // 2N · (2^s)^(N−1) · (N−1)! simplices, computed in f64 so it cannot overflow.
            let count = 2.0
                * N as f64
                * 2f64.powi((s as i32) * (N as i32 - 1))
                * (1..N).map(|k| k as f64).product::<f64>();
            if count > MAX_GENERATED_SIMPLICES as f64 {
                let exact = 1u128
                    .checked_shl(s.saturating_mul(N as u32 - 1))
                    .and_then(|k| k.checked_mul(2 * N as u128 * (1..N as u128).product::<u128>()));
                let count_text = exact.map_or(format!("{count:.3e}"), |c| c.to_string());
                return Err(PathError::new(
                    format!("{path}.subdivisions"),
                    format!("{s} subdivisions would make {count_text} simplices (limit {MAX_GENERATED_SIMPLICES})"),
                ));
            }
            // The mesh and the BVH it will need, refused before the work of generating it.
            crate::memory::check(
                count * 4.0 * N as f64 + bvh_bytes(N, count),
                &format!("a sphere of {count} simplices and its BVH"),
            )
            .map_err(|e| PathError::new(format!("{path}.subdivisions"), e))?;
            shapes::sphere::<N>(s)
        }
        ShapeKind::Mesh => match (&o.vertices, &o.simplices, &o.file) {
            (Some(v), Some(s), None) => {
                let flat_v = vertex_rows::<N>(v, path)?;
                let flat_s = s.flat(N).map_err(|(i, n)| {
                    PathError::new(
                        format!("{path}.simplices[{i}]"),
                        format!("an (N−1)-simplex has {N} vertex indices (dim = {N}), got {n}"),
                    )
                })?;
                mesh_from_rows::<N, i64>(
                    &flat_v,
                    v.len(),
                    &flat_s,
                    s.len(),
                    path,
                    &format!("{path}.vertices"),
                    &format!("{path}.simplices"),
                )?
            }
            (None, None, Some(file)) => read_mesh::<N>(file, base, reader, path)?,
            (None, None, None) => {
                return Err(PathError::new(
                    path,
                    "a mesh needs vertices and simplices, or a file",
                ))
            }
            (_, _, Some(_)) => {
                return Err(PathError::new(
                    format!("{path}.file"),
                    "give either file or vertices and simplices, not both",
                ))
            }
            (None, Some(_), None) => {
                return Err(PathError::new(path, "mesh has simplices but no vertices"))
            }
            (Some(_), None, None) => {
                return Err(PathError::new(path, "mesh has vertices but no simplices"))
            }
        },
    })
}

/// `vertices` as flat rows of N coordinates (borrowed from an array); an error names the
/// first row of another length.
fn vertex_rows<'a, const N: usize>(v: &'a Rows<f64>, path: &str) -> R<Cow<'a, [f64]>> {
    v.flat(N).map_err(|(i, n)| {
        PathError::new(
            format!("{path}.vertices[{i}]"),
            format!("expected {N} numbers (dim = {N}), got {n}"),
        )
    })
}

/// A `surface` object (dim = 4): its vertices as a mesh without simplices, its triangles (those
/// without area dropped, counted in the second value) and its sheet width.
fn surface_mesh<const N: usize>(o: &ObjectDesc, path: &str) -> R<(Mesh<N>, Vec<[u32; 3]>, f64)> {
    if N != 4 {
        return Err(PathError::new(
            format!("{path}.shape"),
            format!("shape \"surface\" is a 2-surface in R^4: it needs dim = 4, got dim = {N}"),
        ));
    }
    for (key, present) in [
        ("simplices", o.simplices.is_some()),
        ("file", o.file.is_some()),
        ("subdivisions", o.subdivisions.is_some()),
    ] {
        if present {
            return Err(PathError::new(
                format!("{path}.{key}"),
                format!("\"{key}\" is not used by shape \"surface\" (give vertices and triangles)"),
            ));
        }
    }
    let (Some(v), Some(t)) = (&o.vertices, &o.triangles) else {
        return Err(PathError::new(
            path,
            "a surface needs vertices (V, 4) and triangles (T, 3)",
        ));
    };
    let width = o.width.unwrap_or(crate::surface::DEFAULT_WIDTH);
    if !(width > 0.0 && width <= crate::surface::MAX_WIDTH) {
        return Err(PathError::new(
            format!("{path}.width"),
            format!(
                "must be a number of retina cells in (0, {}], got {width}",
                crate::surface::MAX_WIDTH
            ),
        ));
    }
    let flat_v = vertex_rows::<N>(v, path)?;
    let vpath = format!("{path}.vertices");
    let mesh = mesh_from_rows::<N, i64>(&flat_v, v.len(), &[], 0, path, &vpath, &vpath)?;
    crate::memory::check(
        t.len() as f64 * 12.0,
        &format!("a surface of {} triangles", t.len()),
    )
    .map_err(|e| PathError::new(path, e))?;
    let flat_t = t.flat(3).map_err(|(i, n)| {
        PathError::new(
            format!("{path}.triangles[{i}]"),
            format!("a triangle has 3 vertex indices, got {n}"),
        )
    })?;
    let mut triangles = Vec::with_capacity(t.len());
    for (i, row) in flat_t.chunks_exact(3).enumerate() {
        let mut idx = [0u32; 3];
        for (k, &x) in row.iter().enumerate() {
            if !(x >= 0 && (x as u64) < v.len() as u64) {
                return Err(PathError::new(
                    format!("{path}.triangles[{i}][{k}]"),
                    format!(
                        "vertex index {x} out of range: the surface has {} vertices",
                        v.len()
                    ),
                ));
            }
            idx[k] = x as u32;
        }
        if idx[0] == idx[1] || idx[1] == idx[2] || idx[0] == idx[2] {
            return Err(PathError::new(
                format!("{path}.triangles[{i}]"),
                format!("repeats a vertex: {idx:?}"),
            ));
        }
        triangles.push(idx);
    }
    Ok((mesh, triangles, width))
}

fn shape_name(k: ShapeKind) -> &'static str {
    ShapeKind::NAMES[k as usize]
}

fn material(m: &MaterialDesc, path: &str) -> R<Material> {
    if !(m.opacity > 0.0 && m.opacity <= 1.0) {
        return Err(PathError::new(
            format!("{path}.opacity"),
            format!("must be in (0, 1], got {}", m.opacity),
        ));
    }
    if !(m.shininess >= 0.0 && m.shininess.is_finite()) {
        return Err(PathError::new(
            format!("{path}.shininess"),
            format!("must be a finite number ≥ 0, got {}", m.shininess),
        ));
    }
    Ok(Material {
        color: rgb(&m.color, &format!("{path}.color"))?,
        ambient: coefficient(&m.ambient, &format!("{path}.ambient"))?,
        diffuse: coefficient(&m.diffuse, &format!("{path}.diffuse"))?,
        specular: coefficient(&m.specular, &format!("{path}.specular"))?,
        shininess: m.shininess,
        smooth: m.smooth,
        opacity: m.opacity,
        texture: texture_spec(m, path)?,
    })
}

/// The texture keys of a material (`colormap`, `range`, `isolines`, `lattice`).
fn texture_spec(m: &MaterialDesc, path: &str) -> R<Option<crate::texture::TextureSpec>> {
    use crate::texture::{colormap, Isolines, Lattice, TextureSpec};
    let colormap = match &m.colormap {
        None => {
            if m.range.is_some() {
                return Err(PathError::new(
                    format!("{path}.range"),
                    "\"range\" sets the values at a colormap's ends: give material.colormap",
                ));
            }
            None
        }
        Some(name) => {
            let map = colormap::get(name).ok_or_else(|| {
                PathError::new(
                    format!("{path}.colormap"),
                    format!(
                        "unknown colormap \"{name}\" (known: {}; \"_r\" reverses one)",
                        colormap::names().join(", ")
                    ),
                )
            })?;
            let range = match &m.range {
                None => None,
                Some(r) => match r[..] {
                    [lo, hi] if lo.is_finite() && hi.is_finite() && hi != lo => Some([lo, hi]),
                    _ => {
                        return Err(PathError::new(
                            format!("{path}.range"),
                            format!(
                                "expected [low, high], two different finite numbers, got {r:?}"
                            ),
                        ))
                    }
                },
            };
            Some((map, range))
        }
    };
    let positive = |x: f64, key: &str| -> R<f64> {
        if x > 0.0 && x.is_finite() {
            Ok(x)
        } else {
            Err(PathError::new(
                format!("{path}.{key}"),
                format!("must be a finite number > 0, got {x}"),
            ))
        }
    };
    let isolines = match &m.isolines {
        None => None,
        Some(i) => {
            if let Some(k) = i.values.iter().position(|v| !v.is_finite()) {
                return Err(PathError::new(
                    format!("{path}.isolines.values[{k}]"),
                    format!("must be finite, got {}", i.values[k]),
                ));
            }
            Some(Isolines {
                values: i.values.clone(),
                width: positive(i.width.unwrap_or(0.03), "isolines.width")?,
                color: match &i.color {
                    Some(c) => rgb(c, &format!("{path}.isolines.color"))?,
                    None => [0.02, 0.02, 0.02],
                },
            })
        }
    };
    let lattice = match &m.lattice {
        None => None,
        Some(l) => {
            let spacing = positive(l.spacing, "lattice.spacing")?;
            let width = positive(l.width.unwrap_or(spacing / 12.0), "lattice.width")?;
            if width >= spacing {
                return Err(PathError::new(
                    format!("{path}.lattice.width"),
                    format!("must be less than the spacing {spacing}, got {width}"),
                ));
            }
            Some(Lattice {
                spacing,
                width,
                color: match &l.color {
                    Some(c) => rgb(c, &format!("{path}.lattice.color"))?,
                    None => [1.0, 1.0, 1.0],
                },
            })
        }
    };
    Ok(
        (colormap.is_some() || isolines.is_some() || lattice.is_some()).then_some(TextureSpec {
            colormap,
            isolines,
            lattice,
        }),
    )
}

fn light<const N: usize>(l: &LightDesc, path: &str) -> R<Light<N>> {
    Ok(match l {
        LightDesc::Directional { direction, color } => {
            let d = vec_n::<N>(direction, &format!("{path}.direction"))?;
            let len = norm(&d);
            if !(len > 0.0) {
                return Err(PathError::new(
                    format!("{path}.direction"),
                    "must not be the zero vector",
                ));
            }
            Light::Directional {
                direction: scale(&d, 1.0 / len),
                color: rgb(color, &format!("{path}.color"))?,
            }
        }
        LightDesc::Point {
            position,
            color,
            falloff,
        } => {
            let f = falloff.unwrap_or(0.0);
            if !(f >= 0.0 && f.is_finite()) {
                return Err(PathError::new(
                    format!("{path}.falloff"),
                    format!("must be a finite number ≥ 0, got {f}"),
                ));
            }
            Light::Point {
                position: vec_n::<N>(position, &format!("{path}.position"))?,
                color: rgb(color, &format!("{path}.color"))?,
                falloff: f,
            }
        }
    })
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
    build_using(desc, base, reader, MORTON_MIN, INSTANCE_MIN)
}

/// [`build_with`], building the BVH with [`Bvh::build_morton`] from `morton_min` simplices
/// and tracing transformed objects of `instance_min` simplices or more in their own space
/// (tests compare the builds on small scenes).
pub(crate) fn build_using<const N: usize>(
    desc: &SceneDesc,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
    morton_min: usize,
    instance_min: usize,
) -> R<Scene<N>> {
    let Parts {
        background,
        ambient,
        camera,
        lights,
        mut objects,
        surface_warnings,
        maps,
        mut own,
    } = parts::<N>(desc, base, reader, (instance_min, true))?;
    let r = &desc.render;
    // 3. Prepared simplices and the BVHs.
    let (offsets, total) = offsets_of(&objects);
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
    let shadows = r.shadows && !lights.is_empty();
    // The trees are built in the objects' own space: the vertices before the transform (the
    // simplices keep the order the transform gave them), swapped in for the build.
    let swap_own = |objects: &mut [Object<N>], own: &mut [Option<Vec<Vector<N>>>]| {
        for (o, v) in objects.iter_mut().zip(own.iter_mut()) {
            if let Some(v) = v {
                std::mem::swap(&mut o.mesh.vertices, v);
            }
        }
    };
    swap_own(&mut objects, &mut own);
    // The untransformed objects in one tree, each transformed object in its own (objects
    // without simplices, surfaces, in none).
    let alone = |k: &usize| own[*k].is_some();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let untransformed: Vec<usize> = (0..objects.len()).filter(|k| !alone(k)).collect();
    if !untransformed.is_empty() {
        groups.push(untransformed);
    }
    groups.extend((0..objects.len()).filter(alone).map(|k| vec![k]));
    let mut tree_of = vec![0u32; objects.len()];
    let mut slots = vec![u32::MAX; total as usize];
    let mut trees = Vec::with_capacity(groups.len());
    for (t, members) in groups.iter().enumerate() {
        let tree = group_tree(
            &mut objects,
            &desc.objects,
            (&offsets, &mut slots),
            members,
            shadows,
            morton_min,
        );
        members.iter().for_each(|&k| tree_of[k] = t as u32);
        trees.push(tree);
    }
    swap_own(&mut objects, &mut own);
    // A certificate found in object space holds in world space (an affine map keeps a body
    // convex); the world normals are turned around with the simplices' order (`ToObject`).
    for (o, m) in objects.iter_mut().zip(&maps) {
        if m.is_some_and(|m| m.flip) {
            o.convex = o.convex.map(|side| !side);
        }
    }
    // The trees find their exact simplices in the scene's objects (and the large transformed
    // ones' vertices in their own space, kept for it).
    let objects = Arc::new(objects);
    let own: Vec<Option<Arc<Vec<Vector<N>>>>> = own.into_iter().map(|v| v.map(Arc::new)).collect();
    for (tree, members) in trees.iter_mut().zip(&groups) {
        tree.set_exact(exact_source(&objects, &offsets, members, &own));
    }
    let skipped = total as usize - trees.iter().map(Bvh::len).sum::<usize>();
    let extent = extent_of(&objects, &offsets, &slots);
    warnings.extend(surface_warnings);
    if skipped > 0 {
        warnings.push(format!(
            "skipped {skipped} degenerate (zero-volume) simplices"
        ));
    }
    let instances = Instances::new(
        trees.into_iter().map(Arc::new).collect(),
        Arc::new(slots),
        Arc::new(tree_of),
        Arc::new(offsets.clone()),
        (maps, &world_boxes(&objects)),
    );
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
        instance_min,
    })
}

/// The tree of the objects `members` (their meshes in the space the tree is built in), with
/// their global ids (`offsets`), its slots written into `slots` ([`Bvh::fill_id_slots`]), and
/// the members' convexity certificates when shadow rays will use them: the SAH build, or the
/// Morton build from `morton_min` simplices.
fn group_tree<const N: usize>(
    objects: &mut [Object<N>],
    descs: &[ObjectDesc],
    (offsets, slots): (&[u32], &mut [u32]),
    members: &[usize],
    shadows: bool,
    morton_min: usize,
) -> Bvh<N> {
    let count: usize = members
        .iter()
        .map(|&k| objects[k].mesh.simplices.len())
        .sum();
    if count < morton_min {
        let tree = sah_bvh(objects, descs, offsets, members, shadows);
        tree.fill_id_slots(slots);
        return tree;
    }
    // Local index i → (member, simplex): the members' simplices one after the other.
    let mut starts = Vec::with_capacity(members.len());
    let mut at = 0;
    for &k in members {
        starts.push(at);
        at += objects[k].mesh.simplices.len();
    }
    let split = |i: usize| {
        let m = starts.partition_point(|&s| s <= i) - 1;
        (members[m], i - starts[m])
    };
    let domain = members
        .par_iter()
        .flat_map(|&k| objects[k].mesh.vertices.par_iter())
        .map(|v| (*v, *v))
        .reduce(empty_box, merge_boxes);
    let tree = {
        let objects = &*objects;
        Bvh::build_morton_with_ids(
            count,
            domain,
            |i| {
                let (k, s) = split(i);
                objects[k].mesh.simplex_points(s)
            },
            |i| {
                let (k, s) = split(i);
                offsets[k] + s as u32
            },
            ExactSource::none(),
        )
    };
    tree.fill_id_slots(slots);
    if shadows {
        certify_held(objects, descs, offsets, members, slots);
    }
    tree
}

/// Convexity certificates of the objects `members` of a Morton tree, from the exact normals of
/// the simplices it holds (`slots` as [`Bvh::id_slots`] gives them; the tree's own normals are
/// rounded to f32); elevation maps are not certified: see `sah_bvh`.
fn certify_held<const N: usize>(
    objects: &mut [Object<N>],
    descs: &[ObjectDesc],
    offsets: &[u32],
    members: &[usize],
    slots: &[u32],
) {
    for &i in members {
        let (o, d) = (&mut objects[i], &descs[i]);
        if d.shape == ShapeKind::Elevation {
            continue;
        }
        let first = offsets[i] as usize;
        let normals: Vec<Vector<N>> = (first..first + o.mesh.simplices.len())
            .into_par_iter()
            .map(|g| match slots[g] {
                u32::MAX => [0.0; N],
                // The exact normal (the tree's is rounded to f32), as `sah_bvh` finds it.
                _ => crate::geometry::hyperplane(&o.mesh.simplex_points(g - first))
                    .map_or([0.0; N], |h| h.normal),
            })
            .collect();
        o.convex = crate::convex::convex_side(&o.mesh, &normals, known_convex(d.shape));
    }
}

/// Per object, the box of its world vertices (exact in any order).
fn world_boxes<const N: usize>(objects: &[Object<N>]) -> Vec<Bounds<N>> {
    objects
        .iter()
        .map(|o| {
            (o.mesh.vertices.par_iter())
                .map(|v| (*v, *v))
                .reduce(empty_box, merge_boxes)
        })
        .collect()
}

/// The diagonal of the box of the simplices the BVH holds (`slots` not `u32::MAX`) and of the
/// surfaces' vertices (it sets their shadow rays' offset); min and max are exact in any order.
fn extent_of<const N: usize>(objects: &[Object<N>], offsets: &[u32], slots: &[u32]) -> f64 {
    let kept = |(o, &off): (&Object<N>, &u32)| {
        let slots = &slots[off as usize..][..o.mesh.simplices.len()];
        (0..slots.len())
            .into_par_iter()
            .filter(|&s| slots[s] != u32::MAX)
            .map(|s| {
                warm_vertices(&o.mesh, s + AHEAD);
                simplex_bounds(&o.mesh.simplex_points(s))
            })
            .reduce(empty_box, merge_boxes)
    };
    let (mut lo, mut hi) = (objects.iter().zip(offsets))
        .map(kept)
        .fold(empty_box(), merge_boxes);
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

impl<const N: usize> Scene<N> {
    /// The scene `desc` describes, when `desc` differs from the description this scene was
    /// built from only in its camera, `[composite]` and objects' transforms (a frame of an
    /// animation that moves objects; the caller makes sure of that: the objects' meshes must
    /// be the same): its objects are built as a build makes them, and this scene's trees are
    /// reached through the new transforms ([`Instances::moved`]) instead of being built: the
    /// large objects' trees hold them in their own space, so nothing per simplex is done for
    /// them; the objects traced in world space get a tree built anew when one of them moves.
    /// It traces bit for bit as a build of `desc`. `None` when an object is read from a file
    /// (it would be read again), a large object's transform turns handedness around where this
    /// scene's did not or the reverse (the simplices' order would differ), or the number of
    /// degenerate simplices changed (the warnings would): build `desc` then. Its warnings are this
    /// scene's (orientation and degeneracy do not depend on the transforms).
    pub(crate) fn moved(&self, desc: &SceneDesc) -> Option<R<Scene<N>>> {
        if desc.objects.iter().any(ObjectDesc::reads_file) {
            return None;
        }
        let Parts {
            background,
            ambient,
            camera,
            lights,
            mut objects,
            maps,
            ..
        } = match parts::<N>(desc, None, None, (self.instance_min, false)) {
            Ok(p) => p,
            Err(e) => return Some(Err(e)),
        };
        let (offsets, _) = offsets_of(&objects);
        if offsets != self.offsets || objects.len() != self.objects.len() {
            return None;
        }
        // Objects of `instance_min` simplices or more are held in their own space, with the
        // simplices' order of the transform's handedness: it must be the same.
        let counts: Vec<usize> = objects.iter().map(|o| o.mesh.simplices.len()).collect();
        let flip = |m: Option<&ToObject<N>>| m.is_some_and(|m| m.flip);
        let same_order = (0..maps.len())
            .filter(|&k| counts[k] >= self.instance_min)
            .all(|k| flip(maps[k].as_ref()) == flip(self.instances.map(k)));
        if !same_order {
            return None;
        }
        // The certificates were found in the objects' own space, as a build of `desc` finds
        // them.
        for (o, base) in objects.iter_mut().zip(self.objects.iter()) {
            o.convex = base.convex;
        }
        // Smaller ones are held in world space: when one moves, they get a tree of their own,
        // built over the moved vertices as a build of `desc` prepares them (with their
        // certificates).
        let small: Vec<usize> = (0..maps.len())
            .filter(|&k| (1..self.instance_min).contains(&counts[k]))
            .collect();
        let boxes = world_boxes(&objects);
        let (objects, instances) = if small
            .iter()
            .all(|&k| objects[k].mesh == self.objects[k].mesh)
        {
            (Arc::new(objects), self.instances.moved(maps, &boxes))
        } else {
            let mut slots = self.instances.slots().to_vec();
            for &k in &small {
                slots[self.ids(k).start as usize..self.ids(k).end as usize].fill(u32::MAX);
            }
            let shadows = desc.render.shadows && !lights.is_empty();
            let mut tree = group_tree(
                &mut objects,
                &desc.objects,
                (&offsets, &mut slots),
                &small,
                shadows,
                MORTON_MIN,
            );

            // A simplex that became degenerate or the reverse changes the warnings: build.
            if slots.par_iter().filter(|&&s| s == u32::MAX).count() != self.skipped_degenerate {
                return None;
            }
            // The moved objects in world space, as this frame's objects hold them.
            let objects = Arc::new(objects);
            tree.set_exact(exact_source(&objects, &offsets, &small, &[]));
            let instances = self
                .instances
                .moved_with((maps, &boxes), tree, &small, slots);
            (objects, instances)
        };
        let extent = extent_of(&objects, &offsets, instances.slots());
        let edge_cache = Arc::new(
            self.edge_cache
                .moved(|o| objects[o].mesh == self.objects[o].mesh),
        );
        Some(Ok(Scene {
            camera,
            objects,
            lights,
            ambient,
            background,
            render: desc.render.clone(),
            instances,
            offsets,
            skipped_degenerate: self.skipped_degenerate,
            extent,
            warnings: self.warnings.clone(),
            edge_cache,
            instance_min: self.instance_min,
        }))
    }
}

/// What a build makes before the BVH: the checked colours, camera and lights, and the objects
/// in world space (with the warnings about their surfaces).
struct Parts<const N: usize> {
    background: Rgb,
    ambient: Rgb,
    camera: Camera<N>,
    lights: Vec<Light<N>>,
    objects: Vec<Object<N>>,
    surface_warnings: Vec<String>,
    /// Per object, the map from world space into its own ([`ToObject::of_transform`]).
    maps: Vec<Option<ToObject<N>>>,
    /// Per object with a map, when asked for, its vertices in its own space (before the
    /// transform).
    own: Vec<Option<Vec<Vector<N>>>>,
}

/// Steps 1 and 2 of a build: everything but the BVH. Transformed objects of `instance_min`
/// simplices or more get maps, and with `keep_own` their own vertices too.
fn parts<const N: usize>(
    desc: &SceneDesc,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
    (instance_min, keep_own): (usize, bool),
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
    let camera = camera::<N>(&desc.camera, r.samples)?;
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
    check_composite(desc.composite.as_ref(), &camera)?;
    // 2. Meshes in world space. A transform that reverses handedness (det < 0) would turn
    //    outward normals inward (normals are pseudotensors), so such simplices are reordered to
    //    keep their orientation.
    let mut objects = Vec::with_capacity(desc.objects.len());
    let (mut maps, mut own) = (Vec::new(), Vec::new());
    let mut surface_warnings = Vec::new();
    for (i, (o, (mat, (a, b)))) in desc.objects.iter().zip(plans).enumerate() {
        let path = format!("objects[{i}]");
        let mut values = None;
        let mut own_normals = None;
        let (mut mesh, triangles) = match o.shape {
            ShapeKind::Surface => {
                reject_elevation_keys(o, &path)?;
                let (m, t, w) = surface_mesh::<N>(o, &path)?;
                (m, Some((t, w)))
            }
            ShapeKind::Elevation => {
                opaque(o, &path)?;
                let e = elevation_object::<N>(o, &path, base, reader)?;
                if e.holes > 0 {
                    surface_warnings.push(format!(
                        "objects[{i}]: left out {} grid cubes with a NaN corner (holes in the elevation map)",
                        e.holes
                    ));
                }
                values = Some(e.values);
                own_normals = e.normals;
                (e.mesh, None)
            }
            _ => {
                reject_elevation_keys(o, &path)?;
                (object_mesh::<N>(o, &path, base, reader)?, None)
            }
        };
        if let Some(v) = &o.values {
            let v = v.values();
            if v.len() != mesh.vertices.len() {
                return Err(PathError::new(
                    format!("{path}.values"),
                    format!(
                        "one value per vertex: the object has {} vertices, got {} values",
                        mesh.vertices.len(),
                        v.len()
                    ),
                ));
            }
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(PathError::new(
                    format!("{path}.values[{k}]"),
                    format!("must be finite, got {}", v[k]),
                ));
            }
            values = Some(v.to_vec());
        }
        if let Some(spec) = &mat.texture {
            if o.shape == ShapeKind::Surface {
                return Err(PathError::new(
                    format!("{path}.material"),
                    "colormap, isolines and lattice are for simplex meshes, not surface objects",
                ));
            }
            if spec.needs_values() && values.is_none() {
                return Err(PathError::new(
                    format!("{path}.values"),
                    "material.colormap and material.isolines need one value per vertex: give values (an elevation map has its field)",
                ));
            }
        }
        // An object of INSTANCE_MIN simplices or more is traced in its own space (its tree
        // holds the vertices before the transform): the transform of an object with
        // simplices must be invertible (a singular one would flatten them all to nothing; a
        // surface's triangles may be flattened).
        let map = ToObject::of_transform(&a, &b);
        let moves = a != identity::<N>() || b.iter().any(|&x| x != 0.0);
        if map.is_none() && moves && !mesh.simplices.is_empty() {
            return Err(PathError::new(
                format!("objects[{i}].transform"),
                format!(
                    "is singular or cannot be inverted in floating point (determinant {}): an object with simplices needs an invertible transform",
                    det(&a)
                ),
            ));
        }
        let map = map.filter(|_| mesh.simplices.len() >= instance_min);
        maps.push(map);
        own.push((keep_own && map.is_some()).then(|| mesh.vertices.clone()));
        mesh.vertices
            .par_iter_mut()
            .for_each(|v| *v = add(&mat_vec(&a, v), &b));
        if let Some(k) = mesh
            .vertices
            .iter()
            .position(|v| v.iter().any(|x| !x.is_finite()))
        {
            return Err(PathError::new(
                format!("objects[{i}].transform"),
                format!("makes vertex {k} non-finite"),
            ));
        }
        if det(&a) < 0.0 {
            mesh.simplices.iter_mut().for_each(|s| s.swap(0, 1));
        }
        let surface = triangles.map(|(t, width)| {
            // Triangles without area have no tangent plane: left out.
            let kept: Vec<[u32; 3]> = t
                .into_iter()
                .filter(|tri| {
                    let [a, b, c] = tri.map(|k| mesh.vertices[k as usize]);
                    crate::surface::tangent_projector(&a, &b, &c).is_some()
                })
                .collect();
            let vertex_tangents = mat
                .smooth
                .then(|| crate::surface::vertex_tangents(&mesh.vertices, &kept));
            crate::surface::Surface {
                triangles: kept,
                width,
                vertex_tangents,
            }
        });
        if let (Some(s), Some(t)) = (&surface, &o.triangles) {
            if s.triangles.len() < t.len() {
                surface_warnings.push(format!(
                    "objects[{i}]: left out {} surface triangles without area",
                    t.len() - s.triangles.len()
                ));
            }
        }
        // Normals are covectors: they map by the inverse transpose, A^(−T) = cofactor(A)/det A.
        let inverse_t = scale_matrix(&cofactor_matrix(&a), 1.0 / det(&a));
        let vertex_normals = match own_normals {
            Some(mut n) => {
                n.par_iter_mut().for_each(|v| {
                    let w = mat_vec(&inverse_t, v);
                    *v = scale(&w, 1.0 / norm(&w));
                });
                Some(n)
            }
            None => (mat.smooth && surface.is_none()).then(|| shapes::vertex_normals(&mesh)),
        };
        let texture = mat.texture.as_ref().map(|spec| {
            let colormap = spec.colormap.as_ref().map(|(map, range)| {
                let range = range.unwrap_or_else(|| {
                    let v = values.as_deref().unwrap_or(&[]);
                    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    if hi > lo {
                        [lo, hi]
                    } else {
                        [lo - 1.0, lo + 1.0]
                    }
                });
                (map.clone(), range)
            });
            let inverse = transpose(&inverse_t);
            crate::texture::Texture {
                values: values.take(),
                colormap,
                isolines: spec.isolines.clone(),
                lattice: spec.lattice.clone(),
                to_object: (inverse, scale(&mat_vec(&inverse, &b), -1.0)),
            }
        });
        objects.push(Object {
            mesh,
            material: mat,
            vertex_normals,
            convex: None,
            surface,
            texture,
        });
    }
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

/// The first id of each object's simplices, and their total.
fn offsets_of<const N: usize>(objects: &[Object<N>]) -> (Vec<u32>, u64) {
    let mut offsets = Vec::with_capacity(objects.len());
    let mut total = 0u64;
    for o in objects {
        offsets.push(total as u32);
        total += o.mesh.simplices.len() as u64;
    }
    (offsets, total)
}

/// Where the tree over the objects `members` finds the exact simplex of a global id: their
/// meshes in `objects`, with the vertices of `own[k]` for an object held in its own space.
fn exact_source<const N: usize>(
    objects: &Arc<Vec<Object<N>>>,
    offsets: &[u32],
    members: &[usize],
    own: &[Option<Arc<Vec<Vector<N>>>>],
) -> ExactSource<N> {
    // (first global id, object, its vertices in its own space when it has them)
    type Part<const N: usize> = (u32, usize, Option<Arc<Vec<Vector<N>>>>);
    let parts: Vec<Part<N>> = members
        .iter()
        .map(|&k| (offsets[k], k, own.get(k).cloned().flatten()))
        .collect();
    let objects = objects.clone();
    ExactSource::new(move |g| {
        let (off, k, own) = &parts[parts.partition_point(|p| p.0 <= g) - 1];
        let mesh = &objects[*k].mesh;
        let vertices = own.as_deref().unwrap_or(&mesh.vertices);
        let idx = &mesh.simplices[(g - off) as usize];
        PreparedSimplex::new(&idx.map(|i| vertices[i as usize]))
            .expect("a simplex prepared once prepares again")
    })
}

/// The points of global simplex g of the objects whose first global ids are `offsets` (what
/// [`Scene::locate`] does, before there is a scene).
fn simplex_at<const N: usize>(objects: &[Object<N>], offsets: &[u32], g: usize) -> [Vector<N>; N] {
    let o = offsets.partition_point(|&off| off as usize <= g) - 1;
    objects[o].mesh.simplex_points(g - offsets[o] as usize)
}

/// The empty box, the identity of [`merge_boxes`].
fn empty_box<const N: usize>() -> Bounds<N> {
    ([f64::INFINITY; N], [f64::NEG_INFINITY; N])
}

/// The box of two boxes (exact, so any reduction order gives the same bits).
fn merge_boxes<const N: usize>((a, b): Bounds<N>, (c, d): Bounds<N>) -> Bounds<N> {
    (
        std::array::from_fn(|k| a[k].min(c[k])),
        std::array::from_fn(|k| b[k].max(d[k])),
    )
}

/// The generated polytopes are convex; an affine map keeps them so.
fn known_convex(shape: ShapeKind) -> bool {
    matches!(
        shape,
        ShapeKind::Simplex | ShapeKind::Hypercube | ShapeKind::CrossPolytope
    )
}

/// The SAH-built BVH over every non-degenerate simplex of the objects `members` (global ids
/// from `offsets`), and their convexity certificates when shadow rays will use them.
fn sah_bvh<const N: usize>(
    objects: &mut [Object<N>],
    descs: &[ObjectDesc],
    offsets: &[u32],
    members: &[usize],
    shadows: bool,
) -> Bvh<N> {
    // Each simplex's build record (holding, for now, its global id, or `DROPPED` for a
    // degenerate simplex), the rows its block lane will hold and, for the convexity
    // certificates, its normal, in one parallel pass in simplex order, so that the fill does
    // not prepare the simplices again. (The rows, N² f32 per simplex, are alive until the
    // blocks are filled; a lane's other part, the simplex's first vertex, is read from the
    // mesh.)
    const DROPPED: u32 = u32::MAX;
    let mut refs: Vec<BuildRef<N>> = Vec::new();
    let mut rows: Vec<[[f32; N]; N]> = Vec::new();
    let mut cells = Vec::new();
    let mut dropped = 0;
    for &k in members {
        let (o, off, d) = (&mut objects[k], offsets[k], &descs[k]);
        // Convexity certificates, which only shadow rays use. An elevation map is not
        // certified: it is a graph over a box, an open surface, and the test would cost more
        // than it saves.
        let certify = shadows && d.shape != ShapeKind::Elevation;
        // Flat pieces are looked for in hypercubes and in meshes of up to MAX_FLAT_SEARCH
        // simplices (matching their ridges costs a sort).
        let search = d.shape == ShapeKind::Hypercube
            || (d.shape == ShapeKind::Mesh && o.mesh.simplices.len() <= MAX_FLAT_SEARCH);
        let count = o.mesh.simplices.len();
        let record = |s: usize, r: &mut BuildRef<N>, row: &mut [[f32; N]; N]| {
            // (The pass runs over increasing s in each task.)
            warm_vertices(&o.mesh, s + AHEAD);
            let pts = o.mesh.simplex_points(s);
            let p = PreparedSimplex::new(&pts)?;
            *r = BuildRef::new(off + s as u32, &simplex_bounds(&pts));
            *row = Lane::rows_of(&p);
            Some(p)
        };
        let none = BuildRef::new(DROPPED, &([0.0; N], [0.0; N]));
        let mut mine = vec![none; count];
        let mut my_rows = vec![[[0.0; N]; N]; count];
        let mut normals = vec![[0.0; N]; if certify { count } else { 0 }];
        let records = mine.par_iter_mut().zip(&mut my_rows).enumerate();
        if certify {
            records.zip(&mut normals).for_each(|((s, (r, row)), n)| {
                if let Some(p) = record(s, r, row) {
                    *n = p.normal();
                }
            });
        } else {
            records.for_each(|(s, (r, row))| {
                record(s, r, row);
            });
        }
        dropped += mine.par_iter().filter(|r| r.id == DROPPED).count();
        if certify {
            o.convex = crate::convex::convex_side(&o.mesh, &normals, known_convex(d.shape));
        }
        if search {
            // Without certificates the normals are made again where they are needed (no list
            // of them is kept).
            let kept = |s: usize| mine[s].id != DROPPED;
            let normal = |s: usize| match certify {
                true => kept(s).then(|| normals[s]),
                false => PreparedSimplex::new(&o.mesh.simplex_points(s)).map(|p| p.normal()),
            };
            for piece in crate::mesh::flat::flat_pieces(&o.mesh, normal, MIN_CELL) {
                cells.push((off, piece));
            }
        }
        if refs.is_empty() {
            (refs, rows) = (mine, my_rows);
        } else {
            refs.extend_from_slice(&mine);
            rows.extend_from_slice(&my_rows);
        }
    }
    if dropped > 0 {
        // `retain` visits the elements in order, once each: row k goes with record k.
        let mut k = 0;
        rows.retain(|_| {
            k += 1;
            refs[k - 1].id != DROPPED
        });
        refs.retain(|r| r.id != DROPPED);
    }
    // The global ids, and the records numbered as the build's inputs.
    let ids: Vec<u32> = (refs.par_iter_mut().enumerate())
        .map(|(i, r)| std::mem::replace(&mut r.id, i as u32))
        .collect();
    // The flat pieces as cells over the build's inputs (`ids`: the global ids of the
    // non-degenerate simplices, increasing; a piece has no degenerate simplex).
    let cells = cells
        .into_iter()
        .map(|(off, piece): (u32, Vec<u32>)| {
            let members = piece
                .iter()
                .map(|&s| {
                    ids.binary_search(&(off + s))
                        .expect("a piece's simplex is kept") as u32
                })
                .collect();
            let points = piece
                .iter()
                .map(|&s| simplex_at(objects, offsets, (off + s) as usize))
                .collect();
            FlatCell { members, points }
        })
        .collect();
    let prepare = |_, g: u32| {
        PreparedSimplex::new(&simplex_at(objects, offsets, g as usize))
            .expect("a simplex prepared once prepares again")
    };
    // The first vertex of global simplex g, and what it is read through.
    let first = |g: u32| {
        let o = offsets.partition_point(|&off| off <= g) - 1;
        let mesh = &objects[o].mesh;
        (mesh, &mesh.simplices[(g - offsets[o]) as usize])
    };
    let lane = |i: usize, g: u32| {
        let (mesh, idx) = first(g);
        Lane {
            rows: rows[i],
            x0: mesh.vertices[idx[0] as usize],
        }
    };
    // What `lane(i, g)` will read: the rows and the simplex's vertex indices, then (`near`)
    // its first vertex.
    let warm = |i: usize, g: u32, near: bool| {
        let (mesh, idx) = first(g);
        if near {
            prefetch_of(&mesh.vertices[idx[0] as usize]);
        } else {
            prefetch_of(idx);
            prefetch_of(&rows[i]);
        }
    };
    Bvh::build_with_cells_borrowing(ids, refs, cells, (prepare, lane, warm))
}

/// How many simplices ahead the passes over a mesh in simplex order ask for their vertices
/// ([`warm_vertices`]).
const AHEAD: usize = 8;

/// Asks for the vertices of simplex `s` of `mesh` (if there is one) ahead of their use: in a
/// large mesh they lie anywhere, and a pass over its simplices would wait for each in turn.
fn warm_vertices<const N: usize>(mesh: &Mesh<N>, s: usize) {
    for &v in mesh.simplices.get(s).into_iter().flatten() {
        if let Some(x) = mesh.vertices.get(v as usize) {
            prefetch_of(x);
        }
    }
}

/// Fewest simplices an object with a transform needs to be traced in its own space, in a tree
/// of its own that frames moving it share ([`Instances`]); smaller ones are traced in world
/// space, in the tree of the untransformed objects (each instance costs a ray a box test, and
/// a rebuild of a few thousand simplices costs little).
pub const INSTANCE_MIN: usize = 4096;

/// Fewest simplices a flat piece needs to be held as a flat cell: below this, testing its
/// blocks costs less than a walk (an N-cube's facet has (N−1)! simplices: N ≥ 5).
const MIN_CELL: usize = 24;
/// Largest mesh whose flat pieces are looked for.
const MAX_FLAT_SEARCH: usize = 1 << 18;
