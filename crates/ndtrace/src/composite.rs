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
//! Work is split over output rows with rayon; every pixel depends only on the inputs and its
//! own coordinates, so the picture is bit-identical whatever the number of threads.

use crate::scene::desc::Projection as SceneProjection;
use crate::{NdError, NdResult};
use glam::{DVec3, Vec4};
use rayon::prelude::*;

/// Perspective or orthographic projection (the scene description's enum, shared).
pub type Projection = SceneProjection;

/// How a 3D volume (the retina of a 4D scene, or the result of the recursive projection for
/// N ≥ 5) is turned into a picture. Ignored for N ≤ 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CompositeMode {
    /// Front-to-back emission–absorption along each pixel ray, sampling the premultiplied RGBA
    /// trilinearly every [`CompositeOptions::step`] cells. A cell's alpha is its opacity over
    /// one cell length: a sample with alpha a over a step of Δ cells has opacity 1 − (1 − a)^Δ
    /// and emits its premultiplied colour times (1 − (1 − a)^Δ) / a, so the picture does not
    /// depend on the step (a uniform slab of alpha a and thickness L cells has opacity exactly
    /// 1 − (1 − a)^L). Rays stop once the transmittance falls below 1e-4.
    #[default]
    Volume,
    /// Maximum intensity projection: each ray shows, unchanged, the cell it crosses whose
    /// premultiplied colour has the largest Rec. 709 luminance (ties: the larger alpha, then
    /// the nearer cell). Cells are crossed exactly (voxel traversal, no interpolation).
    Mip,
    /// The nearest cell with alpha > 0 that the ray crosses, shown opaque in its own
    /// (un-premultiplied) colour: crisp cube-shaped cells and silhouettes.
    FirstHit,
    /// A montage of the 2D slices of the volume along [`CompositeOptions::axis`]; see
    /// [`slice_layout`] for where slice k goes.
    Slices,
}

impl CompositeMode {
    /// Parses `volume`, `mip`, `first_hit` or `slices`.
    pub fn parse(name: &str) -> NdResult<Self> {
        match name {
            "volume" => Ok(Self::Volume),
            "mip" => Ok(Self::Mip),
            "first_hit" => Ok(Self::FirstHit),
            "slices" => Ok(Self::Slices),
            other => Err(NdError::Value {
                arg: "mode".into(),
                message: format!(
                    "expected one of 'volume', 'mip', 'first_hit', 'slices', got {other:?}"
                ),
            }),
        }
    }

    /// The name [`CompositeMode::parse`] accepts.
    pub fn name(self) -> &'static str {
        match self {
            Self::Volume => "volume",
            Self::Mip => "mip",
            Self::FirstHit => "first_hit",
            Self::Slices => "slices",
        }
    }
}

/// Default camera distance, in half-diagonals of the retina cube.
pub const DEFAULT_DISTANCE: f64 = 4.0;
/// Default eye distance d_k of a recursive stage, in half-lengths of the stage's longest axis.
pub const DEFAULT_STAGE_DISTANCE: f64 = 3.0;
/// Rays of the volume mode stop when the transmittance falls below this.
pub const MIN_TRANSMITTANCE: f32 = 1e-4;

/// Options of [`composite`]. Every field has a documented default ([`Default`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CompositeOptions {
    /// How a 3D volume becomes a picture. Default [`CompositeMode::Volume`].
    pub mode: CompositeMode,
    /// Degrees; rotation of the eye about the vertical (row) axis. Default 30.
    pub azimuth: f64,
    /// Degrees; height of the eye above the horizontal plane. Default 20.
    pub elevation: f64,
    /// Distance from the cube's centre to the eye, in units of the cube's half-diagonal r (the
    /// radius of its bounding sphere). Perspective: must exceed 1 (the eye outside the
    /// bounding sphere); the field of view is the one in which the bounding sphere just fills
    /// the shorter side of the picture (tan(fov/2) = 1/√(distance² − 1)), so the object keeps
    /// its size as the camera orbits and a larger distance only weakens the perspective.
    /// Orthographic: any positive value; the picture does not depend on it (the view's shorter
    /// side spans the bounding sphere's diameter 2r). Default [`DEFAULT_DISTANCE`] = 4.
    pub distance: f64,
    /// Magnification of the 3D view (both projections): 2 shows half the width. Default 1.
    pub zoom: f64,
    /// Of the 3D camera and of every recursive stage. Default perspective.
    pub projection: Projection,
    /// Picture size (W, H) in pixels. Default (512, 512).
    pub size: (usize, usize),
    /// Scales every cell's alpha (and its premultiplied colour with it, clamped so alpha ≤ 1)
    /// before anything else, so inner structure shows through: 0.05 makes a solid traced body
    /// a translucent cloud. Must be ≥ 0. Default 1.
    pub opacity: f64,
    /// Sample spacing of the volume mode, in cells (0.01 ..= 4). Default 0.5.
    pub step: f64,
    /// Strength in [0, 1] of depth cueing; 0 turns it off (default). Every hit cell's colour is
    /// multiplied by `1 − s + s · tint(t)` where t ∈ [0, 1] is its depth (distance from the N-D
    /// eye, the `depth` array) normalized over the retina's finite depths, and tint runs
    /// linearly from warm [`NEAR_TINT`] (nearest) to cool [`FAR_TINT`] (farthest), so near and
    /// far along the hidden axis read apart. Needs `depth`.
    pub depth_cue: f64,
    /// For [`CompositeMode::Slices`]: the numpy axis of the 3D volume to slice along
    /// (0 = slices, 1 = rows, 2 = columns). Default 0.
    pub axis: usize,
    /// Opaque background colour, linear RGB. Default black.
    pub background: [f64; 3],
    /// Per-stage perspective parameters (f_k, d_k) of the recursive projection for N ≥ 5,
    /// ordered (f_{N−1}, d_{N−1}), …, (f_4, d_4): `stages[0]` collapses the leading numpy axis
    /// of the (N−1)-D retina. Either empty (every stage at its default) or exactly N − 4 pairs.
    ///
    /// A stage places its k-D input with its centre at the origin and cells of side
    /// `c = 2 / max(R)` (so its longest axis spans [−1, 1]; a_k is the half-length of the
    /// collapsed axis), puts the eye at x_k = −d_k on the collapsed axis (index 0 nearest) and
    /// maps a point to the (k−1)-D film by x_j ↦ x_j · f_k / (d_k + x_k), the course's
    /// "divide by (d − x)/f". Output cells have the input's grid; each output cell's ray is
    /// sampled (multilinearly, zero outside the box) at every input slice, front to back, with
    /// the step correction of the volume mode for its oblique path length. Requires f_k > 0 and
    /// d_k > a_k. Default d_k = [`DEFAULT_STAGE_DISTANCE`] = 3 and f_k = d_k − a_k + c/2, which
    /// maps the nearest slice (index 0, centred at x_k = −a_k + c/2) one-to-one onto the film;
    /// farther slices appear smaller, toward the centre.
    /// With orthographic projection every stage is a parallel projection and (f, d) are unused.
    pub stages: Vec<(f64, f64)>,
    /// For N = 2: height in pixels of the strip (≥ 1; clipped to the picture height).
    /// Default 32.
    pub strip_height: usize,
    /// For [`CompositeMode::Slices`]: draw each slice's index in the top-left corner of its
    /// tile (when the tile is large enough). Default true.
    pub labels: bool,
}

impl Default for CompositeOptions {
    fn default() -> Self {
        Self {
            mode: CompositeMode::Volume,
            azimuth: 30.0,
            elevation: 20.0,
            distance: DEFAULT_DISTANCE,
            zoom: 1.0,
            projection: Projection::Perspective,
            size: (512, 512),
            opacity: 1.0,
            step: 0.5,
            depth_cue: 0.0,
            axis: 0,
            background: [0.0; 3],
            stages: Vec::new(),
            strip_height: 32,
            labels: true,
        }
    }
}

/// Depth-cue tint of the nearest cells (warm).
pub const NEAR_TINT: [f32; 3] = [1.2, 0.9, 0.6];
/// Depth-cue tint of the farthest cells (cool).
pub const FAR_TINT: [f32; 3] = [0.5, 0.75, 1.2];

/// Colour of the separators of the slice montage.
pub const SEPARATOR: [f32; 3] = [0.35, 0.35, 0.35];

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

/// Largest number of pixels of a picture.
pub const MAX_PIXELS: usize = 1 << 28;

/// Composites a retina (premultiplied `rgba`, optional `depth`, numpy-order `shape`) into a
/// picture. See the [module docs](self) and [`CompositeOptions`].
pub fn composite(
    rgba: &[f32],
    depth: Option<&[f32]>,
    shape: &[usize],
    opts: &CompositeOptions,
) -> NdResult<Image> {
    let cells = validate(rgba, depth, shape, opts)?;
    let mut vol = Volume {
        shape: shape.to_vec(),
        cells: prepare(rgba, depth, cells, opts),
    };
    // Recursive projection, one leading axis at a time, down to 3D.
    let mut stage = 0;
    while vol.shape.len() > 3 {
        let (f, d) = stage_params(&vol.shape, opts.stages.get(stage).copied());
        vol = project_stage(&vol, f, d, opts.projection == Projection::Orthographic);
        stage += 1;
    }
    let (w, h) = opts.size;
    let bg = opts.background.map(|x| x as f32);
    let rgba = match vol.shape.len() {
        3 => match opts.mode {
            CompositeMode::Slices => render_slices(&vol, opts, bg),
            mode => render_3d(&Grid::new(&vol), mode, opts, bg),
        },
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
            render_tiles(w, h, &tiles, bg, |_, x, y| y * cols + x)
        }
        _ => render_strip(&vol.cells, w, h, opts.strip_height, bg),
    };
    Ok(Image {
        width: w,
        height: h,
        rgba,
    })
}

// ---------------------------------------------------------------------------------------------
// Validation and preparation
// ---------------------------------------------------------------------------------------------

fn value_err(arg: &str, message: impl Into<String>) -> NdError {
    NdError::Value {
        arg: arg.into(),
        message: message.into(),
    }
}

fn finite(arg: &str, v: f64) -> NdResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(value_err(arg, format!("must be finite, got {v}")))
    }
}

/// Checks everything; returns the number of cells.
fn validate(
    rgba: &[f32],
    depth: Option<&[f32]>,
    shape: &[usize],
    o: &CompositeOptions,
) -> NdResult<usize> {
    let m = shape.len();
    if !(1..=7).contains(&m) {
        return Err(value_err(
            "shape",
            format!("a retina has 1 to 7 axes (scene dimension N = 2..=8), got {m} axes {shape:?}"),
        ));
    }
    if let Some(k) = shape.iter().position(|&r| r == 0) {
        return Err(value_err(
            "shape",
            format!("axis {k} has no cells: {shape:?}"),
        ));
    }
    let cells = shape
        .iter()
        .try_fold(1usize, |a, &r| a.checked_mul(r))
        .filter(|&c| c <= isize::MAX as usize / 16)
        .ok_or_else(|| value_err("shape", format!("too many cells: {shape:?}")))?;
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
    let (w, h) = o.size;
    if w == 0 || h == 0 {
        return Err(value_err(
            "size",
            format!("width and height must be positive, got ({w}, {h})"),
        ));
    }
    if w.checked_mul(h).is_none_or(|p| p > MAX_PIXELS) {
        return Err(value_err(
            "size",
            format!("({w}, {h}) exceeds {MAX_PIXELS} pixels"),
        ));
    }
    finite("azimuth", o.azimuth)?;
    finite("elevation", o.elevation)?;
    let dist = finite("distance", o.distance)?;
    if o.projection == Projection::Perspective && !(dist > 1.0) {
        return Err(value_err(
            "distance",
            format!("must exceed 1 (half-diagonals of the retina cube) for a perspective view, got {dist}"),
        ));
    }
    if !(dist > 0.0) {
        return Err(value_err(
            "distance",
            format!("must be positive, got {dist}"),
        ));
    }
    if !(finite("zoom", o.zoom)? > 0.0) {
        return Err(value_err(
            "zoom",
            format!("must be positive, got {}", o.zoom),
        ));
    }
    if !(finite("opacity", o.opacity)? >= 0.0) {
        return Err(value_err(
            "opacity",
            format!("must be ≥ 0, got {}", o.opacity),
        ));
    }
    if !(0.01..=4.0).contains(&finite("step", o.step)?) {
        return Err(value_err(
            "step",
            format!("must be in [0.01, 4] cells, got {}", o.step),
        ));
    }
    let cue = finite("depth_cue", o.depth_cue)?;
    if !(0.0..=1.0).contains(&cue) {
        return Err(value_err(
            "depth_cue",
            format!("must be in [0, 1], got {cue}"),
        ));
    }
    if cue > 0.0 && depth.is_none() {
        return Err(value_err(
            "depth_cue",
            "needs the retina's depth array (e.g. a traced ndtrace.Retina)",
        ));
    }
    for (k, &b) in o.background.iter().enumerate() {
        finite(&format!("background[{k}]"), b)?;
    }
    if o.mode == CompositeMode::Slices && m >= 3 && o.axis > 2 {
        return Err(value_err(
            "axis",
            format!(
                "must be 0, 1 or 2 (an axis of the 3D volume), got {}",
                o.axis
            ),
        ));
    }
    if o.strip_height == 0 {
        return Err(value_err("strip_height", "must be at least 1"));
    }
    // Stages: N − 4 = m − 3 of them for N ≥ 5.
    let n_stages = m.saturating_sub(3);
    if !o.stages.is_empty() && o.stages.len() != n_stages {
        return Err(value_err(
            "stages",
            format!(
                "expected {n_stages} (f, d) pairs for a {m}-D retina (one per axis collapsed down to 3D) \
                 or none for the defaults, got {}",
                o.stages.len()
            ),
        ));
    }
    if o.projection == Projection::Perspective {
        for (i, &(f, d)) in o.stages.iter().enumerate() {
            let arg = format!("stages[{i}]");
            let f = finite(&arg, f)?;
            let d = finite(&arg, d)?;
            let sub = &shape[i..];
            let a = half_lengths(sub)[0];
            if !(f > 0.0) || !(d > a) {
                return Err(value_err(
                    &arg,
                    format!(
                        "(f, d) = ({f}, {d}): need f > 0 and d > {a} (the eye outside the box, \
                         whose collapsed axis spans ±{a})"
                    ),
                ));
            }
        }
    }
    Ok(cells)
}

/// Half-lengths a_j of a stage box whose cells have side 2 / max(R).
fn half_lengths(shape: &[usize]) -> Vec<f64> {
    let c = 2.0 / *shape.iter().max().unwrap_or(&1) as f64;
    shape.iter().map(|&r| r as f64 * c / 2.0).collect()
}

/// The (f, d) of the stage collapsing the leading axis of `shape`.
fn stage_params(shape: &[usize], given: Option<(f64, f64)>) -> (f64, f64) {
    given.unwrap_or_else(|| {
        // f = d + x_k of slice 0, computed as in `project_stage`, so that slice 0 maps exactly.
        let c = 2.0 / *shape.iter().max().unwrap() as f64;
        let x0 = (0.5 - shape[0] as f64 / 2.0) * c;
        (DEFAULT_STAGE_DISTANCE + x0, DEFAULT_STAGE_DISTANCE)
    })
}

/// A working copy of the retina as one `[f32; 4]` per cell: alpha scaled by the opacity
/// (colour with it) and clamped to [0, 1], and the depth cue applied.
fn prepare(
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
    let span = if hi > lo { hi - lo } else { 1.0 };
    let mut out = vec![[0f32; 4]; cells];
    out.par_chunks_mut(4096)
        .enumerate()
        .for_each(|(chunk, dst)| {
            for (j, cell) in dst.iter_mut().enumerate() {
                let i = chunk * 4096 + j;
                let a = rgba[i * 4 + 3];
                let a2 = (a * opacity).clamp(0.0, 1.0);
                let k = if a > 0.0 { a2 / a } else { 0.0 };
                let mut c = [
                    rgba[i * 4] * k,
                    rgba[i * 4 + 1] * k,
                    rgba[i * 4 + 2] * k,
                    a2,
                ];
                if cue > 0.0 {
                    if let Some(d) = depth.map(|d| d[i]).filter(|d| d.is_finite()) {
                        let t = ((d - lo) / span).clamp(0.0, 1.0);
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
struct Volume {
    shape: Vec<usize>,
    cells: Vec<[f32; 4]>,
}

/// Front-to-back "over" accumulation with the step correction of [`CompositeMode::Volume`].
#[derive(Clone, Copy)]
struct Accum {
    /// Premultiplied colour in x, y, z (w unused).
    color: Vec4,
    trans: f32,
}

impl Accum {
    const EMPTY: Accum = Accum {
        color: Vec4::ZERO,
        trans: 1.0,
    };

    /// Adds a sample of premultiplied `s` over a path of `dt` cells.
    #[inline(always)]
    fn add(&mut self, s: Vec4, dt: f32) {
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

    fn done(&self) -> bool {
        self.trans < MIN_TRANSMITTANCE
    }

    fn rgba(&self) -> [f32; 4] {
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
fn over(s: [f32; 4], bg: [f32; 3]) -> [f32; 4] {
    let t = 1.0 - s[3];
    [s[0] + t * bg[0], s[1] + t * bg[1], s[2] + t * bg[2], s[3]]
}

// ---------------------------------------------------------------------------------------------
// Recursive projection (N ≥ 5)
// ---------------------------------------------------------------------------------------------

const STAGE_CHUNK: usize = 1024;

/// One k-D → (k−1)-D emission–absorption stage along the leading axis (see
/// [`CompositeOptions::stages`]).
fn project_stage(vol: &Volume, f: f64, d: f64, ortho: bool) -> Volume {
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

// ---------------------------------------------------------------------------------------------
// The 3D volume and its camera (N = 4)
// ---------------------------------------------------------------------------------------------

/// Occupancy blocks are BLOCK³ cells.
const BLOCK: usize = 8;

/// A 3D volume in cell coordinates p = (column, row, slice) ∈ [0, nx] × [0, ny] × [0, nz],
/// stored with one extra cell on every side that repeats the edge cell, so that trilinear
/// sampling clamped to the edge cells needs no per-axis clamping.
struct Grid {
    n: [usize; 3],
    /// (nx + 2) × (ny + 2) × (nz + 2) cells; cell (x, y, z) is at padded (x + 1, y + 1, z + 1).
    cells: Vec<Vec4>,
    /// Index strides of the padded y and z axes.
    sy: usize,
    sz: usize,
    /// Upper clamp of padded sample coordinates, n + ½ (a ray is clipped to [0, n]).
    qmax: [f32; 3],
    /// Per block: does any cell within one cell of the block have alpha > 0? Then every
    /// trilinear sample at a point of an unmarked block is zero.
    occupied: Vec<bool>,
    blocks: [usize; 3],
}

impl Grid {
    fn new(vol: &Volume) -> Self {
        let n = [vol.shape[2], vol.shape[1], vol.shape[0]];
        let blocks = n.map(|r| r.div_ceil(BLOCK));
        let mut occupied = vec![false; blocks[0] * blocks[1] * blocks[2]];
        for z in 0..n[2] {
            for y in 0..n[1] {
                let row = &vol.cells[n[0] * (y + n[1] * z)..][..n[0]];
                for (x, c) in row.iter().enumerate() {
                    if c[3] > 0.0 {
                        let r = |i: usize, k: usize| {
                            (i.saturating_sub(1) / BLOCK)..=((i + 1).min(n[k] - 1) / BLOCK)
                        };
                        for bz in r(z, 2) {
                            for by in r(y, 1) {
                                for bx in r(x, 0) {
                                    occupied[bx + blocks[0] * (by + blocks[1] * bz)] = true;
                                }
                            }
                        }
                    }
                }
            }
        }
        let (px, py, pz) = (n[0] + 2, n[1] + 2, n[2] + 2);
        let mut cells = vec![Vec4::ZERO; px * py * pz];
        cells
            .par_chunks_mut(px * py)
            .enumerate()
            .for_each(|(zp, slab)| {
                let z = zp.clamp(1, n[2]) - 1;
                for yp in 0..py {
                    let y = yp.clamp(1, n[1]) - 1;
                    let src = &vol.cells[n[0] * (y + n[1] * z)..][..n[0]];
                    for xp in 0..px {
                        slab[xp + px * yp] = Vec4::from_array(src[xp.clamp(1, n[0]) - 1]);
                    }
                }
            });
        let qmax = n.map(|r| r as f32 + 0.5);
        Grid {
            n,
            cells,
            sy: px,
            sz: px * py,
            qmax,
            occupied,
            blocks,
        }
    }

    #[inline(always)]
    fn cell(&self, x: usize, y: usize, z: usize) -> [f32; 4] {
        self.cells[(x + 1) + self.sy * (y + 1) + self.sz * (z + 1)].to_array()
    }

    /// Trilinear sample at `p` (cell centres at half-integers), clamped to the edge cells.
    #[inline(always)]
    fn sample(&self, p: [f32; 3]) -> Vec4 {
        // Padded coordinates: the centre of cell i is at i + 1.5, so the lower of the two
        // cells around p is ⌊p + ½⌋ (padded) and the fraction is the rest.
        let q = |k: usize| {
            let v = p[k] + 0.5;
            if v > 0.0 {
                if v < self.qmax[k] {
                    v
                } else {
                    self.qmax[k]
                }
            } else {
                0.0
            }
        };
        let (qx, qy, qz) = (q(0), q(1), q(2));
        // i32 (not usize) conversions: single instructions on x86-64.
        let (ix, iy, iz) = (qx as i32, qy as i32, qz as i32);
        let (fx, fy, fz) = (qx - ix as f32, qy - iy as f32, qz - iz as f32);
        let (sy, sz) = (self.sy, self.sz);
        let base = ix as usize + sy * iy as usize + sz * iz as usize;
        let c = &self.cells[base..base + sz + sy + 2];
        let x00 = c[0].lerp(c[1], fx);
        let x10 = c[sy].lerp(c[sy + 1], fx);
        let x01 = c[sz].lerp(c[sz + 1], fx);
        let x11 = c[sz + sy].lerp(c[sz + sy + 1], fx);
        x00.lerp(x10, fy).lerp(x01.lerp(x11, fy), fz)
    }

    /// Calls `seg(ta, tb)` for the maximal runs [ta, tb] ⊂ [t0, t1] of the ray through occupied
    /// blocks, nearest first, until it returns true.
    fn occupied_runs(
        &self,
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        mut seg: impl FnMut(f64, f64) -> bool,
    ) {
        let mut run: Option<f64> = None;
        let mut stopped = false;
        walk_cells(o, d, t0, t1, BLOCK as f64, self.blocks, |c, t_in| {
            let b = c[0] + self.blocks[0] * (c[1] + self.blocks[1] * c[2]);
            match (self.occupied[b], run) {
                (true, None) => run = Some(t_in),
                (false, Some(ta)) => {
                    if seg(ta, t_in) {
                        stopped = true;
                        return true;
                    }
                    run = None;
                }
                _ => {}
            }
            false
        });
        if let (false, Some(ta)) = (stopped, run) {
            seg(ta, t1);
        }
    }
}

/// The orbiting camera, in cell coordinates.
struct Camera3 {
    w: usize,
    h: usize,
    ortho: bool,
    /// Eye (perspective) or centre of the view plane (orthographic), cell coordinates.
    eye: DVec3,
    fwd: DVec3,
    right: DVec3,
    up: DVec3,
    /// Image-plane units per pixel (at unit distance for perspective).
    pixel: f64,
}

impl Camera3 {
    fn new(n: [usize; 3], o: &CompositeOptions) -> Self {
        let c = 2.0 / *n.iter().max().unwrap() as f64;
        let half = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64) * (c / 2.0);
        let radius = half.length();
        let (az, el) = (o.azimuth.to_radians(), o.elevation.to_radians());
        let to_eye = DVec3::new(az.sin() * el.cos(), el.sin(), -az.cos() * el.cos());
        let fwd_w = -to_eye;
        let right_w = DVec3::new(az.cos(), 0.0, az.sin());
        let up_w = fwd_w.cross(right_w);
        // World (x right, y up, z slices) → cell coordinates (column, row, slice).
        let to_cell_dir = |v: DVec3| DVec3::new(v.x, -v.y, v.z);
        let eye_w = to_eye * (o.distance * radius);
        let eye = DVec3::new(eye_w.x + half.x, half.y - eye_w.y, eye_w.z + half.z) / c;
        let ortho = o.projection == Projection::Orthographic;
        let (w, h) = o.size;
        let short = w.min(h) as f64;
        let pixel = if ortho {
            2.0 * radius / c / o.zoom / short
        } else {
            2.0 / (o.distance * o.distance - 1.0).sqrt() / o.zoom / short
        };
        Camera3 {
            w,
            h,
            ortho,
            eye,
            fwd: to_cell_dir(fwd_w),
            right: to_cell_dir(right_w),
            up: to_cell_dir(up_w),
            pixel,
        }
    }

    /// The ray through the centre of pixel (px, py): origin, unit direction (cell units) and
    /// whether t must stay ≥ 0.
    #[inline]
    fn ray(&self, px: usize, py: usize) -> (DVec3, DVec3, bool) {
        let sx = (px as f64 + 0.5 - self.w as f64 / 2.0) * self.pixel;
        let sy = (self.h as f64 / 2.0 - py as f64 - 0.5) * self.pixel;
        if self.ortho {
            (self.eye + self.right * sx + self.up * sy, self.fwd, false)
        } else {
            (
                self.eye,
                (self.fwd + self.right * sx + self.up * sy).normalize(),
                true,
            )
        }
    }
}

/// The parameter interval of the ray inside the box [0, n].
fn clip_box(o: DVec3, d: DVec3, n: [usize; 3], forward_only: bool) -> Option<(f64, f64)> {
    let mut t0 = if forward_only { 0.0 } else { f64::NEG_INFINITY };
    let mut t1 = f64::INFINITY;
    for k in 0..3 {
        let (ok, dk, hi) = (o[k], d[k], n[k] as f64);
        if dk == 0.0 {
            if ok < 0.0 || ok > hi {
                return None;
            }
        } else {
            let (a, b) = ((0.0 - ok) / dk, (hi - ok) / dk);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
    }
    (t1 > t0).then_some((t0, t1))
}

/// Rows of pixels per unit of parallel work; within it, pixels go in TILE × TILE tiles so
/// that neighbouring rays reuse the cells in cache.
const TILE: usize = 16;

fn render_3d(grid: &Grid, mode: CompositeMode, o: &CompositeOptions, bg: [f32; 3]) -> Vec<f32> {
    let cam = Camera3::new(grid.n, o);
    let (w, h) = o.size;
    let step = o.step;
    let mut img = vec![0f32; w * h * 4];
    img.par_chunks_mut(w * 4 * TILE)
        .enumerate()
        .for_each(|(band, rows)| {
            let nrows = rows.len() / (w * 4);
            for tx in (0..w).step_by(TILE) {
                for r in 0..nrows {
                    let py = band * TILE + r;
                    for px in tx..(tx + TILE).min(w) {
                        let (org, dir, fwd_only) = cam.ray(px, py);
                        let v = match clip_box(org, dir, grid.n, fwd_only) {
                            None => [0.0; 4],
                            Some((t0, t1)) => match mode {
                                CompositeMode::Volume => march(grid, org, dir, t0, t1, step),
                                CompositeMode::Mip => mip(grid, org, dir, t0, t1),
                                _ => first_hit(grid, org, dir, t0, t1),
                            },
                        };
                        let i = (r * w + px) * 4;
                        rows[i..i + 4].copy_from_slice(&over(v, bg));
                    }
                }
            }
        });
    img
}

/// Volume mode: emission–absorption at the midpoints t_j = t0 + (j + ½)·step of the ⌊L/step⌋
/// whole steps that fit in the ray's segment [t0, t1] of L cells, plus one sample at the
/// middle of the remainder (weighted by its length); samples in unoccupied blocks (all zero)
/// are skipped.
fn march(grid: &Grid, o: DVec3, d: DVec3, t0: f64, t1: f64, step: f64) -> [f32; 4] {
    let len = t1 - t0;
    let whole = (len / step + 1e-9).floor() as usize;
    let rem = len - whole as f64 * step;
    let n = whole + usize::from(rem > 1e-6 * step);
    let t_last = t0 + whole as f64 * step + 0.5 * rem;
    let mut acc = Accum::EMPTY;
    let (stepf, remf) = (step as f32, rem as f32);
    let start = o + d * (t0 + 0.5 * step);
    let start = [start.x as f32, start.y as f32, start.z as f32];
    let delta = [
        (d.x * step) as f32,
        (d.y * step) as f32,
        (d.z * step) as f32,
    ];
    // The first sample at or after t.
    let first = |t: f64| {
        let j = ((t - t0) / step - 0.5).ceil().max(0.0);
        if j < whole as f64 {
            j as usize
        } else if n > whole && t <= t_last {
            whole
        } else {
            n
        }
    };
    grid.occupied_runs(o, d, t0, t1, |ta, tb| {
        let (j0, j1) = (first(ta), if tb >= t1 { n } else { first(tb) });
        for j in j0..j1 {
            if j < whole {
                let jf = j as i32 as f32;
                let p = [
                    start[0] + jf * delta[0],
                    start[1] + jf * delta[1],
                    start[2] + jf * delta[2],
                ];
                acc.add(grid.sample(p), stepf);
            } else {
                let p = o + d * t_last;
                acc.add(grid.sample([p.x as f32, p.y as f32, p.z as f32]), remf);
            }
            if acc.done() {
                return true;
            }
        }
        false
    });
    acc.rgba()
}

/// Visits the cells the ray crosses in [t0, t1], nearest first, until `visit` returns true.
fn traverse(
    grid: &Grid,
    o: DVec3,
    d: DVec3,
    t0: f64,
    t1: f64,
    mut visit: impl FnMut([f32; 4]) -> bool,
) {
    walk_cells(o, d, t0, t1, 1.0, grid.n, |c, _| {
        visit(grid.cell(c[0], c[1], c[2]))
    });
}

/// The 3D digital differential analyzer (Amanatides–Woo) over a grid of `dims` cubic cells of
/// side `size`: calls `visit(cell, t_enter)` for every cell the ray `o + t·d` crosses in
/// [t0, t1], nearest first, until `visit` returns true or the ray leaves [t0, t1] or the grid.
fn walk_cells(
    o: DVec3,
    d: DVec3,
    t0: f64,
    t1: f64,
    size: f64,
    dims: [usize; 3],
    mut visit: impl FnMut([usize; 3], f64) -> bool,
) {
    let p = o + d * t0;
    let mut cell = [0i64; 3];
    let mut step = [0i64; 3];
    let mut t_max = [f64::INFINITY; 3];
    let mut t_delta = [f64::INFINITY; 3];
    for k in 0..3 {
        let last = dims[k] as i64 - 1;
        cell[k] = ((p[k] / size).floor() as i64).clamp(0, last);
        if d[k] > 0.0 {
            step[k] = 1;
            t_delta[k] = size / d[k];
            t_max[k] = t0 + ((cell[k] + 1) as f64 * size - p[k]) / d[k];
        } else if d[k] < 0.0 {
            step[k] = -1;
            t_delta[k] = -size / d[k];
            t_max[k] = t0 + (cell[k] as f64 * size - p[k]) / d[k];
        }
    }
    let mut t = t0;
    loop {
        let here = [cell[0] as usize, cell[1] as usize, cell[2] as usize];
        if visit(here, t) {
            return;
        }
        let k = if t_max[0] <= t_max[1] && t_max[0] <= t_max[2] {
            0
        } else if t_max[1] <= t_max[2] {
            1
        } else {
            2
        };
        if t_max[k] >= t1 {
            return;
        }
        cell[k] += step[k];
        if cell[k] < 0 || cell[k] >= dims[k] as i64 {
            return;
        }
        t = t_max[k];
        t_max[k] += t_delta[k];
    }
}

/// Rec. 709 luminance.
#[inline]
fn luminance(c: [f32; 4]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

fn mip(grid: &Grid, o: DVec3, d: DVec3, t0: f64, t1: f64) -> [f32; 4] {
    let mut best = [0f32; 4];
    let mut key = (0f32, 0f32);
    grid.occupied_runs(o, d, t0, t1, |ta, tb| {
        traverse(grid, o, d, ta, tb, |c| {
            let k = (luminance(c), c[3]);
            if k > key {
                key = k;
                best = c;
            }
            false
        });
        false
    });
    best
}

fn first_hit(grid: &Grid, o: DVec3, d: DVec3, t0: f64, t1: f64) -> [f32; 4] {
    let mut hit = [0f32; 4];
    grid.occupied_runs(o, d, t0, t1, |ta, tb| {
        let mut found = false;
        traverse(grid, o, d, ta, tb, |c| {
            found = c[3] > 0.0;
            if found {
                hit = [c[0] / c[3], c[1] / c[3], c[2] / c[3], 1.0];
            }
            found
        });
        found
    });
    hit
}

// ---------------------------------------------------------------------------------------------
// Pictures of 2D arrays: the slice montage, the 2D retina, the 1D strip
// ---------------------------------------------------------------------------------------------

/// Where the slice montage puts its tiles: a grid of `cols × rows` tiles of `tile_w × tile_h`
/// pixels separated (and framed) by `gap`-pixel separators, centred in the picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Tiles per row of the montage: ⌈√count⌉.
    pub cols: usize,
    /// Rows of tiles: ⌈count / cols⌉.
    pub rows: usize,
    /// Width of a tile in pixels.
    pub tile_w: usize,
    /// Height of a tile in pixels.
    pub tile_h: usize,
    /// Separator width in pixels.
    pub gap: usize,
    /// Pixel coordinates of the montage's top-left corner (its outer separator).
    pub origin: (usize, usize),
}

impl Layout {
    /// Top-left pixel of tile `k`: tile k sits in montage row k / cols, column k % cols.
    pub fn tile_origin(&self, k: usize) -> (usize, usize) {
        let (r, c) = (k / self.cols, k % self.cols);
        (
            self.origin.0 + self.gap + c * (self.tile_w + self.gap),
            self.origin.1 + self.gap + r * (self.tile_h + self.gap),
        )
    }
}

/// The montage layout for `count` tiles of `tw × th` cells in a `w × h` picture with
/// separators of `gap` pixels (the slice montage uses gap 1; a 2D retina uses 1 tile and gap 0).
///
/// The cell scale s = min((w − (cols+1)·gap) / (cols·tw), (h − (rows+1)·gap) / (rows·th)) is
/// rounded down to a whole number when ≥ 1 (each cell an s × s block of pixels); tiles are
/// max(1, ⌊tw·s⌋) × max(1, ⌊th·s⌋) pixels, and the montage is centred (offsets rounded down).
/// A pixel of a tile shows the cell under its centre (nearest).
pub fn slice_layout(w: usize, h: usize, count: usize, tw: usize, th: usize, gap: usize) -> Layout {
    let cols = ((count as f64).sqrt().ceil() as usize).max(1);
    let cols = if (cols - 1) * (cols - 1) >= count && cols > 1 {
        cols - 1
    } else {
        cols
    };
    let rows = count.div_ceil(cols).max(1);
    let sw = w.saturating_sub((cols + 1) * gap) as f64 / (cols * tw) as f64;
    let sh = h.saturating_sub((rows + 1) * gap) as f64 / (rows * th) as f64;
    let mut s = sw.min(sh);
    if s >= 1.0 {
        s = s.floor();
    }
    let tile_w = ((tw as f64 * s).floor() as usize).max(1);
    let tile_h = ((th as f64 * s).floor() as usize).max(1);
    let mw = cols * tile_w + (cols + 1) * gap;
    let mh = rows * tile_h + (rows + 1) * gap;
    Layout {
        cols,
        rows,
        tile_w,
        tile_h,
        gap,
        origin: (w.saturating_sub(mw) / 2, h.saturating_sub(mh) / 2),
    }
}

/// The 3×5 digits of the slice labels, one row per entry, bit 2 = left column.
const DIGITS: [[u8; 5]; 10] = [
    [0b111, 0b101, 0b101, 0b101, 0b111],
    [0b010, 0b110, 0b010, 0b010, 0b111],
    [0b111, 0b001, 0b111, 0b100, 0b111],
    [0b111, 0b001, 0b111, 0b001, 0b111],
    [0b101, 0b101, 0b111, 0b001, 0b001],
    [0b111, 0b100, 0b111, 0b001, 0b111],
    [0b111, 0b100, 0b111, 0b101, 0b111],
    [0b111, 0b001, 0b001, 0b001, 0b001],
    [0b111, 0b101, 0b111, 0b101, 0b111],
    [0b111, 0b101, 0b111, 0b001, 0b111],
];

/// The label of tile `k` at scale `ls`: is pixel (x, y) of the tile (relative to its top-left
/// corner) part of the label's box, and if so is it ink? The box is a dark plate one font
/// pixel larger than the digits on every side.
fn label_pixel(k: usize, ls: usize, x: usize, y: usize) -> Option<bool> {
    let text = k.to_string();
    let (bw, bh) = ((text.len() * 4 + 1) * ls, 7 * ls);
    if x >= bw || y >= bh {
        return None;
    }
    let (fx, fy) = (x / ls, y / ls);
    if fx == 0 || fy == 0 || fy > 5 {
        return Some(false);
    }
    let (ch, col) = ((fx - 1) / 4, (fx - 1) % 4);
    if col == 3 {
        return Some(false);
    }
    let digit = (text.as_bytes()[ch] - b'0') as usize;
    Some(DIGITS[digit][fy - 1] >> (2 - col) & 1 == 1)
}

/// What [`render_tiles`] draws: `count` tiles of `tw × th` cells from `cells`, separated by
/// `gap`-pixel separators, with or without labels.
struct Tiles<'a> {
    cells: &'a [[f32; 4]],
    tw: usize,
    th: usize,
    count: usize,
    gap: usize,
    labels: bool,
}

/// Draws tiles: tile k's pixel shows the cell `at(k, x, y)` of the cell (x, y) ∈ [0, tw) ×
/// [0, th) under its centre.
fn render_tiles(
    w: usize,
    h: usize,
    t: &Tiles<'_>,
    bg: [f32; 3],
    at: impl Fn(usize, usize, usize) -> usize + Sync,
) -> Vec<f32> {
    let Tiles {
        cells,
        tw,
        th,
        count,
        gap,
        labels,
    } = *t;
    let lay = slice_layout(w, h, count, tw, th, gap);
    let (mw, mh) = (
        lay.cols * lay.tile_w + (lay.cols + 1) * gap,
        lay.rows * lay.tile_h + (lay.rows + 1) * gap,
    );
    let ls = (lay.tile_h / 40).clamp(1, 4);
    let mut img = vec![0f32; w * h * 4];
    img.par_chunks_mut(w * 4).enumerate().for_each(|(py, row)| {
        for px in 0..w {
            let mut v = [bg[0], bg[1], bg[2], 0.0];
            let (ox, oy) = lay.origin;
            if px >= ox && py >= oy && px < ox + mw && py < oy + mh {
                let (mx, my) = (px - ox, py - oy);
                let pitch_x = lay.tile_w + gap;
                let pitch_y = lay.tile_h + gap;
                let (c, xin) = (
                    mx.saturating_sub(gap) / pitch_x,
                    mx.saturating_sub(gap) % pitch_x,
                );
                let (r, yin) = (
                    my.saturating_sub(gap) / pitch_y,
                    my.saturating_sub(gap) % pitch_y,
                );
                let on_sep = mx < gap || my < gap || xin >= lay.tile_w || yin >= lay.tile_h;
                let k = r * lay.cols + c;
                if on_sep {
                    v = [SEPARATOR[0], SEPARATOR[1], SEPARATOR[2], 1.0];
                } else if k < count {
                    let label = if labels
                        && lay.tile_w >= (k.to_string().len() * 4 + 3) * ls
                        && lay.tile_h >= 9 * ls
                    {
                        label_pixel(k, ls, xin, yin)
                    } else {
                        None
                    };
                    v = match label {
                        Some(true) => [1.0, 1.0, 1.0, 1.0],
                        Some(false) => [0.0, 0.0, 0.0, 1.0],
                        None => {
                            let cx = (((xin as f64 + 0.5) * tw as f64 / lay.tile_w as f64)
                                as usize)
                                .min(tw - 1);
                            let cy = (((yin as f64 + 0.5) * th as f64 / lay.tile_h as f64)
                                as usize)
                                .min(th - 1);
                            over(cells[at(k, cx, cy)], bg)
                        }
                    };
                }
            }
            row[px * 4..px * 4 + 4].copy_from_slice(&v);
        }
    });
    img
}

/// The slice montage of a 3D volume. Tile of slice k, at pixel (x, y) of its cell grid:
/// axis 0 → volume[k, y, x] (rows, columns); axis 1 → volume[y, k, x] (slices down, columns
/// across); axis 2 → volume[x, y, k] (rows down, slices across). So image rows stay rows and
/// columns stay columns whenever they remain.
fn render_slices(vol: &Volume, o: &CompositeOptions, bg: [f32; 3]) -> Vec<f32> {
    let [nx, ny, nz] = [vol.shape[2], vol.shape[1], vol.shape[0]];
    let (count, tw, th) = match o.axis {
        0 => (nz, nx, ny),
        1 => (ny, nx, nz),
        _ => (nx, nz, ny),
    };
    let idx = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
    let axis = o.axis;
    let at = move |k: usize, x: usize, y: usize| match axis {
        0 => idx(x, y, k),
        1 => idx(x, k, y),
        _ => idx(k, y, x),
    };
    let (w, h) = o.size;
    let tiles = Tiles {
        cells: &vol.cells,
        tw,
        th,
        count,
        gap: 1,
        labels: o.labels,
    };
    render_tiles(w, h, &tiles, bg, at)
}

/// A 1D retina as a strip: full width, `strip_height` rows (clipped to h) centred vertically.
fn render_strip(
    cells: &[[f32; 4]],
    w: usize,
    h: usize,
    strip_height: usize,
    bg: [f32; 3],
) -> Vec<f32> {
    let sh = strip_height.min(h);
    let top = (h - sh) / 2;
    let r = cells.len();
    let mut img = vec![0f32; w * h * 4];
    img.par_chunks_mut(w * 4).enumerate().for_each(|(py, row)| {
        for px in 0..w {
            let v = if py >= top && py < top + sh {
                let i = (((px as f64 + 0.5) * r as f64 / w as f64) as usize).min(r - 1);
                over(cells[i], bg)
            } else {
                [bg[0], bg[1], bg[2], 0.0]
            };
            row[px * 4..px * 4 + 4].copy_from_slice(&v);
        }
    });
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::rng;
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

    fn ortho(mode: CompositeMode, az: f64, el: f64, size: (usize, usize)) -> CompositeOptions {
        CompositeOptions {
            mode,
            azimuth: az,
            elevation: el,
            projection: Projection::Orthographic,
            size,
            ..Default::default()
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
        for mode in [CompositeMode::FirstHit, CompositeMode::Mip] {
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
                        ..Default::default()
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
                    ..Default::default()
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
            ..Default::default()
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
        assert_eq!(img.pixel(tx, ty), [0.0, 0.0, 0.0, 1.0]); // plate
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
    fn empty_space_skipping_changes_nothing() {
        // Sparse random blobs; the same picture with every block marked occupied.
        let shape = [37usize, 29, 45];
        let mut r = rng(21);
        let centres: Vec<[f64; 3]> = (0..6)
            .map(|_| {
                [
                    r.random_range(0.0..37.0),
                    r.random_range(0.0..29.0),
                    r.random_range(0.0..45.0),
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
        let cells = prepare(&rgba, None, 37 * 29 * 45, &CompositeOptions::default());
        let vol = Volume {
            shape: shape.to_vec(),
            cells,
        };
        let grid = Grid::new(&vol);
        assert!(
            grid.occupied.iter().any(|&b| !b),
            "the test needs empty blocks"
        );
        let mut full = Grid::new(&vol);
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
                ..Default::default()
            };
            let a = render_3d(&grid, mode, &o, [0.0; 3]);
            let b = render_3d(&full, mode, &o, [0.0; 3]);
            let differ = a
                .chunks(4)
                .zip(b.chunks(4))
                .filter(|(x, y)| x.iter().zip(y.iter()).any(|(u, v)| (u - v).abs() > 1e-6))
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
                        ..Default::default()
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
            ..Default::default()
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
            ..Default::default()
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
            ..Default::default()
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
        let ok = CompositeOptions::default();
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
            let mut o = CompositeOptions::default();
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
            ..Default::default()
        };
        assert!(composite(&rgba, None, &shape, &o).is_ok());
        // Stages: N − 4 pairs, f > 0, d beyond the box.
        let shape5 = [2usize, 2, 2, 2];
        let rgba5 = vec![0f32; 64];
        let o = CompositeOptions {
            stages: vec![(1.0, 3.0), (1.0, 3.0)],
            ..Default::default()
        };
        assert_eq!(err(&rgba5, None, &shape5, &o).0, "stages");
        let o = CompositeOptions {
            stages: vec![(1.0, 0.5)],
            ..Default::default()
        };
        assert_eq!(err(&rgba5, None, &shape5, &o).0, "stages[0]");
        let o = CompositeOptions {
            stages: vec![(2.0, 3.0)],
            ..Default::default()
        };
        assert!(composite(&rgba5, None, &shape5, &o).is_ok());
        assert_eq!(CompositeMode::parse("mip").unwrap(), CompositeMode::Mip);
        assert_eq!(arg_of(CompositeMode::parse("mpi").unwrap_err()).0, "mode");
    }
}
