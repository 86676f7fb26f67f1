use super::*;
use crate::camera::Camera;
use crate::composite::{composite, composite_retina, RetinaExtras};
use crate::edges::retina_coords;
use crate::linalg::{norm, sub, Vector};
use crate::testutil::{random_rotation, random_vector, rng};
use rand::Rng;

/// Options as a table or dict gives them (the keys given), for the layout's defaults.
fn from_table(toml: &str) -> CompositeOptions {
    toml::from_str(toml).unwrap()
}

fn inside(r: Rect, outer: Rect) -> bool {
    r.x >= outer.x
        && r.y >= outer.y
        && r.x + r.w <= outer.x + outer.w
        && r.y + r.h <= outer.y + outer.h
}

fn overlap(a: Rect, b: Rect) -> bool {
    a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h
}

#[test]
fn the_sections_layout_titles_four_panels_of_at_least_256_pixels() {
    let o = from_table("layout = \"sections\"\nsection = [0.1, -0.25, 0.5]\n");
    let l = picture_layout(&o, &[64, 64, 64], 1, None);
    assert_eq!(l.size, SECTIONS_SIZE);
    let whole = Rect {
        x: 0,
        y: 0,
        w: l.size.0,
        h: l.size.1,
    };
    let titles: Vec<&str> = l
        .panels
        .iter()
        .map(|p| p.title.as_deref().unwrap())
        .collect();
    assert_eq!(titles, ["volume", "u₃ = 0.50", "u₁ = 0.10", "u₂ = −0.25"]);
    for (i, p) in l.panels.iter().enumerate() {
        assert!(
            p.rect.w >= 256 && p.rect.h >= 256,
            "panel {i}: {:?}",
            p.rect
        );
        let band = p.title_band.unwrap();
        // The title's band lies right above its panel, as wide as it.
        assert_eq!(
            (band.x, band.w, band.y + band.h),
            (p.rect.x, p.rect.w, p.rect.y)
        );
        assert!(inside(band, whole) && inside(p.rect, whole));
        for q in &l.panels[i + 1..] {
            assert!(!overlap(p.rect, q.rect) && !overlap(band, q.rect));
        }
        assert!(!overlap(p.rect, l.legend.unwrap()));
    }
    // Quadrants: the view top left, across z top right, across x bottom left, across y bottom
    // right.
    let [v, z, x, y] = [0, 1, 2, 3].map(|k| l.panels[k].rect);
    assert!(z.x > v.x && z.y == v.y && x.x == v.x && x.y > v.y && y.x == z.x && y.y == x.y);
    // The legend spans the bottom, the glyph sits in the view's lower-left corner.
    let legend = l.legend.unwrap();
    assert_eq!(
        (legend.x, legend.w, legend.y + legend.h),
        (0, l.size.0, l.size.1)
    );
    let a = l.axes.unwrap();
    assert_eq!((a.x, a.y + a.h), (v.x, v.y + v.h));
    assert!(inside(a, v));
    // Options built in code keep their size; a table that gives one keeps it too.
    let code = CompositeOptions {
        layout: ViewLayout::Sections,
        ..Default::default()
    };
    assert_eq!(picture_layout(&code, &[8, 8, 8], 0, None).size, (512, 512));
    let sized = from_table("layout = \"sections\"\nsize = [400, 300]\n");
    assert_eq!(picture_layout(&sized, &[8, 8, 8], 0, None).size, (400, 300));
}

#[test]
fn section_titles_are_in_the_scenes_units_for_an_axis_aligned_orthographic_camera() {
    // The course's camera looking down −w, orthographic: retina axes u₁, u₂, u₃ = x, y, z.
    let camera = RetinaCamera {
        orientation: vec![
            1., 0., 0., 0., //
            0., 1., 0., 0., //
            0., 0., 1., 0., //
            0., 0., 0., -1.,
        ],
        cell: 0.05,
        perspective: false,
    };
    let position = [0.5, 0.0, -1.0, 4.0];
    let o = from_table("layout = \"sections\"\nsection = [0.5, 0.0, -0.5]\n");
    let l = picture_layout(&o, &[40, 40, 40], 0, Some((&camera, &position)));
    let titles: Vec<&str> = l
        .panels
        .iter()
        .map(|p| p.title.as_deref().unwrap())
        .collect();
    // Volume x = 0.5 is 0.5·20 cells = 10 cells = 0.5 units from the centre, x = 0.5 + 0.5.
    assert_eq!(titles, ["volume", "z = −1.50", "x = 1.00", "y = 0.00"]);
    // A perspective camera keeps the volume's coordinates.
    let camera = RetinaCamera {
        perspective: true,
        ..camera
    };
    let l = picture_layout(&o, &[40, 40, 40], 0, Some((&camera, &position)));
    assert_eq!(l.panels[2].title.as_deref(), Some("u₁ = 0.50"));
}

#[test]
fn stereo_and_stage_titles_caption_and_legend_bands() {
    let o = from_table("layout = \"stereo\"\ntitle = \"A pair\"\n");
    let l = picture_layout(&o, &[32, 32, 32], 2, None);
    assert_eq!(l.size, STEREO_SIZE);
    let titles: Vec<&str> = l
        .panels
        .iter()
        .map(|p| p.title.as_deref().unwrap())
        .collect();
    assert_eq!(titles, ["left", "right"]);
    assert!(l.panels.iter().all(|p| p.rect.w >= 256 && p.rect.h >= 256));
    let caption = l.caption.unwrap();
    assert_eq!((caption.x, caption.y, caption.w), (0, 0, l.size.0));
    assert_eq!(l.panels[0].title_band.unwrap().y, caption.h);
    let legend = l.legend.unwrap();
    assert_eq!(legend.h, (2.0 * LEGEND_ROW * l.text).ceil() as usize);
    // N = 5: the view's title says what the stage collapses.
    let l = picture_layout(&CompositeOptions::default(), &[8, 8, 8, 8], 0, None);
    let t = l.panels[0].title.clone().unwrap();
    assert!(
        t.starts_with("retina axis u₄ projected in perspective (f = "),
        "{t}"
    );
    // N = 4, one view, no caption or legend: the panel is the picture.
    let l = picture_layout(&CompositeOptions::default(), &[8, 8, 8], 0, None);
    assert_eq!(
        l.panels[0].rect,
        Rect {
            x: 0,
            y: 0,
            w: 512,
            h: 512
        }
    );
    assert!(l.panels[0].title.is_none() && l.caption.is_none() && l.legend.is_none());
    // The glyph by default for N ≥ 4 only, in at most a fifth of the picture.
    let a = l.axes.unwrap();
    assert!((a.w * a.h) as f64 <= 0.2 * 512.0 * 512.0);
    assert!(
        picture_layout(&CompositeOptions::default(), &[8, 8], 0, None)
            .axes
            .is_none()
    );
    let on = CompositeOptions {
        axes: crate::composite::Toggle::On,
        ..Default::default()
    };
    assert!(picture_layout(&on, &[8, 8], 0, None).axes.is_some());
}

/// The picture position, through the compositing camera of `opts` (for a volume of `n`
/// cells), of the world point `x` as the tracer's camera `cam` images it.
fn through_cameras(cam: &Camera<4>, opts: &CompositeOptions, x: &Vector<4>) -> [f64; 2] {
    let xi = retina_coords(cam, x).unwrap();
    let cam3 = Camera3::new([32, 32, 32], None, opts);
    cam3.project(DVec3::new(xi[0], xi[1], xi[2])).unwrap().0
}

#[test]
fn the_glyphs_arrows_point_where_the_cameras_project_the_unit_axes() {
    let mut r = rng(48);
    for trial in 0..40usize {
        let orientation = random_rotation::<4>(&mut r);
        let look = random_vector::<4>(&mut r, 1.0);
        let view: Vector<4> = std::array::from_fn(|k| orientation[k][3]);
        let perspective = trial.is_multiple_of(2);
        let cam = Camera {
            position: std::array::from_fn(|k| look[k] - 5.0 * view[k]),
            orientation,
            projection: if perspective {
                Projection::Perspective
            } else {
                Projection::Orthographic
            },
            cell: 0.05,
            resolution: vec![32, 32, 32],
        };
        let opts = CompositeOptions {
            azimuth: r.random_range(-180.0..180.0),
            elevation: r.random_range(-80.0..80.0),
            projection: Projection::Orthographic,
            fit: false,
            size: (300, 200),
            ..Default::default()
        };
        let retina = RetinaCamera {
            orientation: orientation.iter().flatten().copied().collect(),
            cell: cam.cell,
            perspective,
        };
        let arrows = axis_arrows(&retina, None, &[32, 32, 32], &opts);
        assert_eq!(
            arrows.iter().map(|a| a.label.as_str()).collect::<Vec<_>>(),
            ["x", "y", "z", "w"]
        );
        // Where a step of ε along each axis from the view axis lands in the picture, and how
        // much nearer it is to the eye.
        let eps = 1e-6;
        let p0 = through_cameras(&cam, &opts, &look);
        let depth = |x: &Vector<4>| match cam.projection {
            Projection::Perspective => norm(&sub(x, &cam.position)),
            Projection::Orthographic => crate::linalg::dot(&sub(x, &cam.position), &view),
        };
        let steps: Vec<([f64; 2], f64)> = (0..4)
            .map(|i| {
                let mut x = look;
                x[i] += eps;
                let p = through_cameras(&cam, &opts, &x);
                (
                    [(p[0] - p0[0]) / eps, (p[1] - p0[1]) / eps],
                    (depth(&look) - depth(&x)) / eps,
                )
            })
            .collect();
        // One scale s for every arrow: step_i = s · tip_i.
        let big = (0..4)
            .max_by(|&a, &b| {
                let l = |k: usize| arrows[k].tip[0].hypot(arrows[k].tip[1]);
                l(a).total_cmp(&l(b))
            })
            .unwrap();
        let s =
            steps[big].0[0].hypot(steps[big].0[1]) / arrows[big].tip[0].hypot(arrows[big].tip[1]);
        for i in 0..4 {
            for k in 0..2 {
                let err = (steps[i].0[k] - s * arrows[i].tip[k]).abs();
                assert!(
                    err < 1e-4 * s,
                    "trial {trial}, axis {i}: {:?} vs {s} × {:?}",
                    steps[i].0,
                    arrows[i].tip
                );
            }
            assert!(
                (steps[i].1 - arrows[i].toward).abs() < 1e-5,
                "trial {trial}, axis {i} toward"
            );
            // An axis in the retina's hyperplane has length 1 before the 3D camera.
            assert!(arrows[i].tip[0].hypot(arrows[i].tip[1]) <= 1.0 + 1e-12);
        }
    }
}

#[test]
fn a_frame_turns_the_glyph_as_the_object() {
    // The glyph of frame R for camera O is the glyph of the world axes for camera Rᵀ·O.
    let mut r = rng(7);
    let o = random_rotation::<4>(&mut r);
    let rot = random_rotation::<4>(&mut r);
    let opts = CompositeOptions::default();
    let flat = |m: &[[f64; 4]; 4]| m.iter().flatten().copied().collect::<Vec<f64>>();
    let camera = RetinaCamera {
        orientation: flat(&o),
        cell: 0.1,
        perspective: true,
    };
    let frame: Vec<Vec<f64>> = rot.iter().map(|row| row.to_vec()).collect();
    let turned = axis_arrows(&camera, Some(&frame), &[8, 8, 8], &opts);
    let rt_o: [[f64; 4]; 4] =
        std::array::from_fn(|i| std::array::from_fn(|k| (0..4).map(|j| rot[j][i] * o[j][k]).sum()));
    let moved = RetinaCamera {
        orientation: flat(&rt_o),
        ..camera.clone()
    };
    let plain = axis_arrows(&moved, None, &[8, 8, 8], &opts);
    for (a, b) in turned.iter().zip(&plain) {
        assert!((a.tip[0] - b.tip[0]).abs() < 1e-12 && (a.tip[1] - b.tip[1]).abs() < 1e-12);
        assert!((a.toward - b.toward).abs() < 1e-12);
    }
}

#[test]
fn fit_centres_the_object_with_equal_margins() {
    // A small ball of cells in a corner of a 24³ retina: framed, it is centred in the picture.
    let n = 24;
    let mut rgba = vec![0f32; n * n * n * 4];
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let d = ((x as f64 - 5.5).powi(2)
                    + (y as f64 - 6.5).powi(2)
                    + (z as f64 - 16.5).powi(2))
                .sqrt();
                if d < 4.0 {
                    rgba[((z * n + y) * n + x) * 4..][..4].copy_from_slice(&[1.0, 1.0, 1.0, 1.0]);
                }
            }
        }
    }
    for (azimuth, elevation) in [(30.0, 20.0), (-70.0, 5.0), (120.0, -40.0)] {
        let o = CompositeOptions {
            mode: CompositeMode::Volume,
            size: (160, 120),
            azimuth,
            elevation,
            ..Default::default()
        };
        let img = composite(&rgba, None, &[n, n, n], &o).unwrap();
        let (mut lo, mut hi) = ([usize::MAX; 2], [0usize; 2]);
        for y in 0..120 {
            for x in 0..160 {
                if img.pixel(x, y)[3] > 0.5 {
                    lo = [lo[0].min(x), lo[1].min(y)];
                    hi = [hi[0].max(x + 1), hi[1].max(y + 1)];
                }
            }
        }
        let (left, right) = (lo[0] as i64, 160 - hi[0] as i64);
        let (top, bottom) = (lo[1] as i64, 120 - hi[1] as i64);
        // Equal within half a cell (the ball's 8 cells span about 110 px here): the hull is the
        // occupied cells' corners, and the rendered rim lies up to half a cell inside them.
        let half_cell = (hi[1] - lo[1]) as i64 / 16;
        assert!(
            (left - right).abs() <= half_cell && (top - bottom).abs() <= half_cell,
            "{azimuth}: {left} {right} {top} {bottom}"
        );
        // And it fills its panel: its width is most of the shorter side.
        assert!(hi[1] - lo[1] > 70, "{:?} {:?}", lo, hi);
    }
}

#[test]
fn the_panels_of_a_caption_and_legend_are_where_the_composite_draws() {
    // With a caption and a legend row, the view is drawn in its panel and the bands stay
    // background (alpha 0).
    let n = 8;
    let rgba = [1f32, 0.5, 0.25, 1.0].repeat(n * n * n);
    let o = from_table(
        "mode = \"volume\"\ntitle = \"t\"\nsize = [120, 160]\nbackground = [0.1, 0.2, 0.3]\n",
    );
    let extras = RetinaExtras {
        legend_rows: 1,
        ..Default::default()
    };
    let img = composite_retina(&rgba, None, &[n, n, n], &extras, &o).unwrap();
    let l = picture_layout(&o, &[n, n, n], 1, None);
    let (cap, leg) = (l.caption.unwrap(), l.legend.unwrap());
    for (x, y) in [(3, 1), (60, cap.h - 1), (5, leg.y), (119, 159)] {
        let p = img.pixel(x, y);
        assert_eq!(p[3], 0.0, "({x}, {y})");
        assert!((p[0] - 0.1).abs() < 1e-6 && (p[2] - 0.3).abs() < 1e-6);
    }
    let p = l.panels[0].rect;
    assert!(img.pixel(p.x + p.w / 2, p.y + p.h / 2)[3] > 0.99);
}
