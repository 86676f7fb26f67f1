//! Tessellations of (N−1)-simplices in R^N: the geometry ndtrace renders, and their
//! [`orientation`].

use crate::linalg::Vector;

pub mod orientation;

/// A mesh of (N−1)-simplices in R^N: vertex positions and, per simplex, its N vertex indices.
///
/// The order of a simplex's vertices fixes its orientation: its normal is the generalized cross
/// product of `x_1 − x_0 … x_{N−1} − x_0` (eq. 6). Generated closed shapes are oriented with
/// normals pointing outward.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh<const N: usize> {
    /// Vertex positions.
    pub vertices: Vec<Vector<N>>,
    /// Vertex indices of each simplex.
    pub simplices: Vec<[u32; N]>,
}

impl<const N: usize> Mesh<N> {
    /// The N vertices of simplex `s`.
    #[inline]
    pub fn simplex_points(&self, s: usize) -> [Vector<N>; N] {
        let idx = &self.simplices[s];
        std::array::from_fn(|k| self.vertices[idx[k] as usize])
    }
}

/// Union–find with path halving: the root of `x`'s set.
pub(crate) fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        parent[x as usize] = parent[parent[x as usize] as usize];
        x = parent[x as usize];
    }
    x
}

pub mod edge_cache;
pub mod elevation;
pub mod features;
mod filing;
pub mod flat;
pub mod slice;
pub use edge_cache::EdgeCache;
pub use features::feature_edges;
