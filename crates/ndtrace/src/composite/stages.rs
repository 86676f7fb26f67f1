//! Recursive projection for N ≥ 5: one k-D → (k−1)-D emission–absorption stage per axis,
//! down to a 3D volume (see [`CompositeOptions::stages`](super::CompositeOptions::stages)).

use super::{Accum, Volume};

/// Default eye distance d_k of a recursive stage, in half-lengths of the stage's longest axis.
pub const DEFAULT_STAGE_DISTANCE: f64 = 3.0;
use glam::Vec4;
use rayon::prelude::*;

/// Half-lengths a_j of a stage box whose cells have side 2 / max(R).
pub(super) fn half_lengths(shape: &[usize]) -> Vec<f64> {
    let c = 2.0 / *shape.iter().max().unwrap_or(&1) as f64;
    shape.iter().map(|&r| r as f64 * c / 2.0).collect()
}

/// The (f, d) of the stage collapsing the leading axis of `shape`.
pub(super) fn stage_params(shape: &[usize], given: Option<(f64, f64)>) -> (f64, f64) {
    given.unwrap_or_else(|| {
        // f = d + x_k of slice 0, computed as in `project_stage`, so that slice 0 maps exactly.
        let c = 2.0 / *shape.iter().max().unwrap() as f64;
        let x0 = (0.5 - shape[0] as f64 / 2.0) * c;
        (DEFAULT_STAGE_DISTANCE + x0, DEFAULT_STAGE_DISTANCE)
    })
}

/// Where the stage collapsing the leading axis of `shape` puts the point `xi` (continuous
/// numpy-order cell coordinates of its k-D input: cell i of an axis spans [i, i + 1]): the
/// (k−1)-D output coordinates, by the stage's x_j ↦ x_j · f / (d + x_k) (or x_j for
/// orthographic), the map whose inverse [`project_stage`] samples along.
pub(super) fn stage_point(shape: &[usize], f: f64, d: f64, ortho: bool, xi: &[f64]) -> Vec<f64> {
    let c = 2.0 / *shape.iter().max().unwrap() as f64;
    let xk = (xi[0] - shape[0] as f64 / 2.0) * c;
    let scale = if ortho { 1.0 } else { f / (d + xk) };
    (1..shape.len())
        .map(|a| {
            let x = (xi[a] - shape[a] as f64 / 2.0) * c;
            x * scale / c + shape[a] as f64 / 2.0
        })
        .collect()
}

const STAGE_CHUNK: usize = 1024;

/// One k-D → (k−1)-D emission–absorption stage along the leading axis (see
/// [`CompositeOptions::stages`](super::CompositeOptions::stages)).
pub(super) fn project_stage(vol: &Volume, f: f64, d: f64, ortho: bool) -> Volume {
    let rk = vol.shape[0];
    let rest: Vec<usize> = vol.shape[1..].to_vec();
    let m = rest.len();
    let slice_len: usize = rest.iter().product();
    let c = 2.0 / *vol.shape.iter().max().unwrap() as f64;
    let half = half_lengths(&vol.shape);
    // Strides of the rest axes inside a slice (numpy order).
    let mut strides = vec![1usize; m];
    for j in (0..m.saturating_sub(1)).rev() {
        strides[j] = strides[j + 1] * rest[j + 1];
    }
    let mut out = vec![[0f32; 4]; slice_len];
    out.par_chunks_mut(STAGE_CHUNK)
        .enumerate()
        .for_each(|(chunk, dst)| {
            let mut y = vec![0f64; m];
            let mut lo = vec![0usize; m];
            let mut hi = vec![0usize; m];
            let mut fr = vec![0f64; m];
            for (j, cell) in dst.iter_mut().enumerate() {
                let idx = chunk * STAGE_CHUNK + j;
                let mut acc = Accum::EMPTY;
                if ortho {
                    // Output cell i samples input cell i of every slice exactly.
                    for s in 0..rk {
                        acc.add(Vec4::from_array(vol.cells[s * slice_len + idx]), 1.0);
                        if acc.done() {
                            break;
                        }
                    }
                } else {
                    let mut r = idx;
                    for a in (0..m).rev() {
                        let i = r % rest[a];
                        r /= rest[a];
                        y[a] = (i as f64 + 0.5 - rest[a] as f64 / 2.0) * c;
                    }
                    let slope2: f64 = y.iter().map(|v| (v / f) * (v / f)).sum();
                    let dt = (1.0 + slope2).sqrt() as f32;
                    'slices: for s in 0..rk {
                        let xk = (s as f64 + 0.5 - rk as f64 / 2.0) * c;
                        let scale = (d + xk) / f;
                        for a in 0..m {
                            let x = y[a] * scale;
                            if x < -half[a + 1] || x > half[a + 1] {
                                continue 'slices;
                            }
                            let q = (x / c + rest[a] as f64 / 2.0 - 0.5)
                                .clamp(0.0, (rest[a] - 1) as f64);
                            let i0 = (q.floor() as usize).min(rest[a] - 1);
                            lo[a] = i0;
                            hi[a] = (i0 + 1).min(rest[a] - 1);
                            fr[a] = q - i0 as f64;
                        }
                        let base = s * slice_len;
                        let mut v = [0f32; 4];
                        for corner in 0..(1usize << m) {
                            let mut w = 1.0f64;
                            let mut off = base;
                            for a in 0..m {
                                if corner >> a & 1 == 1 {
                                    w *= fr[a];
                                    off += hi[a] * strides[a];
                                } else {
                                    w *= 1.0 - fr[a];
                                    off += lo[a] * strides[a];
                                }
                            }
                            if w > 0.0 {
                                let cv = vol.cells[off];
                                for ch in 0..4 {
                                    v[ch] += w as f32 * cv[ch];
                                }
                            }
                        }
                        acc.add(Vec4::from_array(v), dt);
                        if acc.done() {
                            break;
                        }
                    }
                }
                *cell = acc.rgba();
            }
        });
    Volume {
        shape: rest,
        cells: out,
    }
}
