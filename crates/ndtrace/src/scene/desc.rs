//! The one scene description: what a TOML file, a Python dict and the Python builder become.
//!
//! Every key is documented in `docs/scene-format.md`. These two declarations are equivalent:
//!
//! ```toml
//! dim = 4
//! [camera]
//! position = [0, 0, 0, 5]
//! look_at = [0, 0, 0, 0]
//! up = [[0, 1, 0, 0], [0, 0, 1, 0]]
//! fov = 40
//! resolution = 64
//! [[objects]]
//! shape = "hypercube"
//! material = { color = [0.9, 0.6, 0.2] }
//! ```
//!
//! ```python
//! ndtrace.load_dict({"dim": 4,
//!     "camera": {"position": [0, 0, 0, 5], "look_at": [0, 0, 0, 0],
//!                "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 40, "resolution": 64},
//!     "objects": [{"shape": "hypercube", "material": {"color": [0.9, 0.6, 0.2]}}]})
//! ```
//!
//! Deserialization checks the structure (unknown keys are errors); the dimension-dependent
//! checks (vector lengths, orthonormality, index ranges) happen when the scene is built.

use serde::{Deserialize, Serialize};

pub use super::table::{Column, Rows, Shared, Table};

use crate::camera::Projection;

/// A whole scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// Dimension N of the world, 2..=8.
    pub dim: usize,
    /// Colour behind everything (RGB, linear). Misses get alpha 0.
    #[serde(default = "default_background")]
    pub background: Vec<f64>,
    /// Ambient light colour (RGB).
    #[serde(default = "default_ambient")]
    pub ambient: Vec<f64>,
    /// The N-D pinhole (or orthographic) camera.
    pub camera: CameraDesc,
    /// Light sources; none means ambient light only.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lights: Vec<LightDesc>,
    /// Objects: shapes with materials and transforms.
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
    /// Tracing options.
    #[serde(default)]
    pub render: RenderDesc,
    /// How the CLI turns the retina into a picture (keyword arguments of `ndtrace.composite`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub composite: Option<crate::composite::CompositeOptions>,
    /// A sequence of frames in which the objects or the camera rotate (`ndtrace.animate`,
    /// `ndtrace --frames`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub animation: Option<AnimationDesc>,
    /// The hyperplane the command line and `ndtrace.animate` cut the scene with: they render
    /// the (N−1)-dimensional slice ([`super::slice`]) instead of the scene, or beside it with
    /// `[composite] layout = "slice"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slice: Option<SliceDesc>,
    /// Clip hyperplanes acting on every object: rays ignore hits on their far side
    /// ([`super::clip`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub clip: Vec<ClipDesc>,
    /// Fill the cuts of every closed object's clip hyperplanes with its slice (an object's own
    /// `cap` overrides it).
    #[serde(default, skip_serializing_if = "is_false")]
    pub cap: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// A clip hyperplane n̂·x = `offset` (n̂ the unit `normal`): what lies beyond it, n̂·x > offset,
/// is not drawn.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClipDesc {
    /// The hyperplane's normal, N numbers (need not be unit length), pointing to the side
    /// removed.
    pub normal: Vec<f64>,
    /// Its signed distance from the origin along the unit normal.
    pub offset: f64,
}

/// `[slice]`: the hyperplane n̂·x = `offset` (n̂ the unit `normal`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SliceDesc {
    /// The hyperplane's normal, N numbers (need not be unit length).
    pub normal: Vec<f64>,
    /// Its signed distance from the origin along the unit normal.
    pub offset: f64,
}

/// `[animation] slice = { normal, from, to }`: the scene swept through the hyperplane
/// n̂·x = offset, offset linear in t from `from` to `to`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SliceSweepDesc {
    /// The hyperplane's normal, N numbers.
    pub normal: Vec<f64>,
    /// The offset at t = 0.
    pub from: f64,
    /// The offset at t = 1.
    pub to: f64,
}

impl SceneDesc {
    /// Whether `self` and `other` are equal but for their `[animation]` tables.
    pub fn same_but_animation(&self, other: &SceneDesc) -> bool {
        let SceneDesc {
            dim,
            background,
            ambient,
            camera,
            lights,
            objects,
            render,
            composite,
            animation: _,
            slice,
            clip,
            cap,
        } = self;
        (
            dim, background, ambient, camera, lights, objects, render, composite, slice, clip, cap,
        ) == (
            &other.dim,
            &other.background,
            &other.ambient,
            &other.camera,
            &other.lights,
            &other.objects,
            &other.render,
            &other.composite,
            &other.slice,
            &other.clip,
            &other.cap,
        )
    }
}

impl ObjectDesc {
    /// Whether the object is read from a file (a mesh file or an elevation field's file), which
    /// a build reads again.
    pub fn reads_file(&self) -> bool {
        self.file.is_some() || matches!(self.field, Some(FieldDesc::File(_)))
    }
}

/// `[animation]`: frames in which a rotation — one of `sweep`, `slerp` or `rolling` — moves the
/// target from its place in the scene. Frame k of K sits at t = k/(K−1) (t = k/K when
/// `periodic`, so that a full turn loops without a repeated frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnimationDesc {
    /// Number of frames K.
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// Frames per second of the GIF or MP4.
    #[serde(default = "default_fps")]
    pub fps: f64,
    /// t = k/K instead of k/(K−1): the last frame does not repeat the first.
    #[serde(default)]
    pub periodic: bool,
    /// What moves: `"objects"` (all), `"camera"`, or a list of object indices.
    #[serde(default)]
    pub target: AnimationTarget,
    /// Centre of the rotation (default: the origin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<Vec<f64>>,
    /// A plane-angle sweep R_ij(θ(t)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep: Option<SweepDesc>,
    /// An SO(4) double-quaternion slerp (dim = 4).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slerp: Option<SlerpDesc>,
    /// A rolling-ball path.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rolling: Option<RollingPathDesc>,
    /// A sweep of the `[slice]` hyperplane through the scene (no rotation: each frame is the
    /// scene's slice at that offset).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slice: Option<SliceSweepDesc>,
    /// Rotations at given times, interpolated ([`crate::rotation::spline`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keyframes: Option<Vec<KeyframeDesc>>,
    /// How `keyframes` are interpolated: `"spline"` (C¹, the default) or `"slerp"` (geodesic
    /// pieces).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interpolation: Option<Interpolation>,
}

/// One keyframe: the rotation at a time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyframeDesc {
    /// When (any unit; the frames span the first to the last key's time).
    pub time: f64,
    /// The rotation, in any form of a transform's `rotate` step.
    pub rotation: RotateDesc,
}

/// How keyframes are interpolated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Interpolation {
    /// A C¹ orientation spline through the keys.
    #[default]
    Spline,
    /// Geodesic pieces between neighbouring keys.
    Slerp,
}

fn default_frames() -> u32 {
    48
}
fn default_fps() -> f64 {
    24.0
}

/// What an animation moves.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "expected \"objects\", \"camera\" or a list of object indices"
)]
pub enum AnimationTarget {
    /// `"objects"` or `"camera"`.
    Named(String),
    /// These objects (indices into `objects`).
    Objects(Vec<usize>),
}

impl Default for AnimationTarget {
    fn default() -> Self {
        AnimationTarget::Named("objects".into())
    }
}

/// `sweep = {plane = [i, j], degrees = [θ0, θ1]}`: R_ij with θ linear in t.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepDesc {
    /// The rotation plane (axes from 0), turning axis i toward axis j.
    pub plane: [usize; 2],
    /// Angles at t = 0 and t = 1, degrees.
    pub degrees: [f64; 2],
}

/// `slerp = {from = [q, p], to = [q, p]}`: the SO(4) rotation v ↦ q·v·p̄ with q and p slerped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlerpDesc {
    /// Unit quaternions (q, p) at t = 0.
    pub from: [[f64; 4]; 2],
    /// Unit quaternions (q, p) at t = 1.
    pub to: [[f64; 4]; 2],
}

/// `rolling = {path = [[…], …], radius = R}`: the rolling ball driven along a polyline of
/// controller positions (N−1 numbers each), one rolling step per path segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RollingPathDesc {
    /// Controller positions P_0 … P_m (at least two).
    pub path: Vec<Vec<f64>>,
    /// Ball radius R.
    pub radius: f64,
    /// How a displacement becomes an angle: `"course"` (c = R/D, s = r/D) or `"arc"` (θ = r/R).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<crate::rotation::RollingAngle>,
}

fn default_background() -> Vec<f64> {
    vec![0.0, 0.0, 0.0]
}
fn default_ambient() -> Vec<f64> {
    vec![0.2, 0.2, 0.2]
}

/// One resolution for every retina axis, or one per axis R_1 … R_{N−1}.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "expected a positive integer or a list of N−1 positive integers"
)]
pub enum Resolution {
    /// The same number of cells along every retina axis.
    Uniform(u64),
    /// R_1 … R_{N−1}.
    PerAxis(Vec<u64>),
}

/// `up` as a list of N−2 vectors (or, for N = 3, a single vector).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged, expecting = "expected a list of N−2 vectors of N numbers")]
pub enum UpDesc {
    /// The canonical form: a list of vectors.
    List(Vec<Vec<f64>>),
    /// A single vector (allowed when N − 2 = 1).
    Single(Vec<f64>),
}

/// The camera: position, orientation and projection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Focal point (perspective) or centre of the image plane (orthographic).
    pub position: Vec<f64>,
    /// Point looked at; the view direction is `look_at − position`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub look_at: Option<Vec<f64>>,
    /// With `look_at`: N−2 vectors fixing the retina axes u_2 … u_{N−1} in order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<UpDesc>,
    /// Instead of `look_at`: an orthonormal N×N matrix as N rows, whose columns are
    /// u_1 … u_{N−1} and then the viewing direction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<Vec<Vec<f64>>>,
    /// `"perspective"` (default) or `"orthographic"`.
    #[serde(default)]
    pub projection: Projection,
    /// Perspective: full angle across u_1, in degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fov: Option<f64>,
    /// Orthographic: half-width of the retina across u_1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extent: Option<f64>,
    /// Cells per retina axis.
    pub resolution: Resolution,
}

/// A light source.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightDesc {
    /// Light from infinitely far away; `direction` points towards the light.
    Directional {
        /// Towards the light (need not be unit length).
        direction: Vec<f64>,
        /// RGB colour (intensity).
        #[serde(default = "default_light_color")]
        color: Vec<f64>,
    },
    /// A point light.
    Point {
        /// Position of the light.
        position: Vec<f64>,
        /// RGB colour (intensity at distance 1).
        #[serde(default = "default_light_color")]
        color: Vec<f64>,
        /// Intensity falls off as 1/d^falloff (0: none; N−1 is physical in R^N).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        falloff: Option<f64>,
    },
}

fn default_light_color() -> Vec<f64> {
    vec![1.0, 1.0, 1.0]
}

/// The kinds of shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// Inline `vertices` and `simplices`, or a `.npz` `file` with those arrays.
    Mesh,
    /// Boundary of the regular N-simplex (circumradius 1, centred at the origin).
    Simplex,
    /// Boundary of [−1, 1]^N, each (N−1)-cube face split into (N−1)! simplices.
    Hypercube,
    /// Boundary of the cross-polytope with vertices ±e_i.
    CrossPolytope,
    /// The unit sphere S^{N−1}, `subdivisions` levels.
    Sphere,
    /// A triangulated 2-surface in R^4 (`vertices`, `triangles`), rendered directly by the
    /// limit of circle-bundle thickening ("bear hair", [`crate::surface`]).
    Surface,
    /// The 4D elevation map w = height·f(x, y, z) of a 3D scalar `field`
    /// ([`crate::mesh::elevation`]).
    Elevation,
}

impl ShapeKind {
    /// The names accepted in scene files.
    pub const NAMES: [&'static str; 7] = [
        "mesh",
        "simplex",
        "hypercube",
        "cross_polytope",
        "sphere",
        "surface",
        "elevation",
    ];
}

/// An object: a shape, a material and a transform.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// What to build.
    pub shape: ShapeKind,
    /// What the object stands for, in the picture's legend (a swatch of its colour with this
    /// text).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// Mesh and surface: vertex positions (V, N).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertices: Option<Rows<f64>>,
    /// Mesh: vertex indices (S, N) of each (N−1)-simplex.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simplices: Option<Rows<i64>>,
    /// Surface: vertex indices (T, 3) of each triangle.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub triangles: Option<Rows<i64>>,
    /// Surface: the width of its sheet in the retina, in retina cells (default
    /// [`crate::surface::DEFAULT_WIDTH`]): what the retina (its files, and pictures drawn from
    /// its cells alone) holds. Pictures drawn from the scene use `line_width`; a `width` given
    /// is accepted with a warning saying so.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
    /// Surface: its least apparent thickness in a picture drawn from the scene, in picture
    /// pixels (default [`crate::surface::DEFAULT_LINE_WIDTH`]): a surface seen edge-on is a
    /// line this wide.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line_width: Option<f64>,
    /// Mesh: a `.npz` file holding `vertices` and `simplices`, relative to the scene file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// Sphere: subdivision level (default 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub subdivisions: Option<u32>,
    /// Elevation: the 3D scalar field, a file (`.npy`, `.npz` with `key`, `.nii`/`.nii.gz`
    /// through nibabel) relative to the scene file, or inline nested lists indexed `[x][y][z]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub field: Option<FieldDesc>,
    /// Elevation: the array's name in an `.npz` field file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub key: Option<String>,
    /// Elevation: the box [[x0, x1], [y0, y1], [z0, z1]] the grid spans (default: cubic voxels,
    /// the longest side spanning [−1, 1], centred).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extent: Option<Vec<Vec<f64>>>,
    /// Elevation: w = height·f (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
    /// Elevation: normals of the smooth graph, ∝ (−height·∇f, 1), instead of flat tetrahedra.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smooth: Option<bool>,
    /// One scalar per vertex, interpolated at the hit, for `material.colormap` and
    /// `material.isolines` (an elevation map's default: its field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub values: Option<Column<f64>>,
    /// Surface appearance.
    #[serde(default)]
    pub material: MaterialDesc,
    /// Transforms applied in order (the first entry acts first).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub transform: Vec<TransformDesc>,
    /// Clip hyperplanes of this object (world space), besides the scene's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub clip: Vec<ClipDesc>,
    /// Fill the cuts of this object's clip hyperplanes (its own and the scene's) with its slice
    /// (default: the scene's `cap`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cap: Option<bool>,
}

/// An elevation map's field: a file name, the values inline as nested lists `[x][y][z]`, or
/// (from the Python builder) one flat array handed over without a trip through lists.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "expected a file name or a 3-D array of numbers (nested lists indexed [x][y][z])"
)]
pub enum FieldDesc {
    /// A file relative to the scene file.
    File(String),
    /// Inline values.
    Inline(Vec<Vec<Vec<f64>>>),
    /// A C-ordered array set by the bindings (never read from TOML; written as nested lists).
    #[serde(skip_deserializing)]
    Array(Grid),
}

impl FieldDesc {
    /// The shape and values (C order) of an inline or array field; `None` for a file or a
    /// ragged inline list.
    fn cells(&self) -> Option<([usize; 3], Box<dyn Iterator<Item = f64> + '_>)> {
        match self {
            FieldDesc::File(_) => None,
            FieldDesc::Inline(x) => {
                let ny = x.first().map_or(0, Vec::len);
                let nz = x.first().and_then(|p| p.first()).map_or(0, Vec::len);
                let full = x
                    .iter()
                    .all(|p| p.len() == ny && p.iter().all(|r| r.len() == nz));
                full.then(|| {
                    let values = x.iter().flatten().flatten().copied();
                    (
                        [x.len(), ny, nz],
                        Box::new(values) as Box<dyn Iterator<Item = f64>>,
                    )
                })
            }
            FieldDesc::Array(g) => Some((g.shape, Box::new(g.values.iter().copied()))),
        }
    }
}

/// Equal descriptions: an array field equals the inline lists with the same values (what it
/// becomes on a TOML round trip). Values compare bit for bit, so that a field masked with NaN
/// equals its copies.
impl PartialEq for FieldDesc {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (FieldDesc::File(a), FieldDesc::File(b)) => a == b,
            (FieldDesc::File(_), _) | (_, FieldDesc::File(_)) => false,
            _ => match (self.cells(), other.cells()) {
                (Some((sa, a)), Some((sb, b))) => {
                    sa == sb && a.map(f64::to_bits).eq(b.map(f64::to_bits))
                }
                // Ragged lists (refused when built) compare as lists.
                _ => {
                    matches!((self, other), (FieldDesc::Inline(a), FieldDesc::Inline(b)) if a == b)
                }
            },
        }
    }
}

/// A 3-D array of field values, C-ordered (index `[x][y][z]` at `(x·ny + y)·nz + z`), shared
/// between copies of the description.
#[derive(Debug, Clone)]
pub struct Grid {
    shape: [usize; 3],
    values: Shared<f64>,
}

impl Grid {
    /// A grid of `values` (C order) with `shape`; `None` unless their counts agree.
    pub fn new(shape: [usize; 3], values: impl Into<Shared<f64>>) -> Option<Grid> {
        let values = values.into();
        let count = shape.iter().try_fold(1usize, |n, &k| n.checked_mul(k));
        (count == Some(values.len())).then_some(Grid { shape, values })
    }

    /// `[nx, ny, nz]`.
    pub fn shape(&self) -> [usize; 3] {
        self.shape
    }

    /// The `nx·ny·nz` values, C order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
}

/// Written as the nested lists `[x][y][z]` an inline field is read from.
impl Serialize for Grid {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let [nx, ny, nz] = self.shape;
        let planes: Vec<Vec<&[f64]>> = (0..nx)
            .map(|x| {
                (0..ny)
                    .map(|y| &self.values[(x * ny + y) * nz..(x * ny + y + 1) * nz])
                    .collect()
            })
            .collect();
        planes.serialize(s)
    }
}

/// A reflection coefficient: one number or an RGB triple.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged, expecting = "expected a number or a list of 3 numbers (RGB)")]
pub enum Coefficient {
    /// The same for R, G and B.
    Scalar(f64),
    /// Per channel.
    Rgb(Vec<f64>),
}

/// Surface appearance (N-D Lambert + Blinn–Phong).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// Base colour (RGB, linear).
    #[serde(default = "default_color")]
    pub color: Vec<f64>,
    /// Ambient coefficient (default 1).
    #[serde(default = "one")]
    pub ambient: Coefficient,
    /// Diffuse coefficient (default 1).
    #[serde(default = "one")]
    pub diffuse: Coefficient,
    /// Specular coefficient (default 0).
    #[serde(default = "zero")]
    pub specular: Coefficient,
    /// Blinn–Phong exponent (default 32).
    #[serde(default = "default_shininess")]
    pub shininess: f64,
    /// Per-vertex normals averaged from neighbouring simplices, interpolated barycentrically
    /// (for a surface: per-vertex tangent planes).
    #[serde(default)]
    pub smooth: bool,
    /// Surface objects: the fraction of light the surface stops (1 opaque, the default; what
    /// lies behind shows through the rest).
    #[serde(default = "one_f64", skip_serializing_if = "is_one")]
    pub opacity: f64,
    /// Colour from the object's per-vertex `values` through a named colormap (matplotlib's
    /// names, `_r` reversed), instead of `color`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colormap: Option<String>,
    /// The values mapped to the colormap's ends (default: the smallest and largest value).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<Vec<f64>>,
    /// Isosurface markings: bands where the interpolated `values` cross each given value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub isolines: Option<IsolinesDesc>,
    /// A cubic lattice texture on the object's own x, y, z coordinates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lattice: Option<LatticeDesc>,
    /// Colour by structure instead of `color`: `"cell"`, `"object"` or `"depth"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color_by: Option<ColorBy>,
    /// The qualitative palette of `color_by` and of edges coloured by direction (matplotlib's
    /// names; default `"tab10"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub palette: Option<String>,
}

/// `material.color_by`: colour by structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorBy {
    /// Each flat cell (the connected simplices of one hyperplane) a colour of the palette;
    /// cells in parallel hyperplanes share one.
    Cell,
    /// Each object colour k of the palette, k its index in the scene.
    Object,
    /// The N-D depth of the hit (distance from the eye) through the material's colormap.
    Depth,
}

/// `material.isolines`: bands where the interpolated per-vertex values cross each of `values`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IsolinesDesc {
    /// The values marked.
    pub values: Vec<f64>,
    /// Band width in world units along the object (default 0.03).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
    /// Band colour (default near-black).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<Vec<f64>>,
}

/// `material.lattice`: the planes x, y, z = k·spacing of the object's own space, as bands.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeDesc {
    /// Distance between planes.
    pub spacing: f64,
    /// Band width (default spacing / 12).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
    /// Band colour (default white).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<Vec<f64>>,
}

fn default_color() -> Vec<f64> {
    vec![0.7, 0.7, 0.7]
}
fn one() -> Coefficient {
    Coefficient::Scalar(1.0)
}
fn zero() -> Coefficient {
    Coefficient::Scalar(0.0)
}
fn default_shininess() -> f64 {
    32.0
}
fn one_f64() -> f64 {
    1.0
}
fn is_one(x: &f64) -> bool {
    *x == 1.0
}

impl Default for MaterialDesc {
    fn default() -> Self {
        MaterialDesc {
            color: default_color(),
            ambient: one(),
            diffuse: one(),
            specular: zero(),
            shininess: default_shininess(),
            smooth: false,
            opacity: 1.0,
            colormap: None,
            range: None,
            isolines: None,
            lattice: None,
            color_by: None,
            palette: None,
        }
    }
}

/// `scale = s` (uniform) or one factor per axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged, expecting = "expected a number or a list of N numbers")]
pub enum ScaleDesc {
    /// Uniform scale.
    Uniform(f64),
    /// One factor per axis.
    PerAxis(Vec<f64>),
}

/// A rotation, in one of three forms (exactly one of `plane`, `quaternions`, `rolling`):
///
/// * `{ plane = [i, j], degrees = θ }`: the course's R_ij turning axis i toward axis j
///   (rotations paper, eq. 6);
/// * `{ quaternions = [q, p] }` (dim = 4): the rotation v ↦ q·v·p̄ of unit quaternions
///   (notes, "Quaternion form in 4D");
/// * `{ rolling = [d_1, …, d_{N−1}], radius = R, angle = "course" | "arc" }`: the rolling ball
///   M_N (rotations paper, eq. 5) for a controller displacement d.
///
/// Which keys go together is checked when the scene is built, so errors name the field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotateDesc {
    /// Plane form: the axes [i, j] (numbered from 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane: Option<[usize; 2]>,
    /// Plane form: the angle in degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub degrees: Option<f64>,
    /// Double-quaternion form (dim = 4): [q, p], two unit quaternions [q0, q1, q2, q3].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quaternions: Option<Vec<Vec<f64>>>,
    /// Rolling-ball form: the controller displacement, N − 1 numbers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rolling: Option<Vec<f64>>,
    /// Rolling-ball form: the ball radius R (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Rolling-ball form: `"course"` (c = R/D, s = r/D; the default) or `"arc"` (θ = r/R).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<crate::rotation::RollingAngle>,
}

/// One step of an object transform.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum TransformDesc {
    /// Scale about the origin.
    Scale(ScaleDesc),
    /// Translate by a vector.
    Translate(Vec<f64>),
    /// Rotate: in a coordinate plane, by a pair of quaternions (4D) or by the rolling ball.
    Rotate(RotateDesc),
    /// N×N linear or (N+1)×(N+1) affine matrix (rows).
    Matrix(Vec<Vec<f64>>),
}

/// What the tracer writes into the retina's colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RenderMode {
    /// Lighting and shadows.
    #[default]
    Shaded,
    /// Grey level from depth (near bright, far dark).
    Depth,
    /// The first three normal components mapped from [−1, 1] to [0, 1].
    Normal,
    /// A distinct colour per primitive.
    PrimitiveId,
    /// The first three barycentric coordinates as RGB.
    Barycentric,
}

/// Tracing options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// Rays per retina cell (stratified jitter when > 1).
    #[serde(default = "default_samples")]
    pub samples: u32,
    /// Seed of the sample jitter.
    #[serde(default)]
    pub seed: u64,
    /// Cast shadow rays toward the lights.
    #[serde(default = "yes")]
    pub shadows: bool,
    /// Discard simplices facing away from the eye.
    #[serde(default)]
    pub cull_backfaces: bool,
    /// Turn normals toward the viewer before lighting.
    #[serde(default = "yes")]
    pub two_sided: bool,
    /// What to render.
    #[serde(default)]
    pub mode: RenderMode,
    /// Where the lighting is evaluated: at every hit (`"phong"`, the default) or at the hit
    /// simplex's vertices and interpolated (`"gouraud"`).
    #[serde(default, skip_serializing_if = "is_phong")]
    pub shading: Shading,
}

fn is_phong(s: &Shading) -> bool {
    *s == Shading::Phong
}

/// Where the lighting model is evaluated (notes Part II(B): "dot product of light with 4D
/// versions of usual vectors give Gouraud and Phong models").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shading {
    /// At every hit point, with the interpolated shading normal (Phong).
    #[default]
    Phong,
    /// At the vertices of the hit simplex (their normals, positions and directions to the
    /// eye), the diffuse and specular factors interpolated barycentrically (Gouraud).
    Gouraud,
}

fn default_samples() -> u32 {
    1
}
fn yes() -> bool {
    true
}

impl Default for RenderDesc {
    fn default() -> Self {
        RenderDesc {
            samples: 1,
            seed: 0,
            shadows: true,
            cull_backfaces: false,
            two_sided: true,
            mode: RenderMode::Shaded,
            shading: Shading::Phong,
        }
    }
}
