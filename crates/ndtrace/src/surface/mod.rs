//! Surfaces in R^4 rendered directly, without thickening: "bear hair" (course notes, Part
//! II(B), "4D surfaces and points": "Calculate the light that would be reflected from a surface
//! if you attached shiny circles and shrunk them to a point … Render surface projected to 3D
//! from 4D directly … Avoids volume rendering altogether").
//!
//! A triangulated 2-surface of R^4 is projected through the 4D camera into the 3D retina, where
//! it is a thin sheet `width` cells thick, and shaded by the limit of the lighting of its
//! circle-bundle thickening as the circles shrink to a point ([`tube`]). It is occluded by depth
//! against the traced scene and against itself, and may be transparent (`material.opacity`).
//!
//! The pieces: here, [`Surface`] (the triangles and their tangent planes, built with the
//! scene); `tube.rs`, the limit lighting's means over a tube; the drawing is the tracer's:
//! `render/surface.rs` (a surface point's colour) and `render/splat.rs` (projection into the
//! retina, fragments, their occlusion and blending).

pub mod tube;

#[cfg(test)]
mod tests;

pub use tube::{tube_diffuse, tube_specular};

use crate::linalg::{dot, norm, scale, sub, Matrix, Vector};

/// Default width of a surface's sheet in the retina, in cells.
pub const DEFAULT_WIDTH: f64 = 2.0;
/// Default least apparent thickness of a surface in a picture drawn at its own resolution,
/// picture pixels (a surface seen edge-on is a line this wide).
pub const DEFAULT_LINE_WIDTH: f64 = 1.5;
/// Largest least apparent thickness accepted, picture pixels.
pub const MAX_LINE_WIDTH: f64 = 64.0;
/// Largest sheet width accepted, in cells.
pub const MAX_WIDTH: f64 = 64.0;
/// Most layers of one cell blended (nearest first) where a surface overlaps itself.
pub const MAX_LAYERS: usize = 16;

/// A surface object's own part of a scene: its triangles (into the object's mesh vertices, in
/// world space) and how it is drawn.
#[derive(Debug, Clone)]
pub struct Surface<const N: usize> {
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
    /// Width of the sheet in the retina, in cells.
    pub width: f64,
    /// Least apparent thickness in a picture drawn at its own resolution, picture pixels.
    pub line_width: f64,
    /// Per-vertex tangent projectors (a smooth material): the area-weighted mean of the
    /// neighbouring triangles' projectors, interpolated barycentrically at a point.
    pub vertex_tangents: Option<Vec<Matrix<N>>>,
}

/// The orthogonal projector t₁t₁ᵀ + t₂t₂ᵀ onto the tangent plane of the triangle `a b c`
/// (t₁, t₂ orthonormal by Gram–Schmidt of its edges), and the triangle's area; `None` when the
/// triangle has no area (relative to its edges' lengths).
pub fn tangent_projector<const N: usize>(
    a: &Vector<N>,
    b: &Vector<N>,
    c: &Vector<N>,
) -> Option<(Matrix<N>, f64)> {
    let e1 = sub(b, a);
    let e2 = sub(c, a);
    let l1 = norm(&e1);
    let l2 = norm(&e2);
    if !(l1 > 0.0 && l2 > 0.0) {
        return None;
    }
    let t1 = scale(&e1, 1.0 / l1);
    let w = sub(&e2, &scale(&t1, dot(&t1, &e2)));
    let h = norm(&w);
    if !(h > 1e-12 * l2) {
        return None;
    }
    let t2 = scale(&w, 1.0 / h);
    let p = std::array::from_fn(|i| std::array::from_fn(|j| t1[i] * t1[j] + t2[i] * t2[j]));
    Some((p, 0.5 * l1 * h))
}

/// Per-vertex tangent projectors: the area-weighted mean of the projectors of the triangles
/// around each vertex (zero for a vertex no triangle with area uses).
pub fn vertex_tangents<const N: usize>(
    vertices: &[Vector<N>],
    triangles: &[[u32; 3]],
) -> Vec<Matrix<N>> {
    let mut sum = vec![[[0.0; N]; N]; vertices.len()];
    let mut weight = vec![0.0; vertices.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let Some((p, area)) = tangent_projector(&a, &b, &c) else {
            continue;
        };
        for &i in t {
            let s = &mut sum[i as usize];
            for r in 0..N {
                for k in 0..N {
                    s[r][k] += area * p[r][k];
                }
            }
            weight[i as usize] += area;
        }
    }
    for (s, w) in sum.iter_mut().zip(&weight) {
        if *w > 0.0 {
            for row in s.iter_mut() {
                for x in row.iter_mut() {
                    *x /= w;
                }
            }
        }
    }
    sum
}
