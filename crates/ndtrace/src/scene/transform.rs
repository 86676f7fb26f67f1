//! An object's `transform` list (scale, translate, rotate, matrix) as one affine map, with
//! the rotation forms of the course: plane rotations R_ij, double quaternions (4D) and the
//! rolling ball.

use super::desc::{RotateDesc, ScaleDesc, TransformDesc};
use super::errors::PathError;
use super::fields::{finite_list, matrix_rows, vec_n, R};
use crate::linalg::{add, identity, mat_mul, mat_vec, Matrix, Vector};
use crate::rotation::{
    check_plane, plane_rotation, rolling_ball, scene_quaternion, so4_from_quaternions, Quat,
};

/// The affine map x ↦ A·x + b of a transform list (the first entry acts first).
pub(super) fn transform<const N: usize>(
    list: &[TransformDesc],
    path: &str,
) -> R<(Matrix<N>, Vector<N>)> {
    let mut a: Matrix<N> = identity();
    let mut b: Vector<N> = [0.0; N];
    for (k, t) in list.iter().enumerate() {
        let p = format!("{path}[{k}]");
        let (m, c): (Matrix<N>, Vector<N>) = match t {
            TransformDesc::Scale(ScaleDesc::Uniform(s)) => {
                if !(s.is_finite() && *s != 0.0) {
                    return Err(PathError::new(
                        format!("{p}.scale"),
                        format!("must be a non-zero number, got {s}"),
                    ));
                }
                (scale_matrix(&[*s; N]), [0.0; N])
            }
            TransformDesc::Scale(ScaleDesc::PerAxis(v)) => {
                let s = vec_n::<N>(v, &format!("{p}.scale"))?;
                if let Some(i) = s.iter().position(|&x| x == 0.0) {
                    return Err(PathError::new(
                        format!("{p}.scale[{i}]"),
                        "must be non-zero",
                    ));
                }
                (scale_matrix(&s), [0.0; N])
            }
            TransformDesc::Translate(v) => (identity(), vec_n::<N>(v, &format!("{p}.translate"))?),
            TransformDesc::Rotate(r) => (rotate::<N>(r, &format!("{p}.rotate"))?, [0.0; N]),
            TransformDesc::Matrix(rows) => affine_rows::<N>(rows, &format!("{p}.matrix"))?,
        };
        // New map: x ↦ m·(a·x + b) + c.
        a = mat_mul(&m, &a);
        b = add(&mat_vec(&m, &b), &c);
    }
    Ok((a, b))
}

/// The matrix of a `rotate` transform: exactly one of the plane, double-quaternion (4D) and
/// rolling-ball forms, with only the keys of that form.
pub(super) fn rotate<const N: usize>(r: &RotateDesc, path: &str) -> R<Matrix<N>> {
    let forms = [
        ("plane", r.plane.is_some()),
        ("quaternions", r.quaternions.is_some()),
        ("rolling", r.rolling.is_some()),
    ];
    let given: Vec<&str> = forms.iter().filter(|f| f.1).map(|f| f.0).collect();
    match given[..] {
        [] => {
            return Err(PathError::new(
                path,
                "give one of plane (with degrees), quaternions = [q, p] (dim 4) or rolling (with radius)",
            ))
        }
        [_] => {}
        [first, second, ..] => {
            return Err(PathError::new(
                format!("{path}.{second}"),
                format!("give only one of plane, quaternions or rolling, not both {first} and {second}"),
            ))
        }
    }
    let belongs = |key: &str, present: bool, form: &str| -> R<()> {
        if present {
            Err(PathError::new(
                format!("{path}.{key}"),
                format!("\"{key}\" goes with {form}, not with {}", given[0]),
            ))
        } else {
            Ok(())
        }
    };
    if r.plane.is_none() {
        belongs("degrees", r.degrees.is_some(), "plane")?;
    }
    if r.rolling.is_none() {
        belongs("radius", r.radius.is_some(), "rolling")?;
        belongs("angle", r.angle.is_some(), "rolling")?;
    }
    if let Some([i, j]) = r.plane {
        check_plane(i, j, N).map_err(|m| PathError::new(format!("{path}.plane"), m))?;
        let degrees = r
            .degrees
            .ok_or_else(|| PathError::new(path, "plane needs degrees (the angle)"))?;
        if !degrees.is_finite() {
            return Err(PathError::new(format!("{path}.degrees"), "must be finite"));
        }
        return Ok(plane_rotation::<N>(i, j, degrees.to_radians()));
    }
    if let Some(qp) = &r.quaternions {
        let qpath = format!("{path}.quaternions");
        if N != 4 {
            return Err(PathError::new(
                qpath,
                format!(
                    "quaternions = [q, p] give a 4D rotation, but dim = {N}; use plane or rolling"
                ),
            ));
        }
        if qp.len() != 2 {
            return Err(PathError::new(
                qpath,
                format!(
                    "expected [q, p], two lists of 4 numbers, got {} lists",
                    qp.len()
                ),
            ));
        }
        let mut pair: [Quat; 2] = [[0.0; 4]; 2];
        for (k, (v, symbol)) in qp.iter().zip(["q", "p"]).enumerate() {
            let vpath = format!("{qpath}[{k}]");
            if v.len() != 4 {
                return Err(PathError::new(
                    vpath,
                    format!(
                        "expected 4 numbers (a quaternion q0, q1, q2, q3), got {}",
                        v.len()
                    ),
                ));
            }
            finite_list(v, &vpath)?;
            // Hand-typed: |q| within SCENE_UNIT_TOLERANCE of 1, then normalized.
            let q: Quat = std::array::from_fn(|c| v[c]);
            pair[k] =
                scene_quaternion(&q, "quaternion", symbol).map_err(|m| PathError::new(vpath, m))?;
        }
        let m = so4_from_quaternions(&pair[0], &pair[1]);
        // N = 4 here; copy into the generic matrix type.
        return Ok(std::array::from_fn(|i| std::array::from_fn(|j| m[i][j])));
    }
    let d = r.rolling.as_deref().unwrap_or_default();
    let rpath = format!("{path}.rolling");
    if d.len() != N - 1 {
        return Err(PathError::new(
            rpath,
            format!(
                "expected N − 1 = {} numbers (dim = {N}), got {}",
                N - 1,
                d.len()
            ),
        ));
    }
    finite_list(d, &rpath)?;
    let radius = r
        .radius
        .ok_or_else(|| PathError::new(path, "rolling needs radius (the ball radius R)"))?;
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(PathError::new(
            format!("{path}.radius"),
            format!("must be a positive number, got {radius}"),
        ));
    }
    Ok(rolling_ball::<N>(d, radius, r.angle.unwrap_or_default()))
}

fn scale_matrix<const N: usize>(s: &[f64; N]) -> Matrix<N> {
    std::array::from_fn(|i| std::array::from_fn(|j| if i == j { s[i] } else { 0.0 }))
}

fn affine_rows<const N: usize>(rows: &[Vec<f64>], path: &str) -> R<(Matrix<N>, Vector<N>)> {
    if rows.len() == N {
        return Ok((matrix_rows::<N>(rows, path)?, [0.0; N]));
    }
    if rows.len() != N + 1 {
        return Err(PathError::new(
            path,
            format!(
                "expected {N}×{N} (linear) or {}×{} (affine) rows, got {} rows",
                N + 1,
                N + 1,
                rows.len()
            ),
        ));
    }
    let mut m = [[0.0; N]; N];
    let mut b = [0.0; N];
    for (i, row) in rows.iter().enumerate() {
        if row.len() != N + 1 {
            return Err(PathError::new(
                format!("{path}[{i}]"),
                format!("expected {} numbers, got {}", N + 1, row.len()),
            ));
        }
        finite_list(row, &format!("{path}[{i}]"))?;
        if i < N {
            m[i].copy_from_slice(&row[..N]);
            b[i] = row[N];
        } else if row[..N].iter().any(|&x| x != 0.0) || row[N] != 1.0 {
            return Err(PathError::new(
                format!("{path}[{N}]"),
                "the last row of an affine matrix must be [0, …, 0, 1]",
            ));
        }
    }
    Ok((m, b))
}

#[cfg(test)]
mod tests;
