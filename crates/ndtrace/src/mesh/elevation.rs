//! 3D scalar fields as 4D elevation maps (course notes, Part II(B): "any volume-renderable 3D
//! scalar field … is indistinguishable mathematically from a 4D elevation map"): the graph
//! w = height·f(x, y, z) of a field sampled on a regular grid, tessellated into tetrahedra.
//!
//! Each grid cube is split into the six tetrahedra of its Kuhn (Freudenthal) triangulation, one
//! per permutation (a, b, c) of the axes: the path corner → +e_a → +e_b → +e_c. Neighbouring cubes
//! split their shared faces along the same diagonal, so the tetrahedra's projections to xyz tile
//! the box exactly (no gaps, no overlaps; course notes: "*carefully* subdivide a cubic lattice").
//! Every tetrahedron is ordered so that its projection has positive 3D orientation, which makes
//! the 4D normal of every lifted tetrahedron (eq. 6) point to +w: the terrain faces up.

use super::Mesh;
use crate::linalg::{norm, scale, Vector};
use rayon::prelude::*;

/// A 3D scalar field on a regular grid, indexed `[x, y, z]` in C order (z fastest).
#[derive(Debug, Clone, Copy)]
pub struct Field<'a> {
    /// Grid values, `shape[0]·shape[1]·shape[2]` of them; NaN marks missing data.
    pub values: &'a [f64],
    /// Grid points along x, y and z.
    pub shape: [usize; 3],
}

/// The box a field spans: `[x0, x1]`, `[y0, y1]`, `[z0, z1]`.
pub type Extent = [[f64; 2]; 3];

/// An elevation map ready to render: its mesh (in R^4), the field value at each of its vertices
/// and, per vertex, the index of its grid point.
#[derive(Debug, Clone)]
pub struct Elevation<const N: usize> {
    /// Vertices (x, y, z, height·f) and Kuhn tetrahedra (N = 4).
    pub mesh: Mesh<N>,
    /// The field value f at each vertex.
    pub values: Vec<f64>,
    /// The grid index (C order) of each vertex.
    pub grid: Vec<u32>,
    /// The box the grid spans.
    pub extent: Extent,
    /// Grid cubes left out because a corner is NaN.
    pub holes: usize,
}

/// The default extent of a grid of `shape` points: cubic voxels, the longest side spanning
/// [−1, 1], centred on the origin.
pub fn default_extent(shape: [usize; 3]) -> Extent {
    let longest = shape.iter().copied().max().unwrap_or(2).max(2);
    let h = 2.0 / (longest - 1) as f64;
    shape.map(|n| {
        let half = 0.5 * h * (n.max(1) - 1) as f64;
        [-half, half]
    })
}

/// Checks a field and an extent; errors say what is wrong (the caller adds where).
pub fn check(field: &Field<'_>, extent: Option<&Extent>, height: f64) -> Result<(), String> {
    let [nx, ny, nz] = field.shape;
    if field.shape.iter().any(|&n| n < 2) {
        return Err(format!(
            "a field needs at least 2 grid points along each axis, got shape ({nx}, {ny}, {nz})"
        ));
    }
    let count = nx
        .checked_mul(ny)
        .and_then(|c| c.checked_mul(nz))
        .filter(|&c| c < u32::MAX as usize)
        .ok_or_else(|| format!("a field of shape ({nx}, {ny}, {nz}) has too many grid points"))?;
    if field.values.len() != count {
        return Err(format!(
            "a field of shape ({nx}, {ny}, {nz}) needs {count} values, got {}",
            field.values.len()
        ));
    }
    if let Some(i) = field.values.iter().position(|v| v.is_infinite()) {
        let (x, y, z) = (i / (ny * nz), i / nz % ny, i % nz);
        return Err(format!(
            "field[{x}, {y}, {z}] is {} (only finite values, or NaN for missing data)",
            field.values[i]
        ));
    }
    if !height.is_finite() || height == 0.0 {
        return Err(format!(
            "height must be a finite non-zero number, got {height}"
        ));
    }
    // w = height·f must be finite too.
    if let Some(i) = field
        .values
        .iter()
        .position(|&v| v.is_finite() && !(height * v).is_finite())
    {
        let (x, y, z) = (i / (ny * nz), i / nz % ny, i % nz);
        return Err(format!(
            "height {height} × field[{x}, {y}, {z}] = {:e} overflows float64 (the elevation w = height·f must be finite)",
            field.values[i]
        ));
    }
    if let Some(e) = extent {
        for (axis, [lo, hi]) in ["x", "y", "z"].iter().zip(e) {
            if !(lo.is_finite() && hi.is_finite() && hi > lo) {
                return Err(format!(
                    "the {axis} range [{lo}, {hi}] must be finite with {axis}1 > {axis}0"
                ));
            }
        }
    }
    Ok(())
}

/// The elevation map of `field` over `extent` (default [`default_extent`]): vertex (x, y, z, w)
/// with w = height·f exactly, six Kuhn tetrahedra per grid cube whose eight corners are finite
/// (cubes with a NaN corner are holes; vertices no kept cube uses are dropped). Errors name the
/// problem; a field without a single finite cube is an error. N must be 4.
pub fn elevation_map<const N: usize>(
    field: &Field<'_>,
    extent: Option<&Extent>,
    height: f64,
) -> Result<Elevation<N>, String> {
    if N != 4 {
        return Err(format!(
            "an elevation map of a 3D field lives in R^4: it needs dim = 4, got dim = {N}"
        ));
    }
    let e = elevation_map_4d(field, extent, height)?;
    Ok(crate::dim::same(e).unwrap_or_else(|_| unreachable!("N = 4")))
}

/// [`elevation_map`] in R^4, compiled once.
fn elevation_map_4d(
    field: &Field<'_>,
    extent: Option<&Extent>,
    height: f64,
) -> Result<Elevation<4>, String> {
    const N: usize = 4;
    check(field, extent, height)?;
    let [nx, ny, nz] = field.shape;
    let extent = extent
        .copied()
        .unwrap_or_else(|| default_extent(field.shape));
    let f = field.values;
    let at = |x: usize, y: usize, z: usize| (x * ny + y) * nz + z;
    // Which cubes are kept (all eight corners finite), by cube index.
    let cubes = (nx - 1) * (ny - 1) * (nz - 1);
    let keep: Vec<bool> = (0..cubes)
        .into_par_iter()
        .map(|c| {
            let (x, y, z) = (
                c / ((ny - 1) * (nz - 1)),
                c / (nz - 1) % (ny - 1),
                c % (nz - 1),
            );
            CORNERS
                .iter()
                .all(|&[dx, dy, dz]| !f[at(x + dx, y + dy, z + dz)].is_nan())
        })
        .collect();
    let kept = keep.iter().filter(|&&k| k).count();
    if kept == 0 {
        return Err(format!(
            "the field of shape ({nx}, {ny}, {nz}) has no grid cube with 8 finite corners (NaN marks missing data)"
        ));
    }
    // Vertex numbering: every grid point when nothing is missing, else the used ones in order.
    let used: Option<Vec<u32>> = (kept < cubes || f.iter().any(|v| v.is_nan())).then(|| {
        let mut used = vec![false; f.len()];
        for (c, _) in keep.iter().enumerate().filter(|(_, &k)| k) {
            let (x, y, z) = (
                c / ((ny - 1) * (nz - 1)),
                c / (nz - 1) % (ny - 1),
                c % (nz - 1),
            );
            for &[dx, dy, dz] in &CORNERS {
                used[at(x + dx, y + dy, z + dz)] = true;
            }
        }
        let mut next = 0u32;
        used.iter()
            .map(|&u| {
                if u {
                    next += 1;
                    next - 1
                } else {
                    u32::MAX
                }
            })
            .collect()
    });
    let grid: Vec<u32> = match &used {
        Some(number) => (0..f.len() as u32)
            .filter(|&g| number[g as usize] != u32::MAX)
            .collect(),
        None => (0..f.len() as u32).collect(),
    };
    let coord = |axis: usize, i: usize, n: usize| {
        let [lo, hi] = extent[axis];
        // Exact at both ends.
        if i + 1 == n {
            hi
        } else {
            lo + (hi - lo) * (i as f64 / (n - 1) as f64)
        }
    };
    let vertices: Vec<Vector<N>> = grid
        .par_iter()
        .map(|&g| {
            let g = g as usize;
            let (x, y, z) = (g / (ny * nz), g / nz % ny, g % nz);
            let p = [
                coord(0, x, nx),
                coord(1, y, ny),
                coord(2, z, nz),
                height * f[g],
            ];
            std::array::from_fn(|k| p[k])
        })
        .collect();
    let values: Vec<f64> = grid.par_iter().map(|&g| f[g as usize]).collect();
    let vertex = |g: usize| match &used {
        Some(number) => number[g],
        None => g as u32,
    };
    let kept_cubes: Vec<usize> = (0..cubes).filter(|&c| keep[c]).collect();
    let simplices: Vec<[u32; N]> = kept_cubes
        .par_iter()
        .flat_map_iter(|&c| {
            let (x, y, z) = (
                c / ((ny - 1) * (nz - 1)),
                c / (nz - 1) % (ny - 1),
                c % (nz - 1),
            );
            KUHN.iter().map(move |path| {
                std::array::from_fn(|k| {
                    let [dx, dy, dz] = path[k.min(3)];
                    vertex(at(x + dx, y + dy, z + dz))
                })
            })
        })
        .collect();
    Ok(Elevation {
        mesh: Mesh {
            vertices,
            simplices,
        },
        values,
        grid,
        extent,
        holes: cubes - kept,
    })
}

/// Unit normals of the smooth graph at the vertices of `elev`: ∝ (−height·∇f, 1), the 4D normal
/// of w = height·f(x, y, z) (course notes, "Normals and the Cross-Product": the gradient of
/// F = w − height·f), with ∇f by central differences in the box's units (one-sided at the
/// grid's border and next to missing values), exact for fields linear along each axis.
pub fn gradient_normals<const N: usize>(
    field: &Field<'_>,
    elev: &Elevation<N>,
    height: f64,
) -> Vec<Vector<N>> {
    let elev = crate::dim::same_ref::<_, Elevation<4>>(elev).expect("an elevation map is 4D");
    crate::dim::same(gradient_normals_4d(field, elev, height))
        .unwrap_or_else(|_| unreachable!("N = 4"))
}

/// [`gradient_normals`] in R^4, compiled once.
fn gradient_normals_4d(field: &Field<'_>, elev: &Elevation<4>, height: f64) -> Vec<Vector<4>> {
    const N: usize = 4;
    let [nx, ny, nz] = field.shape;
    let f = field.values;
    let strides = [ny * nz, nz, 1];
    let steps: [f64; 3] = std::array::from_fn(|a| {
        (elev.extent[a][1] - elev.extent[a][0]) / (field.shape[a] - 1) as f64
    });
    elev.grid
        .par_iter()
        .map(|&g| {
            let g = g as usize;
            let idx = [g / (ny * nz), g / nz % ny, g % nz];
            let grad: [f64; 3] = std::array::from_fn(|a| {
                let n = [nx, ny, nz][a];
                let s = strides[a];
                let lo = (idx[a] > 0 && !f[g - s].is_nan()).then(|| f[g - s]);
                let hi = (idx[a] + 1 < n && !f[g + s].is_nan()).then(|| f[g + s]);
                match (lo, hi) {
                    (Some(l), Some(h)) => (h - l) / (2.0 * steps[a]),
                    (None, Some(h)) => (h - f[g]) / steps[a],
                    (Some(l), None) => (f[g] - l) / steps[a],
                    (None, None) => 0.0,
                }
            });
            let n4 = [-height * grad[0], -height * grad[1], -height * grad[2], 1.0];
            let v: Vector<N> = std::array::from_fn(|k| n4[k]);
            scale(&v, 1.0 / norm(&v))
        })
        .collect()
}

/// The eight corners of a grid cube, offsets along x, y, z.
const CORNERS: [[usize; 3]; 8] = [
    [0, 0, 0],
    [0, 0, 1],
    [0, 1, 0],
    [0, 1, 1],
    [1, 0, 0],
    [1, 0, 1],
    [1, 1, 0],
    [1, 1, 1],
];

/// The Kuhn tetrahedra of the unit cube: for each permutation (a, b, c) of the axes, the corners
/// 0, e_a, e_a + e_b, e_a + e_b + e_c, with the last two swapped for odd permutations so that
/// every tetrahedron's edge determinant is +1 (positive 3D orientation).
const KUHN: [[[usize; 3]; 4]; 6] = {
    const fn e(a: usize) -> [usize; 3] {
        let mut v = [0; 3];
        v[a] = 1;
        v
    }
    const fn plus(u: [usize; 3], v: [usize; 3]) -> [usize; 3] {
        [u[0] + v[0], u[1] + v[1], u[2] + v[2]]
    }
    const PERMS: [([usize; 3], bool); 6] = [
        ([0, 1, 2], false),
        ([1, 2, 0], false),
        ([2, 0, 1], false),
        ([0, 2, 1], true),
        ([2, 1, 0], true),
        ([1, 0, 2], true),
    ];
    let mut out = [[[0; 3]; 4]; 6];
    let mut i = 0;
    while i < 6 {
        let ([a, b, c], odd) = PERMS[i];
        let p1 = e(a);
        let p2 = plus(p1, e(b));
        let p3 = plus(p2, e(c));
        out[i] = if odd {
            [[0, 0, 0], p1, p3, p2]
        } else {
            [[0, 0, 0], p1, p2, p3]
        };
        i += 1;
    }
    out
};

#[cfg(test)]
mod tests;
