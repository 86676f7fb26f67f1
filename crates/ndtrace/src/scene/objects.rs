//! The objects of a scene: each `[[objects]]` entry's mesh (a generated shape, a mesh given
//! inline or read from a file, an elevation map, a surface), checked, with its values and
//! texture, moved into world space by its transform (course notes, "N-dimensional Imaging":
//! tessellations of (N−1)-simplices; normals by eq. 6, mapped as covectors).

use super::desc::{ObjectDesc, Rows, ShapeKind};
use super::elevation::{elevation_object, reject_elevation_keys};
use super::errors::PathError;
use super::fields::{mesh_from_rows, R};
use super::material::Material;
use super::mesh_file::{read_mesh, MeshReader};
use crate::accel::{bvh_bytes, AccelOptions, FlatFacets, ShapeHints, ToObject};
use crate::convex::Certificate;
use crate::linalg::{
    add, cofactor_matrix, det, identity, mat_vec, norm, scale, transpose, Matrix, Vector,
};
use crate::mesh::Mesh;
use crate::shapes;
use rayon::prelude::*;
use std::borrow::Cow;
use std::path::Path;

/// Largest number of simplices a generated sphere may have.
pub const MAX_GENERATED_SIMPLICES: u64 = 50_000_000;

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
    /// ([`crate::convex::convex_side`]), found at the first trace or probe that needs it
    /// ([`Scene::find_certificates`](super::Scene::find_certificates)). Shadow rays leaving a
    /// simplex away from the body skip the object.
    pub convex: Certificate<N>,
    /// For a `surface` object: its triangles (into `mesh.vertices`; `mesh` has no simplices)
    /// and how they are drawn.
    pub surface: Option<crate::surface::Surface<N>>,
    /// Colour varying over the object ([`crate::texture`]).
    pub texture: Option<crate::texture::Texture<N>>,
    /// World directions → the object's own (A⁻¹ of its transform x ↦ A·x + b; the identity
    /// when A is singular): the legend names the directions of edges in the object's axes.
    pub own_from_world: Matrix<N>,
}

/// What the index may assume of an object of shape `shape` ([`ShapeHints`]): the generated
/// polytopes are convex (an affine map keeps them so), the N-cube's facets are flat pieces of
/// (N−1)! simplices and a mesh's may be, and an elevation map is not worth a convexity
/// certificate (a graph over a box, an open surface).
pub(super) fn hints(shape: ShapeKind) -> ShapeHints {
    ShapeHints {
        known_convex: matches!(
            shape,
            ShapeKind::Simplex | ShapeKind::Hypercube | ShapeKind::CrossPolytope
        ),
        certify: shape != ShapeKind::Elevation,
        flat_facets: match shape {
            ShapeKind::Hypercube => FlatFacets::Always,
            ShapeKind::Mesh => FlatFacets::Search,
            _ => FlatFacets::Never,
        },
    }
}

/// An object of a build in world space, with what the index needs of its transform.
pub(super) struct WorldObject<const N: usize> {
    /// The object, its mesh moved into world space.
    pub object: Object<N>,
    /// The map from world space into its own ([`ToObject::of_transform`]), when it is held
    /// there ([`AccelOptions::own_space`]).
    pub map: Option<ToObject<N>>,
    /// With `keep_own` and a map, its vertices in its own space (before the transform).
    pub own: Option<Vec<Vector<N>>>,
}

/// Step 2 of a build for one object, `o` at `path` with its checked material `mat` and
/// transform x ↦ a·x + b: its mesh (generated, read, or given), its values and texture, its
/// vertices moved into world space (a transform that reverses handedness, det a < 0, would
/// turn outward normals inward — normals are pseudotensors — so its simplices are reordered to
/// keep their orientation), its surface and vertex normals. Warnings about what was left out
/// go to `warnings`.
pub(super) fn world_object<const N: usize>(
    (o, path): (&ObjectDesc, &str),
    (mat, (a, b)): (Material, (Matrix<N>, Vector<N>)),
    (base, reader): (Option<&Path>, Option<&dyn MeshReader>),
    (options, keep_own): (&AccelOptions, bool),
    warnings: &mut Vec<String>,
) -> R<WorldObject<N>> {
    let mut values = None;
    let mut own_normals = None;
    let (mut mesh, triangles) = match o.shape {
        ShapeKind::Surface => {
            reject_elevation_keys(o, path)?;
            let (m, t, w) = surface_mesh::<N>(o, path)?;
            if o.width.is_some() {
                warnings.push(format!(
                    "{path}.width: sets the surface's sheet in the retina (retina cells), which \
                     only pictures drawn from the retina's cells show; pictures drawn from the \
                     scene draw the surface itself, at least `line_width` picture pixels thick"
                ));
            }
            (m, Some((t, w)))
        }
        ShapeKind::Elevation => {
            opaque(o, path)?;
            let e = elevation_object::<N>(o, path, base, reader)?;
            if e.holes > 0 {
                warnings.push(format!(
                    "{path}: left out {} grid cubes with a NaN corner (holes in the elevation map)",
                    e.holes
                ));
            }
            values = Some(e.values);
            own_normals = e.normals;
            (e.mesh, None)
        }
        _ => {
            reject_elevation_keys(o, path)?;
            (object_mesh::<N>(o, path, base, reader)?, None)
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
    if mat.color_by == Some(super::desc::ColorBy::Cell) {
        // A tessellation of a curved boundary has no cells to tell apart: each simplex would
        // be a cell of its own.
        let curved = match o.shape {
            ShapeKind::Surface => Some("a surface has triangles, not cells"),
            ShapeKind::Sphere => Some("a sphere's simplices approximate a curved boundary"),
            ShapeKind::Elevation => Some("an elevation map is a curved graph"),
            _ if mat.smooth => Some("a smooth material shades it as a curved boundary"),
            _ => None,
        };
        if let Some(why) = curved {
            return Err(PathError::new(
                format!("{path}.material.color_by"),
                format!(
                    "\"cell\" needs a mesh of flat cells (coplanar simplices, such as a polytope's): {why}; use \"object\" or \"depth\""
                ),
            ));
        }
    }
    // The cells of `color_by = "cell"`, found in the object's own space (before its transform),
    // so that their normals read in its own axes.
    let cells = (mat.texture.as_ref())
        .and_then(|t| t.by_cell.as_ref())
        .map(|palette| {
            let classes = crate::texture::cells::cell_classes(&mesh);
            let colors = (0..classes.normals.len())
                .map(|k| palette.color(k))
                .collect();
            crate::texture::CellColors { classes, colors }
        });
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
            format!("{path}.transform"),
            format!(
                "is singular or cannot be inverted in floating point (determinant {}): an object with simplices needs an invertible transform",
                det(&a)
            ),
        ));
    }
    let map = map.filter(|_| options.own_space(mesh.simplices.len()));
    let own = (keep_own && map.is_some()).then(|| mesh.vertices.clone());
    mesh.vertices
        .par_iter_mut()
        .for_each(|v| *v = add(&mat_vec(&a, v), &b));
    if let Some(k) = mesh
        .vertices
        .iter()
        .position(|v| v.iter().any(|x| !x.is_finite()))
    {
        // Only a transform can make a vertex non-finite here (the shapes' own vertices are
        // checked where they are made); without one, the object itself is named.
        return Err(if moves {
            PathError::new(
                format!("{path}.transform"),
                format!("makes vertex {k} non-finite"),
            )
        } else {
            PathError::new(path, format!("vertex {k} is not finite"))
        });
    }
    if det(&a) < 0.0 {
        mesh.simplices.iter_mut().for_each(|s| s.swap(0, 1));
    }
    let surface = triangles.map(|(t, (width, line_width))| {
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
            line_width,
            vertex_tangents,
        }
    });
    if let (Some(s), Some(t)) = (&surface, &o.triangles) {
        if s.triangles.len() < t.len() {
            warnings.push(format!(
                "{path}: left out {} surface triangles without area",
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
        // `color_by = "depth"`: the range, unless given, is the scene's camera's (set by the
        // build, `depth_ranges`).
        let depth = (spec.colormap.as_ref())
            .filter(|_| spec.by_depth)
            .map(|(map, range)| (map.clone(), range.unwrap_or([f64::NAN; 2])));
        let colormap = (spec.colormap.as_ref())
            .filter(|_| !spec.by_depth)
            .map(|(map, range)| {
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
            cells,
            depth,
        }
    });
    let own_from_world = Some(transpose(&inverse_t))
        .filter(|m| m.iter().flatten().all(|x| x.is_finite()))
        .unwrap_or_else(identity::<N>);
    let object = Object {
        mesh,
        material: mat,
        vertex_normals,
        // (The build's index says what it is found from.)
        convex: Certificate::none(),
        surface,
        texture,
        own_from_world,
    };
    Ok(WorldObject { object, map, own })
}

fn scale_matrix<const N: usize>(m: &Matrix<N>, s: f64) -> Matrix<N> {
    m.map(|row| scale(&row, s))
}

/// Only surface objects may be transparent.
pub(super) fn opaque(o: &ObjectDesc, path: &str) -> R<()> {
    if o.material.opacity != 1.0 {
        return Err(PathError::new(
            format!("{path}.material.opacity"),
            "only surface objects can be transparent (opacity < 1)",
        ));
    }
    Ok(())
}

/// The mesh of an object of a generated shape or of shape `mesh` (inline or from a file), at
/// `path`, with the keys its shape does not use refused.
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
    extra("line_width", o.line_width.is_some())?;
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

/// A surface's mesh, triangles and widths (the sheet's in the retina, the line's in pictures).
type SurfaceParts<const N: usize> = (Mesh<N>, Vec<[u32; 3]>, (f64, f64));

/// A `surface` object (dim = 4): its vertices as a mesh without simplices, its triangles (those
/// without area dropped, counted in the second value), its sheet width in the retina and its
/// least line width in pictures.
fn surface_mesh<const N: usize>(o: &ObjectDesc, path: &str) -> R<SurfaceParts<N>> {
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
    let line_width = o.line_width.unwrap_or(crate::surface::DEFAULT_LINE_WIDTH);
    if !(line_width > 0.0 && line_width <= crate::surface::MAX_LINE_WIDTH) {
        return Err(PathError::new(
            format!("{path}.line_width"),
            format!(
                "must be a number of picture pixels in (0, {}], got {line_width}",
                crate::surface::MAX_LINE_WIDTH
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
    Ok((mesh, triangles, (width, line_width)))
}

fn shape_name(k: ShapeKind) -> &'static str {
    ShapeKind::NAMES[k as usize]
}
