//! What a picture may ask the scene its retina was traced from ([`Detail::Scene`](super::Detail::Scene), N = 4): the
//! scene's exact structure in the retina, and the 4D ray through any retina point.
//!
//! A retina point p is a 4D ray from the eye. A mesh simplex (a tetrahedron) projects, through
//! the 4D camera's perspective, to a tetrahedron of the retina, and the region of the retina
//! whose rays meet a mesh is the union of those. Over it, the number of simplices a ray crosses
//! (its *layers*) changes only across the projections of the ridges (triangles) whose
//! simplices lie on one side of it: the **contour ridges**, where the hypersurface folds away
//! from the eye (two simplices on one side: ±2), and the boundary ridges of an open mesh (±1).
//! Those triangles — *count sheets* — bound the region exactly: a picture ray that counts its
//! crossings from outside knows between any two of them whether it is inside ([`Structure::counted`]),
//! at any picture resolution, whatever the retina's. Across the other ridges a ray's layer
//! count does not change, but its colour may: the **crease sheets** are the ridges whose two
//! simplices' normals differ by more than the crease angle (a polytope's 2-faces, seen where
//! they are the nearest surface). A surface object ("bear hair") is its triangles, projected
//! likewise: **surface sheets**.
//!
//! The scene side (`render/probe.rs`) gives the sheets and answers [`SceneProbe::probe`]: the
//! colour, depth and object of the nearest hit of the ray through a retina point, shaded as
//! the tracer shades it. The picture ([`super::picture`]) casts those rays only where the
//! retina's cells do not say enough.

use crate::camera::Projection;

/// A vertex of a sheet: its position in the retina (continuous cell coordinates x = column,
/// y = row, z = slice; cell i spans [i, i + 1]) and the 4D camera's view coordinate Z of the
/// world point it is the image of (Z > 0 in front of the eye; for an orthographic camera the
/// distance from the image plane).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheetVertex {
    /// Retina position, cell coordinates (column, row, slice).
    pub p: [f64; 3],
    /// 4D view coordinate of the world point.
    pub z: f64,
}

/// What a sheet is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SheetKind {
    /// The projection of a ridge of a mesh object. A ray crossing it toward the side its
    /// normal (p₁ − p₀) × (p₂ − p₀) points to gains `delta` layers (the simplices on that side
    /// less those on the other: 0 for most ridges, ±2 at a contour, ±1 at an open boundary);
    /// `crease` when its two simplices' normals differ by more than the crease angle.
    Mesh {
        /// Layers gained crossing toward the normal's side.
        delta: i8,
        /// A crease between two simplices.
        crease: bool,
    },
    /// Triangle `triangle` of a surface object.
    Surface {
        /// The triangle's index in its object.
        triangle: u32,
    },
}

/// A triangle of the structure: three [`SheetVertex`] indices, its object and kind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sheet {
    /// Indices into [`Structure::vertices`].
    pub v: [u32; 3],
    /// The object's index in the scene.
    pub object: u32,
    /// What it is.
    pub kind: SheetKind,
    /// Whether the 4D eye sees it, where the scene knows without a ray (a crease of a convex
    /// object alone in the scene: seen where its simplices face the eye); `None`: ask.
    pub visible: Option<bool>,
}

/// How an object looks in a picture drawn at the picture's resolution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectLook {
    /// A smooth hypersurface (few of its bends are creases): the illustrative mode shows it by
    /// its 4D shading, a denser interior, with its silhouette as a thin line (the course's
    /// "magazine photo"), instead of a nearly clear interior with creases.
    pub smooth: bool,
    /// Surface objects: the least apparent thickness of the sheet, in picture pixels (a sheet
    /// seen edge-on is a line this wide); 0 for meshes.
    pub line_width: f64,
    /// Surface objects: the material's opacity (1 for meshes).
    pub opacity: f64,
}

/// The scene's structure in the retina, for one crease angle: every sheet (see the [module
/// docs](self)), their vertices (shared between the sheets of an object, so that their
/// crossings are counted once), and what decides how a picture uses them.
#[derive(Debug, Clone, Default)]
pub struct Structure {
    /// The sheets' vertices.
    pub vertices: Vec<SheetVertex>,
    /// Count, crease and surface sheets (mesh sheets of neither kind are left out).
    pub sheets: Vec<Sheet>,
    /// Whether a ray's layers may be counted from outside the retina: every simplex of every
    /// mesh projects in front of the eye and inside the retina's box, and none is degenerate.
    /// Otherwise the picture asks [`SceneProbe::covered`] between crossings.
    pub counted: bool,
    /// Per object (scene order).
    pub looks: Vec<ObjectLook>,
    /// The retina: cells per axis (column, row, slice).
    pub res: [usize; 3],
    /// Side of a cell (at unit distance for perspective).
    pub cell: f64,
    /// The 4D camera's projection.
    pub projection: Projection,
}

impl Structure {
    /// The depth the tracer records (distance from the eye; orthographic: from the image
    /// plane) of the point of sheet `v` at retina barycentric coordinates `b`, at retina
    /// position `p`: 1/Z is affine over a perspective image (Z itself over an orthographic one).
    pub fn depth(&self, v: [u32; 3], b: [f64; 3], p: [f64; 3]) -> f64 {
        let z = |k: usize| self.vertices[v[k] as usize].z;
        match self.projection {
            Projection::Perspective => {
                let inv = b[0] / z(0) + b[1] / z(1) + b[2] / z(2);
                let u = self.retina_point(p);
                (1.0 + u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt() / inv
            }
            Projection::Orthographic => b[0] * z(0) + b[1] * z(1) + b[2] * z(2),
        }
    }

    /// The retina coordinates (u₁, u₂, u₃) of cell-coordinate point `p` (camera.rs: u₁ =
    /// (x − R₁/2)·s, u₂ = (R₂/2 − y)·s, u₃ = (z − R₃/2)·s).
    pub fn retina_point(&self, p: [f64; 3]) -> [f64; 3] {
        let [r1, r2, r3] = self.res.map(|r| r as f64);
        [
            (p[0] - r1 / 2.0) * self.cell,
            (r2 / 2.0 - p[1]) * self.cell,
            (p[2] - r3 / 2.0) * self.cell,
        ]
    }
}

/// The texture lines at a hit — its object's isolines and lattice — for a picture that draws
/// them itself, a constant number of pixels wide: each line is the level `level[j]` of a
/// scalar field of value `value[j]` at the hit (the object's interpolated `values`, or an
/// object-space coordinate for the lattice), drawn in `color[j]` (shaded as the hit is); `base`
/// is the hit's colour without them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureLines {
    /// How many of the arrays' entries are used.
    pub count: usize,
    /// The field's value at the hit.
    pub value: [f64; MAX_TEXTURE_LINES],
    /// The level of the nearest line.
    pub level: [f64; MAX_TEXTURE_LINES],
    /// The line's colour there, linear RGB.
    pub color: [[f32; 3]; MAX_TEXTURE_LINES],
    /// The hit's colour without lines, linear RGB.
    pub base: [f32; 3],
}

/// Most fields of [`TextureLines`]: the isolines' and the lattice's three axes.
pub const MAX_TEXTURE_LINES: usize = 4;

/// The nearest hit of the 4D ray through a retina point, as [`SceneProbe::probe`] gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Probe {
    /// Whether the ray meets a mesh.
    pub hit: bool,
    /// Its depth (as the retina's `depth`), infinite on a miss.
    pub depth: f64,
    /// Its object, −1 on a miss.
    pub object: i32,
    /// Its colour as the tracer shades it (linear RGB, the render mode's), black on a miss.
    pub color: [f32; 3],
    /// Its object's texture lines, when it has isolines or a lattice (the shaded mode).
    pub lines: Option<TextureLines>,
}

impl Probe {
    /// A ray that meets nothing.
    pub const MISS: Probe = Probe {
        hit: false,
        depth: f64::INFINITY,
        object: -1,
        color: [0.0; 3],
        lines: None,
    };
}

/// The scene a retina was traced from, as a picture may ask it ([`Detail::Scene`]).
/// Retina points are in continuous cell coordinates (column, row, slice).
///
/// [`Detail::Scene`]: super::Detail::Scene
pub trait SceneProbe: Sync {
    /// The structure of the scene in the retina at crease angle `crease_angle` (degrees).
    fn structure(&self, crease_angle: f64) -> Structure;
    /// The nearest mesh hit of the ray through `p`, shaded as the tracer shades it.
    fn probe(&self, p: [f64; 3]) -> Probe;
    /// Whether the ray through `p` meets any mesh.
    fn covered(&self, p: [f64; 3]) -> bool;
    /// The point at retina barycentric coordinates `b` of triangle `triangle` of surface
    /// object `object`: its colour (linear RGB, the render mode's) and depth, or `None` when a
    /// mesh is nearer along its ray.
    fn surface(&self, object: u32, triangle: u32, b: [f64; 3]) -> Option<([f32; 3], f64)>;
}
