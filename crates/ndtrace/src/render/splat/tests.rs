use super::closest_on_triangle;
use crate::render::{trace, Progress, Retina};
use crate::scene::{load_toml_str, AnyScene, Scene};
use crate::testutil::rng;
use rand::Rng;

#[test]
fn the_closest_triangle_point_is_the_brute_force_one() {
    let mut rng = rng(3);
    let mut r3 = || std::array::from_fn::<f64, 3, _>(|_| 4.0 * rng.random::<f64>() - 2.0);
    for case in 0..300 {
        let mut t = [r3(), r3(), r3()];
        if case % 10 == 0 {
            // Without area: the third vertex on the first edge.
            t[2] = std::array::from_fn(|k| 0.3 * t[0][k] + 0.7 * t[1][k]);
        }
        let p = r3();
        let b = closest_on_triangle(&p, &t);
        assert!(b.iter().all(|&x| x >= -1e-12) && (b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let at = |b: [f64; 3]| -> f64 {
            (0..3)
                .map(|k| {
                    let x = b[0] * t[0][k] + b[1] * t[1][k] + b[2] * t[2][k] - p[k];
                    x * x
                })
                .sum::<f64>()
                .sqrt()
        };
        let n = 120;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                best = best.min(at([1.0 - u - v, u, v]));
            }
        }
        assert!(
            at(b) <= best + 1e-12,
            "case {case}: {} vs brute force {best}",
            at(b)
        );
        assert!(at(b) >= best - 0.03, "case {case}: the grid is fine enough");
    }
}

fn scene4(text: &str) -> Scene<4> {
    match load_toml_str(text, "test.toml", None).unwrap().1 {
        AnyScene::D4(s) => s,
        _ => panic!("dim 4"),
    }
}

/// An orthographic camera down −w (retina axes x, y, z) over [−1, 1]³ at `res` cells.
fn ortho(res: usize) -> String {
    format!(
        "dim = 4\n[camera]\nposition = [0, 0, 0, 5]\nlook_at = [0, 0, 0, 0]\n\
         up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nprojection = \"orthographic\"\nextent = 1\n\
         resolution = {res}\n[render]\nshadows = false\n"
    )
}

fn traced(s: &Scene<4>) -> Retina {
    trace(s, &Progress::default()).unwrap()
}

#[test]
fn a_triangle_covers_the_cells_within_half_its_width_and_no_others() {
    let res = 24;
    for (width, tri) in [
        (
            1.25,
            "[[-0.8, -0.6, -0.2, 0.3], [0.7, -0.1, 0.5, -0.2], [-0.1, 0.8, -0.6, 0.1]]",
        ),
        (
            3.0,
            "[[-0.5, -0.5, 0.1, 0.0], [0.6, -0.4, 0.1, 0.4], [0.0, 0.7, 0.1, -0.3]]",
        ),
        (
            1.0,
            "[[-0.9, 0.0, 0.0, 0.0], [0.9, 0.01, 0.0, 0.5], [0.0, 0.02, 0.9, -0.5]]",
        ),
    ] {
        let text = format!(
            "{}[[objects]]\nshape = \"surface\"\nvertices = {tri}\ntriangles = [[0, 1, 2]]\n\
             width = {width}\n",
            ortho(res)
        );
        let s = scene4(&text);
        let r = traced(&s);
        // Independently: the camera maps (x, y, z, w) to cell coordinates
        // ((x + 1)·res/2, (1 − y)·res/2, (z + 1)·res/2), depth 5 − w.
        let v = &s.objects[0].mesh.vertices;
        let g: [[f64; 3]; 3] = std::array::from_fn(|i| {
            let x = v[i];
            [
                (x[0] + 1.0) * 12.0,
                (1.0 - x[1]) * 12.0,
                (x[2] + 1.0) * 12.0,
            ]
        });
        for k in 0..res * res * res {
            let c = [k % res, k / res % res, k / (res * res)].map(|i| i as f64 + 0.5);
            // Brute force over a fine grid of the triangle.
            let n = 400;
            let mut best = (f64::INFINITY, 0.0);
            for i in 0..=n {
                for j in 0..=n - i {
                    let (a, b) = (i as f64 / n as f64, j as f64 / n as f64);
                    let w = [1.0 - a - b, a, b];
                    let d: f64 = (0..3)
                        .map(|m| (w[0] * g[0][m] + w[1] * g[1][m] + w[2] * g[2][m] - c[m]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    if d < best.0 {
                        let depth = 5.0 - (w[0] * v[0][3] + w[1] * v[1][3] + w[2] * v[2][3]);
                        best = (d, depth);
                    }
                }
            }
            let covered = r.object_id[k] == 0;
            let h = width / 2.0;
            if best.0 < h - 0.01 {
                assert!(
                    covered,
                    "width {width}: cell {k} at {} should be covered",
                    best.0
                );
                assert!(
                    (r.depth[k] as f64 - best.1).abs() < 0.02,
                    "depth at cell {k}"
                );
                assert_eq!(r.rgba[k * 4 + 3], 1.0);
            } else if best.0 > h + 0.01 {
                assert!(
                    !covered,
                    "width {width}: cell {k} at {} should be empty",
                    best.0
                );
            }
        }
    }
}

/// A flat square in the plane of x and y tilted into z and w, split into `n`² × 2 triangles.
fn patch(n: usize) -> (String, String) {
    let mut v = Vec::new();
    let mut t = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (a, b) = (
                1.4 * i as f64 / n as f64 - 0.7,
                1.4 * j as f64 / n as f64 - 0.7,
            );
            v.push(format!(
                "[{a}, {}, {}, {}]",
                0.8 * b,
                0.3 * a + 0.4 * b,
                0.5 * b - 0.2 * a
            ));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let k = j * (n + 1) + i;
            t.push(format!("[{k}, {}, {}]", k + 1, k + n + 2));
            t.push(format!("[{k}, {}, {}]", k + n + 2, k + n + 1));
        }
    }
    (format!("[{}]", v.join(", ")), format!("[{}]", t.join(", ")))
}

#[test]
fn perspective_fragments_lie_on_the_surface_at_their_cells() {
    let (v, t) = patch(6);
    let text = format!(
        "dim = 4\n[camera]\nposition = [0.3, 0.2, 0.4, 3]\nlook_at = [0, 0, 0, 0]\n\
         up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 40\nresolution = 20\n[render]\nshadows = false\n\
         [[objects]]\nshape = \"surface\"\nvertices = {v}\ntriangles = {t}\nwidth = 1.5\n"
    );
    let s = scene4(&text);
    let r = traced(&s);
    let cam = &s.camera;
    let mut seen = 0;
    for k in 0..r.depth.len() {
        if r.object_id[k] != 0 {
            continue;
        }
        seen += 1;
        // The recorded depth puts the point on the surface's plane along a ray within the
        // sheet's half width of the cell's centre ray.
        let mut u = [0.0; 4];
        cam.retina_point(k, &[0.5; 3], &mut u[..3]);
        let ray = cam.ray(&u[..3]);
        let dir = crate::linalg::scale(&ray.dir, 1.0 / crate::linalg::norm(&ray.dir));
        let x = crate::linalg::add_scaled(&ray.origin, r.depth[k] as f64, &dir);
        // The patch is {(a, 0.8b, 0.3a + 0.4b, 0.5b − 0.2a)}: z and w are fixed by x and y.
        let (a, b) = (x[0], x[1] / 0.8);
        let off = [
            (x[2] - 0.3 * a - 0.4 * b).abs(),
            (x[3] - 0.5 * b + 0.2 * a).abs(),
        ];
        let cell_at = r.depth[k] as f64 * cam.cell;
        assert!(
            off[0].max(off[1]) < 2.0 * cell_at,
            "cell {k}: {off:?}, cell {cell_at}"
        );
    }
    assert!(seen > 100, "{seen} cells");
}

#[test]
fn surfaces_are_occluded_by_depth_and_blend_with_their_opacity() {
    let base = |opacity: f64, w: f64| {
        format!(
            "{}[[objects]]\nshape = \"hypercube\"\ntransform = [{{ scale = 0.3 }}]\n\
             material = {{ color = [0.2, 0.9, 0.3] }}\n\
             [[objects]]\nshape = \"surface\"\nvertices = [[-1, -1, 0, {w}], [1, -1, 0, {w}], \
             [1, 1, 0, {w}], [-1, 1, 0, {w}]]\ntriangles = [[0, 1, 2], [0, 2, 3]]\n\
             material = {{ color = [1, 0.2, 0.2], opacity = {opacity} }}\n\
             [[lights]]\ntype = \"directional\"\ndirection = [0.3, 0.2, 0.5, 1]\n",
            ortho(16)
        )
    };
    // Behind the cube (w = −0.5 < −0.3): the cube's cells are untouched.
    let behind = scene4(&base(1.0, -0.5));
    let alone = scene4(
        &base(1.0, -0.5).replace("shape = \"surface\"", "shape = \"surface\"\nwidth = 1e-9"),
    );
    let (rb, ra) = (traced(&behind), traced(&alone));
    let mut cube = 0;
    for k in 0..rb.depth.len() {
        if ra.object_id[k] == 0 {
            cube += 1;
            assert_eq!(rb.object_id[k], 0);
            assert_eq!(rb.rgba[k * 4..k * 4 + 4], ra.rgba[k * 4..k * 4 + 4]);
        }
    }
    assert!(cube > 10);
    // In front (w = 0.5): opaque, it hides the cube; at opacity ½ the cube shows through half.
    let front = traced(&scene4(&base(1.0, 0.5)));
    let half = traced(&scene4(&base(0.5, 0.5)));
    let mut blended = 0;
    for k in 0..front.depth.len() {
        if front.object_id[k] == 1 {
            assert_eq!(half.object_id[k], 1);
            assert_eq!(front.depth[k], half.depth[k]);
            let under = &ra.rgba[k * 4..k * 4 + 4];
            for j in 0..4 {
                let want = 0.5 * front.rgba[k * 4 + j] + 0.5 * under[j];
                assert!((half.rgba[k * 4 + j] - want).abs() < 1e-6, "cell {k}");
            }
            blended += (ra.object_id[k] == 0) as usize;
        }
    }
    assert!(blended > 10, "{blended} cells over the cube");
}

#[test]
fn the_retina_is_the_same_on_any_number_of_threads() {
    let (v, t) = patch(10);
    let text = format!(
        "dim = 4\n[camera]\nposition = [0.3, 0.2, 0.4, 3]\nlook_at = [0, 0, 0, 0]\n\
         up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 40\nresolution = 24\n\
         [[objects]]\nshape = \"surface\"\nvertices = {v}\ntriangles = {t}\n\
         material = {{ smooth = true, specular = 0.5, opacity = 0.6 }}\n\
         [[lights]]\ntype = \"point\"\nposition = [1, 2, 1, 2]\n"
    );
    let s = scene4(&text);
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| traced(&s))
    };
    let one = run(1);
    assert!(one.object_id.iter().filter(|&&o| o == 0).count() > 100);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

#[test]
fn bad_surfaces_are_located_errors() {
    let head = ortho(8);
    let obj = "[[objects]]\nshape = \"surface\"\n";
    let tri = "vertices = [[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]]\n";
    for (body, want) in [
        (
            format!("{obj}{tri}"),
            "objects[0]: a surface needs vertices (V, 4) and triangles (T, 3)",
        ),
        (
            format!("{obj}{tri}triangles = [[0, 1]]\n"),
            "objects[0].triangles[0]: a triangle has 3 vertex indices",
        ),
        (
            format!("{obj}{tri}triangles = [[0, 1, 3]]\n"),
            "objects[0].triangles[0][2]: vertex index 3 out of range",
        ),
        (
            format!("{obj}{tri}triangles = [[0, 1, 1]]\n"),
            "objects[0].triangles[0]: repeats a vertex",
        ),
        (
            format!("{obj}{tri}triangles = [[0, 1, 2]]\nwidth = 0\n"),
            "objects[0].width: must be a number of retina cells",
        ),
        (
            format!("{obj}{tri}triangles = [[0, 1, 2]]\nsimplices = [[0, 1, 2, 0]]\n"),
            "objects[0].simplices: \"simplices\" is not used by shape \"surface\"",
        ),
        (
            format!("{obj}{tri}triangles = [[0, 1, 2]]\nmaterial = {{ opacity = 0 }}\n"),
            "objects[0].material.opacity: must be in (0, 1]",
        ),
        (
            "[[objects]]\nshape = \"hypercube\"\nmaterial = { opacity = 0.5 }\n".to_string(),
            "objects[0].material.opacity: only surface objects",
        ),
        (
            "[[objects]]\nshape = \"hypercube\"\ntriangles = [[0, 1, 2]]\n".to_string(),
            "objects[0].triangles: \"triangles\" is not used by shape \"hypercube\"",
        ),
    ] {
        let text = format!("{head}{body}");
        let err = match load_toml_str(&text, "s.toml", None) {
            Ok(_) => panic!("accepted:\n{text}"),
            Err(e) => e.to_string(),
        };
        assert!(err.contains(want), "{err}\nwanted: {want}");
        assert!(err.starts_with("s.toml:"), "located: {err}");
    }
    let three = "dim = 3\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\n\
                 fov = 40\nresolution = 8\n[[objects]]\nshape = \"surface\"\n\
                 vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\ntriangles = [[0, 1, 2]]\n";
    let err = load_toml_str(three, "s.toml", None)
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("objects[0].shape: shape \"surface\" is a 2-surface in R^4: it needs dim = 4"),
        "{err}"
    );
}
