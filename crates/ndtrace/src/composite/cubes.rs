//! `cubes = { size }`: the notes' display aid for volumes, "break into tiny cubes — to help see
//! inside volume, leave a little space instead of transparency" (Part II(B)). Each occupied
//! cell of the 3D volume (coverage ≥ ½) is an opaque cube of side `size` cells about its
//! centre; a pixel's ray walks the cells it crosses in order (Amanatides and Woo's grid
//! traversal) and stops at the first cube it meets (the slab test against the cube's box), in
//! the cell's straight colour, shaded by a headlight on the face it enters so the cubes read
//! as solids; the gaps between them show what lies behind.

use super::volume::{clip_box, Camera3, Grid};
use super::CompositeOptions;
use glam::DVec3;
use rayon::prelude::*;

/// Brightness of a face seen edge-on; face-on is 1.
const EDGE_ON: f64 = 0.35;

/// The first cube of `grid` along the ray `o + t·d`, t ∈ [t0, t1] (inside the volume's box):
/// its premultiplied opaque colour and the t at which it is entered; nothing (transparent,
/// infinite t) if the ray passes every cube.
pub(super) fn first_cube(
    grid: &Grid,
    o: DVec3,
    d: DVec3,
    t0: f64,
    t1: f64,
    size: f64,
) -> ([f32; 4], f32) {
    let n = grid.n;
    let p = o + d * t0;
    let mut cell = [0i64; 3];
    let mut step = [0i64; 3];
    let mut next = [f64::INFINITY; 3];
    let mut delta = [f64::INFINITY; 3];
    for k in 0..3 {
        cell[k] = (p[k].floor() as i64).clamp(0, n[k] as i64 - 1);
        if d[k] > 0.0 {
            step[k] = 1;
            delta[k] = 1.0 / d[k];
            next[k] = t0 + ((cell[k] + 1) as f64 - p[k]) / d[k];
        } else if d[k] < 0.0 {
            step[k] = -1;
            delta[k] = -1.0 / d[k];
            next[k] = t0 + (cell[k] as f64 - p[k]) / d[k];
        }
    }
    let half = 0.5 * size;
    let unit = d.normalize();
    loop {
        let c = grid.cell_at(cell);
        if c[3] >= 0.5 {
            // The slab test against [centre − half, centre + half]³.
            let (mut enter, mut exit, mut axis) = (f64::NEG_INFINITY, f64::INFINITY, 0);
            for k in 0..3 {
                let centre = cell[k] as f64 + 0.5;
                if d[k] == 0.0 {
                    if (o[k] - centre).abs() > half {
                        enter = f64::INFINITY;
                    }
                    continue;
                }
                let (a, b) = ((centre - half - o[k]) / d[k], (centre + half - o[k]) / d[k]);
                let (lo, hi) = (a.min(b), a.max(b));
                if lo > enter {
                    (enter, axis) = (lo, k);
                }
                exit = exit.min(hi);
            }
            if enter <= exit && exit >= t0 {
                let shade = (EDGE_ON + (1.0 - EDGE_ON) * unit[axis].abs()) as f32;
                let s = shade / c[3];
                return ([c[0] * s, c[1] * s, c[2] * s, 1.0], enter.max(t0) as f32);
            }
        }
        // The next cell: across the nearest cell wall.
        let k = (0..3)
            .min_by(|&a, &b| next[a].total_cmp(&next[b]))
            .unwrap_or(0);
        if next[k] > t1 {
            return ([0.0; 4], f32::INFINITY);
        }
        cell[k] += step[k];
        if cell[k] < 0 || cell[k] >= n[k] as i64 {
            return ([0.0; 4], f32::INFINITY);
        }
        next[k] += delta[k];
    }
}

/// The picture of `grid` through `cam` drawn as cubes of side `size` cells: RGBA over `bg`
/// (row-major), a ray through every pixel (cubes have hard edges everywhere), and with
/// `half` the distance along the view direction of each pixel's cube (what the edge overlay
/// fades edges behind).
pub(super) fn render_cubes(
    grid: &Grid,
    cam: &Camera3,
    o: &CompositeOptions,
    size: f64,
    bg: [f32; 3],
    half: bool,
) -> (Vec<f32>, Option<Vec<f32>>) {
    let (w, h) = o.size;
    let mut img = vec![0f32; w * h * 4];
    let mut halves = vec![f32::INFINITY; w * h];
    img.par_chunks_mut(w * 4)
        .zip(halves.par_chunks_mut(w))
        .enumerate()
        .for_each(|(py, (row, row_halves))| {
            for px in 0..w {
                let (org, dir, fwd_only) = cam.ray(px, py);
                let (v, t) = match clip_box(org, dir, grid.n, fwd_only) {
                    None => ([0.0; 4], f32::INFINITY),
                    Some((t0, t1)) => first_cube(grid, org, dir, t0, t1, size),
                };
                row[px * 4..px * 4 + 4].copy_from_slice(&super::over(v, bg));
                row_halves[px] = t * dir.dot(cam.fwd) as f32;
            }
        });
    (img, half.then_some(halves))
}
