//! The illustrative mode: a retina composited so that its structure reads, not its outside.
//!
//! An opaque volume render of a 4D retina shows only the outer surface of the retina block, so
//! a tesseract looks like a cube. The course notes say what a 4D picture should carry instead:
//! "volume rendered projections of 4D lit hypersurfaces to 3D contain information similar to
//! \[a\] 2D magazine photo" (shape from shading), with the "new cues: ridges, occlusion edges,
//! depth from occlusion". Here the cells are nearly clear, keeping their 4D-lit colour, and the
//! opacity is concentrated where the retina has structure:
//!
//! * **creases** — neighbouring cells whose 4D unit normals' lines differ by more than
//!   [`CompositeOptions::crease_angle`] (by normal, not by primitive id, so the six tetrahedra
//!   of a cube's Kuhn split do not show): the images of the polytope's 2-faces between cells;
//! * **occlusion contours** — neighbouring cells that see surfaces far apart in N-D (a nearer
//!   part of the object passing in front of a farther one): with the camera known, the hit
//!   points x_i, x_j (from the cells' rays and depths) are each farther than three ray spacings
//!   from the other's tangent hyperplane (eq. 11, the point–hyperplane distance n̂·(x − x_0));
//!   without it, a relative depth jump;
//! * **silhouettes** — the boundary of the retina's occupied region, seen where it is seen
//!   edge-on (opacity ∝ (1 − |ĝ·v|)⁴ for the coverage gradient g and the view ray v, the
//!   contour enhancement of illustrative volume rendering), so the outline of the projected
//!   body shows without a fog in front of it.
//!
//! For N = 4 the cues are found once per retina (in the box of its hit cells grown by four
//! cells, their reach): the cells' (dilated) colour with their smoothed coverage, the coverage
//! gradient and the crease and occlusion opacity; each view classifies them into a
//! premultiplied volume, the silhouettes from its own view rays. For N ≥ 5 the creases and
//! occlusion contours are classified in the (N−1)-D retina into a premultiplied volume which
//! the recursive stages project, with the retina's coverage beside it; the silhouettes are
//! then those of the projected coverage, seen per view as for N = 4.

use super::{CompositeOptions, Volume};
use crate::composite::volume::Camera3;
use glam::DVec3;
use rayon::prelude::*;

/// Opacity per cell of a fully covered cell's interior, at `opacity = 1`.
pub const INTERIOR_OPACITY: f32 = 0.012;
/// Peak opacity per cell of creases and occlusion contours.
pub const CREASE_OPACITY: f32 = 0.45;
/// Opacity per cell of a silhouette surface seen face-on, and the extra opacity seen edge-on.
pub const SILHOUETTE_FACE: f32 = 0.03;
/// See [`SILHOUETTE_FACE`].
pub const SILHOUETTE_EDGE: f32 = 0.35;
/// Silhouette opacity grows with the coverage gradient's magnitude (per cell) times this, up to 1.
pub const SILHOUETTE_GAIN: f32 = 1.0;
/// The silhouette fades out where the smoothed coverage is below 1 / this (outside the body),
/// so the outline does not glow beyond it.
pub const SILHOUETTE_GATE: f32 = 4.0;
/// The crease and occlusion opacity (at most [`CREASE_OPACITY`]) is scaled by this.
pub const CREASE_GAIN: f32 = 1.3;
/// Occlusion test: hit points farther apart than this many ray spacings from each other's
/// tangent hyperplanes are on different surfaces.
pub const OCCLUSION_SPACINGS: f64 = 3.0;
/// Without a camera: a relative depth jump above this between neighbours is an occlusion.
pub const OCCLUSION_DEPTH_JUMP: f32 = 0.08;

/// What the retina's camera says about its cells: enough to rebuild each cell's hit point in
/// camera coordinates (c = Oᵀ(x − C)) and to turn world normals into camera ones.
#[derive(Debug, Clone, PartialEq)]
pub struct RetinaCamera {
    /// N×N orientation, row-major: columns u_1 … u_{N−1}, then the view direction.
    pub orientation: Vec<f64>,
    /// Side of a cell (at unit distance for perspective).
    pub cell: f64,
    /// Perspective (rays from a point) or orthographic (parallel rays).
    pub perspective: bool,
}

/// Per-cell structure flags.
const CREASE: u8 = 1;
const OCCLUSION: u8 = 2;

/// The part of a retina the cues are found in: cells `origin .. origin + shape` (numpy order)
/// of a retina of `full` cells, beyond which no cell is hit within [`CUE_REACH`] cells.
#[derive(Debug, Clone, Copy)]
pub(super) struct Window<'a> {
    pub(super) origin: &'a [usize],
    pub(super) full: &'a [usize],
}

/// How far from a hit cell the cues reach: its neighbours' flags, smoothed, their coverage
/// gradient and the trilinear samples of the view (one cell each), and an empty cell beyond.
pub(super) const CUE_REACH: usize = 4;

/// The flags of every cell: comparisons with its 2m axis neighbours.
fn flags(
    rgba: &[f32],
    depth: &[f32],
    normal: Option<&[f32]>,
    shape: &[usize],
    window: Window<'_>,
    camera: Option<&RetinaCamera>,
    crease_angle: f64,
) -> Vec<u8> {
    let m = shape.len();
    let n = m + 1;
    let cells: usize = shape.iter().product();
    let mut strides = vec![1usize; m];
    for a in (0..m.saturating_sub(1)).rev() {
        strides[a] = strides[a + 1] * shape[a + 1];
    }
    let cos_angle = crease_angle.to_radians().cos() as f32;
    let hit = |i: usize| depth[i].is_finite() && rgba[i * 4 + 3] > 0.0;
    // Hit points and normals in camera coordinates, when the camera is known.
    let frame: Option<(Vec<f64>, Vec<f64>, Vec<f64>)> = camera.zip(normal).map(|(cam, normal)| {
        let mut points = vec![0.0; cells * n];
        let mut normals = vec![0.0; cells * n];
        let mut spacing = vec![0.0; cells];
        points
            .par_chunks_mut(n)
            .zip(normals.par_chunks_mut(n))
            .zip(spacing.par_iter_mut())
            .enumerate()
            .for_each(|(i, ((x, nc), sp))| {
                if !hit(i) {
                    return;
                }
                // Retina coordinates u_k of the cell centre (camera axis k = numpy axis m−1−k).
                let mut rest = i;
                let mut u = [0.0f64; 8];
                for a in (0..m).rev() {
                    let r = shape[a];
                    let idx = rest % r + window.origin[a];
                    rest /= r;
                    let k = m - 1 - a;
                    let half = window.full[a] as f64 / 2.0;
                    u[k] = if k == 1 {
                        (half - idx as f64 - 0.5) * cam.cell
                    } else {
                        (idx as f64 + 0.5 - half) * cam.cell
                    };
                }
                let d = depth[i] as f64;
                if cam.perspective {
                    let len = (1.0 + u[..m].iter().map(|v| v * v).sum::<f64>()).sqrt();
                    for k in 0..m {
                        x[k] = d * u[k] / len;
                    }
                    x[m] = d / len;
                    *sp = cam.cell * d;
                } else {
                    x[..m].copy_from_slice(&u[..m]);
                    x[m] = d;
                    *sp = cam.cell;
                }
                for k in 0..n {
                    nc[k] = (0..n)
                        .map(|r| cam.orientation[r * n + k] * normal[i * n + r] as f64)
                        .sum();
                }
            });
        (points, normals, spacing)
    });
    let mut out = vec![0u8; cells];
    out.par_iter_mut().enumerate().for_each(|(i, f)| {
        let hi = hit(i);
        let mut rest = i;
        let mut idx = [0usize; 8];
        for a in (0..m).rev() {
            idx[a] = rest % shape[a];
            rest /= shape[a];
        }
        for a in 0..m {
            for forward in [false, true] {
                let j = match (forward, idx[a]) {
                    (false, 0) => continue,
                    (false, _) => i - strides[a],
                    (true, v) if v + 1 >= shape[a] => continue,
                    (true, _) => i + strides[a],
                };
                let hj = hit(j);
                if hi != hj {
                    // A silhouette: found from the coverage gradient, per view.
                    continue;
                }
                if !hi {
                    continue;
                }
                let occluded = match &frame {
                    Some((x, nc, sp)) => {
                        let tol = OCCLUSION_SPACINGS * sp[i].max(sp[j]);
                        let (mut di, mut dj) = (0.0, 0.0);
                        for k in 0..n {
                            let delta = x[j * n + k] - x[i * n + k];
                            di += nc[i * n + k] * delta;
                            dj += nc[j * n + k] * delta;
                        }
                        di.abs() > tol && dj.abs() > tol
                    }
                    None => {
                        let (a, b) = (depth[i], depth[j]);
                        (a - b).abs() > OCCLUSION_DEPTH_JUMP * a.min(b)
                    }
                };
                if occluded {
                    *f |= OCCLUSION;
                } else if let Some(normal) = normal {
                    let dot: f32 = (0..n).map(|k| normal[i * n + k] * normal[j * n + k]).sum();
                    if dot.abs() < cos_angle {
                        *f |= CREASE;
                    }
                }
            }
        }
    });
    out
}

/// One pass of the separable [1, 2, 1]/4 filter along every axis of `shape`, over `width`
/// channels per cell (zero outside).
fn smooth(values: &[f32], width: usize, shape: &[usize]) -> Vec<f32> {
    let mut cur = values.to_vec();
    let mut dst = vec![0f32; values.len()];
    // Along axis a the data is `outer` runs of r rows of `inner` contiguous numbers.
    let mut inner = width;
    for &r in shape.iter().rev() {
        let filter = |src: &[f32], out: &mut [f32], pos: usize| {
            // One row of `inner` numbers at `pos` from the rows of its run (`src`).
            let here = &src[pos * inner..][..inner];
            let prev = (pos > 0).then(|| &src[(pos - 1) * inner..][..inner]);
            let next = (pos + 1 < r).then(|| &src[(pos + 1) * inner..][..inner]);
            for (j, v) in out.iter_mut().enumerate() {
                let mut s = 2.0 * here[j];
                if let Some(p) = prev {
                    s += p[j];
                }
                if let Some(n) = next {
                    s += n[j];
                }
                *v = s * 0.25;
            }
        };
        if inner >= 64 {
            // Long rows: one unit of parallel work per row.
            dst.par_chunks_mut(inner).enumerate().for_each(|(k, out)| {
                let (run, pos) = (k / r, k % r);
                filter(&cur[run * r * inner..][..r * inner], out, pos);
            });
        } else {
            // Short rows (the innermost axes): one unit per run.
            dst.par_chunks_mut(r * inner)
                .zip(cur.par_chunks(r * inner))
                .for_each(|(out, src)| {
                    for (pos, row) in out.chunks_mut(inner).enumerate() {
                        filter(src, row, pos);
                    }
                });
        }
        std::mem::swap(&mut cur, &mut dst);
        inner *= r;
    }
    cur
}

/// The smoothed cues of a retina: per cell the dilated straight colour and smoothed coverage
/// (`color`, 4 floats) and the crease + occlusion opacity.
struct Cues {
    color: Vec<[f32; 4]>,
    structure: Vec<f32>,
}

fn cues(
    rgba: &[f32],
    depth: &[f32],
    normal: Option<&[f32]>,
    shape: &[usize],
    window: Window<'_>,
    camera: Option<&RetinaCamera>,
    o: &CompositeOptions,
) -> Cues {
    let cells: usize = shape.iter().product();
    let f = flags(rgba, depth, normal, shape, window, camera, o.crease_angle);
    let marks: Vec<f32> = f
        .par_iter()
        .map(|&b| f32::from(b & (CREASE | OCCLUSION) != 0))
        .collect();
    let marks = smooth(&marks, 1, shape);
    let blurred = smooth(rgba, 4, shape);
    let opacity = o.opacity as f32;
    let mut color = vec![[0f32; 4]; cells];
    color.par_iter_mut().enumerate().for_each(|(i, c)| {
        let a = rgba[i * 4 + 3];
        let b = &blurred[i * 4..i * 4 + 4];
        let (src, w) = if a >= 0.5 {
            (&rgba[i * 4..i * 4 + 3], a)
        } else {
            (&b[..3], b[3])
        };
        if w > 1e-6 {
            *c = [src[0] / w, src[1] / w, src[2] / w, b[3] * opacity];
        }
    });
    let structure = marks
        .par_iter()
        .map(|&m| (m * 1.6).min(1.0) * CREASE_OPACITY)
        .collect();
    Cues { color, structure }
}

/// Lightens (dark background) or darkens (light background) a colour by `k` ∈ [0, 1]: the ink
/// of creases and silhouettes.
#[inline]
pub(super) fn ink(c: [f32; 3], k: f32, dark_background: bool) -> [f32; 3] {
    if dark_background {
        c.map(|v| v + (1.0 - v).max(0.0) * 0.4 * k)
    } else {
        c.map(|v| v * (1.0 - 0.5 * k))
    }
}

/// Whether a background colour counts as dark (its Rec. 709 luminance below 0.3).
pub fn dark(bg: [f64; 3]) -> bool {
    0.2126 * bg[0] + 0.7152 * bg[1] + 0.0722 * bg[2] < 0.3
}

/// For N ≥ 5: the retina classified into a premultiplied volume for the recursive stages —
/// the cells' interior, creases and occlusion contours, inked — and its coverage (alpha only),
/// which the stages project too: the silhouettes are found in the projected 3D volume and
/// seen per view ([`Cues3::projected`]), as for N = 4. (A silhouette shell classified in the
/// (N−1)-D retina would be projected through the stages into a fog over the whole body and
/// a halo around it.)
pub(super) fn classify(
    rgba: &[f32],
    depth: &[f32],
    normal: Option<&[f32]>,
    shape: &[usize],
    camera: Option<&RetinaCamera>,
    o: &CompositeOptions,
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let origin = vec![0; shape.len()];
    let whole = Window {
        origin: &origin,
        full: shape,
    };
    let c = cues(rgba, depth, normal, shape, whole, camera, o);
    let dark_bg = dark(o.background);
    let classified = (0..c.color.len())
        .into_par_iter()
        .map(|i| {
            let [r, g, b, cov] = c.color[i];
            let feature = c.structure[i];
            let a = (INTERIOR_OPACITY * cov).max(feature).min(1.0);
            let k = (feature / 0.3).min(1.0);
            let col = ink([r, g, b], k, dark_bg);
            [col[0] * a, col[1] * a, col[2] * a, a]
        })
        .collect();
    let coverage = (0..c.color.len())
        .into_par_iter()
        .map(|i| [0.0, 0.0, 0.0, rgba[i * 4 + 3].clamp(0.0, 1.0)])
        .collect();
    (classified, coverage)
}

/// The view-independent cues of a 3D volume — a 3D retina (N = 4) or, for N ≥ 5, the
/// stages' projection of the classified retina ([`Cues3::projected`]) — classified per view
/// by [`Cues3::classify`].
pub(super) struct Cues3 {
    /// Numpy order (slices, rows, columns).
    shape: [usize; 3],
    /// Cell coordinates (column, row, slice) of the first cell in the retina.
    origin: [usize; 3],
    /// Straight colour and opacity-scaled coverage per cell (smoothed for N = 4; for N ≥ 5
    /// the projected coverage as the stages made it, the silhouettes' gate).
    color: Vec<[f32; 4]>,
    /// Coverage gradient in cell coordinates (column, row, slice) and the crease + occlusion
    /// opacity (0 for N ≥ 5, where `interior` holds them).
    cues: Vec<[f32; 4]>,
    /// Opacity of the cell's interior (with creases, for N ≥ 5: already classified).
    interior: Vec<f32>,
    dark_bg: bool,
}

impl Cues3 {
    /// From (the `window` of) a 3D retina (`shape` of length 3, numpy order).
    pub(super) fn new(
        rgba: &[f32],
        depth: &[f32],
        normal: Option<&[f32]>,
        shape: &[usize],
        window: Window<'_>,
        camera: Option<&RetinaCamera>,
        o: &CompositeOptions,
    ) -> Self {
        let c = cues(rgba, depth, normal, shape, window, camera, o);
        let interior = c
            .color
            .par_iter()
            .map(|v| INTERIOR_OPACITY * v[3])
            .collect();
        let origin = [window.origin[2], window.origin[1], window.origin[0]];
        Self::with_gradient(shape, origin, c.color, c.structure, interior, o)
    }

    /// For N ≥ 5: from the 3D volume the stages made of the classified retina
    /// ([`classify`]), `vol`, and of its coverage, `coverage` (alpha only): the straight
    /// colours and opacities of `vol` (dilated by one smoothing pass into the cells around
    /// them), with the silhouettes of the projected coverage, smoothed.
    pub(super) fn projected(vol: &Volume, coverage: &Volume, o: &CompositeOptions) -> Self {
        let shape = &vol.shape;
        let flat: Vec<f32> = vol.cells.iter().flatten().copied().collect();
        let blurred = smooth(&flat, 4, shape);
        let raw: Vec<f32> = coverage.cells.iter().map(|c| c[3]).collect();
        let cov = smooth(&raw, 1, shape);
        let opacity = o.opacity as f32;
        let color = (0..vol.cells.len())
            .into_par_iter()
            .map(|i| {
                let [r, g, b, a] = vol.cells[i];
                let (src, w) = if a > 1e-6 {
                    ([r, g, b], a)
                } else {
                    (
                        [blurred[i * 4], blurred[i * 4 + 1], blurred[i * 4 + 2]],
                        blurred[i * 4 + 3],
                    )
                };
                if w > 1e-6 {
                    [src[0] / w, src[1] / w, src[2] / w, cov[i] * opacity]
                } else {
                    [0.0, 0.0, 0.0, cov[i] * opacity]
                }
            })
            .collect();
        let interior = vol.cells.iter().map(|c| c[3]).collect();
        let structure = vec![0.0; vol.cells.len()];
        let mut cues = Self::with_gradient(shape, [0; 3], color, structure, interior, o);
        // The silhouettes' gate is the coverage before smoothing: the smoothed coverage's
        // gradient reaches a cell beyond the body, which would glow around it (by a cell
        // of the coarse projected volume: a wide halo).
        for (c, r) in cues.color.iter_mut().zip(raw) {
            c[3] = r * opacity;
        }
        cues
    }

    /// The cues with the coverage gradient of `color`'s coverage.
    fn with_gradient(
        shape: &[usize],
        origin: [usize; 3],
        color: Vec<[f32; 4]>,
        structure: Vec<f32>,
        interior: Vec<f32>,
        o: &CompositeOptions,
    ) -> Self {
        let (nz, ny, nx) = (shape[0], shape[1], shape[2]);
        // Central differences in cell coordinates, one-sided at the faces.
        let cov = |i: usize| color[i][3];
        let axis = |v: usize, r: usize, i: usize, stride: usize| {
            let (a, b) = (v.saturating_sub(1), (v + 1).min(r - 1));
            if b > a {
                (cov(i + (b - v) * stride) - cov(i - (v - a) * stride)) / (b - a) as f32
            } else {
                0.0
            }
        };
        let mut cues = vec![[0f32; 4]; color.len()];
        cues.par_chunks_mut(nx).enumerate().for_each(|(row, out)| {
            let (y, z) = (row % ny, row / ny);
            for (x, g) in out.iter_mut().enumerate() {
                let i = row * nx + x;
                *g = [
                    axis(x, nx, i, 1),
                    axis(y, ny, i, nx),
                    axis(z, nz, i, nx * ny),
                    structure[i],
                ];
            }
        });
        Cues3 {
            shape: [nz, ny, nx],
            origin,
            color,
            cues,
            interior,
            dark_bg: dark(o.background),
        }
    }

    /// The cell coordinates (column, row, slice) of the first cell in the retina.
    pub(super) fn origin(&self) -> [usize; 3] {
        self.origin
    }

    /// The premultiplied volume seen by `cam` (the window's cells): every cell's interior,
    /// crease and silhouette opacity, the silhouette's from the angle between the coverage
    /// gradient and the view ray through the cell's centre.
    pub(super) fn classify(&self, cam: &Camera3) -> Volume {
        let [_, ny, nx] = self.shape;
        let cells = (0..self.color.len())
            .into_par_iter()
            .map(|i| {
                let [r, g, b, cov] = self.color[i];
                let [gx, gy, gz, structure] = self.cues[i];
                let gm = (gx * gx + gy * gy + gz * gz).sqrt();
                let sil = if gm > 1e-4 {
                    let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
                    let [ox, oy, oz] = self.origin;
                    let v = cam.view_direction(DVec3::new(
                        (ox + x) as f64 + 0.5,
                        (oy + y) as f64 + 0.5,
                        (oz + z) as f64 + 0.5,
                    ));
                    let facing =
                        ((gx as f64 * v.x + gy as f64 * v.y + gz as f64 * v.z) as f32 / gm).abs();
                    let e = (1.0 - facing.min(1.0)).powi(4);
                    (gm * SILHOUETTE_GAIN).min(1.0)
                        * (SILHOUETTE_FACE + SILHOUETTE_EDGE * e)
                        * (cov * SILHOUETTE_GATE).min(1.0)
                } else {
                    0.0
                };
                let feature = (structure * CREASE_GAIN).max(sil);
                let a = self.interior[i].max(feature).min(1.0);
                let k = (feature / 0.3).min(1.0);
                let col = ink([r, g, b], k, self.dark_bg);
                [col[0] * a, col[1] * a, col[2] * a, a]
            })
            .collect();
        Volume {
            shape: self.shape.to_vec(),
            cells,
        }
    }
}

#[cfg(test)]
mod tests;
