//! The N-D camera and its (N−1)-D retina (course notes, "N-dimensional Imaging").
//!
//! The orientation is an orthonormal N×N matrix whose columns are the retina axes
//! u_1 … u_{N−1} and then the viewing direction. The ray through retina point
//! (u_1, …, u_{N−1}) has direction `col_N + Σ u_k·col_k` (perspective, from the position) or
//! direction `col_N` from `position + Σ u_k·col_k` (orthographic).
//!
//! Cells are cubes of side s (`2·tan(fov/2)/R_1` at unit distance, or `2·extent/R_1`); cell
//! (i_1, …, i_{N−1}) is centred at `u_k = (i_k + ½ − R_k/2)·s`, except
//! `u_2 = (R_2/2 − i_2 − ½)·s` so that image rows go down. Retina arrays are stored in numpy
//! order `[i_{N−1}, …, i_2, i_1]`: the linear cell index is `i_1 + R_1·(i_2 + R_2·(i_3 + …))`.
//!
//! The course's own camera — focal point at `d_N` on the +x_N axis, focal length `f_N`,
//! looking down −x_N — is `position = d_N·e_N`, `orientation` with columns e_1 … e_{N−1}, −e_N,
//! and `fov = 2·atan(R_1·pixel / (2·f_N))` for a film of `R_1` cells of size `pixel`.

use crate::geometry::generalized_cross;
use crate::linalg::{add_scaled, dot, norm, scale, sub, Matrix, Vector};
use crate::ray::Ray;
use serde::{Deserialize, Serialize};

/// Perspective (pinhole) or orthographic projection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    /// Rays from the camera position through the retina; `fov` sets the cell size.
    #[default]
    Perspective,
    /// Parallel rays along the view direction; `extent` sets the cell size.
    Orthographic,
}

/// A camera ready to generate rays.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera<const N: usize> {
    /// Focal point (perspective) or centre of the image plane (orthographic).
    pub position: Vector<N>,
    /// Orthonormal; columns u_1 … u_{N−1}, then the viewing direction.
    pub orientation: Matrix<N>,
    /// Perspective or orthographic.
    pub projection: Projection,
    /// Side s of a retina cell (at unit distance for perspective).
    pub cell: f64,
    /// Cells along each retina axis, R_1 … R_{N−1}.
    pub resolution: Vec<usize>,
}

impl<const N: usize> Camera<N> {
    /// Column k of the orientation (0-based: u_1 is column 0, the view direction column N−1).
    #[inline]
    pub fn axis(&self, k: usize) -> Vector<N> {
        std::array::from_fn(|r| self.orientation[r][k])
    }

    /// Number of retina cells.
    pub fn cell_count(&self) -> usize {
        self.resolution.iter().product()
    }

    /// Retina shape in numpy order `[R_{N−1}, …, R_1]`.
    pub fn numpy_shape(&self) -> Vec<usize> {
        self.resolution.iter().rev().copied().collect()
    }

    /// Retina coordinates (u_1 … u_{N−1}) of the point at fractional position `f` inside cell
    /// `index` (f = ½ in every axis is the centre), written into `u[..N−1]`.
    #[inline]
    pub fn retina_point(&self, index: usize, f: &[f64], u: &mut [f64]) {
        let mut idx = [0; N];
        self.cell_index(index, &mut idx);
        self.cell_point(&idx, f, u);
    }

    /// The multi-index (i_1 … i_{N−1}) of cell `index` (i_1 varies fastest), into `idx[..N−1]`.
    #[inline]
    pub fn cell_index(&self, index: usize, idx: &mut [usize]) {
        let mut rest = index;
        for k in 0..N - 1 {
            let r = self.resolution[k];
            idx[k] = rest % r;
            rest /= r;
        }
    }

    /// Advances a multi-index of [`Camera::cell_index`] to the next cell.
    #[inline]
    pub fn next_cell(&self, idx: &mut [usize]) {
        for k in 0..N - 1 {
            idx[k] += 1;
            if idx[k] < self.resolution[k] {
                return;
            }
            idx[k] = 0;
        }
    }

    /// [`Camera::retina_point`] of the cell with multi-index `idx` (see [`Camera::cell_index`]).
    #[inline]
    pub fn cell_point(&self, idx: &[usize], f: &[f64], u: &mut [f64]) {
        // Through i64: one signed conversion instruction (the values are far below 2⁶³).
        for k in 0..N - 1 {
            let half = self.resolution[k] as i64 as f64 / 2.0;
            let i = idx[k] as i64 as f64;
            u[k] = if k == 1 {
                (half - i - f[k]) * self.cell
            } else {
                (i + f[k] - half) * self.cell
            };
        }
    }

    /// The ray through retina point `u` (u_1 … u_{N−1}).
    #[inline]
    pub fn ray(&self, u: &[f64]) -> Ray<N> {
        let mut offset = [0.0; N];
        for k in 0..N - 1 {
            offset = add_scaled(&offset, u[k], &self.axis(k));
        }
        self.ray_at(&offset)
    }

    /// The ray through the retina point whose offset from the retina's centre is `offset` =
    /// `Σ u_k·col_k`.
    #[inline]
    pub fn ray_at(&self, offset: &Vector<N>) -> Ray<N> {
        let view = self.axis(N - 1);
        match self.projection {
            Projection::Perspective => Ray {
                origin: self.position,
                dir: std::array::from_fn(|i| view[i] + offset[i]),
            },
            Projection::Orthographic => Ray {
                origin: std::array::from_fn(|i| self.position[i] + offset[i]),
                dir: view,
            },
        }
    }

    /// Depth of a hit at ray parameter t: Euclidean distance from the camera position
    /// (perspective) or from the image plane along the view direction (orthographic), for a ray
    /// whose direction has length `dir_len`.
    #[inline]
    pub fn depth(&self, t: f64, dir_len: f64) -> f64 {
        match self.projection {
            Projection::Perspective => t * dir_len,
            Projection::Orthographic => t,
        }
    }

    /// The vector from a point toward the eye, used for back-face culling and lighting.
    #[inline]
    pub fn toward_eye(&self, x: &Vector<N>) -> Vector<N> {
        match self.projection {
            Projection::Perspective => sub(&self.position, x),
            Projection::Orthographic => scale(&self.axis(N - 1), -1.0),
        }
    }
}

/// The rays through the centres of a camera's cells, from tables of their offset terms: the
/// same rays, bit for bit, as [`Camera::cell_point`] with f = ½ then [`Camera::ray`] give,
/// without their per-ray index conversions and products.
pub struct CentreRays<'a, const N: usize> {
    cam: &'a Camera<N>,
    /// `terms[start[k] + i]` = u_k·col_k for index i along axis k, with `0 + ` in front for
    /// k = 0 (the first step of [`Camera::ray`]'s sum).
    terms: Vec<Vector<N>>,
    start: [usize; N],
}

impl<'a, const N: usize> CentreRays<'a, N> {
    /// The tables of `cam` (one vector per cell along each axis).
    pub fn new(cam: &'a Camera<N>) -> Self {
        let centre = [0.5; N];
        let mut idx = [0; N];
        let mut u = [0.0; N];
        let mut terms = Vec::new();
        let mut start = [0; N];
        for k in 0..N - 1 {
            start[k] = terms.len();
            for i in 0..cam.resolution[k] {
                idx[k] = i;
                cam.cell_point(&idx[..N - 1], &centre[..N - 1], &mut u[..N - 1]);
                terms.push(if k == 0 {
                    add_scaled(&[0.0; N], u[k], &cam.axis(k))
                } else {
                    scale(&cam.axis(k), u[k])
                });
            }
        }
        CentreRays { cam, terms, start }
    }

    /// The ray through the centre of the cell with multi-index `idx` (see
    /// [`Camera::cell_index`]).
    #[inline(always)]
    pub fn ray(&self, idx: &[usize]) -> Ray<N> {
        let mut offset = self.terms[idx[0]];
        for k in 1..N - 1 {
            let t = &self.terms[self.start[k] + idx[k]];
            for j in 0..N {
                offset[j] += t[j];
            }
        }
        self.cam.ray_at(&offset)
    }
}

/// The orientation of a `look_at` camera: view = look_at − position; `up` fixes u_2 … u_{N−1}
/// in order, each orthonormalized against the view direction and the axes before it; u_1
/// completes the frame so that det[u_1 … u_{N−1}, −view] = +1 (for N = 3: u_1 right, u_2 up,
/// and the matrix [right, up, view] has determinant −1).
///
/// Returns the index of the offending `up` vector (or `None` for a zero view direction) when
/// the vectors are not independent.
pub fn look_at_orientation<const N: usize>(
    position: &Vector<N>,
    look_at: &Vector<N>,
    up: &[Vector<N>],
) -> Result<Matrix<N>, Option<usize>> {
    let v = sub(look_at, position);
    let lv = norm(&v);
    if !(lv > 0.0) {
        return Err(None);
    }
    let view = scale(&v, 1.0 / lv);
    let mut axes: Vec<Vector<N>> = vec![view];
    for (k, u) in up.iter().enumerate() {
        let mut w = *u;
        for a in &axes {
            w = add_scaled(&w, -dot(&w, a), a);
        }
        let l = norm(&w);
        if !(l > 1e-9 * norm(u)) || !(l > 0.0) {
            return Err(Some(k));
        }
        axes.push(scale(&w, 1.0 / l));
    }
    // u_1 = (−1)^(N−1) · cross(u_2, …, u_{N−1}, −view): moving the cross product from the last
    // column to the first is a cyclic shift of N columns, of sign (−1)^(N−1).
    let mut edges: Vec<Vector<N>> = axes[1..].to_vec();
    edges.push(scale(&view, -1.0));
    let c = generalized_cross(&edges);
    let sign = if (N - 1).is_multiple_of(2) { 1.0 } else { -1.0 };
    let u1 = scale(&c, sign / norm(&c));
    let mut cols: Vec<Vector<N>> = vec![u1];
    cols.extend_from_slice(&axes[1..]);
    cols.push(view);
    Ok(std::array::from_fn(|r| std::array::from_fn(|c| cols[c][r])))
}

#[cfg(test)]
mod tests;
