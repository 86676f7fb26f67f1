//! The small parsers every part of the scene build uses: a field of the description checked
//! and converted to its typed value, or a [`PathError`] naming the field (`objects[2].material
//! .color[1]: must be ≥ 0, got -1`).

use super::desc::Coefficient;
use super::errors::PathError;
use crate::linalg::{Matrix, Rgb, Vector};
use crate::mesh::Mesh;

/// A field's value or the located error.
pub(crate) type R<T> = Result<T, PathError>;

/// The hyperplane of a `[slice]` table (errors name `path.normal`, `path.offset`).
pub(crate) fn slice_plane<const N: usize>(
    s: &super::desc::SliceDesc,
    path: &str,
) -> R<crate::mesh::slice::SlicePlane<N>> {
    if s.normal.len() != N {
        return Err(PathError::new(
            format!("{path}.normal"),
            format!("expected {N} numbers, got {}", s.normal.len()),
        ));
    }
    crate::mesh::slice::SlicePlane::<N>::new(&s.normal, s.offset).map_err(|e| match e {
        crate::NdError::Value { arg, message } => PathError::new(format!("{path}.{arg}"), message),
        e => PathError::new(path, e.to_string()),
    })
}

/// Every number of `v` is finite; else the error names the first that is not (`path[i]`).
pub(crate) fn finite_list(v: &[f64], path: &str) -> R<()> {
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
pub(crate) fn rgb(v: &[f64], path: &str) -> R<Rgb> {
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

/// A reflection coefficient, one number for R, G and B or one per channel, as RGB.
pub(crate) fn coefficient(c: &Coefficient, path: &str) -> R<Rgb> {
    match c {
        Coefficient::Scalar(s) => rgb(&[*s; 3], path),
        Coefficient::Rgb(v) => rgb(v, path),
    }
}

/// An N×N matrix given as N rows of N finite numbers.
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

/// A vertex index as given: an integer (descriptions) or a float (`.npz` files).
pub(crate) trait VertexIndex: Copy + std::fmt::Display {
    /// The index, when it is a whole number below `count`.
    fn below(self, count: usize) -> Option<u32>;
}

impl VertexIndex for f64 {
    fn below(self, count: usize) -> Option<u32> {
        (self >= 0.0 && self < count as f64 && self.fract() == 0.0).then_some(self as u32)
    }
}

impl VertexIndex for i64 {
    fn below(self, count: usize) -> Option<u32> {
        (self >= 0 && (self as u64) < count as u64).then_some(self as u32)
    }
}

/// A mesh from flat row-major arrays: `nv` vertices of N finite coordinates and `ns` simplices
/// of N vertex indices (whole numbers below `nv`); errors name the element
/// (`vpath[i][k]`, `spath[s][k]`). `path` is the object's field path.
pub(crate) fn mesh_from_rows<const N: usize, I: VertexIndex>(
    vertices: &[f64],
    nv: usize,
    simplices: &[I],
    ns: usize,
    path: &str,
    vpath: &str,
    spath: &str,
) -> R<Mesh<N>> {
    // The mesh's own arrays, before they are allocated (the BVH is counted once all
    // objects are known).
    crate::memory::check(
        (nv as f64 * 8.0 + ns as f64 * 4.0) * N as f64,
        &format!("a mesh of {nv} vertices and {ns} simplices"),
    )
    .map_err(|e| PathError::new(path, e))?;
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
            idx[k] = x.below(nv).ok_or_else(|| {
                PathError::new(
                    format!("{spath}[{s}][{k}]"),
                    format!("vertex index {x} out of range: the mesh has {nv} vertices"),
                )
            })?;
        }
        mesh.simplices.push(idx);
    }
    Ok(mesh)
}
