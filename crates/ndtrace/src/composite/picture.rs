//! Pictures at the picture's resolution ([`Detail::Scene`](super::Detail::Scene), N = 4): the
//! first-hit, volume and illustrative views and the sections of a retina that comes with the
//! scene it was traced from ([`SceneProbe`]).
//!
//! The retina's grid decides nothing the picture can see sharply. Each picture ray meets the
//! scene's sheets ([`super::sheets`]) at exact points; between two crossings the ray is inside
//! the retina's covered region or outside it — from the layer count when the scene allows it
//! ([`Structure::counted`]), else from one 4D ray between them ([`SceneProbe::covered`]) —
//! and the cutaway is removed from it exactly. So the coverage stops at the true silhouette
//! (nothing glows beyond it) and is the same at any retina resolution. What varies smoothly
//! between crossings — the 4D-lit colour — comes from the retina's cells, interpolated over
//! the covered ones only; where no covered cell is near (a feature thinner than a cell), and
//! wherever a colour must be exact (the first-hit surface, the sections), a 4D ray is cast
//! through the point ([`SceneProbe::probe`]).
//!
//! * **first_hit**: opaque at the first covered point along the ray, in the colour of the 4D
//!   ray through it, surfaces in front blended by their opacity;
//! * **volume**: emission–absorption with opacity `opacity` per unit length inside the covered
//!   region (the unit: [`REFERENCE_CELLS`]ths of the retina's longest side, a cell of the
//!   default 64³ retina), the colour interpolated from the cells;
//! * **illustrative**: the same with a nearly clear interior ([`INTERIOR_OPACITY`] per unit)
//!   for faceted objects, or a denser one ([`SMOOTH_OPACITY`]) for smooth hypersurfaces
//!   ([`ObjectLook::smooth`]), read by their 4D shading; the crease and occlusion-contour
//!   sheets the 4D eye sees drawn as thin inked layers, more opaque edge-on; the silhouette
//!   drawn as a line by the edge overlay ([`Exact::silhouettes`]).
//!
//! Anti-aliasing: every pixel gets one ray through its centre; a pixel whose neighbours differ
//! from it — in what its ray crossed, or in colour or coverage — gets
//! [`CompositeOptions::edge_samples`] rays in a jittered √K × √K pattern instead, averaged.
//! Every pixel depends only on the inputs and its coordinates: the picture is the same for
//! any number of threads.

use super::aids::{world_of, Cutaway};
use super::illustrative::{dark, ink};
use super::montage::slice_layout;
use super::overlay::edge_width;
use super::probe::{ObjectLook, Probe, SceneProbe, SheetKind, Structure};
use super::sheets::{Crossing, ViewSheets};
use super::volume::{clip_box, lattice_spacing, Camera3, Grid};
use super::{over, CompositeMode, CompositeOptions, Volume, FAR_TINT, NEAR_TINT};
use glam::DVec3;
use rayon::prelude::*;

/// The unit of length of [`CompositeOptions::opacity`] in pictures drawn from the scene: the
/// retina's longest side over this many (a cell of the default 64³ retina), so that a scene's
/// look does not depend on its retina's resolution.
pub const REFERENCE_CELLS: f64 = 64.0;
/// Illustrative mode: opacity per unit length of a faceted object's interior, at `opacity` 1.
pub const INTERIOR_OPACITY: f64 = 0.012;
/// Illustrative mode: opacity per unit length of a smooth hypersurface's interior, at
/// `opacity` 1.
pub const SMOOTH_OPACITY: f64 = 0.07;
/// Illustrative mode: opacity of a crease or occlusion-contour sheet seen face-on; seen at an
/// angle θ to its normal, 1 − (1 − this)^(1/cos θ) (a thin slab's), at most [`SHEET_MAX`].
pub const SHEET_OPACITY: f64 = 0.1;
/// See [`SHEET_OPACITY`].
pub const SHEET_MAX: f64 = 0.85;
/// Largest spacing, pixels, of the lattice of rays whose blocks are interpolated where the
/// picture is smooth.
const MAX_SPACING: usize = 8;
/// Largest difference, in a channel (colour as √RGB, alpha as it is), between a block's traced
/// middle pixel and its interpolation for the block to be interpolated.
const SMOOTH_MIDDLE: f32 = 0.008;
/// A fold of the covered region's boundary inside it is an occlusion contour when what it hides
/// lies at least this many retina cells (at its depth) behind it.
pub const OCCLUSION_GAP: f64 = 3.0;
/// Rays stop once the transmittance falls below this.
const MIN_TRANSMITTANCE: f64 = 1e-4;
/// A pixel differs from a neighbour — and gets the anti-aliasing's rays — when a channel
/// (colour as √RGB, alpha as it is) differs by more than this.
const EDGE_STEP: f32 = 0.02;

/// A retina made ready for pictures drawn from its scene.
pub(super) struct Exact<'a> {
    probe: &'a dyn SceneProbe,
    s: Structure,
    /// The cells' colours (unit opacity, depth cue), premultiplied by coverage.
    grid: Grid,
    n: [usize; 3],
    /// The retina's depth and object per cell (numpy order).
    depth: Option<&'a [f32]>,
    object: Option<&'a [i32]>,
    /// The depth cue: strength, nearest depth, span.
    cue: (f32, f64, f64),
    /// The reference length, cells.
    unit: f64,
    /// Pairs of count sheets sharing an edge: (vertex a, vertex b, sheet i, sheet j).
    folds: Vec<[u32; 4]>,
}

/// One ray's result: premultiplied RGBA (not over the background), the distance along the view
/// direction at which its opacity reached ½, and a summary of what it crossed.
#[derive(Debug, Clone, Copy)]
struct Sample {
    rgba: [f32; 4],
    half: f32,
    sig: u32,
    /// The share of the ray's (or the pixel's rays') that meet the object, whatever its
    /// opacity: what the lines drawn over the picture are masked by.
    cover: f32,
}

impl Sample {
    const EMPTY: Sample = Sample {
        rgba: [0.0; 4],
        half: f32::INFINITY,
        sig: 0,
        cover: 0.0,
    };
}

/// Front-to-back layers.
struct Layers {
    c: [f64; 3],
    trans: f64,
    half: f64,
}

impl Layers {
    fn new() -> Self {
        Layers {
            c: [0.0; 3],
            trans: 1.0,
            half: f64::INFINITY,
        }
    }

    /// A layer of straight colour `c` and opacity `a` at ray distance `t`.
    #[inline]
    fn add(&mut self, c: [f32; 3], a: f64, t: f64) {
        if !(a > 0.0) {
            return;
        }
        let a = a.min(1.0);
        for k in 0..3 {
            self.c[k] += self.trans * a * c[k] as f64;
        }
        self.trans *= 1.0 - a;
        if self.half.is_infinite() && self.trans <= 0.5 {
            self.half = t;
        }
    }

    fn done(&self) -> bool {
        self.trans < MIN_TRANSMITTANCE
    }

    fn rgba(&self) -> [f32; 4] {
        [
            self.c[0] as f32,
            self.c[1] as f32,
            self.c[2] as f32,
            (1.0 - self.trans) as f32,
        ]
    }
}

/// An event along a ray: a crossing of a sheet that matters to the mode.
#[derive(Clone, Copy)]
enum Event {
    /// The covered region starts (true) or ends, at a crossing (its index; `u32::MAX` at the
    /// box or a cut).
    Region(f64, bool, u32),
    /// A crease or occlusion-contour sheet (index into the crossings).
    Sheet(usize),
    /// A surface sheet.
    Surface(usize),
}

/// Per-thread scratch space.
#[derive(Default)]
struct Scratch {
    cands: Vec<u32>,
    cross: Vec<Crossing>,
    events: Vec<(f64, u8, Event)>,
}

impl<'a> Exact<'a> {
    /// `prepared`: the retina's cells as [`super::prepare`] makes them with unit opacity (the
    /// depth cue applied), numpy order of `shape` (3 axes).
    pub(super) fn new(
        probe: &'a dyn SceneProbe,
        prepared: &[[f32; 4]],
        shape: &[usize],
        depth: Option<&'a [f32]>,
        object: Option<&'a [i32]>,
        o: &CompositeOptions,
    ) -> Self {
        let s = probe.structure(o.crease_angle);
        let n = [shape[2], shape[1], shape[0]];
        let grid = Grid::new(&Volume {
            shape: shape.to_vec(),
            cells: prepared.to_vec(),
        });
        let cue = match depth {
            Some(d) if o.depth_cue > 0.0 => {
                let (lo, hi) = d
                    .iter()
                    .filter(|v| v.is_finite())
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
                        (lo.min(v), hi.max(v))
                    });
                let (lo, hi) = (lo as f64, hi as f64);
                (o.depth_cue as f32, lo, if hi > lo { hi - lo } else { 1.0 })
            }
            _ => (0.0, 0.0, 1.0),
        };
        let folds = folds(&s);
        Exact {
            probe,
            unit: *n.iter().max().unwrap() as f64 / REFERENCE_CELLS,
            s,
            grid,
            n,
            depth,
            object,
            cue,
            folds,
        }
    }

    /// The box of the structure in the retina (cell coordinates, clipped to the retina): what
    /// the compositing camera frames with `fit`, the same at any retina resolution; `None`
    /// when the structure is empty.
    pub(super) fn frame(&self) -> Option<([f64; 3], [f64; 3])> {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for sh in &self.s.sheets {
            for &v in &sh.v {
                let p = self.s.vertices[v as usize].p;
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        if !(lo[0] <= hi[0]) {
            return None;
        }
        let lo: [f64; 3] = std::array::from_fn(|k| lo[k].clamp(0.0, self.n[k] as f64));
        let hi: [f64; 3] = std::array::from_fn(|k| hi[k].clamp(0.0, self.n[k] as f64));
        // A flat structure still has a box with volume.
        let hi: [f64; 3] = std::array::from_fn(|k| hi[k].max(lo[k] + 1e-6));
        Some((lo, hi))
    }

    /// The view of `cam` in `mode`: RGBA over the background and per pixel the distance along
    /// the view direction at which the opacity reached ½; `None` when the structure cannot be
    /// seen by this camera (then the caller draws from the cells).
    pub(super) fn view(
        &self,
        cam: &Camera3,
        mode: CompositeMode,
        o: &CompositeOptions,
    ) -> Option<(Vec<f32>, Vec<f32>, Vec<f32>)> {
        let vs = ViewSheets::new(&self.s, &self.s.looks, cam, self.n)?;
        let (w, h) = o.size;
        let bg = o.background.map(|x| x as f32);
        let ctx = Ctx {
            ex: self,
            vs: &vs,
            cam,
            mode,
            o,
            dark_bg: dark(o.background),
            cut: o.cutaway,
        };
        // 1. One ray through each pixel's centre, or (where the picture is smooth) through a
        //    lattice of them with the blocks between interpolated.
        let spacing = match self.frame() {
            Some((lo, hi)) if o.rays_per_cell > 0 => lattice_spacing(
                cam,
                (DVec3::from_array(lo), DVec3::from_array(hi)),
                o.rays_per_cell,
            )
            .min(MAX_SPACING),
            _ => 1,
        };
        let first = blocks(w, h, spacing, &|px, py, scratch: &mut Scratch| {
            ctx.sample(px as f64 + 0.5, py as f64 + 0.5, scratch)
        });
        // 2. The pixels that differ from a neighbour: K rays each.
        let (k2, k) = o.edge_samples();
        let finals: Vec<Sample> = if k2 > 1 {
            (0..h)
                .into_par_iter()
                .flat_map_iter(|py| {
                    let mut scratch = Scratch::default();
                    let (ctx, first) = (&ctx, &first);
                    (0..w)
                        .map(move |px| {
                            let here = first[py * w + px];
                            if !edge_pixel(first, w, h, px, py) {
                                return here;
                            }
                            ctx.supersample(px, py, k, &mut scratch)
                        })
                        .collect::<Vec<_>>()
                })
                .collect()
        } else {
            first
        };
        let mut img = vec![0f32; w * h * 4];
        let mut half = vec![f32::INFINITY; w * h];
        img.par_chunks_mut(4)
            .zip(half.par_iter_mut())
            .zip(finals.par_iter())
            .for_each(|((px, hf), s)| {
                px.copy_from_slice(&over(s.rgba, bg));
                *hf = s.half;
            });
        let cover = finals.iter().map(|s| s.cover).collect();
        Some((img, half, cover))
    }

    /// The silhouettes of the covered region seen by `cam`: the edges where the count sheets
    /// fold away from the compositing eye (one of the two sheets faces it, the other not) that
    /// lie on the outline of the picture's coverage `alpha` (the view's alpha channel), in cell
    /// coordinates, with the 4D depths of their ends.
    pub(super) fn silhouettes(
        &self,
        cam: &Camera3,
        alpha: &[f32],
    ) -> Vec<(DVec3, DVec3, [f64; 2])> {
        let eye = cam.eye();
        let fwd = cam.forward();
        let ortho = cam.orthographic();
        let facing = |i: u32| -> bool {
            let sh = &self.s.sheets[i as usize];
            let SheetKind::Mesh { delta, .. } = sh.kind else {
                return false;
            };
            let q =
                sh.v.map(|v| DVec3::from_array(self.s.vertices[v as usize].p));
            // Toward fewer layers: outward.
            let out = (q[1] - q[0]).cross(q[2] - q[0]) * -(delta.signum() as f64);
            let to_eye = if ortho { -fwd } else { eye - q[0] };
            out.dot(to_eye) > 0.0
        };
        // The picture's outline: folds with coverage on one side and none on the other, a
        // pixel and a half away (small folds of a mesh inside its picture are not drawn).
        let (w, h) = cam.size();
        let alpha_at = |q: [f64; 2]| -> Option<f32> {
            let (x, y) = (q[0].floor(), q[1].floor());
            (x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h)
                .then(|| alpha[y as usize * w + x as usize])
        };
        let outline = |f: &[u32; 4]| -> bool {
            let ends =
                [f[0], f[1]].map(|v| cam.project(DVec3::from_array(self.s.vertices[v as usize].p)));
            let [Some((a, _)), Some((b, _))] = ends else {
                return false;
            };
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = dx.hypot(dy);
            if !(len > 0.0) {
                return false;
            }
            let (nx, ny) = (-dy / len * 1.5, dx / len * 1.5);
            let m = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            match (
                alpha_at([m[0] + nx, m[1] + ny]),
                alpha_at([m[0] - nx, m[1] - ny]),
            ) {
                (Some(p), Some(q)) => p.min(q) < 0.02 && p.max(q) > 0.1,
                (Some(p), None) | (None, Some(p)) => p > 0.1,
                (None, None) => false,
            }
        };
        self.folds
            .par_iter()
            .filter(|f| facing(f[2]) != facing(f[3]) && outline(f))
            .map(|f| {
                let (a, b) = (
                    self.s.vertices[f[0] as usize].p,
                    self.s.vertices[f[1] as usize].p,
                );
                let depth = |v: u32, p: [f64; 3]| self.s.depth([v, v, v], [1.0, 0.0, 0.0], p);
                (
                    DVec3::from_array(a),
                    DVec3::from_array(b),
                    [depth(f[0], a), depth(f[1], b)],
                )
            })
            .collect()
    }

    /// Section `k` (0: across z, 1: across x, 2: across y, as [`super::ViewLayout::Sections`])
    /// through the world point `at`, `w` × `h` pixels over `bg`: each pixel the colour of the
    /// 4D ray through its point of the section plane, the plane scaled to fit (aspect kept,
    /// centred); pixels that differ from a neighbour get the anti-aliasing's rays.
    pub(super) fn section(
        &self,
        at: [f64; 3],
        k: usize,
        w: usize,
        h: usize,
        o: &CompositeOptions,
    ) -> Vec<f32> {
        let bg = o.background.map(|x| x as f32);
        let n = self.n;
        let c = 2.0 / *n.iter().max().unwrap() as f64;
        // The plane's position in cell coordinates along its axis.
        let cell = |v: f64, axis: usize, flip: bool| -> f64 {
            let half = n[axis] as f64 * c / 2.0;
            let x = if flip { (half - v) / c } else { (v + half) / c };
            x.clamp(0.0, n[axis] as f64)
        };
        let (x0, y0, z0) = (
            cell(at[0], 0, false),
            cell(at[1], 1, true),
            cell(at[2], 2, false),
        );
        let (tw, th) = match k {
            0 => (n[0], n[1]),
            1 => (n[2], n[1]),
            _ => (n[0], n[2]),
        };
        let lay = slice_layout(w, h, 1, tw, th, 0);
        let (ox, oy) = (lay.origin.0 as f64, lay.origin.1 as f64);
        let (sx, sy) = (lay.tile_w as f64 / tw as f64, lay.tile_h as f64 / th as f64);
        let point = move |x: f64, y: f64| -> Option<[f64; 3]> {
            let (u, v) = ((x - ox) / sx, (y - oy) / sy);
            if !(u >= 0.0 && v >= 0.0 && u <= tw as f64 && v <= th as f64) {
                return None;
            }
            Some(match k {
                0 => [u, v, z0],
                1 => [x0, v, u],
                _ => [u, y0, v],
            })
        };
        // One pixel right and one down, in the plane.
        let (dx, dy) = match k {
            0 => (DVec3::X / sx, DVec3::Y / sy),
            1 => (DVec3::Z / sx, DVec3::Y / sy),
            _ => (DVec3::X / sx, DVec3::Z / sy),
        };
        let line = texture_line_width(o);
        let one = |x: f64, y: f64| -> Sample {
            match point(x, y) {
                None => Sample::EMPTY,
                Some(p) => {
                    let hit = self.probe.probe(p);
                    if !hit.hit {
                        return Sample {
                            rgba: [0.0, 0.0, 0.0, 0.0],
                            half: f32::INFINITY,
                            sig: 1,
                            cover: 0.0,
                        };
                    }
                    let c = self.with_lines(&hit, DVec3::from_array(p), dx, dy, line);
                    let c = self.cued(c, hit.depth);
                    Sample {
                        rgba: [c[0], c[1], c[2], 1.0],
                        half: f32::INFINITY,
                        sig: (2 + hit.object as u32) ^ bands(&hit),
                        cover: 1.0,
                    }
                }
            }
        };
        let first = blocks(
            w,
            h,
            MAX_SPACING.min(w).min(h).max(1),
            &|px, py, _: &mut Scratch| one(px as f64 + 0.5, py as f64 + 0.5),
        );
        let (k2, kk) = o.edge_samples();
        let mut img = vec![0f32; w * h * 4];
        img.par_chunks_mut(w * 4).enumerate().for_each(|(py, row)| {
            for px in 0..w {
                let mut s = first[py * w + px];
                if k2 > 1 && edge_pixel(&first, w, h, px, py) {
                    let mut acc = [0f32; 4];
                    for (dx, dy) in pattern(px, py, kk) {
                        let v = one(px as f64 + dx, py as f64 + dy);
                        for c in 0..4 {
                            acc[c] += v.rgba[c];
                        }
                    }
                    s.rgba = acc.map(|v| v / k2 as f32);
                }
                row[px * 4..px * 4 + 4].copy_from_slice(&over(s.rgba, bg));
            }
        });
        img
    }

    /// `c` tinted by the depth cue at depth `d`.
    fn cued(&self, c: [f32; 3], d: f64) -> [f32; 3] {
        let (cue, lo, span) = self.cue;
        if cue > 0.0 && d.is_finite() {
            let t = ((d - lo) / span).clamp(0.0, 1.0) as f32;
            std::array::from_fn(|k| {
                let tint = NEAR_TINT[k] + (FAR_TINT[k] - NEAR_TINT[k]) * t;
                c[k] * (1.0 - cue + cue * tint)
            })
        } else {
            c
        }
    }

    /// The object of the retina cell holding `p` (−1 when unknown).
    fn object_at(&self, p: DVec3) -> i32 {
        let Some(obj) = self.object else {
            return -1;
        };
        let idx = |v: f64, r: usize| (v.max(0.0) as usize).min(r - 1);
        let (x, y, z) = (
            idx(p.x, self.n[0]),
            idx(p.y, self.n[1]),
            idx(p.z, self.n[2]),
        );
        obj[x + self.n[0] * (y + self.n[1] * z)]
    }

    /// The look of the object at `p`.
    fn look_at(&self, p: DVec3) -> Option<&ObjectLook> {
        let o = self.object_at(p);
        (o >= 0).then(|| self.s.looks.get(o as usize)).flatten()
    }

    /// The straight colour at `p` inside the covered region: interpolated from the covered
    /// cells, or (none near) the 4D ray's through it.
    fn color_at(&self, p: DVec3) -> [f32; 3] {
        let v = self.grid.sample([p.x as f32, p.y as f32, p.z as f32]);
        if v.w > 1e-3 {
            [v.x / v.w, v.y / v.w, v.z / v.w]
        } else {
            let hit = self.probe.probe(p.to_array());
            self.cued(hit.color, hit.depth)
        }
    }

    /// Whether the 4D eye sees the mesh sheet crossed at `c` (the nearest hit of the ray through
    /// the crossing point lies on it).
    fn sheet_visible(&self, c: &Crossing) -> bool {
        let sh = &self.s.sheets[c.sheet as usize];
        if let Some(k) = sh.visible {
            return k;
        }
        let d = self.s.depth(sh.v, c.b, c.p.to_array());
        // The cells around the point: all nearer by far, hidden; else ask the scene.
        if let Some(depth) = self.depth {
            let (mut lo, mut hi, mut finite) = (f64::INFINITY, f64::NEG_INFINITY, 0);
            let base = |v: f64, r: usize| -> (usize, usize) {
                let i = (v - 0.5).floor().clamp(0.0, (r - 1) as f64) as usize;
                (i, (i + 1).min(r - 1))
            };
            let (xs, ys, zs) = (
                base(c.p.x, self.n[0]),
                base(c.p.y, self.n[1]),
                base(c.p.z, self.n[2]),
            );
            for z in [zs.0, zs.1] {
                for y in [ys.0, ys.1] {
                    for x in [xs.0, xs.1] {
                        let v = depth[x + self.n[0] * (y + self.n[1] * z)] as f64;
                        if v.is_finite() {
                            finite += 1;
                            lo = lo.min(v);
                            hi = hi.max(v);
                        }
                    }
                }
            }
            let world_cell = self.world_cell(d);
            if finite == 8 && d > hi + 2.0 * (hi - lo).max(world_cell) {
                return false;
            }
        }
        let hit = self.probe.probe(c.p.to_array());
        hit.hit && (hit.depth - d).abs() <= 1e-5 * d.abs().max(1e-12) + 1e-9
    }
}

/// Which side of each of its texture lines a hit lies on, hashed: two points on either side
/// of a line differ, so that a block of pixels a thin line crosses is never interpolated over
/// it (see [`blocks`]).
fn bands(hit: &Probe) -> u32 {
    let Some(l) = &hit.lines else {
        return 0;
    };
    let mut h = 0u32;
    for j in 0..l.count {
        let side = u32::from(l.value[j] >= l.level[j]);
        let level = (l.level[j] as f32).to_bits();
        h = h
            .wrapping_mul(0x9E37_79B1)
            .wrapping_add(level.rotate_left(1) ^ side);
    }
    h.wrapping_mul(0x85EB_CA6B)
}

/// The width, picture pixels, of texture lines drawn by a picture: 0.6 of the edges'.
fn texture_line_width(o: &CompositeOptions) -> f64 {
    (0.6 * edge_width(o)).max(1.0)
}

impl Exact<'_> {
    /// The colour of the probe `hit` at retina point `p` with its texture lines drawn `width`
    /// pixels wide, anti-aliased: each line's distance in pixels is its field's distance to its
    /// level over the field's change across a pixel, from the probes one pixel right (`p +
    /// dx`) and one down (`p + dy`) on the same object.
    fn with_lines(&self, hit: &Probe, p: DVec3, dx: DVec3, dy: DVec3, width: f64) -> [f32; 3] {
        let Some(l) = &hit.lines else {
            return hit.color;
        };
        let (hx, hy) = (
            self.probe.probe((p + dx).to_array()),
            self.probe.probe((p + dy).to_array()),
        );
        let mut best = (0.0f64, [0f32; 3]);
        for j in 0..l.count {
            let step = |q: &Probe| {
                q.lines
                    .filter(|m| q.object == hit.object && m.count == l.count)
                    .map(|m| m.value[j] - l.value[j])
            };
            let grad = match (step(&hx), step(&hy)) {
                (Some(a), Some(b)) => a.hypot(b),
                (Some(a), None) | (None, Some(a)) => a.abs(),
                (None, None) => continue,
            };
            if !(grad > 0.0) {
                continue;
            }
            let dist = (l.value[j] - l.level[j]).abs() / grad;
            let cov = (0.5 * width + 0.5 - dist).clamp(0.0, 1.0);
            if cov > best.0 {
                best = (cov, l.color[j]);
            }
        }
        let k = best.0 as f32;
        std::array::from_fn(|c| l.base[c] + (best.1[c] - l.base[c]) * k)
    }

    /// Whether the count sheet crossed at `c`, seen by the 4D eye, hides a surface at least
    /// [`OCCLUSION_GAP`] retina cells behind it: the nearest hit just off the sheet on its
    /// side of fewer layers (`outward`, a unit direction in cell coordinates).
    fn occludes(&self, c: &Crossing, outward: DVec3) -> bool {
        let sh = &self.s.sheets[c.sheet as usize];
        let d = self.s.depth(sh.v, c.b, c.p.to_array());
        let hit = self.probe.probe((c.p + outward * 0.25).to_array());
        hit.hit && hit.depth > d + OCCLUSION_GAP * self.world_cell(d)
    }

    /// The size in the world of a retina cell at depth `d`.
    fn world_cell(&self, d: f64) -> f64 {
        match self.s.projection {
            crate::camera::Projection::Perspective => self.s.cell * d,
            crate::camera::Projection::Orthographic => self.s.cell,
        }
    }
}

/// The count sheets' edges shared by exactly two count sheets (where the region's boundary
/// may fold away from a compositing eye).
fn folds(s: &Structure) -> Vec<[u32; 4]> {
    let mut edges: Vec<(u32, u32, u32)> = Vec::new();
    for (i, sh) in s.sheets.iter().enumerate() {
        if let SheetKind::Mesh { delta, .. } = sh.kind {
            if delta != 0 {
                for k in 0..3 {
                    let (a, b) = (sh.v[k], sh.v[(k + 1) % 3]);
                    edges.push((a.min(b), a.max(b), i as u32));
                }
            }
        }
    }
    edges.par_sort_unstable();
    let mut out = Vec::new();
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
            j += 1;
        }
        if j - i == 2 {
            out.push([edges[i].0, edges[i].1, edges[i].2, edges[i + 1].2]);
        }
        i = j;
    }
    out
}

/// The samples of a `w` × `h` picture: `eval` at the pixels of a lattice every `s` pixels (and
/// the last row and column), then each block between four of them interpolated bilinearly when
/// its corners cross the same structure and its middle pixel, traced, agrees with the
/// interpolation within [`SMOOTH_MIDDLE`]; else split into four at traced side and middle
/// pixels, recursively, down to single pixels. Every decision depends only on pixels traced
/// for the block itself: the picture is the same for any number of threads.
fn blocks(
    w: usize,
    h: usize,
    s: usize,
    eval: &(dyn Fn(usize, usize, &mut Scratch) -> Sample + Sync),
) -> Vec<Sample> {
    let mut out = vec![Sample::EMPTY; w * h];
    if s <= 1 || w < 2 || h < 2 {
        out.par_chunks_mut(w).enumerate().for_each(|(py, row)| {
            let mut scratch = Scratch::default();
            for (px, v) in row.iter_mut().enumerate() {
                *v = eval(px, py, &mut scratch);
            }
        });
        return out;
    }
    let stops = |len: usize| -> Vec<usize> {
        let mut v: Vec<usize> = (0..len).step_by(s).collect();
        if *v.last().unwrap() != len - 1 {
            v.push(len - 1);
        }
        v
    };
    let (xs, ys) = (stops(w), stops(h));
    let lattice: Vec<Sample> = ys
        .par_iter()
        .flat_map_iter(|&py| {
            let mut scratch = Scratch::default();
            let xs = &xs;
            xs.iter()
                .map(move |&px| eval(px, py, &mut scratch))
                .collect::<Vec<_>>()
        })
        .collect();
    let at = |i: usize, j: usize| lattice[j * xs.len() + i];
    // One band of blocks (rows ys[j] .. ys[j + 1], the last with its closing row) per unit of
    // parallel work.
    let mut bands: Vec<(usize, &mut [Sample])> = Vec::with_capacity(ys.len());
    let mut rest = &mut out[..];
    for j in 0..ys.len() - 1 {
        let rows = if j + 2 == ys.len() {
            h - ys[j]
        } else {
            ys[j + 1] - ys[j]
        };
        let (a, b) = std::mem::take(&mut rest).split_at_mut(rows * w);
        bands.push((j, a));
        rest = b;
    }
    bands.into_par_iter().for_each(|(j, rows)| {
        let mut scratch = Scratch::default();
        let y0 = ys[j];
        let nrows = rows.len() / w;
        let mut put = |px: usize, py: usize, v: Sample| rows[(py - y0) * w + px] = v;
        for i in 0..xs.len() - 1 {
            let corners = [at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)];
            let own = [
                if i + 2 == xs.len() {
                    xs[i + 1] + 1
                } else {
                    xs[i + 1]
                },
                y0 + nrows,
            ];
            block(
                [xs[i], xs[i + 1]],
                [y0, ys[j + 1]],
                corners,
                own,
                eval,
                &mut scratch,
                &mut put,
            );
        }
    });
    out
}

/// One block of [`blocks`] (corners x0 y0, x1 y0, x0 y1, x1 y1), putting its pixels below `own`
/// (exclusive ends).
fn block(
    x: [usize; 2],
    y: [usize; 2],
    c: [Sample; 4],
    own: [usize; 2],
    eval: &(dyn Fn(usize, usize, &mut Scratch) -> Sample + Sync),
    scratch: &mut Scratch,
    put: &mut impl FnMut(usize, usize, Sample),
) {
    let ([x0, x1], [y0, y1]) = (x, y);
    let (xm, ym) = ((x0 + x1) / 2, (y0 + y1) / 2);
    if xm == x0 && ym == y0 {
        for (k, (px, py)) in [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
            .into_iter()
            .enumerate()
        {
            if px < own[0] && py < own[1] {
                put(px, py, c[k]);
            }
        }
        return;
    }
    let fraction = |v: usize, a: usize, b: usize| {
        if b > a {
            (v - a) as f32 / (b - a) as f32
        } else {
            0.0
        }
    };
    let mid = eval(xm, ym, scratch);
    let same = c.iter().all(|q| q.sig == mid.sig);
    if same {
        let guess = bilinear(&c, fraction(xm, x0, x1), fraction(ym, y0, y1));
        let (a, b) = (perceptual(&mid.rgba), perceptual(&guess.rgba));
        if (0..4).all(|k| (a[k] - b[k]).abs() <= SMOOTH_MIDDLE) {
            for py in y0..own[1].min(y1 + 1) {
                let fy = fraction(py, y0, y1);
                for px in x0..own[0].min(x1 + 1) {
                    put(px, py, bilinear(&c, fraction(px, x0, x1), fy));
                }
            }
            return;
        }
    }
    let top = eval(xm, y0, scratch);
    let bottom = eval(xm, y1, scratch);
    let left = eval(x0, ym, scratch);
    let right = eval(x1, ym, scratch);
    let quarters = [
        ([x0, xm], [y0, ym], [c[0], top, left, mid]),
        ([xm, x1], [y0, ym], [top, c[1], mid, right]),
        ([x0, xm], [ym, y1], [left, mid, c[2], bottom]),
        ([xm, x1], [ym, y1], [mid, right, bottom, c[3]]),
    ];
    for (qx, qy, corners) in quarters {
        let own_q = [
            if qx[1] == x1 { own[0] } else { qx[1] },
            if qy[1] == y1 { own[1] } else { qy[1] },
        ];
        if qx[0] >= own_q[0] || qy[0] >= own_q[1] {
            continue;
        }
        block(qx, qy, corners, own_q, eval, scratch, put);
    }
}

/// Bilinear interpolation of four samples (x0 y0, x1 y0, x0 y1, x1 y1) at (fx, fy); the
/// half-opacity distance where all four are finite.
fn bilinear(c: &[Sample; 4], fx: f32, fy: f32) -> Sample {
    let w = [
        (1.0 - fx) * (1.0 - fy),
        fx * (1.0 - fy),
        (1.0 - fx) * fy,
        fx * fy,
    ];
    let rgba = std::array::from_fn(|k| {
        w[0] * c[0].rgba[k] + w[1] * c[1].rgba[k] + w[2] * c[2].rgba[k] + w[3] * c[3].rgba[k]
    });
    let half = if c.iter().all(|q| q.half.is_finite()) {
        w[0] * c[0].half + w[1] * c[1].half + w[2] * c[2].half + w[3] * c[3].half
    } else {
        f32::INFINITY
    };
    let cover = w[0] * c[0].cover + w[1] * c[1].cover + w[2] * c[2].cover + w[3] * c[3].cover;
    Sample {
        rgba,
        half,
        sig: c[0].sig,
        cover,
    }
}

/// Whether pixel (px, py) of `first` differs from one of its four neighbours: in what its ray
/// crossed, or by more than [`EDGE_STEP`] in a channel.
fn edge_pixel(first: &[Sample], w: usize, h: usize, px: usize, py: usize) -> bool {
    let here = &first[py * w + px];
    let a = perceptual(&here.rgba);
    let differs = |q: &Sample| {
        if q.sig != here.sig {
            return true;
        }
        let b = perceptual(&q.rgba);
        (0..4).any(|k| (a[k] - b[k]).abs() > EDGE_STEP)
    };
    (px > 0 && differs(&first[py * w + px - 1]))
        || (px + 1 < w && differs(&first[py * w + px + 1]))
        || (py > 0 && differs(&first[(py - 1) * w + px]))
        || (py + 1 < h && differs(&first[(py + 1) * w + px]))
}

/// Colour as √RGB (about perceived lightness), alpha as it is.
#[inline]
fn perceptual(v: &[f32; 4]) -> [f32; 4] {
    [
        v[0].max(0.0).sqrt(),
        v[1].max(0.0).sqrt(),
        v[2].max(0.0).sqrt(),
        v[3],
    ]
}

/// The k × k jittered sample offsets within pixel (px, py) (in [0, 1)²), the jitter a hash of
/// the pixel and the stratum: the same for any number of threads.
fn pattern(px: usize, py: usize, k: usize) -> impl Iterator<Item = (f64, f64)> {
    (0..k * k).map(move |i| {
        let (a, b) = (i % k, i / k);
        let mut hsh = (px as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (py as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ (i as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
        hsh ^= hsh >> 29;
        hsh = hsh.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        hsh ^= hsh >> 32;
        let jx = (hsh & 0xffff) as f64 / 65536.0;
        let jy = ((hsh >> 16) & 0xffff) as f64 / 65536.0;
        ((a as f64 + jx) / k as f64, (b as f64 + jy) / k as f64)
    })
}

/// What a view's rays share.
struct Ctx<'a, 'b> {
    ex: &'a Exact<'b>,
    vs: &'a ViewSheets,
    cam: &'a Camera3,
    mode: CompositeMode,
    o: &'a CompositeOptions,
    dark_bg: bool,
    cut: Option<Cutaway>,
}

impl Ctx<'_, '_> {
    /// The mean of k × k rays within pixel (px, py). Rays that cross the same structure and
    /// enter by the same face ([`Ctx::walk`]'s key) share one integral, the first one's (the
    /// colour between sheets is smooth; the coverage is what varies within a pixel).
    fn supersample(&self, px: usize, py: usize, k: usize, scratch: &mut Scratch) -> Sample {
        let mut groups: Vec<(u32, Sample, u32)> = Vec::with_capacity(4);
        let mut cands = std::mem::take(&mut scratch.cands);
        self.vs.candidates(px, py, &mut cands);
        for (dx, dy) in pattern(px, py, k) {
            let walked = self.walk(px as f64 + dx, py as f64 + dy, Some(&cands), scratch);
            let (key, walked) = match walked {
                None => (0, None),
                Some((o, d, sig, key)) => (key, Some((o, d, sig))),
            };
            if let Some(g) = groups.iter_mut().find(|g| g.0 == key) {
                g.2 += 1;
                continue;
            }
            let s = match walked {
                None => Sample::EMPTY,
                Some((o, d, sig)) => self.integrate(o, d, sig, scratch),
            };
            groups.push((key, s, 1));
        }
        scratch.cands = cands;
        let mut acc = [0f32; 4];
        let mut half = f32::INFINITY;
        let mut sig = 0u32;
        let mut cover = 0f32;
        for (_, s, count) in &groups {
            for c in 0..4 {
                acc[c] += s.rgba[c] * *count as f32;
            }
            cover += s.cover * *count as f32;
            half = half.min(s.half);
            sig = sig.wrapping_add(s.sig);
        }
        let kk = (k * k) as f32;
        Sample {
            rgba: acc.map(|v| v / kk),
            half,
            sig,
            cover: cover / kk,
        }
    }

    /// The ray through picture point (x, y).
    fn sample(&self, x: f64, y: f64, scratch: &mut Scratch) -> Sample {
        match self.walk(x, y, None, scratch) {
            None => Sample::EMPTY,
            Some((org, dir, sig, _)) => self.integrate(org, dir, sig, scratch),
        }
    }

    /// The events of the ray through picture point (x, y), in order, into `scratch`: where it
    /// enters and leaves the covered region, the sheets the 4D eye sees that it crosses (the
    /// illustrative mode), the surfaces; its origin, direction and a summary of what it crosses
    /// (rays with the same summary cross the same kinds of structure in the same order).
    /// `None` when the ray misses the retina's box.
    fn walk(
        &self,
        x: f64,
        y: f64,
        cands: Option<&[u32]>,
        scratch: &mut Scratch,
    ) -> Option<(DVec3, DVec3, u32, u32)> {
        let ex = self.ex;
        let (org, dir, fwd_only) = self.cam.ray_at(x, y);
        let (tb0, tb1) = clip_box(org, dir, ex.n, fwd_only)?;
        // The part of the ray inside the cutaway, removed from the covered region.
        let cut = self.cut.as_ref().and_then(|c| {
            let (a, b) = (org + dir * tb0, org + dir * tb1);
            c.inside(world_of(ex.n, a), world_of(ex.n, b))
                .map(|(s0, s1)| (tb0 + (tb1 - tb0) * s0, tb0 + (tb1 - tb0) * s1))
        });
        scratch.cross.clear();
        match cands {
            Some(c) => self.vs.crossings_of(c, x, y, org, dir, &mut scratch.cross),
            None => self.vs.crossings(x, y, org, dir, &mut scratch.cross),
        }
        let cross = &mut scratch.cross;
        cross.sort_unstable_by(|a, b| a.t.total_cmp(&b.t).then(a.sheet.cmp(&b.sheet)));
        // 1. The covered intervals and the events of the ray, in order.
        let events = &mut scratch.events;
        events.clear();
        let inside_cut = |t: f64| cut.is_some_and(|(a, b)| t > a && t < b);
        let push_region = |events: &mut Vec<(f64, u8, Event)>, a: f64, b: f64, at: u32| {
            // [a, b] ∩ box, minus the cut.
            let at = if a >= tb0 { at } else { u32::MAX };
            let (a, b) = (a.max(tb0), b.min(tb1));
            if !(b > a) {
                return;
            }
            let mut parts = [(a, b, at), (0.0, -1.0, at)];
            if let Some((c0, c1)) = cut {
                parts = [(a, b.min(c0), at), (a.max(c1), b, u32::MAX)];
            }
            for (p0, p1, at) in parts {
                if p1 > p0 {
                    events.push((p0, 0, Event::Region(p0, true, at)));
                    events.push((p1, 0, Event::Region(p1, false, u32::MAX)));
                }
            }
        };
        let mut sig: u32 = 0;
        if ex.s.counted {
            let mut count = 0i32;
            let (mut start, mut start_at) = (f64::NEG_INFINITY, u32::MAX);
            for (i, c) in cross.iter().enumerate() {
                let sh = &ex.s.sheets[c.sheet as usize];
                match sh.kind {
                    SheetKind::Mesh { crease, .. } => {
                        let before = count;
                        count += c.enter as i32;
                        if before <= 0 && count > 0 {
                            (start, start_at) = (c.t, i as u32);
                        } else if before > 0 && count <= 0 {
                            push_region(events, start, c.t, start_at);
                        }
                        let internal = before > 0 && count > 0;
                        if (crease || (c.enter != 0 && internal))
                            && c.t > tb0
                            && c.t < tb1
                            && !inside_cut(c.t)
                            && (before > 0 || count > 0)
                        {
                            events.push((c.t, 1, Event::Sheet(i)));
                        }
                    }
                    SheetKind::Surface { .. } => {
                        if c.t > tb0 && c.t < tb1 && !inside_cut(c.t) {
                            events.push((c.t, 2, Event::Surface(i)));
                        }
                    }
                }
            }
            if count > 0 {
                push_region(events, start, f64::INFINITY, start_at);
            }
        } else {
            // Between the count sheets' crossings, one 4D ray says whether it is covered.
            let mut bounds: Vec<f64> = vec![tb0];
            for c in cross.iter() {
                if c.enter != 0 && c.t > tb0 && c.t < tb1 {
                    bounds.push(c.t);
                }
            }
            bounds.push(tb1);
            let mut states = Vec::with_capacity(bounds.len());
            for wdw in bounds.windows(2) {
                let mid = org + dir * (0.5 * (wdw[0] + wdw[1]));
                states.push(wdw[1] > wdw[0] && ex.probe.covered(mid.to_array()));
            }
            let mut j = 0;
            while j < states.len() {
                if states[j] {
                    let a = bounds[j];
                    while j < states.len() && states[j] {
                        j += 1;
                    }
                    push_region(events, a, bounds[j], u32::MAX);
                } else {
                    j += 1;
                }
            }
            // Sheets: creases anywhere covered; count sheets between two covered intervals.
            let covered_at = |t: f64| -> bool {
                match bounds.windows(2).position(|w| t >= w[0] && t < w[1]) {
                    Some(k) => states[k],
                    None => false,
                }
            };
            for (i, c) in cross.iter().enumerate() {
                if !(c.t > tb0 && c.t < tb1) || inside_cut(c.t) {
                    continue;
                }
                match ex.s.sheets[c.sheet as usize].kind {
                    SheetKind::Mesh { crease, .. } => {
                        let eps = 1e-7 * (tb1 - tb0);
                        let (b, a) = (covered_at(c.t - eps), covered_at(c.t + eps));
                        if (crease && (a || b)) || (c.enter != 0 && a && b) {
                            events.push((c.t, 1, Event::Sheet(i)));
                        }
                    }
                    SheetKind::Surface { .. } => events.push((c.t, 2, Event::Surface(i))),
                }
            }
        }
        events.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        // 2. The sheets the 4D eye sees (illustrative), and the summary.
        let illustrative = self.mode == CompositeMode::Illustrative;
        events.retain(|&(_, _, e)| match e {
            Event::Sheet(i) => {
                let c = &cross[i];
                // A fold inside the covered region is an occlusion contour where what it
                // hides lies well behind it (not a small fold of the mesh).
                let obj = ex.s.sheets[c.sheet as usize].object as usize;
                illustrative
                    && !ex.s.looks.get(obj).is_some_and(|l| l.smooth)
                    && ex.sheet_visible(c)
                    && (c.enter == 0 || ex.occludes(c, dir * -(c.enter.signum() as f64)))
            }
            _ => true,
        });
        // What lies behind an opaque layer does not count.
        let opaque_at = |e: &Event| match (*e, self.mode) {
            (Event::Region(_, true, _), CompositeMode::FirstHit) => true,
            (Event::Region(_, true, _), CompositeMode::Volume) => self.o.opacity >= 1.0,
            (Event::Surface(i), CompositeMode::FirstHit | CompositeMode::Volume) => {
                let obj = ex.s.sheets[cross[i].sheet as usize].object;
                ex.s.looks
                    .get(obj as usize)
                    .is_some_and(|l| l.opacity >= 1.0)
            }
            _ => false,
        };
        for (_, _, e) in events.iter() {
            let e = *e;
            let k = match e {
                Event::Region(_, true, _) => 3,
                Event::Region(_, false, _) => 0,
                Event::Sheet(i) => {
                    // Sheets of one flat face share a normal: a face's border is an edge.
                    let sh = &ex.s.sheets[cross[i].sheet as usize];
                    let q = sh.v.map(|v| DVec3::from_array(ex.s.vertices[v as usize].p));
                    let n = (q[1] - q[0]).cross(q[2] - q[0]).normalize_or_zero();
                    let n = if n.x < 0.0 || (n.x == 0.0 && n.y < 0.0) {
                        -n
                    } else {
                        n
                    };
                    let quant = |v: f64| ((v + 1.0) * 64.0) as u32;
                    5 + quant(n.x) * 7919 + quant(n.y) * 104_729 + quant(n.z) * 1_299_709
                }
                Event::Surface(i) => 11 + ex.s.sheets[cross[i].sheet as usize].object,
            };
            sig = sig.wrapping_mul(0x9E37_79B1).wrapping_add(k);
            if opaque_at(&e) {
                break;
            }
        }
        // The key a pixel's rays are grouped by: the summary and the face the ray enters by.
        let entry = events.iter().find_map(|&(_, _, e)| match e {
            Event::Region(_, true, at) if at != u32::MAX => Some(at),
            _ => None,
        });
        let key = match entry {
            Some(i) => {
                let sh = &ex.s.sheets[cross[i as usize].sheet as usize];
                let q = sh.v.map(|v| DVec3::from_array(ex.s.vertices[v as usize].p));
                let n = (q[1] - q[0]).cross(q[2] - q[0]).normalize_or_zero();
                let n = if n.x < 0.0 || (n.x == 0.0 && n.y < 0.0) {
                    -n
                } else {
                    n
                };
                let quant = |v: f64| ((v + 1.0) * 4.0) as u32;
                sig ^ (1 + quant(n.x) + 9 * quant(n.y) + 81 * quant(n.z)).wrapping_mul(0x85EB_CA6B)
            }
            None => sig,
        };
        Some((org, dir, sig, key))
    }

    /// The mode's integral along the ray `org + t·dir` whose events [`Ctx::walk`] put in
    /// `scratch`.
    fn integrate(&self, org: DVec3, dir: DVec3, mut sig: u32, scratch: &Scratch) -> Sample {
        let ex = self.ex;
        let (cross, events) = (&scratch.cross, &scratch.events);
        let fwd = dir.dot(self.cam.forward());
        let mut layers = Layers::new();
        let o = self.o;
        match self.mode {
            CompositeMode::FirstHit => {
                if !(o.opacity > 0.0) {
                    return Sample::EMPTY;
                }
                for &(_, _, e) in events.iter() {
                    match e {
                        Event::Region(t, true, _) => {
                            // Just inside: the 4D ray through the entry point.
                            let next = events
                                .iter()
                                .find_map(|&(_, _, e)| match e {
                                    Event::Region(u, false, _) if u > t => Some(u),
                                    _ => None,
                                })
                                .unwrap_or(t);
                            let eps = (1e-4 * ex.unit).min(0.5 * (next - t));
                            let p = org + dir * (t + eps);
                            let hit = ex.probe.probe(p.to_array());
                            let c = if hit.hit {
                                let (dx, dy) = self.cam.pixel_steps(p);
                                let c = ex.with_lines(&hit, p, dx, dy, texture_line_width(o));
                                ex.cued(c, hit.depth)
                            } else {
                                ex.color_at(p)
                            };
                            sig = sig.wrapping_mul(31).wrapping_add(7 + hit.object as u32)
                                ^ bands(&hit);
                            layers.add(c, 1.0, t);
                            break;
                        }
                        Event::Surface(i) if self.surface(&cross[i], &mut layers, &mut sig) => {
                            break;
                        }
                        _ => {}
                    }
                }
            }
            CompositeMode::Volume | CompositeMode::Illustrative => {
                let illustrative = self.mode == CompositeMode::Illustrative;
                let mut inside_from: Option<f64> = None;
                for &(t, _, e) in events.iter() {
                    match e {
                        Event::Region(_, true, _) => inside_from = Some(t),
                        Event::Region(_, false, _) => {
                            if let Some(a) = inside_from.take() {
                                self.march(org, dir, a, t, illustrative, &mut layers);
                            }
                        }
                        Event::Sheet(i) => {
                            if !illustrative {
                                continue;
                            }
                            if let Some(a) = inside_from {
                                self.march(org, dir, a, t, true, &mut layers);
                                inside_from = Some(t);
                            }
                            let c = &cross[i];
                            let cos = c.cos.max(0.02);
                            let a = (1.0 - (1.0 - SHEET_OPACITY).powf(1.0 / cos)).min(SHEET_MAX);
                            let col = ink(ex.color_at(c.p), 1.0, self.dark_bg);
                            layers.add(col, a, t);
                        }
                        Event::Surface(i) => {
                            if let Some(a) = inside_from {
                                self.march(org, dir, a, t, illustrative, &mut layers);
                                inside_from = Some(t);
                            }
                            self.surface(&cross[i], &mut layers, &mut sig);
                        }
                    }
                    if layers.done() {
                        break;
                    }
                }
            }
            _ => {}
        }
        Sample {
            rgba: layers.rgba(),
            half: (layers.half * fwd) as f32,
            sig,
            cover: if layers.trans < 1.0 { 1.0 } else { 0.0 },
        }
    }

    /// A surface sheet's crossing as a layer (when the 4D eye sees it); whether the ray is
    /// done.
    fn surface(&self, c: &Crossing, layers: &mut Layers, sig: &mut u32) -> bool {
        let ex = self.ex;
        let sh = &ex.s.sheets[c.sheet as usize];
        let SheetKind::Surface { triangle } = sh.kind else {
            return false;
        };
        if let Some((col, d)) = ex.probe.surface(sh.object, triangle, c.b) {
            let a =
                ex.s.looks
                    .get(sh.object as usize)
                    .map_or(1.0, |l| l.opacity);
            *sig = sig.wrapping_mul(31).wrapping_add(11 + sh.object);
            layers.add(ex.cued(col, d), a, c.t);
        }
        layers.done()
    }

    /// Emission–absorption over the covered stretch [a, b] of the ray: opacity per unit
    /// length `opacity` (volume) or the object's interior opacity (illustrative), the colour
    /// interpolated from the cells, at the middles of ⌈(b − a)/step⌉ equal steps.
    fn march(&self, o: DVec3, d: DVec3, a: f64, b: f64, illustrative: bool, layers: &mut Layers) {
        let ex = self.ex;
        let len = b - a;
        if !(len > 0.0) {
            return;
        }
        let steps = ((len / self.o.step).ceil() as usize).max(1);
        let dt = len / steps as f64;
        let per_unit = |alpha: f64| 1.0 - (1.0 - alpha.min(1.0)).powf(dt / ex.unit);
        let plain = per_unit(self.o.opacity);
        let faceted = per_unit(INTERIOR_OPACITY * self.o.opacity);
        let smooth = per_unit(SMOOTH_OPACITY * self.o.opacity);
        for j in 0..steps {
            let t = a + (j as f64 + 0.5) * dt;
            let p = o + d * t;
            let alpha = if illustrative {
                match ex.look_at(p) {
                    Some(l) if l.smooth => smooth,
                    _ => faceted,
                }
            } else {
                plain
            };
            layers.add(ex.color_at(p), alpha, t);
            if layers.done() {
                return;
            }
        }
    }
}
