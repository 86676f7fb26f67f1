//! Display aids of the best 4D viewers (tesserxel's sections and cutaways, stereo pairs,
//! turntables), for the 3D volume a retina becomes (the retina of a 4D scene, or the result of
//! the N ≥ 5 stages): cutaways that remove a half-space, a ball or a box of it, and the layouts
//! of [`ViewLayout`].
//!
//! Cutaway regions are given in the volume's **world coordinates**, those of
//! [`composite`](super::composite): the volume centred at the origin with its longest side
//! spanning [−1, 1], x along the columns, y up the rows (row 0 on top), z along the slices.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A region removed from the 3D volume before it is composited, so that what is inside shows.
/// Cells are removed by the fraction of a cell their centre lies inside the region (a smooth
/// cut, not a staircase); feature edges are cut with them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum Cutaway {
    /// Removes the half-space {x : n̂·x > offset} (n̂ the unit `normal`).
    HalfSpace {
        /// Points toward the removed side; need not be unit.
        normal: [f64; 3],
        /// Signed distance of the cutting plane from the centre along n̂. Default 0.
        #[serde(default)]
        offset: f64,
    },
    /// Removes the ball |x − center| < radius.
    Sphere {
        /// Default the centre of the volume.
        #[serde(default)]
        center: [f64; 3],
        /// Positive.
        radius: f64,
    },
    /// Removes the box min < x < max (per axis).
    Box {
        /// Lower corner.
        min: [f64; 3],
        /// Upper corner (each coordinate above `min`'s).
        max: [f64; 3],
    },
}

/// How the picture is laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ViewLayout {
    /// One view (the default).
    #[default]
    Single,
    /// Four quadrants: the view (top left) and three orthogonal sections through the volume at
    /// [`section`](super::CompositeOptions::section): across z (top right: the slice seen
    /// face-on, x right and y up), across x (bottom left: z right, y up) and across y (bottom
    /// right: x right, z down).
    Sections,
    /// A stereo pair side by side for parallel ("wall-eyed") viewing: the left half seen from
    /// azimuth − [`stereo_angle`](super::CompositeOptions::stereo_angle)/2, the right half
    /// from azimuth + stereo_angle/2.
    Stereo,
    /// The view (left half) beside the scene's current `[slice]` (right half): `ndtrace` (the
    /// command line) and `ndtrace.animate` trace the slice and draw it there, and mark the
    /// slicing hyperplane in the view; the compositor alone leaves the right half background.
    Slice,
}

/// `cubes = { size = s }`: the notes' display aid "break into tiny cubes — to help see inside
/// volume, leave a little space instead of transparency": each occupied retina cell (coverage
/// ≥ ½) drawn as an opaque cube of side s cells about its centre, in the cell's colour, its
/// faces shaded by a headlight so the cubes read as solids.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cubes {
    /// The cube's side, a fraction of a cell in (0, 1] (default 0.6).
    #[serde(default = "default_cube_size")]
    pub size: f64,
}

fn default_cube_size() -> f64 {
    0.6
}

impl Cutaway {
    /// Checks the region's numbers; `key` names the option in messages.
    pub fn validate(&self, key: &str) -> Result<(), (String, String)> {
        let finite = |name: &str, v: &[f64]| -> Result<(), (String, String)> {
            match v.iter().position(|x| !x.is_finite()) {
                Some(i) => Err((
                    format!("{key}.{name}[{i}]"),
                    format!("must be finite, got {}", v[i]),
                )),
                None => Ok(()),
            }
        };
        match self {
            Cutaway::HalfSpace { normal, offset } => {
                finite("normal", normal)?;
                finite("offset", &[*offset])?;
                if normal.iter().all(|&v| v == 0.0) {
                    return Err((format!("{key}.normal"), "must not be zero".into()));
                }
            }
            Cutaway::Sphere { center, radius } => {
                finite("center", center)?;
                finite("radius", &[*radius])?;
                if !(*radius > 0.0) {
                    return Err((
                        format!("{key}.radius"),
                        format!("must be positive, got {radius}"),
                    ));
                }
            }
            Cutaway::Box { min, max } => {
                finite("min", min)?;
                finite("max", max)?;
                if let Some(k) = (0..3).find(|&k| !(max[k] > min[k])) {
                    return Err((
                        format!("{key}.max[{k}]"),
                        format!("must exceed min[{k}] = {}, got {}", min[k], max[k]),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Signed distance of `p` (world coordinates) from the region's surface, negative inside
    /// (for the box, the exact Euclidean distance outside and the distance to the nearest face
    /// inside).
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        match *self {
            Cutaway::HalfSpace { normal, offset } => {
                let n = DVec3::from_array(normal).normalize();
                offset - n.dot(p)
            }
            Cutaway::Sphere { center, radius } => (p - DVec3::from_array(center)).length() - radius,
            Cutaway::Box { min, max } => {
                let (lo, hi) = (DVec3::from_array(min), DVec3::from_array(max));
                let c = (lo + hi) * 0.5;
                let q = (p - c).abs() - (hi - lo) * 0.5;
                q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
            }
        }
    }

    /// The parameter interval (t_in, t_out) ⊂ [0, 1] of the segment a → b inside the region,
    /// if any (every region is convex, so it is one interval).
    pub fn inside(&self, a: DVec3, b: DVec3) -> Option<(f64, f64)> {
        let d = b - a;
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let mut slab = |num: f64, den: f64| {
            // Keeps the t with num + den·t < 0 (strictly inside one plane).
            if den == 0.0 {
                if num >= 0.0 {
                    t1 = f64::NEG_INFINITY;
                }
            } else if den > 0.0 {
                t1 = t1.min(-num / den);
            } else {
                t0 = t0.max(-num / den);
            }
        };
        match *self {
            Cutaway::HalfSpace { normal, offset } => {
                let n = DVec3::from_array(normal).normalize();
                slab(offset - n.dot(a), -n.dot(d));
            }
            Cutaway::Box { min, max } => {
                for k in 0..3 {
                    slab(min[k] - a[k], -d[k]);
                    slab(a[k] - max[k], d[k]);
                }
            }
            Cutaway::Sphere { center, radius } => {
                let f = a - DVec3::from_array(center);
                let (qa, qb, qc) = (d.dot(d), 2.0 * f.dot(d), f.dot(f) - radius * radius);
                let disc = qb * qb - 4.0 * qa * qc;
                if qa == 0.0 || disc <= 0.0 {
                    return (qc < 0.0).then_some((0.0, 1.0));
                }
                let s = disc.sqrt();
                t0 = t0.max((-qb - s) / (2.0 * qa));
                t1 = t1.min((-qb + s) / (2.0 * qa));
            }
        }
        (t1 > t0).then_some((t0, t1))
    }
}

/// World position of the centre of cell (x, y, z) (cell coordinates, column, row, slice) of a
/// volume of `n` cells.
pub(super) fn cell_world(n: [usize; 3], x: usize, y: usize, z: usize) -> DVec3 {
    world_of(
        n,
        DVec3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5),
    )
}

/// Cell coordinates → world coordinates.
pub(super) fn world_of(n: [usize; 3], p: DVec3) -> DVec3 {
    let c = 2.0 / *n.iter().max().unwrap() as f64;
    DVec3::new(
        p.x * c - n[0] as f64 * c / 2.0,
        n[1] as f64 * c / 2.0 - p.y * c,
        p.z * c - n[2] as f64 * c / 2.0,
    )
}

/// Removes the cutaway from premultiplied cells in numpy order (`shape` = slices, rows,
/// columns): each cell keeps the fraction clamp(½ + s/c, 0, 1) of itself, s the signed
/// distance of its centre from the region and c the cell side.
pub(super) fn cut(cells: &mut [[f32; 4]], shape: &[usize], cutaway: &Cutaway) {
    use rayon::prelude::*;
    let n = [shape[2], shape[1], shape[0]];
    let c = 2.0 / *n.iter().max().unwrap() as f64;
    cells.par_iter_mut().enumerate().for_each(|(i, v)| {
        let (x, y, z) = (i % n[0], (i / n[0]) % n[1], i / (n[0] * n[1]));
        let keep = (0.5 + cutaway.signed_distance(cell_world(n, x, y, z)) / c).clamp(0.0, 1.0);
        if keep < 1.0 {
            *v = v.map(|ch| ch * keep as f32);
        }
    });
}
