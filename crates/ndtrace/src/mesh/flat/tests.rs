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
