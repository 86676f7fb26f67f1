use super::*;
use crate::accel::tests::*;

#[test]
fn accel_build_is_deterministic() {
    fn check<const N: usize>() {
        let mut r = rng(4000 + N as u64);
        let s = soup::<N>(&mut r, 3000);
        let a = build_soup(&s, PAR_MIN);
        let b = build_soup(&s, PAR_MIN);
        assert!(a == b, "N={N}: two builds differ");
        // Maximal forking, and a one-thread pool, give the same tree.
        let c = build_soup(&s, 2);
        assert!(a == c, "N={N}: parallel build differs");
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let d = pool.install(|| build_soup(&s, 2));
        assert!(a == d, "N={N}: one-thread build differs");
        assert!(a.node_count() > 1 && a.memory_bytes() > 0);
    }
    for_each_dim!(check);
}

#[test]
fn accel_a_lazily_prepared_build_is_the_build_over_prepared_simplices() {
    fn check<const N: usize>() {
        let mut r = rng(4100 + N as u64);
        // Ids that are not input positions, as a scene's global ids after skipped simplices.
        let s: Vec<([[f64; N]; N], u32)> = (soup::<N>(&mut r, 3000).into_iter().enumerate())
            .map(|(k, (p, _))| (p, 3 + 5 * k as u32))
            .collect();
        let want = build_soup(&s, PAR_MIN);
        let kept: Vec<&([[f64; N]; N], u32)> = s
            .iter()
            .filter(|(p, _)| PreparedSimplex::new(p).is_some())
            .collect();
        let ids: Vec<u32> = kept.iter().map(|(_, id)| *id).collect();
        let bounds = kept.iter().map(|(p, _)| simplex_bounds(p)).collect();
        let s = s.clone();
        let lazy = Bvh::build_lazily(ids, bounds, move |id| {
            PreparedSimplex::new(&s[(id as usize - 3) / 5].0).unwrap()
        });
        assert!(lazy == want, "N={N}: the lazy build differs");
        assert!(want.len() == kept.len() && want.node_count() > 1);
    }
    for_each_dim!(check);
}

#[test]
fn accel_from_mesh_matches_from_simplices() {
    let cells = cube_boundary::<4>(2);
    let mut mesh = Mesh::<4>::default();
    for c in &cells {
        let base = mesh.vertices.len() as u32;
        mesh.vertices.extend(c.iter().map(|v| v.map(|x| x as f64)));
        mesh.simplices
            .push(std::array::from_fn(|k| base + k as u32));
    }
    // One degenerate simplex (repeated vertex) is skipped; ids stay the simplex indices.
    mesh.simplices.push([0, 0, 1, 2]);
    let points: Vec<[[f64; 4]; 4]> = cells
        .iter()
        .map(|c| c.map(|v| v.map(|x| x as f64)))
        .collect();
    let ids: Vec<u32> = (0..points.len() as u32).collect();
    let a = Bvh::from_mesh(&mesh);
    assert!(a == Bvh::from_simplices(&points, &ids));
    assert_eq!(a.len(), cells.len());
    let ray = Ray {
        origin: [1.0, 1.3, 0.7, -5.0],
        dir: [0.0, 0.0, 0.0, 1.0],
    };
    let h = a.closest_hit(&ray, 0.0, f64::INFINITY, |_| true).unwrap();
    assert!((h.t - 5.0).abs() < 1e-12 && (h.prim as usize) < cells.len());
}
