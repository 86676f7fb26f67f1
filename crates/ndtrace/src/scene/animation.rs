//! `[animation]`: a sequence of frames in which one rotation moves the objects or the camera.
//!
//! ```toml
//! [animation]
//! frames = 48                                   # K
//! periodic = true                               # t = k/K: a full turn loops seamlessly
//! target = "objects"                            # or "camera", or [0, 2]
//! sweep = { plane = [0, 3], degrees = [0, 360] }
//! # or, in 4D: slerp = { from = [q0, p0], to = [q1, p1] }
//! # or: rolling = { path = [[0, 0, 0], [1, 0, 0], [1, 1, 0]], radius = 1 }
//! ```
//!
//! Frame k is the scene as written with the motion's rotation M(t_k) applied about `center`:
//! appended to each target object's transform (so it acts after the object's own steps), or
//! applied to the camera (position, look_at, up or orientation), which makes the world appear
//! turned by M⁻¹.
//!
//! The motions, each a rotation of R^N:
//! - `sweep`: the plane rotation R_ij(θ) (rotations paper, eq. 6) with θ linear in t;
//! - `slerp` (N = 4): v ↦ q·v·p̄ with q and p slerped between two unit-quaternion pairs, the
//!   geodesic between two 4D frames (course notes, "Quaternions and 4D rotations");
//! - `rolling`: the rolling ball (rotations paper, eq. 5) driven along a polyline of controller
//!   positions as a mouse would drive it: one rolling step per segment, accumulated in world
//!   coordinates (M = M_m ⋯ M_1), the segment reached at t travelled in proportion to its length.

use super::desc::*;
use super::errors::PathError;
use super::fields::{matrix_rows, vec_n, R};
use crate::linalg::{add, mat_mul, mat_vec, sub, Matrix, Vector};
use crate::rotation::{
    check_plane, plane_rotation, rolling_ball, scene_quaternion, slerp_so4, so4_from_quaternions,
    Quat,
};
use crate::{with_dim, NdError};

/// Largest number of frames accepted.
pub const MAX_FRAMES: u32 = 100_000;

/// The time t ∈ [0, 1] of frame `k`: k/(K−1), or k/K when `periodic` (0 for a single frame).
pub fn frame_time(a: &AnimationDesc, k: u32) -> f64 {
    let n = f64::from(a.frames);
    if a.periodic {
        f64::from(k) / n
    } else if a.frames <= 1 {
        0.0
    } else {
        f64::from(k) / (n - 1.0)
    }
}

/// Checks the whole `[animation]` table for dimension N with `objects` objects (called when
/// the scene is built, so that errors carry the table's position in the file).
pub(crate) fn check<const N: usize>(a: &AnimationDesc, objects: usize) -> R<()> {
    if a.frames == 0 || a.frames > MAX_FRAMES {
        return Err(PathError::new(
            "animation.frames",
            format!("must be in 1..={MAX_FRAMES}, got {}", a.frames),
        ));
    }
    if !(a.fps.is_finite() && a.fps > 0.0) {
        return Err(PathError::new(
            "animation.fps",
            format!("must be a positive number, got {}", a.fps),
        ));
    }
    match &a.target {
        AnimationTarget::Named(n) if n == "objects" || n == "camera" => {}
        AnimationTarget::Named(n) => {
            return Err(PathError::new(
                "animation.target",
                format!("expected \"objects\", \"camera\" or a list of object indices, got {n:?}"),
            ))
        }
        AnimationTarget::Objects(ids) => {
            if ids.is_empty() {
                return Err(PathError::new(
                    "animation.target",
                    "lists no objects: give at least one index, \"objects\" or \"camera\"",
                ));
            }
            for (k, &i) in ids.iter().enumerate() {
                if i >= objects {
                    return Err(PathError::new(
                        format!("animation.target[{k}]"),
                        format!("object {i} does not exist (the scene has {objects} objects)"),
                    ));
                }
                if let Some(first) = ids[..k].iter().position(|&j| j == i) {
                    return Err(PathError::new(
                        format!("animation.target[{k}]"),
                        format!("object {i} is already listed at animation.target[{first}]"),
                    ));
                }
            }
        }
    }
    center::<N>(a)?;
    motion::<N>(a, 0.0).map(|_| ())
}

fn center<const N: usize>(a: &AnimationDesc) -> R<Vector<N>> {
    match &a.center {
        None => Ok([0.0; N]),
        Some(c) => vec_n::<N>(c, "animation.center"),
    }
}

fn unit_quaternion(q: &Quat, path: &str, symbol: &str) -> R<Quat> {
    scene_quaternion(q, "quaternion", symbol).map_err(|message| PathError::new(path, message))
}

/// The rotation M(t) of the animation's one motion (validated on the way).
pub fn motion<const N: usize>(a: &AnimationDesc, t: f64) -> R<Matrix<N>> {
    let given = [a.sweep.is_some(), a.slerp.is_some(), a.rolling.is_some()];
    if given.iter().filter(|&&g| g).count() != 1 {
        return Err(PathError::new(
            "animation",
            "give exactly one motion: sweep, slerp or rolling",
        ));
    }
    if let Some(s) = &a.sweep {
        let [i, j] = s.plane;
        check_plane(i, j, N).map_err(|m| PathError::new("animation.sweep.plane", m))?;
        if let Some(k) = s.degrees.iter().position(|d| !d.is_finite()) {
            return Err(PathError::new(
                format!("animation.sweep.degrees[{k}]"),
                "must be finite",
            ));
        }
        let deg = s.degrees[0] + t * (s.degrees[1] - s.degrees[0]);
        return Ok(plane_rotation::<N>(i, j, deg.to_radians()));
    }
    if let Some(s) = &a.slerp {
        if N != 4 {
            return Err(PathError::new(
                "animation.slerp",
                format!("quaternion pairs rotate 4D space, but dim = {N}"),
            ));
        }
        let q0 = unit_quaternion(&s.from[0], "animation.slerp.from[0]", "q")?;
        let p0 = unit_quaternion(&s.from[1], "animation.slerp.from[1]", "p")?;
        let q1 = unit_quaternion(&s.to[0], "animation.slerp.to[0]", "q")?;
        let p1 = unit_quaternion(&s.to[1], "animation.slerp.to[1]", "p")?;
        let (q, p) = slerp_so4((&q0, &p0), (&q1, &p1), t);
        let m = so4_from_quaternions(&q, &p);
        // N = 4 here: copy the 4×4 matrix into Matrix<N>.
        return Ok(std::array::from_fn(|r| std::array::from_fn(|c| m[r][c])));
    }
    let r = a.rolling.as_ref().expect("one motion is given");
    if !(r.radius.is_finite() && r.radius > 0.0) {
        return Err(PathError::new(
            "animation.rolling.radius",
            format!("must be a positive number, got {}", r.radius),
        ));
    }
    if r.path.len() < 2 {
        return Err(PathError::new(
            "animation.rolling.path",
            format!(
                "expected at least two controller positions, got {}",
                r.path.len()
            ),
        ));
    }
    let mut points = Vec::with_capacity(r.path.len());
    for (k, p) in r.path.iter().enumerate() {
        let path = format!("animation.rolling.path[{k}]");
        if p.len() != N - 1 {
            return Err(PathError::new(
                path,
                format!(
                    "expected {} numbers (a controller position, dim − 1), got {}",
                    N - 1,
                    p.len()
                ),
            ));
        }
        if let Some(i) = p.iter().position(|x| !x.is_finite()) {
            return Err(PathError::new(format!("{path}[{i}]"), "must be finite"));
        }
        points.push(p.clone());
    }
    let angle = r.angle.unwrap_or_default();
    // Walk the polyline to arc length t·L, one rolling step per (partial) segment.
    let lengths: Vec<f64> = points
        .windows(2)
        .map(|w| {
            w[0].iter()
                .zip(&w[1])
                .map(|(a, b)| (b - a).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let mut left = t.clamp(0.0, 1.0) * lengths.iter().sum::<f64>();
    let mut m: Matrix<N> = crate::linalg::identity();
    for (w, &len) in points.windows(2).zip(&lengths) {
        if left <= 0.0 {
            break;
        }
        let f = if len > left { left / len } else { 1.0 };
        left -= len;
        let d: Vec<f64> = w[0].iter().zip(&w[1]).map(|(a, b)| f * (b - a)).collect();
        m = mat_mul(&rolling_ball::<N>(&d, r.radius, angle), &m);
    }
    Ok(m)
}

/// The description of frame `k`: the scene with M(t_k) applied to the target about `center`,
/// and without the `[animation]` table (a still).
pub fn frame_desc(desc: &SceneDesc, k: u32) -> Result<SceneDesc, PathError> {
    let Some(a) = &desc.animation else {
        return Err(PathError::new(
            "animation",
            "the scene has no [animation] table",
        ));
    };
    if k >= a.frames {
        return Err(PathError::new(
            "animation.frames",
            format!(
                "frame {k} does not exist: the animation has {} frames (0-based)",
                a.frames
            ),
        ));
    }
    let dim = desc.dim;
    with_dim!(dim, N => frame_desc_n::<N>(desc, a, k))
        .unwrap_or_else(|e: NdError| Err(PathError::new("dim", e.to_string())))
}

fn frame_desc_n<const N: usize>(desc: &SceneDesc, a: &AnimationDesc, k: u32) -> R<SceneDesc> {
    check::<N>(a, desc.objects.len())?;
    let m = motion::<N>(a, frame_time(a, k))?;
    let c = center::<N>(a)?;
    let vec = vec_n::<N>;
    let about = |x: &[f64], path: &str| -> R<Vec<f64>> {
        Ok(add(&c, &mat_vec(&m, &sub(&vec(x, path)?, &c))).to_vec())
    };
    let turn =
        |x: &[f64], path: String| -> R<Vec<f64>> { Ok(mat_vec(&m, &vec(x, &path)?).to_vec()) };
    let mut out = desc.clone();
    out.animation = None;
    let step = if c.iter().all(|&x| x == 0.0) {
        TransformDesc::Matrix(m.iter().map(|r| r.to_vec()).collect())
    } else {
        // x ↦ M(x − c) + c as (N+1)×(N+1) affine rows.
        let b = sub(&c, &mat_vec(&m, &c));
        let mut rows: Vec<Vec<f64>> = (0..N)
            .map(|i| m[i].iter().copied().chain([b[i]]).collect())
            .collect();
        rows.push((0..=N).map(|j| if j == N { 1.0 } else { 0.0 }).collect());
        TransformDesc::Matrix(rows)
    };
    match &a.target {
        AnimationTarget::Named(n) if n == "camera" => {
            let cam = &mut out.camera;
            cam.position = about(&cam.position, "camera.position")?;
            if let Some(l) = &cam.look_at {
                cam.look_at = Some(about(l, "camera.look_at")?);
            }
            cam.up = match &cam.up {
                None => None,
                Some(UpDesc::Single(u)) => Some(UpDesc::Single(turn(u, "camera.up".into())?)),
                Some(UpDesc::List(l)) => Some(UpDesc::List(
                    l.iter()
                        .enumerate()
                        .map(|(k, u)| turn(u, format!("camera.up[{k}]")))
                        .collect::<R<_>>()?,
                )),
            };
            if let Some(o) = &cam.orientation {
                let rows = matrix_rows::<N>(o, "camera.orientation")?;
                cam.orientation = Some(mat_mul(&m, &rows).iter().map(|r| r.to_vec()).collect());
            }
        }
        AnimationTarget::Named(_) => {
            for o in &mut out.objects {
                o.transform.push(step.clone());
            }
        }
        AnimationTarget::Objects(ids) => {
            for &i in ids {
                out.objects[i].transform.push(step.clone());
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::{det, identity, transpose};
    use crate::rotation::RollingAngle;
    use crate::scene::{load_toml_str, to_toml};

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
        let o0 =
            crate::scene::fields::matrix_rows::<4>(desc.camera.orientation.as_ref().unwrap(), "o")
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

    fn err(text: &str) -> String {
        match load_toml_str(text, "scene.toml", None) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("expected an error for:\n{text}"),
        }
    }

    #[test]
    fn bad_animation_tables_are_located_errors() {
        let line = SPIN
            .lines()
            .position(|l| l.starts_with("frames = 5"))
            .unwrap()
            + 1;
        assert_eq!(
            err(&SPIN.replace("frames = 5", "frames = 0")),
            format!("scene.toml:{line}:10: animation.frames: must be in 1..={MAX_FRAMES}, got 0")
        );
        let cases = [
            ("degrees = [0, 90] }", "degrees = [0, 90] }\nfps = -1", "animation.fps: must be a positive number"),
            ("plane = [0, 3]", "plane = [0, 4]", "animation.sweep.plane: expected two different axes in 0..3"),
            ("frames = 5", "frames = 5\ntarget = \"lights\"", "animation.target: expected \"objects\", \"camera\""),
            ("frames = 5", "frames = 5\ntarget = [0, 2]", "animation.target[1]: object 2 does not exist"),
            ("frames = 5", "frames = 5\ntarget = [1, 0, 1]", "animation.target[2]: object 1 is already listed at animation.target[0]"),
            ("frames = 5", "frames = 5\ntarget = []", "animation.target: lists no objects"),
            ("frames = 5", "frames = 5\ncenter = [0, 0]", "animation.center: expected 4 numbers (dim = 4), got 2"),
            ("frames = 5", "frames = 5\nrolling = { path = [[0, 0, 0], [1, 0, 0]], radius = 1 }", "animation: give exactly one motion"),
            ("sweep = { plane = [0, 3], degrees = [0, 90] }", "", "animation: give exactly one motion"),
            ("sweep = { plane = [0, 3], degrees = [0, 90] }", "rolling = { path = [[0, 0, 0]], radius = 1 }", "animation.rolling.path: expected at least two"),
            ("sweep = { plane = [0, 3], degrees = [0, 90] }", "rolling = { path = [[0, 0, 0], [1, 0]], radius = 1 }", "animation.rolling.path[1]: expected 3 numbers"),
            ("sweep = { plane = [0, 3], degrees = [0, 90] }", "rolling = { path = [[0, 0, 0], [1, 0, 0]], radius = 0 }", "animation.rolling.radius: must be a positive number"),
            ("sweep = { plane = [0, 3], degrees = [0, 90] }", "slerp = { from = [[1, 0, 0, 0], [1, 0, 0, 0]], to = [[1, 1, 0, 0], [1, 0, 0, 0]] }", "animation.slerp.to[0]: not a unit quaternion (|q| = 1.414"),
            ("sweep = { plane = [0, 3], degrees = [0, 90] }", "sweeep = 1", "did you mean \"sweep\""),
        ];
        for (from, to, want) in cases {
            let e = err(&SPIN.replace(from, to));
            assert!(e.contains(want), "{to:?}: {e}");
        }
        let three = SPIN
            .replace("dim = 4", "dim = 3")
            .replace("[0, 0, 0, 5]", "[0, 0, 5]")
            .replace("[0, 0, 0, 0]", "[0, 0, 0]")
            .replace("up = [[0, 1, 0, 0], [0, 0, 1, 0]]", "up = [0, 1, 0]")
            .replace("sweep = { plane = [0, 3], degrees = [0, 90] }", "slerp = { from = [[1, 0, 0, 0], [1, 0, 0, 0]], to = [[1, 0, 0, 0], [1, 0, 0, 0]] }");
        let e = err(&three);
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
}
