use super::*;
use crate::shapes;

#[test]
fn the_tesseracts_eight_cubes_fall_in_four_parallel_pairs() {
    let mesh = shapes::hypercube::<4>();
    let c = cell_classes(&mesh);
    assert_eq!(c.normals.len(), 4);
    assert_eq!(c.cells, vec![2; 4]);
    // Every simplex is in a class, and each class's normal is an axis.
    assert!(c.class.iter().all(|&k| k < 4));
    // In the axes' order: ±x, ±y, ±z, ±w.
    let axes: Vec<usize> = c
        .normals
        .iter()
        .map(|n| {
            n.iter()
                .position(|x| (x.abs() - 1.0).abs() < 1e-12)
                .unwrap()
        })
        .collect();
    assert_eq!(axes, vec![0, 1, 2, 3]);
    // The 6 simplices of one cube share a class; 6·8 = 48 simplices in all.
    for k in 0..4 {
        assert_eq!(c.class.iter().filter(|&&x| x == k).count(), 12);
    }
}

#[test]
fn the_16_cell_has_eight_directions_and_the_simplex_five() {
    let c = cell_classes(&shapes::cross_polytope::<4>());
    assert_eq!((c.normals.len(), c.cells.iter().sum::<u32>()), (8, 16));
    let c = cell_classes(&shapes::simplex_boundary::<4>());
    assert_eq!((c.normals.len(), c.cells.iter().sum::<u32>()), (5, 5));
    let c = cell_classes(&shapes::hypercube::<5>());
    assert_eq!((c.normals.len(), c.cells.iter().sum::<u32>()), (5, 10));
}
