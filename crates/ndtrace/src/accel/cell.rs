//! Flat cells: the simplices that tile one flat, convex (N−1)-cell of a polytope's boundary,
//! held by the tree as one primitive.
//!
//! A facet of the N-cube is an (N−1)-cube, Kuhn-triangulated into (N−1)! simplices that all
//! share its diagonal: their boxes are nearly the facet's box, so no bounding-volume hierarchy
//! can separate them and a ray that meets the facet used to test all of them (720 for the
//! 7-cube). A [`Cell`] is the tree's leaf for such a facet. Its simplices stay in ordinary
//! blocks (consecutive, in the cell's order); a ray meets the cell's hyperplane (eq. 1, through
//! the start simplex) at X, and a *visibility walk* over the cell's simplices locates X: in
//! simplex S with barycentric coordinates b (the course's "Barycentric Coordinates"), step to
//! the neighbour across the facet of the most negative b_k, until every b_k is positive. Then
//! only S's block is tested, with the exact ray test of every other block: the hit and its id
//! are bit for bit those of testing every simplex of the cell.
//!
//! **Why the other simplices can be skipped** (all distances within the cell's hyperplane):
//! if every b_k ≥ τ, X lies at least τ·h from S's boundary (h the least height of a simplex of
//! the cell), hence at least τ·h from every other simplex S′ (their interiors are disjoint).
//! A point at distance δ from S′ has coordinates b′ whose negative parts sum to at least
//! δ/(2·diam S′) (the point Σ₊b′_j x′_j / Σ₊b′_j lies in S′ within 2·Σ₋|b′_j|·diam S′ of it),
//! so min_j b′_j ≤ −τ·a/(2(N−1)) with a = h/diam the cell's aspect. τ is chosen per cell so
//! that this is [`MARGIN`], a thousand times [`BARY_SLACK`](super::BARY_SLACK): S′'s own test,
//! which sees X within the rounding the walk allows (see below), rejects it. A walk that would
//! leave the cell across its boundary with b_k < −τ has X at least τ·h outside the (convex)
//! cell: a miss of every simplex, by the same bound.
//!
//! **When the walk is not trusted**, every block of the cell is tested, which is exact by
//! definition: when some |b_k| < τ (X near a ridge), when the walk takes more than
//! [`walk_limit`] steps, and when the ray is too close to parallel to the hyperplane for the
//! simplices' own hyperplanes (which differ from the start simplex's by the rounding of their
//! vertices, `residual`) to put their X within [`TRUST`]·h of the walk's.
//!
//! **What the build checks** before it makes a cell of the simplices it is given
//! ([`CellGeometry::new`]), keeping them as ordinary simplices otherwise: every simplex is
//! non-degenerate; every ridge (matched by the bits of its vertices' coordinates) belongs to one
//! or two of them, and two that share one lie on opposite sides of it; they are connected;
//! every vertex lies on the inner side of every boundary ridge (convex); they are flat
//! (`residual` ≤ 1e-9 of the diameter); and τ ≤ 10⁻². A Kuhn-triangulated (N−1)-cube has
//! a = 1/√(2(N−1)) and τ = 2(N−1)·MARGIN/a ≈ 5·10⁻⁵ at N = 8.

use super::simplex::{PreparedRay, PreparedSimplex, BARY_SLACK};
use crate::linalg::{dot, sub, Vector};

/// How far below −[`BARY_SLACK`] the coordinates of the simplices a walk skips are guaranteed
/// to be: 1000 × BARY_SLACK.
pub(super) const MARGIN: f64 = 1e-6;
/// The largest error, in barycentric units, the walk's hit point may carry with respect to the
/// hit point of any simplex's own test: a tenth of [`MARGIN`].
pub(super) const TRUST: f64 = 1e-7;
/// Largest τ a cell may need (a cell of slivers would fall back to testing everything).
const MAX_TAU: f64 = 1e-2;
/// The marker of a missing neighbour (a ridge on the cell's boundary).
pub(super) const NO_NEIGHBOUR: u32 = u32::MAX;

/// Simplices of a flat cell as the caller proposes them to [`Bvh::build_lazily_with_cells`](super::Bvh::build_lazily_with_cells):
/// the build checks them (see the module docs) and keeps them as ordinary simplices when they
/// do not form a flat convex cell.
#[derive(Debug, Clone, PartialEq)]
pub struct FlatCell<const N: usize> {
    /// The input indices (into the build's `ids` and `bounds`) of the cell's simplices.
    pub members: Vec<u32>,
    /// Their vertices, in the order their prepared simplices take them.
    pub points: Vec<[Vector<N>; N]>,
}

/// What the walk needs of a cell besides its simplices, found once at the build.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct CellGeometry<const N: usize> {
    /// Per simplex, the local index of its neighbour across the facet opposite each vertex
    /// ([`NO_NEIGHBOUR`] on the boundary).
    pub(super) neighbours: Vec<[u32; N]>,
    /// The simplex the walks start from (the one nearest the cell's centre).
    pub(super) start: u32,
    /// The threshold τ of the module docs.
    pub(super) tau: f64,
    /// The hit-point error independent of the ray: twice the residual plus the rounding of
    /// coordinates of the cell's magnitude.
    pub(super) err0: f64,
    /// [`TRUST`] × the least height: the hit-point error allowed, times |cos θ|.
    pub(super) trusted: f64,
    /// The prepared simplices, which fill the cell's blocks.
    pub(super) prepared: Vec<PreparedSimplex<N>>,
}

/// A flat cell in the tree: its simplices are the `count` lanes from block `first_block` on
/// (in the order of the cell's `neighbours`), in the blocks `first_block .. end_block`; its
/// links are `links .. links + count` of [`Bvh::cell_links`](super::Bvh).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Cell {
    pub(super) first_block: u32,
    pub(super) end_block: u32,
    pub(super) count: u32,
    pub(super) links: u32,
    pub(super) start: u32,
    pub(super) tau: f64,
    pub(super) err0: f64,
    pub(super) trusted: f64,
}

/// Which of a cell's simplices a ray must be tested against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Pick {
    /// None: the ray misses the cell.
    Miss,
    /// Those of the block of this simplex (the cell's own index): X lies well inside it.
    Simplex(u32),
    /// Every block of the cell.
    All,
}

/// Most steps a walk may take before the cell is tested whole: a Kuhn-triangulated
/// (N−1)-cube needs at most (N−1)(N−2)/2 (one per inversion of a permutation).
pub(super) const fn walk_limit(n: usize) -> usize {
    2 * n * n + 16
}

impl Cell {
    /// The blocks holding the cell's simplices.
    #[inline]
    pub(super) fn blocks(&self) -> std::ops::Range<u32> {
        self.first_block..self.end_block
    }

    /// Which simplices `ray` must be tested against (see the module docs). `links` are the
    /// cell's neighbour links, `plane` the unit normal and first vertex of its start simplex,
    /// and `bary(s, x)` the barycentric coordinates of x in simplex s of the cell.
    #[inline]
    pub(super) fn pick<const N: usize>(
        &self,
        links: &[[u32; N]],
        ray: &PreparedRay<N>,
        (n, x0): (Vector<N>, Vector<N>),
        bary: impl Fn(u32, &Vector<N>) -> [f64; N],
    ) -> Pick {
        // X: the ray meets the start simplex's hyperplane.
        let den = dot(&n, &ray.d);
        let p = sub(&x0, &ray.o);
        let reach = p.iter().chain(&ray.o).fold(0.0f64, |m, v| m.max(v.abs()));
        let err = self.err0 + 16.0 * N as f64 * f64::EPSILON * reach;
        let d_len = dot(&ray.d, &ray.d).sqrt();
        // Near-parallel rays (and NaN): the simplices' own hit points may lie too far apart.
        if !(den.abs() * self.trusted >= err * d_len) {
            return Pick::All;
        }
        let t = dot(&n, &p) / den;
        let x: Vector<N> = std::array::from_fn(|i| ray.o[i] + t * ray.d[i]);
        let links = &links[self.links as usize..][..self.count as usize];
        let mut s = self.start;
        for _ in 0..walk_limit(N) {
            let b = bary(s, &x);
            let mut k_min = 0;
            for k in 1..N {
                if b[k] < b[k_min] {
                    k_min = k;
                }
            }
            if b[k_min] >= self.tau {
                return Pick::Simplex(s);
            }
            if !(b[k_min] < -self.tau) {
                return Pick::All;
            }
            // Beyond a boundary ridge by more than τ: outside the convex cell.
            let next = links[s as usize];
            if (0..N).any(|k| b[k] < -self.tau && next[k] == NO_NEIGHBOUR) {
                return Pick::Miss;
            }
            s = next[k_min];
        }
        Pick::All
    }
}

/// The centroid of points.
fn centroid<const N: usize>(pts: &[Vector<N>]) -> Vector<N> {
    std::array::from_fn(|i| pts.iter().map(|v| v[i]).sum::<f64>() / pts.len() as f64)
}

impl<const N: usize> CellGeometry<N> {
    /// The simplex whose centroid is nearest the centroid of all the vertices (the first on a
    /// tie): where the walks start.
    fn start(points: &[[Vector<N>; N]]) -> u32 {
        let all: Vec<Vector<N>> = points.iter().flatten().copied().collect();
        let c = centroid(&all);
        let mut best = (f64::INFINITY, 0u32);
        for (s, pts) in points.iter().enumerate() {
            let e = sub(&centroid(pts), &c);
            let d2 = dot(&e, &e);
            if d2 < best.0 {
                best = (d2, s as u32);
            }
        }
        best.1
    }

    /// The geometry of the cell tiled by the simplices `points`, prepared as `prepared`
    /// ([`PreparedSimplex::new`] of each), or `None` when they do not form a flat, convex,
    /// properly tiled cell the walk can serve (see the module docs).
    pub(super) fn new(
        points: &[[Vector<N>; N]],
        prepared: Vec<PreparedSimplex<N>>,
    ) -> Option<Self> {
        let count = points.len();
        if !(2..(1 << 24)).contains(&count) || prepared.len() != count {
            return None;
        }
        // Vertices by the bits of their coordinates (−0 = +0).
        let bits = |v: &Vector<N>| v.map(|x| if x == 0.0 { 0 } else { x.to_bits() });
        let mut verts: Vec<[u64; N]> = points.iter().flatten().map(bits).collect();
        verts.sort_unstable();
        verts.dedup();
        let vertex_id = |v: &Vector<N>| verts.binary_search(&bits(v)).unwrap() as u32;
        let ids: Vec<[u32; N]> = points.iter().map(|s| s.map(|v| vertex_id(&v))).collect();
        let vertices: Vec<Vector<N>> = verts.iter().map(|b| b.map(f64::from_bits)).collect();
        // Ridges: (sorted vertex ids of the facet opposite slot k, simplex, k).
        let mut ridges: Vec<([u32; N], u32, u32)> = Vec::with_capacity(count * N);
        for (s, idx) in ids.iter().enumerate() {
            if (1..N).any(|a| idx[..a].contains(&idx[a])) {
                return None;
            }
            for k in 0..N {
                let mut key = *idx;
                key[k] = u32::MAX;
                key.sort_unstable();
                ridges.push((key, s as u32, k as u32));
            }
        }
        ridges.sort_unstable();
        let mut neighbours = vec![[NO_NEIGHBOUR; N]; count];
        let mut boundary = Vec::new();
        let mut i = 0;
        while i < ridges.len() {
            let mut j = i + 1;
            while j < ridges.len() && ridges[j].0 == ridges[i].0 {
                j += 1;
            }
            match j - i {
                1 => boundary.push((ridges[i].1, ridges[i].2)),
                2 => {
                    let (a, ka) = (ridges[i].1, ridges[i].2);
                    let (b, kb) = (ridges[i + 1].1, ridges[i + 1].2);
                    // The two lie on opposite sides of their common ridge.
                    let apex_b = &points[b as usize][kb as usize];
                    let apex_a = &points[a as usize][ka as usize];
                    if !(prepared[a as usize].barycentric(apex_b)[ka as usize] < -MARGIN
                        && prepared[b as usize].barycentric(apex_a)[kb as usize] < -MARGIN)
                    {
                        return None;
                    }
                    neighbours[a as usize][ka as usize] = b;
                    neighbours[b as usize][kb as usize] = a;
                }
                _ => return None,
            }
            i = j;
        }
        drop(ridges);
        // Connected.
        let mut seen = vec![false; count];
        let mut queue = vec![0u32];
        seen[0] = true;
        while let Some(s) = queue.pop() {
            for &t in &neighbours[s as usize] {
                if t != NO_NEIGHBOUR && !seen[t as usize] {
                    seen[t as usize] = true;
                    queue.push(t);
                }
            }
        }
        if seen.iter().any(|&v| !v) {
            return None;
        }
        // Walks stay short: no simplex more than half the walk limit from the start (by
        // neighbour steps), which also bounds the work below (a large flat floor is left to
        // the tree).
        let start = Self::start(points);
        let mut depth = vec![u32::MAX; count];
        let mut front = vec![start];
        depth[start as usize] = 0;
        let mut d = 0;
        while !front.is_empty() {
            if d as usize > walk_limit(N) / 2 {
                return None;
            }
            let mut next = Vec::new();
            for &s in &front {
                for &t in &neighbours[s as usize] {
                    if t != NO_NEIGHBOUR && depth[t as usize] == u32::MAX {
                        depth[t as usize] = d + 1;
                        next.push(t);
                    }
                }
            }
            front = next;
            d += 1;
        }
        // Size, aspect and magnitude.
        let mut diam: f64 = 0.0;
        for s in points {
            for a in 0..N {
                for b in a + 1..N {
                    let e = sub(&s[a], &s[b]);
                    diam = diam.max(dot(&e, &e).sqrt());
                }
            }
        }
        let mut h_min = f64::INFINITY;
        for p in &prepared {
            let mut r0 = [0.0; N];
            for k in 1..N {
                let r = &p.m[k];
                h_min = h_min.min(1.0 / dot(r, r).sqrt());
                for i in 0..N {
                    r0[i] -= r[i];
                }
            }
            h_min = h_min.min(1.0 / dot(&r0, &r0).sqrt());
        }
        let reach = vertices
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if !(h_min > 0.0 && diam.is_finite() && reach.is_finite()) {
            return None;
        }
        // Flat: every simplex's hyperplane passes through every vertex of the cell.
        let mut residual: f64 = 0.0;
        for p in &prepared {
            for v in &vertices {
                residual = residual.max(dot(&p.m[0], &sub(v, &p.x0)).abs());
            }
        }
        if !(residual <= 1e-9 * diam) {
            return None;
        }
        // Convex: every vertex on the inner side of every boundary ridge, where coordinate k
        // of simplex s, `[k = 0] + r_k·(v − x_0)` (r_0 = −Σ r_k), is ≥ 0.
        for &(s, k) in &boundary {
            let p = &prepared[s as usize];
            let (r, one) = if k > 0 {
                (p.m[k as usize], 0.0)
            } else {
                let mut r0 = [0.0; N];
                for row in &p.m[1..] {
                    for i in 0..N {
                        r0[i] -= row[i];
                    }
                }
                (r0, 1.0)
            };
            if vertices
                .iter()
                .any(|v| !(one + dot(&r, &sub(v, &p.x0)) >= -BARY_SLACK))
            {
                return None;
            }
        }
        // One sheet: the start simplex's centroid lies in no other simplex (with the
        // checks above, the simplices then cover the cell once).
        let c: Vector<N> = centroid(&points[start as usize]);
        let covering = prepared
            .iter()
            .filter(|p| p.barycentric(&c).iter().all(|&b| b >= -MARGIN))
            .count();
        if covering != 1 {
            return None;
        }
        let aspect = h_min / diam;
        let tau = 2.0 * (N - 1) as f64 * MARGIN / aspect + 1e-8;
        if !(tau <= MAX_TAU) {
            return None;
        }
        Some(CellGeometry {
            neighbours,
            start,
            tau,
            err0: 2.0 * residual + 16.0 * N as f64 * f64::EPSILON * reach,
            trusted: TRUST * h_min,
            prepared,
        })
    }
}

#[cfg(test)]
mod tests;
