//! Compositing a retina into a 2D picture (course notes, Part II(B): "Projection: film ≈
//! volumetric retina of 4D cyclops. Volume render: splat, Shirley–Tuchman, texture panels", and
//! "ND perspective … repeat recursively down to 2D image: a hierarchy of parameter sets
//! (f_N, d_N), …, (f_3, d_3)").
//!
//! The input is a traced retina: premultiplied linear RGBA per cell (`rgba`, 4 floats per cell)
//! and optionally the distance from the N-D eye (`depth`, inf on a miss), both C-ordered in numpy
//! order `[i_{N−1}, …, i_1]` with `shape = [R_{N−1}, …, R_1]` (so N = `shape.len()` + 1).
//!
//! # What each dimension becomes
//!
//! * **N = 4** (a 3D retina `(slices, rows, columns)`): a 3D camera orbits the retina cube; see
//!   [`CompositeMode`] for the four renderings. The cube is placed with its centre at the origin,
//!   world x along the columns (i_1 → +x), world y up the rows (row 0 on top, as in an image)
//!   and world z along the slices (i_3 → +z); cells are cubes of side `2 / max(R)`, so the
//!   longest side of the cube spans [−1, 1]. At `azimuth = elevation = 0` the camera looks
//!   along +z (slice 0 nearest) with x to the right and y up, so a face-on orthographic picture
//!   of a retina constant across slices is exactly one slice image (rows down, columns right).
//!   Positive azimuth swings the eye toward +x (the picture's right), positive elevation toward
//!   +y (the top): the eye sits at `distance · r · (sin az cos el, sin el, −cos az cos el)`,
//!   where r is the half-diagonal of the cube.
//! * **N ≥ 5**: recursive projection. The (N−1)-D retina is composited one axis at a time,
//!   each stage a k-D → (k−1)-D emission–absorption projection along the leading numpy axis,
//!   down to a 3D volume that is then rendered as for N = 4 (see [`CompositeOptions::stages`]).
//! * **N = 3** (a 2D retina `(rows, columns)`): the retina is the image. It is scaled to fit
//!   `size` (aspect ratio kept, centred, nearest-cell sampling, by a whole factor when it is
//!   enlarged) over the background; passing `size = (R_1, R_2)` returns it at native size.
//! * **N = 2** (a 1D retina): a strip of `strip_height` rows spanning the width `size.0`,
//!   centred vertically in the picture.
//!
//! # The result
//!
//! An [`Image`]: linear float32 RGBA, row-major `(H, W, 4)`, row 0 at the top. **The RGB
//! channels are the retina composited over the opaque background colour** (what one sees:
//! `C + (1 − A) · background`, with C the accumulated premultiplied colour); **the alpha
//! channel is the accumulated opacity A of the retina's content alone** (1 − transmittance;
//! separators and labels of the slice montage count as opaque). With the default black
//! background the RGB channels are exactly C, so `(RGB, A)` is then a valid premultiplied
//! image that can be composited over anything else.
//!
//! Work is split over output rows (and blocks of the ray lattice) with rayon; every pixel
//! depends only on the inputs, its own coordinates and the pixels traced for its block, so the
//! picture is bit-identical whatever the number of threads.

mod aids;
pub mod annotate;
mod cubes;
pub mod illustrative;
mod montage;
mod options;
pub mod overlay;
pub mod picture;
pub mod probe;
mod sheets;
mod stages;
mod view;
mod volume;

pub use aids::{Cubes, Cutaway, ViewLayout};
pub use annotate::{axis_arrows, picture_layout, AxisArrow, Panel, PictureLayout, Rect};
pub use illustrative::RetinaCamera;
pub use montage::{slice_layout, Layout, SEPARATOR};
pub use options::{
    CompositeMode, CompositeOptions, Detail, EdgeColorBy, GivenKeys, HiddenEdges, OptionError,
    Toggle, DEFAULT_DISTANCE, DEFAULT_SAMPLES, MAX_PIXELS, MAX_SAMPLES, MAX_TITLE_CHARS,
    MAX_TURNTABLE_FRAMES,
};
pub use overlay::{PixelEdge, RetinaEdge, MAX_RETINA_DIM};
pub use probe::{
    ObjectLook, Probe, SceneProbe, Sheet, SheetKind, SheetVertex, Structure, TextureLines,
    MAX_TEXTURE_LINES,
};
pub use stages::DEFAULT_STAGE_DISTANCE;

use crate::{NdError, NdResult};
use glam::Vec4;
use montage::{render_slices, render_strip, render_tiles, Tiles};
use rayon::prelude::*;
use stages::{project_stage, stage_params};
use view::View3;

/// Rays of the volume mode stop when the transmittance falls below this.
pub const MIN_TRANSMITTANCE: f32 = 1e-4;
/// Depth-cue tint of the nearest cells (warm).
pub const NEAR_TINT: [f32; 3] = [1.2, 0.9, 0.6];
/// Depth-cue tint of the farthest cells (cool).
pub const FAR_TINT: [f32; 3] = [0.5, 0.75, 1.2];

/// A composited picture: linear float32 RGBA `(H, W, 4)`, row 0 at the top; RGB over the
/// opaque background, alpha the content's opacity (see the [module docs](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// W.
    pub width: usize,
    /// H.
    pub height: usize,
    /// `width · height · 4` floats.
    pub rgba: Vec<f32>,
}

impl Image {
    /// The RGBA of pixel (x, y).
    pub fn pixel(&self, x: usize, y: usize) -> [f32; 4] {
        let i = (y * self.width + x) * 4;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }
}

/// What a traced retina gives the compositor beyond its colours and depths (all optional): the
/// unit N-D normal of each cell's nearest hit (`N` floats per cell, numpy order), its camera,
/// the pieces of the scene's feature edges in retina coordinates, each cell's object, and the
/// scene itself. The illustrative mode uses the normals, camera and edges; a picture drawn at
/// its own resolution ([`Detail::Scene`], N = 4) asks the scene and uses the objects.
#[derive(Clone, Default)]
pub struct RetinaExtras<'a> {
    /// `cells · N` floats: the shading normal of each cell (0 on a miss).
    pub normal: Option<&'a [f32]>,
    /// The camera that traced the retina (occlusion contours from exact hit points).
    pub camera: Option<RetinaCamera>,
    /// Feature-edge pieces to draw (see [`crate::edges::retina_edges`]).
    pub edges: &'a [RetinaEdge],
    /// The object of each cell's nearest hit (−1 on a miss), numpy order.
    pub object: Option<&'a [i32]>,
    /// The scene the retina was traced from, for pictures drawn at their own resolution.
    pub scene: Option<&'a dyn SceneProbe>,
    /// Rows of the legend the picture makes room for at its bottom (0: none; see
    /// [`annotate::picture_layout`]): whoever draws the legend knows what it holds.
    pub legend_rows: usize,
}

impl std::fmt::Debug for RetinaExtras<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RetinaExtras")
            .field("normal", &self.normal.map(|n| n.len()))
            .field("camera", &self.camera)
            .field("edges", &self.edges.len())
            .field("object", &self.object.map(|o| o.len()))
            .field("scene", &self.scene.is_some())
            .field("legend_rows", &self.legend_rows)
            .finish()
    }
}

/// Composites a retina (premultiplied `rgba`, optional `depth`, numpy-order `shape`) into a
/// picture. See the [module docs](self) and [`CompositeOptions`].
pub fn composite(
    rgba: &[f32],
    depth: Option<&[f32]>,
    shape: &[usize],
    opts: &CompositeOptions,
) -> NdResult<Image> {
    composite_retina(rgba, depth, shape, &RetinaExtras::default(), opts)
}

/// [`composite`] with the retina's [`RetinaExtras`].
pub fn composite_retina(
    rgba: &[f32],
    depth: Option<&[f32]>,
    shape: &[usize],
    extras: &RetinaExtras<'_>,
    opts: &CompositeOptions,
) -> NdResult<Image> {
    let cells = check_retina(rgba, depth, shape)?;
    check_extras(extras, cells, shape.len())?;
    opts.validate_for(shape, depth.is_some())?;
    check_memory(shape, opts, 0)?;
    let m = shape.len();
    let layout = picture_layout(opts, shape, extras.legend_rows, None);
    let (w, h) = layout.size;
    check_size(w, h)?;
    let bg = opts.background.map(|x| x as f32);
    if m >= 3 && opts.mode != CompositeMode::Slices {
        return Ok(Image {
            width: w,
            height: h,
            rgba: View3::new(rgba, depth, shape, extras, cells, opts).picture(opts, &layout),
        });
    }
    // A montage, a 2D retina or a strip: drawn in the one panel.
    let panel = layout.panels[0].rect;
    let inner = CompositeOptions {
        size: (panel.w.max(1), panel.h.max(1)),
        ..opts.clone()
    };
    let opts = &inner;
    let (pw, ph) = opts.size;
    let mut vol = Volume {
        shape: shape.to_vec(),
        cells: prepare(rgba, depth, cells, opts),
    };
    // Recursive projection, one leading axis at a time, down to 3D.
    let mut stage = 0;
    while vol.shape.len() > 3 {
        let (f, d) = stage_params(&vol.shape, opts.stages.get(stage).copied());
        vol = project_stage(
            &vol,
            f,
            d,
            opts.projection == crate::camera::Projection::Orthographic,
        );
        stage += 1;
    }
    let tile = match vol.shape.len() {
        3 => render_slices(&vol, opts, bg),
        2 => {
            let (rows, cols) = (vol.shape[0], vol.shape[1]);
            let tiles = Tiles {
                cells: &vol.cells,
                tw: cols,
                th: rows,
                count: 1,
                gap: 0,
                labels: false,
            };
            render_tiles(pw, ph, &tiles, bg, |_, x, y| y * cols + x)
        }
        _ => render_strip(&vol.cells, pw, ph, opts.strip_height, bg),
    };
    let rgba = if (pw, ph) == (w, h) {
        tile
    } else {
        let mut img = [bg[0], bg[1], bg[2], 0.0].repeat(w * h);
        if panel.w > 0 && panel.h > 0 {
            for y in 0..panel.h {
                let row = ((panel.y + y) * w + panel.x) * 4;
                img[row..row + panel.w * 4].copy_from_slice(&tile[y * pw * 4..][..panel.w * 4]);
            }
        }
        img
    };
    Ok(Image {
        width: w,
        height: h,
        rgba,
    })
}

/// Refuses a picture (of a layout's default size) of more than [`MAX_PIXELS`].
fn check_size(w: usize, h: usize) -> NdResult<()> {
    if w.checked_mul(h).is_none_or(|p| p > MAX_PIXELS) {
        return Err(OptionError {
            key: "size".into(),
            message: format!("({w}, {h}) exceeds {MAX_PIXELS} pixels"),
        }
        .into());
    }
    Ok(())
}

/// A turntable: `frames` pictures of the retina seen by a compositing camera orbiting it, frame
/// k from azimuth `opts.azimuth + 360° · k / frames` (motion parallax for the price of one
/// trace). The retina is prepared once (for the illustrative mode, its cues), so a frame costs
/// one view. For N ≤ 3, and for the slices mode, every frame is the same picture.
pub fn composite_turntable(
    rgba: &[f32],
    depth: Option<&[f32]>,
    shape: &[usize],
    extras: &RetinaExtras<'_>,
    opts: &CompositeOptions,
    frames: usize,
) -> NdResult<Vec<Image>> {
    check_frames(frames)?;
    check_memory(shape, opts, frames)?;
    let mut out = Vec::with_capacity(frames);
    composite_turntable_each(rgba, depth, shape, extras, opts, frames, |_, image| {
        out.push(image)
    })?;
    Ok(out)
}

/// [`composite_turntable`] handing each frame to `each(k, frame)` as it is made, in order,
/// instead of keeping them all: a caller that copies the frames into one array of its own
/// holds them once. Checks the memory of one frame at a time (the caller's array is its own).
pub fn composite_turntable_each(
    rgba: &[f32],
    depth: Option<&[f32]>,
    shape: &[usize],
    extras: &RetinaExtras<'_>,
    opts: &CompositeOptions,
    frames: usize,
    mut each: impl FnMut(usize, Image),
) -> NdResult<()> {
    check_frames(frames)?;
    let cells = check_retina(rgba, depth, shape)?;
    check_extras(extras, cells, shape.len())?;
    opts.validate_for(shape, depth.is_some())?;
    check_memory(shape, opts, 0)?;
    if shape.len() < 3 || opts.mode == CompositeMode::Slices {
        let one = composite_retina(rgba, depth, shape, extras, opts)?;
        for k in 0..frames {
            each(k, one.clone());
        }
        return Ok(());
    }
    let layout = picture_layout(opts, shape, extras.legend_rows, None);
    let (w, h) = layout.size;
    check_size(w, h)?;
    let view = View3::new(rgba, depth, shape, extras, cells, opts);
    for k in 0..frames {
        let o = CompositeOptions {
            azimuth: opts.azimuth + 360.0 * k as f64 / frames as f64,
            ..opts.clone()
        };
        each(
            k,
            Image {
                width: w,
                height: h,
                rgba: view.picture(&o, &layout),
            },
        );
    }
    Ok(())
}

fn check_frames(frames: usize) -> NdResult<()> {
    if !(1..=MAX_TURNTABLE_FRAMES).contains(&frames) {
        return Err(NdError::Value {
            arg: "turntable".into(),
            message: format!("must be 1 to {MAX_TURNTABLE_FRAMES} frames, got {frames}"),
        });
    }
    Ok(())
}

/// Bytes a composite holds per retina cell beyond the retina itself, for an N-D retina: the
/// prepared copy and the 3D volume's padded copy (16 bytes each), and the illustrative mode's
/// cues (hit points and normals, N f64 each, colours, spacing and coverage).
fn bytes_per_cell(n: usize) -> f64 {
    64.0 + 16.0 * n as f64
}

/// Bytes a composite holds per picture pixel while it draws one: the picture (RGBA f32), the
/// depths of the first-hit mode and the traced lattice of the sparse rays.
const BYTES_PER_PIXEL: f64 = 16.0 + 4.0 + 16.0;

/// Checks with the [memory guard](crate::memory::check) what a composite of a retina of numpy
/// `shape` with `opts` needs, before any of it is allocated: its working copies of the cells,
/// the picture being drawn and, for `frames` > 0, that many finished pictures (W × H RGBA
/// floats each) held for the caller. A refusal names the option that decides it: `size` for a
/// picture, `turntable` for a turntable's frames.
pub fn check_memory(shape: &[usize], opts: &CompositeOptions, frames: usize) -> NdResult<()> {
    let (w, h) = opts.size;
    let pixels = w as f64 * h as f64;
    let cells = shape.iter().map(|&r| r as f64).product::<f64>();
    let working = cells * bytes_per_cell(shape.len() + 1) + pixels * BYTES_PER_PIXEL;
    let (arg, what) = if frames == 0 {
        ("size", format!("a picture of {w} × {h} pixels"))
    } else {
        ("turntable", format!("{frames} frames of {w} × {h} pixels"))
    };
    crate::memory::check(working + frames as f64 * pixels * 16.0, &what).map_err(|message| {
        NdError::Value {
            arg: arg.into(),
            message,
        }
    })
}

/// The feature-edge pieces the illustrative picture of `opts` draws (one view, whatever
/// `layout`, in the panel [`picture_layout`] gives it), in picture pixels (x right, y down) with their N-D depths and visibility: what a
/// vector drawing of the picture's edges needs (`ndtrace.write_svg`). Empty unless the retina
/// comes with edges and `opts.edges`.
pub fn picture_edges(
    rgba: &[f32],
    depth: Option<&[f32]>,
    shape: &[usize],
    extras: &RetinaExtras<'_>,
    opts: &CompositeOptions,
) -> NdResult<Vec<PixelEdge>> {
    let cells = check_retina(rgba, depth, shape)?;
    check_extras(extras, cells, shape.len())?;
    opts.validate_for(shape, depth.is_some())?;
    if shape.len() < 3 {
        return Ok(Vec::new());
    }
    let o = CompositeOptions {
        mode: CompositeMode::Illustrative,
        layout: ViewLayout::Single,
        ..opts.clone()
    };
    let layout = picture_layout(&o, shape, extras.legend_rows, None);
    Ok(View3::new(rgba, depth, shape, extras, cells, &o).pixel_edges(&o, &layout))
}

fn check_extras(extras: &RetinaExtras<'_>, cells: usize, m: usize) -> NdResult<()> {
    let n = m + 1;
    if let Some(nrm) = extras.normal {
        if nrm.len() != cells * n {
            return Err(NdError::Shape {
                arg: "normal".into(),
                expected: format!("{cells} cells × {n} = {} floats", cells * n),
                got: format!("{} floats", nrm.len()),
            });
        }
    }
    if let Some(cam) = &extras.camera {
        if cam.orientation.len() != n * n || !cam.orientation.iter().all(|v| v.is_finite()) {
            return Err(NdError::Value {
                arg: "camera".into(),
                message: format!("expected a finite {n}×{n} orientation"),
            });
        }
        if !(cam.cell > 0.0 && cam.cell.is_finite()) {
            return Err(NdError::Value {
                arg: "camera".into(),
                message: format!("cell size must be positive, got {}", cam.cell),
            });
        }
    }
    if let Some(obj) = extras.object {
        if obj.len() != cells {
            return Err(NdError::Shape {
                arg: "object_id".into(),
                expected: format!("{cells} cells"),
                got: format!("{} ints", obj.len()),
            });
        }
    }
    if let Some(e) = extras.edges.iter().position(|e| {
        e.a[..m]
            .iter()
            .chain(&e.b[..m])
            .chain(&e.depth)
            .any(|v| !v.is_finite())
    }) {
        return Err(NdError::Value {
            arg: "edges".into(),
            message: format!("edge {e} has a non-finite coordinate or depth"),
        });
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// The input, its preparation and front-to-back accumulation
// ---------------------------------------------------------------------------------------------

fn shape_err(message: String) -> NdError {
    NdError::Value {
        arg: "shape".into(),
        message,
    }
}

/// Checks the retina's shape and the lengths of its arrays; returns the number of cells.
fn check_retina(rgba: &[f32], depth: Option<&[f32]>, shape: &[usize]) -> NdResult<usize> {
    let m = shape.len();
    if !(1..=7).contains(&m) {
        return Err(shape_err(format!(
            "a retina has 1 to 7 axes (scene dimension N = 2..=8), got {m} axes {shape:?}"
        )));
    }
    if let Some(k) = shape.iter().position(|&r| r == 0) {
        return Err(shape_err(format!("axis {k} has no cells: {shape:?}")));
    }
    let cells = shape
        .iter()
        .try_fold(1usize, |a, &r| a.checked_mul(r))
        .filter(|&c| c <= isize::MAX as usize / 16)
        .ok_or_else(|| shape_err(format!("too many cells: {shape:?}")))?;
    let dims = shape
        .iter()
        .map(|r| r.to_string())
        .collect::<Vec<_>>()
        .join(", ");
    if rgba.len() != cells * 4 {
        return Err(NdError::Shape {
            arg: "rgba".into(),
            expected: format!("({dims}, 4) = {} floats", cells * 4),
            got: format!("{} floats", rgba.len()),
        });
    }
    if let Some(d) = depth {
        if d.len() != cells {
            return Err(NdError::Shape {
                arg: "depth".into(),
                expected: format!("({dims}) = {cells} floats"),
                got: format!("{} floats", d.len()),
            });
        }
    }
    // NaN or infinite colours would make the whole picture NaN; depth is +inf on a miss.
    let bad = |arg: &str, index: usize, value: f32| NdError::NonFinite {
        arg: arg.into(),
        index,
        value: value as f64,
    };
    if let Some(i) = rgba.iter().position(|v| !v.is_finite()) {
        return Err(bad("rgba", i, rgba[i]));
    }
    if let Some(d) = depth {
        if let Some(i) = d.iter().position(|&v| v.is_nan() || v == f32::NEG_INFINITY) {
            return Err(bad("depth", i, d[i]));
        }
    }
    Ok(cells)
}

/// A working copy of the retina as one `[f32; 4]` per cell: alpha scaled by the opacity
/// (colour with it) and clamped to [0, 1], and the depth cue applied.
pub(super) fn prepare(
    rgba: &[f32],
    depth: Option<&[f32]>,
    cells: usize,
    o: &CompositeOptions,
) -> Vec<[f32; 4]> {
    let opacity = o.opacity as f32;
    let cue = o.depth_cue as f32;
    let (lo, hi) = match (depth, cue > 0.0) {
        (Some(d), true) => d
            .iter()
            .filter(|v| v.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            }),
        _ => (0.0, 0.0),
    };
    // In f64: the span of depths near ±f32::MAX overflows f32.
    let (lo, span) = (lo as f64, if hi > lo { hi as f64 - lo as f64 } else { 1.0 });
    let mut out = vec![[0f32; 4]; cells];
    out.par_chunks_mut(4096)
        .enumerate()
        .for_each(|(chunk, dst)| {
            for (j, cell) in dst.iter_mut().enumerate() {
                let i = chunk * 4096 + j;
                let a = rgba[i * 4 + 3];
                let a2 = (a * opacity).clamp(0.0, 1.0);
                let k = if a > 0.0 { a2 / a } else { 0.0 };
                // A large opacity over a faint cell can scale its colour past f32::MAX.
                let scaled = |x: f32| (x * k).clamp(-f32::MAX, f32::MAX);
                let mut c = [
                    scaled(rgba[i * 4]),
                    scaled(rgba[i * 4 + 1]),
                    scaled(rgba[i * 4 + 2]),
                    a2,
                ];
                if cue > 0.0 {
                    if let Some(d) = depth.map(|d| d[i]).filter(|d| d.is_finite()) {
                        let t = ((d as f64 - lo) / span).clamp(0.0, 1.0) as f32;
                        for ch in 0..3 {
                            let tint = NEAR_TINT[ch] + (FAR_TINT[ch] - NEAR_TINT[ch]) * t;
                            c[ch] *= 1.0 - cue + cue * tint;
                        }
                    }
                }
                *cell = c;
            }
        });
    out
}

/// An m-D array of premultiplied RGBA cells in numpy order.
pub(super) struct Volume {
    pub(super) shape: Vec<usize>,
    pub(super) cells: Vec<[f32; 4]>,
}

/// Front-to-back "over" accumulation with the step correction of [`CompositeMode::Volume`].
#[derive(Clone, Copy)]
pub(super) struct Accum {
    /// Premultiplied colour in x, y, z (w unused).
    color: Vec4,
    trans: f32,
}

impl Accum {
    pub(super) const EMPTY: Accum = Accum {
        color: Vec4::ZERO,
        trans: 1.0,
    };

    /// Adds a sample of premultiplied `s` over a path of `dt` cells.
    #[inline(always)]
    pub(super) fn add(&mut self, s: Vec4, dt: f32) {
        let a = s.w;
        if !(a > 0.0) {
            return;
        }
        let (alpha, k) = if a >= 1.0 {
            (1.0, 1.0)
        } else {
            let alpha = opacity_over(a, dt);
            (alpha, if a > 1e-6 { alpha / a } else { dt })
        };
        self.color += s * (self.trans * k);
        self.trans *= 1.0 - alpha;
    }

    pub(super) fn done(&self) -> bool {
        self.trans < MIN_TRANSMITTANCE
    }

    pub(super) fn rgba(&self) -> [f32; 4] {
        [self.color.x, self.color.y, self.color.z, 1.0 - self.trans]
    }
}

/// 1 − (1 − a)^dt, the opacity over `dt` cells of a cell of alpha a < 1; the common steps avoid
/// `powf` (which dominated the volume mode).
#[inline(always)]
fn opacity_over(a: f32, dt: f32) -> f32 {
    let u = 1.0 - a;
    if dt == 1.0 {
        a
    } else if dt == 0.5 {
        1.0 - u.sqrt()
    } else if dt == 0.25 {
        1.0 - u.sqrt().sqrt()
    } else if dt == 2.0 {
        1.0 - u * u
    } else {
        1.0 - u.powf(dt)
    }
}

/// `s` (premultiplied) over the opaque background: RGB composited, alpha kept.
#[inline]
pub(super) fn over(s: [f32; 4], bg: [f32; 3]) -> [f32; 4] {
    let t = 1.0 - s[3];
    [s[0] + t * bg[0], s[1] + t * bg[1], s[2] + t * bg[2], s[3]]
}

#[cfg(test)]
mod tests;
