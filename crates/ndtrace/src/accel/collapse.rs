//! The collapse of the binary SAH tree into the wide tree: which binary nodes become wide nodes
//! (the optimal plan), the leaf blocks, and the id ranges of every child slot.

use super::simplex::PreparedSimplex;
use super::tree::{
    half_area, BinaryNode, LeafBlock, WideNode, BLOCK_WIDTH, EMPTY_SLOT, LEAF_TAG, NODE_WIDTH,
};
use rayon::prelude::*;

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
    pub(super) fn new<const N: usize>(bin: &[BinaryNode<N>]) -> Self {
        let n = bin.len();
        let mut cost = vec![[0.0f64; NODE_WIDTH]; n];
        let mut slots = vec![[[0u8; 2]; NODE_WIDTH]; n];
        let mut wide = vec![[0u8; 2]; n];
        // Children come after their parent in depth-first order: one pass from the end.
        for b in (0..n).rev() {
            if bin[b].count > 0 {
                continue;
            }
            let (l, r) = (b + 1, bin[b].first as usize);
            // The best sharing of k slots between the children (ties: fewest to the left).
            let share = |k: usize| {
                let mut best = (f64::INFINITY, [1u8, (k - 1) as u8]);
                for j in 1..k {
                    let c = cost[l][j - 1] + cost[r][k - j - 1];
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
            wide[b] = w;
            for k in 0..NODE_WIDTH {
                cost[b][k] = row[k].0;
                slots[b][k] = row[k].1;
            }
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

/// Collapses the binary tree into wide nodes and blocks (both in depth-first order).
struct Collapse<'a, const N: usize> {
    bin: &'a [BinaryNode<N>],
    plan: CollapsePlan,
    /// The input ids, and the leaf order: `order[j]` is the input index of the j-th simplex in
    /// leaf order.
    ids: &'a [u32],
    order: &'a [u32],
    nodes: Vec<WideNode<N>>,
    /// The blocks, their simplices' ids set and their prepared simplices filled in afterwards
    /// (in parallel) from `block_first`, the position of each block's first simplex in `order`.
    blocks: Vec<LeafBlock<N>>,
    block_first: Vec<u32>,
}

impl<const N: usize> Collapse<'_, N> {
    /// The reference (node index or `LEAF_TAG | block`) of binary node `b`'s subtree.
    fn child_ref(&mut self, b: usize) -> u32 {
        if self.bin[b].count > 0 {
            self.leaf(b)
        } else {
            self.node(b)
        }
    }

    fn leaf(&mut self, b: usize) -> u32 {
        let nd = self.bin[b];
        let mut block = LeafBlock {
            m: [[[0.0; BLOCK_WIDTH]; N]; N],
            x0: [[0.0; BLOCK_WIDTH]; N],
            ids: [EMPTY_SLOT; BLOCK_WIDTH],
            count: nd.count,
        };
        for l in 0..nd.count as usize {
            block.ids[l] = self.ids[self.order[nd.first as usize + l] as usize];
        }
        self.blocks.push(block);
        self.block_first.push(nd.first);
        LEAF_TAG | (self.blocks.len() - 1) as u32
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
) -> Vec<[[u32; NODE_WIDTH]; 2]> {
    let mut ranges = vec![[[u32::MAX; NODE_WIDTH], [0; NODE_WIDTH]]; nodes.len()];
    for i in (0..nodes.len()).rev() {
        for l in 0..NODE_WIDTH {
            let c = nodes[i].child[l];
            let (lo, hi) = if c == EMPTY_SLOT {
                (u32::MAX, 0)
            } else if c & LEAF_TAG != 0 {
                let b = &blocks[(c & !LEAF_TAG) as usize];
                let ids = &b.ids[..b.count as usize];
                (
                    ids.iter().copied().min().unwrap(),
                    ids.iter().copied().max().unwrap(),
                )
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

/// The wide nodes and leaf blocks (both in depth-first order) over the binary tree `bin` with
/// leaf order `order`, laid out by the [`CollapsePlan`]; `prepare(i)` and `ids[i]` are the
/// input simplices. The blocks' simplices are prepared in parallel once the layout is known,
/// so that no list of prepared simplices is alive beside the blocks.
pub(super) fn wide_tree<const N: usize>(
    bin: &[BinaryNode<N>],
    order: &[u32],
    prepare: impl Fn(usize) -> PreparedSimplex<N> + Sync,
    ids: &[u32],
) -> (Vec<WideNode<N>>, Vec<LeafBlock<N>>) {
    let plan = CollapsePlan::new(bin);
    let mut c = Collapse {
        bin,
        plan,
        ids,
        order,
        nodes: Vec::new(),
        blocks: Vec::with_capacity(bin.iter().filter(|b| b.count > 0).count()),
        block_first: Vec::new(),
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
    let (mut nodes, mut blocks) = (c.nodes, c.blocks);
    (blocks.par_iter_mut().zip(c.block_first))
        .with_min_len(256)
        .for_each(|(block, first)| {
            for l in 0..block.count as usize {
                let p = prepare(order[first as usize + l] as usize);
                for k in 0..N {
                    for i in 0..N {
                        block.m[k][i][l] = p.m[k][i];
                    }
                }
                for i in 0..N {
                    block.x0[i][l] = p.x0[i];
                }
            }
        });
    nodes.shrink_to_fit();
    blocks.shrink_to_fit();
    (nodes, blocks)
}
