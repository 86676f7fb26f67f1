//! The options of [`composite`](super::composite): one struct that is also a scene's
//! `[composite]` table, the dict the Python bindings accept and what the command line's flags
//! set. Each field is declared once below, with its type and default; every range check is in
//! [`CompositeOptions::validate`] and [`CompositeOptions::validate_for`], so a bad value gets
//! the same message whichever way it arrives (a TOML file locates it, `file:line:col:
//! composite.opacity: must be ≥ 0, got -1`; a keyword argument names it, `opacity: must be ≥ 0,
//! got -1`).
//!
//! These two are equivalent:
//!
//! ```toml
//! [composite]
//! mode = "slices"
//! size = [800, 600]
//! ```
//!
//! ```python
//! ndtrace.composite(retina, mode="slices", size=(800, 600))
//! ```

use super::aids::{Cutaway, ViewLayout};
use super::stages::half_lengths;
use crate::camera::Projection;
use crate::NdError;
use serde::de::{self, DeserializeSeed, MapAccess, Visitor};
use serde::ser::SerializeStruct;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// How a 3D volume (the retina of a 4D scene, or the result of the recursive projection for
/// N ≥ 5) is turned into a picture. Ignored for N ≤ 3. Named in snake case (`"first_hit"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CompositeMode {
    /// Front-to-back emission–absorption along each pixel ray, sampling the premultiplied RGBA
    /// trilinearly every [`CompositeOptions::step`] cells. A cell's alpha is its opacity over
    /// one cell length: a sample with alpha a over a step of Δ cells has opacity 1 − (1 − a)^Δ
    /// and emits its premultiplied colour times (1 − (1 − a)^Δ) / a, so the picture does not
    /// depend on the step (a uniform slab of alpha a and thickness L cells has opacity exactly
    /// 1 − (1 − a)^L). Rays stop once the transmittance falls below 1e-4.
    Volume,
    /// Maximum intensity projection: each ray shows, unchanged, the cell it crosses whose
    /// premultiplied colour has the largest Rec. 709 luminance (ties: the larger alpha, then
    /// the nearer cell). Cells are crossed exactly (voxel traversal, no interpolation).
    Mip,
    /// The nearest point where the trilinearly interpolated alpha reaches ½ (times `opacity`,
    /// at most 1), found every [`CompositeOptions::step`] cells and refined by bisection, shown
    /// opaque in the interpolated (un-premultiplied) colour there: a smooth iso-surface of the
    /// coverage, not a staircase of cells.
    FirstHit,
    /// A montage of the 2D slices of the volume along [`CompositeOptions::axis`]; see
    /// [`slice_layout`](super::slice_layout) for where slice k goes.
    Slices,
    /// Nearly clear cells in their 4D-lit colour, with opacity where the retina has structure —
    /// creases between cells whose 4D normals differ, occlusion contours, silhouettes seen
    /// edge-on — and the objects' feature edges drawn over it, visible ones solid and hidden
    /// ones dashed (see [`illustrative`](super::illustrative) and [`overlay`](super::overlay)).
    /// The default: a tesseract reads as a cube inside a cube joined by six frusta.
    #[default]
    Illustrative,
}

/// How the illustrative mode draws the pieces of feature edges hidden in N-D.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HiddenEdges {
    /// Dashed, thinner and fainter than the visible ones (the default).
    #[default]
    Dashed,
    /// Solid, faint.
    Faint,
    /// Not drawn.
    None,
}

/// Where a picture's detail comes from (N = 4; see [`composite`](super) and
/// [`picture`](super::picture)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Detail {
    /// At the picture's resolution: a retina that comes with the scene it was traced from
    /// (`ndtrace.trace`) has its first-hit, volume and illustrative views and its sections
    /// drawn from the scene's exact structure — the silhouettes, creases and occlusion
    /// contours of its meshes and its surfaces, projected into the retina — and from 4D rays
    /// cast where the picture asks (the default). Without a scene, as `Retina`.
    #[default]
    Scene,
    /// From the retina's cells alone (trilinear samples of the grid): the maximum-intensity
    /// and slice pictures, N ≠ 4, a retina without its scene (an array, a file), and the
    /// viewer's drafts.
    Retina,
}

/// A picture aid that is shown when it helps (`"auto"`) or forced on (`true`) or off
/// (`false`): a table writes it as `"auto"`, `true` or `false`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Toggle {
    /// Shown when it says something (see the option).
    #[default]
    Auto,
    /// Always shown.
    On,
    /// Never shown.
    Off,
}

impl Toggle {
    /// Whether the aid is shown, `auto` standing for `when_auto`.
    pub fn resolve(self, when_auto: bool) -> bool {
        match self {
            Toggle::Auto => when_auto,
            Toggle::On => true,
            Toggle::Off => false,
        }
    }
}

impl Serialize for Toggle {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Toggle::Auto => serializer.serialize_str("auto"),
            Toggle::On => serializer.serialize_bool(true),
            Toggle::Off => serializer.serialize_bool(false),
        }
    }
}

impl<'de> Deserialize<'de> for Toggle {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Toggle;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("\"auto\", true or false")
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Toggle, E> {
                Ok(if v { Toggle::On } else { Toggle::Off })
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Toggle, E> {
                match v {
                    "auto" => Ok(Toggle::Auto),
                    _ => Err(E::custom(format!(
                        "expected \"auto\", true or false, got \"{v}\""
                    ))),
                }
            }
        }
        deserializer.deserialize_any(V)
    }
}

/// What colours the feature edges of the illustrative mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EdgeColorBy {
    /// Parallel edges share a colour of the object's `material.palette` (the tesseract's 32
    /// edges in 4 colours, one per axis direction).
    Direction,
    /// The course's depth cueing (the default): edges thicker and stronger near the N-D eye,
    /// thinner and fainter far from it, over the depth range of the edges drawn.
    #[default]
    Depth,
    /// One colour and width ([`CompositeOptions::edge_color`]).
    None,
}

/// Default camera distance, in half-diagonals of the retina cube.
pub const DEFAULT_DISTANCE: f64 = 4.0;
/// Largest number of pixels of a picture.
pub const MAX_PIXELS: usize = 1 << 28;
/// Most rays per pixel of the anti-aliasing ([`CompositeOptions::samples`]).
pub const MAX_SAMPLES: usize = 256;
/// Rays per pixel at edges when [`CompositeOptions::samples`] is 0.
pub const DEFAULT_SAMPLES: usize = 16;
/// Most frames of a turntable.
pub const MAX_TURNTABLE_FRAMES: usize = 3600;
/// Most characters of a [`CompositeOptions::title`].
pub const MAX_TITLE_CHARS: usize = 200;

/// Declares [`CompositeOptions`] from one list of `field: Type = default` entries: the struct,
/// its [`Default`], [`CompositeOptions::KEYS`] and its serde form (a table with one optional
/// key per field, unknown keys refused, as `#[serde(default, deny_unknown_fields)]` would
/// derive, but remembering which keys were given; see [`GivenKeys`]).
macro_rules! composite_options {
    (
        $(#[$meta:meta])*
        pub struct $Name:ident {
            $( $(#[$field_meta:meta])* $field:ident : $ty:ty = $default:expr, )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, PartialEq)]
        pub struct $Name {
            $( $(#[$field_meta])* pub $field: $ty, )*
            /// The keys of the table or dict these options were read from (none for options
            /// built in code). Serializing writes these keys and every value that differs from
            /// its default, so a scene's `[composite]` table is written back as it was given.
            pub given: GivenKeys,
        }

        impl Default for $Name {
            fn default() -> Self {
                Self { $( $field: $default, )* given: GivenKeys::NONE }
            }
        }

        impl $Name {
            /// The keys of a `[composite]` table (the fields, in the order they are written).
            pub const KEYS: &'static [&'static str] = &[$( stringify!($field) ),*];
        }

        impl Serialize for $Name {
            fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                let default = Self::default();
                let written =
                    [$( self.given.has(stringify!($field)) || self.$field != default.$field ),*];
                let count = written.iter().filter(|&&w| w).count();
                let mut table = serializer.serialize_struct(stringify!($Name), count)?;
                let mut written = written.into_iter();
                $(
                    if written.next() == Some(true) {
                        table.serialize_field(stringify!($field), &self.$field)?;
                    } else {
                        table.skip_field(stringify!($field))?;
                    }
                )*
                table.end()
            }
        }

        impl<'de> Deserialize<'de> for $Name {
            fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                struct Table;
                impl<'de> Visitor<'de> for Table {
                    type Value = $Name;
                    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                        f.write_str("a table of composite options")
                    }
                    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<$Name, A::Error> {
                        let mut options = $Name::default();
                        while let Some(key) = map.next_key_seed(Key)? {
                            if options.given.has(key) {
                                return Err(de::Error::duplicate_field(key));
                            }
                            options.given.insert(key);
                            match key {
                                $( stringify!($field) => options.$field = map.next_value()?, )*
                                other => return Err(de::Error::unknown_field(other, $Name::KEYS)),
                            }
                        }
                        Ok(options)
                    }
                }
                deserializer.deserialize_struct(stringify!($Name), $Name::KEYS, Table)
            }
        }
    };
}

composite_options! {
    /// Options of [`composite`](super::composite): a scene's `[composite]` table, the
    /// `options` dict of the bindings, the keyword arguments of `ndtrace.composite`. Every
    /// field has a documented default ([`Default`]); [`validate`](Self::validate) and
    /// [`validate_for`](Self::validate_for) state their ranges.
    pub struct CompositeOptions {
        /// How a 3D volume becomes a picture. Default [`CompositeMode::Illustrative`].
        mode: CompositeMode = CompositeMode::Illustrative,
        /// Degrees; rotation of the eye about the vertical (row) axis. Default 30.
        azimuth: f64 = 30.0,
        /// Degrees; height of the eye above the horizontal plane. Default 20.
        elevation: f64 = 20.0,
        /// Distance from the cube's centre to the eye, in units of the cube's half-diagonal r
        /// (the radius of its bounding sphere). Perspective: must exceed 1 (the eye outside the
        /// bounding sphere); the field of view is the one in which the bounding sphere just
        /// fills the shorter side of the picture (tan(fov/2) = 1/√(distance² − 1)), so the
        /// object keeps its size as the camera orbits and a larger distance only weakens the
        /// perspective. Orthographic: any positive value; the picture does not depend on it
        /// (the view's shorter side spans the bounding sphere's diameter 2r). Default
        /// [`DEFAULT_DISTANCE`] = 4.
        distance: f64 = DEFAULT_DISTANCE,
        /// Magnification of the 3D view (both projections): 2 shows half the width. Must be
        /// positive. Default 1.
        zoom: f64 = 1.0,
        /// Of the 3D camera and of every recursive stage. Default perspective.
        projection: Projection = Projection::Perspective,
        /// Picture size (W, H) in pixels, each ≥ 1, at most [`MAX_PIXELS`] in all. Default
        /// (512, 512).
        size: (usize, usize) = (512, 512),
        /// Scales every cell's alpha (and its premultiplied colour with it, clamped so
        /// alpha ≤ 1) before anything else, so inner structure shows through: 0.05 makes a
        /// solid traced body a translucent cloud. Must be ≥ 0. Default 1.
        opacity: f64 = 1.0,
        /// Sample spacing of the volume mode, in cells (0.01 ..= 4). Default 0.5.
        step: f64 = 0.5,
        /// For N ≥ 4 (volume, first-hit and illustrative views; mip traces every pixel):
        /// rays are cast at most this many to a cell's width where the cells look smallest —
        /// every s-th pixel, s = ⌊pixels per cell / rays_per_cell⌋ ≤ 16 — and the pixels
        /// between them are traced where the picture changes and interpolated bilinearly
        /// where it is smooth (see `composite::volume::render_view`). 0 traces a ray through
        /// every pixel. In 0 ..= 64. Default 1.
        rays_per_cell: usize = 1,
        /// Strength in [0, 1] of depth cueing; 0 turns it off (default). Every hit cell's
        /// colour is multiplied by `1 − s + s · tint(t)` where t ∈ [0, 1] is its depth
        /// (distance from the N-D eye, the `depth` array) normalized over the retina's finite
        /// depths, and tint runs linearly from warm [`NEAR_TINT`](super::NEAR_TINT) (nearest)
        /// to cool [`FAR_TINT`](super::FAR_TINT) (farthest), so near and far along the hidden
        /// axis read apart. Needs `depth`.
        depth_cue: f64 = 0.0,
        /// For [`CompositeMode::Slices`]: the numpy axis of the 3D volume to slice along
        /// (0 = slices, 1 = rows, 2 = columns). Default 0.
        axis: usize = 0,
        /// Opaque background colour, linear RGB (finite). Default black.
        background: [f64; 3] = [0.0; 3],
        /// Per-stage perspective parameters (f_k, d_k) of the recursive projection for N ≥ 5,
        /// ordered (f_{N−1}, d_{N−1}), …, (f_4, d_4): `stages[0]` collapses the leading numpy
        /// axis of the (N−1)-D retina. Either empty (every stage at its default) or exactly
        /// N − 4 pairs of finite numbers.
        ///
        /// A stage places its k-D input with its centre at the origin and cells of side
        /// `c = 2 / max(R)` (so its longest axis spans [−1, 1]; a_k is the half-length of the
        /// collapsed axis), puts the eye at x_k = −d_k on the collapsed axis (index 0 nearest)
        /// and maps a point to the (k−1)-D film by x_j ↦ x_j · f_k / (d_k + x_k), the course's
        /// "divide by (d − x)/f". Output cells have the input's grid; each output cell's ray is
        /// sampled (multilinearly, zero outside the box) at every input slice, front to back,
        /// with the step correction of the volume mode for its oblique path length. Requires
        /// f_k > 0 and d_k > a_k. Default d_k = [`super::DEFAULT_STAGE_DISTANCE`] = 3 and
        /// f_k = d_k − a_k + c/2, which maps the nearest slice (index 0, centred at
        /// x_k = −a_k + c/2) one-to-one onto the film; farther slices appear smaller, toward
        /// the centre. With orthographic projection every stage is a parallel projection and
        /// (f, d) are unused.
        stages: Vec<(f64, f64)> = Vec::new(),
        /// For N = 2: height in pixels of the strip (≥ 1; clipped to the picture height).
        /// Default 32.
        strip_height: usize = 32,
        /// For [`CompositeMode::Slices`]: draw each slice's index in the top-left corner of its
        /// tile (when the tile is large enough). Default true.
        labels: bool = true,
        /// For N ≥ 4: the compositing camera looks at the centre of the box of the retina's
        /// occupied cells (alpha > 0), and `distance` counts in that box's half-diagonals, so
        /// the object fills the picture whatever the retina's field of view. False: the whole
        /// retina box. Default true.
        fit: bool = true,
        /// For the illustrative mode: neighbouring cells whose unit normals' lines are more
        /// than this many degrees apart show a crease; also the crease angle of the feature
        /// edges drawn ([`crate::mesh::feature_edges`]). In [0, 90]. Default 20.
        crease_angle: f64 = 20.0,
        /// For the illustrative mode: draw the objects' feature edges over the picture when the
        /// retina comes with them (a retina traced from a scene). Default true.
        edges: bool = true,
        /// Width in pixels of visible edges (hidden ones are 0.6× as wide); 0 picks one that
        /// reads at the picture's size, max(1, min(W, H)/300). In [0, 64]. Default 0.
        edge_width: f64 = 0.0,
        /// Linear RGB of the edges; none (the default) picks near-white on a dark background,
        /// near-black on a light one. With `depth_cue` > 0 edges are also tinted by their N-D
        /// depth, warm (near) to cool (far).
        edge_color: Option<[f64; 3]> = None,
        /// How pieces of edges hidden in N-D are drawn: `"dashed"` (default), `"faint"` or
        /// `"none"`.
        hidden_edges: HiddenEdges = HiddenEdges::Dashed,
        /// For N ≥ 4: one view (`"single"`, the default), `"sections"` (the view and three
        /// orthogonal sections through [`section`](Self::section)) or `"stereo"` (a side-by-side
        /// pair); see [`ViewLayout`].
        layout: ViewLayout = ViewLayout::Single,
        /// For the sections layout: the world point (volume centred, longest side spanning
        /// [−1, 1]; x columns, y up, z slices) the three sections pass through. Default the
        /// centre.
        section: [f64; 3] = [0.0; 3],
        /// For the stereo layout: degrees of azimuth between the two eyes, in [0, 30].
        /// Default 6.
        stereo_angle: f64 = 6.0,
        /// A turntable of this many frames (1 ..= [`MAX_TURNTABLE_FRAMES`]): frame k seen from
        /// azimuth + 360°·k/frames, the retina traced once; `ndtrace.composite` then returns
        /// the frames and `-o orbit.gif` animates them. 0 (the default): one picture.
        turntable: usize = 0,
        /// A colour bar (and keys) along the bottom of the picture: the colormap's ramp with
        /// its name, range, ticks and isoline levels; for `material.color_by` and
        /// [`edge_color_by`](Self::edge_color_by) `"direction"` a key of the colours used.
        /// `"auto"` (the default) shows it when an object has a colormap, a `color_by` or a
        /// `label`, or the edges are coloured by direction; `true`/`false` force it. The core
        /// reserves the strip ([`annotate`](super::annotate)); `ndtrace.composite` draws it.
        legend: Toggle = Toggle::Auto,
        /// The N-D axes glyph in the lower-left corner of the view: the N world axes (or the
        /// columns of [`axes_frame`](Self::axes_frame)) as arrows through the N-D camera, the
        /// stages and the compositing camera, each shortened and dimmed by how far it points
        /// away from the N-D eye. `"auto"` (the default) shows it for N ≥ 4.
        axes: Toggle = Toggle::Auto,
        /// The frame whose axes the glyph shows: N rows of N numbers, its columns the axes in
        /// world coordinates (the viewer sets its rotation here, so the glyph turns with the
        /// drag). Default none: the world axes.
        axes_frame: Option<Vec<Vec<f64>>> = None,
        /// A caption line above the picture. Default none.
        title: Option<String> = None,
        /// How the feature edges are coloured: `"depth"` (the default: the course's depth
        /// cueing), `"direction"` (parallel edges share a palette colour) or `"none"`.
        edge_color_by: EdgeColorBy = EdgeColorBy::Depth,
        /// For N ≥ 4: a region of the 3D volume removed so its inside shows: a table with
        /// `shape = "half_space"` (`normal`, `offset`), `"sphere"` (`center`, `radius`) or
        /// `"box"` (`min`, `max`), in world coordinates (see [`Cutaway`]). Default none.
        cutaway: Option<Cutaway> = None,
        /// For N ≥ 4: draw each occupied cell (coverage ≥ ½) as a small opaque cube of side
        /// `size` cells (0 < size ≤ 1), the course's "break into tiny cubes: leave a little
        /// space instead of transparency", instead of the mode's rendering (see
        /// [`Cubes`](super::Cubes)). Default none.
        cubes: Option<super::Cubes> = None,
        /// Anti-aliasing: rays per pixel where the picture has an edge — a silhouette, a
        /// sheet's border, a step of colour or coverage between neighbouring pixels — in a
        /// stratified √K × √K pattern (K rounded down to a square); one ray through the centre
        /// elsewhere. 0 (the default) is automatic: 16. 1 turns anti-aliasing off. In
        /// 0 ..= 256.
        samples: usize = 0,
        /// Where the picture's detail comes from: `"scene"` (the default: at the picture's
        /// resolution, from the scene a traced retina comes with) or `"retina"` (the retina's
        /// cells alone); see [`Detail`].
        detail: Detail = Detail::Scene,
    }
}

/// Which keys of [`CompositeOptions::KEYS`] a table gave (see [`CompositeOptions::given`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GivenKeys(u64);

impl GivenKeys {
    /// No key: options built in code.
    pub const NONE: GivenKeys = GivenKeys(0);
    /// Every key (serializing then writes every field, e.g. to list the defaults).
    pub const ALL: GivenKeys = GivenKeys(u64::MAX >> (64 - CompositeOptions::KEYS.len()));

    fn bit(key: &str) -> u64 {
        CompositeOptions::KEYS
            .iter()
            .position(|k| *k == key)
            .map_or(0, |i| 1 << i)
    }

    /// Whether `key` was given.
    pub fn has(self, key: &str) -> bool {
        self.0 & Self::bit(key) != 0
    }

    fn insert(&mut self, key: &str) {
        self.0 |= Self::bit(key);
    }
}

/// A table key: one of [`CompositeOptions::KEYS`], or serde's "unknown field" error (which
/// the scene loader turns into `unknown key "x" (did you mean "y"?)`).
struct Key;

impl<'de> DeserializeSeed<'de> for Key {
    type Value = &'static str;
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<&'static str, D::Error> {
        deserializer.deserialize_identifier(self)
    }
}

impl Visitor<'_> for Key {
    type Value = &'static str;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("the name of a composite option")
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<&'static str, E> {
        CompositeOptions::KEYS
            .iter()
            .find(|k| **k == v)
            .copied()
            .ok_or_else(|| E::unknown_field(v, CompositeOptions::KEYS))
    }
}

/// A bad option: its key path (`opacity`, `background[1]`, `stages[0]`) and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct OptionError {
    /// The key, with an index for an element of a list.
    pub key: String,
    /// What is wrong, with the allowed range.
    pub message: String,
}

impl From<OptionError> for NdError {
    fn from(e: OptionError) -> NdError {
        NdError::Value {
            arg: e.key,
            message: e.message,
        }
    }
}

fn bad(key: &str, message: impl Into<String>) -> OptionError {
    OptionError {
        key: key.into(),
        message: message.into(),
    }
}

/// `v` if it is finite and within float32's range (the compositor works in f32: a larger
/// value would become infinite there and the picture NaN).
fn finite(key: &str, v: f64) -> Result<f64, OptionError> {
    if !v.is_finite() {
        Err(bad(key, format!("must be finite, got {v}")))
    } else if v.abs() > f32::MAX as f64 {
        Err(bad(
            key,
            format!(
                "{v} overflows float32 (at most {:e} in magnitude)",
                f32::MAX
            ),
        ))
    } else {
        Ok(v)
    }
}

impl CompositeOptions {
    /// The rays per pixel of the anti-aliasing at an edge: [`samples`](Self::samples) (0:
    /// [`DEFAULT_SAMPLES`]) rounded down to a square k², and k.
    pub fn edge_samples(&self) -> (usize, usize) {
        let want = if self.samples == 0 {
            DEFAULT_SAMPLES
        } else {
            self.samples
        };
        let k = (want as f64).sqrt().floor().max(1.0) as usize;
        (k * k, k)
    }

    /// These options with every key marked as given, so that serializing writes every field.
    pub fn with_every_key(self) -> Self {
        CompositeOptions {
            given: GivenKeys::ALL,
            ..self
        }
    }

    /// Checks every value on its own, without the retina: what a scene's `[composite]` table
    /// or a command-line flag can be checked for before anything is traced.
    pub fn validate(&self) -> Result<(), OptionError> {
        // Naming every field: a new option does not compile until it is considered here.
        let CompositeOptions {
            mode: _,
            azimuth,
            elevation,
            distance,
            zoom,
            projection,
            size: (w, h),
            opacity,
            step,
            rays_per_cell,
            samples,
            detail: _,
            depth_cue,
            axis: _,
            background,
            stages,
            strip_height,
            labels: _,
            fit: _,
            crease_angle,
            edges: _,
            edge_width,
            edge_color,
            hidden_edges: _,
            layout: _,
            section,
            stereo_angle,
            cutaway,
            turntable,
            legend: _,
            axes: _,
            axes_frame,
            title,
            edge_color_by: _,
            cubes,
            given: _,
        } = self;
        if let Some(c) = cubes {
            if !(c.size > 0.0 && c.size <= 1.0) {
                return Err(bad(
                    "cubes.size",
                    format!("must be in (0, 1] (a fraction of a cell), got {}", c.size),
                ));
            }
        }
        if let Some(t) = title {
            if t.chars().count() > MAX_TITLE_CHARS || t.contains(['\n', '\r']) {
                return Err(bad(
                    "title",
                    format!("must be one line of at most {MAX_TITLE_CHARS} characters"),
                ));
            }
        }
        if let Some(f) = axes_frame {
            for (i, row) in f.iter().enumerate() {
                for (j, &v) in row.iter().enumerate() {
                    finite(&format!("axes_frame[{i}][{j}]"), v)?;
                }
            }
        }
        for (k, &v) in section.iter().enumerate() {
            finite(&format!("section[{k}]"), v)?;
        }
        if !(0.0..=30.0).contains(&finite("stereo_angle", *stereo_angle)?) {
            return Err(bad(
                "stereo_angle",
                format!("must be in [0, 30] degrees, got {stereo_angle}"),
            ));
        }
        if let Some(c) = cutaway {
            c.validate("cutaway")
                .map_err(|(key, message)| bad(&key, message))?;
        }
        if *turntable > MAX_TURNTABLE_FRAMES {
            return Err(bad(
                "turntable",
                format!(
                    "must be 0 (one picture) to {MAX_TURNTABLE_FRAMES} frames, got {turntable}"
                ),
            ));
        }
        if !(0.0..=90.0).contains(&finite("crease_angle", *crease_angle)?) {
            return Err(bad(
                "crease_angle",
                format!("must be in [0, 90] degrees, got {crease_angle}"),
            ));
        }
        if !(0.0..=64.0).contains(&finite("edge_width", *edge_width)?) {
            return Err(bad(
                "edge_width",
                format!("must be in [0, 64] pixels (0: automatic), got {edge_width}"),
            ));
        }
        if let Some(c) = edge_color {
            for (k, &v) in c.iter().enumerate() {
                if !(finite(&format!("edge_color[{k}]"), v)? >= 0.0) {
                    return Err(bad(
                        &format!("edge_color[{k}]"),
                        format!("must be ≥ 0, got {v}"),
                    ));
                }
            }
        }
        if *strip_height == 0 {
            return Err(bad("strip_height", "must be at least 1"));
        }
        if *w == 0 || *h == 0 {
            return Err(bad(
                "size",
                format!("width and height must be positive, got ({w}, {h})"),
            ));
        }
        if w.checked_mul(*h).is_none_or(|p| p > MAX_PIXELS) {
            return Err(bad(
                "size",
                format!("({w}, {h}) exceeds {MAX_PIXELS} pixels"),
            ));
        }
        finite("azimuth", *azimuth)?;
        finite("elevation", *elevation)?;
        let dist = finite("distance", *distance)?;
        if *projection == Projection::Perspective && !(dist > 1.0) {
            return Err(bad(
                "distance",
                format!("must exceed 1 (half-diagonals of the retina cube) for a perspective view, got {dist}"),
            ));
        }
        if !(dist > 0.0) {
            return Err(bad("distance", format!("must be positive, got {dist}")));
        }
        if !(finite("zoom", *zoom)? > 0.0) {
            return Err(bad("zoom", format!("must be positive, got {zoom}")));
        }
        if !(finite("opacity", *opacity)? >= 0.0) {
            return Err(bad("opacity", format!("must be ≥ 0, got {opacity}")));
        }
        if !(0.01..=4.0).contains(&finite("step", *step)?) {
            return Err(bad(
                "step",
                format!("must be in [0.01, 4] cells, got {step}"),
            ));
        }
        if *rays_per_cell > 64 {
            return Err(bad(
                "rays_per_cell",
                format!("must be in 0 ..= 64 (0: a ray through every pixel), got {rays_per_cell}"),
            ));
        }
        if *samples > MAX_SAMPLES {
            return Err(bad(
                "samples",
                format!(
                    "must be in 0 ..= {MAX_SAMPLES} rays per pixel (0: automatic), got {samples}"
                ),
            ));
        }
        let cue = finite("depth_cue", *depth_cue)?;
        if !(0.0..=1.0).contains(&cue) {
            return Err(bad("depth_cue", format!("must be in [0, 1], got {cue}")));
        }
        for (k, &b) in background.iter().enumerate() {
            finite(&format!("background[{k}]"), b)?;
        }
        for (i, &(f, d)) in stages.iter().enumerate() {
            let key = format!("stages[{i}]");
            finite(&key, f)?;
            finite(&key, d)?;
        }
        Ok(())
    }

    /// [`validate`](Self::validate), then the checks that depend on the retina: its numpy
    /// `shape` (without the channel axis; N = `shape.len()` + 1) and whether it has depth.
    pub fn validate_for(&self, shape: &[usize], has_depth: bool) -> Result<(), OptionError> {
        self.validate()?;
        let m = shape.len();
        if self.depth_cue > 0.0 && !has_depth {
            return Err(bad(
                "depth_cue",
                "needs the retina's depth array (e.g. a traced ndtrace.Retina)",
            ));
        }
        if self.mode == CompositeMode::Slices && m >= 3 && self.axis > 2 {
            return Err(bad(
                "axis",
                format!(
                    "must be 0, 1 or 2 (an axis of the 3D volume), got {}",
                    self.axis
                ),
            ));
        }
        if let Some(f) = &self.axes_frame {
            let n = m + 1;
            if f.len() != n || f.iter().any(|row| row.len() != n) {
                return Err(bad(
                    "axes_frame",
                    format!("expected {n} rows of {n} numbers (an N×N matrix for N = {n})"),
                ));
            }
        }
        if self.cubes.is_some() && m < 3 {
            return Err(bad(
                "cubes",
                "draws the cells of a 3D (or larger) retina, N ≥ 4",
            ));
        }
        // Stages: N − 4 = m − 3 of them for N ≥ 5.
        let n_stages = m.saturating_sub(3);
        if !self.stages.is_empty() && self.stages.len() != n_stages {
            return Err(bad(
                "stages",
                format!(
                    "expected {n_stages} (f, d) pairs for a {m}-D retina (one per axis collapsed down to 3D) \
                     or none for the defaults, got {}",
                    self.stages.len()
                ),
            ));
        }
        if self.projection == Projection::Perspective {
            for (i, &(f, d)) in self.stages.iter().enumerate() {
                let a = half_lengths(&shape[i..])[0];
                if !(f > 0.0) || !(d > a) {
                    return Err(bad(
                        &format!("stages[{i}]"),
                        format!(
                            "(f, d) = ({f}, {d}): need f > 0 and d > {a} (the eye outside the box, \
                             whose collapsed axis spans ±{a})"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
