//! Feature edges drawn over a composited picture: the visible pieces of every object's edges
//! (exact N-D hidden-line removal, [`crate::edges`]) as anti-aliased lines, the hidden pieces
//! dashed or faint, projected through the same maps as the cells — the N ≥ 5 stages' x_j ↦
//! x_j·f/(d + x_k) and the compositing camera — so they lie exactly on the cells they bound.
//! Perspective maps send lines to lines, so each piece's two ends suffice.

use super::options::{CompositeOptions, EdgeColorBy, HiddenEdges};
use super::{FAR_TINT, NEAR_TINT};
use rayon::prelude::*;

/// Largest retina dimension m = N − 1.
pub const MAX_RETINA_DIM: usize = 7;

/// One piece of an edge in retina coordinates: continuous numpy-order cell coordinates (cell i
/// of an axis spans [i, i + 1]), the N-D depth (distance from the eye) of its ends, and whether
/// the N-D camera sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RetinaEdge {
    /// One end, first `m` entries used.
    pub a: [f64; MAX_RETINA_DIM],
    /// The other end.
    pub b: [f64; MAX_RETINA_DIM],
    /// N-D depth of `a` and `b`.
    pub depth: [f64; 2],
    /// Seen by the N-D camera (else hidden in N-D).
    pub visible: bool,
    /// The colour of the edge's direction (linear RGB; used with
    /// [`EdgeColorBy::Direction`], see [`crate::edges::edge_directions`]).
    pub color: [f32; 3],
}

/// A piece projected to the picture: pixel coordinates (x right, y down; pixel (i, j) spans
/// [i, i + 1] × [j, j + 1]), the compositing camera's distance and the N-D depth of each end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelEdge {
    /// The two ends, pixels.
    pub p: [[f64; 2]; 2],
    /// The compositing camera's distance of each end (cell units).
    pub z: [f64; 2],
    /// The N-D depth of each end.
    pub depth: [f64; 2],
    /// Seen by the N-D camera.
    pub visible: bool,
    /// The colour of its direction (see [`RetinaEdge::color`]).
    pub color: [f32; 3],
}

/// Width of the nearest edges over [`edge_width`] with [`EdgeColorBy::Depth`] and
/// [`EdgeColorBy::Direction`]; the farthest are [`FAR_WIDTH`] of it.
pub const NEAR_WIDTH: f64 = 1.5;
/// Width of the farthest edges over [`edge_width`].
pub const FAR_WIDTH: f64 = 0.55;
/// Strength (opacity) of the farthest edges with [`EdgeColorBy::Depth`]; the nearest have 1.
pub const FAR_STRENGTH: f32 = 0.4;

/// The line width in pixels: the option, or for 0 a width that reads at the picture's size.
pub fn edge_width(o: &CompositeOptions) -> f64 {
    if o.edge_width > 0.0 {
        o.edge_width
    } else {
        (o.size.0.min(o.size.1) as f64 / 300.0).max(1.0)
    }
}

/// The colour of visible edges: the option, or near-white on a dark background and near-black
/// on a light one.
pub fn edge_color(o: &CompositeOptions) -> [f32; 3] {
    match o.edge_color {
        Some(c) => c.map(|v| v as f32),
        None if super::illustrative::dark(o.background) => [0.95, 0.93, 0.88],
        None => [0.06, 0.06, 0.08],
    }
}

/// How an edge looks at an N-D depth: [`edge_color`] (with `depth_cue` > 0 tinted from warm,
/// nearest, to cool, farthest) or its direction's colour, and with
/// [`EdgeColorBy::Depth`] or [`EdgeColorBy::Direction`] its width and strength by depth (the
/// course's depth cueing: thicker and stronger near the N-D eye), over the depth range of the
/// edges drawn.
pub struct EdgeColors {
    base: [f32; 3],
    cue: f32,
    by: EdgeColorBy,
    lo: f64,
    span: f64,
}

impl EdgeColors {
    /// For the pieces `edges` drawn with `o`.
    pub fn new(edges: &[PixelEdge], o: &CompositeOptions) -> Self {
        let (lo, hi) = edges
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), e| {
                (
                    lo.min(e.depth[0].min(e.depth[1])),
                    hi.max(e.depth[0].max(e.depth[1])),
                )
            });
        EdgeColors {
            base: edge_color(o),
            cue: o.depth_cue as f32,
            by: o.edge_color_by,
            lo,
            span: if hi > lo { hi - lo } else { 1.0 },
        }
    }

    /// Depth `d` on [0, 1] over the edges' range (nearest 0).
    fn t(&self, d: f64) -> f64 {
        ((d - self.lo) / self.span).clamp(0.0, 1.0)
    }

    /// The linear RGB of edge `e` at depth `d`.
    pub fn at(&self, e: &PixelEdge, d: f64) -> [f32; 3] {
        if self.by == EdgeColorBy::Direction {
            return e.color;
        }
        if self.cue > 0.0 {
            let t = self.t(d) as f32;
            std::array::from_fn(|k| {
                let tint = NEAR_TINT[k] + (FAR_TINT[k] - NEAR_TINT[k]) * t;
                (self.base[k] * (1.0 - self.cue + self.cue * tint)).min(1.0)
            })
        } else {
            self.base
        }
    }

    /// The width (times [`edge_width`]) and strength (opacity) of an edge at depth `d`.
    pub fn weight(&self, d: f64) -> (f64, f32) {
        match self.by {
            EdgeColorBy::None => (1.0, 1.0),
            by => {
                let t = self.t(d);
                let strength = match by {
                    EdgeColorBy::Depth => 1.0 - (1.0 - FAR_STRENGTH) * t as f32,
                    _ => 1.0,
                };
                (NEAR_WIDTH + (FAR_WIDTH - NEAR_WIDTH) * t, strength)
            }
        }
    }
}

/// Distance from pixel centre `q` to the segment `p0 p1` and the parameter of the closest point.
#[inline]
fn distance(q: [f64; 2], p0: [f64; 2], p1: [f64; 2]) -> (f64, f64) {
    let (dx, dy) = (p1[0] - p0[0], p1[1] - p0[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((q[0] - p0[0]) * dx + (q[1] - p0[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (cx, cy) = (p0[0] + t * dx - q[0], p0[1] + t * dy - q[1]);
    ((cx * cx + cy * cy).sqrt(), t)
}

/// Draws `edges` over `img` (RGBA over the background, row-major, `w` pixels wide). `half`, if given,
/// is per pixel the compositing-camera distance at which the picture's opacity reached ½:
/// edge points behind it are drawn at a third of their strength, as seen through the cells.
///
/// Visible pieces are solid lines of [`edge_width`]; hidden pieces follow
/// [`CompositeOptions::hidden_edges`]: dashed (8 px period) at 60 % strength and 0.6× width,
/// faint (solid at 30 %), or not drawn. Colour, width and strength by N-D depth or direction
/// are [`EdgeColors`]'. Each pixel takes
/// the strongest visible and the strongest hidden coverage (so crossings and shared vertices
/// are not darker), hidden under visible: the result does not depend on the edges' order or
/// the number of threads.
pub(super) fn draw(
    img: &mut [f32],
    w: usize,
    edges: &[PixelEdge],
    half: Option<&[f32]>,
    o: &CompositeOptions,
) {
    if edges.is_empty() {
        return;
    }
    let width = edge_width(o);
    let colors = EdgeColors::new(edges, o);
    let hidden = o.hidden_edges;
    img.par_chunks_mut(w * 4).enumerate().for_each(|(py, row)| {
        let y = py as f64 + 0.5;
        // Strongest coverage and its colour, visible and hidden layers.
        let mut layers = vec![[(0f32, [0f32; 3]); 2]; w];
        for e in edges {
            let (strength, lw, dashed) = match (e.visible, hidden) {
                (true, _) => (1.0f32, width, false),
                (false, HiddenEdges::Dashed) => (0.6, 0.6 * width, true),
                (false, HiddenEdges::Faint) => (0.3, 0.6 * width, false),
                (false, HiddenEdges::None) => continue,
            };
            // The widest the piece gets (by depth), for the rows and columns it may cover.
            let widest = colors.weight(e.depth[0]).0.max(colors.weight(e.depth[1]).0);
            let r = lw * widest / 2.0 + 1.0;
            let (ymin, ymax) = (e.p[0][1].min(e.p[1][1]) - r, e.p[0][1].max(e.p[1][1]) + r);
            if y < ymin || y > ymax {
                continue;
            }
            let xmin = (e.p[0][0].min(e.p[1][0]) - r).floor().max(0.0) as usize;
            let xmax = ((e.p[0][0].max(e.p[1][0]) + r).ceil().max(0.0) as usize).min(w);
            let len = ((e.p[1][0] - e.p[0][0]).powi(2) + (e.p[1][1] - e.p[0][1]).powi(2)).sqrt();
            for (px, layer) in layers.iter_mut().enumerate().take(xmax).skip(xmin) {
                let (dist, t) = distance([px as f64 + 0.5, y], e.p[0], e.p[1]);
                let d = e.depth[0] + t * (e.depth[1] - e.depth[0]);
                let (scale, weight) = colors.weight(d);
                let mut cov = (lw * scale / 2.0 + 0.5 - dist).clamp(0.0, 1.0) as f32 * weight;
                if cov <= 0.0 {
                    continue;
                }
                if dashed {
                    let s = (t * len) % 8.0;
                    cov *= (s.min(4.5 - s) + 0.5).clamp(0.0, 1.0) as f32;
                }
                if let Some(hz) = half {
                    let z = e.z[0] + t * (e.z[1] - e.z[0]);
                    if z > hz[py * w + px] as f64 + 1.0 {
                        cov *= 1.0 / 3.0;
                    }
                }
                let cov = cov * strength;
                let slot = &mut layer[usize::from(!e.visible)];
                if cov > slot.0 {
                    *slot = (cov, colors.at(e, d));
                }
            }
        }
        for (px, layer) in layers.iter().enumerate() {
            let v = &mut row[px * 4..px * 4 + 4];
            for &(cov, col) in [layer[1], layer[0]].iter() {
                if cov > 0.0 {
                    for k in 0..3 {
                        v[k] += (col[k] - v[k]) * cov;
                    }
                    v[3] += (1.0 - v[3]) * cov;
                }
            }
        }
    });
}
