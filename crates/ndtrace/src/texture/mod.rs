//! Colour that varies over an object: the course's cues for 3D scalar fields shown as 4D
//! elevation maps (Part II(B), "Multiple cues … color, slices, and isosurfaces" and "Cubic
//! Lattice Grids"), for any simplex mesh:
//! - a **colormap** of a per-vertex scalar, interpolated barycentrically at the hit;
//! - **isolines** ("isosurface markings"): bands where the interpolated scalar crosses given
//!   values, of a constant width in world units along the object;
//! - a **lattice**: the planes x_k = m·spacing (k = 0, 1, 2, in the object's own coordinates, so
//!   that the grid moves with the object), drawn as bands of a given width — a cubic lattice
//!   whose walls cut every visible part of the retina's volume image in lines.
//!
//! - colour **by structure** (`material.color_by`): each flat cell a colour of a qualitative
//!   [`palette`] ([`cells`]), or the hit's N-D depth through a colormap.
//!
//! The colour C at a hit replaces the material's colour in the lighting sum of
//! [`crate::render::shade_hit`].

pub mod cells;
pub mod colormap;
pub mod palette;

use crate::linalg::Rgb;
use crate::linalg::{add, dot, mat_vec, solve_block, sub, Matrix, Vector};
use crate::mesh::Mesh;
pub use cells::CellClasses;
pub use colormap::Colormap;
pub use palette::Palette;

/// Bands where a per-vertex scalar crosses given values.
#[derive(Debug, Clone, PartialEq)]
pub struct Isolines {
    /// The values marked.
    pub values: Vec<f64>,
    /// Band width in world units, measured along the object.
    pub width: f64,
    /// Band colour.
    pub color: Rgb,
}

/// A cubic lattice of planes in the object's own coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Lattice {
    /// Distance between neighbouring planes.
    pub spacing: f64,
    /// Band width, in the object's units.
    pub width: f64,
    /// Band colour.
    pub color: Rgb,
}

/// A material's texture before it meets its object (the values and the transform).
#[derive(Debug, Clone, PartialEq)]
pub struct TextureSpec {
    /// The colormap and, when given, the range mapped onto it: of the values, or with
    /// `by_depth` of the hit's depth.
    pub colormap: Option<(Colormap, Option<[f64; 2]>)>,
    /// Isosurface markings.
    pub isolines: Option<Isolines>,
    /// The lattice.
    pub lattice: Option<Lattice>,
    /// `color_by = "cell"`: the palette the cells' classes take their colours from.
    pub by_cell: Option<Palette>,
    /// `color_by = "depth"`: the colormap maps the hit's N-D depth, not the values.
    pub by_depth: bool,
}

impl TextureSpec {
    /// Whether the spec needs per-vertex values.
    pub fn needs_values(&self) -> bool {
        (self.colormap.is_some() && !self.by_depth) || self.isolines.is_some()
    }
}

/// Per simplex, the colour of its cell (`color_by = "cell"`).
#[derive(Debug, Clone)]
pub struct CellColors<const N: usize> {
    /// The cells' classes (by the direction of their hyperplane, in the object's own space).
    pub classes: CellClasses<N>,
    /// Per class, its colour (the palette's colour of the class's index).
    pub colors: Vec<Rgb>,
}

/// The texture of one object.
#[derive(Debug, Clone)]
pub struct Texture<const N: usize> {
    /// One scalar per mesh vertex (needed by the colormap and the isolines).
    pub values: Option<Vec<f64>>,
    /// The colormap and the value range mapped onto it.
    pub colormap: Option<(Colormap, [f64; 2])>,
    /// Isosurface markings.
    pub isolines: Option<Isolines>,
    /// The lattice.
    pub lattice: Option<Lattice>,
    /// World space → the object's own space (the inverse of its transform), for the lattice.
    pub to_object: (Matrix<N>, Vector<N>),
    /// `color_by = "cell"`: each simplex the colour of its cell.
    pub cells: Option<CellColors<N>>,
    /// `color_by = "depth"`: the colormap and the depth range mapped onto it.
    pub depth: Option<(Colormap, [f64; 2])>,
}

impl<const N: usize> Texture<N> {
    /// The colour C at the point `x` (world space) of simplex `local` of `mesh`, with barycentric
    /// coordinates `bary` and N-D depth `depth` (used by `color_by = "depth"` only); `base` is
    /// the material's colour.
    pub fn color(
        &self,
        base: &Rgb,
        mesh: &Mesh<N>,
        local: usize,
        bary: &[f64; N],
        x: &Vector<N>,
        depth: f64,
    ) -> Rgb {
        let idx = &mesh.simplices[local];
        let value = |vals: &[f64]| {
            let mut v = 0.0;
            for k in 0..N {
                v += bary[k] * vals[idx[k] as usize];
            }
            v
        };
        let mut c = *base;
        if let Some(cells) = &self.cells {
            if let Some(k) = cells.colors.get(cells.classes.class[local] as usize) {
                c = *k;
            }
        }
        if let Some((map, [lo, hi])) = &self.depth {
            c = map.at((depth - lo) / (hi - lo));
        }
        if let (Some(vals), Some((map, [lo, hi]))) = (&self.values, &self.colormap) {
            c = map.at((value(vals) - lo) / (hi - lo));
        }
        if let (Some(vals), Some(iso)) = (&self.values, &self.isolines) {
            let v = value(vals);
            let g = value_gradient_norm(mesh, local, vals);
            // |v − c| / |∇v| is the distance along the simplex to the level set v = c.
            if g > 0.0
                && iso
                    .values
                    .iter()
                    .any(|&level| (v - level).abs() <= 0.5 * iso.width * g)
            {
                c = iso.color;
            }
        }
        if let Some(lat) = &self.lattice {
            let p = add(&mat_vec(&self.to_object.0, x), &self.to_object.1);
            let on = (0..N.min(3)).any(|k| {
                let u = p[k] / lat.spacing;
                (u - u.round()).abs() * lat.spacing <= 0.5 * lat.width
            });
            if on {
                c = lat.color;
            }
        }
        c
    }
}

/// |∇v| of the scalar `vals` interpolated linearly over simplex `local` of `mesh`, the gradient
/// taken within the simplex's hyperplane: with edges e_k = x_k − x_0 and differences
/// δ_k = v_k − v_0, the gradient g = Σ a_k e_k solves (EᵀE)·a = δ, and |g|² = δ·a.
/// 0 for a degenerate simplex.
pub fn value_gradient_norm<const N: usize>(mesh: &Mesh<N>, local: usize, vals: &[f64]) -> f64 {
    let p = mesh.simplex_points(local);
    let idx = &mesh.simplices[local];
    let m = N - 1;
    let e: [Vector<N>; N] = std::array::from_fn(|k| {
        if k < m {
            sub(&p[k + 1], &p[0])
        } else {
            [0.0; N]
        }
    });
    let mut gram: Matrix<N> = [[0.0; N]; N];
    let mut delta: Vector<N> = [0.0; N];
    for i in 0..m {
        for j in 0..m {
            gram[i][j] = dot(&e[i], &e[j]);
        }
        delta[i] = vals[idx[i + 1] as usize] - vals[idx[0] as usize];
    }
    match solve_block(gram, delta, m) {
        Some(a) => (0..m).map(|i| delta[i] * a[i]).sum::<f64>().max(0.0).sqrt(),
        None => 0.0,
    }
}

#[cfg(test)]
mod tests;
