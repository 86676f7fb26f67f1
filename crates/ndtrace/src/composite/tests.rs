//! Tests of the compositing: analytic pictures from the documented conventions.

use super::volume::{render_3d, Grid};
use super::*;
use crate::camera::Projection;
use crate::testutil::rng;
use crate::NdError;
use rand::Rng;

/// A retina of `shape` (numpy order) with cell values from `f(index)`.
fn retina(shape: &[usize], f: impl Fn(&[usize]) -> [f32; 4]) -> Vec<f32> {
    let cells: usize = shape.iter().product();
    let mut out = Vec::with_capacity(cells * 4);
    let mut idx = vec![0usize; shape.len()];
    for lin in 0..cells {
        let mut r = lin;
        for a in (0..shape.len()).rev() {
            idx[a] = r % shape[a];
            r /= shape[a];
        }
        out.extend_from_slice(&f(&idx));
    }
    out
}

/// The options these tests were written for: the volume mode framing the whole retina box
/// (the defaults are the illustrative mode and `fit`, tested in `illustrative_tests`).
fn legacy() -> CompositeOptions {
    CompositeOptions {
        mode: CompositeMode::Volume,
        fit: false,
        // A ray through every pixel: these tests check the rays' arithmetic, the lattice
        // of `rays_per_cell` is tested against it.
        rays_per_cell: 0,
        ..Default::default()
    }
}

fn ortho(mode: CompositeMode, az: f64, el: f64, size: (usize, usize)) -> CompositeOptions {
    CompositeOptions {
        mode,
        azimuth: az,
        elevation: el,
        projection: Projection::Orthographic,
        size,
        ..legacy()
    }
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

/// World (x, y) of the centre of pixel (px, py) of a face-on orthographic view, computed
/// from the documented conventions: the shorter side spans the bounding sphere's diameter.
fn face_on_pixel(shape: [usize; 3], size: (usize, usize), px: usize, py: usize) -> (f64, f64) {
    let c = 2.0 / *shape.iter().max().unwrap() as f64;
    let h = [
        shape[2] as f64 * c / 2.0,
        shape[1] as f64 * c / 2.0,
        shape[0] as f64 * c / 2.0,
    ];
    let r = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let pw = 2.0 * r / size.0.min(size.1) as f64;
    (
        (px as f64 + 0.5 - size.0 as f64 / 2.0) * pw,
        (size.1 as f64 / 2.0 - py as f64 - 0.5) * pw,
    )
}

/// Is world (x, y) inside the face-on footprint of column `col`, row `row`?
fn in_footprint(shape: [usize; 3], col: usize, row: usize, x: f64, y: f64) -> bool {
    let c = 2.0 / *shape.iter().max().unwrap() as f64;
    let (hx, hy) = (shape[2] as f64 * c / 2.0, shape[1] as f64 * c / 2.0);
    let (x0, y1) = (-hx + col as f64 * c, hy - row as f64 * c);
    x > x0 && x < x0 + c && y < y1 && y > y1 - c
}

#[test]
fn opaque_cell_face_on_covers_exactly_its_pixels() {
    let shape = [3usize, 5, 6];
    let (slice, row, col) = (1, 2, 4);
    let color = [0.2f32, 0.5, 0.8];
    let a = 0.5f32; // premultiplied by a partial coverage: first_hit shows it opaque
    let rgba = retina(&shape, |i| {
        if i == [slice, row, col] {
            [color[0] * a, color[1] * a, color[2] * a, a]
        } else {
            [0.0; 4]
        }
    });
    let size = (61, 50);
    let bg = [0.1, 0.2, 0.3];
    // (First-hit shows the smooth surface where the interpolated coverage reaches ½, not cell
    // footprints: tests/test_pictures.py checks it on a ball.)
    for mode in [CompositeMode::Mip] {
        let mut o = ortho(mode, 0.0, 0.0, size);
        o.background = bg;
        let img = composite(&rgba, None, &shape, &o).unwrap();
        assert_eq!(
            (img.width, img.height, img.rgba.len()),
            (61, 50, 61 * 50 * 4)
        );
        let mut covered = 0;
        for py in 0..size.1 {
            for px in 0..size.0 {
                let (x, y) = face_on_pixel(shape, size, px, py);
                let p = img.pixel(px, py);
                let expect = if in_footprint(shape, col, row, x, y) {
                    covered += 1;
                    match mode {
                        CompositeMode::FirstHit => [color[0], color[1], color[2], 1.0],
                        _ => {
                            let t = 1.0 - a;
                            [
                                color[0] * a + t * 0.1,
                                color[1] * a + t * 0.2,
                                color[2] * a + t * 0.3,
                                a,
                            ]
                        }
                    }
                } else {
                    [0.1, 0.2, 0.3, 0.0]
                };
                for ch in 0..4 {
                    assert!(
                        close(p[ch], expect[ch], 1e-6),
                        "{mode:?} pixel ({px}, {py}): {p:?} vs {expect:?}"
                    );
                }
            }
        }
        // The cell is 1/6 of the width of the box: about (61 · w_box / 2r / 6)² pixels.
        assert!(covered > 20, "{covered}");
    }
}

/// The path length in cells of the central ray through a cube of side n.
fn central_path(n: usize, az: f64, el: f64) -> f64 {
    let (az, el) = (az.to_radians(), el.to_radians());
    let d = [az.sin() * el.cos(), el.sin(), az.cos() * el.cos()];
    n as f64 / d.iter().map(|v| v.abs()).fold(0.0, f64::max)
}

#[test]
fn uniform_slab_matches_the_closed_form() {
    let s = [0.9f32, 0.6, 0.3];
    for &a in &[0.05f32, 0.3, 0.9] {
        for &l in &[1usize, 3, 8] {
            for &step in &[0.5, 0.3, 1.0, 2.5] {
                let shape = [l, 6, 6];
                let rgba = retina(&shape, |_| [s[0] * a, s[1] * a, s[2] * a, a]);
                let mut o = ortho(CompositeMode::Volume, 0.0, 0.0, (9, 9));
                o.step = step;
                let img = composite(&rgba, None, &shape, &o).unwrap();
                let opacity = 1.0 - (1.0 - a as f64).powi(l as i32);
                // Rays stop once the transmittance is below MIN_TRANSMITTANCE.
                let tol = if 1.0 - opacity < MIN_TRANSMITTANCE as f64 {
                    MIN_TRANSMITTANCE
                } else {
                    2e-6
                };
                let p = img.pixel(4, 4);
                assert!(
                    close(p[3], opacity as f32, tol),
                    "a={a} L={l} step={step}: {} vs {opacity}",
                    p[3]
                );
                for ch in 0..3 {
                    assert!(close(p[ch], (s[ch] as f64 * opacity) as f32, tol), "{p:?}");
                }
                // The corner pixel's ray misses the box: background, no opacity.
                assert_eq!(img.pixel(0, 0), [0.0; 4]);
            }
        }
    }
    // Oblique central rays through a uniform cube: the opacity follows the path length,
    // whatever the projection and the step.
    let n = 8;
    let a = 0.12f32;
    let shape = [n, n, n];
    let rgba = retina(&shape, |_| [a, a, a, a]);
    for (az, el) in [(30.0, 0.0), (30.0, 20.0), (-50.0, 35.0), (200.0, -10.0)] {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            for step in [0.5, 0.37] {
                let o = CompositeOptions {
                    azimuth: az,
                    elevation: el,
                    projection,
                    size: (65, 65),
                    step,
                    ..legacy()
                };
                let p = composite(&rgba, None, &shape, &o).unwrap().pixel(32, 32);
                let expect = 1.0 - (1.0 - a as f64).powf(central_path(n, az, el));
                assert!(
                    close(p[3], expect as f32, 1e-5),
                    "az={az} el={el} {projection:?}: {} vs {expect}",
                    p[3]
                );
                assert!(close(p[0], expect as f32, 1e-5));
            }
        }
    }
}

#[test]
fn trilinear_sampling_reproduces_linear_ramps() {
    // Uniform alpha, straight colour linear in the column and row indices: every ray of a
    // face-on view sees the ramp's value at its (x, y), clamped to the edge cell centres.
    let shape = [4usize, 7, 9];
    let a = 0.4f32;
    let ramp = |col: f64, row: f64| [0.1 + 0.08 * col, 0.9 - 0.1 * row, 0.5];
    let rgba = retina(&shape, |i| {
        let s = ramp(i[2] as f64, i[1] as f64);
        [s[0] as f32 * a, s[1] as f32 * a, s[2] as f32 * a, a]
    });
    let size = (73, 61);
    let o = ortho(CompositeMode::Volume, 0.0, 0.0, size);
    let img = composite(&rgba, None, &shape, &o).unwrap();
    let opacity = 1.0 - (1.0 - a as f64).powi(4);
    let c = 2.0 / 9.0;
    let mut checked = 0;
    for py in 0..size.1 {
        for px in 0..size.0 {
            let (x, y) = face_on_pixel(shape, size, px, py);
            let (u, v) = ((x + 1.0) / c, (7.0 * c / 2.0 - y) / c);
            if u <= 0.0 || u >= 9.0 || v <= 0.0 || v >= 7.0 {
                continue;
            }
            checked += 1;
            let s = ramp((u - 0.5).clamp(0.0, 8.0), (v - 0.5).clamp(0.0, 6.0));
            let p = img.pixel(px, py);
            for ch in 0..3 {
                assert!(
                    close(p[ch], (s[ch] * opacity) as f32, 1e-5),
                    "({px}, {py}) ch {ch}: {} vs {}",
                    p[ch],
                    s[ch] * opacity
                );
            }
        }
    }
    assert!(checked > 1000);
}

#[test]
fn opacity_scales_alpha_and_colour() {
    let shape = [4usize, 4, 4];
    let rgba = retina(&shape, |_| [0.4, 0.2, 0.1, 0.5]);
    let mut o = ortho(CompositeMode::Volume, 0.0, 0.0, (9, 9));
    o.opacity = 0.4; // cell alpha 0.2, colour (0.16, 0.08, 0.04)
    let p = composite(&rgba, None, &shape, &o).unwrap().pixel(4, 4);
    let opacity = 1.0 - 0.8f64.powi(4);
    assert!(close(p[3], opacity as f32, 1e-6), "{p:?}");
    assert!(close(p[0], (0.8 * opacity) as f32, 1e-6), "{p:?}");
    // Opacity 10 clamps alpha to 1: the first slice hides the rest.
    o.opacity = 10.0;
    let p = composite(&rgba, None, &shape, &o).unwrap().pixel(4, 4);
    assert_eq!(p, [0.8, 0.4, 0.2, 1.0]);
}

#[test]
fn mip_shows_the_brightest_cell_along_rays_through_it() {
    let shape = [5usize, 5, 5];
    let bright = [1.0f32, 0.8, 0.6, 1.0];
    let dim = [0.1f32, 0.1, 0.1, 0.2];
    let rgba = retina(&shape, |i| if i == [2, 1, 3] { bright } else { dim });
    let size = (40, 40);
    let img = composite(
        &rgba,
        None,
        &shape,
        &ortho(CompositeMode::Mip, 0.0, 0.0, size),
    )
    .unwrap();
    let mut through = 0;
    for py in 0..size.1 {
        for px in 0..size.0 {
            let (x, y) = face_on_pixel(shape, size, px, py);
            let p = img.pixel(px, py);
            if in_footprint(shape, 3, 1, x, y) {
                through += 1;
                assert_eq!(p, bright);
            } else if x.abs() < 0.99 && y.abs() < 0.99 {
                assert_eq!(p, dim);
            }
        }
    }
    assert!(through > 10);
    // Seen from the side (azimuth 90: along −x), the bright cell's row is still found.
    let img = composite(
        &rgba,
        None,
        &shape,
        &ortho(CompositeMode::Mip, 90.0, 0.0, (41, 41)),
    )
    .unwrap();
    assert_eq!(img.pixel(20, 20), dim);
    let found = (0..41).any(|py| (0..41).any(|px| img.pixel(px, py) == bright));
    assert!(found);
}

#[test]
fn first_hit_shows_the_nearest_cell() {
    let shape = [5usize, 5, 5];
    let red = [0.9f32, 0.1, 0.1, 1.0];
    let blue = [0.05f32, 0.1, 0.45, 0.5]; // straight colour (0.1, 0.2, 0.9)
    let rgba = retina(&shape, |i| match i {
        [1, 2, 2] => red,
        [3, 2, 2] => blue,
        _ => [0.0; 4],
    });
    for (az, expect) in [
        (0.0, [0.9, 0.1, 0.1, 1.0]),
        (180.0, [0.1, 0.2, 0.9, 1.0]),
        (10.0, [0.9, 0.1, 0.1, 1.0]),
    ] {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let o = CompositeOptions {
                mode: CompositeMode::FirstHit,
                azimuth: az,
                elevation: 0.0,
                projection,
                size: (31, 31),
                ..legacy()
            };
            let p = composite(&rgba, None, &shape, &o).unwrap().pixel(15, 15);
            for ch in 0..4 {
                assert!(
                    close(p[ch], expect[ch], 1e-6),
                    "az {az} {projection:?}: {p:?}"
                );
            }
        }
    }
    // Volume mode (trilinear, so softened) is dominated by the near cell's colour.
    let o = CompositeOptions {
        azimuth: 0.0,
        elevation: 0.0,
        size: (31, 31),
        ..legacy()
    };
    let p = composite(&rgba, None, &shape, &o).unwrap().pixel(15, 15);
    assert!(p[3] > 0.85 && p[0] > 3.0 * p[2], "{p:?}");
}

#[test]
fn camera_orientation_matches_the_documented_axes() {
    // A cell at the top-left-front corner (slice 0, row 0, column 0).
    let shape = [4usize, 4, 4];
    let rgba = retina(&shape, |i| if i == [0, 0, 0] { [1.0; 4] } else { [0.0; 4] });
    let hit = |az: f64, el: f64| {
        let img = composite(
            &rgba,
            None,
            &shape,
            &ortho(CompositeMode::FirstHit, az, el, (64, 64)),
        )
        .unwrap();
        let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
        for py in 0..64 {
            for px in 0..64 {
                if img.pixel(px, py)[3] > 0.0 {
                    (sx, sy, n) = (sx + px as f64, sy + py as f64, n + 1.0);
                }
            }
        }
        assert!(n > 0.0, "az {az} el {el}: not seen");
        (sx / n - 31.5, sy / n - 31.5)
    };
    // Face on: top left.
    let (x, y) = hit(0.0, 0.0);
    assert!(x < -5.0 && y < -5.0, "{x} {y}");
    // Eye swung to +x (azimuth 90, looking along −x): slice 0 (z = −h) is on the left.
    let (x, _) = hit(90.0, 0.0);
    assert!(x < -5.0, "{x}");
    // Eye swung to −x: column 0 is now nearest and slice 0 is on the right.
    let (x, _) = hit(-90.0, 0.0);
    assert!(x > 5.0, "{x}");
    // From above (elevation 90, looking down): row 0 faces the eye; slice 0 at the bottom.
    let (x, y) = hit(0.0, 90.0);
    assert!(x < -5.0 && y > 5.0, "{x} {y}");
}

#[test]
fn slices_montage_places_slice_k_at_its_tile() {
    let shape = [5usize, 3, 4];
    let rgba = retina(&shape, |i| {
        [
            i[0] as f32 / 10.0,
            i[1] as f32 / 10.0,
            i[2] as f32 / 10.0,
            1.0,
        ]
    });
    let mut o = ortho(CompositeMode::Slices, 0.0, 0.0, (50, 40));
    o.labels = false;
    let img = composite(&rgba, None, &shape, &o).unwrap();
    // 5 tiles of 4×3 cells: 3 columns × 2 rows; scale min(46/12, 37/6) → 3; tiles 12×9;
    // the montage is 40×21 pixels, centred at (5, 9).
    let lay = slice_layout(50, 40, 5, 4, 3, 1);
    assert_eq!(
        lay,
        Layout {
            cols: 3,
            rows: 2,
            tile_w: 12,
            tile_h: 9,
            gap: 1,
            origin: (5, 9)
        }
    );
    for k in 0..5 {
        let (tx, ty) = (5 + 1 + (k % 3) * 13, 9 + 1 + (k / 3) * 10);
        assert_eq!(lay.tile_origin(k), (tx, ty));
        for row in 0..3 {
            for col in 0..4 {
                for (dx, dy) in [(0, 0), (2, 2), (1, 2)] {
                    let p = img.pixel(tx + 3 * col + dx, ty + 3 * row + dy);
                    assert_eq!(
                        p,
                        [k as f32 / 10.0, row as f32 / 10.0, col as f32 / 10.0, 1.0],
                        "slice {k} cell ({row}, {col})"
                    );
                }
            }
        }
    }
    // Separators (between tiles 0 and 1, and the frame) and the empty sixth tile.
    let sep = [SEPARATOR[0], SEPARATOR[1], SEPARATOR[2], 1.0];
    assert_eq!(img.pixel(5 + 13, 12), sep);
    assert_eq!(img.pixel(5, 9), sep);
    assert_eq!(img.pixel(5 + 1 + 2 * 13 + 4, 9 + 1 + 10 + 4), [0.0; 4]);
    // Outside the montage: background.
    assert_eq!(img.pixel(2, 2), [0.0; 4]);
    // Other axes: axis 1 shows volume[y, k, x] (slices down), axis 2 volume[x, y, k].
    o.axis = 1;
    let img = composite(&rgba, None, &shape, &o).unwrap();
    let lay = slice_layout(50, 40, 3, 4, 5, 1);
    let (tx, ty) = lay.tile_origin(2);
    let s = lay.tile_w / 4;
    assert_eq!(
        img.pixel(tx + s * 3 + s / 2, ty + s * 4 + s / 2),
        [0.4, 0.2, 0.3, 1.0]
    );
    o.axis = 2;
    let img = composite(&rgba, None, &shape, &o).unwrap();
    let lay = slice_layout(50, 40, 4, 5, 3, 1);
    let (tx, ty) = lay.tile_origin(3);
    let s = lay.tile_w / 5;
    assert_eq!(
        img.pixel(tx + s * 4 + s / 2, ty + s / 2),
        [0.4, 0.0, 0.3, 1.0]
    );
    // Labels: slice 1's tile in a large picture gets a white "1" on a dark plate.
    o.axis = 0;
    o.labels = true;
    o.size = (400, 300);
    let img = composite(&rgba, None, &shape, &o).unwrap();
    let lay = slice_layout(400, 300, 5, 4, 3, 1);
    let (tx, ty) = lay.tile_origin(1);
    let ls = (lay.tile_h / 40).clamp(1, 4);
    assert!(ls >= 2);
    // The plate.
    assert_eq!(img.pixel(tx, ty), [0.0, 0.0, 0.0, 1.0]);
    // "1" = 010 / 110 / ...: font pixel (2, 1) of the label box is ink, (1, 1) is not.
    assert_eq!(img.pixel(tx + 2 * ls, ty + ls), [1.0; 4]);
    assert_eq!(img.pixel(tx + ls, ty + ls), [0.0, 0.0, 0.0, 1.0]);
    assert_eq!(
        img.pixel(tx + lay.tile_w - 1, ty + lay.tile_h - 1),
        [0.1, 0.2, 0.3, 1.0]
    );
}

fn random_retina(shape: &[usize], seed: u64, binary: bool, constant_axis0: bool) -> Vec<f32> {
    let mut r = rng(seed);
    let slice: usize = shape[1..].iter().product();
    let base: Vec<[f32; 4]> = (0..shape.iter().product::<usize>())
        .map(|_| {
            let a: f32 = if binary {
                if r.random_bool(0.3) {
                    1.0
                } else {
                    0.0
                }
            } else if r.random_bool(0.5) {
                r.random_range(0.0..1.0)
            } else {
                0.0
            };
            let c: [f32; 3] = std::array::from_fn(|_| r.random_range(0.0..1.0f32) * a);
            [c[0], c[1], c[2], a]
        })
        .collect();
    let mut out = Vec::new();
    for (i, _) in base.iter().enumerate() {
        let src = if constant_axis0 { i % slice } else { i };
        out.extend_from_slice(&base[src]);
    }
    out
}

#[test]
fn n5_constant_along_the_collapsed_axis_reduces_to_n4() {
    let shape5 = [3usize, 4, 5, 6];
    let slice = 4 * 5 * 6;
    // Opaque-or-empty cells: the stage gives exactly one slice.
    let rgba5 = random_retina(&shape5, 11, true, true);
    for mode in [
        CompositeMode::Volume,
        CompositeMode::Mip,
        CompositeMode::FirstHit,
        CompositeMode::Slices,
    ] {
        let o = ortho(mode, 25.0, 15.0, (48, 40));
        let a = composite(&rgba5, None, &shape5, &o).unwrap();
        let b = composite(&rgba5[..slice * 4], None, &shape5[1..], &o).unwrap();
        assert_eq!(a, b, "{mode:?}");
    }
    // Partial alphas: the stage composites L = 3 equal slices, 1 − (1 − a)³.
    let rgba5 = random_retina(&shape5, 12, false, true);
    let folded: Vec<f32> = rgba5[..slice * 4]
        .chunks(4)
        .flat_map(|c| {
            let a = c[3] as f64;
            let a3 = 1.0 - (1.0 - a).powi(3);
            let k = if a > 0.0 { a3 / a } else { 0.0 };
            [c[0] * k as f32, c[1] * k as f32, c[2] * k as f32, a3 as f32]
        })
        .collect();
    let o = ortho(CompositeMode::Volume, -30.0, 40.0, (32, 32));
    let a = composite(&rgba5, None, &shape5, &o).unwrap();
    let b = composite(&folded, None, &shape5[1..], &o).unwrap();
    for (x, y) in a.rgba.iter().zip(&b.rgba) {
        assert!(close(*x, *y, 2e-5), "{x} vs {y}");
    }
    // N = 6 and N = 7 recursions of retinas constant along the collapsed axes as well.
    for shape in [vec![2usize, 3, 4, 5, 6], vec![2usize, 2, 3, 3, 4, 5]] {
        let inner: usize = shape[shape.len() - 3..].iter().product();
        let mut r = rng(13);
        let base: Vec<[f32; 4]> = (0..inner)
            .map(|_| {
                if r.random_bool(0.4) {
                    [r.random_range(0.0..1.0), 0.5, 0.25, 1.0]
                } else {
                    [0.0; 4]
                }
            })
            .collect();
        let total: usize = shape.iter().product();
        let rgba: Vec<f32> = (0..total).flat_map(|i| base[i % inner]).collect();
        let o = ortho(CompositeMode::FirstHit, 40.0, 10.0, (32, 24));
        let a = composite(&rgba, None, &shape, &o).unwrap();
        let b = composite(&rgba[..inner * 4], None, &shape[shape.len() - 3..], &o).unwrap();
        assert_eq!(a, b, "{shape:?}");
    }
}

#[test]
fn perspective_stage_maps_slice_zero_exactly_and_shrinks_far_slices() {
    let shape = vec![5usize, 9, 9, 9];
    let cells: usize = shape.iter().product();
    let slice = 9 * 9 * 9;
    let lin = |s: usize, i: usize, j: usize, k: usize| ((s * 9 + i) * 9 + j) * 9 + k;
    // Slice 0 only: reproduced (up to interpolation round-off).
    let mut vol = vec![[0f32; 4]; cells];
    vol[lin(0, 1, 7, 2)] = [0.3, 0.6, 0.9, 1.0];
    vol[lin(0, 4, 4, 4)] = [0.2, 0.2, 0.2, 1.0];
    let (f, d) = stage_params(&shape, None);
    let out = project_stage(
        &Volume {
            shape: shape.clone(),
            cells: vol,
        },
        f,
        d,
        false,
    );
    assert_eq!(out.shape, vec![9, 9, 9]);
    for (i, c) in out.cells.iter().enumerate() {
        let expect = match i {
            i if i == lin(0, 1, 7, 2) => [0.3, 0.6, 0.9, 1.0],
            i if i == lin(0, 4, 4, 4) => [0.2, 0.2, 0.2, 1.0],
            _ => [0.0; 4],
        };
        for ch in 0..4 {
            assert!((c[ch] - expect[ch]).abs() < 1e-6, "cell {i}: {c:?}");
        }
    }
    // A cell of the last slice at offset +4 cells along every axis appears at
    // 4 · f / (d + x_last) cells: closer to the centre.
    let mut vol = vec![[0f32; 4]; cells];
    vol[lin(4, 8, 8, 8)] = [1.0; 4];
    let out = project_stage(
        &Volume {
            shape: shape.clone(),
            cells: vol,
        },
        f,
        d,
        false,
    );
    let c = 2.0 / 9.0;
    let x_last = (4.5 - 2.5) * c;
    let pos = (4.0 * f / (d + x_last) + 4.0).round() as usize;
    assert!(pos < 8);
    assert!(
        out.cells[lin(0, pos, pos, pos)][3] > 0.5,
        "{:?}",
        out.cells[lin(0, pos, pos, pos)]
    );
    assert_eq!(out.cells[lin(0, 8, 8, 8)][3], 0.0);
    let _ = slice;
}

#[test]
fn empty_space_skipping_and_storing_only_the_occupied_part_change_nothing() {
    // Sparse random blobs; the same picture, bit for bit, from the grid of every cell with every
    // block marked occupied.
    let shape = [37usize, 29, 45];
    let mut r = rng(21);
    let centres: Vec<[f64; 3]> = (0..6)
        .map(|_| {
            [
                r.random_range(6.0..30.0),
                r.random_range(5.0..23.0),
                r.random_range(6.0..38.0),
            ]
        })
        .collect();
    let rgba = retina(&shape, |i| {
        let near = centres
            .iter()
            .any(|c| (0..3).map(|k| (i[k] as f64 - c[k]).powi(2)).sum::<f64>() < 9.0);
        if near {
            [0.3, 0.2 + i[0] as f32 * 0.01, 0.1, 0.5]
        } else {
            [0.0; 4]
        }
    });
    let cells = prepare(&rgba, None, 37 * 29 * 45, &legacy());
    let vol = Volume {
        shape: shape.to_vec(),
        cells,
    };
    let grid = Grid::new(&vol);
    assert!(
        grid.occupied.iter().any(|&b| !b),
        "the test needs empty blocks"
    );
    let (lo, hi) = grid.stored_box();
    assert!(
        lo.min_element() > 0.0 || hi.x < 45.0 || hi.y < 29.0 || hi.z < 37.0,
        "the test needs a part of the volume left out"
    );
    let mut full = Grid::whole(&vol);
    full.occupied.iter_mut().for_each(|b| *b = true);
    for (mode, az, el, projection) in [
        (CompositeMode::Volume, 30.0, 20.0, Projection::Perspective),
        (
            CompositeMode::Volume,
            -100.0,
            45.0,
            Projection::Orthographic,
        ),
        (CompositeMode::Mip, 12.0, -30.0, Projection::Perspective),
        (
            CompositeMode::FirstHit,
            200.0,
            10.0,
            Projection::Perspective,
        ),
        (CompositeMode::FirstHit, 0.0, 0.0, Projection::Orthographic),
    ] {
        let o = CompositeOptions {
            mode,
            azimuth: az,
            elevation: el,
            projection,
            size: (90, 70),
            step: 0.37,
            // First-hit's surface is at coverage ½ · min(opacity, 1) (the cells, prepared above,
            // have alpha ½): put it at ¼ so the balls show.
            opacity: if mode == CompositeMode::FirstHit {
                0.5
            } else {
                1.0
            },
            ..legacy()
        };
        let a = render_3d(&grid, mode, &o, [0.0; 3]);
        let b = render_3d(&full, mode, &o, [0.0; 3]);
        let differ = a
            .chunks(4)
            .zip(b.chunks(4))
            .filter(|(x, y)| {
                x.iter()
                    .zip(y.iter())
                    .any(|(u, v)| u.to_bits() != v.to_bits())
            })
            .count();
        assert!(differ == 0, "{mode:?} az {az}: {differ} pixels differ");
        assert!(a.chunks(4).filter(|p| p[3] > 0.0).count() > 100);
    }
}

#[test]
fn output_is_identical_whatever_the_thread_count() {
    let shape = [20usize, 24, 28];
    let rgba = random_retina(&shape, 5, false, false);
    let shape5 = [3usize, 10, 12, 14];
    let rgba5 = random_retina(&shape5, 6, false, false);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut outs = vec![];
            for mode in [
                CompositeMode::Volume,
                CompositeMode::Mip,
                CompositeMode::FirstHit,
                CompositeMode::Slices,
            ] {
                let o = CompositeOptions {
                    mode,
                    azimuth: 37.0,
                    elevation: -15.0,
                    opacity: 0.3,
                    size: (70, 50),
                    ..legacy()
                };
                outs.push(composite(&rgba, None, &shape, &o).unwrap());
                outs.push(composite(&rgba5, None, &shape5, &o).unwrap());
            }
            outs
        })
    };
    let one = run(1);
    assert_eq!(one, run(3));
    assert_eq!(one, run(2));
}

#[test]
fn depth_cue_tints_near_warm_and_far_cool() {
    let shape = [1usize, 1, 3];
    let rgba = vec![0.5, 0.5, 0.5, 1.0, 0.5, 0.5, 0.5, 1.0, 0.0, 0.0, 0.0, 0.0];
    let depth = [2.0f32, 6.0, f32::INFINITY];
    let o = CompositeOptions {
        mode: CompositeMode::FirstHit,
        depth_cue: 1.0,
        size: (3, 1),
        ..legacy()
    };
    // Through the 2D path (N = 3 would need 2 axes): use the prepared cells directly.
    let cells = prepare(&rgba, Some(&depth), 3, &o);
    assert_eq!(&cells[0][..3], &NEAR_TINT.map(|t| 0.5 * t));
    assert_eq!(&cells[1][..3], &FAR_TINT.map(|t| 0.5 * t));
    assert_eq!(cells[2], [0.0; 4]);
    let half = CompositeOptions {
        depth_cue: 0.5,
        ..o.clone()
    };
    let cells = prepare(&rgba, Some(&depth), 3, &half);
    assert!((cells[0][0] - 0.5 * (0.5 + 0.5 * NEAR_TINT[0])).abs() < 1e-7);
    // End to end: face-on first_hit of the two cells.
    let img = composite(
        &rgba,
        Some(&depth),
        &shape,
        &ortho(CompositeMode::FirstHit, 0.0, 0.0, (30, 10)),
    )
    .unwrap();
    // The box spans x ∈ [−1, 1], pixels 10.5 … 19.5: cells at pixels 12, 15 and 18.
    let plain = img.pixel(12, 5);
    let mut o = ortho(CompositeMode::FirstHit, 0.0, 0.0, (30, 10));
    o.depth_cue = 1.0;
    let img = composite(&rgba, Some(&depth), &shape, &o).unwrap();
    let (near, far) = (img.pixel(12, 5), img.pixel(15, 5));
    assert_eq!(plain, [0.5, 0.5, 0.5, 1.0]);
    assert!(near[0] > near[2] && far[2] > far[0], "{near:?} {far:?}");
}

#[test]
fn two_d_and_one_d_retinas() {
    let shape = [3usize, 4];
    let rgba = retina(&shape, |i| {
        [i[0] as f32 * 0.25, i[1] as f32 * 0.2, 0.0, 0.5]
    });
    let bg = [0.0, 0.0, 1.0];
    let o = CompositeOptions {
        size: (4, 3),
        background: bg,
        ..legacy()
    };
    let img = composite(&rgba, None, &shape, &o).unwrap();
    for r in 0..3 {
        for c in 0..4 {
            assert_eq!(img.pixel(c, r), [r as f32 * 0.25, c as f32 * 0.2, 0.5, 0.5]);
        }
    }
    // 10 × 10: scale ⌊min(10/4, 10/3)⌋ = 2, an 8 × 6 picture at (1, 2).
    let o = CompositeOptions {
        size: (10, 10),
        ..o
    };
    let img = composite(&rgba, None, &shape, &o).unwrap();
    assert_eq!(img.pixel(0, 0), [0.0, 0.0, 1.0, 0.0]);
    assert_eq!(
        img.pixel(1 + 2 * 3 + 1, 2 + 2 * 2 + 1),
        [0.5, 0.6, 0.5, 0.5]
    );
    assert_eq!(img.pixel(9, 5), [0.0, 0.0, 1.0, 0.0]);
    // 1D: a 20-cell retina as a 40 × 10 picture with a 4-row strip in rows 3..7.
    let rgba: Vec<f32> = (0..20)
        .flat_map(|i| [i as f32 / 20.0, 0.0, 0.0, 1.0])
        .collect();
    let o = CompositeOptions {
        size: (40, 10),
        strip_height: 4,
        ..legacy()
    };
    let img = composite(&rgba, None, &[20], &o).unwrap();
    for y in 0..10 {
        for x in 0..40 {
            let expect = if (3..7).contains(&y) {
                [(x / 2) as f32 / 20.0, 0.0, 0.0, 1.0]
            } else {
                [0.0; 4]
            };
            assert_eq!(img.pixel(x, y), expect, "({x}, {y})");
        }
    }
}

#[test]
fn bad_input_is_a_clear_error() {
    let shape = [2usize, 2, 2];
    let rgba = vec![0f32; 32];
    let ok = legacy();
    assert!(composite(&rgba, None, &shape, &ok).is_ok());
    let arg_of = |e: NdError| match e {
        NdError::Value { arg, message } => (arg, message),
        NdError::Shape { arg, expected, got } => (arg, format!("{expected} / {got}")),
        e => panic!("unexpected {e:?}"),
    };
    let err = |rgba: &[f32], depth: Option<&[f32]>, shape: &[usize], o: &CompositeOptions| {
        arg_of(composite(rgba, depth, shape, o).unwrap_err())
    };
    let (a, m) = err(&rgba[..31], None, &shape, &ok);
    assert_eq!(a, "rgba");
    assert!(
        m.contains("(2, 2, 2, 4) = 32 floats") && m.contains("31"),
        "{m}"
    );
    assert_eq!(err(&rgba, Some(&[0.0; 7]), &shape, &ok).0, "depth");
    assert_eq!(err(&[], None, &[], &ok).0, "shape");
    let s8 = [1usize; 8];
    let (a, m) = err(&[0.0; 4], None, &s8, &ok);
    assert!(a == "shape" && m.contains("1 to 7"), "{m}");
    assert_eq!(err(&[], None, &[2, 0, 2], &ok).0, "shape");
    let with = |f: &dyn Fn(&mut CompositeOptions)| {
        let mut o = legacy();
        f(&mut o);
        err(&rgba, None, &shape, &o)
    };
    assert_eq!(with(&|o| o.size = (0, 10)).0, "size");
    assert_eq!(with(&|o| o.size = (100_000, 100_000)).0, "size");
    let (a, m) = with(&|o| {
        o.mode = CompositeMode::Slices;
        o.axis = 3
    });
    assert!(a == "axis" && m.contains('3'), "{m}");
    assert_eq!(with(&|o| o.azimuth = f64::NAN).0, "azimuth");
    assert_eq!(with(&|o| o.elevation = f64::INFINITY).0, "elevation");
    assert_eq!(with(&|o| o.distance = 0.5).0, "distance");
    assert_eq!(with(&|o| o.opacity = -1.0).0, "opacity");
    assert_eq!(with(&|o| o.depth_cue = 2.0).0, "depth_cue");
    assert_eq!(with(&|o| o.depth_cue = 0.5).0, "depth_cue"); // no depth
    assert_eq!(
        with(&|o| o.background = [0.0, f64::NAN, 0.0]).0,
        "background[1]"
    );
    assert_eq!(with(&|o| o.step = 0.0).0, "step");
    assert_eq!(with(&|o| o.zoom = 0.0).0, "zoom");
    assert_eq!(with(&|o| o.strip_height = 0).0, "strip_height");
    // Orthographic views accept any positive distance.
    let o = CompositeOptions {
        distance: 0.5,
        projection: Projection::Orthographic,
        ..legacy()
    };
    assert!(composite(&rgba, None, &shape, &o).is_ok());
    // Stages: N − 4 pairs, f > 0, d beyond the box.
    let shape5 = [2usize, 2, 2, 2];
    let rgba5 = vec![0f32; 64];
    let o = CompositeOptions {
        stages: vec![(1.0, 3.0), (1.0, 3.0)],
        ..legacy()
    };
    assert_eq!(err(&rgba5, None, &shape5, &o).0, "stages");
    let o = CompositeOptions {
        stages: vec![(1.0, 0.5)],
        ..legacy()
    };
    assert_eq!(err(&rgba5, None, &shape5, &o).0, "stages[0]");
    let o = CompositeOptions {
        stages: vec![(2.0, 3.0)],
        ..legacy()
    };
    assert!(composite(&rgba5, None, &shape5, &o).is_ok());
    // Stage values must be finite even where orthographic stages do not use them.
    let o = CompositeOptions {
        stages: vec![(f64::NAN, 3.0)],
        projection: Projection::Orthographic,
        ..legacy()
    };
    assert_eq!(err(&rgba5, None, &shape5, &o).0, "stages[0]");
}

#[test]
fn pictures_traced_on_a_lattice_are_the_pictures_traced_at_every_pixel_within_a_level() {
    // Bodies as a traced retina has them: balls covered inside, partly covered on their rims,
    // coloured smoothly, in a small retina seen large, so that a cell spans many pixels and the
    // lattice skips most of them; and random cells (sharp jumps from cell to cell), the worst
    // case, at two rays per cell.
    let shape = [24usize, 28, 32];
    let balls = [
        ([8.0, 10.0, 11.0], 6.0),
        ([15.0, 17.0, 21.0], 7.5),
        ([12.0, 20.0, 8.0], 3.0),
    ];
    let bodies = retina(&shape, |i| {
        let cover = balls
            .iter()
            .map(|(c, r)| {
                let d = (0..3)
                    .map(|k| (i[k] as f64 + 0.5 - c[k]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                (r + 0.5 - d).clamp(0.0, 1.0)
            })
            .fold(0.0, f64::max) as f32;
        let col = [
            0.3 + i[2] as f32 * 0.02,
            0.6 - i[1] as f32 * 0.01,
            0.2 + i[0] as f32 * 0.015,
        ];
        [col[0] * cover, col[1] * cover, col[2] * cover, cover]
    });
    let random = random_retina(&[9, 11, 13], 31, false, false);
    let srgb = |v: f32| v.max(0.0).sqrt();
    for (mode, opacity, (cells, shape), projection, rays_per_cell, bound) in [
        (
            CompositeMode::Volume,
            0.3,
            (&bodies, [24, 28, 32]),
            Projection::Perspective,
            1,
            0.03,
        ),
        (
            CompositeMode::Volume,
            1.0,
            (&bodies, [24, 28, 32]),
            Projection::Orthographic,
            1,
            0.06,
        ),
        (
            CompositeMode::FirstHit,
            1.0,
            (&bodies, [24, 28, 32]),
            Projection::Perspective,
            1,
            0.03,
        ),
        (
            CompositeMode::Illustrative,
            1.0,
            (&bodies, [24, 28, 32]),
            Projection::Perspective,
            1,
            0.03,
        ),
        (
            CompositeMode::Volume,
            0.4,
            (&random, [9, 11, 13]),
            Projection::Perspective,
            2,
            0.04,
        ),
        (
            CompositeMode::Illustrative,
            1.0,
            (&random, [9, 11, 13]),
            Projection::Perspective,
            2,
            0.03,
        ),
    ] {
        let o = CompositeOptions {
            mode,
            opacity,
            projection,
            azimuth: 23.0,
            elevation: 31.0,
            size: (320, 240),
            background: [0.2, 0.3, 0.4],
            rays_per_cell,
            ..Default::default()
        };
        let vol = Volume {
            shape: shape.to_vec(),
            cells: prepare(cells, None, shape.iter().product(), &o),
        };
        let grid = Grid::new(&vol);
        // The views frame the occupied part's hull (`fit`): its box sets the pixel size.
        let framed = super::annotate::hull(&shape, &vol.cells).map(|h| h.frame);
        let cam = volume::Camera3::new([shape[2], shape[1], shape[0]], framed, &o);
        // The spacing over the stored part of the prepared volume (what the volume and
        // first-hit views render), and the least spacing any grid of this volume can have
        // (the illustrative view renders a classified grid of its own, stored in a box of
        // its own within the volume).
        let s = volume::lattice_spacing(&cam, grid.stored_box(), o.rays_per_cell);
        let least = volume::lattice_spacing(&cam, Grid::whole(&vol).stored_box(), o.rays_per_cell);
        assert!(
            least >= 3 && s >= least,
            "{mode:?}: the lattice must skip pixels (spacing {least} … {s})"
        );
        let traced = composite(
            cells,
            None,
            &shape,
            &CompositeOptions {
                rays_per_cell: 0,
                ..o.clone()
            },
        )
        .unwrap();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| composite(cells, None, &shape, &o).unwrap())
        };
        let lattice = run(1);
        assert_eq!(
            lattice,
            run(3),
            "{mode:?}: the same picture on any number of threads"
        );
        // Lattice pixels are traced; the others differ by little, and rarely at all.
        let (w, h) = o.size;
        let (mut worst, mut off) = (0f32, 0usize);
        for y in 0..h {
            for x in 0..w {
                let (a, b) = (lattice.pixel(x, y), traced.pixel(x, y));
                if mode != CompositeMode::Illustrative && x % s == 0 && y % s == 0 {
                    assert_eq!(a, b, "{mode:?}: lattice pixel ({x}, {y})");
                }
                // Colour as √RGB (about perceived lightness), alpha as it is.
                let d = (0..3)
                    .map(|k| (srgb(a[k]) - srgb(b[k])).abs())
                    .fold((a[3] - b[3]).abs(), f32::max);
                worst = worst.max(d);
                off += usize::from(d > 2.0 / 255.0);
            }
        }
        assert!(worst < bound, "{mode:?}: a pixel off by {worst}");
        assert!(
            off * 200 < w * h,
            "{mode:?}: {off} pixels off by more than 2 levels"
        );
        assert!(
            traced.rgba.chunks(4).filter(|p| p[3] > 0.02).count() > w * h / 20,
            "{mode:?}: content"
        );
        // The half-opacity distances the edge overlay fades edges with: finite where the
        // traced picture's are, and close to them.
        if mode != CompositeMode::Illustrative {
            let bg = [0.2, 0.3, 0.4];
            let every = CompositeOptions {
                rays_per_cell: 0,
                ..o.clone()
            };
            let th = |o: &CompositeOptions| {
                volume::render_view(&grid, &cam, mode, o, bg, true)
                    .1
                    .unwrap()
            };
            let (a, b) = (th(&o), th(&every));
            let mut off = 0usize;
            for (x, y) in a.iter().zip(&b) {
                if x.is_finite() != y.is_finite() {
                    off += 1;
                } else if x.is_finite() {
                    off += usize::from((x - y).abs() > 0.05 * y.abs().max(1.0));
                }
            }
            assert!(
                off * 200 < w * h,
                "{mode:?}: {off} half-opacity distances off"
            );
        }
    }
    // A maximum-intensity picture is a mosaic of cells: traced at every pixel.
    let o = CompositeOptions {
        mode: CompositeMode::Mip,
        size: (320, 240),
        ..Default::default()
    };
    let every = CompositeOptions {
        rays_per_cell: 0,
        ..o.clone()
    };
    assert_eq!(
        composite(&bodies, None, &shape, &o).unwrap(),
        composite(&bodies, None, &shape, &every).unwrap()
    );
}
