//! The 3D volume and its orbiting camera (N = 4, and N ≥ 5 after the stages): the volume,
//! maximum-intensity and first-hit renderings of [`CompositeMode`].

use super::{over, Accum, CompositeMode, CompositeOptions, Projection, Volume};
use glam::{DVec3, Vec4};
use rayon::prelude::*;

/// Occupancy blocks are BLOCK³ cells.
const BLOCK: usize = 8;

/// A 3D volume in cell coordinates p = (column, row, slice) ∈ [0, nx] × [0, ny] × [0, nz],
/// stored with one extra cell on every side that repeats the edge cell, so that trilinear
/// sampling clamped to the edge cells needs no per-axis clamping.
pub(super) struct Grid {
    pub(super) n: [usize; 3],
    /// (nx + 2) × (ny + 2) × (nz + 2) cells; cell (x, y, z) is at padded (x + 1, y + 1, z + 1).
    cells: Vec<Vec4>,
    /// Index strides of the padded y and z axes.
    sy: usize,
    sz: usize,
    /// Upper clamp of padded sample coordinates, n + ½ (a ray is clipped to [0, n]).
    qmax: [f32; 3],
    /// Per block: does any cell within one cell of the block have alpha > 0? Then every
    /// trilinear sample at a point of an unmarked block is zero.
    pub(super) occupied: Vec<bool>,
    blocks: [usize; 3],
}

impl Grid {
    pub(super) fn new(vol: &Volume) -> Self {
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

    /// The bounding box, in cell coordinates, of the cells with alpha > 0 (`None` if none).
    #[cfg(test)]
    pub(super) fn occupied_box(&self) -> Option<([f64; 3], [f64; 3])> {
        occupied_box(self.n, |x, y, z| self.cell(x, y, z)[3])
    }

    #[inline(always)]
    fn cell(&self, x: usize, y: usize, z: usize) -> [f32; 4] {
        self.cells[(x + 1) + self.sy * (y + 1) + self.sz * (z + 1)].to_array()
    }

    /// Trilinear sample at `p` (cell centres at half-integers), clamped to the edge cells.
    #[inline(always)]
    pub(super) fn sample(&self, p: [f32; 3]) -> Vec4 {
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
    pub(super) fn occupied_runs(
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

/// The bounding box, in cell coordinates, of the cells (x, y, z) < `n` whose `alpha` is > 0
/// (`None` if none).
pub(super) fn occupied_box(
    n: [usize; 3],
    alpha: impl Fn(usize, usize, usize) -> f32,
) -> Option<([f64; 3], [f64; 3])> {
    let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
    for z in 0..n[2] {
        for y in 0..n[1] {
            for x in 0..n[0] {
                if alpha(x, y, z) > 0.0 {
                    for (k, v) in [x, y, z].into_iter().enumerate() {
                        lo[k] = lo[k].min(v);
                        hi[k] = hi[k].max(v + 1);
                    }
                }
            }
        }
    }
    (lo[0] != usize::MAX).then(|| (lo.map(|v| v as f64), hi.map(|v| v as f64)))
}

/// The orbiting camera, in cell coordinates.
pub(super) struct Camera3 {
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
    /// The camera of `o` for a volume of `n` cells, looking at the centre of `frame` (a box in
    /// cell coordinates; the whole volume [0, n] when `None`), `distance` counting in the
    /// frame's half-diagonals.
    pub(super) fn new(
        n: [usize; 3],
        frame: Option<([f64; 3], [f64; 3])>,
        o: &CompositeOptions,
    ) -> Self {
        let c = 2.0 / *n.iter().max().unwrap() as f64;
        // The frame's half-extent in world units (x right, y up, z slices).
        let half = match frame {
            None => DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64) * (c / 2.0),
            Some((lo, hi)) => DVec3::new(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) * (c / 2.0),
        };
        let radius = half.length();
        let (az, el) = (o.azimuth.to_radians(), o.elevation.to_radians());
        let to_eye = DVec3::new(az.sin() * el.cos(), el.sin(), -az.cos() * el.cos());
        let fwd_w = -to_eye;
        let right_w = DVec3::new(az.cos(), 0.0, az.sin());
        let up_w = fwd_w.cross(right_w);
        // World (x right, y up, z slices) → cell coordinates (column, row, slice).
        let to_cell_dir = |v: DVec3| DVec3::new(v.x, -v.y, v.z);
        let eye_w = to_eye * (o.distance * radius);
        let eye = match frame {
            None => DVec3::new(eye_w.x + half.x, half.y - eye_w.y, eye_w.z + half.z) / c,
            Some((lo, hi)) => {
                DVec3::new(lo[0] + hi[0], lo[1] + hi[1], lo[2] + hi[2]) * 0.5
                    + DVec3::new(eye_w.x, -eye_w.y, eye_w.z) / c
            }
        };
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

    /// The picture position (x right, y down, in pixels: pixel (i, j) spans [i, i + 1] ×
    /// [j, j + 1]) of the point `p` (cell coordinates) and its distance along the view
    /// direction, or `None` for a point not in front of a perspective eye. The inverse of
    /// [`Camera3::ray`].
    pub(super) fn project(&self, p: DVec3) -> Option<([f64; 2], f64)> {
        let v = p - self.eye;
        let z = v.dot(self.fwd);
        let (sx, sy) = if self.ortho {
            (v.dot(self.right), v.dot(self.up))
        } else {
            if !(z > 1e-9) {
                return None;
            }
            (v.dot(self.right) / z, v.dot(self.up) / z)
        };
        Some((
            [
                sx / self.pixel + self.w as f64 / 2.0,
                self.h as f64 / 2.0 - sy / self.pixel,
            ],
            z,
        ))
    }

    /// The unit direction of the view ray through `p` (cell coordinates).
    pub(super) fn view_direction(&self, p: DVec3) -> DVec3 {
        if self.ortho {
            self.fwd
        } else {
            (p - self.eye).normalize_or(self.fwd)
        }
    }

    /// Distance of `p` (cell coordinates) along the view direction from the eye.
    pub(super) fn view_distance(&self, p: DVec3) -> f64 {
        (p - self.eye).dot(self.fwd)
    }

    /// The distance along the view direction of the plane below which a perspective eye sees
    /// nothing: pieces of lines are clipped to [`Camera3::view_distance`] ≥ this before
    /// [`Camera3::project`].
    pub(super) fn near(&self) -> f64 {
        if self.ortho {
            f64::NEG_INFINITY
        } else {
            1e-6
        }
    }

    /// The ray through the centre of pixel (px, py): origin, unit direction (cell units) and
    /// whether t must stay ≥ 0.
    #[inline]
    pub(super) fn ray(&self, px: usize, py: usize) -> (DVec3, DVec3, bool) {
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

#[cfg(test)]
/// The box of the camera's framing: the occupied cells' bounding box with `fit`, else none (the
/// whole volume).
pub(super) fn frame(grid: &Grid, o: &CompositeOptions) -> Option<([f64; 3], [f64; 3])> {
    if !o.fit {
        return None;
    }
    grid.occupied_box()
}

/// The parameter interval of the ray inside the box [0, n].
pub(super) fn clip_box(
    o: DVec3,
    d: DVec3,
    n: [usize; 3],
    forward_only: bool,
) -> Option<(f64, f64)> {
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
pub(super) const TILE: usize = 16;

#[cfg(test)]
pub(super) fn render_3d(
    grid: &Grid,
    mode: CompositeMode,
    o: &CompositeOptions,
    bg: [f32; 3],
) -> Vec<f32> {
    let cam = Camera3::new(grid.n, frame(grid, o), o);
    render_view(grid, &cam, mode, o, bg, false).0
}

/// Renders `grid` through `cam`: RGBA over `bg` (row-major) and, when `half` is asked for, per
/// pixel the distance along the view direction at which the opacity reached ½ (the volume
/// mode; the surface for first-hit; infinite if never), which the edge overlay uses to fade
/// edges behind dense content.
pub(super) fn render_view(
    grid: &Grid,
    cam: &Camera3,
    mode: CompositeMode,
    o: &CompositeOptions,
    bg: [f32; 3],
    half: bool,
) -> (Vec<f32>, Option<Vec<f32>>) {
    let (w, h) = o.size;
    let step = o.step;
    let mut img = vec![0f32; w * h * 4];
    let mut halves = vec![f32::INFINITY; w * h];
    let iso = FIRST_HIT_ALPHA * (o.opacity as f32).min(1.0);
    img.par_chunks_mut(w * 4 * TILE)
        .zip(halves.par_chunks_mut(w * TILE))
        .enumerate()
        .for_each(|(band, (rows, band_halves))| {
            let nrows = rows.len() / (w * 4);
            for tx in (0..w).step_by(TILE) {
                for r in 0..nrows {
                    let py = band * TILE + r;
                    for px in tx..(tx + TILE).min(w) {
                        let (org, dir, fwd_only) = cam.ray(px, py);
                        let (v, th) = match clip_box(org, dir, grid.n, fwd_only) {
                            None => ([0.0; 4], f32::INFINITY),
                            Some((t0, t1)) => match mode {
                                CompositeMode::Volume => march(grid, org, dir, t0, t1, step),
                                CompositeMode::Mip => (mip(grid, org, dir, t0, t1), f32::INFINITY),
                                _ => first_hit(grid, org, dir, t0, t1, step, iso),
                            },
                        };
                        let i = (r * w + px) * 4;
                        rows[i..i + 4].copy_from_slice(&over(v, bg));
                        // As a distance along the view direction, as the overlay measures.
                        band_halves[r * w + px] = th * dir.dot(cam.fwd) as f32;
                    }
                }
            }
        });
    (img, half.then_some(halves))
}

/// Volume mode: emission–absorption at the midpoints t_j = t0 + (j + ½)·step of the ⌊L/step⌋
/// whole steps that fit in the ray's segment [t0, t1] of L cells, plus one sample at the
/// middle of the remainder (weighted by its length); samples in unoccupied blocks (all zero)
/// are skipped.
fn march(grid: &Grid, o: DVec3, d: DVec3, t0: f64, t1: f64, step: f64) -> ([f32; 4], f32) {
    let len = t1 - t0;
    let whole = (len / step + 1e-9).floor() as usize;
    let rem = len - whole as f64 * step;
    let n = whole + usize::from(rem > 1e-6 * step);
    let t_last = t0 + whole as f64 * step + 0.5 * rem;
    let mut acc = Accum::EMPTY;
    let mut t_half = f32::INFINITY;
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
            if t_half.is_infinite() && acc.trans <= 0.5 {
                t_half = if j < whole {
                    (t0 + (j as f64 + 0.5) * step) as f32
                } else {
                    t_last as f32
                };
            }
            if acc.done() {
                return true;
            }
        }
        false
    });
    (acc.rgba(), t_half)
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

/// First-hit mode: the surface where the trilinearly interpolated alpha first reaches `iso`
/// ([`FIRST_HIT_ALPHA`] times the `opacity`, at most 1) along the ray (found every `step` cells, then refined by bisection),
/// opaque in the interpolated cells' straight colour there: a smooth iso-surface of the
/// coverage, not a staircase of cubes. A ray that never reaches it shows nothing.
fn first_hit(
    grid: &Grid,
    o: DVec3,
    d: DVec3,
    t0: f64,
    t1: f64,
    step: f64,
    iso: f32,
) -> ([f32; 4], f32) {
    let at = |t: f64| {
        let p = o + d * t;
        grid.sample([p.x as f32, p.y as f32, p.z as f32])
    };
    // Samples on the lattice t_j = t0 + j·step (the same whichever blocks are skipped, as
    // every sample in an unoccupied block is zero), then bisection between t_{j−1} and t_j.
    let mut hit = ([0f32; 4], f32::INFINITY);
    grid.occupied_runs(o, d, t0, t1, |ta, tb| {
        let mut j = ((ta - t0) / step).ceil().max(0.0) as usize;
        loop {
            let t = t0 + j as f64 * step;
            if t > tb || t > t1 {
                return false;
            }
            let s = at(t);
            if s.w >= iso {
                let (mut a, mut b, mut best) = ((t - step).max(t0), t, s);
                for _ in 0..FIRST_HIT_BISECTIONS {
                    let mid = 0.5 * (a + b);
                    let sm = at(mid);
                    if sm.w >= iso {
                        (b, best) = (mid, sm);
                    } else {
                        a = mid;
                    }
                }
                hit = (
                    [best.x / best.w, best.y / best.w, best.z / best.w, 1.0],
                    b as f32,
                );
                return true;
            }
            j += 1;
        }
    });
    hit
}

/// The coverage at which the first-hit mode sees a surface.
pub const FIRST_HIT_ALPHA: f32 = 0.5;
/// Bisection steps refining a first-hit surface (to step / 2^8).
const FIRST_HIT_BISECTIONS: usize = 8;
