//! The packet path against one ray at a time: every cell of the tracer's retina has, bit for
//! bit, the value that the single-ray BVH queries and [`shade_hit`] give its rays.

use super::sampling::{sample_offsets, SplitMix};
use super::shade::shading_normal;
use super::*;
use crate::linalg::{det, sub, Vector};
use crate::scene::{load_toml_str, Scene};

/// One cell, one ray at a time, with the single-ray queries and [`shade_hit`]: the colour sum
/// and nearest hit (the first sample of least depth) the packet path must reproduce bit for
/// bit, and the samples that hit. Camera rays see the simplices `accept`s.
fn one_ray_at_a_time<const N: usize>(
    scene: &Scene<N>,
    cell: usize,
    accept: &dyn Fn(u32) -> bool,
) -> ([f64; 3], NearestHit<N>, usize) {
    let samples = scene.render.samples as usize;
    let mut rng = SplitMix::new(scene.render.seed, cell as u64);
    let mut offsets = vec![];
    sample_offsets(samples, N - 1, &mut rng, &mut offsets);
    let (mut color, mut covered) = ([0.0; 3], 0);
    let mut nearest = NearestHit::MISS;
    let mut u = [0.0; N];
    for j in 0..samples {
        scene
            .camera
            .retina_point(cell, &offsets[j * (N - 1)..(j + 1) * (N - 1)], &mut u);
        let ray = scene.camera.ray(&u[..N - 1]);
        let first = scene
            .instances
            .closest_hit(&ray, 0.0, f64::INFINITY, accept);
        let Some(hit) = (if scene.clips.active() {
            clip::nearest_kept(scene, &ray, 0.0, f64::INFINITY, &accept, first)
        } else {
            first
        }) else {
            continue;
        };
        covered += 1;
        let depth = scene.camera.depth(hit.t, crate::linalg::norm(&ray.dir));
        if covered == 1 || depth < nearest.depth {
            let (obj, local) = scene.locate(hit.prim);
            nearest = NearestHit {
                depth,
                normal: shading_normal(scene, &hit, obj, local, &ray),
                object: obj as i32,
                primitive: local as i64,
            };
        }
        let c = shade_hit(scene, &ray, &hit);
        for k in 0..3 {
            color[k] += c[k];
        }
    }
    (color, nearest, covered)
}

/// Every cell of the retina has the bits of [`one_ray_at_a_time`]; returns the cells hit and
/// the cells that a shadow darkens (whose colour differs with shadows turned off).
fn shade_as_one_ray_at_a_time<const N: usize>(scene: &mut Scene<N>) -> (usize, usize) {
    // Back-face culling (course notes): a simplex is culled when
    // det[x_1 − x_0 … x_{N−1} − x_0 | C − x_0] < 0, here the determinant itself (the
    // tracer takes the dot product of the flat normal with C − x_0).
    let culled: Vec<bool> = (0..scene.simplex_count() as u32)
        .map(|g| {
            let (o, s) = scene.locate(g);
            let mesh = &scene.objects[o].mesh;
            let x: Vec<Vector<N>> = mesh.simplices[s]
                .iter()
                .map(|&i| mesh.vertices[i as usize])
                .collect();
            let mut m = [[0.0; N]; N];
            for (k, row) in m.iter_mut().enumerate() {
                *row = if k + 1 < N {
                    sub(&x[k + 1], &x[0])
                } else {
                    scene.camera.toward_eye(&x[0])
                };
            }
            scene.render.cull_backfaces && det(&m) < 0.0
        })
        .collect();
    let accept = |g: u32| !culled[g as usize];
    let samples = scene.render.samples as usize;
    // Stale values in buffers of every output's size, which the trace takes from the pool
    // (unless a concurrent test does): it must overwrite every element.
    let cells = scene.camera.cell_count();
    for len in [cells * 4, cells, cells * N] {
        pool::recycle(vec![f32::NAN; len]);
    }
    pool::recycle(vec![7i32; cells]);
    pool::recycle(vec![7i64; cells]);
    let retina = trace(scene, &Progress::default()).unwrap();
    let inv = 1.0 / samples as f64;
    let mut lit = 0;
    let mut colors = Vec::with_capacity(cells);
    for cell in 0..cells {
        let (color, nearest, covered) = one_ray_at_a_time(scene, cell, &accept);
        for k in 0..3 {
            assert_eq!(
                retina.rgba[cell * 4 + k].to_bits(),
                ((color[k] * inv) as f32).to_bits(),
                "N={N}, samples {samples}, cell {cell}, channel {k}"
            );
        }
        assert_eq!(retina.rgba[cell * 4 + 3], (covered as f64 * inv) as f32);
        // Every element written, misses' too, with the nearest hit's record.
        let normal = &retina.normal[cell * N..(cell + 1) * N];
        assert_eq!(
            retina.depth[cell].to_bits(),
            (nearest.depth as f32).to_bits()
        );
        assert_eq!(normal, nearest.normal.map(|x| x as f32).as_slice());
        assert_eq!(
            (retina.object_id[cell], retina.primitive_id[cell]),
            (nearest.object, nearest.primitive),
            "cell {cell}"
        );
        if covered > 0 {
            assert!(retina.object_id[cell] >= 0 && retina.primitive_id[cell] >= 0);
            assert!(retina.depth[cell].is_finite(), "cell {cell}");
            let len2: f32 = normal.iter().map(|x| x * x).sum();
            assert!((len2 - 1.0).abs() < 1e-5, "cell {cell}: normal {normal:?}");
        } else {
            assert_eq!(
                (retina.object_id[cell], retina.primitive_id[cell]),
                (-1, -1)
            );
            assert_eq!(retina.depth[cell], f32::INFINITY, "cell {cell}");
            assert!(normal.iter().all(|&x| x == 0.0), "cell {cell}: {normal:?}");
        }
        lit += (covered > 0) as usize;
        colors.push(color);
    }
    // The cells in shadow: darker than with every light unblocked.
    let shadows = std::mem::replace(&mut scene.render.shadows, false);
    let shadowed = (0..cells)
        .filter(|&cell| one_ray_at_a_time(scene, cell, &accept).0 != colors[cell])
        .count();
    scene.render.shadows = shadows;
    (lit, shadowed)
}

/// [`shade_as_one_ray_at_a_time`] on the scene `text`, which must have at least `lit` cells
/// hit and at least `shadowed` in shadow.
fn shades_as_one_ray_at_a_time(text: &str, lit: usize, shadowed: usize) {
    let (_, mut any) = load_toml_str(text, "test.toml", None).unwrap();
    let (l, s) = crate::with_scene!(&mut any, scene, _N => shade_as_one_ray_at_a_time(scene));
    assert!(
        l >= lit && s >= shadowed,
        "{l} cells hit, {s} in shadow, in\n{text}"
    );
}

/// Two point lights (one with falloff) and a directional one, for the 3D shading tests.
const LIGHTS: &str = r#"
[[lights]]
type = "point"
position = [2.0, 3.0, 2.5]
color = [0.8, 0.7, 0.6]
[[lights]]
type = "directional"
direction = [-1.0, 0.5, 0.2]
color = [0.3, 0.4, 0.5]
[[lights]]
type = "point"
position = [-3.0, -0.5, 1.0]
color = [0.2, 0.2, 0.9]
falloff = 1.0"#;

#[test]
fn clipped_and_capped_scenes_shade_as_one_ray_at_a_time() {
    // A 3-sphere cut open by a scene clip, capped, beside a tesseract cut by its own clip
    // that lets light through onto the sphere; shadows on.
    let text = r#"
dim = 4
clip = [{ normal = [0.3, 0.2, 0.1, 1.0], offset = 0.15 }]
[camera]
position = [1.0, 1.4, 1.9, 4.0]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 55
resolution = 14
[[lights]]
type = "directional"
direction = [0.4, 0.9, 0.3, -0.6]
[[lights]]
type = "point"
position = [-2.0, 2.5, 1.0, 1.5]
[[objects]]
shape = "sphere"
subdivisions = 1
cap = true
[[objects]]
shape = "hypercube"
clip = [{ normal = [0, 1, 0, 0], offset = 1.2 }]
cap = true
transform = [{ scale = 0.4 }, { translate = [0.2, 1.3, 0.1, 0.0] }]
[render]
samples = 3
"#;
    shades_as_one_ray_at_a_time(text, 100, 0);
}

#[test]
fn gouraud_shading_shades_as_one_ray_at_a_time() {
    // A smooth sphere (vertex normals) and a flat-shaded tesseract (the flat normal at every
    // vertex), a point light with falloff (attenuation per vertex) and a specular term.
    let text = r#"
dim = 4
[camera]
position = [1.0, 1.4, 1.9, 4.0]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 55
resolution = 12
[[lights]]
type = "point"
position = [-2.0, 2.5, 1.0, 1.5]
falloff = 1.0
[[lights]]
type = "directional"
direction = [0.4, 0.9, 0.3, -0.6]
[[objects]]
shape = "sphere"
subdivisions = 1
material = { smooth = true, specular = 0.5 }
[[objects]]
shape = "hypercube"
transform = [{ scale = 0.4 }, { translate = [0.2, 1.3, 0.1, 0.0] }]
[render]
samples = 2
shading = "gouraud"
"#;
    shades_as_one_ray_at_a_time(text, 80, 0);
}

#[test]
fn terms_added_at_once_or_after_the_shadow_pass_sum_in_light_order() {
    // One coarse smooth convex sphere: a term needs a shadow ray only when its light lies
    // on the inner side of the flat facet hit, which the smooth normal still faces (near
    // each light's terminator); that ray leaves through the inside and is blocked. So a
    // ray's terms are added at once, or some wait for the shadow pass (in at least one
    // cell); without shadows all are added at once.
    for (shadows, shadowed) in [(true, 1), (false, 0)] {
        let text = format!(
            r#"
dim = 3
ambient = [0.1, 0.1, 0.1]
[camera]
position = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0]]
fov = 40.0
resolution = [40, 30]
{LIGHTS}
[[objects]]
shape = "sphere"
subdivisions = 1
material = {{ color = [0.9, 0.5, 0.3], specular = 0.5, shininess = 20.0, smooth = true }}
[render]
shadows = {shadows}
"#
        );
        shades_as_one_ray_at_a_time(&text, 300, shadowed);
    }
}

#[test]
fn packets_shade_every_cell_as_one_ray_at_a_time() {
    // Objects that shadow each other, a light behind some surfaces (filtered out before the
    // shadow pass), two lights of each kind, 1 and 3 samples (packets split across cells).
    // Retinas in 8×8 tiles: 37 × 29 (one short chunk, partial tiles and strip), 64 × 70
    // (a full chunk of 64 rows and a short one of 6), 64 × 67 (the short chunk ends with a
    // strip of 3 rows, the last of them alone).
    for (samples, resolution) in [
        (1, "[37, 29]"),
        (3, "[37, 29]"),
        (1, "[64, 70]"),
        (3, "[64, 70]"),
        (1, "[64, 67]"),
    ] {
        let text = format!(
            r#"
dim = 3
ambient = [0.1, 0.1, 0.1]
[camera]
position = [0.5, 1.0, 6.0]
look_at = [0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0]]
fov = 40.0
resolution = {resolution}
{LIGHTS}
[[objects]]
shape = "sphere"
subdivisions = 2
material = {{ color = [0.9, 0.5, 0.3], specular = 0.5, shininess = 20.0, smooth = true }}
[[objects]]
shape = "hypercube"
transform = [{{ scale = 0.4 }}, {{ translate = [1.0, 0.8, 1.2] }}]
[[objects]]
shape = "hypercube"
transform = [{{ scale = [3.0, 0.1, 3.0] }}, {{ translate = [0.0, -1.3, 0.0] }}]
[render]
samples = {samples}
seed = 5
shadows = true
"#
        );
        shades_as_one_ray_at_a_time(&text, 301, 51);
    }
    // A 3D retina in strips of rows, within slices (6 rows) and across them (5 rows), and
    // in two chunks, the second starting mid-slice (row 512: slice 7, row 22).
    for resolution in ["[8, 6, 5]", "[8, 5, 6]", "[8, 70, 10]"] {
        let text = format!(
            r#"
dim = 4
[camera]
position = [0.3, 0.5, 0.2, 2.6]
look_at = [0.0, 0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
fov = 60.0
resolution = {resolution}
[[lights]]
type = "point"
position = [2.0, 3.0, 1.0, 2.5]
[[objects]]
shape = "sphere"
subdivisions = 1
[[objects]]
shape = "hypercube"
transform = [{{ scale = 0.3 }}, {{ translate = [0.5, 0.6, 0.2, 1.2] }}]
[render]
shadows = true
"#
        );
        shades_as_one_ray_at_a_time(&text, 61, 6);
    }
}

#[test]
fn other_cameras_and_dimensions_shade_as_one_ray_at_a_time() {
    // (scene, cells hit at least, cells with a blocked shadow ray at least), each traced
    // with 1, 2 and 3 samples per cell.
    let cases = [
        // N = 2: a 1-D retina of one chunk, a polygon circle shadowing a square.
        (
            r#"
dim = 2
[camera]
position = [0.3, 3.0]
look_at = [0.0, 0.0]
fov = 70.0
resolution = 53
[[lights]]
type = "point"
position = [2.5, 2.0]
[[lights]]
type = "directional"
direction = [-1.0, 0.3]
color = [0.3, 0.2, 0.1]
[[objects]]
shape = "sphere"
subdivisions = 3
material = { color = [0.9, 0.5, 0.3], specular = 0.5, shininess = 8.0 }
[[objects]]
shape = "hypercube"
transform = [{ scale = 0.3 }, { translate = [-1.2, -0.6] }]
[render]
shadows = true
samples = SAMPLES
"#,
            15,
            1,
        ),
        // Orthographic, one-sided lighting, back-face culling: a triangle facing the camera
        // and one facing away (culled: the sphere behind it shows).
        (
            r#"
dim = 3
[camera]
position = [0.2, 0.1, 5.0]
look_at = [0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0]]
projection = "orthographic"
extent = 2.0
resolution = [30, 21]
[[lights]]
type = "point"
position = [1.0, 3.0, 4.0]
falloff = 2.0
[[objects]]
shape = "sphere"
subdivisions = 2
[[objects]]
shape = "mesh"
vertices = [[-1.9, -1.9, 2.0], [-0.7, -1.9, 2.0], [-1.9, -0.7, 2.0],
        [0.0, 0.0, 1.6], [0.0, 1.2, 1.6], [1.2, 0.0, 1.6]]
simplices = [[0, 1, 2], [3, 4, 5]]
[render]
shadows = true
cull_backfaces = true
two_sided = false
samples = SAMPLES
"#,
            150,
            20,
        ),
        // One cell.
        (
            r#"
dim = 3
[camera]
position = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0]]
fov = 10.0
resolution = 1
[[lights]]
type = "directional"
direction = [0.2, 0.3, 1.0]
[[objects]]
shape = "sphere"
subdivisions = 1
[render]
samples = SAMPLES
"#,
            1,
            0,
        ),
        // N = 4, orthographic, a retina of unequal sides with a side of 1.
        (
            r#"
dim = 4
[camera]
position = [0.3, 0.2, 0.1, 4.0]
look_at = [0.0, 0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
projection = "orthographic"
extent = 1.5
resolution = [5, 7, 1]
[[lights]]
type = "point"
position = [1.0, 2.0, 0.5, 3.0]
[[objects]]
shape = "hypercube"
transform = [{ rotate = { plane = [0, 3], degrees = 20.0 } }]
[render]
shadows = true
samples = SAMPLES
"#,
            12,
            0,
        ),
        // N = 5 and N = 7, perspective, with shadows between two objects.
        (
            r#"
dim = 5
[camera]
position = [0.2, 0.3, 0.1, 0.4, 3.0]
look_at = [0.0, 0.0, 0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0, 0.0]]
fov = 45.0
resolution = 8
[[lights]]
type = "point"
position = [1.0, 2.0, 0.5, 0.3, 2.5]
[[objects]]
shape = "sphere"
subdivisions = 1
[[objects]]
shape = "cross_polytope"
transform = [{ scale = 0.6 }, { translate = [0.65, 1.3, 0.32, 0.19, 1.6] }]
[render]
shadows = true
samples = SAMPLES
"#,
            300,
            200,
        ),
        (
            r#"
dim = 7
[camera]
position = [0.1, 0.2, 0.1, 0.1, 0.1, 0.1, 3.0]
look_at = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
  [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
  [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]]
fov = 50.0
resolution = 3
[[lights]]
type = "directional"
direction = [0.3, 1.0, 0.2, 0.1, 0.0, 0.2, 1.0]
[[objects]]
shape = "hypercube"
[render]
samples = SAMPLES
"#,
            700,
            0,
        ),
    ];
    for (text, lit, shadowed) in cases {
        for samples in [1, 2, 3] {
            let text = text.replace("SAMPLES", &samples.to_string());
            shades_as_one_ray_at_a_time(&text, lit, shadowed);
        }
    }
}

/// Shadow rays that skip the convex object they leave change nothing: the retina is the
/// same, bit for bit, when every object's convexity certificate is dropped (so that every
/// shadow ray is tested against everything).
fn skipping_convex_objects_changes_nothing<const N: usize>(scene: &mut Scene<N>) -> usize {
    let fast = trace(scene, &Progress::default()).unwrap();
    let convex = (scene.objects.iter())
        .filter(|o| o.convex.get().is_some())
        .count();
    // (A copy: the trees find their exact simplices in the objects they were built with.)
    std::sync::Arc::make_mut(&mut scene.objects)
        .iter_mut()
        .for_each(|o| o.convex = crate::convex::Certificate::none());
    let slow = trace(scene, &Progress::default()).unwrap();
    assert!(fast
        .rgba
        .iter()
        .zip(&slow.rgba)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    assert_eq!(fast, slow);
    convex
}

#[test]
fn shadow_rays_skipping_convex_objects_give_the_same_image() {
    // Convex objects that shadow each other, a light inside one of them, each kind of
    // light, and a non-convex lattice sphere, all in a convex room with the camera: the
    // shadow rays from its walls toward the directional light leave on the inner side and
    // are blocked by the room itself.
    for (dim, extra) in [(3, ""), (4, ", 0.3"), (5, ", 0.3, -0.2")] {
        let up: Vec<String> = (1..dim - 1)
            .map(|k| {
                let e: Vec<&str> = (0..dim)
                    .map(|i| if i == k { "1.0" } else { "0.0" })
                    .collect();
                format!("[{}]", e.join(", "))
            })
            .collect();
        let z = ", 0.0".repeat(dim - 3);
        let text = format!(
            r#"
dim = {dim}
ambient = [0.1, 0.1, 0.1]
[camera]
position = [0.5, 1.0, 6.0{extra}]
look_at = [0.0, 0.0, 0.0{z}]
up = [{up}]
fov = 50.0
resolution = 24
[[lights]]
type = "point"
position = [2.0, 3.0, 2.5{z}]
[[lights]]
type = "directional"
direction = [-1.0, 0.5, 0.2{extra}]
[[lights]]
type = "point"
position = [-0.6, 0.2, 0.4{z}]
color = [0.5, 0.2, 0.2]
[[objects]]
shape = "cross_polytope"
transform = [{{ scale = 0.8 }}, {{ translate = [-0.6, 0.2, 0.4{z}] }}]
[[objects]]
shape = "simplex"
transform = [{{ scale = 0.5 }}, {{ translate = [0.9, 0.8, 1.2{z}] }}]
[[objects]]
shape = "hypercube"
transform = [{{ scale = 7.0 }}]
material = {{ smooth = true }}
[[objects]]
shape = "sphere"
subdivisions = 1
transform = [{{ scale = 0.4 }}, {{ translate = [1.0, -0.6, -0.5{z}] }}]
[render]
shadows = true
two_sided = true
"#,
            up = up.join(", ")
        );
        let (_, mut any) = load_toml_str(&text, "test.toml", None).unwrap();
        let convex = crate::with_scene!(&mut any, scene, _N => skipping_convex_objects_changes_nothing(scene));
        assert_eq!(
            convex, 3,
            "N={dim}: the polytopes are convex, the sphere is not"
        );
    }
    // One convex object alone, lit from outside: its shadow rays are not traced at all.
    for dim in [3, 4] {
        let z = ", 0.0".repeat(dim - 3);
        let up = if dim == 3 {
            "[[0.0, 1.0, 0.0]]"
        } else {
            "[[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]"
        };
        let text = format!(
            r#"
dim = {dim}
[camera]
position = [0.5, 1.0, 4.0{z}]
look_at = [0.0, 0.0, 0.0{z}]
up = {up}
fov = 50.0
resolution = 16
[[lights]]
type = "point"
position = [2.0, 3.0, 2.5{z}]
[[objects]]
shape = "cross_polytope"
transform = [{{ rotate = {{ plane = [0, 2], degrees = 20.0 }} }}]
[render]
shadows = true
"#
        );
        let (_, mut any) = load_toml_str(&text, "test.toml", None).unwrap();
        let convex = crate::with_scene!(&mut any, scene, _N => skipping_convex_objects_changes_nothing(scene));
        assert_eq!(convex, 1, "N={dim}");
    }
}

/// The cube [−1, 1]^N seen head-on from 4·e_N through a one-cell retina, so that the ray hits
/// x = e_N on the face of normal e_N; lit by a point light on the axis, a directional light at
/// 45° from it (toward e_2), a light behind the face and a point light at 45° (toward e_1)
/// whose shadow ray a small cube blocks. Returns the colour [`shade_hit`] gives that ray.
fn head_on_face<const N: usize>(shadows: bool) -> [f64; 3] {
    let e = crate::testutil::unit_toml::<N>;
    // s·e_axis + t·e_N.
    let diagonal = |axis: usize, s: f64, t: f64| -> String {
        let v: Vec<String> = (0..N)
            .map(|i| match i {
                i if i == axis => format!("{s:?}"),
                i if i == N - 1 => format!("{t:?}"),
                _ => "0.0".into(),
            })
            .collect();
        format!("[{}]", v.join(", "))
    };
    let up: Vec<String> = (1..N - 1).map(|k| e(k, 1.0)).collect();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let text = format!(
        r#"
dim = {N}
ambient = [0.2, 0.2, 0.2]
[camera]
position = {eye}
look_at = {origin}
up = [{up}]
fov = 10.0
resolution = 1
[[lights]]
type = "point"
position = {axis}
color = [0.8, 0.6, 0.4]
falloff = 2.0
[[lights]]
type = "directional"
direction = {tilted}
color = [0.3, 0.5, 0.7]
[[lights]]
type = "directional"
direction = {behind}
[[lights]]
type = "point"
position = {far}
color = [0.1, 0.2, 0.3]
[[objects]]
shape = "hypercube"
material = {{ color = [0.5, 0.4, 0.3], ambient = 0.5, diffuse = 0.8, specular = 0.25, shininess = 10.0 }}
[[objects]]
shape = "hypercube"
transform = [{{ scale = 0.1 }}, {{ translate = {blocker} }}]
[render]
shadows = {shadows}
"#,
        eye = e(N - 1, 4.0),
        origin = e(0, 0.0),
        up = up.join(", "),
        axis = e(N - 1, 3.0),
        tilted = diagonal(1, 1.0, 1.0),
        behind = e(N - 1, -1.0),
        far = diagonal(0, 2.0 * h, 1.0 + 2.0 * h),
        blocker = diagonal(0, h, 1.0 + h),
    );
    let (_, any) = load_toml_str(&text, "head_on.toml", None).unwrap();
    crate::with_scene!(&any, s, M => {
        assert_eq!(M, N);
        let ray = s.camera.ray(&[0.0; N][..N - 1]);
        let hit = s.instances.closest_hit(&ray, 0.0, f64::INFINITY, &|_| true).unwrap();
        assert!((hit.t - 3.0).abs() < 1e-12 && s.locate(hit.prim).0 == 0);
        shade_hit(s, &ray, &hit)
    })
}

#[test]
fn shade_hit_is_the_course_formula_on_a_face_seen_head_on() {
    // n̂ = v̂ = e_N at x = e_N. Light 1 along n̂ at distance 2 with falloff 2: n̂·l̂ = 1, ĥ = n̂,
    // a = 2^−2. Light 2 at 45°: n̂·l̂ = cos 45°, n̂·ĥ = cos 22.5°. Light 3 behind: nothing.
    // Light 4 at 45° and distance 2, falloff 0: as light 2 geometrically, but shadowed.
    let (c, ka, kd, ks, s, ambient) = ([0.5, 0.4, 0.3], 0.5, 0.8, 0.25, 10.0, 0.2);
    let (i1, i2, i4) = ([0.8, 0.6, 0.4], [0.3, 0.5, 0.7], [0.1, 0.2, 0.3]);
    let cos45 = std::f64::consts::FRAC_1_SQRT_2;
    let spec45 = (std::f64::consts::PI / 8.0).cos().powf(s);
    let expected = |shadows: bool| -> [f64; 3] {
        std::array::from_fn(|k| {
            let lit = ka * ambient * c[k]
                + 0.25 * i1[k] * (kd * c[k] + ks)
                + i2[k] * (kd * c[k] * cos45 + ks * spec45);
            lit + if shadows {
                0.0
            } else {
                i4[k] * (kd * c[k] * cos45 + ks * spec45)
            }
        })
    };
    fn check<const N: usize>(expected: &dyn Fn(bool) -> [f64; 3]) {
        for shadows in [true, false] {
            let got = head_on_face::<N>(shadows);
            let want = expected(shadows);
            for k in 0..3 {
                assert!(
                    (got[k] - want[k]).abs() < 1e-12 * want[k],
                    "N={N}, shadows {shadows}: {got:?} vs {want:?}"
                );
            }
        }
    }
    check::<3>(&expected);
    check::<4>(&expected);
    check::<5>(&expected);
}

#[test]
fn scenes_built_with_the_morton_bvh_render_bit_for_bit_as_with_the_sah_one() {
    // The two builds differ only in the tree's shape; every query returns the least (t, id),
    // so retinas (colour, depth, normals, ids) and flat normals must agree bit for bit:
    // shadows, convexity certificates, back-face culling, a degenerate simplex, an elevation
    // map with smooth normals and a colormap, in 3D and 4D.
    fn both<const N: usize>(text: &str) {
        let (desc, _) = load_toml_str(text, "both.toml", None).unwrap();
        let (sah, mor) = sah_and_morton::<N>(&desc);
        assert!(
            sah.instances.trees() != mor.instances.trees(),
            "the trees should differ"
        );
        assert_eq!(sah.skipped_degenerate, mor.skipped_degenerate);
        assert_eq!(sah.extent.to_bits(), mor.extent.to_bits());
        assert_eq!(sah.simplex_count(), mor.simplex_count());
        for g in 0..sah.simplex_count() as u32 {
            assert_eq!(sah.flat_normal(g), mor.flat_normal(g), "flat normal {g}");
        }
        sah.find_certificates();
        mor.find_certificates();
        for (a, b) in sah.objects.iter().zip(mor.objects.iter()) {
            assert_eq!(a.convex.get(), b.convex.get());
        }
        let p = Progress::default();
        let (ra, rb) = (trace(&sah, &p).unwrap(), trace(&mor, &p).unwrap());
        assert!(ra.rgba.iter().any(|&v| v > 0.0), "something is seen");
        assert_eq!(ra.rgba, rb.rgba);
        assert_eq!(ra.depth, rb.depth);
        assert_eq!(ra.normal, rb.normal);
        assert_eq!(ra.object_id, rb.object_id);
    }
    both::<4>(
        r#"
dim = 4
[camera]
position = [0.6, 0.8, 1.1, 3.0]
look_at = [0.0, 0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
fov = 50
resolution = 24
[[lights]]
type = "directional"
direction = [0.3, 0.6, 0.4, 1.0]
[[objects]]
shape = "hypercube"
transform = [{ scale = 0.4 }, { translate = [0.5, 0.0, 0.0, 0.4] }]
[[objects]]
shape = "elevation"
field = [[[0.0, 0.3, 0.1], [0.2, 0.9, 0.2], [0.1, 0.2, 0.0]], [[0.1, 0.5, 0.1], [0.4, 1.0, 0.3], [0.0, 0.3, 0.2]], [[0.0, 0.1, 0.0], [0.1, 0.4, 0.1], [0.0, 0.1, 0.0]]]
height = 0.6
smooth = true
material = { colormap = "viridis" }
[[objects]]
shape = "mesh"
vertices = [[0.0, 0.0, 0.0, -1.0], [1.0, 0.0, 0.0, -1.0], [0.0, 1.0, 0.0, -1.0], [0.0, 0.0, 1.0, -1.0]]
simplices = [[0, 1, 2, 3], [0, 0, 1, 2]]
[render]
samples = 2
shadows = true
cull_backfaces = true
"#,
    );
    both::<3>(
        r#"
dim = 3
[camera]
position = [0.0, 0.5, 4.0]
look_at = [0.0, 0.0, 0.0]
up = [[0.0, 1.0, 0.0]]
fov = 40
resolution = [30, 20]
[[lights]]
type = "point"
position = [2.0, 3.0, 2.0]
[[objects]]
shape = "sphere"
subdivisions = 2
material = { smooth = true }
[[objects]]
shape = "hypercube"
transform = [{ scale = 0.5 }, { translate = [0.8, 0.3, 0.9] }]
[render]
shadows = true
"#,
    );
}

#[test]
fn n_cubes_whose_facets_are_flat_cells_render_bit_for_bit_as_their_simplices() {
    // The SAH build holds each (N−1)!-simplex facet of an N-cube as a flat cell; the Morton
    // build holds no cells. Retinas (colour with shadows and culling, depth, normals, ids) and
    // flat normals agree bit for bit, with a cube seen from outside and one around the camera
    // and the light (whose facets the first one shadows).
    fn both<const N: usize>() {
        let axis = crate::testutil::unit_toml::<N>;
        let up: Vec<String> = (1..N - 1).map(|k| axis(k, 1.0)).collect();
        let position: Vec<String> = (0..N)
            .map(|i| format!("{:?}", 0.9 + 0.35 * i as f64))
            .collect();
        let res = if N <= 5 {
            10
        } else if N == 6 {
            6
        } else {
            4
        };
        let text = format!(
            "dim = {N}\n[camera]\nposition = [{}]\nlook_at = {}\nup = [{}]\nfov = 55\n\
             resolution = {res}\n[[lights]]\ntype = \"point\"\nposition = {}\n\
             [[objects]]\nshape = \"hypercube\"\n\
             transform = [{{ rotate = {{ plane = [0, {}], degrees = 20 }} }}]\n\
             [[objects]]\nshape = \"hypercube\"\ntransform = [{{ scale = 9.0 }}]\n\
             material = {{ color = [0.9, 0.8, 0.7] }}\n\
             [render]\nsamples = 2\nshadows = true\n",
            position.join(", "),
            axis(0, 0.0),
            up.join(", "),
            axis(N - 1, 2.5),
            N - 1
        );
        let (desc, _) = load_toml_str(&text, "cube.toml", None).unwrap();
        let (sah, mor) = sah_and_morton::<N>(&desc);
        assert_eq!(
            sah.instances.cell_count(),
            4 * N,
            "N={N}: every facet is a cell"
        );
        assert_eq!(mor.instances.cell_count(), 0);
        for g in 0..sah.simplex_count() as u32 {
            assert_eq!(
                sah.flat_normal(g),
                mor.flat_normal(g),
                "N={N}: flat normal {g}"
            );
        }
        let p = Progress::default();
        let (ra, rb) = (trace(&sah, &p).unwrap(), trace(&mor, &p).unwrap());
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(
            ra.object_id.contains(&0) && ra.object_id.contains(&1),
            "N={N}: both cubes seen"
        );
        assert_eq!(bits(&ra.rgba), bits(&rb.rgba), "N={N}");
        assert_eq!(bits(&ra.depth), bits(&rb.depth), "N={N}");
        assert_eq!(bits(&ra.normal), bits(&rb.normal), "N={N}");
        assert_eq!(ra.object_id, rb.object_id, "N={N}");
        assert_eq!(ra.primitive_id, rb.primitive_id, "N={N}");
    }
    both::<5>();
    both::<6>();
    both::<7>();
}

/// Every slab cut of the retina, traced slab by slab and concatenated, is the retina traced
/// whole, bit for bit (jittered samples, culling, shadows, a surface splatted over the cells it
/// covers, N = 2 … 5); ranges that are not whole chunks are refused.
#[test]
fn slabs_traced_apart_and_concatenated_are_the_whole_retina() {
    fn check<const N: usize>(scene: &Scene<N>) -> usize {
        let whole = trace(scene, &Progress::default()).unwrap();
        let total = scene.camera.cell_count();
        let mut cuts = 0;
        for count in [1, 2, 3, 7, 1000] {
            let cut = slabs(scene, count);
            assert_eq!(cut.first().unwrap().start, 0);
            assert_eq!(cut.last().unwrap().end, total);
            assert!(cut
                .windows(2)
                .all(|w| w[0].end == w[1].start && w[0].start < w[0].end));
            assert!(cut.len() <= count);
            let mut joined = Retina {
                dim: N,
                shape: scene.camera.numpy_shape(),
                rgba: vec![],
                depth: vec![],
                normal: vec![],
                object_id: vec![],
                primitive_id: vec![],
            };
            for range in cut.clone() {
                let progress = Progress::default();
                let part = trace_slab(scene, &progress, range.clone()).unwrap();
                assert_eq!(part.shape, vec![range.len()]);
                assert_eq!(
                    progress.done.load(std::sync::atomic::Ordering::Relaxed),
                    range.len()
                );
                joined.rgba.extend(part.rgba);
                joined.depth.extend(part.depth);
                joined.normal.extend(part.normal);
                joined.object_id.extend(part.object_id);
                joined.primitive_id.extend(part.primitive_id);
            }
            // The first cell whose bits differ, if any (not the whole arrays in the message).
            let bits = |r: &Retina, c: usize| {
                let f = |v: &[f32], w: usize| {
                    v[c * w..(c + 1) * w]
                        .iter()
                        .map(|x| x.to_bits())
                        .collect::<Vec<_>>()
                };
                (
                    f(&r.rgba, 4),
                    f(&r.depth, 1),
                    f(&r.normal, N),
                    r.object_id[c],
                    r.primitive_id[c],
                )
            };
            assert_eq!(joined.depth.len(), total);
            let differs = (0..total).find(|&c| bits(&joined, c) != bits(&whole, c));
            assert_eq!(
                differs, None,
                "{count} slabs, N = {N}: first differing cell"
            );
            cuts = cuts.max(cut.len());
        }
        // Not whole chunks, reversed, or beyond the retina: refused, naming the argument.
        let chunk = slabs(scene, 1000)[0].len();
        let mut bads = vec![1..total, 0..total + 1, chunk..chunk - 1];
        if total > chunk + 1 {
            bads.push(0..chunk + 1); // an end inside a chunk
        }
        for bad in bads {
            match trace_slab(scene, &Progress::default(), bad.clone()) {
                Err(crate::NdError::Value { arg, message }) => {
                    assert_eq!(arg, "cells");
                    assert!(message.contains("whole chunks"), "{message}");
                }
                other => panic!("{bad:?}: {:?}", other.map(|r| r.shape)),
            }
        }
        assert!(whole.object_id.iter().any(|&o| o >= 0));
        cuts
    }
    let common = "[[lights]]\ntype = \"point\"\nposition = [2.0, 2.5, 1.5, 2.0, 1.0]\n\
                  [[objects]]\nshape = \"hypercube\"\ntransform = [{ scale = 0.4 }, { rotate = \
                  { plane = [0, 1], degrees = 20 } }]\n[[objects]]\nshape = \"sphere\"\n\
                  subdivisions = 2\ntransform = [{ scale = 0.3 }, { translate = [0.5, 0.4, 0.3, \
                  0.2, 0.1] }]\n[render]\nshadows = true\ncull_backfaces = true\nsamples = 3\n";
    let camera = |dim: usize, res: &str| {
        let pos: Vec<String> = (0..dim)
            .map(|i| format!("{}", 1.0 + 0.7 * i as f64))
            .collect();
        // Up vectors e_1 … e_{N−2}.
        let up: Vec<String> = (1..dim - 1)
            .map(|k| {
                format!(
                    "[{}]",
                    (0..dim)
                        .map(|i| if i == k { "1" } else { "0" })
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
            .collect();
        let up = if dim > 2 {
            format!("up = [{}]\n", up.join(", "))
        } else {
            String::new()
        };
        format!(
            "dim = {dim}\n[camera]\nposition = [{}]\nlook_at = [{}]\n{up}fov = 60.0\n\
             resolution = {res}\n",
            pos.join(", "),
            vec!["0.0"; dim].join(", ")
        )
    };
    let fit = |text: String, dim: usize| {
        // Points of the common text have 5 coordinates: keep the scene's `dim`.
        text.replace(
            "[2.0, 2.5, 1.5, 2.0, 1.0]",
            &format!("[{}]", vec!["2.0"; dim].join(", ")),
        )
        .replace(
            "[0.5, 0.4, 0.3, 0.2, 0.1]",
            &format!("[{}]", vec!["0.3"; dim].join(", ")),
        )
    };
    let parsed = |text: String| load_toml_str(&text, "slabs.toml", None).unwrap().1;
    let mut most = 0;
    // Retinas of one chunk and of several: N = 2 (chunks in memory order), N = 3 (strips of
    // tiled rows, the last chunk short), N = 4 and 5.
    for (dim, res) in [
        (2, "300"),
        (2, "13000"),
        (3, "[61, 47]"),
        (3, "[128, 100]"),
        (4, "[23, 19, 17]"),
        (5, "[12, 11, 10, 9]"),
        (5, "[9, 7, 6, 5]"),
    ] {
        let text = fit(format!("{}{common}", camera(dim, res)), dim);
        most = most.max(crate::with_scene!(&parsed(text), s, _N => check(s)));
    }
    // A 4D scene with a surface splatted over part of the retina.
    let surface = fit(
        format!(
            "{}{common}[[objects]]\nshape = \"surface\"\nvertices = [[-1, -1, 0, 0.5], \
             [1, -1, 0, 0.5], [1, 1, 0, 0.5]]\ntriangles = [[0, 1, 2]]\nwidth = 2.0\n\
             material = {{ opacity = 0.6 }}\n",
            camera(4, "[40, 36, 30]")
        ),
        4,
    );
    most = most.max(crate::with_scene!(&parsed(surface), s, _N => check(s)));
    assert!(most >= 3, "the retinas cut into several slabs ({most})");
}

/// The scene `desc` built with the SAH tree and with the Morton tree.
fn sah_and_morton<const N: usize>(desc: &crate::scene::SceneDesc) -> (Scene<N>, Scene<N>) {
    let build = |morton_min| {
        let min = crate::accel::INSTANCE_MIN;
        crate::scene::build::build_using::<N>(desc, None, None, (morton_min, min)).unwrap()
    };
    (build(usize::MAX), build(0))
}

#[test]
fn the_specular_power_is_powf_within_its_bound() {
    // Whole exponents up to 1024 by squaring: within s·2⁻⁵² (relative) of the correctly
    // rounded x^s (powf, itself within an ulp), on random bases and at the ends; other
    // exponents are powf's bits.
    use super::shade::power;
    let mut rng = SplitMix::new(7, 0);
    let mut unit = || (rng.next() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    for s in (0..=1024u32).chain([20, 32, 64, 100]) {
        let s = s as f64;
        for x in (0..64)
            .map(|_| unit())
            .chain([0.0, 1.0, 0.5, 1.0 - f64::EPSILON])
        {
            let (got, want) = (power(x, s), x.powf(s));
            let bound = (s + 2.0) * f64::EPSILON * want;
            assert!(
                (got - want).abs() <= bound || want < 1e-290,
                "{x}^{s}: {got} vs {want}"
            );
        }
    }
    assert_eq!(power(0.0, 0.0), 1.0);
    assert_eq!(power(0.3, 0.0), 1.0);
    assert_eq!(power(0.0, 20.0), 0.0);
    assert_eq!(power(0.5, 3.0), 0.125);
    for (x, s) in [
        (0.7, 2.5),
        (0.7, 1025.0),
        (0.7, 0.1),
        (0.9, 2048.0),
        (0.8, 1e300),
    ] {
        assert_eq!(power(x, s).to_bits(), x.powf(s).to_bits(), "{x}^{s}");
    }
}
