use super::*;
use crate::geometry::{barycentric as bary, ray_hyperplane};
use crate::scene::load_toml_str;

/// Whether the point `q` is hidden from the camera, by brute force over every simplex: the ray
/// toward it meets a simplex (all barycentric coordinates ≥ 0) at t < 1 − `gap`.
fn hidden_brute<const N: usize>(scene: &Scene<N>, q: &Vector<N>, gap: f64) -> bool {
    let cam = &scene.camera;
    let (origin, dir) = match cam.projection {
        Projection::Perspective => (cam.position, sub(q, &cam.position)),
        Projection::Orthographic => {
            let view = cam.axis(N - 1);
            let d = dot(&sub(q, &cam.position), &view);
            (
                std::array::from_fn(|k| q[k] - d * view[k]),
                std::array::from_fn(|k| d * view[k]),
            )
        }
    };
    scene.objects.iter().any(|obj| {
        (0..obj.mesh.simplices.len()).any(|s| {
            let pts = obj.mesh.simplex_points(s);
            let Ok(t) = ray_hyperplane(&origin, &dir, &pts) else {
                return false;
            };
            if !(t > 1e-9 && t < 1.0 - gap) {
                return false;
            }
            let x: Vector<N> = std::array::from_fn(|k| origin[k] + t * dir[k]);
            let mut b = [0.0; N];
            bary(&x, &pts, &mut b).is_ok() && b.iter().all(|&v| v >= -1e-12)
        })
    })
}

/// Whether `q` lies in the camera's field of view.
fn in_view<const N: usize>(cam: &Camera<N>, q: &Vector<N>) -> bool {
    match retina_coords(cam, q) {
        Some(xi) => (0..N - 1).all(|k| xi[k] >= 0.0 && xi[k] <= cam.resolution[k] as f64),
        None => false,
    }
}

/// Every piece of every edge, sampled densely away from its ends, is classified as the brute
/// force says; the pieces of each edge tile it; returns (visible, hidden) lengths.
fn check_against_brute_force<const N: usize>(scene: &Scene<N>) -> (f64, f64) {
    let segs = edge_segments(scene, 20.0).unwrap();
    let (mut vis, mut hid) = (0.0, 0.0);
    let mut checked = 0;
    for seg in &segs {
        let len = crate::linalg::norm(&sub(&seg.b, &seg.a));
        if seg.visible {
            vis += len;
        } else {
            hid += len;
        }
        for i in 1..40 {
            let s = i as f64 / 40.0;
            let q = lerp(&seg.a, &seg.b, s);
            // Stay clear of the piece's ends (where visibility changes) by 1e-3 of its length.
            if len * s.min(1.0 - s) < 1e-3 * len.max(1e-3) {
                continue;
            }
            let expected = in_view(&scene.camera, &q) && !hidden_brute(scene, &q, 1e-4);
            assert_eq!(
                seg.visible, expected,
                "piece {seg:?} at s = {s}: the brute force says visible = {expected}"
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "only {checked} points checked");
    (vis, hid)
}

fn scene_of(text: &str) -> crate::scene::AnyScene {
    load_toml_str(text, "test.toml", None).unwrap().1
}

const TESSERACT: &str = r#"
dim = 4
[camera]
position = [1.2, 1.6, 2.0, 4.5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 50
resolution = 16
[[objects]]
shape = "hypercube"
transform = [{ rotate = { plane = [0, 3], degrees = 20 } }, { rotate = { plane = [1, 2], degrees = 15 } }]
"#;

#[test]
fn tesseract_edges_match_a_brute_force_occlusion_test() {
    let any = scene_of(TESSERACT);
    let crate::scene::AnyScene::D4(scene) = &any else {
        unreachable!()
    };
    let (vis, hid) = check_against_brute_force(scene);
    // A convex body seen from outside: some edges face the eye, some are hidden behind it.
    assert!(vis > 0.0 && hid > 0.0, "visible {vis}, hidden {hid}");
    // The pieces of each edge tile it: the total length is that of the 32 edges of side 2.
    assert!(((vis + hid) - 64.0).abs() < 1e-9, "{}", vis + hid);
}

#[test]
fn cross_polytope_and_orthographic_views_match_the_brute_force() {
    for projection in ["perspective", "orthographic"] {
        let lens = if projection == "perspective" {
            "fov = 45"
        } else {
            "extent = 1.6"
        };
        let text = format!(
            r#"
dim = 4
[camera]
position = [0.9, -1.3, 1.1, 4.0]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
{lens}
projection = "{projection}"
resolution = 12
[[objects]]
shape = "cross_polytope"
transform = [{{ rotate = {{ plane = [0, 2], degrees = 33 }} }}]
"#
        );
        let any = scene_of(&text);
        let crate::scene::AnyScene::D4(scene) = &any else {
            unreachable!()
        };
        let (vis, hid) = check_against_brute_force(scene);
        assert!(
            vis > 0.0 && hid > 0.0,
            "{projection}: visible {vis}, hidden {hid}"
        );
    }
}

#[test]
fn one_object_hides_part_of_another() {
    // The longest visible piece of the tesseract's edges, from its midpoint M: a small 16-cell
    // halfway between the eye and M hides the middle of that edge and nothing at its ends.
    let any = scene_of(TESSERACT);
    let crate::scene::AnyScene::D4(alone) = &any else {
        unreachable!()
    };
    let segs = edge_segments(alone, 20.0).unwrap();
    let longest = segs
        .iter()
        .filter(|s| s.visible)
        .max_by(|x, y| {
            let l = |s: &EdgeSegment<4>| crate::linalg::norm(&sub(&s.b, &s.a));
            l(x).total_cmp(&l(y))
        })
        .unwrap();
    let m = lerp(&longest.a, &longest.b, 0.5);
    let e = alone.camera.position;
    let c = lerp(&e, &m, 0.5);
    let len = crate::linalg::norm(&sub(&longest.b, &longest.a));
    let text = format!(
        "{TESSERACT}\n[[objects]]\nshape = \"cross_polytope\"\n\
         transform = [{{ scale = {} }}, {{ translate = {:?} }}]\n",
        0.1 * len,
        c
    );
    let any = scene_of(&text);
    let crate::scene::AnyScene::D4(scene) = &any else {
        unreachable!()
    };
    let segs = edge_segments(scene, 20.0).unwrap();
    let on_edge: Vec<_> = segs
        .iter()
        .filter(|s| {
            s.object == 0 && {
                // Pieces of the longest edge: collinear with it.
                let d = sub(&longest.b, &longest.a);
                let off = |p: &Vector<4>| {
                    let w = sub(p, &longest.a);
                    let t = dot(&w, &d) / dot(&d, &d);
                    crate::linalg::norm(&sub(&w, &crate::linalg::scale(&d, t)))
                };
                off(&s.a) < 1e-9 && off(&s.b) < 1e-9
            }
        })
        .collect();
    let pattern: Vec<bool> = on_edge.iter().map(|s| s.visible).collect();
    assert!(
        pattern.windows(3).any(|w| w == [true, false, true]),
        "the edge is not interrupted: {on_edge:?}"
    );
    let (vis, hid) = check_against_brute_force(scene);
    assert!(((vis + hid) - 64.0 - 24.0 * 2f64.sqrt() * 0.1 * len).abs() < 1e-9);
}

#[test]
fn three_and_five_dimensional_scenes_match_the_brute_force() {
    let cube = r#"
dim = 3
[camera]
position = [2.5, 1.8, 3.5]
look_at = [0, 0, 0]
up = [0, 1, 0]
fov = 45
resolution = 16
[[objects]]
shape = "hypercube"
"#;
    let any = scene_of(cube);
    let crate::scene::AnyScene::D3(scene) = &any else {
        unreachable!()
    };
    let (vis, hid) = check_against_brute_force(scene);
    // A cube seen from a generic direction in front of three faces: 9 edges seen, 3 hidden.
    // (Up to the on-edge tolerance where a hidden edge ends at a visible corner.)
    assert!(
        (vis - 18.0).abs() < 1e-4 && (hid - 6.0).abs() < 1e-4,
        "{vis} {hid}"
    );
    assert!(((vis + hid) - 24.0).abs() < 1e-9);
    let penteract = r#"
dim = 5
[camera]
position = [1.1, 1.5, 1.2, 2.0, 5.0]
look_at = [0, 0, 0, 0, 0]
up = [[0, 1, 0, 0, 0], [0, 0, 1, 0, 0], [0, 0, 0, 1, 0]]
fov = 50
resolution = 8
[[objects]]
shape = "hypercube"
"#;
    let any = scene_of(penteract);
    let crate::scene::AnyScene::D5(scene) = &any else {
        unreachable!()
    };
    let (vis, hid) = check_against_brute_force(scene);
    assert!(((vis + hid) - 160.0).abs() < 1e-9 && vis > 0.0 && hid > 0.0);
}

#[test]
fn edge_directions_give_parallel_edges_one_colour_in_the_objects_own_axes() {
    // The tesseract turned 20° in x–w: its 32 edges in 4 directions, named in its own axes.
    let text = r#"dim = 4
[camera]
position = [1.2, 1.6, 2.0, 4.5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 50
resolution = 16
[[objects]]
shape = "hypercube"
transform = [{ rotate = { plane = [0, 3], degrees = 20 } }]
"#;
    let scene = match load_toml_str(text, "t.toml", None).unwrap().1 {
        crate::scene::AnyScene::D4(s) => s,
        _ => unreachable!(),
    };
    let dirs = edge_directions(&scene, 20.0).unwrap();
    assert_eq!(dirs.len(), 4);
    let palette = crate::texture::palette::get("tab10").unwrap();
    for (k, d) in dirs.iter().enumerate() {
        // Its own direction is axis k (x, y, z, w in order), its colour the palette's k-th.
        let axis = d.own.iter().position(|x| (x - 1.0).abs() < 1e-9);
        assert_eq!(axis, Some(k), "{:?}", d.own);
        assert_eq!(d.color, palette.color(k));
    }
    // In the retina, every piece takes its direction's colour: 4 colours, and the pieces along
    // one direction share one.
    let edges = retina_edges(&scene, 20.0).unwrap();
    let mut colors: Vec<[f32; 3]> = edges.iter().map(|e| e.color).collect();
    colors.sort_by(|a, b| a.partial_cmp(b).unwrap());
    colors.dedup();
    assert_eq!(colors.len(), 4);
    for e in &edges {
        let d = &dirs
            .iter()
            .find(|d| d.color.map(|c| c as f32) == e.color)
            .unwrap();
        assert!(d.object == 0);
    }
}
