//! The options of [`composite`](super::composite), their defaults and their checks.

use super::stages::half_lengths;
use crate::scene::desc::Projection as SceneProjection;
use crate::{NdError, NdResult};

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
    /// [`slice_layout`](super::slice_layout) for where slice k goes.
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

/// Options of [`composite`](super::composite). Every field has a documented default
/// ([`Default`]).
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
    /// linearly from warm [`NEAR_TINT`](super::NEAR_TINT) (nearest) to cool
    /// [`FAR_TINT`](super::FAR_TINT) (farthest), so near and far along the hidden axis read
    /// apart. Needs `depth`.
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

/// Largest number of pixels of a picture.
pub const MAX_PIXELS: usize = 1 << 28;

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
pub(super) fn validate(
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
