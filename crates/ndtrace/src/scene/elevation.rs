//! `shape = "elevation"`: a 3D scalar field as a 4D elevation map ([`crate::mesh::elevation`]),
//! from a file (`.npy`, `.npz`, or NIfTI through the [`MeshReader`]) or inline values; errors
//! name the field and the file.

use super::desc::{FieldDesc, ObjectDesc, ShapeKind};
use super::errors::PathError;
use super::fields::R;
use super::mesh_file::MeshReader;
use super::npz::{read_npy, read_npz_array, ArrayNd};
use crate::linalg::Vector;
use crate::mesh::elevation::{elevation_map, gradient_normals, Extent, Field};
use crate::mesh::Mesh;
use std::borrow::Cow;
use std::path::Path;

/// An elevation object's mesh, its per-vertex field values, its smooth normals (in the field's
/// own space; when `smooth = true`) and the number of grid cubes left out as holes.
pub(crate) struct ElevationObject<const N: usize> {
    pub mesh: Mesh<N>,
    pub values: Vec<f64>,
    pub normals: Option<Vec<Vector<N>>>,
    pub holes: usize,
}

/// The keys an elevation object does not use.
fn unused(o: &ObjectDesc) -> [(&'static str, bool); 6] {
    [
        ("vertices", o.vertices.is_some()),
        ("simplices", o.simplices.is_some()),
        ("triangles", o.triangles.is_some()),
        ("width", o.width.is_some()),
        ("file", o.file.is_some()),
        ("subdivisions", o.subdivisions.is_some()),
    ]
}

/// Errors for the elevation keys on an object of another shape.
pub(crate) fn reject_elevation_keys(o: &ObjectDesc, path: &str) -> R<()> {
    for (key, present) in [
        ("field", o.field.is_some()),
        ("key", o.key.is_some()),
        ("extent", o.extent.is_some()),
        ("height", o.height.is_some()),
        ("smooth", o.smooth.is_some()),
    ] {
        if present {
            return Err(PathError::new(
                format!("{path}.{key}"),
                format!(
                    "\"{key}\" is used by shape \"elevation\" only, not \"{}\"{}",
                    ShapeKind::NAMES[o.shape as usize],
                    if key == "smooth" {
                        " (smooth shading of a mesh: material.smooth)"
                    } else {
                        ""
                    }
                ),
            ));
        }
    }
    Ok(())
}

/// Builds the elevation object `o` at `path`; files resolve against `base`.
pub(crate) fn elevation_object<const N: usize>(
    o: &ObjectDesc,
    path: &str,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
) -> R<ElevationObject<N>> {
    if N != 4 {
        return Err(PathError::new(
            format!("{path}.shape"),
            format!("shape \"elevation\" is the graph of a 3D field in R^4: it needs dim = 4, got dim = {N}"),
        ));
    }
    let e = elevation_object_4d(o, path, base, reader)?;
    Ok(crate::dim::same(e).unwrap_or_else(|_| unreachable!("N = 4")))
}

/// [`elevation_object`] in R^4, compiled once.
fn elevation_object_4d(
    o: &ObjectDesc,
    path: &str,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
) -> R<ElevationObject<4>> {
    const N: usize = 4;
    for (key, present) in unused(o) {
        if present {
            return Err(PathError::new(
                format!("{path}.{key}"),
                format!("\"{key}\" is not used by shape \"elevation\" (give field)"),
            ));
        }
    }
    let fpath = format!("{path}.field");
    let (values, shape) = match &o.field {
        None => {
            return Err(PathError::new(
                path,
                "an elevation map needs a field (a file or a 3-D array)",
            ))
        }
        Some(FieldDesc::Inline(x)) => {
            let (values, shape) = inline(x, &fpath)?;
            (Cow::Owned(values), shape)
        }
        Some(FieldDesc::Array(g)) => (Cow::Borrowed(g.values()), g.shape()),
        Some(FieldDesc::File(file)) => {
            let full = match base {
                Some(b) => b.join(file),
                None => Path::new(file).to_path_buf(),
            };
            let a = read_field_file(&full, o.key.as_deref(), reader)
                .map_err(|e| PathError::new(&fpath, e))?;
            let [nx, ny, nz] = match a.shape[..] {
                [x, y, z] => [x, y, z],
                _ => {
                    return Err(PathError::new(
                        &fpath,
                        format!(
                            "{}: expected a 3-D array indexed [x, y, z], got shape {:?}",
                            full.display(),
                            a.shape
                        ),
                    ))
                }
            };
            (Cow::Owned(a.data), [nx, ny, nz])
        }
    };
    if o.key.is_some()
        && !matches!(&o.field, Some(FieldDesc::File(f)) if f.to_ascii_lowercase().ends_with(".npz"))
    {
        return Err(PathError::new(
            format!("{path}.key"),
            "\"key\" names an array of an .npz field file",
        ));
    }
    let extent = match &o.extent {
        None => None,
        Some(e) => Some(extent(e, &format!("{path}.extent"))?),
    };
    let height = o.height.unwrap_or(1.0);
    let field = Field {
        values: &values,
        shape,
    };
    // The mesh (per grid point one vertex, its normal and value, six tetrahedra) and the BVH
    // over its tetrahedra, refused before any of it is built.
    let points = field.values.len() as f64;
    let tets = 6.0
        * shape
            .iter()
            .map(|&k| k.saturating_sub(1) as f64)
            .product::<f64>();
    crate::memory::check(
        points * (8.0 * 4.0 + 8.0 * 4.0 + 8.0)
            + tets * 4.0 * 4.0
            + crate::accel::bvh_bytes(N, tets),
        &format!(
            "an elevation map of {} grid points and its BVH",
            field.values.len()
        ),
    )
    .map_err(|e| PathError::new(path, e))?;
    let elev = elevation_map::<N>(&field, extent.as_ref(), height).map_err(|e| {
        let at = if e.starts_with("height") {
            format!("{path}.height")
        } else if e.starts_with("the ") && e.contains(" range ") {
            format!("{path}.extent")
        } else {
            fpath.clone()
        };
        PathError::new(at, e)
    })?;
    let normals = o
        .smooth
        .unwrap_or(false)
        .then(|| gradient_normals(&field, &elev, height));
    Ok(ElevationObject {
        mesh: elev.mesh,
        values: elev.values,
        normals,
        holes: elev.holes,
    })
}

/// A field file: `.npy`, `.npz` (the array `key`, or its only array), or anything else through
/// `reader` (NIfTI with nibabel in the Python package).
fn read_field_file(
    full: &Path,
    key: Option<&str>,
    reader: Option<&dyn MeshReader>,
) -> Result<ArrayNd, String> {
    let ext = full
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if !full.is_file() {
        return Err(format!("cannot open {}: no such file", full.display()));
    }
    let a = if ext.ends_with(".npy") {
        read_npy(full)?
    } else if ext.ends_with(".npz") {
        read_npz_array(full, key)?
    } else {
        match reader {
            Some(r) => r.read_field(full).map_err(|e| format!("{}: {e}", full.display()))?,
            None => {
                return Err(format!(
                    "{}: only .npy and .npz fields can be read here (the Python package reads NIfTI .nii/.nii.gz with nibabel)",
                    full.display()
                ))
            }
        }
    };
    Ok(a)
}

/// Inline nested lists [x][y][z], checked to be a full box.
fn inline(x: &[Vec<Vec<f64>>], fpath: &str) -> R<(Vec<f64>, [usize; 3])> {
    let nx = x.len();
    let ny = x.first().map_or(0, Vec::len);
    let nz = x.first().and_then(|p| p.first()).map_or(0, Vec::len);
    let mut values = Vec::with_capacity(nx * ny * nz);
    for (i, plane) in x.iter().enumerate() {
        if plane.len() != ny {
            return Err(PathError::new(
                format!("{fpath}[{i}]"),
                format!("expected {ny} rows (as field[0]), got {}", plane.len()),
            ));
        }
        for (j, row) in plane.iter().enumerate() {
            if row.len() != nz {
                return Err(PathError::new(
                    format!("{fpath}[{i}][{j}]"),
                    format!("expected {nz} values (as field[0][0]), got {}", row.len()),
                ));
            }
            values.extend_from_slice(row);
        }
    }
    Ok((values, [nx, ny, nz]))
}

fn extent(e: &[Vec<f64>], path: &str) -> R<Extent> {
    if e.len() != 3 || e.iter().any(|r| r.len() != 2) {
        return Err(PathError::new(
            path,
            "expected [[x0, x1], [y0, y1], [z0, z1]]",
        ));
    }
    let out: Extent = std::array::from_fn(|k| [e[k][0], e[k][1]]);
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let [lo, hi] = out[k];
        if !(lo.is_finite() && hi.is_finite() && hi > lo) {
            return Err(PathError::new(
                format!("{path}[{k}]"),
                format!("the {axis} range [{lo}, {hi}] must be finite with {axis}1 > {axis}0"),
            ));
        }
    }
    Ok(out)
}
