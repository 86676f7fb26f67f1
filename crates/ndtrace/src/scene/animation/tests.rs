use super::*;
use crate::linalg::{det, identity, transpose};
use crate::rotation::RollingAngle;
use crate::scene::{load_toml_str, to_toml};
use crate::testutil::load_error;

const SPIN: &str = r#"
dim = 4
[camera]
position = [0, 0, 0, 5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 40
resolution = 4

[[objects]]
shape = "hypercube"
transform = [{ scale = 0.5 }]

[[objects]]
shape = "simplex"

[animation]
frames = 5
sweep = { plane = [0, 3], degrees = [0, 90] }
"#;

fn close<const N: usize>(a: &Matrix<N>, b: &Matrix<N>, tol: f64) -> bool {
    (0..N).all(|i| (0..N).all(|j| (a[i][j] - b[i][j]).abs() <= tol))
}

fn rows<const N: usize>(t: &TransformDesc) -> Matrix<N> {
    match t {
        TransformDesc::Matrix(r) => std::array::from_fn(|i| std::array::from_fn(|j| r[i][j])),
        other => panic!("expected a matrix step, got {other:?}"),
    }
}

#[test]
fn a_sweep_appends_the_plane_rotation_of_each_frame_to_every_object() {
    let (desc, _) = load_toml_str(SPIN, "spin.toml", None).unwrap();
    for k in 0..5u32 {
        let f = frame_desc(&desc, k).unwrap();
        assert!(f.animation.is_none(), "a frame is a still");
        let want = plane_rotation::<4>(0, 3, (22.5 * f64::from(k)).to_radians());
        assert_eq!(f.objects[0].transform.len(), 2, "appended after the scale");
        assert!(close(&rows::<4>(&f.objects[0].transform[1]), &want, 1e-15));
        assert!(close(&rows::<4>(&f.objects[1].transform[0]), &want, 1e-15));
        assert_eq!(f.camera, desc.camera);
    }
    // Frame 0 of a sweep from 0° is the identity; the frame itself builds.
    let f0 = frame_desc(&desc, 0).unwrap();
    assert!(close(
        &rows::<4>(&f0.objects[1].transform[0]),
        &identity(),
        0.0
    ));
    let text = to_toml(&frame_desc(&desc, 3).unwrap()).unwrap();
    load_toml_str(&text, "frame.toml", None).unwrap();
}

#[test]
fn periodic_frames_stop_short_of_the_end() {
    let (desc, _) = load_toml_str(SPIN, "spin.toml", None).unwrap();
    let a = desc.animation.clone().unwrap();
    assert_eq!(frame_time(&a, 4), 1.0);
    let p = AnimationDesc {
        periodic: true,
        ..a.clone()
    };
    assert_eq!(frame_time(&p, 4), 0.8);
    let one = AnimationDesc { frames: 1, ..a };
    assert_eq!(frame_time(&one, 0), 0.0);
}

#[test]
fn the_camera_target_turns_position_view_and_up_about_the_center() {
    let text = SPIN.replace(
        "frames = 5",
        "frames = 3\ntarget = \"camera\"\ncenter = [0, 0, 0, 1]",
    );
    let (desc, _) = load_toml_str(&text, "spin.toml", None).unwrap();
    let f = frame_desc(&desc, 2).unwrap();
    let m = plane_rotation::<4>(0, 3, 90f64.to_radians());
    // position (0,0,0,5) − c = (0,0,0,4) ↦ M·(0,0,0,4) = (−4,0,0,0) (R_03 turns e3 to −e0).
    let p = &f.camera.position;
    assert!(
        (p[0] + 4.0).abs() < 1e-12 && p[1].abs() < 1e-12 && (p[3] - 1.0).abs() < 1e-12,
        "{p:?}"
    );
    let l = f.camera.look_at.as_ref().unwrap();
    assert!((l[0] + m[0][3]).abs() < 1e-12 && (l[3] - 1.0 + m[3][3]).abs() < 1e-12);
    assert_eq!(f.objects, desc.objects, "objects stay");
    // The built camera is the turned one: its orientation is M times the original.
    let o0 = with_scene_orientation(&desc);
    let o1 = with_scene_orientation(&f);
    assert!(close(&o1, &crate::linalg::mat_mul(&m, &o0), 1e-12));
}

fn with_scene_orientation(desc: &SceneDesc) -> Matrix<4> {
    let d = SceneDesc {
        animation: None,
        ..desc.clone()
    };
    match crate::scene::build_desc(&d, "test", None).unwrap() {
        crate::scene::AnyScene::D4(s) => s.camera.orientation,
        _ => panic!("a 4D scene"),
    }
}

#[test]
fn an_orientation_camera_and_listed_objects() {
    let text = SPIN
        .replace(
            "look_at = [0, 0, 0, 0]\nup = [[0, 1, 0, 0], [0, 0, 1, 0]]",
            "orientation = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, -1], [0, 0, 1, 0]]",
        )
        .replace("frames = 5", "frames = 2\ntarget = [1]");
    let (desc, _) = load_toml_str(&text, "spin.toml", None).unwrap();
    let f = frame_desc(&desc, 1).unwrap();
    assert_eq!(f.objects[0], desc.objects[0], "object 0 is not a target");
    assert_eq!(f.objects[1].transform.len(), 1);
    let cam = SPIN.replace("frames = 5", "frames = 2\ntarget = \"camera\"");
    let cam = cam.replace(
        "look_at = [0, 0, 0, 0]\nup = [[0, 1, 0, 0], [0, 0, 1, 0]]",
        "orientation = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, -1], [0, 0, 1, 0]]",
    );
    let (desc, _) = load_toml_str(&cam, "spin.toml", None).unwrap();
    let f = frame_desc(&desc, 1).unwrap();
    let o = crate::scene::fields::matrix_rows::<4>(f.camera.orientation.as_ref().unwrap(), "o")
        .unwrap();
    let m = plane_rotation::<4>(0, 3, 90f64.to_radians());
    let o0 = crate::scene::fields::matrix_rows::<4>(desc.camera.orientation.as_ref().unwrap(), "o")
        .unwrap();
    assert!(close(&o, &crate::linalg::mat_mul(&m, &o0), 1e-12));
}

#[test]
fn a_double_quaternion_slerp_runs_between_its_two_frames() {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let text = SPIN.replace(
            "sweep = { plane = [0, 3], degrees = [0, 90] }",
            &format!("slerp = {{ from = [[1, 0, 0, 0], [1, 0, 0, 0]], to = [[{h}, {h}, 0, 0], [{h}, -{h}, 0, 0]] }}"),
        );
    let (desc, _) = load_toml_str(&text, "q.toml", None).unwrap();
    let a = desc.animation.as_ref().unwrap();
    assert!(close(&motion::<4>(a, 0.0).unwrap(), &identity(), 1e-15));
    let end = so4_from_quaternions(&[h, h, 0.0, 0.0], &[h, -h, 0.0, 0.0]);
    assert!(close(&motion::<4>(a, 1.0).unwrap(), &end, 1e-12));
    // q = p̄ = (cos, sin·e1): v ↦ q v q turns the (0,1) plane by 2·45°·t and fixes 2 and 3.
    let mid = motion::<4>(a, 0.5).unwrap();
    assert!(
        close(&mid, &plane_rotation::<4>(0, 1, 45f64.to_radians()), 1e-12),
        "{mid:?}"
    );
    let f = frame_desc(&desc, 4).unwrap();
    assert!(close(&rows::<4>(&f.objects[1].transform[0]), &end, 1e-12));
}

#[test]
fn a_rolling_path_accumulates_one_step_per_segment() {
    let text = SPIN.replace(
        "sweep = { plane = [0, 3], degrees = [0, 90] }",
        "rolling = { path = [[0, 0, 0], [2, 0, 0], [2, 1, 0]], radius = 1.5 }",
    );
    let (desc, _) = load_toml_str(&text, "r.toml", None).unwrap();
    let a = desc.animation.as_ref().unwrap();
    let c = RollingAngle::Course;
    let m1 = rolling_ball::<4>(&[2.0, 0.0, 0.0], 1.5, c);
    let m2 = rolling_ball::<4>(&[0.0, 1.0, 0.0], 1.5, c);
    assert!(close(
        &motion::<4>(a, 1.0).unwrap(),
        &crate::linalg::mat_mul(&m2, &m1),
        1e-14
    ));
    // t = 1/3 is halfway along the first segment (total length 3).
    let half = rolling_ball::<4>(&[1.0, 0.0, 0.0], 1.5, c);
    assert!(close(&motion::<4>(a, 1.0 / 3.0).unwrap(), &half, 1e-14));
    assert!(close(&motion::<4>(a, 0.0).unwrap(), &identity(), 0.0));
    for k in 0..5 {
        let m = motion::<4>(a, frame_time(a, k)).unwrap();
        assert!((det(&m) - 1.0).abs() < 1e-12);
        assert!(close(
            &crate::linalg::mat_mul(&transpose(&m), &m),
            &identity(),
            1e-12
        ));
    }
    let arc = AnimationDesc {
        rolling: Some(RollingPathDesc {
            angle: Some(RollingAngle::Arc),
            ..a.rolling.clone().unwrap()
        }),
        ..a.clone()
    };
    let m = motion::<4>(&arc, 1.0 / 3.0).unwrap();
    assert!(close(
        &m,
        &rolling_ball::<4>(&[1.0, 0.0, 0.0], 1.5, RollingAngle::Arc),
        1e-14
    ));
}

#[test]
fn bad_animation_tables_are_located_errors() {
    let line = SPIN
        .lines()
        .position(|l| l.starts_with("frames = 5"))
        .unwrap()
        + 1;
    assert_eq!(
        load_error(&SPIN.replace("frames = 5", "frames = 0")),
        format!("scene.toml:{line}:10: animation.frames: must be in 1..={MAX_FRAMES}, got 0")
    );
    let cases = [
        (
            "degrees = [0, 90] }",
            "degrees = [0, 90] }\nfps = -1",
            "animation.fps: must be a positive number",
        ),
        (
            "plane = [0, 3]",
            "plane = [0, 4]",
            "animation.sweep.plane: expected two different axes in 0..3",
        ),
        (
            "frames = 5",
            "frames = 5\ntarget = \"lights\"",
            "animation.target: expected \"objects\", \"camera\"",
        ),
        (
            "frames = 5",
            "frames = 5\ntarget = [0, 2]",
            "animation.target[1]: object 2 does not exist",
        ),
        (
            "frames = 5",
            "frames = 5\ntarget = [1, 0, 1]",
            "animation.target[2]: object 1 is already listed at animation.target[0]",
        ),
        (
            "frames = 5",
            "frames = 5\ntarget = []",
            "animation.target: lists no objects",
        ),
        (
            "frames = 5",
            "frames = 5\ncenter = [0, 0]",
            "animation.center: expected 4 numbers (dim = 4), got 2",
        ),
        (
            "frames = 5",
            "frames = 5\nrolling = { path = [[0, 0, 0], [1, 0, 0]], radius = 1 }",
            "animation: give exactly one motion",
        ),
        (
            "sweep = { plane = [0, 3], degrees = [0, 90] }",
            "",
            "animation: give exactly one motion",
        ),
        (
            "sweep = { plane = [0, 3], degrees = [0, 90] }",
            "rolling = { path = [[0, 0, 0]], radius = 1 }",
            "animation.rolling.path: expected at least two",
        ),
        (
            "sweep = { plane = [0, 3], degrees = [0, 90] }",
            "rolling = { path = [[0, 0, 0], [1, 0]], radius = 1 }",
            "animation.rolling.path[1]: expected 3 numbers",
        ),
        (
            "sweep = { plane = [0, 3], degrees = [0, 90] }",
            "rolling = { path = [[0, 0, 0], [1, 0, 0]], radius = 0 }",
            "animation.rolling.radius: must be a positive number",
        ),
        (
            "sweep = { plane = [0, 3], degrees = [0, 90] }",
            "slerp = { from = [[1, 0, 0, 0], [1, 0, 0, 0]], to = [[1, 1, 0, 0], [1, 0, 0, 0]] }",
            "animation.slerp.to[0]: not a unit quaternion (|q| = 1.414",
        ),
        (
            "sweep = { plane = [0, 3], degrees = [0, 90] }",
            "sweeep = 1",
            "did you mean \"sweep\"",
        ),
    ];
    for (from, to, want) in cases {
        let e = load_error(&SPIN.replace(from, to));
        assert!(e.contains(want), "{to:?}: {e}");
    }
    let three = SPIN
        .replace("dim = 4", "dim = 3")
        .replace("[0, 0, 0, 5]", "[0, 0, 5]")
        .replace("[0, 0, 0, 0]", "[0, 0, 0]")
        .replace("up = [[0, 1, 0, 0], [0, 0, 1, 0]]", "up = [0, 1, 0]")
        .replace(
            "sweep = { plane = [0, 3], degrees = [0, 90] }",
            "slerp = { from = [[1, 0, 0, 0], [1, 0, 0, 0]], to = [[1, 0, 0, 0], [1, 0, 0, 0]] }",
        );
    let e = load_error(&three);
    assert!(
        e.contains("animation.slerp: quaternion pairs rotate 4D space, but dim = 3"),
        "{e}"
    );
    let (desc, _) = load_toml_str(SPIN, "spin.toml", None).unwrap();
    let e = frame_desc(&desc, 5).unwrap_err();
    assert!(e.message.contains("frame 5 does not exist"), "{e:?}");
    let still = SceneDesc {
        animation: None,
        ..desc
    };
    assert!(frame_desc(&still, 0)
        .unwrap_err()
        .message
        .contains("no [animation] table"));
}
