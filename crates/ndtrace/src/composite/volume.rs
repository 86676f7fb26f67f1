//! The 3D volume and its orbiting camera (N = 4, and N ≥ 5 after the stages): the volume,
//! maximum-intensity and first-hit renderings of [`CompositeMode`].

use super::{over, Accum, CompositeMode, CompositeOptions, Volume};
use crate::camera::Projection;
use glam::{DVec3, Vec4};
use rayon::prelude::*;

/// Occupancy blocks are BLOCK³ cells.
const BLOCK: usize = 8;

/// A 3D volume in cell coordinates p = (column, row, slice) ∈ [0, nx] × [0, ny] × [0, nz],
/// of which only the part around the cells with alpha > 0 is stored (every sample outside it
/// is zero), with one extra cell on every side that repeats the edge cell, so that trilinear
/// sampling clamped to the edge cells needs no per-axis clamping.
pub(super) struct Grid {
    /// The whole volume's cells: rays are clipped to [0, n], so the samples along a ray do not
    /// depend on which part is stored.
    pub(super) n: [usize; 3],
    /// The stored part: cells `lo .. lo + m`.
    lo: [usize; 3],
    m: [usize; 3],
    /// `lo` as floats.
    lo_f: [f32; 3],
    /// (mx + 2) × (my + 2) × (mz + 2) cells; stored cell (x, y, z) is at padded (x + 1, y + 1,
    /// z + 1).
    cells: Vec<Vec4>,
    /// Index strides of the padded y and z axes.
    sy: usize,
    sz: usize,
    /// Upper clamp of padded sample coordinates, m + ½.
    qmax: [f32; 3],
    /// Per block of the stored part: does any cell within one cell of the block have alpha > 0?
    /// Then every trilinear sample at a point of an unmarked block is zero.
    pub(super) occupied: Vec<bool>,
    blocks: [usize; 3],
}

impl Grid {
    /// The grid of a 3D volume (numpy order), storing the box of its cells with alpha > 0
    /// grown by one cell (so the stored part's faces are empty, and samples beyond them are
    /// zero, as in the whole volume).
    pub(super) fn new(vol: &Volume) -> Self {
        let n = [vol.shape[2], vol.shape[1], vol.shape[0]];
        Self::placed(vol, [0; 3], n)
    }

    /// [`Grid::new`] of a volume that is the part of a larger one of `n` cells starting at cell
    /// `origin` (cell coordinates); every cell of the larger one outside it has alpha 0.
    pub(super) fn placed(vol: &Volume, origin: [usize; 3], n: [usize; 3]) -> Self {
        let part = [vol.shape[2], vol.shape[1], vol.shape[0]];
        let (lo, m) = match occupied_box(part, |x, y, z| {
            vol.cells[x + part[0] * (y + part[1] * z)][3]
        }) {
            Some((a, b)) => {
                let a = a.map(|v| (v as usize).saturating_sub(1));
                let b: [usize; 3] = std::array::from_fn(|k| (b[k] as usize + 1).min(part[k]));
                (a, std::array::from_fn(|k| b[k] - a[k]))
            }
            None => ([0; 3], [1; 3]),
        };
        Self::stored(vol, lo, m, origin, n)
    }

    /// The grid storing the cells `lo .. lo + m` of `vol` (a part of the larger volume of `n`
    /// cells, at `origin`).
    fn stored(
        vol: &Volume,
        lo: [usize; 3],
        m: [usize; 3],
        origin: [usize; 3],
        n: [usize; 3],
    ) -> Self {
        let part = [vol.shape[2], vol.shape[1], vol.shape[0]];
        let at = |x: usize, y: usize, z: usize| {
            vol.cells[(lo[0] + x) + part[0] * ((lo[1] + y) + part[1] * (lo[2] + z))]
        };
        let blocks = m.map(|r| r.div_ceil(BLOCK));
        let mut occupied = vec![false; blocks[0] * blocks[1] * blocks[2]];
        for z in 0..m[2] {
            for y in 0..m[1] {
                for x in 0..m[0] {
                    if at(x, y, z)[3] > 0.0 {
                        let r = |i: usize, k: usize| {
                            (i.saturating_sub(1) / BLOCK)..=((i + 1).min(m[k] - 1) / BLOCK)
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
        let (px, py, pz) = (m[0] + 2, m[1] + 2, m[2] + 2);
        let mut cells = vec![Vec4::ZERO; px * py * pz];
        cells
            .par_chunks_mut(px * py)
            .enumerate()
            .for_each(|(zp, slab)| {
                let z = zp.clamp(1, m[2]) - 1;
                for yp in 0..py {
                    let y = yp.clamp(1, m[1]) - 1;
                    for xp in 0..px {
                        slab[xp + px * yp] = Vec4::from_array(at(xp.clamp(1, m[0]) - 1, y, z));
                    }
                }
            });
        let lo: [usize; 3] = std::array::from_fn(|k| origin[k] + lo[k]);
        Grid {
            n,
            lo,
            m,
            lo_f: lo.map(|v| v as f32),
            cells,
            sy: px,
            sz: px * py,
            qmax: m.map(|r| r as f32 + 0.5),
            occupied,
            blocks,
        }
    }

    /// The box of the stored part, in cell coordinates of the whole volume.
    pub(super) fn stored_box(&self) -> (DVec3, DVec3) {
        let lo = DVec3::new(self.lo[0] as f64, self.lo[1] as f64, self.lo[2] as f64);
        (
            lo,
            lo + DVec3::new(self.m[0] as f64, self.m[1] as f64, self.m[2] as f64),
        )
    }

    /// The grid storing every cell of `vol` (what [`Grid::new`] stores a part of).
    #[cfg(test)]
    pub(super) fn whole(vol: &Volume) -> Self {
        let n = [vol.shape[2], vol.shape[1], vol.shape[0]];
        Self::stored(vol, [0; 3], n, [0; 3], n)
    }

    /// The bounding box, in cell coordinates, of the cells with alpha > 0 (`None` if none).
    #[cfg(test)]
    pub(super) fn occupied_box(&self) -> Option<([f64; 3], [f64; 3])> {
        let (lo, hi) = occupied_box(self.m, |x, y, z| self.cell(x, y, z)[3])?;
        let at = |v: [f64; 3]| std::array::from_fn(|k| v[k] + self.lo[k] as f64);
        Some((at(lo), at(hi)))
    }

    /// Stored cell (x, y, z) (counted from `lo`).
    #[inline(always)]
    fn cell(&self, x: usize, y: usize, z: usize) -> [f32; 4] {
        self.cells[(x + 1) + self.sy * (y + 1) + self.sz * (z + 1)].to_array()
    }

    /// Cell `c` of the whole volume (x, y, z from 0), zero outside the stored part.
    #[inline]
    pub(super) fn cell_at(&self, c: [i64; 3]) -> [f32; 4] {
        let mut local = [0usize; 3];
        for k in 0..3 {
            let v = c[k] - self.lo[k] as i64;
            if v < 0 || v >= self.m[k] as i64 {
                return [0.0; 4];
            }
            local[k] = v as usize;
        }
        self.cell(local[0], local[1], local[2])
    }

    /// Trilinear sample at `p` (cell centres at half-integers), clamped to the edge cells.
    #[inline(always)]
    pub(super) fn sample(&self, p: [f32; 3]) -> Vec4 {
        // Padded coordinates: the centre of cell i is at i + 1.5, so the lower of the two
        // cells around p is ⌊p + ½⌋ (padded) and the fraction is the rest.
        let q = |k: usize| {
            // p + ½ first, then the stored part's origin (an integer, so exactly): the same
            // cells and fractions as in the whole volume.
            let v = (p[k] + 0.5) - self.lo_f[k];
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
        // The part of [t0, t1] in the stored part, walked in its coordinates.
        let lo = DVec3::new(self.lo[0] as f64, self.lo[1] as f64, self.lo[2] as f64);
        let Some((a, b)) = clip_box(o - lo, d, self.m, false) else {
            return;
        };
        let (t0, t1) = (t0.max(a), t1.min(b));
        if !(t1 > t0) {
            return;
        }
        let mut run: Option<f64> = None;
        let mut stopped = false;
        walk_cells(o - lo, d, t0, t1, BLOCK as f64, self.blocks, |c, t_in| {
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
    /// The view direction (unit), cell coordinates.
    pub(super) fwd: DVec3,
    right: DVec3,
    up: DVec3,
    /// Image-plane units per pixel (at unit distance for perspective).
    pixel: f64,
    /// The picture position of the view axis, pixels: the picture's centre unless
    /// [`Camera3::centred_on`] moved it.
    centre: [f64; 2],
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
            centre: [w as f64 / 2.0, h as f64 / 2.0],
        }
    }

    /// The camera with its view axis moved in the picture so that the box of the projections
    /// of `points` (cell coordinates) is centred: equal margins left and right, top and
    /// bottom. Unchanged when no point projects.
    pub(super) fn centred_on(mut self, points: &[DVec3]) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &p in points {
            if let Some((q, _)) = self.project(p) {
                for k in 0..2 {
                    lo[k] = lo[k].min(q[k]);
                    hi[k] = hi[k].max(q[k]);
                }
            }
        }
        if lo[0].is_finite() && lo[1].is_finite() {
            let target = [self.w as f64 / 2.0, self.h as f64 / 2.0];
            for k in 0..2 {
                self.centre[k] += target[k] - (lo[k] + hi[k]) / 2.0;
            }
        }
        self
    }

    /// The camera's right, up and forward directions, unit, in cell coordinates (column, row,
    /// slice: y down the rows).
    pub(super) fn basis(&self) -> (DVec3, DVec3, DVec3) {
        (self.right, self.up, self.fwd)
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
                sx / self.pixel + self.centre[0],
                self.centre[1] - sy / self.pixel,
            ],
            z,
        ))
    }

    /// The eye (perspective) or the centre of the view plane (orthographic), cell coordinates.
    pub(super) fn eye(&self) -> DVec3 {
        self.eye
    }

    /// The unit view direction (cell coordinates).
    pub(super) fn forward(&self) -> DVec3 {
        self.fwd
    }

    /// Whether the camera is orthographic.
    pub(super) fn orthographic(&self) -> bool {
        self.ortho
    }

    /// The picture's size (W, H) in pixels.
    pub(super) fn size(&self) -> (usize, usize) {
        (self.w, self.h)
    }

    /// The displacements (cell coordinates) of one picture pixel to the right and one down, at
    /// the depth of `p`.
    pub(super) fn pixel_steps(&self, p: DVec3) -> (DVec3, DVec3) {
        let k = if self.ortho {
            self.pixel
        } else {
            self.pixel * self.view_distance(p)
        };
        (self.right * k, self.up * -k)
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
        self.ray_at(px as f64 + 0.5, py as f64 + 0.5)
    }

    /// The ray through the picture point (x, y) (pixels, x right and y down; pixel (i, j)
    /// spans [i, i + 1] × [j, j + 1]): origin, unit direction (cell units) and whether t must
    /// stay ≥ 0.
    #[inline]
    pub(super) fn ray_at(&self, x: f64, y: f64) -> (DVec3, DVec3, bool) {
        let sx = (x - self.centre[0]) * self.pixel;
        let sy = (self.centre[1] - y) * self.pixel;
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
///
/// Rays are cast through the pixels of a lattice every s pixels ([`lattice_spacing`]: at most
/// `rays_per_cell` rays to a cell where cells look smallest, s ≤ 16), and each s × s block
/// between four lattice pixels is filled by bilinear interpolation of its corners where the
/// picture is smooth there ([`smooth_block`], then its traced middle pixel), else split into
/// quarters at traced side and middle pixels, recursively, down to single pixels. Every
/// decision depends only on pixels traced for the block itself, so the picture is the same
/// for any number of threads; with s = 1 every pixel is traced.
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
    let iso = FIRST_HIT_ALPHA * (o.opacity as f32).min(1.0);
    // The picture's RGBA over `bg` at pixel (px, py), and its half-opacity distance.
    let pixel = |px: usize, py: usize| -> ([f32; 4], f32) {
        let (org, dir, fwd_only) = cam.ray(px, py);
        let (v, th) = match clip_box(org, dir, grid.n, fwd_only) {
            None => ([0.0; 4], f32::INFINITY),
            Some((t0, t1)) => match mode {
                CompositeMode::Volume => march(grid, org, dir, t0, t1, step),
                CompositeMode::Mip => (mip(grid, org, dir, t0, t1), f32::INFINITY),
                _ => first_hit(grid, org, dir, t0, t1, step, iso),
            },
        };
        // As a distance along the view direction, as the overlay measures.
        (over(v, bg), th * dir.dot(cam.fwd) as f32)
    };
    let mut img = vec![0f32; w * h * 4];
    let mut halves = vec![f32::INFINITY; w * h];
    // A maximum-intensity picture is a mosaic of the cells' colours, nothing to interpolate.
    let s = match mode {
        CompositeMode::Mip => 1,
        _ => lattice_spacing(cam, grid.stored_box(), o.rays_per_cell),
    };
    if s == 1 {
        img.par_chunks_mut(w * 4 * TILE)
            .zip(halves.par_chunks_mut(w * TILE))
            .enumerate()
            .for_each(|(band, (rows, band_halves))| {
                let nrows = rows.len() / (w * 4);
                for tx in (0..w).step_by(TILE) {
                    for r in 0..nrows {
                        for px in tx..(tx + TILE).min(w) {
                            let (v, th) = pixel(px, band * TILE + r);
                            rows[(r * w + px) * 4..][..4].copy_from_slice(&v);
                            band_halves[r * w + px] = th;
                        }
                    }
                }
            });
        return (img, half.then_some(halves));
    }
    // 1. The lattice: pixels 0, s, 2s, … and the last one on each axis.
    let stops = |len: usize| -> Vec<usize> {
        let mut v: Vec<usize> = (0..len).step_by(s).collect();
        if *v.last().unwrap() != len - 1 {
            v.push(len - 1);
        }
        v
    };
    let (xs, ys) = (stops(w), stops(h));
    let lattice: Vec<([f32; 4], f32)> = ys
        .par_iter()
        .flat_map_iter(|&py| xs.iter().map(move |&px| (px, py)))
        .map(|(px, py)| pixel(px, py))
        .collect();
    let at = |i: usize, j: usize| &lattice[j * xs.len() + i];
    // 2. The blocks, one band of them (image rows ys[j] .. ys[j + 1], the last band with its
    //    closing row) per unit of parallel work.
    let mut bands: Vec<(usize, &mut [f32], &mut [f32])> = Vec::with_capacity(ys.len());
    let (mut img_rest, mut half_rest) = (&mut img[..], &mut halves[..]);
    for j in 0..ys.len().saturating_sub(1) {
        let rows = if j + 2 == ys.len() {
            h - ys[j]
        } else {
            ys[j + 1] - ys[j]
        };
        let (a, b) = std::mem::take(&mut img_rest).split_at_mut(rows * w * 4);
        let (c, d) = std::mem::take(&mut half_rest).split_at_mut(rows * w);
        bands.push((j, a, c));
        (img_rest, half_rest) = (b, d);
    }
    if ys.len() == 1 {
        // A picture one pixel high: the lattice row is the picture.
        bands.push((0, img_rest, half_rest));
    }
    bands.into_par_iter().for_each(|(j, rows, band_halves)| {
        let y0 = ys[j];
        let nrows = rows.len() / (w * 4);
        let mut put = |px: usize, py: usize, (v, th): ([f32; 4], f32)| {
            let r = py - y0;
            rows[(r * w + px) * 4..][..4].copy_from_slice(&v);
            band_halves[r * w + px] = th;
        };
        if ys.len() == 1 || xs.len() == 1 {
            for py in y0..y0 + nrows {
                for px in 0..w {
                    put(px, py, pixel(px, py));
                }
            }
            return;
        }
        for i in 0..xs.len() - 1 {
            let (x0, x1) = (xs[i], xs[i + 1]);
            let y1 = ys[j + 1];
            let block = Block {
                x: [x0, x1],
                y: [y0, y1],
                corners: [*at(i, j), *at(i + 1, j), *at(i, j + 1), *at(i + 1, j + 1)],
            };
            // The block's pixels: up to x1 and y1, and x1 (y1) itself in the last column (row).
            let own = [if i + 2 == xs.len() { x1 + 1 } else { x1 }, y0 + nrows];
            let lattice_smooth = smooth_block(&lattice, xs.len(), ys.len(), i, j, half);
            block.render(lattice_smooth, own, half, &pixel, &mut put);
        }
    });
    (img, half.then_some(halves))
}

/// A block of the picture between four traced pixels (its corners): x0 y0, x1 y0, x0 y1, x1 y1.
struct Block {
    x: [usize; 2],
    y: [usize; 2],
    corners: [([f32; 4], f32); 4],
}

impl Block {
    /// Puts the pixels of the block below `own` (exclusive ends, x then y): interpolated when
    /// the block is smooth (`smooth`, and its traced middle pixel agrees with its interpolation
    /// within [`SMOOTH_MIDDLE`]), else split at its middle into four blocks, each rendered
    /// so, down to blocks whose every pixel is a corner.
    fn render(
        &self,
        smooth: bool,
        own: [usize; 2],
        half: bool,
        pixel: &impl Fn(usize, usize) -> ([f32; 4], f32),
        put: &mut impl FnMut(usize, usize, ([f32; 4], f32)),
    ) {
        let ([x0, x1], [y0, y1]) = (self.x, self.y);
        let c = &self.corners;
        let (xm, ym) = ((x0 + x1) / 2, (y0 + y1) / 2);
        if xm == x0 && ym == y0 {
            // No pixel inside: the corners (those the block owns) are the block.
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
        let mid = pixel(xm, ym);
        let smooth = smooth
            && one_kind_of_distance(c.iter(), half)
            && close(
                &mid,
                &bilinear(c, fraction(xm, x0, x1), fraction(ym, y0, y1)),
                half,
            );
        if smooth {
            for py in y0..own[1] {
                let fy = fraction(py, y0, y1);
                for px in x0..own[0] {
                    put(px, py, bilinear(c, fraction(px, x0, x1), fy));
                }
            }
            return;
        }
        // The four quarters, with the pixels at the middles of the block's sides.
        let top = pixel(xm, y0);
        let bottom = pixel(xm, y1);
        let left = pixel(x0, ym);
        let right = pixel(x1, ym);
        let quarters = [
            ([x0, xm], [y0, ym], [c[0], top, left, mid]),
            ([xm, x1], [y0, ym], [top, c[1], mid, right]),
            ([x0, xm], [ym, y1], [left, mid, c[2], bottom]),
            ([xm, x1], [ym, y1], [mid, right, bottom, c[3]]),
        ];
        for (x, y, corners) in quarters {
            // A quarter owns up to the next quarter, or what the block owns.
            let own_q = [
                if x[1] == x1 { own[0] } else { x[1] },
                if y[1] == y1 { own[1] } else { y[1] },
            ];
            if x[0] >= own_q[0] || y[0] >= own_q[1] {
                continue;
            }
            Block { x, y, corners }.render(true, own_q, half, pixel, put);
        }
    }
}

/// The lattice spacing s ≥ 1 of [`render_view`] for at most `rays_per_cell` rays across a cell
/// where the cells of the box `(lo, hi)` (cell coordinates: the part of the volume that is not
/// empty) look smallest, at its corner farthest from a perspective eye; 1 when `rays_per_cell`
/// is 0.
pub(super) fn lattice_spacing(
    cam: &Camera3,
    (lo, hi): (DVec3, DVec3),
    rays_per_cell: usize,
) -> usize {
    if rays_per_cell == 0 {
        return 1;
    }
    let far = if cam.ortho {
        1.0
    } else {
        (0..8)
            .map(|c: usize| {
                let pick = |bit: usize, k: usize| if c >> bit & 1 == 0 { lo[k] } else { hi[k] };
                (DVec3::new(pick(0, 0), pick(1, 1), pick(2, 2)) - cam.eye).length()
            })
            .fold(0.0, f64::max)
    };
    // Pixels across one cell at that distance.
    let pixels = 1.0 / (cam.pixel * far);
    ((pixels / rays_per_cell as f64).floor() as usize).clamp(1, MAX_LATTICE_SPACING)
}

/// Largest lattice spacing of [`render_view`], in pixels.
const MAX_LATTICE_SPACING: usize = 16;

/// Largest second difference, across three neighbouring lattice pixels, of a channel of a
/// block's corners (colour as √RGB, which follows perceived lightness; alpha as it is) for
/// the block to be interpolated: bilinear interpolation then errs by about an eighth of it.
const SMOOTH_SECOND_DIFFERENCE: f32 = 0.02;

/// Whether block (i, j) of a `cols` × `rows` lattice (row-major) is smooth enough to
/// interpolate: at each of its four corners, along both axes, the second differences of
/// every channel over the corner's lattice neighbours stay under
/// [`SMOOTH_SECOND_DIFFERENCE`], and (with `half`) its corners' half-opacity distances are
/// all finite or all infinite.
fn smooth_block(
    lattice: &[([f32; 4], f32)],
    cols: usize,
    rows: usize,
    i: usize,
    j: usize,
    half: bool,
) -> bool {
    let at = |i: usize, j: usize| &lattice[j * cols + i];
    let corners = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)];
    if !one_kind_of_distance(corners.iter().map(|&(a, b)| at(a, b)), half) {
        return false;
    }
    let second = |a: &([f32; 4], f32), b: &([f32; 4], f32), c: &([f32; 4], f32)| {
        let (a, b, c) = (perceptual(&a.0), perceptual(&b.0), perceptual(&c.0));
        (0..4).all(|k| (a[k] - 2.0 * b[k] + c[k]).abs() <= SMOOTH_SECOND_DIFFERENCE)
    };
    corners.iter().all(|&(a, b)| {
        let along_x = a == 0 || a + 1 == cols || second(at(a - 1, b), at(a, b), at(a + 1, b));
        let along_y = b == 0 || b + 1 == rows || second(at(a, b - 1), at(a, b), at(a, b + 1));
        along_x && along_y
    })
}

/// Largest difference, in a channel (colour as √RGB, alpha as it is), between a block's
/// traced middle pixel and its interpolation for the block to be interpolated: about two
/// levels of an 8-bit sRGB picture at mid-grey.
const SMOOTH_MIDDLE: f32 = 0.008;

/// Whether the traced pixel `a` and its interpolation `b` agree within [`SMOOTH_MIDDLE`] (and,
/// with `half`, their half-opacity distances are both finite or both infinite).
/// Whether the pixels' half-opacity distances are all finite or all infinite (always, when
/// they are not wanted): a block mixing them holds a silhouette of the edge overlay's depth
/// and is not interpolated.
fn one_kind_of_distance<'a>(
    mut pixels: impl Iterator<Item = &'a ([f32; 4], f32)>,
    half: bool,
) -> bool {
    if !half {
        return true;
    }
    match pixels.next() {
        Some(first) => {
            let finite = first.1.is_finite();
            pixels.all(|p| p.1.is_finite() == finite)
        }
        None => true,
    }
}

fn close(a: &([f32; 4], f32), b: &([f32; 4], f32), half: bool) -> bool {
    let (pa, pb) = (perceptual(&a.0), perceptual(&b.0));
    (!half || a.1.is_finite() == b.1.is_finite())
        && (0..4).all(|k| (pa[k] - pb[k]).abs() <= SMOOTH_MIDDLE)
}

/// A pixel's channels as the smoothness tests compare them: colour as √RGB (about perceived
/// lightness), alpha as it is.
#[inline]
fn perceptual(v: &[f32; 4]) -> [f32; 4] {
    [
        v[0].max(0.0).sqrt(),
        v[1].max(0.0).sqrt(),
        v[2].max(0.0).sqrt(),
        v[3],
    ]
}

/// Bilinear interpolation of the corners (x0 y0, x1 y0, x0 y1, x1 y1) at fractions (fx, fy);
/// the half-opacity distance is interpolated when all four are finite.
#[inline]
fn bilinear(c: &[([f32; 4], f32); 4], fx: f32, fy: f32) -> ([f32; 4], f32) {
    let w = [
        (1.0 - fx) * (1.0 - fy),
        fx * (1.0 - fy),
        (1.0 - fx) * fy,
        fx * fy,
    ];
    let mut v = [0f32; 4];
    for (k, out) in v.iter_mut().enumerate() {
        *out = w[0] * c[0].0[k] + w[1] * c[1].0[k] + w[2] * c[2].0[k] + w[3] * c[3].0[k];
    }
    let th = if c.iter().all(|c| c.1.is_finite()) {
        w[0] * c[0].1 + w[1] * c[1].1 + w[2] * c[2].1 + w[3] * c[3].1
    } else {
        f32::INFINITY
    };
    (v, th)
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
        // The run's samples accumulate into local copies (kept in registers: the captured
        // `acc` would be read and written through memory at every sample).
        let (mut a, mut th) = (acc, t_half);
        let mut stop = false;
        for j in j0..j1 {
            if j < whole {
                let jf = j as i32 as f32;
                let p = [
                    start[0] + jf * delta[0],
                    start[1] + jf * delta[1],
                    start[2] + jf * delta[2],
                ];
                a.add(grid.sample(p), stepf);
            } else {
                let p = o + d * t_last;
                a.add(grid.sample([p.x as f32, p.y as f32, p.z as f32]), remf);
            }
            if th.is_infinite() && a.trans <= 0.5 {
                th = if j < whole {
                    (t0 + (j as f64 + 0.5) * step) as f32
                } else {
                    t_last as f32
                };
            }
            if a.done() {
                stop = true;
                break;
            }
        }
        (acc, t_half) = (a, th);
        stop
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
    let lo = DVec3::new(grid.lo[0] as f64, grid.lo[1] as f64, grid.lo[2] as f64);
    walk_cells(o - lo, d, t0, t1, 1.0, grid.m, |c, _| {
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
