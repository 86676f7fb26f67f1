//! Colour by cell (`material.color_by = "cell"`): the flat cells of a mesh — the connected
//! simplices of one hyperplane ([`crate::mesh::flat::flat_pieces`]), such as the tesseract's
//! eight cubes or the 16-cell's tetrahedra — grouped by the direction of their hyperplane, so
//! that cells in parallel hyperplanes (a polytope's opposite cells, which a 4D eye outside it
//! never sees both of) share a colour and the cells in view all differ: Hollasch's colouring
//! that "greatly aids identifying sub-structures".

use crate::geometry::simplex_normal;
use crate::linalg::{norm, scale, Vector};
use crate::mesh::Mesh;

/// The cells of a mesh grouped by the direction of their hyperplane.
#[derive(Debug, Clone, PartialEq)]
pub struct CellClasses<const N: usize> {
    /// Per simplex, its class (`u32::MAX` for a degenerate simplex, in no cell).
    pub class: Vec<u32>,
    /// Per class, the unit normal of its hyperplanes (in the mesh's coordinates, the sign
    /// making its first component beyond 10⁻⁶ positive).
    pub normals: Vec<Vector<N>>,
    /// Per class, how many cells it has.
    pub cells: Vec<u32>,
}

/// Relative rounding of the normals that count as parallel.
const PARALLEL: f64 = 1e-6;

/// The flat cells of `mesh` grouped by their hyperplanes' direction, classes numbered in the
/// order of their first simplex. A mesh whose ridges do not pair up (no flat pieces can be
/// found) has each simplex as a cell of its own.
pub fn cell_classes<const N: usize>(mesh: &Mesh<N>) -> CellClasses<N> {
    let unit = |s: usize| {
        let n = simplex_normal(&mesh.simplex_points(s));
        let l = norm(&n);
        (l > 0.0 && l.is_finite()).then(|| scale(&n, 1.0 / l))
    };
    let count = mesh.simplices.len();
    let mut pieces = crate::mesh::flat::flat_pieces(mesh, unit, 1);
    if pieces.is_empty() {
        pieces = (0..count as u32)
            .filter(|&s| unit(s as usize).is_some())
            .map(|s| vec![s])
            .collect();
    }
    // Pieces in the order of their first simplex, each keyed by its normal up to sign.
    pieces.sort_unstable_by_key(|p| p[0]);
    let key = |n: &Vector<N>| {
        let sign = n
            .iter()
            .find(|x| x.abs() > PARALLEL)
            .map_or(1.0, |x| x.signum());
        (sign, n.map(|x| (sign * x / PARALLEL).round() as i64))
    };
    let mut keys: Vec<[i64; N]> = Vec::new();
    let mut out = CellClasses {
        class: vec![u32::MAX; count],
        normals: Vec::new(),
        cells: Vec::new(),
    };
    for piece in &pieces {
        let Some(n) = unit(piece[0] as usize) else {
            continue;
        };
        let (sign, k) = key(&n);
        let class = match keys.iter().position(|x| *x == k) {
            Some(c) => c,
            None => {
                keys.push(k);
                out.normals.push(scale(&n, sign));
                out.cells.push(0);
                keys.len() - 1
            }
        };
        out.cells[class] += 1;
        for &s in piece {
            out.class[s as usize] = class as u32;
        }
    }
    // Classes in the order of the axes their normals are nearest (the tesseract's ±x, ±y, ±z,
    // ±w), so that the palette's colours go to them in that order.
    let mut order: Vec<usize> = (0..out.normals.len()).collect();
    order.sort_by(|&a, &b| order_key(&out.normals[a]).total_cmp(&order_key(&out.normals[b])));
    let mut rank = vec![0u32; order.len()];
    for (r, &c) in order.iter().enumerate() {
        rank[c] = r as u32;
    }
    for c in out.class.iter_mut().filter(|c| **c != u32::MAX) {
        *c = rank[*c as usize];
    }
    out.normals = order.iter().map(|&c| out.normals[c]).collect();
    out.cells = order.iter().map(|&c| out.cells[c]).collect();
    out
}

/// A unit normal's place in the order of the axes: the axis of its largest component, then
/// the normals nearer that axis first (stable for ties: the sort keeps their first-simplex
/// order).
fn order_key<const N: usize>(n: &Vector<N>) -> f64 {
    let (axis, big) = n.iter().enumerate().fold((0, 0.0f64), |(i, m), (k, x)| {
        if x.abs() > m + 1e-9 {
            (k, x.abs())
        } else {
            (i, m)
        }
    });
    axis as f64 + (1.0 - big)
}

#[cfg(test)]
mod tests;
