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
//! # or: slice = { normal = [0, 0, 0, 1], from = -1.2, to = 1.2 }
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
//!   coordinates (M = M_m ⋯ M_1), the segment reached at t travelled in proportion to its length;
//! - `slice`: no rotation; frame k is the scene's slice by the hyperplane n̂·x = offset(t_k),
//!   the offset linear in t (its `[slice]` table set, see [`super::slice`]): the object passing
//!   through our space.

use super::desc::*;
use super::errors::PathError;
use super::fields::{matrix_rows, slice_plane, vec_n, R};
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
    let given = [
        a.sweep.is_some(),
        a.slerp.is_some(),
        a.rolling.is_some(),
        a.slice.is_some(),
        a.keyframes.is_some(),
    ];
    if given.iter().filter(|&&g| g).count() != 1 {
        return Err(PathError::new(
            "animation",
            "give exactly one motion: sweep, slerp, rolling, slice or keyframes",
        ));
    }
    if a.interpolation.is_some() && a.keyframes.is_none() {
        return Err(PathError::new(
            "animation.interpolation",
            "applies to keyframes only",
        ));
    }
    if let Some(keys) = &a.keyframes {
        return keyframed::<N>(keys, a.interpolation.unwrap_or_default(), t);
    }
    if a.slice.is_some() {
        slice_at::<N>(a, t)?;
        return Ok(crate::linalg::identity());
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

/// The rotation of `keyframes` at animation time t ∈ [0, 1] (mapped onto the first to the
/// last key's time): a C¹ spline through the keys ([`crate::rotation::spline`]: quaternions
/// for N = 3, double quaternions for N = 4, SO(N) through the matrix log and exp otherwise),
/// or geodesic pieces between neighbours (`"slerp"`).
fn keyframed<const N: usize>(keys: &[KeyframeDesc], how: Interpolation, t: f64) -> R<Matrix<N>> {
    use crate::rotation::spline;
    let times: Vec<f64> = keys.iter().map(|k| k.time).collect();
    let mats: Vec<Matrix<N>> = keys
        .iter()
        .enumerate()
        .map(|(i, k)| {
            super::transform::rotate::<N>(
                &k.rotation,
                &format!("animation.keyframes[{i}].rotation"),
            )
        })
        .collect::<R<_>>()?;
    spline::check_times(&times, keys.len()).map_err(|e| match e {
        NdError::Value { arg, message } if arg == "times" => {
            PathError::new("animation.keyframes", format!("times {message}"))
        }
        e => PathError::new("animation.keyframes", e.to_string()),
    })?;
    let time = times[0] + t * (times[keys.len() - 1] - times[0]);
    let fail = |e: NdError| PathError::new("animation.keyframes", e.to_string());
    match how {
        Interpolation::Slerp => {
            // Geodesic pieces: the two keys around `time`, whose two-key spline is the slerp.
            let i = times
                .partition_point(|&x| x <= time)
                .clamp(1, keys.len() - 1)
                - 1;
            let pair = [mats[i], mats[i + 1]];
            interpolate::<N>(&pair, &times[i..i + 2], time).map_err(fail)
        }
        Interpolation::Spline => interpolate::<N>(&mats, &times, time).map_err(fail),
    }
}

/// The spline through rotations `mats` at `times`, at `time`, by the form of its dimension.
fn interpolate<const N: usize>(
    mats: &[Matrix<N>],
    times: &[f64],
    time: f64,
) -> crate::NdResult<Matrix<N>> {
    use crate::rotation::{matrix_to_quat_sequence, quat_to_matrix, quaternions_from_so4, spline};
    let cast =
        |m: &[f64]| -> Matrix<N> { std::array::from_fn(|r| std::array::from_fn(|c| m[r * N + c])) };
    if N == 3 {
        let m3: Vec<Matrix<3>> = mats
            .iter()
            .map(|m| std::array::from_fn(|r| std::array::from_fn(|c| m[r][c])))
            .collect();
        let q = matrix_to_quat_sequence(&m3);
        let r = quat_to_matrix(&spline::quaternion_spline(&q, times, &[time], true)?[0]);
        return Ok(cast(r.as_flattened()));
    }
    if N == 4 {
        let (l, p): (Vec<_>, Vec<_>) = mats
            .iter()
            .map(|m| {
                quaternions_from_so4(&std::array::from_fn(|r| std::array::from_fn(|c| m[r][c])))
            })
            .unzip();
        let r = spline::so4_spline(&l, &p, times, &[time])?[0];
        return Ok(cast(r.as_flattened()));
    }
    Ok(spline::so_n_spline(mats, times, &[time])?[0])
}

/// The `[slice]` of a slice sweep at time t: offset `from + t·(to − from)`; `None` for the
/// other motions.
pub fn slice_at<const N: usize>(a: &AnimationDesc, t: f64) -> R<Option<SliceDesc>> {
    let Some(s) = &a.slice else {
        return Ok(None);
    };
    for (name, x) in [("from", s.from), ("to", s.to)] {
        if !x.is_finite() {
            return Err(PathError::new(
                format!("animation.slice.{name}"),
                format!("must be finite, got {x}"),
            ));
        }
    }
    let cut = SliceDesc {
        normal: s.normal.clone(),
        offset: s.from + t * (s.to - s.from),
    };
    slice_plane::<N>(&cut, "animation.slice")?;
    Ok(Some(cut))
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
    if let Some(cut) = slice_at::<N>(a, frame_time(a, k))? {
        // A slice sweep moves the hyperplane, not the scene.
        out.slice = Some(cut);
        return Ok(out);
    }
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
mod tests;
