//! The Morton build of the wide tree for very large inputs ([`Bvh::build_morton`]): linear-time
//! grouping instead of the SAH, and no per-simplex memory beyond the finished tree's.
//!
//! 1. Each simplex gets the Morton code of its box centre: the centre quantised inside the box
//!    of all vertices, the bits interleaved (most significant first), so that sorting by code
//!    lays the simplices out along a Z-order curve (Lauterbach et al., "Fast BVH construction on
//!    GPUs", 2009). The sort key is the code above the simplex's index in one u64 (the index
//!    takes the bits it needs, the axes share the rest).
//! 2. Sorted by (code, index), consecutive runs of [`BLOCK_WIDTH`] simplices become the leaf
//!    blocks, so every block but the last is full.
//! 3. The wide nodes group the blocks by the leading bits of their codes: a range is halved at
//!    the highest bit in which its first and last code differ (a binary radix tree over the
//!    codes), and each wide node takes the eight largest ranges that halving its range gives;
//!    a range of at most [`NODE_WIDTH`] blocks is one node over them, a range of one block a
//!    leaf slot, equal codes are split by count.
//! 4. Boxes are computed bottom-up from the simplices' vertices (each padded by
//!    [`BOX_PAD`](super::BOX_PAD) of its largest extent, as in the SAH build) and rounded
//!    outward to `f32`; the nodes are made before the leaf blocks (the prepared simplices),
//!    so that the per-block boxes are gone when the big blocks arrive.
//!
//! Every step depends on the input only (ties in the sort go to the lower index, the grouping
//! is sequential, the parallel passes write to fixed places), so the tree is the same for any
//! number of threads. Queries give the same results as over the SAH tree: a closest hit is the
//! minimum of (t, id) over the accepted hits whatever the tree's shape.

use super::build::BOX_PAD;
use super::simplex::{simplex_bounds, Bounds, PreparedSimplex};
use super::tree::{
    f32_down, f32_up, Bvh, ExactSource, Lane, LeafBlock, WideNode, BLOCK_WIDTH, LEAF_TAG,
    NODE_WIDTH,
};
use crate::linalg::Vector;
use rayon::prelude::*;

/// Scenes of at least this many simplices are built with [`Bvh::build_morton`] (about 2 M:
/// beyond it the SAH build's passes over all simplices and its per-simplex buffers, some
/// 400 bytes each in 4D, dominate loading; below it, the SAH tree's faster queries win).
pub const MORTON_MIN: usize = 1 << 21;

/// A child slot of the grouping: nothing, a leaf block, or a wide node (by index).
#[derive(Clone, Copy)]
enum Slot {
    Empty,
    Block(u32),
    Node(u32),
}

/// `SPREAD[n][b]`: the 8 bits of byte b moved to bits 0, n, 2n, … (n = 2 … 8), so that the
/// Morton code interleaves whole bytes of the axes' quantised coordinates at once.
static SPREAD: [[u64; 256]; 9] = {
    let mut t = [[0u64; 256]; 9];
    let mut n = 2;
    while n <= 8 {
        let mut b = 0;
        while b < 256 {
            let mut j = 0;
            while j < 8 {
                t[n][b] |= (((b >> j) & 1) as u64) << (j * n);
                j += 1;
            }
            b += 1;
        }
        n += 1;
    }
    t
};

/// Quantises `c` into the box `lo + [0, top/scale]` with `bits ≤ 64/N` bits per axis
/// (`top = 2^bits − 1`) and interleaves the bits, most significant first (axis 0 leading
/// within each bit level).
pub(super) fn morton<const N: usize>(
    c: &Vector<N>,
    lo: &Vector<N>,
    scale: &Vector<N>,
    bits: usize,
) -> u64 {
    let top = ((1u128 << bits) - 1) as f64;
    let spread = &SPREAD[N];
    let mut code = 0u64;
    for a in 0..N {
        // NaN (a non-finite simplex, dropped later) quantises to 0 through `as`.
        let q = ((c[a] - lo[a]) * scale[a]).clamp(0.0, top) as u64;
        // Bit j of q goes to bit j·N + (N − 1 − a).
        let mut s = 0u64;
        let mut byte = 0;
        while byte * 8 < bits {
            s |= spread[((q >> (8 * byte)) & 0xff) as usize] << (8 * byte * N);
            byte += 1;
        }
        code |= s << (N - 1 - a);
    }
    code
}

/// The box centre of a simplex.
fn centre<const N: usize>(p: &[[f64; N]; N]) -> Vector<N> {
    std::array::from_fn(|i| {
        let (lo, hi) = p
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(v[i]), h.max(v[i]))
            });
        0.5 * (lo + hi)
    })
}

/// What the grouping needs of a leaf block: its box, rounded outward to f32, and the least and
/// greatest id it holds.
struct BlockInfo<const N: usize> {
    lo: [f32; N],
    hi: [f32; N],
    ids: [u32; 2],
}

/// Ranges of at least this many blocks have their children grouped in parallel.
const PAR_BLOCKS: usize = 1 << 14;

/// The two halves of the blocks `x..y` (at least 2, with sorted `keys`): split at the highest
/// bit in which the range's first and last key differ (every key of the range shares the bits
/// above it, so the keys with that bit clear come first), or in the middle if all are equal.
fn halves(keys: &[u64], x: usize, y: usize) -> [(usize, usize); 2] {
    let diff = keys[x] ^ keys[y - 1];
    let m = if diff == 0 {
        // Equal keys (not made by `build_morton`, whose keys hold the index).
        (x + y) / 2
    } else {
        let bit = 63 - diff.leading_zeros();
        x + keys[x..y].partition_point(|&k| (k >> bit) & 1 == 0)
    };
    [(x, m), (m, y)]
}

/// The ≤ 8 sub-ranges that the blocks `a..b` (more than [`NODE_WIDTH`] of them) split into: the
/// binary radix tree over their keys ([`halves`]) collapsed into one wide node. Ranges of more
/// than [`NODE_WIDTH`] blocks are halved, the largest first (the first of equal ones), while
/// there is room; then ranges small enough to fit are opened into single blocks, the smallest
/// first, so that few nodes hold only a few blocks (a level of the code's bits that divides
/// nothing, along a thin axis say, costs no node).
fn split(keys: &[u64], a: usize, b: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::with_capacity(NODE_WIDTH);
    out.push((a, b));
    while out.len() < NODE_WIDTH {
        let (i, &(x, y)) = out
            .iter()
            .enumerate()
            .rev()
            .max_by_key(|(_, r)| r.1 - r.0)
            .expect("at least one range");
        if y - x <= NODE_WIDTH {
            break;
        }
        out.splice(i..=i, halves(keys, x, y));
    }
    loop {
        let room = NODE_WIDTH + 1 - out.len();
        let Some((i, &(x, y))) = out
            .iter()
            .enumerate()
            .filter(|(_, r)| (2..=room).contains(&(r.1 - r.0)))
            .min_by_key(|(_, r)| r.1 - r.0)
        else {
            break;
        };
        out.splice(i..=i, (x..y).map(|k| (k, k + 1)));
    }
    out
}

/// The children of the node over blocks `a..b` (at least 2).
fn parts(keys: &[u64], a: usize, b: usize) -> Vec<(usize, usize)> {
    if b - a <= NODE_WIDTH {
        (a..b).map(|i| (i, i + 1)).collect()
    } else {
        split(keys, a, b)
    }
}

/// The 8-ary grouping of the blocks `a..b` (at least 2) as wide nodes in depth-first order,
/// children after their parent, node indices relative to the first (this subtree's root).
/// Large ranges group their children in parallel; the result does not depend on it.
fn grouping(keys: &[u64], a: usize, b: usize) -> Vec<[Slot; NODE_WIDTH]> {
    let mut out = Vec::new();
    if b - a < PAR_BLOCKS {
        grouping_seq(keys, a, b, &mut out);
        return out;
    }
    let parts = parts(keys, a, b);
    let subtrees: Vec<Option<Vec<[Slot; NODE_WIDTH]>>> = parts
        .par_iter()
        .map(|&(x, y)| (y - x > 1).then(|| grouping(keys, x, y)))
        .collect();
    out.push([Slot::Empty; NODE_WIDTH]);
    for (l, (&(x, _), sub)) in parts.iter().zip(subtrees).enumerate() {
        out[0][l] = match sub {
            None => Slot::Block(x as u32),
            Some(nodes) => {
                let base = out.len() as u32;
                out.extend(nodes.into_iter().map(|slots| {
                    slots.map(|s| match s {
                        Slot::Node(j) => Slot::Node(j + base),
                        other => other,
                    })
                }));
                Slot::Node(base)
            }
        };
    }
    out
}

/// [`grouping`] in one thread, appending to `out` (indices relative to the start of `out`).
fn grouping_seq(keys: &[u64], a: usize, b: usize, out: &mut Vec<[Slot; NODE_WIDTH]>) -> u32 {
    let me = out.len();
    out.push([Slot::Empty; NODE_WIDTH]);
    for (l, (x, y)) in parts(keys, a, b).into_iter().enumerate() {
        let slot = if y - x == 1 {
            Slot::Block(x as u32)
        } else {
            Slot::Node(grouping_seq(keys, x, y, out))
        };
        out[me][l] = slot;
    }
    me as u32
}

impl<const N: usize> Bvh<N> {
    /// The Morton build (see the module `morton`) over `count` simplices, simplex i being
    /// `simplex(i)` with id i, whose vertices lie in the box `domain` (it sets the quantisation
    /// of the codes; a simplex outside it only loses locality); degenerate and non-finite ones are left out, as in
    /// [`Bvh::from_simplices`]. Linear work after one sort, parallel, and lean: besides the
    /// finished tree it holds 8 bytes per simplex (the sort keys) and the blocks' boxes.
    /// Queries return the same hits as over the SAH build; the tree is looser, so they are
    /// somewhat slower on irregular meshes.
    ///
    /// # Panics
    /// If `count` is 2³¹ or more.
    pub fn build_morton(
        count: usize,
        domain: Bounds<N>,
        simplex: impl Fn(usize) -> [[f64; N]; N] + Send + Sync + 'static,
    ) -> Self {
        let simplex = std::sync::Arc::new(simplex);
        let at = simplex.clone();
        let exact = ExactSource::new(move |id| {
            PreparedSimplex::new(&at(id as usize)).expect("a simplex prepared once prepares again")
        });
        Self::build_morton_with_ids(count, domain, |i| simplex(i), |i| i as u32, exact)
    }

    /// [`Bvh::build_morton`] with simplex i given the id `id_of(i)` (increasing in i: the
    /// tree's id ranges keep their order), so that a tree may hold some of a scene's simplices
    /// under their global ids; `exact` gives the exact simplex of an id (see [`ExactSource`]).
    ///
    /// # Panics
    /// If `count` is 2³¹ or more.
    pub fn build_morton_with_ids(
        count: usize,
        domain: Bounds<N>,
        simplex: impl Fn(usize) -> [[f64; N]; N] + Sync,
        id_of: impl Fn(usize) -> u32 + Sync,
        exact: ExactSource<N>,
    ) -> Self {
        assert!(
            count < LEAF_TAG as usize,
            "Bvh::build_morton: too many simplices"
        );
        let empty = Bvh {
            nodes: Vec::new(),
            blocks: Vec::new(),
            len: 0,
            reach: 0.0,
            ranges: Vec::new(),
            cells: Vec::new(),
            cell_links: Vec::new(),
            cell_prepared: Vec::new(),
            exact: exact.clone(),
            exact_rows: Vec::new(),
        };
        if count == 0 {
            return empty;
        }
        // 1. Codes, quantised in the box of the simplices' vertices (it holds every centre).
        let (clo, chi) = domain;
        // A sort key is the code above the index: `bits` per axis in the 64 bits the index
        // leaves (the index breaks ties, so equal codes keep input order).
        let id_bits = (usize::BITS - (count - 1).leading_zeros()).max(1) as usize;
        let bits = (64 - id_bits) / N;
        let top = ((1u128 << bits) - 1) as f64;
        let scale: Vector<N> = std::array::from_fn(|i| {
            let s = top / (chi[i] - clo[i]);
            if s.is_finite() && s > 0.0 {
                s
            } else {
                0.0
            }
        });
        let mut order: Vec<u64> = (0..count)
            .into_par_iter()
            .map(|i| (morton(&centre(&simplex(i)), &clo, &scale, bits) << id_bits) | i as u64)
            .collect();
        // 2. Blocks of consecutive simplices in key order, with their boxes (each simplex's box
        //    padded by BOX_PAD of its largest extent) and least and greatest ids.
        order.par_sort_unstable();
        let id_mask = (1u64 << id_bits) - 1;
        let keys: Vec<u64> = order.par_chunks(BLOCK_WIDTH).map(|c| c[0]).collect();
        // The blocks' boxes and id ranges first, so that the tree's nodes exist before the big
        // leaf blocks are made. They cover every finite simplex of the block, degenerate ones
        // too (the blocks leave those out), which only makes them conservative.
        let infos: Vec<BlockInfo<N>> = order
            .par_chunks(BLOCK_WIDTH)
            .map(|run| {
                let (mut lo, mut hi) = ([f64::INFINITY; N], [f64::NEG_INFINITY; N]);
                let (mut first, mut last) = (u32::MAX, 0);
                for &key in run {
                    let id = (key & id_mask) as u32;
                    let pts = simplex(id as usize);
                    if !pts.iter().flatten().all(|x| x.is_finite()) {
                        continue;
                    }
                    let (a, b) = simplex_bounds(&pts);
                    let pad = BOX_PAD * (0..N).map(|i| b[i] - a[i]).fold(0.0, f64::max);
                    for i in 0..N {
                        lo[i] = lo[i].min(a[i] - pad);
                        hi[i] = hi[i].max(b[i] + pad);
                    }
                    first = first.min(id);
                    last = last.max(id);
                }
                BlockInfo {
                    lo: lo.map(f32_down),
                    hi: hi.map(f32_up),
                    ids: match first {
                        u32::MAX => [first, last],
                        _ => [id_of(first as usize), id_of(last as usize)],
                    },
                }
            })
            .collect();
        // 3. The grouping, then the wide nodes bottom-up.
        let block_count = infos.len();
        let groups = if block_count == 1 {
            let mut root = [Slot::Empty; NODE_WIDTH];
            root[0] = Slot::Block(0);
            vec![root]
        } else {
            grouping(&keys, 0, block_count)
        };
        drop(keys);
        // Children come after their parent: one pass from the last node up sees them first.
        let mut nodes = vec![WideNode::<N>::EMPTY; groups.len()];
        let mut ranges = vec![[[u32::MAX; NODE_WIDTH], [0; NODE_WIDTH]]; groups.len()];
        for i in (0..groups.len()).rev() {
            for (l, slot) in groups[i].iter().enumerate() {
                let (child, lo, hi, ids) = match *slot {
                    Slot::Empty => continue,
                    Slot::Block(b) if infos[b as usize].ids[0] == u32::MAX => continue,
                    Slot::Block(b) => {
                        let info = &infos[b as usize];
                        (LEAF_TAG | b, info.lo, info.hi, info.ids)
                    }
                    Slot::Node(j) => {
                        let (c, r) = (&nodes[j as usize], &ranges[j as usize]);
                        let lo = std::array::from_fn(|a| {
                            c.bounds[0][a].iter().copied().fold(f32::INFINITY, f32::min)
                        });
                        let hi = std::array::from_fn(|a| {
                            c.bounds[1][a]
                                .iter()
                                .copied()
                                .fold(f32::NEG_INFINITY, f32::max)
                        });
                        let ids = [
                            r[0].iter().copied().min().unwrap_or(u32::MAX),
                            r[1].iter().copied().max().unwrap_or(0),
                        ];
                        (j, lo, hi, ids)
                    }
                };
                let nd = &mut nodes[i];
                nd.child[l] = child;
                for a in 0..N {
                    nd.bounds[0][a][l] = lo[a];
                    nd.bounds[1][a][l] = hi[a];
                }
                ranges[i][0][l] = ids[0];
                ranges[i][1][l] = ids[1];
            }
        }
        drop(infos);
        drop(groups);
        // 4. The leaf blocks: the prepared simplices, in key order.
        let blocks: Vec<LeafBlock<N>> = order
            .par_chunks(BLOCK_WIDTH)
            .map(|run| {
                let mut block = LeafBlock::EMPTY;
                let mut l = 0;
                for &key in run {
                    let id = (key & id_mask) as u32;
                    let Some(p) = PreparedSimplex::new(&simplex(id as usize)) else {
                        continue;
                    };
                    block.set_lane(l, &Lane::of(&p), id_of(id as usize));
                    l += 1;
                }
                block
            })
            .collect();
        drop(order);
        let len: usize = blocks.par_iter().map(|b| b.count()).sum();
        if len == 0 {
            return empty;
        }
        let reach = nodes[0].reach();
        Bvh {
            nodes,
            blocks,
            len,
            reach,
            ranges,
            cells: Vec::new(),
            cell_links: Vec::new(),
            cell_prepared: Vec::new(),
            exact,
            exact_rows: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests;
