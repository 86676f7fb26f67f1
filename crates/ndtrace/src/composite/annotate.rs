//! What a picture says about itself. matplotlib, ParaView and napari show a colour bar, an
//! orientation glyph and panel titles by default, and Hanson's figures label their axes: here
//! the core decides where the caption ([`CompositeOptions::title`]), the panels and their
//! titles, the legend strip ([`CompositeOptions::legend`]) and the N-D axes glyph
//! ([`CompositeOptions::axes`]) go — [`picture_layout`] — and where the glyph's arrows point,
//! [`axis_arrows`]: the N world axes through the N-D camera, the N ≥ 5 stages and the
//! compositing camera. It also frames the object: [`Hull`], the occupied part of the volume
//! the views centre with equal margins.
//!
//! The views are rendered into the panels here; the text, the colour bar and the arrows are
//! drawn into the places reserved for them by `ndtrace.composite` (Python's `annotate`
//! module, with a font shipped in the package), and written as SVG elements by
//! `ndtrace.write_svg`.
//!
//! ```toml
//! [composite]
//! title = "The tesseract, turned 20° in x–w"
//! legend = "auto"          # a colour bar when an object has a colormap, color_by or label
//! axes = true              # the glyph (default for N ≥ 4)
//! edge_color_by = "direction"
//! ```

use super::aids::ViewLayout;
use super::illustrative::RetinaCamera;
use super::options::{CompositeMode, CompositeOptions};
use super::stages::stage_params;
use super::volume::Camera3;
use crate::camera::Projection;
use glam::DVec3;

/// A rectangle of the picture, pixels: x right, y down from the top-left corner.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Rect {
    /// Left edge.
    pub x: usize,
    /// Top edge.
    pub y: usize,
    /// Width.
    pub w: usize,
    /// Height.
    pub h: usize,
}

/// One panel of a picture: where a view or a section is drawn, and its title above it.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Where the view or section is drawn.
    pub rect: Rect,
    /// Its title (`"volume"`, `"x = 0.10"`, `"left"` …), if it has one.
    pub title: Option<String>,
    /// The band the title is written in (with a title): above `rect`, except for the stages'
    /// title of a single view, written over the top of `rect`.
    pub title_band: Option<Rect>,
}

/// Where everything of a picture goes (see the [module docs](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct PictureLayout {
    /// The picture's size (W, H): [`picture_size`].
    pub size: (usize, usize),
    /// The size of its text, pixels (the height of a capital and descender, roughly the font
    /// size): `min(W, H) / 36`, at least 9.
    pub text: f64,
    /// The caption band across the top, with a [`CompositeOptions::title`].
    pub caption: Option<Rect>,
    /// The legend strip across the bottom, when a legend is drawn.
    pub legend: Option<Rect>,
    /// The panels: the view first, then the sections (across z, x, y) or the right eye.
    pub panels: Vec<Panel>,
    /// The axes glyph's box, in the lower-left corner of the view's panel.
    pub axes: Option<Rect>,
}

/// Default picture size of the sections layout (each panel keeps more than 256 px).
pub const SECTIONS_SIZE: (usize, usize) = (720, 720);
/// Default picture size of the stereo layout.
pub const STEREO_SIZE: (usize, usize) = (960, 540);
/// Height of a legend row, in text sizes.
pub const LEGEND_ROW: f64 = 2.9;
/// Height of a panel title's band, in text sizes.
pub const TITLE_BAND: f64 = 1.7;
/// Height of the caption band, in text sizes.
pub const CAPTION_BAND: f64 = 2.2;
/// Side of the axes glyph's box over the shorter side of the view's panel, …
pub const AXES_BOX: f64 = 0.26;
/// … but at least this many pixels, …
pub const MIN_AXES_BOX: f64 = 100.0;
/// … and at most this part of the shorter side.
pub const MAX_AXES_BOX: f64 = 0.34;
/// Margin around the framed object, over the shorter side of its panel.
pub const MARGIN: f64 = 0.06;

/// Whether a retina of `m` axes is seen through 3D views (not a slice montage, a 2D picture or
/// a 1D strip).
fn viewed(opts: &CompositeOptions, m: usize) -> bool {
    m >= 3 && opts.mode != CompositeMode::Slices
}

/// The picture's size: [`CompositeOptions::size`], except that a table or dict that gives no
/// `size` with `layout = "sections"` or `"stereo"` gets [`SECTIONS_SIZE`] or [`STEREO_SIZE`],
/// so that each panel keeps more than 256 px (options built in code keep their `size`).
pub fn picture_size(opts: &CompositeOptions, m: usize) -> (usize, usize) {
    let from_table = opts.given != super::GivenKeys::NONE;
    if !from_table || opts.given.has("size") || !viewed(opts, m) {
        return opts.size;
    }
    match opts.layout {
        ViewLayout::Single | ViewLayout::Slice => opts.size,
        ViewLayout::Sections => SECTIONS_SIZE,
        ViewLayout::Stereo => STEREO_SIZE,
    }
}

/// The text size of a picture of size (w, h).
pub fn text_size(w: usize, h: usize) -> f64 {
    (w.min(h) as f64 / 36.0).round().max(9.0)
}

/// Axis `i`'s name: x, y, z, w, then x5, x6, … (the course's names).
pub fn axis_name(i: usize) -> String {
    match i {
        0..=3 => ["x", "y", "z", "w"][i].to_string(),
        _ => format!("x{}", i + 1),
    }
}

/// Subscript digits of `k` (u₁, u₂ …).
fn subscript(k: usize) -> String {
    k.to_string()
        .chars()
        .map(|c| char::from_u32(0x2080 + c.to_digit(10).unwrap_or(0)).unwrap_or(c))
        .collect()
}

/// A number as a title shows it: two decimals, a true minus sign.
fn number(v: f64) -> String {
    let v = if v.abs() < 5e-3 { 0.0 } else { v };
    format!("{v:.2}").replace('-', "−")
}

/// Where everything of the picture of `opts` goes, for a retina of numpy `shape` with
/// `legend_rows` rows of legend (0: none) and, for the sections' titles in the scene's units,
/// the camera that traced it and its position.
pub fn picture_layout(
    opts: &CompositeOptions,
    shape: &[usize],
    legend_rows: usize,
    camera: Option<(&RetinaCamera, &[f64])>,
) -> PictureLayout {
    let m = shape.len();
    let (w, h) = picture_size(opts, m);
    let u = text_size(w, h);
    let band = |k: f64| ((k * u).ceil() as usize).min(h);
    // 1. The caption across the top and the legend across the bottom.
    let caption = opts.title.as_ref().map(|_| Rect {
        x: 0,
        y: 0,
        w,
        h: band(CAPTION_BAND),
    });
    let top = caption.map_or(0, |c| c.h);
    let legend = (legend_rows > 0).then(|| {
        let lh = band(LEGEND_ROW * legend_rows as f64).min(h - top);
        Rect {
            x: 0,
            y: h - lh,
            w,
            h: lh,
        }
    });
    let bottom = legend.map_or(h, |l| l.y);
    let area = Rect {
        x: 0,
        y: top,
        w,
        h: bottom.saturating_sub(top),
    };
    // 2. The panels, each with its title band.
    let titled = |r: Rect, title: Option<String>| match title {
        None => Panel {
            rect: r,
            title: None,
            title_band: None,
        },
        Some(t) => {
            let th = band(TITLE_BAND).min(r.h);
            Panel {
                rect: Rect {
                    x: r.x,
                    y: r.y + th,
                    w: r.w,
                    h: r.h - th,
                },
                title: Some(t),
                title_band: Some(Rect { h: th, ..r }),
            }
        }
    };
    let layout = if viewed(opts, m) {
        opts.layout
    } else {
        ViewLayout::Single
    };
    let stages = stage_title(opts, shape);
    let panels = match layout {
        // The stages' title is written over the top margin of the view (the framed object
        // keeps [`MARGIN`] clear), so the view is the same picture with or without it.
        ViewLayout::Single => {
            let band = stages.as_ref().map(|_| Rect {
                h: band(TITLE_BAND).min(area.h),
                ..area
            });
            vec![Panel {
                rect: area,
                title: stages,
                title_band: band,
            }]
        }
        ViewLayout::Stereo => {
            let wl = area.w / 2;
            let half = |x: usize, w: usize| Rect { x, w, ..area };
            vec![
                titled(half(0, wl), Some("left".into())),
                titled(half(wl, area.w - wl), Some("right".into())),
            ]
        }
        // The view beside the slice (drawn by whoever traces it), untitled.
        ViewLayout::Slice => {
            let wl = area.w / 2;
            let half = |x: usize, w: usize| Rect { x, w, ..area };
            vec![
                titled(half(0, wl), None),
                titled(half(wl, area.w - wl), None),
            ]
        }
        ViewLayout::Sections => {
            let (wl, ht) = (area.w / 2, area.h / 2);
            let quad = |x: usize, y: usize, w: usize, h: usize| Rect {
                x,
                y: area.y + y,
                w,
                h,
            };
            let names = section_titles(opts, shape, camera);
            let view = "volume".to_string();
            vec![
                titled(quad(0, 0, wl, ht), Some(view)),
                titled(quad(wl, 0, area.w - wl, ht), Some(names[0].clone())),
                titled(quad(0, ht, wl, area.h - ht), Some(names[1].clone())),
                titled(
                    quad(wl, ht, area.w - wl, area.h - ht),
                    Some(names[2].clone()),
                ),
            ]
        }
    };
    // 3. The glyph in the lower-left corner of the view.
    let n = m + 1;
    let axes = opts.axes.resolve(n >= 4).then(|| {
        let r = panels[0].rect;
        let short = r.w.min(r.h) as f64;
        let side = ((AXES_BOX * short)
            .max(MIN_AXES_BOX)
            .min(MAX_AXES_BOX * short)
            .round() as usize)
            .min(r.w)
            .min(r.h);
        Rect {
            x: r.x,
            y: r.y + r.h - side,
            w: side,
            h: side,
        }
    });
    PictureLayout {
        size: (w, h),
        text: u,
        caption,
        legend,
        panels,
        axes: axes.filter(|a| a.w > 0),
    }
}

/// For N ≥ 5, what the stages collapse: `retina axis u₄ projected in perspective (f = 1.47,
/// d = 3.00)`.
fn stage_title(opts: &CompositeOptions, shape: &[usize]) -> Option<String> {
    let m = shape.len();
    if m < 4 || !viewed(opts, m) {
        return None;
    }
    // The stages collapse the leading numpy axes: retina axes u_m, then u_{m−1}, … u_4.
    let axes: Vec<String> = (4..=m)
        .rev()
        .map(|k| format!("u{}", subscript(k)))
        .collect();
    let how = if opts.projection == Projection::Orthographic {
        "orthographically".to_string()
    } else if m == 4 {
        let (f, d) = stage_params(shape, opts.stages.first().copied());
        format!("in perspective (f = {}, d = {})", number(f), number(d))
    } else {
        "in perspective".to_string()
    };
    let which = if axes.len() == 1 { "axis" } else { "axes" };
    Some(format!(
        "retina {which} {} projected {how}",
        axes.join(", then ")
    ))
}

/// The titles of the three sections (across z, x, y): the section's coordinate in the scene's
/// units where the retina's axis is a world axis seen orthographically (`x = 0.10`), else in the
/// volume's coordinates along the retina axis (`u₁ = 0.10`, the longest side spanning
/// [−1, 1]).
fn section_titles(
    opts: &CompositeOptions,
    shape: &[usize],
    camera: Option<(&RetinaCamera, &[f64])>,
) -> [String; 3] {
    let m = shape.len();
    let n = m + 1;
    // Volume axes x, y, z are retina axes u₁, u₂, u₃ (N = 4; for N ≥ 5 the stages' output).
    let longest = *shape.iter().max().unwrap_or(&1) as f64;
    let title = |axis: usize| -> String {
        let v = opts.section[axis];
        if let Some((cam, position)) = camera.filter(|(c, p)| {
            !c.perspective && m == 3 && c.orientation.len() == n * n && p.len() == n
        }) {
            // The column of retina axis u_{axis+1}: a world axis, either way?
            let col: Vec<f64> = (0..n).map(|r| cam.orientation[r * n + axis]).collect();
            if let Some(j) = col.iter().position(|x| (x.abs() - 1.0).abs() < 1e-9) {
                let u = v * longest / 2.0 * cam.cell;
                return format!("{} = {}", axis_name(j), number(position[j] + col[j] * u));
            }
        }
        format!("u{} = {}", subscript(axis + 1), number(v))
    };
    [title(2), title(0), title(1)]
}

/// One arrow of the axes glyph.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisArrow {
    /// The axis' name: x, y, z, w, x5 …
    pub label: String,
    /// Its tip relative to the glyph's centre, picture directions (x right, y down), for a unit
    /// axis: the length is the part of the axis the picture shows (1 for an axis in the
    /// picture's plane, 0 for one along a line of sight).
    pub tip: [f64; 2],
    /// How far it points toward the N-D eye: −1 (away) … 1 (toward), the negated component
    /// along the N-D view direction. The glyph dims arrows pointing away.
    pub toward: f64,
}

/// The N-D axes glyph's arrows: the columns f_i of `frame` (N×N rows; `None`: the world axes
/// e_i) as the picture of `opts` shows them. Each goes through the N-D camera (its components
/// along the retina axes u_1 … u_{N−1}, c = Oᵀ f_i: the derivative of the camera's projection
/// at the view axis, up to a common scale), through the N ≥ 5 stages (which keep u_1 … u_3 at
/// the centre of their box, up to a common scale) and through the compositing camera (the
/// volume's x, y, z = u_1, u_2, u_3 onto its right and up axes). Directions only: the same
/// for perspective and orthographic cameras at the centre of the view.
pub fn axis_arrows(
    camera: &RetinaCamera,
    frame: Option<&[Vec<f64>]>,
    shape: &[usize],
    opts: &CompositeOptions,
) -> Vec<AxisArrow> {
    let n = shape.len() + 1;
    if camera.orientation.len() != n * n || n < 3 {
        return Vec::new();
    }
    let o = |r: usize, k: usize| camera.orientation[r * n + k];
    let axis = |i: usize, r: usize| match frame {
        Some(f) => f.get(r).and_then(|row| row.get(i)).copied().unwrap_or(0.0),
        None => f64::from(u8::from(r == i)),
    };
    // The compositing camera's axes in the volume's cell coordinates (y down the rows); a 2D
    // retina is the picture itself.
    let (right, up) = if n >= 4 {
        let m = n - 1;
        let view = Camera3::new([shape[m - 1], shape[m - 2], shape[m - 3]], None, opts);
        let (right, up, _) = view.basis();
        (right, up)
    } else {
        (DVec3::X, DVec3::NEG_Y)
    };
    (0..n)
        .map(|i| {
            // c_k = Σ_r O[r][k] f_i[r]: camera-frame components (the last along the view).
            let c: Vec<f64> = (0..n)
                .map(|k| (0..n).map(|r| o(r, k) * axis(i, r)).sum())
                .collect();
            let len = c
                .iter()
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt()
                .max(f64::MIN_POSITIVE);
            // The volume's direction (x = u₁, y = u₂ up, z = u₃) in cell coordinates.
            let d = DVec3::new(c[0], -c[1], if n >= 4 { c[2] } else { 0.0 }) / len;
            AxisArrow {
                label: axis_name(i),
                tip: [d.dot(right), -d.dot(up)],
                toward: -c[n - 1] / len,
            }
        })
        .collect()
}

/// The occupied part of a volume, for framing: the corners of the occupied cells of a coarse
/// grid over the box of the cells with alpha > 0, and the centre and radius of their sphere.
#[derive(Debug, Clone, PartialEq)]
pub struct Hull {
    /// Corners of the occupied coarse cells, cell coordinates (column, row, slice).
    pub points: Vec<DVec3>,
    /// The box of the occupied cells (cell coordinates): centred on the same point as
    /// [`Hull::points`]' sphere, with that sphere's radius as its half-diagonal, so a camera
    /// framing it frames the sphere.
    pub frame: ([f64; 3], [f64; 3]),
}

/// Cells per axis of the coarse grid of a [`Hull`].
const HULL_GRID: usize = 12;

/// The [`Hull`] of a 3D volume of premultiplied cells in numpy order (`shape` = slices, rows,
/// columns), or `None` when no cell is occupied.
pub fn hull(shape: &[usize], cells: &[[f32; 4]]) -> Option<Hull> {
    let (nx, ny, nz) = (shape[2], shape[1], shape[0]);
    let (lo, hi) =
        super::volume::occupied_box([nx, ny, nz], |x, y, z| cells[x + nx * (y + ny * z)][3])?;
    // Coarse cells over the box: bins of ⌈extent / HULL_GRID⌉ cells.
    let step: [usize; 3] =
        std::array::from_fn(|k| (((hi[k] - lo[k]) as usize).div_ceil(HULL_GRID)).max(1));
    let bins: [usize; 3] = std::array::from_fn(|k| ((hi[k] - lo[k]) as usize).div_ceil(step[k]));
    let mut occupied = vec![false; bins[0] * bins[1] * bins[2]];
    for z in lo[2] as usize..hi[2] as usize {
        for y in lo[1] as usize..hi[1] as usize {
            for x in lo[0] as usize..hi[0] as usize {
                if cells[x + nx * (y + ny * z)][3] > 0.0 {
                    let b = [x, y, z];
                    let i: [usize; 3] = std::array::from_fn(|k| (b[k] - lo[k] as usize) / step[k]);
                    occupied[i[0] + bins[0] * (i[1] + bins[1] * i[2])] = true;
                }
            }
        }
    }
    let mut points = Vec::new();
    for (i, _) in occupied.iter().enumerate().filter(|(_, &o)| o) {
        let b = [
            i % bins[0],
            (i / bins[0]) % bins[1],
            i / (bins[0] * bins[1]),
        ];
        for corner in 0..8 {
            let p: [f64; 3] = std::array::from_fn(|k| {
                let v = lo[k] + ((b[k] + ((corner >> k) & 1)) * step[k]) as f64;
                v.min(hi[k])
            });
            points.push(DVec3::from_array(p));
        }
    }
    Some(Hull::about(points, lo, hi))
}

/// The [`Hull`] of points (cell coordinates; the vertices of a structure, any number): the
/// corners of the 12³ bins of their box that hold one, or `None` without points.
pub fn hull_of_points(points: impl Iterator<Item = DVec3> + Clone) -> Option<Hull> {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in points.clone() {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if !(lo.x <= hi.x) {
        return None;
    }
    let step = ((hi - lo) / HULL_GRID as f64).max(DVec3::splat(1e-9));
    let bin = |p: DVec3| -> [usize; 3] {
        let b = ((p - lo) / step).floor();
        std::array::from_fn(|k| (b[k].max(0.0) as usize).min(HULL_GRID - 1))
    };
    let mut occupied = vec![false; HULL_GRID.pow(3)];
    for p in points {
        let b = bin(p);
        occupied[b[0] + HULL_GRID * (b[1] + HULL_GRID * b[2])] = true;
    }
    let mut corners = Vec::new();
    for (i, _) in occupied.iter().enumerate().filter(|(_, &o)| o) {
        let b = [
            i % HULL_GRID,
            (i / HULL_GRID) % HULL_GRID,
            i / (HULL_GRID * HULL_GRID),
        ];
        for corner in 0..8 {
            let c = DVec3::from_array(std::array::from_fn(|k| (b[k] + ((corner >> k) & 1)) as f64));
            corners.push((lo + c * step).min(hi));
        }
    }
    Some(Hull::about(corners, lo.to_array(), hi.to_array()))
}

impl Hull {
    /// The hull of `points` in the box `lo`..`hi`: its frame the box about the box's centre
    /// whose half-diagonal is the radius of the sphere about that centre through the farthest
    /// point.
    fn about(points: Vec<DVec3>, lo: [f64; 3], hi: [f64; 3]) -> Hull {
        let centre = (DVec3::from_array(lo) + DVec3::from_array(hi)) * 0.5;
        let radius = points
            .iter()
            .map(|p| (*p - centre).length())
            .fold(0.0f64, f64::max)
            .max(1e-9);
        let half = DVec3::splat(radius / 3f64.sqrt());
        Hull {
            points,
            frame: ((centre - half).to_array(), (centre + half).to_array()),
        }
    }
}

#[cfg(test)]
mod tests;
