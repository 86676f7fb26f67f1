//! The structure's sheets ([`super::probe`]) seen by one compositing camera: every triangle
//! projected into the picture and binned into tiles of [`TILE`] × [`TILE`] pixels, so that the
//! crossings of any picture ray with the sheets are found from its tile's list alone.
//!
//! A ray crosses a triangle where the picture point lies inside the projected triangle: the
//! inside test is a 2D one, with each edge's function computed the same way for both triangles
//! that share it (from its lower vertex index to the higher) and ties given to exactly one of
//! them, so that a ray through a shared edge crosses the sheet once — the layer count of
//! [`super::probe::Structure::counted`] stays exact. The crossing's retina point comes from
//! the 2D barycentric coordinates, corrected for the perspective of the compositing camera.
//! A surface sheet is widened in the picture to its [`ObjectLook::line_width`]: a ray passing
//! within half of it meets the sheet at its nearest edge point, so a surface seen edge-on is
//! a line of that width.

use super::probe::{ObjectLook, SheetKind, Structure};
use super::volume::Camera3;
use glam::DVec3;
use rayon::prelude::*;

/// Side of a tile, pixels.
pub(super) const TILE: usize = 8;

/// A crossing of a picture ray with a sheet.
#[derive(Debug, Clone, Copy)]
pub(super) struct Crossing {
    /// Ray parameter (cell units from the ray's origin).
    pub t: f64,
    /// Index into [`Structure::sheets`].
    pub sheet: u32,
    /// Barycentric coordinates of the crossing in the sheet's retina triangle (its vertex
    /// order).
    pub b: [f64; 3],
    /// The retina point (cell coordinates).
    pub p: DVec3,
    /// Layers gained (mesh count sheets; 0 otherwise).
    pub enter: i8,
    /// |cos| of the angle between the ray and the sheet's normal.
    pub cos: f64,
}

/// A sheet's triangle in the picture.
#[derive(Debug, Clone, Copy)]
struct Tri {
    /// Structure vertex indices, counter-clockwise in the picture (y down: clockwise on
    /// screen), with `order` mapping them back to the sheet's own order.
    v: [u32; 3],
    order: [u8; 3],
    sheet: u32,
    /// Half the widening, pixels (surfaces).
    radius: f64,
    /// Retina normal of the sheet (its own vertex order), unit.
    normal: DVec3,
    /// Mesh count change toward the normal's side.
    delta: i8,
    /// The widened box in the picture: x0, y0, x1, y1.
    bbox: [f64; 4],
}

/// The sheets as one camera sees them.
pub(super) struct ViewSheets {
    /// Per structure vertex: picture position (x, y) and view distance.
    xy: Vec<[f64; 2]>,
    z: Vec<f64>,
    /// Per structure vertex: retina position.
    p: Vec<DVec3>,
    tris: Vec<Tri>,
    /// Tiles: columns, rows; per tile the range of `list` holding its triangles.
    cols: usize,
    rows: usize,
    starts: Vec<u32>,
    list: Vec<u32>,
    ortho: bool,
}

/// The 2D cross product (b − a) × (c − a).
#[inline(always)]
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Distance from `q` to the segment `a b` and the parameter of the nearest point.
#[inline]
fn segment_distance(q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> (f64, f64) {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (cx, cy) = (a[0] + t * dx - q[0], a[1] + t * dy - q[1]);
    ((cx * cx + cy * cy).sqrt(), t)
}

impl ViewSheets {
    /// The sheets of `s` seen by `cam`, those that can meet the retina's box `n` (cells); `None`
    /// when a sheet in the box reaches behind a perspective camera's eye (then the picture is
    /// drawn from the retina's cells).
    pub(super) fn new(
        s: &Structure,
        looks: &[ObjectLook],
        cam: &Camera3,
        n: [usize; 3],
    ) -> Option<Self> {
        let ortho = cam.orthographic();
        let (w, h) = cam.size();
        let near = cam.near();
        // 1. The vertices in the picture.
        let p: Vec<DVec3> = s.vertices.iter().map(|v| DVec3::from_array(v.p)).collect();
        let projected: Vec<Option<([f64; 2], f64)>> = p
            .par_iter()
            .map(|&q| {
                if cam.view_distance(q) <= near {
                    return None;
                }
                cam.project(q)
            })
            .collect();
        // 2. The triangles, counter-clockwise in the picture; those wholly outside the box or
        //    with no area in the picture (and no widening) are left out.
        let tris: Vec<Result<Option<Tri>, ()>> = s
            .sheets
            .par_iter()
            .enumerate()
            .map(|(i, sh)| {
                let q = sh.v.map(|k| p[k as usize]);
                let lo = q[0].min(q[1]).min(q[2]);
                let hi = q[0].max(q[1]).max(q[2]);
                if (0..3).any(|k| hi[k] < 0.0 || lo[k] > n[k] as f64) {
                    return Ok(None);
                }
                let mut xy = [[0.0; 2]; 3];
                for k in 0..3 {
                    match projected[sh.v[k] as usize] {
                        Some((a, _)) => xy[k] = a,
                        None => return Err(()),
                    }
                }
                let normal = (q[1] - q[0]).cross(q[2] - q[0]);
                let area = orient(xy[0], xy[1], xy[2]);
                let (radius, delta) = match sh.kind {
                    SheetKind::Mesh { delta, .. } => (0.0, delta),
                    SheetKind::Surface { .. } => (
                        0.5 * looks.get(sh.object as usize).map_or(0.0, |l| l.line_width),
                        0,
                    ),
                };
                let len = normal.length();
                if radius == 0.0 && !(area.abs() > 1e-12 && len > 0.0) {
                    return Ok(None);
                }
                let (v, order) = if area >= 0.0 {
                    (sh.v, [0, 1, 2])
                } else {
                    ([sh.v[0], sh.v[2], sh.v[1]], [0, 2, 1])
                };
                let (xs, ys) = (xy.map(|a| a[0]), xy.map(|a| a[1]));
                let bbox = [
                    xs[0].min(xs[1]).min(xs[2]) - radius,
                    ys[0].min(ys[1]).min(ys[2]) - radius,
                    xs[0].max(xs[1]).max(xs[2]) + radius,
                    ys[0].max(ys[1]).max(ys[2]) + radius,
                ];
                Ok(Some(Tri {
                    v,
                    order,
                    sheet: i as u32,
                    radius,
                    normal: if len > 0.0 { normal / len } else { DVec3::ZERO },
                    delta,
                    bbox,
                }))
            })
            .collect();
        if tris.iter().any(|t| t.is_err()) {
            return None;
        }
        let tris: Vec<Tri> = tris.into_iter().flatten().flatten().collect();
        let xy: Vec<[f64; 2]> = projected
            .iter()
            .map(|o| o.map_or([0.0; 2], |v| v.0))
            .collect();
        let z: Vec<f64> = projected.iter().map(|o| o.map_or(1.0, |v| v.1)).collect();
        // 3. The tiles each triangle's (widened) box meets, counted then filled in triangle
        //    order (the lists, and so every crossing's order of discovery, are the same for
        //    any number of threads).
        let (cols, rows) = (w.div_ceil(TILE).max(1), h.div_ceil(TILE).max(1));
        let span = |t: &Tri| -> Option<[usize; 4]> {
            let r = t.radius + 1e-6;
            let xs = t.v.map(|k| xy[k as usize][0]);
            let ys = t.v.map(|k| xy[k as usize][1]);
            let (x0, x1) = (
                xs[0].min(xs[1]).min(xs[2]) - r,
                xs[0].max(xs[1]).max(xs[2]) + r,
            );
            let (y0, y1) = (
                ys[0].min(ys[1]).min(ys[2]) - r,
                ys[0].max(ys[1]).max(ys[2]) + r,
            );
            if x1 < 0.0 || y1 < 0.0 || x0 > w as f64 || y0 > h as f64 {
                return None;
            }
            let tile = |v: f64, count: usize| ((v.max(0.0) / TILE as f64) as usize).min(count - 1);
            Some([
                tile(x0, cols),
                tile(x1, cols),
                tile(y0, rows),
                tile(y1, rows),
            ])
        };
        let spans: Vec<Option<[usize; 4]>> = tris.par_iter().map(span).collect();
        let mut counts = vec![0u32; cols * rows + 1];
        for sp in spans.iter().flatten() {
            for ty in sp[2]..=sp[3] {
                for tx in sp[0]..=sp[1] {
                    counts[ty * cols + tx] += 1;
                }
            }
        }
        let mut starts = vec![0u32; cols * rows + 1];
        for i in 0..cols * rows {
            starts[i + 1] = starts[i] + counts[i];
        }
        let mut fill = starts.clone();
        let mut list = vec![0u32; starts[cols * rows] as usize];
        for (i, sp) in spans.iter().enumerate() {
            if let Some(sp) = sp {
                for ty in sp[2]..=sp[3] {
                    for tx in sp[0]..=sp[1] {
                        let c = &mut fill[ty * cols + tx];
                        list[*c as usize] = i as u32;
                        *c += 1;
                    }
                }
            }
        }
        Some(ViewSheets {
            xy,
            z,
            p,
            tris,
            cols,
            rows,
            starts,
            list,
            ortho,
        })
    }

    /// The triangles of pixel (px, py)'s tile whose widened boxes meet the pixel, into `out`
    /// (the candidates of [`ViewSheets::crossings_of`] for points within the pixel).
    pub(super) fn candidates(&self, px: usize, py: usize, out: &mut Vec<u32>) {
        out.clear();
        let (tx, ty) = (px / TILE, py / TILE);
        if tx >= self.cols || ty >= self.rows {
            return;
        }
        let tile = ty * self.cols + tx;
        let (x0, y0) = (px as f64, py as f64);
        for &i in &self.list[self.starts[tile] as usize..self.starts[tile + 1] as usize] {
            let b = &self.tris[i as usize].bbox;
            if !(x0 + 1.0 < b[0] || x0 > b[2] || y0 + 1.0 < b[1] || y0 > b[3]) {
                out.push(i);
            }
        }
    }

    /// The crossings of the ray (origin `o`, unit direction `d`) through picture point (x, y)
    /// with the sheets, appended to `out` in the order of the tile's list (not sorted).
    pub(super) fn crossings(&self, x: f64, y: f64, o: DVec3, d: DVec3, out: &mut Vec<Crossing>) {
        if x < 0.0 || y < 0.0 {
            return;
        }
        let (tx, ty) = ((x / TILE as f64) as usize, (y / TILE as f64) as usize);
        if tx >= self.cols || ty >= self.rows {
            return;
        }
        let tile = ty * self.cols + tx;
        self.crossings_of(
            &self.list[self.starts[tile] as usize..self.starts[tile + 1] as usize],
            x,
            y,
            o,
            d,
            out,
        );
    }

    /// [`ViewSheets::crossings`] with the triangles `cands` (a tile's list, or a pixel's
    /// [`ViewSheets::candidates`] for a point within it).
    pub(super) fn crossings_of(
        &self,
        cands: &[u32],
        x: f64,
        y: f64,
        o: DVec3,
        d: DVec3,
        out: &mut Vec<Crossing>,
    ) {
        let q = [x, y];
        for &i in cands {
            let t = &self.tris[i as usize];
            let b = &t.bbox;
            if x < b[0] || x > b[2] || y < b[1] || y > b[3] {
                continue;
            }
            let a = t.v.map(|k| self.xy[k as usize]);
            let r = t.radius;
            // Edge k runs from corner k to corner k + 1; its function is computed from the
            // lower vertex index to the higher, and a tie goes to the triangle that runs the
            // edge that way.
            let mut e = [0.0; 3];
            let mut inside = true;
            for k in 0..3 {
                let (i0, i1) = (t.v[k], t.v[(k + 1) % 3]);
                let (lo, hi, sign) = if i0 < i1 {
                    (i0, i1, 1.0)
                } else {
                    (i1, i0, -1.0)
                };
                let f = sign * orient(self.xy[lo as usize], self.xy[hi as usize], q);
                e[(k + 2) % 3] = f;
                if !(f > 0.0 || (f == 0.0 && sign > 0.0)) {
                    inside = false;
                }
            }
            let lam = if inside {
                let sum = e[0] + e[1] + e[2];
                if !(sum > 0.0) {
                    continue;
                }
                [e[0] / sum, e[1] / sum, e[2] / sum]
            } else if r > 0.0 {
                // The nearest point of the triangle's edges, within the widening.
                let mut best = (f64::INFINITY, [0.0; 3]);
                for k in 0..3 {
                    let (dist, s) = segment_distance(q, a[k], a[(k + 1) % 3]);
                    if dist < best.0 {
                        let mut l = [0.0; 3];
                        l[k] = 1.0 - s;
                        l[(k + 1) % 3] = s;
                        best = (dist, l);
                    }
                }
                if best.0 > r {
                    continue;
                }
                best.1
            } else {
                continue;
            };
            // Perspective: 1/z is affine in the picture, so the retina weights are λ_k / z_k.
            let w = if self.ortho {
                lam
            } else {
                let w = [0, 1, 2].map(|k| lam[k] / self.z[t.v[k] as usize]);
                let s = w[0] + w[1] + w[2];
                if !(s > 0.0) {
                    continue;
                }
                w.map(|v| v / s)
            };
            let p = self.p[t.v[0] as usize] * w[0]
                + self.p[t.v[1] as usize] * w[1]
                + self.p[t.v[2] as usize] * w[2];
            let mut b = [0.0; 3];
            for k in 0..3 {
                b[t.order[k] as usize] = w[k];
            }
            let dn = t.normal.dot(d);
            out.push(Crossing {
                t: (p - o).dot(d),
                sheet: t.sheet,
                b,
                p,
                enter: if dn > 0.0 { t.delta } else { -t.delta },
                cos: dn.abs(),
            });
        }
    }
}
