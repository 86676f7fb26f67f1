//! Refitting: the tree of simplices that moved, without a build. The blocks are prepared
//! again from the moved vertices and every box is recomputed bottom-up; the tree keeps its
//! shape. Every query returns the least (t, id) over the simplices hit, whatever the tree's
//! shape, so a refitted tree answers bit for bit as a tree built over the same simplices moved
//! (the simplices it holds: one left out as degenerate stays out, which the caller checks).
//! The shape stays a good one when the simplices move together, as an animated object does;
//! a rotation grows the boxes somewhat.

use super::build::BOX_PAD;
use super::cell::CellGeometry;
use super::simplex::{simplex_bounds, PreparedSimplex};
use super::tree::{f32_down, f32_up, Bvh, WideNode, CELL_TAG, EMPTY_SLOT, LEAF_TAG, NODE_WIDTH};
use crate::linalg::Vector;
use rayon::prelude::*;

/// A box in f32, rounded outward.
type Box32<const N: usize> = ([f32; N], [f32; N]);

/// The empty box.
fn empty<const N: usize>() -> Box32<N> {
    ([f32::INFINITY; N], [f32::NEG_INFINITY; N])
}

/// The union of two boxes (exact).
fn union<const N: usize>(a: Box32<N>, b: Box32<N>) -> Box32<N> {
    (
        std::array::from_fn(|i| a.0[i].min(b.0[i])),
        std::array::from_fn(|i| a.1[i].max(b.1[i])),
    )
}

/// The box of simplices whose raw bounds are `lo`, `hi`, padded by [`BOX_PAD`] of its largest
/// extent (as the builds pad) and rounded outward to f32.
fn padded<const N: usize>((lo, hi): ([f64; N], [f64; N])) -> Box32<N> {
    let pad = BOX_PAD * (0..N).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
    (
        std::array::from_fn(|i| f32_down(lo[i] - pad)),
        std::array::from_fn(|i| f32_up(hi[i] + pad)),
    )
}

impl<const N: usize> Bvh<N> {
    /// This tree over its simplices moved: `points(id)` gives the new vertices of the simplex
    /// with id `id`. Hits are bit for bit those of a tree built over the moved simplices that
    /// this tree holds (see the module docs; a simplex it left out as degenerate is not added,
    /// even if the move made it valid: the caller checks that). `None` when a simplex the tree
    /// holds is degenerate once moved, or a flat cell no longer passes its checks: build anew
    /// then.
    pub fn refit(&self, points: impl Fn(u32) -> [Vector<N>; N] + Sync) -> Option<Self> {
        let mut blocks = self.blocks.clone();
        // The blocks prepared again, and their boxes.
        let boxes: Vec<Box32<N>> = blocks
            .par_iter_mut()
            .with_min_len(256)
            .map(|b| {
                let mut bx = empty();
                for l in 0..b.count as usize {
                    let pts = points(b.ids[l]);
                    b.set_lane(l, &PreparedSimplex::new(&pts)?);
                    bx = union(bx, padded(simplex_bounds(&pts)));
                }
                Some(bx)
            })
            .collect::<Option<_>>()?;
        // The cells checked again (their walk's thresholds depend on the geometry), and their
        // boxes: the members' bounds, padded as the build pads a cell's.
        let mut cells = self.cells.clone();
        let mut cell_links = self.cell_links.clone();
        let cell_boxes: Vec<Box32<N>> = cells
            .par_iter_mut()
            .zip(
                // Each cell's own run of links.
                self.cells
                    .iter()
                    .map(|c| c.links as usize..(c.links + c.count) as usize)
                    .collect::<Vec<_>>(),
            )
            .map(|(cell, links)| {
                let ids: Vec<u32> = (cell.blocks())
                    .flat_map(|b| {
                        let b = &blocks[b as usize];
                        b.ids[..b.count as usize].to_vec()
                    })
                    .collect();
                let pts: Vec<[Vector<N>; N]> = ids.iter().map(|&id| points(id)).collect();
                let prepared = pts
                    .iter()
                    .map(PreparedSimplex::new)
                    .collect::<Option<_>>()?;
                let g = CellGeometry::new(&pts, prepared)?;
                let (mut lo, mut hi) = ([f64::INFINITY; N], [f64::NEG_INFINITY; N]);
                for p in &pts {
                    let (a, b) = simplex_bounds(p);
                    for i in 0..N {
                        lo[i] = lo[i].min(a[i]);
                        hi[i] = hi[i].max(b[i]);
                    }
                }
                (cell.start, cell.tau, cell.err0, cell.trusted) =
                    (g.start, g.tau, g.err0, g.trusted);
                Some((padded((lo, hi)), g.neighbours, links))
            })
            .collect::<Option<Vec<_>>>()?
            .into_iter()
            .map(|(bx, neighbours, links)| {
                cell_links[links].copy_from_slice(&neighbours);
                bx
            })
            .collect();
        // The nodes' slots, bottom-up (children come after their parent).
        let mut nodes = self.nodes.clone();
        for i in (0..nodes.len()).rev() {
            for l in 0..NODE_WIDTH {
                let c = nodes[i].child[l];
                let (lo, hi) = if c == EMPTY_SLOT {
                    continue;
                } else if c & (LEAF_TAG | CELL_TAG) == LEAF_TAG | CELL_TAG {
                    cell_boxes[(c & !(LEAF_TAG | CELL_TAG)) as usize]
                } else if c & LEAF_TAG != 0 {
                    boxes[(c & !LEAF_TAG) as usize]
                } else {
                    let child = &nodes[c as usize];
                    (0..NODE_WIDTH).fold(empty(), |acc, k| {
                        union(
                            acc,
                            (
                                std::array::from_fn(|a| child.bounds[0][a][k]),
                                std::array::from_fn(|a| child.bounds[1][a][k]),
                            ),
                        )
                    })
                };
                for a in 0..N {
                    nodes[i].bounds[0][a][l] = lo[a];
                    nodes[i].bounds[1][a][l] = hi[a];
                }
            }
        }
        let reach = nodes.first().map_or(0.0, WideNode::reach);
        Some(Bvh {
            nodes,
            blocks,
            len: self.len,
            reach,
            ranges: self.ranges.clone(),
            cells,
            cell_links,
        })
    }
}
