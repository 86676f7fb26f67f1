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
//! For N = 4 the marcher samples two grids: the cells' (dilated) colour with their smoothed
//! coverage, and the coverage gradient with the crease and occlusion opacity. For N ≥ 5 the
//! cues are classified in the (N−1)-D retina into a premultiplied volume (silhouettes as a
//! view-independent shell) which the recursive stages then project as any other.

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
const SILHOUETTE: u8 = 4;

/// The flags of every cell: comparisons with its 2m axis neighbours.
fn flags(
    rgba: &[f32],
    depth: &[f32],
    normal: Option<&[f32]>,
    shape: &[usize],
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
                    let idx = rest % r;
                    rest /= r;
                    let k = m - 1 - a;
                    let half = r as f64 / 2.0;
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
                    *f |= SILHOUETTE;
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
    let m = shape.len();
    let mut cur = values.to_vec();
    let mut stride = 1usize;
    for a in (0..m).rev() {
        let r = shape[a];
        let src = cur;
        let mut dst = vec![0f32; src.len()];
        dst.par_chunks_mut(4096 * width)
            .enumerate()
            .for_each(|(chunk, out)| {
                for (j, v) in out.iter_mut().enumerate() {
                    let e = chunk * 4096 * width + j;
                    let (cell, ch) = (e / width, e % width);
                    let pos = (cell / stride) % r;
                    let mut s = 2.0 * src[e];
                    if pos > 0 {
                        s += src[(cell - stride) * width + ch];
                    }
                    if pos + 1 < r {
                        s += src[(cell + stride) * width + ch];
                    }
                    *v = s * 0.25;
                }
            });
        cur = dst;
        stride *= r;
    }
    cur
}

/// The smoothed cues of a retina: per cell the dilated straight colour and smoothed coverage
/// (`color`, 4 floats), the crease + occlusion opacity and the smoothed silhouette shell.
struct Cues {
    color: Vec<[f32; 4]>,
    structure: Vec<f32>,
    shell: Vec<f32>,
}

fn cues(
    rgba: &[f32],
    depth: &[f32],
    normal: Option<&[f32]>,
    shape: &[usize],
    camera: Option<&RetinaCamera>,
    o: &CompositeOptions,
) -> Cues {
    let cells: usize = shape.iter().product();
    let f = flags(rgba, depth, normal, shape, camera, o.crease_angle);
    let marks: Vec<f32> = f
        .iter()
        .flat_map(|&b| {
            [
                f32::from(b & (CREASE | OCCLUSION) != 0),
                f32::from(b & SILHOUETTE != 0),
            ]
        })
        .collect();
    let marks = smooth(&marks, 2, shape);
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
    let structure = (0..cells)
        .map(|i| (marks[2 * i] * 1.6).min(1.0) * CREASE_OPACITY)
        .collect();
    let shell = (0..cells)
        .map(|i| (marks[2 * i + 1] * 1.6).min(1.0))
        .collect();
    Cues {
        color,
        structure,
        shell,
    }
}

/// Lightens (dark background) or darkens (light background) a colour by `k` ∈ [0, 1]: the ink
/// of creases and silhouettes.
#[inline]
fn ink(c: [f32; 3], k: f32, dark_background: bool) -> [f32; 3] {
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

/// For N ≥ 5: the retina classified into a premultiplied volume for the recursive stages.
pub(super) fn classify(
    rgba: &[f32],
    depth: &[f32],
    normal: Option<&[f32]>,
    shape: &[usize],
    camera: Option<&RetinaCamera>,
    o: &CompositeOptions,
) -> Vec<[f32; 4]> {
    let c = cues(rgba, depth, normal, shape, camera, o);
    let dark_bg = dark(o.background);
    (0..c.color.len())
        .into_par_iter()
        .map(|i| {
            let [r, g, b, cov] = c.color[i];
            let feature = c.structure[i].max(0.5 * c.shell[i]);
            let a = (INTERIOR_OPACITY * cov).max(feature).min(1.0);
            let k = (feature / 0.3).min(1.0);
            let col = ink([r, g, b], k, dark_bg);
            [col[0] * a, col[1] * a, col[2] * a, a]
        })
        .collect()
}

/// The view-independent cues of a 3D retina (N = 4), classified per view by
/// [`Cues3::classify`].
pub(super) struct Cues3 {
    /// Numpy order (slices, rows, columns).
    shape: [usize; 3],
    /// Straight colour and (smoothed, opacity-scaled) coverage per cell.
    color: Vec<[f32; 4]>,
    /// Coverage gradient in cell coordinates (column, row, slice) and the crease + occlusion
    /// opacity.
    cues: Vec<[f32; 4]>,
    dark_bg: bool,
}

impl Cues3 {
    /// From a 3D retina (`shape` of length 3, numpy order).
    pub(super) fn new(
        rgba: &[f32],
        depth: &[f32],
        normal: Option<&[f32]>,
        shape: &[usize],
        camera: Option<&RetinaCamera>,
        o: &CompositeOptions,
    ) -> Self {
        let c = cues(rgba, depth, normal, shape, camera, o);
        let (nz, ny, nx) = (shape[0], shape[1], shape[2]);
        let cov = |x: usize, y: usize, z: usize| c.color[x + nx * (y + ny * z)][3];
        let cues: Vec<[f32; 4]> = (0..c.color.len())
            .into_par_iter()
            .map(|i| {
                let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
                // Central differences in cell coordinates, one-sided at the faces.
                let d = |lo: f32, hi: f32, span: usize| (hi - lo) / span as f32;
                let axis = |v: usize, r: usize, at: &dyn Fn(usize) -> f32| {
                    let (a, b) = (v.saturating_sub(1), (v + 1).min(r - 1));
                    if b > a {
                        d(at(a), at(b), b - a)
                    } else {
                        0.0
                    }
                };
                let gx = axis(x, nx, &|v| cov(v, y, z));
                let gy = axis(y, ny, &|v| cov(x, v, z));
                let gz = axis(z, nz, &|v| cov(x, y, v));
                [gx, gy, gz, c.structure[i]]
            })
            .collect();
        Cues3 {
            shape: [nz, ny, nx],
            color: c.color,
            cues,
            dark_bg: dark(o.background),
        }
    }

    /// The premultiplied volume seen by `cam`: every cell's interior, crease and silhouette
    /// opacity, the silhouette's from the angle between the coverage gradient and the view ray
    /// through the cell's centre.
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
                    let v = cam.view_direction(DVec3::new(
                        x as f64 + 0.5,
                        y as f64 + 0.5,
                        z as f64 + 0.5,
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
                let a = (INTERIOR_OPACITY * cov).max(feature).min(1.0);
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
