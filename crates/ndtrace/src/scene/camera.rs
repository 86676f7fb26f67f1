//! The camera of a scene: a `[camera]` table checked and made into a [`Camera<N>`] (course
//! notes, "N-dimensional Imaging": the N-D pinhole and its (N−1)-D retina).

use super::desc::{CameraDesc, Resolution, UpDesc};
use super::errors::PathError;
use super::fields::{matrix_rows, vec_n, R};
use crate::camera::Projection;
use crate::camera::{look_at_orientation, Camera};
use crate::linalg::{identity, mat_mul, Matrix, Vector};

/// Bytes of retina output per cell for dimension N: rgba f32×4, depth f32, normal f32×N,
/// object id i32, primitive id i64.
pub const fn retina_bytes_per_cell(n: usize) -> usize {
    16 + 4 + 4 * n + 4 + 8
}

/// The camera a `[camera]` table describes, checked: an orientation from `look_at` and `up`
/// (the course's frame by Gram–Schmidt) or given orthonormal, the field of view or extent, and a
/// retina whose output fits the memory guard.
pub(super) fn build_camera<const N: usize>(c: &CameraDesc) -> R<Camera<N>> {
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
    Ok(Camera {
        position,
        orientation,
        projection: c.projection,
        cell: cell_unit / resolution[0] as f64,
        resolution: resolution.iter().map(|&r| r as usize).collect(),
    })
}
