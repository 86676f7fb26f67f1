//! From a [`SceneDesc`] to a traceable [`Scene<N>`]: every dimension-dependent check, the
//! generated shapes, object transforms, materials, lights, the camera and the BVH.

use super::desc::*;
use super::errors::PathError;
use super::mesh_file::{orientation_warning, read_mesh, MeshReader};
use crate::accel::{Bvh, PreparedSimplex};
use crate::camera::{look_at_orientation, Camera};
use crate::linalg::{add, det, dot, identity, mat_mul, mat_vec, norm, scale, Matrix, Vector};
use crate::mesh::Mesh;
use crate::rotation::{
    check_plane, plane_rotation, rolling_ball, scene_quaternion, so4_from_quaternions, Quat,
};
use crate::shapes;
use rayon::prelude::*;
use std::path::Path;

/// Largest number of rays per retina cell accepted.
pub const MAX_SAMPLES: u32 = 4096;
/// Largest number of simplices a generated sphere may have.
pub const MAX_GENERATED_SIMPLICES: u64 = 50_000_000;
/// Bytes of retina output per cell for dimension N: rgba f32×4, depth f32, normal f32×N,
/// object id i32, primitive id i64.
pub const fn retina_bytes_per_cell(n: usize) -> usize {
    16 + 4 + 4 * n + 4 + 8
}

/// An RGB triple.
pub type Rgb = [f64; 3];

/// Surface appearance with every coefficient resolved to RGB.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Base colour.
    pub color: Rgb,
    /// Ambient, diffuse and specular coefficients.
    pub ambient: Rgb,
    /// Diffuse coefficient.
    pub diffuse: Rgb,
    /// Specular coefficient.
    pub specular: Rgb,
    /// Blinn–Phong exponent.
    pub shininess: f64,
    /// Interpolated vertex normals.
    pub smooth: bool,
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
}

/// A scene ready to trace: world-space objects, the BVH over all their simplices (built once),
/// lights and the camera.
pub struct Scene<const N: usize> {
    /// The camera.
    pub camera: Camera<N>,
    /// Objects, indexed by object id.
    pub objects: Vec<Object<N>>,
    /// Lights.
    pub lights: Vec<Light<N>>,
    /// Ambient light colour.
    pub ambient: Rgb,
    /// Background colour.
    pub background: Rgb,
    /// Tracing options.
    pub render: RenderDesc,
    /// BVH over every non-degenerate simplex; hit ids are global ids (see [`Scene::locate`]).
    pub bvh: Bvh<N>,
    /// Unit flat normal (eq. 6) per global simplex id.
    pub flat_normals: Vec<Vector<N>>,
    /// First global id of each object's simplices.
    pub offsets: Vec<u32>,
    /// Simplices skipped because they have no volume.
    pub skipped_degenerate: usize,
    /// Diagonal of the scene's bounding box (sets ray epsilons).
    pub extent: f64,
    /// Warnings for the user (e.g. skipped degenerate simplices).
    pub warnings: Vec<String>,
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
            .unwrap_or(self.flat_normals.len() as u32);
        self.offsets[obj]..end
    }
}

type R<T> = Result<T, PathError>;

/// Global id, prepared simplex (None when degenerate), unit normal and bounds of a simplex.
type PrimRecord<const N: usize> = (
    u32,
    Option<PreparedSimplex<N>>,
    Vector<N>,
    ([f64; N], [f64; N]),
);

fn finite_list(v: &[f64], path: &str) -> R<()> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(PathError::new(
            format!("{path}[{i}]"),
            format!("non-finite value {}", v[i]),
        )),
        None => Ok(()),
    }
}

/// A vector of exactly N finite numbers.
pub(crate) fn vec_n<const N: usize>(v: &[f64], path: &str) -> R<Vector<N>> {
    if v.len() != N {
        return Err(PathError::new(
            path,
            format!("expected {N} numbers (dim = {N}), got {}", v.len()),
        ));
    }
    finite_list(v, path)?;
    Ok(std::array::from_fn(|i| v[i]))
}

/// An RGB triple of finite, non-negative numbers.
fn rgb(v: &[f64], path: &str) -> R<Rgb> {
    if v.len() != 3 {
        return Err(PathError::new(
            path,
            format!("expected 3 numbers, got {}", v.len()),
        ));
    }
    finite_list(v, path)?;
    if let Some(i) = v.iter().position(|&x| x < 0.0) {
        return Err(PathError::new(
            format!("{path}[{i}]"),
            format!("must be ≥ 0, got {}", v[i]),
        ));
    }
    Ok([v[0], v[1], v[2]])
}

fn coefficient(c: &Coefficient, path: &str) -> R<Rgb> {
    match c {
        Coefficient::Scalar(s) => rgb(&[*s; 3], path),
        Coefficient::Rgb(v) => rgb(v, path),
    }
}

pub(crate) fn matrix_rows<const N: usize>(rows: &[Vec<f64>], path: &str) -> R<Matrix<N>> {
    if rows.len() != N {
        return Err(PathError::new(
            path,
            format!("expected {N} rows of {N} numbers, got {} rows", rows.len()),
        ));
    }
    let mut m = [[0.0; N]; N];
    for (i, row) in rows.iter().enumerate() {
        m[i] = vec_n::<N>(row, &format!("{path}[{i}]"))?;
    }
    Ok(m)
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
    let available = available_memory();
    if bytes > available as f64 / 2.0 {
        return Err(PathError::new(
            "camera.resolution",
            format!(
                "a retina of {cells_text} cells needs about {} of memory, more than this machine can spare ({} available)",
                human_bytes(bytes),
                human_bytes(available as f64)
            ),
        ));
    }
    let _ = samples;
    Ok(Camera {
        position,
        orientation,
        projection: c.projection,
        cell: cell_unit / resolution[0] as f64,
        resolution: resolution.iter().map(|&r| r as usize).collect(),
    })
}

/// Memory available to this process (MemAvailable on Linux, else 16 GiB).
fn available_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("MemAvailable:"))
                .and_then(|l| {
                    l.split_whitespace()
                        .nth(1)
                        .and_then(|k| k.parse::<u64>().ok())
                })
        })
        .map(|kib| kib * 1024)
        .unwrap_or(16 << 30)
}

fn human_bytes(b: f64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB", "ZiB", "YiB"];
    let mut v = b;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if v >= 1024.0 {
        format!("{b:.3e} B")
    } else {
        format!("{v:.1} {}", units[u])
    }
}

/// The affine map x ↦ A·x + b of a transform list (the first entry acts first).
fn transform<const N: usize>(list: &[TransformDesc], path: &str) -> R<(Matrix<N>, Vector<N>)> {
    let mut a: Matrix<N> = identity();
    let mut b: Vector<N> = [0.0; N];
    for (k, t) in list.iter().enumerate() {
        let p = format!("{path}[{k}]");
        let (m, c): (Matrix<N>, Vector<N>) = match t {
            TransformDesc::Scale(ScaleDesc::Uniform(s)) => {
                if !(s.is_finite() && *s != 0.0) {
                    return Err(PathError::new(
                        format!("{p}.scale"),
                        format!("must be a non-zero number, got {s}"),
                    ));
                }
                (scale_matrix(&[*s; N]), [0.0; N])
            }
            TransformDesc::Scale(ScaleDesc::PerAxis(v)) => {
                let s = vec_n::<N>(v, &format!("{p}.scale"))?;
                if let Some(i) = s.iter().position(|&x| x == 0.0) {
                    return Err(PathError::new(
                        format!("{p}.scale[{i}]"),
                        "must be non-zero",
                    ));
                }
                (scale_matrix(&s), [0.0; N])
            }
            TransformDesc::Translate(v) => (identity(), vec_n::<N>(v, &format!("{p}.translate"))?),
            TransformDesc::Rotate(r) => (rotate::<N>(r, &format!("{p}.rotate"))?, [0.0; N]),
            TransformDesc::Matrix(rows) => affine_rows::<N>(rows, &format!("{p}.matrix"))?,
        };
        // New map: x ↦ m·(a·x + b) + c.
        a = mat_mul(&m, &a);
        b = add(&mat_vec(&m, &b), &c);
    }
    Ok((a, b))
}

/// The matrix of a `rotate` transform: exactly one of the plane, double-quaternion (4D) and
/// rolling-ball forms, with only the keys of that form.
fn rotate<const N: usize>(r: &RotateDesc, path: &str) -> R<Matrix<N>> {
    let forms = [
        ("plane", r.plane.is_some()),
        ("quaternions", r.quaternions.is_some()),
        ("rolling", r.rolling.is_some()),
    ];
    let given: Vec<&str> = forms.iter().filter(|f| f.1).map(|f| f.0).collect();
    match given[..] {
        [] => {
            return Err(PathError::new(
                path,
                "give one of plane (with degrees), quaternions = [q, p] (dim 4) or rolling (with radius)",
            ))
        }
        [_] => {}
        [first, second, ..] => {
            return Err(PathError::new(
                format!("{path}.{second}"),
                format!("give only one of plane, quaternions or rolling, not both {first} and {second}"),
            ))
        }
    }
    let belongs = |key: &str, present: bool, form: &str| -> R<()> {
        if present {
            Err(PathError::new(
                format!("{path}.{key}"),
                format!("\"{key}\" goes with {form}, not with {}", given[0]),
            ))
        } else {
            Ok(())
        }
    };
    if r.plane.is_none() {
        belongs("degrees", r.degrees.is_some(), "plane")?;
    }
    if r.rolling.is_none() {
        belongs("radius", r.radius.is_some(), "rolling")?;
        belongs("angle", r.angle.is_some(), "rolling")?;
    }
    if let Some([i, j]) = r.plane {
        check_plane(i, j, N).map_err(|m| PathError::new(format!("{path}.plane"), m))?;
        let degrees = r
            .degrees
            .ok_or_else(|| PathError::new(path, "plane needs degrees (the angle)"))?;
        if !degrees.is_finite() {
            return Err(PathError::new(format!("{path}.degrees"), "must be finite"));
        }
        return Ok(plane_rotation::<N>(i, j, degrees.to_radians()));
    }
    if let Some(qp) = &r.quaternions {
        let qpath = format!("{path}.quaternions");
        if N != 4 {
            return Err(PathError::new(
                qpath,
                format!(
                    "quaternions = [q, p] give a 4D rotation, but dim = {N}; use plane or rolling"
                ),
            ));
        }
        if qp.len() != 2 {
            return Err(PathError::new(
                qpath,
                format!(
                    "expected [q, p], two lists of 4 numbers, got {} lists",
                    qp.len()
                ),
            ));
        }
        let mut pair: [Quat; 2] = [[0.0; 4]; 2];
        for (k, (v, symbol)) in qp.iter().zip(["q", "p"]).enumerate() {
            let vpath = format!("{qpath}[{k}]");
            if v.len() != 4 {
                return Err(PathError::new(
                    vpath,
                    format!(
                        "expected 4 numbers (a quaternion q0, q1, q2, q3), got {}",
                        v.len()
                    ),
                ));
            }
            finite_list(v, &vpath)?;
            // Hand-typed: |q| within SCENE_UNIT_TOLERANCE of 1, then normalized.
            let q: Quat = std::array::from_fn(|c| v[c]);
            pair[k] =
                scene_quaternion(&q, "quaternion", symbol).map_err(|m| PathError::new(vpath, m))?;
        }
        let m = so4_from_quaternions(&pair[0], &pair[1]);
        // N = 4 here; copy into the generic matrix type.
        return Ok(std::array::from_fn(|i| std::array::from_fn(|j| m[i][j])));
    }
    let d = r.rolling.as_deref().unwrap_or_default();
    let rpath = format!("{path}.rolling");
    if d.len() != N - 1 {
        return Err(PathError::new(
            rpath,
            format!(
                "expected N − 1 = {} numbers (dim = {N}), got {}",
                N - 1,
                d.len()
            ),
        ));
    }
    finite_list(d, &rpath)?;
    let radius = r
        .radius
        .ok_or_else(|| PathError::new(path, "rolling needs radius (the ball radius R)"))?;
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(PathError::new(
            format!("{path}.radius"),
            format!("must be a positive number, got {radius}"),
        ));
    }
    Ok(rolling_ball::<N>(d, radius, r.angle.unwrap_or_default()))
}

fn scale_matrix<const N: usize>(s: &[f64; N]) -> Matrix<N> {
    std::array::from_fn(|i| std::array::from_fn(|j| if i == j { s[i] } else { 0.0 }))
}

fn affine_rows<const N: usize>(rows: &[Vec<f64>], path: &str) -> R<(Matrix<N>, Vector<N>)> {
    if rows.len() == N {
        return Ok((matrix_rows::<N>(rows, path)?, [0.0; N]));
    }
    if rows.len() != N + 1 {
        return Err(PathError::new(
            path,
            format!(
                "expected {N}×{N} (linear) or {}×{} (affine) rows, got {} rows",
                N + 1,
                N + 1,
                rows.len()
            ),
        ));
    }
    let mut m = [[0.0; N]; N];
    let mut b = [0.0; N];
    for (i, row) in rows.iter().enumerate() {
        if row.len() != N + 1 {
            return Err(PathError::new(
                format!("{path}[{i}]"),
                format!("expected {} numbers, got {}", N + 1, row.len()),
            ));
        }
        finite_list(row, &format!("{path}[{i}]"))?;
        if i < N {
            m[i].copy_from_slice(&row[..N]);
            b[i] = row[N];
        } else if row[..N].iter().any(|&x| x != 0.0) || row[N] != 1.0 {
            return Err(PathError::new(
                format!("{path}[{N}]"),
                "the last row of an affine matrix must be [0, …, 0, 1]",
            ));
        }
    }
    Ok((m, b))
}

pub(super) fn mesh_from_rows<const N: usize>(
    vertices: &[f64],
    nv: usize,
    simplices: &[f64],
    ns: usize,
    path: &str,
    vpath: &str,
    spath: &str,
) -> R<Mesh<N>> {
    if let Some(i) = vertices.iter().position(|x| !x.is_finite()) {
        return Err(PathError::new(
            format!("{vpath}[{}][{}]", i / N, i % N),
            format!("non-finite coordinate {}", vertices[i]),
        ));
    }
    let mut mesh = Mesh {
        vertices: Vec::with_capacity(nv),
        simplices: Vec::with_capacity(ns),
    };
    for v in vertices.chunks_exact(N) {
        mesh.vertices.push(std::array::from_fn(|i| v[i]));
    }
    for (s, row) in simplices.chunks_exact(N).enumerate() {
        let mut idx = [0u32; N];
        for (k, &x) in row.iter().enumerate() {
            if !(x >= 0.0 && x < nv as f64 && x.fract() == 0.0) {
                return Err(PathError::new(
                    format!("{spath}[{s}][{k}]"),
                    format!("vertex index {x} out of range: the mesh has {nv} vertices"),
                ));
            }
            idx[k] = x as u32;
        }
        mesh.simplices.push(idx);
    }
    let _ = path;
    Ok(mesh)
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
    Ok(match o.shape {
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
            shapes::sphere::<N>(s)
        }
        ShapeKind::Mesh => match (&o.vertices, &o.simplices, &o.file) {
            (Some(v), Some(s), None) => {
                for (i, row) in v.iter().enumerate() {
                    if row.len() != N {
                        return Err(PathError::new(
                            format!("{path}.vertices[{i}]"),
                            format!("expected {N} numbers (dim = {N}), got {}", row.len()),
                        ));
                    }
                }
                for (i, row) in s.iter().enumerate() {
                    if row.len() != N {
                        return Err(PathError::new(
                            format!("{path}.simplices[{i}]"),
                            format!(
                                "an (N−1)-simplex has {N} vertex indices (dim = {N}), got {}",
                                row.len()
                            ),
                        ));
                    }
                }
                let flat_v: Vec<f64> = v.iter().flatten().copied().collect();
                let flat_s: Vec<f64> = s.iter().flatten().map(|&x| x as f64).collect();
                mesh_from_rows::<N>(
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

fn shape_name(k: ShapeKind) -> &'static str {
    ShapeKind::NAMES[k as usize]
}

fn material(m: &MaterialDesc, path: &str) -> R<Material> {
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
    })
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
    if let Some(c) = &desc.composite {
        c.validate_for(&camera.numpy_shape(), true)
            .map_err(|e| PathError::new(format!("composite.{}", e.key), e.message))?;
    }
    // 2. Meshes in world space. A transform that reverses handedness (det < 0) would turn
    //    outward normals inward (normals are pseudotensors), so such simplices are reordered to
    //    keep their orientation.
    let mut objects = Vec::with_capacity(desc.objects.len());
    for (i, (o, (mat, (a, b)))) in desc.objects.iter().zip(plans).enumerate() {
        let mut mesh = object_mesh::<N>(o, &format!("objects[{i}]"), base, reader)?;
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
        let vertex_normals = mat.smooth.then(|| shapes::vertex_normals(&mesh));
        objects.push(Object {
            mesh,
            material: mat,
            vertex_normals,
            convex: None,
        });
    }
    // 3. Prepared simplices and the BVH.
    let mut offsets = Vec::with_capacity(objects.len());
    let mut total = 0u64;
    for o in &objects {
        offsets.push(total as u32);
        total += o.mesh.simplices.len() as u64;
    }
    if total >= 1 << 31 {
        return Err(PathError::new(
            "objects",
            format!(
                "{total} simplices in all: at most {} are supported",
                (1u64 << 31) - 1
            ),
        ));
    }
    let per_object: Vec<Vec<PrimRecord<N>>> = objects
        .iter()
        .zip(&offsets)
        .map(|(o, &off)| {
            (0..o.mesh.simplices.len())
                .into_par_iter()
                .map(|s| {
                    let pts = o.mesh.simplex_points(s);
                    let mut lo = pts[0];
                    let mut hi = pts[0];
                    for p in &pts[1..] {
                        for k in 0..N {
                            lo[k] = lo[k].min(p[k]);
                            hi[k] = hi[k].max(p[k]);
                        }
                    }
                    let prep = PreparedSimplex::new(&pts);
                    let n = prep.as_ref().map_or([0.0; N], |p| p.normal());
                    (off + s as u32, prep, n, (lo, hi))
                })
                .collect()
        })
        .collect();
    // Convexity certificates, which only shadow rays use.
    if r.shadows && !lights.is_empty() {
        for ((o, list), d) in objects.iter_mut().zip(&per_object).zip(&desc.objects) {
            let normals: Vec<Vector<N>> = list.par_iter().map(|rec| rec.2).collect();
            // The generated polytopes are convex; an affine map keeps them so.
            let known = matches!(
                d.shape,
                ShapeKind::Simplex | ShapeKind::Hypercube | ShapeKind::CrossPolytope
            );
            o.convex = crate::convex::convex_side(&o.mesh, &normals, known);
        }
    }
    let mut prims = Vec::with_capacity(total as usize);
    let mut ids = Vec::with_capacity(total as usize);
    let mut bounds = Vec::with_capacity(total as usize);
    let mut flat_normals = Vec::with_capacity(total as usize);
    let mut skipped = 0;
    let (mut lo, mut hi) = ([f64::INFINITY; N], [f64::NEG_INFINITY; N]);
    for list in per_object {
        for (id, prep, n, bb) in list {
            flat_normals.push(n);
            match prep {
                Some(p) => {
                    for k in 0..N {
                        lo[k] = lo[k].min(bb.0[k]);
                        hi[k] = hi[k].max(bb.1[k]);
                    }
                    prims.push(p);
                    ids.push(id);
                    bounds.push(bb);
                }
                None => skipped += 1,
            }
        }
    }
    let extent = if prims.is_empty() {
        1.0
    } else {
        norm(&std::array::from_fn::<f64, N, _>(|k| hi[k] - lo[k])).max(1e-300)
    };
    let mut warnings: Vec<String> = (objects.iter().zip(&desc.objects).enumerate())
        .filter(|(_, (_, d))| d.shape == ShapeKind::Mesh)
        .filter_map(|(i, (o, _))| orientation_warning(&o.mesh, &format!("objects[{i}]")))
        .collect();
    if skipped > 0 {
        warnings.push(format!(
            "skipped {skipped} degenerate (zero-volume) simplices"
        ));
    }
    let bvh = Bvh::build(prims, ids, bounds);
    let _ = dot::<N>;
    Ok(Scene {
        camera,
        objects,
        lights,
        ambient,
        background,
        render: desc.render.clone(),
        bvh,
        flat_normals,
        offsets,
        skipped_degenerate: skipped,
        extent,
        warnings,
    })
}
