//! Pictures at the picture's resolution ([`Detail::Scene`](super::Detail::Scene), N = 4): the
//! first-hit, volume and illustrative views and the sections of a retina that comes with the
//! scene it was traced from ([`SceneProbe`]).
//!
//! The retina's grid decides nothing the picture can see sharply. Each picture ray meets the
//! scene's sheets (`composite/sheets.rs`) at exact points; between two crossings the ray is inside
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
//!   drawn as a line by the edge overlay (`Exact::silhouettes`).
//!
//! Anti-aliasing: every pixel gets one ray through its centre; a pixel whose neighbours differ
//! from it — in what its ray crossed, or in colour or coverage — gets
//! [`CompositeOptions::edge_samples`] rays in a jittered √K × √K pattern instead, averaged.
//! Every pixel depends only on the inputs and its coordinates: the picture is the same for
//! any number of threads.

use super::aids::{world_of, Cutaway};
use super::annotate::{hull_of_points, Hull};
use super::illustrative::{dark, ink};
use super::overlay::edge_width;
use super::probe::{ObjectLook, Probe, SceneProbe, SheetKind, Structure};
use super::sheets::{Crossing, ViewSheets};
use super::volume::{clip_box, lattice_spacing, Camera3, Grid};
use super::{over, CompositeMode, CompositeOptions, Volume, FAR_TINT, NEAR_TINT};
use glam::DVec3;
use rayon::prelude::*;

mod lattice;
mod ray;

use lattice::{blocks, edge_pixel, pattern};
use ray::Ctx;

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

    /// The [`Hull`] of the structure in the retina (its sheets' vertices, clipped to the
    /// retina): what the compositing camera frames and centres with `fit`, the same at any
    /// retina resolution; `None` when the structure is empty.
    pub(super) fn hull(&self) -> Option<Hull> {
        let n = self.n.map(|v| v as f64);
        hull_of_points(self.s.sheets.iter().flat_map(|sh| {
            sh.v.iter().map(|&v| {
                let p = self.s.vertices[v as usize].p;
                DVec3::from_array(std::array::from_fn(|k| p[k].clamp(0.0, n[k])))
            })
        }))
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
    /// centred) — with `fit`, only the part of it over the structure's box and a margin of a
    /// 32nd of the retina, so each section frames the object at any retina resolution; pixels
    /// that differ from a neighbour get the anti-aliasing's rays.
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
        // The part of the plane shown (cell coordinates): the structure's box with a margin,
        // or the whole retina.
        let full = ([0.0; 3], n.map(|v| v as f64));
        let (lo, hi) = match self.frame().filter(|_| o.fit) {
            Some((lo, hi)) => {
                let m = *n.iter().max().unwrap() as f64 / 32.0;
                (
                    std::array::from_fn(|a| (lo[a] - m).max(0.0)),
                    std::array::from_fn(|a| (hi[a] + m).min(full.1[a])),
                )
            }
            None => full,
        };
        let (ua, va) = match k {
            0 => (0, 1),
            1 => (2, 1),
            _ => (0, 2),
        };
        let (tw, th) = (hi[ua] - lo[ua], hi[va] - lo[va]);
        let scale = (w as f64 / tw).min(h as f64 / th);
        let (ox, oy) = (
            (w as f64 - tw * scale) / 2.0 - lo[ua] * scale,
            (h as f64 - th * scale) / 2.0 - lo[va] * scale,
        );
        let (sx, sy) = (scale, scale);
        let point = move |x: f64, y: f64| -> Option<[f64; 3]> {
            let (u, v) = ((x - ox) / sx, (y - oy) / sy);
            if !(u >= lo[ua] && v >= lo[va] && u <= hi[ua] && v <= hi[va]) {
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
