//! Tests of the illustrative mode, the edge overlay, the stages' point map and `fit`.

use super::{smooth, Cues3, RetinaCamera};
use crate::camera::Projection;
use crate::composite::overlay::edge_color;
use crate::composite::stages::stage_point;
use crate::composite::volume::Camera3;
use crate::composite::*;

fn options(size: (usize, usize)) -> CompositeOptions {
    CompositeOptions {
        mode: CompositeMode::Illustrative,
        azimuth: 0.0,
        elevation: 0.0,
        projection: Projection::Orthographic,
        size,
        fit: false,
        edge_color_by: EdgeColorBy::None,
        ..Default::default()
    }
}

/// A 3D retina (numpy order) fully covered, depth 5, normal from `normal(index)`.
fn block(
    shape: [usize; 3],
    normal: impl Fn([usize; 3]) -> [f32; 4],
) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let cells = shape.iter().product::<usize>();
    let mut rgba = Vec::with_capacity(cells * 4);
    let mut nrm = Vec::with_capacity(cells * 4);
    for z in 0..shape[0] {
        for y in 0..shape[1] {
            for x in 0..shape[2] {
                rgba.extend_from_slice(&[0.5, 0.4, 0.3, 1.0]);
                nrm.extend_from_slice(&normal([z, y, x]));
            }
        }
    }
    (rgba, vec![5.0; cells], nrm)
}

#[test]
fn creases_between_cells_of_different_normals_are_opaque_and_flat_cells_clear() {
    // Columns 0..8 face e_1, columns 8..16 face e_2: one crease plane x = 8, seen edge-on
    // from the front (looking along the slices).
    let shape = [16, 16, 16];
    let (rgba, depth, normal) = block(shape, |[_, _, x]| {
        if x < 8 {
            [1., 0., 0., 0.]
        } else {
            [0., 1., 0., 0.]
        }
    });
    let extras = RetinaExtras {
        normal: Some(&normal),
        ..Default::default()
    };
    let o = options((64, 64));
    let img = composite_retina(&rgba, Some(&depth), &shape, &extras, &o).unwrap();
    // Face-on orthographic: the cube's 16 columns span 64/√3·… pixels; find the crease column
    // as the pixel column of the largest alpha along the middle row.
    let row = 32;
    let alphas: Vec<f32> = (0..64).map(|x| img.pixel(x, row)[3]).collect();
    let (best, amax) = alphas
        .iter()
        .enumerate()
        .fold((0, 0f32), |b, (i, &a)| if a > b.1 { (i, a) } else { b });
    assert!(
        (best as i32 - 32).abs() <= 1,
        "crease at pixel {best}: {alphas:?}"
    );
    // Away from the crease and the silhouette, a ray through 16 nearly clear cells.
    let inner = alphas[24];
    let expect = 1.0 - (1.0 - illustrative::INTERIOR_OPACITY).powi(16);
    assert!(
        (inner - expect).abs() < 0.08,
        "interior alpha {inner}, expected ≈ {expect}"
    );
    assert!(amax > 2.0 * inner, "crease {amax} vs interior {inner}");
    // The same block with one normal everywhere has no crease.
    let (rgba, depth, normal) = block(shape, |_| [1., 0., 0., 0.]);
    let flat = composite_retina(
        &rgba,
        Some(&depth),
        &shape,
        &RetinaExtras {
            normal: Some(&normal),
            ..Default::default()
        },
        &o,
    )
    .unwrap();
    assert!((flat.pixel(32, row)[3] - inner).abs() < 0.02);
    // A crease of 10° is below the default crease angle, and above a crease angle of 5°.
    let c10 = (10f32).to_radians();
    let (rgba, depth, normal) = block(shape, |[_, _, x]| {
        if x < 8 {
            [1., 0., 0., 0.]
        } else {
            [c10.cos(), c10.sin(), 0., 0.]
        }
    });
    let extras = RetinaExtras {
        normal: Some(&normal),
        ..Default::default()
    };
    let at = |o: &CompositeOptions| {
        composite_retina(&rgba, Some(&depth), &shape, &extras, o)
            .unwrap()
            .pixel(32, row)[3]
    };
    assert!((at(&o) - inner).abs() < 0.02);
    assert!(
        at(&CompositeOptions {
            crease_angle: 5.0,
            ..o.clone()
        }) > 2.0 * inner
    );
}

#[test]
fn occlusion_contours_need_surfaces_apart_in_n_d() {
    // Same normal everywhere, but the right half of the columns sees a surface much farther
    // away: with the camera, the hit points are far from each other's tangent hyperplanes.
    let shape = [16, 16, 16];
    let (rgba, mut depth, normal) = block(shape, |_| [0., 0., 0., 1.]);
    for (i, d) in depth.iter_mut().enumerate() {
        if i % 16 >= 8 {
            *d = 9.0;
        }
    }
    let camera = RetinaCamera {
        orientation: vec![
            1., 0., 0., 0., //
            0., 1., 0., 0., //
            0., 0., 1., 0., //
            0., 0., 0., -1.,
        ],
        cell: 0.05,
        perspective: true,
    };
    let o = options((64, 64));
    let with = |camera: Option<RetinaCamera>| {
        let extras = RetinaExtras {
            normal: Some(&normal),
            camera,
            ..Default::default()
        };
        composite_retina(&rgba, Some(&depth), &shape, &extras, &o).unwrap()
    };
    let img = with(Some(camera));
    assert!(img.pixel(32, 32)[3] > 2.0 * img.pixel(24, 32)[3]);
    // Without a camera the relative depth jump (9 vs 5) still shows it.
    let img = with(None);
    assert!(img.pixel(32, 32)[3] > 2.0 * img.pixel(24, 32)[3]);
}

#[test]
fn visible_edges_are_solid_and_hidden_ones_dashed() {
    // An empty 8³ retina (nothing to frame) with one visible edge along row 2 and one hidden
    // edge along row 6, both across all columns, in slice 4.
    let shape = [8, 8, 8];
    let rgba = vec![0f32; 8 * 8 * 8 * 4];
    let edge = |row: f64, visible: bool| {
        let mut e = RetinaEdge {
            a: [0.0; MAX_RETINA_DIM],
            b: [0.0; MAX_RETINA_DIM],
            depth: [3.0, 4.0],
            visible,
            color: [1.0; 3],
        };
        e.a[..3].copy_from_slice(&[4.0, row, 0.0]);
        e.b[..3].copy_from_slice(&[4.0, row, 8.0]);
        e
    };
    let edges = [edge(2.0, true), edge(6.0, false)];
    let extras = RetinaExtras {
        edges: &edges,
        ..Default::default()
    };
    let o = CompositeOptions {
        edge_width: 3.0,
        ..options((96, 96))
    };
    let img = composite_retina(&rgba, None, &shape, &extras, &o).unwrap();
    // Face-on orthographic: the shorter side spans the cube's bounding sphere, 2√3·(8 cells)/2.
    let pixels_per_cell = 96.0 / (8.0 * 3f64.sqrt());
    let y_of = |row: f64| (48.0 + (row - 4.0) * pixels_per_cell) as usize;
    let white = edge_color(&o);
    let visible: Vec<f32> = (30..66).map(|x| img.pixel(x, y_of(2.0))[3]).collect();
    assert!(visible.iter().all(|&a| a > 0.95), "{visible:?}");
    assert!((img.pixel(48, y_of(2.0))[0] - white[0]).abs() < 0.02);
    let hidden: Vec<f32> = (30..66).map(|x| img.pixel(x, y_of(6.0))[3]).collect();
    let on = hidden.iter().filter(|&&a| a > 0.4).count();
    let off = hidden.iter().filter(|&&a| a < 0.05).count();
    assert!(on > 8 && off > 8, "a dashed line: {hidden:?}");
    assert!(
        hidden.iter().all(|&a| a < 0.65),
        "hidden edges are fainter: {hidden:?}"
    );
    // Between the lines, nothing.
    assert_eq!(img.pixel(48, y_of(4.0))[3], 0.0);
    // Hidden edges can be left out, and all edges switched off.
    for (o2, row) in [
        (
            CompositeOptions {
                hidden_edges: HiddenEdges::None,
                ..o.clone()
            },
            6.0,
        ),
        (
            CompositeOptions {
                edges: false,
                ..o.clone()
            },
            2.0,
        ),
    ] {
        let img = composite_retina(&rgba, None, &shape, &extras, &o2).unwrap();
        assert!((30..66).all(|x| img.pixel(x, y_of(row))[3] == 0.0));
    }
    // The other modes draw no edges.
    let vol = composite_retina(
        &rgba,
        None,
        &shape,
        &extras,
        &CompositeOptions {
            mode: CompositeMode::Volume,
            ..o
        },
    )
    .unwrap();
    assert!(vol.rgba.chunks(4).all(|p| p[3] == 0.0));
}

#[test]
fn camera_projection_inverts_its_rays() {
    let n = [9, 7, 5];
    for (projection, fit) in [
        (Projection::Perspective, None),
        (Projection::Orthographic, None),
        (
            Projection::Perspective,
            Some(([1.0, 2.0, 0.5], [4.0, 6.0, 3.0])),
        ),
    ] {
        let o = CompositeOptions {
            azimuth: 37.0,
            elevation: -21.0,
            projection,
            size: (40, 30),
            ..Default::default()
        };
        let cam = Camera3::new(n, fit, &o);
        for (px, py) in [(0, 0), (39, 29), (17, 11), (20, 15)] {
            let (org, dir, _) = cam.ray(px, py);
            let p = org + dir * 7.5;
            let (q, _) = cam.project(p).unwrap();
            assert!(
                (q[0] - (px as f64 + 0.5)).abs() < 1e-9 && (q[1] - (py as f64 + 0.5)).abs() < 1e-9,
                "{projection:?}: pixel ({px}, {py}) → {q:?}"
            );
        }
    }
}

#[test]
fn stage_point_is_the_map_the_stage_samples_along() {
    // project_stage gives output cell i (film y = (i + ½ − R/2)·c) the input point
    // x = y·(d + x_k)/f of slice s; stage_point must send that point back to the cell centre.
    let shape = [6usize, 5, 7, 4];
    let (f, d) = stage_params(&shape, None);
    let c = 2.0 / 7.0;
    for s in 0..6 {
        let xk = (s as f64 + 0.5 - 3.0) * c;
        for (i, j, k) in [(0, 0, 0), (4, 6, 3), (2, 3, 1)] {
            let y = [i, j, k]
                .iter()
                .zip(&shape[1..])
                .map(|(&i, &r)| (i as f64 + 0.5 - r as f64 / 2.0) * c)
                .collect::<Vec<_>>();
            let mut xi = vec![s as f64 + 0.5];
            for (a, &ya) in y.iter().enumerate() {
                let x = ya * (d + xk) / f;
                xi.push(x / c + shape[a + 1] as f64 / 2.0);
            }
            let out = stage_point(&shape, f, d, false, &xi);
            for (a, (&o, &ii)) in out.iter().zip([i, j, k].iter()).enumerate() {
                assert!(
                    (o - (ii as f64 + 0.5)).abs() < 1e-12,
                    "slice {s}, axis {a}: {o}"
                );
            }
        }
    }
}

#[test]
fn fit_frames_the_occupied_cells() {
    // One opaque 2³ block in a corner of a 16³ retina: framed, it fills far more of the picture.
    let shape = [16, 16, 16];
    let mut rgba = vec![0f32; 16 * 16 * 16 * 4];
    for z in 0..2 {
        for y in 0..2 {
            for x in 0..2 {
                let i = x + 16 * (y + 16 * z);
                rgba[i * 4..i * 4 + 4].copy_from_slice(&[0.8, 0.8, 0.8, 1.0]);
            }
        }
    }
    let cover = |fit: bool| {
        let o = CompositeOptions {
            mode: CompositeMode::Volume,
            fit,
            size: (64, 64),
            ..Default::default()
        };
        let img = composite(&rgba, None, &shape, &o).unwrap();
        img.rgba.chunks(4).filter(|p| p[3] > 0.5).count()
    };
    let (framed, whole) = (cover(true), cover(false));
    assert!(
        framed > 20 * whole.max(1),
        "fit {framed} pixels, whole box {whole}"
    );
    // The framed block is centred.
    let o = CompositeOptions {
        mode: CompositeMode::Volume,
        size: (64, 64),
        ..Default::default()
    };
    let img = composite(&rgba, None, &shape, &o).unwrap();
    assert!(img.pixel(32, 32)[3] > 0.5);
}

#[test]
fn illustrative_pictures_do_not_depend_on_the_thread_count() {
    let shape = [12, 10, 14];
    let (rgba, depth, normal) = block(shape, |[z, y, x]| {
        let v = [(x as f32).sin(), (y as f32).cos(), z as f32 * 0.1, 1.0];
        let l = v.iter().map(|a| a * a).sum::<f32>().sqrt();
        v.map(|a| a / l)
    });
    let edges = [RetinaEdge {
        a: [1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 0.0],
        b: [11.0, 8.0, 12.0, 0.0, 0.0, 0.0, 0.0],
        depth: [2.0, 3.0],
        visible: true,
        color: [1.0; 3],
    }];
    let extras = RetinaExtras {
        normal: Some(&normal),
        edges: &edges,
        ..Default::default()
    };
    let o = CompositeOptions {
        size: (50, 40),
        ..Default::default()
    };
    let run = |t: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
            .install(|| composite_retina(&rgba, Some(&depth), &shape, &extras, &o).unwrap())
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn cues_found_in_the_window_around_the_hit_cells_are_those_of_the_whole_retina() {
    // A 4D-lit ball off-centre in a 26 × 30 × 34 retina: normals, depths and hits vary, and a
    // perspective retina camera places the hit points (occlusion contours).
    let shape = [26usize, 30, 34];
    let (c, r) = ([13.0, 15.0, 20.0], 6.5);
    let cells: usize = shape.iter().product();
    let (mut rgba, mut depth, mut normal) = (
        vec![0f32; cells * 4],
        vec![f32::INFINITY; cells],
        vec![0f32; cells * 4],
    );
    for z in 0..shape[0] {
        for y in 0..shape[1] {
            for x in 0..shape[2] {
                let p = [z as f64 - c[0], y as f64 - c[1], x as f64 - c[2]];
                let d2 = p.iter().map(|v| v * v).sum::<f64>();
                if d2 > r * r {
                    continue;
                }
                let i = (z * shape[1] + y) * shape[2] + x;
                let w = (r * r - d2).sqrt();
                let len = (d2 + w * w).sqrt();
                let nrm = [p[2] / len, -p[1] / len, p[0] / len, -w / len];
                normal[i * 4..i * 4 + 4].copy_from_slice(&nrm.map(|v| v as f32));
                let a = if d2 > (r - 1.0) * (r - 1.0) { 0.6 } else { 1.0 };
                rgba[i * 4..i * 4 + 4].copy_from_slice(&[0.7 * a, 0.5 * a, 0.2 * a, a]);
                depth[i] = (6.0 - w * 0.05 + if x > 21 { 1.5 } else { 0.0 }) as f32;
            }
        }
    }
    let camera = RetinaCamera {
        orientation: (0..16)
            .map(|k| if k % 5 == 0 { 1.0 } else { 0.0 })
            .collect(),
        cell: 0.02,
        perspective: true,
    };
    let o = CompositeOptions {
        background: [0.9, 0.9, 0.9],
        ..options((40, 40))
    };
    let whole = Cues3::new(
        &rgba,
        &depth,
        Some(&normal),
        &shape,
        illustrative::Window {
            origin: &[0, 0, 0],
            full: &shape,
        },
        Some(&camera),
        &o,
    );
    // The window: the hit cells' box grown by the cues' reach.
    let lo = [
        (c[0] - r).floor() as usize - illustrative::CUE_REACH,
        (c[1] - r).floor() as usize - illustrative::CUE_REACH,
        (c[2] - r).floor() as usize - illustrative::CUE_REACH,
    ];
    let m: [usize; 3] = std::array::from_fn(|k| {
        ((c[k] + r).ceil() as usize + 1 + illustrative::CUE_REACH).min(shape[k]) - lo[k]
    });
    assert!(
        (0..3).all(|k| m[k] < shape[k]),
        "the window must leave cells out: {m:?}"
    );
    let part = |data: &[f32], width: usize| -> Vec<f32> {
        let mut out = vec![];
        for z in lo[0]..lo[0] + m[0] {
            for y in lo[1]..lo[1] + m[1] {
                let row = (z * shape[1] + y) * shape[2] + lo[2];
                out.extend_from_slice(&data[row * width..(row + m[2]) * width]);
            }
        }
        out
    };
    let windowed = Cues3::new(
        &part(&rgba, 4),
        &part(&depth, 1),
        Some(&part(&normal, 4)),
        &m,
        illustrative::Window {
            origin: &lo,
            full: &shape,
        },
        Some(&camera),
        &o,
    );
    for (az, el, projection) in [
        (30.0, 20.0, Projection::Perspective),
        (-70.0, 5.0, Projection::Orthographic),
    ] {
        let view = CompositeOptions {
            azimuth: az,
            elevation: el,
            projection,
            ..o.clone()
        };
        let cam = Camera3::new([shape[2], shape[1], shape[0]], None, &view);
        let a = whole.classify(&cam);
        let b = windowed.classify(&cam);
        let mut inside = 0;
        for z in 0..shape[0] {
            for y in 0..shape[1] {
                for x in 0..shape[2] {
                    let va = a.cells[(z * shape[1] + y) * shape[2] + x];
                    let k = [z, y, x];
                    if (0..3).all(|j| (lo[j]..lo[j] + m[j]).contains(&k[j])) {
                        let vb = b.cells[((z - lo[0]) * m[1] + y - lo[1]) * m[2] + x - lo[2]];
                        assert_eq!(va.map(f32::to_bits), vb.map(f32::to_bits), "cell {k:?}");
                        inside += usize::from(va[3] > 0.0);
                    } else {
                        assert_eq!(va, [0.0; 4], "cell {k:?} outside the window");
                    }
                }
            }
        }
        assert!(inside > 1000, "{inside} cells with opacity");
    }
}

#[test]
fn n5_silhouettes_outline_the_projected_body_without_fog_or_halo() {
    // A cube of cells 4..12 of a 16³ retina, the same in slices 1..5 of the 6 of a 4D retina
    // (N = 5): a 4D box, faces across the collapsed axis included. Through an orthographic
    // stage, the 3D volume of a cube; seen face-on, the cube spans x ∈ [−½, ½] of the unit
    // box, pixels 32 ± 64/(2√3)·½ of a 64² picture. (A silhouette shell classified in 4D
    // covers the whole cube in slices 1 and 4, a fog once projected.)
    let shape = [6usize, 16, 16, 16];
    let inside = |i: usize| (4..12).contains(&i);
    let mut rgba = Vec::new();
    for s in 0..shape[0] {
        for z in 0..16 {
            for y in 0..16 {
                for x in 0..16 {
                    let body = (1..5).contains(&s) && inside(x) && inside(y) && inside(z);
                    let a = if body { 1.0 } else { 0.0 };
                    rgba.extend_from_slice(&[0.5 * a, 0.4 * a, 0.3 * a, a]);
                }
            }
        }
    }
    let depth = vec![5.0f32; rgba.len() / 4];
    let o = options((64, 64));
    let img = composite_retina(&rgba, Some(&depth), &shape, &RetinaExtras::default(), &o).unwrap();
    let row = 32;
    let alphas: Vec<f32> = (0..64).map(|x| img.pixel(x, row)[3]).collect();
    let half = 64.0 / (2.0 * 3f32.sqrt()) * 0.5;
    let cell = 64.0 / (2.0 * 3f32.sqrt()) * 0.125;
    // No halo: rays that pass more than a cell (the trilinear reach) from the cube see nothing.
    for (x, &a) in alphas.iter().enumerate() {
        if (x as f32 + 0.5 - 32.0).abs() > half + cell + 1.0 {
            assert!(
                a < 1e-6,
                "pixel {x} outside the cube: alpha {a}: {alphas:?}"
            );
        }
    }
    // No fog: through the middle, the 8 cells' interior (each the stage's 4 slices of
    // INTERIOR_OPACITY) and the two faces' faint silhouette, nothing more.
    let slab = 1.0 - (1.0 - illustrative::INTERIOR_OPACITY).powi(4);
    let body = 1.0 - (1.0 - slab).powi(8);
    let faces = 1.0 - (1.0 - illustrative::SILHOUETTE_FACE).powi(2);
    let centre = alphas[32];
    assert!(
        centre > body - 0.05 && centre < 1.0 - (1.0 - body) * (1.0 - faces) + 0.05,
        "centre alpha {centre}, interior {body}, faces {faces}: {alphas:?}"
    );
    // The outline: where the sides are seen edge-on, far more opaque than the middle.
    let left = alphas[..32].iter().copied().fold(0f32, f32::max);
    let right = alphas[32..].iter().copied().fold(0f32, f32::max);
    assert!(
        left > centre + 0.08 && right > centre + 0.08,
        "outline {left} / {right} vs centre {centre}: {alphas:?}"
    );
}

/// The filter written out cell by cell: the index arithmetic of every neighbour spelled
/// out, summed in the same order (centre twice, then the lower, then the upper neighbour).
fn smooth_cell_by_cell(values: &[f32], width: usize, shape: &[usize]) -> Vec<f32> {
    let mut cur = values.to_vec();
    let mut stride = 1usize;
    for &r in shape.iter().rev() {
        let mut dst = vec![0f32; cur.len()];
        for (e, v) in dst.iter_mut().enumerate() {
            let (cell, ch) = (e / width, e % width);
            let pos = (cell / stride) % r;
            let mut s = 2.0 * cur[e];
            if pos > 0 {
                s += cur[(cell - stride) * width + ch];
            }
            if pos + 1 < r {
                s += cur[(cell + stride) * width + ch];
            }
            *v = s * 0.25;
        }
        cur = dst;
        stride *= r;
    }
    cur
}

#[test]
fn smoothing_is_the_filter_written_cell_by_cell_bit_for_bit() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.3
    };
    for shape in [
        vec![7usize],
        vec![1, 5],
        vec![3, 1, 4],
        vec![9, 17, 13],
        vec![2, 3, 70, 5],
        vec![40, 33, 2],
    ] {
        for width in [1usize, 2, 4] {
            let cells: usize = shape.iter().product();
            let values: Vec<f32> = (0..cells * width).map(|_| next()).collect();
            let fast = smooth(&values, width, &shape);
            let slow = smooth_cell_by_cell(&values, width, &shape);
            assert_eq!(
                fast.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                slow.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                "shape {shape:?}, width {width}"
            );
        }
    }
}

#[test]
fn edges_by_depth_are_thicker_and_stronger_near_the_eye_and_by_direction_take_their_colour() {
    // One visible edge across the picture, its depth from 2 (left) to 10 (right), and a second
    // far one at depth 10 fixing the range's far end.
    let shape = [8, 8, 8];
    let rgba = vec![0f32; 8 * 8 * 8 * 4];
    let edge = |row: f64, depth: [f64; 2]| {
        let mut e = RetinaEdge {
            a: [0.0; MAX_RETINA_DIM],
            b: [0.0; MAX_RETINA_DIM],
            depth,
            visible: true,
            color: [0.9, 0.1, 0.2],
        };
        e.a[..3].copy_from_slice(&[4.0, row, 0.0]);
        e.b[..3].copy_from_slice(&[4.0, row, 8.0]);
        e
    };
    let edges = [edge(2.0, [2.0, 10.0]), edge(6.0, [10.0, 10.0])];
    let extras = RetinaExtras {
        edges: &edges,
        ..Default::default()
    };
    let pixels_per_cell = 96.0 / (8.0 * 3f64.sqrt());
    let y_of = |row: f64| 48.0 + (row - 4.0) * pixels_per_cell;
    // The covered rows of column x around the line's row, weighted by alpha: its width there.
    let width = |img: &crate::composite::Image, x: usize, row: f64| -> f32 {
        let y = y_of(row) as usize;
        (y - 8..y + 8).map(|py| img.pixel(x, py)[3]).sum()
    };
    let o = CompositeOptions {
        edge_width: 4.0,
        edge_color_by: EdgeColorBy::Depth,
        ..options((96, 96))
    };
    let img = composite_retina(&rgba, None, &shape, &extras, &o).unwrap();
    let (near, far) = (width(&img, 22, 2.0), width(&img, 74, 2.0));
    assert!(near > 1.8 * far, "near {near}, far {far}");
    // The farthest edge: thin and faint.
    let faint = img.pixel(48, y_of(6.0) as usize)[3];
    assert!(faint < 0.5 && faint > 0.2, "{faint}");
    // By direction: the edge's colour, widths by depth still.
    let o = CompositeOptions {
        edge_color_by: EdgeColorBy::Direction,
        ..o
    };
    let img = composite_retina(&rgba, None, &shape, &extras, &o).unwrap();
    let p = img.pixel(22, y_of(2.0) as usize);
    assert!(
        (p[0] - 0.9).abs() < 0.02 && (p[1] - 0.1).abs() < 0.02,
        "{p:?}"
    );
    assert!(width(&img, 22, 2.0) > 1.8 * width(&img, 74, 2.0));
    // None: one width.
    let o = CompositeOptions {
        edge_color_by: EdgeColorBy::None,
        ..o
    };
    let img = composite_retina(&rgba, None, &shape, &extras, &o).unwrap();
    assert!((width(&img, 22, 2.0) - width(&img, 74, 2.0)).abs() < 0.3);
}
