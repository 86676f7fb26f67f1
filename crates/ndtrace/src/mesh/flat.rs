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
mod tests {
    use super::*;
    use crate::geometry::hyperplane;
    use crate::shapes;

    /// [`flat_pieces`] with the normals of eq. 6.
    fn pieces_of<const N: usize>(mesh: &Mesh<N>, min: usize) -> Vec<Vec<u32>> {
        let normal = |s: usize| Some(hyperplane(&mesh.simplex_points(s)).ok()?.normal);
        flat_pieces(mesh, normal, min)
    }

    #[test]
    fn the_facets_of_the_n_cube_are_its_flat_pieces() {
        fn check<const N: usize>() {
            let cube = shapes::hypercube::<N>();
            let pieces = pieces_of(&cube, 2);
            // 2N facets of (N−1)! simplices each, every simplex in one.
            let per: usize = (1..N).product();
            assert_eq!(pieces.len(), 2 * N, "N = {N}");
            assert!(pieces.iter().all(|p| p.len() == per), "N = {N}");
            let mut all: Vec<u32> = pieces.concat();
            all.sort_unstable();
            assert_eq!(all, (0..cube.simplices.len() as u32).collect::<Vec<_>>());
            // Each piece lies in one facet x_a = ±1.
            for p in &pieces {
                let v = &cube.vertices[cube.simplices[p[0] as usize][0] as usize];
                let facet = (0..N).find(|&a| {
                    p.iter().all(|&s| {
                        cube.simplices[s as usize]
                            .iter()
                            .all(|&w| cube.vertices[w as usize][a] == v[a])
                    })
                });
                assert!(facet.is_some(), "N = {N}: a piece spans two facets");
            }
            // Fewer than `min` simplices: no piece.
            assert!(pieces_of(&cube, per + 1).is_empty());
        }
        check::<3>();
        check::<4>();
        check::<5>();
        check::<6>();
        check::<7>();
    }

    #[test]
    fn curved_meshes_have_no_flat_pieces_and_bent_squares_split() {
        assert!(pieces_of(&shapes::sphere::<4>(2), 2).is_empty());
        // Two squares at a right angle, each two triangles: two pieces of two.
        let mesh = Mesh::<3> {
            vertices: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
            ],
            simplices: vec![[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]],
        };
        assert_eq!(pieces_of(&mesh, 2), vec![vec![0, 1], vec![2, 3]]);
        // Orientation does not matter.
        let mut flipped = mesh.clone();
        flipped.simplices[1].swap(0, 1);
        assert_eq!(pieces_of(&flipped, 2), vec![vec![0, 1], vec![2, 3]]);
        // Lifting one vertex of a square by more than COPLANAR bends it.
        let mut bent = mesh.clone();
        bent.vertices[3][2] = 1e-6;
        assert_eq!(pieces_of(&bent, 2), vec![vec![2, 3]]);
    }
}
