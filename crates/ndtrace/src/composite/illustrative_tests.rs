//! Tests of the illustrative mode, the edge overlay, the stages' point map and `fit`.

use super::overlay::edge_color;
use super::stages::stage_point;
use super::*;
use crate::composite::volume::Camera3;

fn options(size: (usize, usize)) -> CompositeOptions {
    CompositeOptions {
        mode: CompositeMode::Illustrative,
        azimuth: 0.0,
        elevation: 0.0,
        projection: Projection::Orthographic,
        size,
        fit: false,
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
