//! Mesh objects given by `file`: the core reads `.npz` archives itself and asks a
//! [`MeshReader`] it is given (the Python bindings implement one with meshio) for every other
//! format. Either way the arrays are checked here, and errors name the field and the file.

use super::errors::PathError;
use super::fields::mesh_from_rows;
use super::npz::{read_npz, Array2};
use crate::mesh::{orientation, Mesh};
use std::path::Path;

/// Reads the mesh files whose formats the core does not read itself (`.obj`, `.stl`, `.msh`, …).
pub trait MeshReader: Sync {
    /// The arrays `[vertices (V, N), simplices (S, N)]` of the mesh in `path`, for a scene of
    /// dimension `dim`; an error says what is wrong (the caller adds the field and the path).
    fn read(&self, path: &Path, dim: usize) -> Result<[Array2; 2], String>;

    /// The 3D scalar field in `path` (an elevation map's `field`: NIfTI `.nii`, `.nii.gz`, …),
    /// indexed [x, y, z]; an error says what is wrong (the caller adds the field and the path).
    fn read_field(&self, path: &Path) -> Result<super::npz::ArrayNd, String> {
        Err(format!(
            "{}: only .npy and .npz fields can be read here (the Python package reads NIfTI with nibabel)",
            path.display()
        ))
    }
}

/// The mesh of `file` (relative to `base`) for the object at `path`.
pub(crate) fn read_mesh<const N: usize>(
    file: &str,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
    path: &str,
) -> Result<Mesh<N>, PathError> {
    let full = match base {
        Some(b) => b.join(file),
        None => Path::new(file).to_path_buf(),
    };
    let fpath = format!("{path}.file");
    let npz = full
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npz"));
    let arrays = if npz {
        read_npz(&full, &["vertices", "simplices"])
            .and_then(|a| <[Array2; 2]>::try_from(a).map_err(|_| "expected two arrays".into()))
    } else if !full.is_file() {
        Err(format!("cannot open {}: no such file", full.display()))
    } else {
        match reader {
            Some(r) => r
                .read(&full, N)
                .map_err(|e| format!("{}: {e}", full.display())),
            None => Err(format!(
                "{}: only .npz mesh files can be read here (the Python package reads other formats with meshio)",
                full.display()
            )),
        }
    };
    let [v, s] = arrays.map_err(|e| PathError::new(&fpath, e))?;
    // Checked: a header may declare any number of rows.
    let holds = |a: &Array2| a.shape.0.checked_mul(N) == Some(a.data.len());
    let shape_error =
        |message: String| PathError::new(&fpath, format!("{}: {message}", full.display()));
    if v.shape.1 != N || !holds(&v) {
        return Err(shape_error(format!(
            "array \"vertices\" has shape {:?}, expected (V, {N}) for a scene of dimension {N}",
            v.shape
        )));
    }
    if s.shape.1 != N || !holds(&s) {
        return Err(shape_error(format!(
            "array \"simplices\" has shape {:?}, expected (S, {N}) for a scene of dimension {N}",
            s.shape
        )));
    }
    if !s.integer {
        return Err(shape_error(
            "array \"simplices\" must hold integer vertex indices, not floats or bools (e.g. simplices.astype(numpy.int64))".into(),
        ));
    }
    mesh_from_rows::<N, f64>(
        &v.data,
        v.shape.0,
        &s.data,
        s.shape.0,
        path,
        &format!("{fpath}:vertices"),
        &format!("{fpath}:simplices"),
    )
}

/// The warning for the mesh object at `path` when it is closed but not consistently oriented
/// ([`orientation::inconsistency`]): back-face culling would drop its inward simplices.
pub(crate) fn orientation_warning<const N: usize>(mesh: &Mesh<N>, path: &str) -> Option<String> {
    let (flipped, count) = orientation::inconsistency(mesh)?;
    Some(if flipped == 0 {
        format!("{path}: the closed mesh is not orientable: no orientation makes all its {count} simplices agree with their neighbours")
    } else {
        format!(
            "{path}: the closed mesh is not consistently oriented: {flipped} of its {count} simplices face inward (back-face culling drops them); ndtrace.mesh.orient(vertices, simplices) repairs it"
        )
    })
}

#[cfg(test)]
mod tests;
