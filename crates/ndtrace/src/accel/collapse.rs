//! The collapse of the binary SAH tree into the wide tree: which binary nodes become wide nodes
//! (the optimal plan), the leaf blocks, and the id ranges of every child slot.

use super::cell::{Cell, CellGeometry};
use super::simplex::PreparedSimplex;
use super::tree::{
    half_area, BinaryNode, Lane, LeafBlock, WideNode, BLOCK_WIDTH, CELL_TAG, EMPTY_SLOT, LEAF_TAG,
    NODE_WIDTH,
};

/// The mark of a flat cell in the leaf order: `CELL_MARK | c` is cell c of the build's list.
pub(super) const CELL_MARK: u32 = 1 << 31;
/// How far ahead in the leaf order the fill asks for the simplices' references, and then for
/// what they point to (see `wide_tree`).
const WARM_FAR: usize = 3 * BLOCK_WIDTH;
const WARM_NEAR: usize = BLOCK_WIDTH;
use rayon::prelude::*;

/// A leaf block as the layout places it, filled once the layout is done (and the binary tree
/// is gone): `count` simplices from position `first` of the leaf order, or the `chunk`-th
/// [`BLOCK_WIDTH`] members of flat cell `cell` of the build's list.
#[derive(Clone, Copy)]
enum Pending {
    Order { first: u32, count: u32 },
    Cell { cell: u32, chunk: u32 },
}

/// How each binary subtree is laid out in the wide tree: the optimal collapse of Ylitie,
/// Karras and Laine ("Efficient incoherent ray traversal on GPUs through compressed wide BVHs",
/// HPG 2017, §4.1), a dynamic program over the binary tree.
///
/// The leaves are the binary tree's and each is tested exactly when its own box is met, so
/// the collapse only decides which binary inner nodes become wide nodes. A ray visits a wide
/// node (one slab test of all its slots, whatever their number) with probability proportional
/// to the node's [`half_area`], so the plan minimises the sum of the wide nodes' half areas.
/// With `S(b, k)` the least cost of holding subtree b in at most k slots of its parent:
///
/// * a leaf takes one slot at no cost: `S(b, k) = 0`;
/// * an inner node in one slot is the root of a wide node: `S(b, 1) = A(b) + D(b, 8)`, where
///   `D(b, k) = min_{1 ≤ j < k} S(left, j) + S(right, k − j)` shares k slots between its
///   children;
/// * with more slots it may also be opened: `S(b, k) = min(S(b, k − 1), D(b, k))`.
///
/// The greedy rule (open the child of largest area until 8 slots are used) leaves a small wide
/// node wherever a subtree did not fit (on large meshes, most nodes then hold 2 leaves).
pub(super) struct CollapsePlan {
    /// `slots[b][k − 1]`: how subtree b fills at most k slots: `[0, 0]` in one slot (a leaf
    /// or a wide node's root), else `[j, m]`, j slots to the left child and m to the right.
    pub(super) slots: Vec<[[u8; 2]; NODE_WIDTH]>,
    /// The split of the `NODE_WIDTH` slots of the wide node rooted at inner node b.
    pub(super) wide: Vec<[u8; 2]>,
}

impl CollapsePlan {
    /// The plan of the binary tree `bin` (in depth-first order), by a walk that returns each
    /// subtree's costs to its parent (no list of them is kept), forking for subtrees of at
    /// least `PLAN_PAR_MIN` nodes. Every row depends on its children's only, so the plan is the
    /// same for any number of threads.
    pub(super) fn new<const N: usize>(bin: &[BinaryNode<N>]) -> Self {
        let n = bin.len();
        let mut slots = vec![[[0u8; 2]; NODE_WIDTH]; n];
        let mut wide = vec![[0u8; 2]; n];
        if n > 0 {
            plan_subtree(bin, 0, &mut slots, &mut wide);
        }
        CollapsePlan { slots, wide }
    }

    /// Appends to `kids`, in left-to-right order, the binary nodes that subtree b puts in its
    /// at most k slots.
    pub(super) fn expand<const N: usize>(
        &self,
        bin: &[BinaryNode<N>],
        b: usize,
        k: usize,
        kids: &mut Vec<usize>,
    ) {
        match self.slots[b][k - 1] {
            [0, _] => kids.push(b),
            [j, m] => {
                self.expand(bin, b + 1, j as usize, kids);
                self.expand(bin, bin[b].first as usize, m as usize, kids);
            }
        }
    }
}

/// Subtrees of at least this many binary nodes are planned in parallel.
pub(super) const PLAN_PAR_MIN: usize = 1 << 14;

/// Plans the subtree of binary node b, whose nodes' rows of `slots` and `wide` are the given
/// slices (node b first, in depth-first order), and returns its costs `S(b, k)`.
fn plan_subtree<const N: usize>(
    bin: &[BinaryNode<N>],
    b: usize,
    slots: &mut [[[u8; 2]; NODE_WIDTH]],
    wide: &mut [[u8; 2]],
) -> [f64; NODE_WIDTH] {
    if bin[b].count > 0 {
        return [0.0; NODE_WIDTH];
    }
    // Node b, its left subtree from b + 1, its right one from `first`.
    let (size, right) = (slots.len(), bin[b].first as usize - b);
    let (me, rest) = slots.split_at_mut(1);
    let (left_slots, right_slots) = rest.split_at_mut(right - 1);
    let (me_wide, rest) = wide.split_at_mut(1);
    let (left_wide, right_wide) = rest.split_at_mut(right - 1);
    let (l, r) = if size >= PLAN_PAR_MIN {
        rayon::join(
            || plan_subtree(bin, b + 1, left_slots, left_wide),
            || plan_subtree(bin, b + right, right_slots, right_wide),
        )
    } else {
        (
            plan_subtree(bin, b + 1, left_slots, left_wide),
            plan_subtree(bin, b + right, right_slots, right_wide),
        )
    };
    // The best sharing of k slots between the children (ties: fewest to the left).
    let share = |k: usize| {
        let mut best = (f64::INFINITY, [1u8, (k - 1) as u8]);
        for j in 1..k {
            let c = l[j - 1] + r[k - j - 1];
            if c < best.0 {
                best = (c, [j as u8, (k - j) as u8]);
            }
        }
        best
    };
    let (d, w) = share(NODE_WIDTH);
    let mut row = [(0.0, [0u8; 2]); NODE_WIDTH];
    // A NaN area (from infinite bounds) counts as infinite.
    let area = half_area(&bin[b].min.map(f64::from), &bin[b].max.map(f64::from));
    row[0].0 = if area.is_nan() { f64::INFINITY } else { area } + d;
    for k in 2..=NODE_WIDTH {
        // D(b, NODE_WIDTH) is already known.
        let (c, how) = if k == NODE_WIDTH { (d, w) } else { share(k) };
        // Opening b must gain: on a tie, fewer slots.
        row[k - 1] = if c < row[k - 2].0 {
            (c, how)
        } else {
            row[k - 2]
        };
    }
    me_wide[0] = w;
    me[0] = row.map(|(_, how)| how);
    row.map(|(c, _)| c)
}

/// Collapses the binary tree into wide nodes and blocks (both in depth-first order).
struct Collapse<'a, const N: usize> {
    bin: &'a [BinaryNode<N>],
    plan: CollapsePlan,
    /// The leaf order: `order[j]` is the input index of the j-th simplex in leaf order (or
    /// `CELL_MARK | c` for cell c).
    order: &'a [u32],
    /// The flat cells of the build (members, geometry), and those made so far with their links.
    cells_in: &'a [(Vec<u32>, CellGeometry<N>)],
    cells: Vec<Cell>,
    cell_links: Vec<[u32; N]>,
    cell_prepared: Vec<PreparedSimplex<N>>,
    nodes: Vec<WideNode<N>>,
    /// The blocks, in order, filled afterwards (in parallel).
    blocks: Vec<Pending>,
}

impl<const N: usize> Collapse<'_, N> {
    /// The reference (node index, `LEAF_TAG | block` or a flat cell's) of binary node `b`'s subtree.
    fn child_ref(&mut self, b: usize) -> u32 {
        if self.bin[b].count > 0 {
            self.leaf(b)
        } else {
            self.node(b)
        }
    }

    fn leaf(&mut self, b: usize) -> u32 {
        let nd = self.bin[b];
        let first = self.order[nd.first as usize];
        if first & CELL_MARK != 0 {
            debug_assert_eq!(nd.count, 1);
            return self.cell((first & !CELL_MARK) as usize);
        }
        self.push_block(Pending::Order {
            first: nd.first,
            count: nd.count,
        })
    }

    /// Appends a block; its reference.
    fn push_block(&mut self, block: Pending) -> u32 {
        assert!(
            self.blocks.len() < CELL_TAG as usize,
            "Bvh::build: too many blocks"
        );
        self.blocks.push(block);
        LEAF_TAG | (self.blocks.len() - 1) as u32
    }

    /// The blocks of flat cell c (its members in order) and its reference.
    fn cell(&mut self, c: usize) -> u32 {
        let (members, geometry) = &self.cells_in[c];
        let first_block = self.blocks.len() as u32;
        for chunk in 0..members.len().div_ceil(BLOCK_WIDTH) as u32 {
            self.push_block(Pending::Cell {
                cell: c as u32,
                chunk,
            });
        }
        assert!(
            self.cells.len() < (CELL_TAG - 1) as usize,
            "Bvh::build: too many cells"
        );
        self.cells.push(Cell {
            first_block,
            end_block: self.blocks.len() as u32,
            count: members.len() as u32,
            links: self.cell_links.len() as u32,
            start: geometry.start,
            tau: geometry.tau,
            err0: geometry.err0,
            trusted: geometry.trusted,
        });
        self.cell_links.extend_from_slice(&geometry.neighbours);
        self.cell_prepared.extend_from_slice(&geometry.prepared);
        LEAF_TAG | CELL_TAG | (self.cells.len() - 1) as u32
    }

    /// The wide node over binary inner node `b`: its children as the [`CollapsePlan`] lays them out,
    /// in left-to-right order.
    fn node(&mut self, b: usize) -> u32 {
        let [j, m] = self.plan.wide[b];
        let mut kids = Vec::with_capacity(NODE_WIDTH);
        self.plan.expand(self.bin, b + 1, j as usize, &mut kids);
        self.plan
            .expand(self.bin, self.bin[b].first as usize, m as usize, &mut kids);
        debug_assert!((2..=NODE_WIDTH).contains(&kids.len()));
        let me = self.nodes.len();
        self.nodes.push(WideNode::EMPTY);
        for (l, &c) in kids.iter().enumerate() {
            let r = self.child_ref(c);
            let nd = &mut self.nodes[me];
            nd.child[l] = r;
            for i in 0..N {
                nd.bounds[0][i][l] = self.bin[c].min[i];
                nd.bounds[1][i][l] = self.bin[c].max[i];
            }
        }
        me as u32
    }
}

/// The id range of every child of every node (see `Bvh::ranges`). Children come after their
/// parent in depth-first order, so one pass from the last node up sees every child first.
pub(super) fn id_ranges<const N: usize>(
    nodes: &[WideNode<N>],
    blocks: &[LeafBlock<N>],
    cells: &[Cell],
) -> Vec<[[u32; NODE_WIDTH]; 2]> {
    // Each block's, in parallel (the blocks were just filled by all threads).
    let block_ranges: Vec<(u32, u32)> = (blocks.par_iter())
        .map(|b| {
            let ids = &b.ids[..b.count()];
            (
                ids.iter().copied().min().unwrap(),
                ids.iter().copied().max().unwrap(),
            )
        })
        .collect();
    let block_range = |b: u32| block_ranges[b as usize];
    let mut ranges = vec![[[u32::MAX; NODE_WIDTH], [0; NODE_WIDTH]]; nodes.len()];
    for i in (0..nodes.len()).rev() {
        for l in 0..NODE_WIDTH {
            let c = nodes[i].child[l];
            let (lo, hi) = if c == EMPTY_SLOT {
                (u32::MAX, 0)
            } else if c & (LEAF_TAG | CELL_TAG) == LEAF_TAG | CELL_TAG {
                let cell = &cells[(c & !(LEAF_TAG | CELL_TAG)) as usize];
                cell.blocks()
                    .map(block_range)
                    .fold((u32::MAX, 0), |(a, b), (c, d)| (a.min(c), b.max(d)))
            } else if c & LEAF_TAG != 0 {
                block_range(c & !LEAF_TAG)
            } else {
                let r = &ranges[c as usize];
                (
                    r[0].iter().copied().min().unwrap(),
                    r[1].iter().copied().max().unwrap(),
                )
            };
            ranges[i][0][l] = lo;
            ranges[i][1][l] = hi;
        }
    }
    ranges
}

/// The wide tree: nodes and leaf blocks (both in depth-first order), flat cells and their links.
pub(super) struct WideTree<const N: usize> {
    pub(super) nodes: Vec<WideNode<N>>,
    pub(super) blocks: Vec<LeafBlock<N>>,
    pub(super) cells: Vec<Cell>,
    pub(super) cell_links: Vec<[u32; N]>,
    pub(super) cell_prepared: Vec<PreparedSimplex<N>>,
}

/// The wide tree over the binary tree `bin` with leaf order `order` (input indices, and
/// `CELL_MARK | c` for the flat cells `cells`), laid out by the [`CollapsePlan`]; `lane(i)`
/// and `ids[i]` are the input simplices, and `warm(i, near)` asks for what `lane(i)` reads
/// (`near`: after its reference). The binary tree and the plan are dropped once the
/// layout is known, before the blocks are made; the blocks are then filled in parallel, so
/// that the binary tree is not alive beside them.
pub(super) fn wide_tree<const N: usize>(
    bin: Vec<BinaryNode<N>>,
    order: &[u32],
    (lane, warm): (
        impl Fn(usize) -> Lane<N> + Sync,
        impl Fn(usize, bool) + Sync,
    ),
    ids: &[u32],
    cells: &[(Vec<u32>, CellGeometry<N>)],
) -> WideTree<N> {
    let plan = CollapsePlan::new(&bin);
    let mut c = Collapse {
        bin: &bin,
        plan,
        order,
        cells_in: cells,
        cells: Vec::with_capacity(cells.len()),
        cell_links: Vec::new(),
        cell_prepared: Vec::new(),
        nodes: Vec::new(),
        blocks: Vec::with_capacity(bin.iter().filter(|b| b.count > 0).count()),
    };
    if bin[0].count > 0 {
        // A single leaf: a root node with one child.
        c.nodes.push(WideNode::EMPTY);
        let r = c.leaf(0);
        c.nodes[0].child[0] = r;
        for i in 0..N {
            c.nodes[0].bounds[0][i][0] = bin[0].min[i];
            c.nodes[0].bounds[1][i][0] = bin[0].max[i];
        }
    } else {
        c.node(0);
    }
    let Collapse {
        mut nodes,
        blocks: pending,
        cells: made,
        cell_links,
        cell_prepared,
        plan,
        ..
    } = c;
    drop((bin, plan));
    nodes.shrink_to_fit();
    let blocks = pending
        .par_iter()
        .with_min_len(256)
        .map(|&p| {
            let mut block = LeafBlock::EMPTY;
            match p {
                Pending::Order { first, count } => {
                    let (first, count) = (first as usize, count as usize);
                    // The simplices of the next blocks in leaf order are asked for ahead
                    // (`warm`): in a large mesh each lies somewhere else in memory, and the
                    // lanes would wait for it in turn. Their references first, far ahead; the
                    // data they point to once the references are likely in.
                    for (ahead, near) in [(WARM_FAR, false), (WARM_NEAR, true)] {
                        let end = (first + ahead + count).min(order.len());
                        let at = (first + ahead).min(end)..end;
                        for &i in order[at].iter().filter(|&&i| i & CELL_MARK == 0) {
                            warm(i as usize, near);
                        }
                    }
                    for l in 0..count {
                        let i = order[first + l] as usize;
                        block.set_lane(l, &lane(i), ids[i]);
                    }
                }
                Pending::Cell { cell, chunk } => {
                    let (members, geometry) = &cells[cell as usize];
                    let at = chunk as usize * BLOCK_WIDTH..;
                    let (members, prepared) = (&members[at.clone()], &geometry.prepared[at]);
                    for (l, (&i, p)) in members.iter().zip(prepared).take(BLOCK_WIDTH).enumerate() {
                        block.set_lane(l, &Lane::of(p), ids[i as usize]);
                    }
                }
            }
            block
        })
        .collect();
    WideTree {
        nodes,
        blocks,
        cells: made,
        cell_links,
        cell_prepared,
    }
}

#[cfg(test)]
mod tests;
