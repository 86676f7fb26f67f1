//! Flat pieces of a mesh: simplices that share ridges and lie in one hyperplane, such as the
//! (N−1)! Kuhn simplices of a facet of the N-cube. The tracer holds each such piece as one flat
//! cell ([`crate::accel::FlatCell`]), which checks the piece itself before relying on it.

use super::orientation::ridges;
use super::{find, Mesh};
use crate::linalg::{dot, sub, Vector};
use rayon::prelude::*;

/// Relative distance (to the simplex's longest edge) within which a neighbour's vertices count
/// as lying in a simplex's hyperplane.
const COPLANAR: f64 = 1e-9;

/// The flat pieces of `mesh` with at least `min` simplices: sets of simplices connected through
/// shared ridges, each neighbour's vertices within `COPLANAR` (10⁻⁹) times the longest edge of
/// the hyperplane (eq. 1) of the simplex it shares a ridge with. `normal(s)` is the unit normal of simplex s (eq. 6), or
/// `None` for a degenerate one, which belongs to no piece. Each piece lists its simplices in
/// increasing order; the pieces come in the order of their first simplex. A mesh with a ridge
/// of more than two simplices has no pieces.
pub fn flat_pieces<const N: usize>(
    mesh: &Mesh<N>,
    normal: impl Fn(usize) -> Option<Vector<N>> + Sync,
    min: usize,
) -> Vec<Vec<u32>> {
    let count = mesh.simplices.len();
    if count < min.max(2) {
        return Vec::new();
    }
    // Per simplex: its normal and longest edge (None when degenerate).
    let planes: Vec<Option<(Vector<N>, f64)>> = (0..count)
        .into_par_iter()
        .map(|s| {
            let n = normal(s)?;
            let p = mesh.simplex_points(s);
            let mut edge: f64 = 0.0;
            for a in 0..N {
                for b in a + 1..N {
                    let e = sub(&p[a], &p[b]);
                    edge = edge.max(dot(&e, &e).sqrt());
                }
            }
            Some((n, edge))
        })
        .collect();
    // A cheap screen first: a piece of `min` simplices has `min` normals equal up to sign and
    // rounding (keyed to 10⁻⁶, the sign making the first component beyond 0.1 positive; a
    // piece split by the rounding of its keys is only missed).
    let key = |n: &Vector<N>| {
        let sign = n.iter().find(|x| x.abs() > 0.1).map_or(1.0, |x| x.signum());
        n.map(|x| (sign * x * 1e6).round() as i64)
    };
    let mut keys: Vec<[i64; N]> = planes
        .par_iter()
        .filter_map(|p| p.as_ref().map(|(n, _)| key(n)))
        .collect();
    keys.par_sort_unstable();
    if !keys.chunk_by(|a, b| a == b).any(|run| run.len() >= min) {
        return Vec::new();
    }
    drop(keys);
    let Ok(r) = ridges(mesh) else {
        return Vec::new();
    };
    let in_plane_of = |a: u32, b: u32| match (&planes[a as usize], &planes[b as usize]) {
        (Some((n, edge)), Some(_)) => {
            let x0 = &mesh.vertices[mesh.simplices[a as usize][0] as usize];
            mesh.simplices[b as usize]
                .iter()
                .all(|&v| dot(n, &sub(&mesh.vertices[v as usize], x0)).abs() <= COPLANAR * edge)
        }
        _ => false,
    };
    let mut parent: Vec<u32> = (0..count as u32).collect();
    for &(a, b, _) in &r.pairs {
        if in_plane_of(a, b) && in_plane_of(b, a) {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    let mut members: Vec<(u32, u32)> = (0..count as u32)
        .filter(|&s| planes[s as usize].is_some())
        .map(|s| (find(&mut parent, s), s))
        .collect();
    members.sort_unstable();
    members
        .chunk_by(|a, b| a.0 == b.0)
        .filter(|run| run.len() >= min)
        .map(|run| run.iter().map(|&(_, s)| s).collect())
        .collect()
}

#[cfg(test)]
mod tests;
