use super::*;
use crate::linalg::{add_scaled, norm};
use crate::testutil::for_each_dim;
use crate::testutil::{random_vector, rng};

#[test]
fn colormaps_are_matplotlibs_tables_in_linear_rgb() {
    let v = colormap::get("viridis").unwrap();
    assert_eq!(v.table.len(), 256);
    // matplotlib's viridis starts at (0.267004, 0.004874, 0.329415) and ends at
    // (0.993248, 0.906157, 0.143936), sRGB.
    let lin = |x: f64| ((x + 0.055) / 1.055f64).powf(2.4);
    assert!((v.at(0.0)[0] - lin(0.267004)).abs() < 1e-6);
    assert!((v.at(0.0)[1] - 0.004874 / 12.92).abs() < 1e-7);
    assert!((v.at(1.0)[1] - lin(0.906157)).abs() < 1e-6);
    // Interpolated between entries, clamped outside [0, 1].
    let mid: [f64; 3] = std::array::from_fn(|c| 0.5 * (v.table[0][c] + v.table[1][c]));
    assert!(v
        .at(0.5 / 255.0)
        .iter()
        .zip(&mid)
        .all(|(a, b)| (a - b).abs() < 1e-12));
    assert_eq!(v.at(-3.0), v.at(0.0));
    assert_eq!(v.at(7.0), v.at(1.0));
    let r = colormap::get("viridis_r").unwrap();
    assert_eq!(r.at(0.0), v.at(1.0));
    assert!(colormap::get("no_such_map").is_none());
    for name in [
        "plasma", "inferno", "magma", "cividis", "turbo", "terrain", "gray", "coolwarm",
    ] {
        assert!(colormap::names().contains(&name), "{name}");
    }
    // gray is the identity in sRGB.
    let g = colormap::get("gray").unwrap();
    assert!((g.at(1.0)[0] - 1.0).abs() < 1e-9 && g.at(0.0)[0].abs() < 1e-12);
}

#[test]
fn the_value_gradient_is_the_steepest_slope_along_the_simplex() {
    fn check<const N: usize>() {
        let mut r = rng(N as u64);
        for _ in 0..20 {
            let mesh = Mesh::<N> {
                vertices: (0..N).map(|_| random_vector(&mut r, 1.0)).collect(),
                simplices: vec![std::array::from_fn(|k| k as u32)],
            };
            let vals: Vec<f64> = (0..N).map(|_| random_vector::<1>(&mut r, 1.0)[0]).collect();
            let g = value_gradient_norm(&mesh, 0, &vals);
            // Independently: the linear function extended to R^N constant along the normal n
            // (eq. 6) has gradient G with e_k·G = δ_k and n·G = 0, a full N × N system.
            let p = mesh.simplex_points(0);
            let edges: Vec<_> = (1..N).map(|k| sub(&p[k], &p[0])).collect();
            let n = crate::geometry::generalized_cross(&edges);
            let mut a = [[0.0; N]; N];
            let mut rhs = [0.0; N];
            for k in 0..N - 1 {
                a[k] = edges[k];
                rhs[k] = vals[k + 1] - vals[0];
            }
            a[N - 1] = n;
            let big = crate::linalg::solve_block(a, rhs, N).unwrap();
            assert!(
                (norm(&big) - g).abs() <= 1e-9 * g,
                "N = {N}: {} vs {g}",
                norm(&big)
            );
            // And no direction within the simplex is steeper.
            for _ in 0..2000 {
                let c = random_vector::<N>(&mut r, 1.0);
                let mut d = [0.0; N];
                let mut dv = 0.0;
                for k in 1..N {
                    d = add_scaled(&d, c[k], &edges[k - 1]);
                    dv += c[k] * (vals[k] - vals[0]);
                }
                assert!(dv.abs() / norm(&d) <= g * (1.0 + 1e-9), "N = {N}");
            }
        }
    }
    for_each_dim!(check);
}

#[test]
fn isolines_and_the_lattice_fall_where_they_should() {
    // One tetrahedron of R^4 in the hyperplane w = 0 with value v = x.
    let mesh = Mesh::<4> {
        vertices: vec![
            [0.0; 4],
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        simplices: vec![[0, 1, 2, 3]],
    };
    let base = [0.5, 0.5, 0.5];
    let ident = (crate::linalg::identity::<4>(), [0.0; 4]);
    let t = Texture::<4> {
        values: Some(vec![0.0, 1.0, 0.0, 0.0]),
        colormap: None,
        isolines: Some(Isolines {
            values: vec![0.3],
            width: 0.1,
            color: [1.0, 0.0, 0.0],
        }),
        lattice: None,
        to_object: ident,
        cells: None,
        depth: None,
    };
    let at = |t: &Texture<4>, x: f64, y: f64, z: f64| {
        let bary = [1.0 - x - y - z, x, y, z];
        t.color(&base, &mesh, 0, &bary, &[x, y, z, 0.0], 0.0)
    };
    assert_eq!(at(&t, 0.3, 0.1, 0.1), [1.0, 0.0, 0.0]);
    assert_eq!(at(&t, 0.34, 0.1, 0.1), [1.0, 0.0, 0.0]);
    assert_eq!(at(&t, 0.36, 0.1, 0.1), base);
    assert_eq!(at(&t, 0.2, 0.1, 0.1), base);
    // Doubling the scalar halves the band's width in value but not along the object.
    let t2 = Texture {
        values: Some(vec![0.0, 2.0, 0.0, 0.0]),
        isolines: Some(Isolines {
            values: vec![0.6],
            ..t.isolines.clone().unwrap()
        }),
        ..t.clone()
    };
    assert_eq!(at(&t2, 0.34, 0.1, 0.1), [1.0, 0.0, 0.0]);
    assert_eq!(at(&t2, 0.36, 0.1, 0.1), base);
    // A lattice of spacing 0.25 and width 0.02, in object space: the object was moved by +0.1
    // along y, so world y = 0.35 is object y = 0.25, on a plane.
    let lat = Texture::<4> {
        values: None,
        isolines: None,
        lattice: Some(Lattice {
            spacing: 0.25,
            width: 0.02,
            color: [0.0, 0.0, 1.0],
        }),
        to_object: (crate::linalg::identity::<4>(), [0.0, -0.1, 0.0, 0.0]),
        ..t.clone()
    };
    assert_eq!(at(&lat, 0.13, 0.35, 0.13), [0.0, 0.0, 1.0]);
    assert_eq!(at(&lat, 0.13, 0.30, 0.13), base);
    assert_eq!(at(&lat, 0.505, 0.2, 0.13), [0.0, 0.0, 1.0]);
    // The colormap replaces the base colour.
    let cm = Texture::<4> {
        colormap: Some((colormap::get("gray").unwrap(), [0.0, 1.0])),
        isolines: None,
        ..t.clone()
    };
    let c = at(&cm, 1.0, 0.0, 0.0);
    assert!((c[0] - 1.0).abs() < 1e-9);
}

#[test]
fn depth_maps_the_hit_depth_and_cells_their_class_colour() {
    let mesh = Mesh::<4> {
        vertices: vec![
            [0.0; 4],
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        simplices: vec![[0, 1, 2, 3]],
    };
    let gray = colormap::get("gray").unwrap();
    let t = Texture::<4> {
        values: None,
        colormap: None,
        isolines: None,
        lattice: None,
        to_object: (crate::linalg::identity::<4>(), [0.0; 4]),
        cells: None,
        depth: Some((gray, [2.0, 4.0])),
    };
    let bary = [0.25; 4];
    let at = |t: &Texture<4>, d: f64| t.color(&[0.5; 3], &mesh, 0, &bary, &[0.25; 4], d);
    // Linear in depth over the range, clamped beyond it.
    assert!(at(&t, 2.0)[0] < 1e-9 && (at(&t, 4.0)[0] - 1.0).abs() < 1e-9);
    assert_eq!(at(&t, 1.0), at(&t, 2.0));
    assert!(at(&t, 3.0)[0] > at(&t, 2.5)[0]);
    // A cell's colour is its class's.
    let cells = Texture::<4> {
        depth: None,
        cells: Some(CellColors {
            classes: cells::cell_classes(&mesh),
            colors: vec![[0.1, 0.2, 0.3]],
        }),
        ..t.clone()
    };
    assert_eq!(at(&cells, 3.0), [0.1, 0.2, 0.3]);
}
