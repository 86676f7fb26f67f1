//! Orientation of simplicial meshes: whether neighbouring simplices agree, and its repair.
//!
//! A simplex's orientation is the order of its vertices: its normal is the generalized cross
//! product of `x_1 − x_0 … x_{N−1} − x_0` (eq. 6), and swapping two vertices negates it. Two
//! simplices sharing a ridge (N−1 common vertices) are **consistently oriented** when they
//! induce opposite orientations on it, as the two triangles of a square `[a, b, c]`,
//! `[a, c, d]` do on their diagonal `ac`. A mesh is **closed** when every ridge belongs to
//! exactly two simplices; a closed, consistently oriented mesh bounds a region, and its normals
//! point **outward** when the volume they enclose,
//! `V = Σ_s N_s·(x_0 − c) / N!` (divergence theorem; N_s the unnormalized normal of eq. 6, c any
//! point), is positive.
//!
//! [`ridges`] matches the simplices along their ridges; [`orient`] makes every connected piece
//! consistent by a breadth-first walk over ridge neighbours, then outward (V > 0) where the piece
//! is closed, or as close to the given orientation as possible where it has a boundary.
//! Simplices with a repeated vertex index have no orientation and are left out of both.

use super::filing::{file_ridges, Filed, RidgeEntry};
use super::Mesh;
use crate::geometry::simplex_normal;
use crate::linalg::{add, dot, scale, sub};
use crate::{with_dim, NdError, NdResult};
use rayon::prelude::*;
use std::collections::VecDeque;

/// The ridge of a simplex opposite its slot k: a hash of its sorted vertex indices, those
/// indices (padded with `u32::MAX`), and the orientation the simplex induces on it (the parity
/// of k plus that of the sort).
#[inline]
pub(crate) fn ridge<const N: usize>(idx: &[u32; N], k: usize) -> (u64, [u32; N], bool) {
    let mut key = [u32::MAX; N];
    let mut m = 0;
    for (j, &v) in idx.iter().enumerate() {
        if j != k {
            key[m] = v;
            m += 1;
        }
    }
    let mut odd = k % 2 == 1;
    for a in 0..N - 1 {
        for b in a + 1..N - 1 {
            odd ^= key[a] > key[b];
        }
    }
    key[..N - 1].sort_unstable();
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    for &v in &key[..N - 1] {
        h = (h ^ u64::from(v)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h ^= h >> 31;
    }
    (h, key, odd)
}

/// How a mesh's simplices meet along their ridges.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ridges {
    /// Each ridge shared by two simplices: (a, b, whether they induce opposite orientations on
    /// it, i.e. agree), with a < b, sorted.
    pub pairs: Vec<(u32, u32, bool)>,
    /// The simplex of each ridge that no other simplex shares (the mesh's boundary), sorted.
    pub boundary: Vec<u32>,
    /// Simplices left out because a vertex index repeats in them.
    pub degenerate: Vec<u32>,
}

impl Ridges {
    /// Every ridge is shared by exactly two simplices (and no simplex was left out).
    pub fn closed(&self) -> bool {
        self.boundary.is_empty() && self.degenerate.is_empty()
    }

    /// Every pair of neighbours agrees.
    pub fn consistent(&self) -> bool {
        self.pairs.iter().all(|p| p.2)
    }

    /// With `pairs` and `boundary` sorted, as [`ridges`] gives them.
    fn sorted(mut self) -> Self {
        self.pairs.par_sort_unstable();
        self.boundary.par_sort_unstable();
        self
    }
}

/// Why a mesh's orientation cannot be repaired.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OrientError {
    /// A ridge (its sorted vertex indices) belongs to more than two simplices.
    NonManifold { ridge: Vec<u32>, simplices: usize },
    /// No orientation of the piece containing this simplex makes all its neighbours agree (a
    /// Möbius strip or Klein bottle).
    NonOrientable { simplex: usize },
}

impl std::fmt::Display for OrientError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OrientError::NonManifold { ridge, simplices } => write!(
                f,
                "the ridge with vertices {ridge:?} belongs to {simplices} simplices (at most 2 can be oriented consistently)"
            ),
            OrientError::NonOrientable { simplex } => write!(
                f,
                "the piece containing simplex {simplex} is not orientable (like a Möbius strip): no orientation makes all its neighbours agree"
            ),
        }
    }
}

/// Matches the simplices of `mesh` along their ridges, in time O(S·N²) for meshes whose
/// vertices each lie in a bounded number of simplices.
///
/// Each ridge is filed under its smallest vertex index by a counting sort (stable and
/// parallel: no comparison sort over all S·N ridges); the ridges filed under one vertex are
/// then matched by their sorted vertices, in parallel over runs of vertices. When a ridge belongs to more than two simplices, the error names the first such
/// ridge in the order of the ridges' sorted vertices.
pub fn ridges<const N: usize>(mesh: &Mesh<N>) -> Result<Ridges, OrientError> {
    matched_ridges(mesh).map(Ridges::sorted)
}

/// [`ridges`] before `pairs` and `boundary` are sorted (they come in the order of the ridges'
/// smallest vertices): for the callers that only ask whether every pair agrees, and so need
/// no sort of S·N/2 pairs.
pub(crate) fn matched_ridges<const N: usize>(mesh: &Mesh<N>) -> Result<Ridges, OrientError> {
    fn matched<const N: usize, T: RidgeEntry>(mesh: &Mesh<N>) -> Result<Ridges, OrientError> {
        let (filed, degenerate) = file(mesh);
        lists::<N, T>(mesh, &filed, degenerate)
    }
    match entries_fit_u32(mesh) {
        true => matched::<N, u32>(mesh),
        false => matched::<N, u64>(mesh),
    }
}

/// Whether every entry `simplex·N + slot` of the filed ridges fits in a u32.
fn entries_fit_u32<const N: usize>(mesh: &Mesh<N>) -> bool {
    u32::try_from(mesh.simplices.len() * N).is_ok()
}

/// The ridges of `mesh` filed under their smallest vertex ([`file_ridges`]), and the simplices
/// left out of them because a vertex index repeats in them.
fn file<const N: usize, T: RidgeEntry>(mesh: &Mesh<N>) -> (Filed<T>, Vec<u32>) {
    let s = &mesh.simplices;
    let repeated = |idx: &[u32; N]| (1..N).any(|a| idx[..a].contains(&idx[a]));
    let degenerate: Vec<u32> = (0..s.len() as u32)
        .filter(|&i| repeated(&s[i as usize]))
        .collect();
    let buckets = s.par_iter().flatten().max().map_or(0, |&m| m as usize + 1);
    (file_ridges(s, buckets, |idx| !repeated(idx)), degenerate)
}

/// The matched ridges as lists, from the `filed` ridges of `mesh` and its `degenerate`
/// simplices.
fn lists<const N: usize, T: RidgeEntry>(
    mesh: &Mesh<N>,
    filed: &Filed<T>,
    degenerate: Vec<u32>,
) -> Result<Ridges, OrientError> {
    let new = || (Vec::new(), Vec::new());
    let add = |(pairs, boundary): &mut (Vec<_>, Vec<_>), m: Shared| match m {
        Shared::Pair(a, b, agree) => pairs.push((a, b, agree)),
        Shared::Boundary(a) => boundary.push(a),
    };
    let (mut pairs, mut boundary) = (Vec::new(), Vec::new());
    for (p, b) in match_filed(mesh, filed, new, add)? {
        pairs.extend(p);
        boundary.extend(b);
    }
    Ok(Ridges {
        pairs,
        boundary,
        degenerate,
    })
}

/// How one ridge is shared: by two simplices (a < b, and whether they agree on it) or by one.
enum Shared {
    Pair(u32, u32, bool),
    Boundary(u32),
}

/// Matches the simplices of `mesh` along their `filed` ridges (see [`ridges`]), handing each
/// ridge to the accumulator of its run of vertices (`new` makes one, `add` adds to it).
/// Returns the accumulators in the order of their runs, so in the order of the ridges'
/// smallest vertices.
fn match_filed<const N: usize, T: RidgeEntry, A: Send>(
    mesh: &Mesh<N>,
    Filed { start, entries }: &Filed<T>,
    new: impl Fn() -> A + Sync,
    add: impl Fn(&mut A, Shared) + Sync,
) -> Result<Vec<A>, OrientError> {
    let s = &mesh.simplices;
    let buckets = start.len() - 1;
    // Runs of whole buckets of about equal size, matched in parallel and joined in order.
    let pieces = rayon::current_num_threads() * 8;
    let mut cuts = vec![0usize];
    for k in 1..pieces {
        let want = entries.len() * k / pieces;
        let v = start.partition_point(|&x| x < want).min(buckets);
        cuts.push(v.max(*cuts.last().unwrap_or(&0)));
    }
    cuts.push(buckets);
    let matched: Vec<Result<A, OrientError>> = cuts
        .par_windows(2)
        .map(|w| {
            let mut acc = new();
            let mut run: Vec<([u32; N], bool, u32)> = vec![];
            for v in w[0]..w[1] {
                run.clear();
                run.extend(entries[start[v]..start[v + 1]].iter().map(|&r| {
                    let r: u64 = r.into();
                    let (simplex, slot) = ((r / N as u64) as usize, (r % N as u64) as usize);
                    let (_, key, odd) = ridge(&s[simplex], slot);
                    (key, odd, simplex as u32)
                }));
                run.sort_unstable();
                for same in run.chunk_by(|a, b| a.0 == b.0) {
                    match same {
                        [(_, _, a)] => add(&mut acc, Shared::Boundary(*a)),
                        [(_, odd_a, a), (_, odd_b, b)] => add(
                            &mut acc,
                            Shared::Pair((*a).min(*b), (*a).max(*b), odd_a != odd_b),
                        ),
                        more => {
                            return Err(OrientError::NonManifold {
                                ridge: more[0].0[..N - 1].to_vec(),
                                simplices: more.len(),
                            })
                        }
                    }
                }
            }
            Ok(acc)
        })
        .collect();
    matched.into_iter().collect()
}

/// One connected piece of a mesh (simplices linked through shared ridges), as [`orient`] found
/// it.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// Its simplices.
    pub simplices: usize,
    /// Every ridge of its simplices is shared with another of them.
    pub closed: bool,
    /// Its neighbours all agreed as given.
    pub consistent: bool,
    /// How many of its simplices [`orient`] flips.
    pub flipped: usize,
}

/// A consistent orientation: which simplices to flip (swap two vertices of), and the pieces.
#[derive(Debug, Clone, PartialEq)]
pub struct Repair {
    /// Per simplex: whether it must be flipped.
    pub flip: Vec<bool>,
    /// The connected pieces, in the order of their first simplex.
    pub pieces: Vec<Piece>,
}

impl Repair {
    /// Number of simplices flipped.
    pub fn flipped(&self) -> usize {
        self.pieces.iter().map(|p| p.flipped).sum()
    }

    /// Applies the repair to `mesh` (which must be the mesh it was computed for): each flipped
    /// simplex has its first two vertices swapped.
    pub fn apply<const N: usize>(&self, mesh: &mut Mesh<N>) {
        for (idx, &f) in mesh.simplices.iter_mut().zip(&self.flip) {
            if f {
                idx.swap(0, 1);
            }
        }
    }
}

/// The flips that orient every connected piece of `mesh` consistently: a breadth-first walk
/// over ridge neighbours from the piece's first simplex fixes each neighbour's flip so that the
/// two agree; then a closed piece is turned outward (its enclosed volume V, module docs,
/// positive) and a piece with a boundary keeps the orientation of the majority of its
/// simplices. Already consistent, outward pieces are left unchanged.
pub fn orient<const N: usize>(mesh: &Mesh<N>) -> Result<Repair, OrientError> {
    orient_along(mesh, &matched_ridges(mesh)?)
}

/// [`orient`] with the mesh's ridges `r` already matched, in any order: the walk meets a
/// piece's simplices in an order that depends on it, but their flips do not (each is fixed by
/// the piece's first simplex, and a contradiction fails the piece whatever the order).
fn orient_along<const N: usize>(mesh: &Mesh<N>, r: &Ridges) -> Result<Repair, OrientError> {
    let count = mesh.simplices.len();
    // Neighbour lists (compressed rows), with whether the pair agrees.
    let mut start = vec![0usize; count + 1];
    for &(a, b, _) in &r.pairs {
        start[a as usize + 1] += 1;
        start[b as usize + 1] += 1;
    }
    for i in 0..count {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut next = vec![(0u32, false); start[count]];
    for &(a, b, agree) in &r.pairs {
        next[fill[a as usize]] = (b, agree);
        fill[a as usize] += 1;
        next[fill[b as usize]] = (a, agree);
        fill[b as usize] += 1;
    }
    let mut open = vec![false; count];
    for &b in r.boundary.iter().chain(&r.degenerate) {
        open[b as usize] = true;
    }
    let mut flip = vec![false; count];
    let mut seen = vec![false; count];
    for &d in &r.degenerate {
        seen[d as usize] = true;
    }
    let mut pieces = vec![];
    let mut queue = VecDeque::new();
    let mut members = vec![];
    for seed in 0..count {
        if seen[seed] {
            continue;
        }
        // 1. Walk the piece: a neighbour that agrees takes the same flip, one that does not
        //    the opposite one; meeting a simplex again with the other flip is a contradiction.
        seen[seed] = true;
        queue.push_back(seed);
        members.clear();
        let (mut closed, mut consistent) = (true, true);
        while let Some(a) = queue.pop_front() {
            members.push(a);
            closed &= !open[a];
            for &(b, agree) in &next[start[a]..start[a + 1]] {
                let b = b as usize;
                consistent &= agree;
                let want = flip[a] ^ !agree;
                if !seen[b] {
                    seen[b] = true;
                    flip[b] = want;
                    queue.push_back(b);
                } else if flip[b] != want {
                    return Err(OrientError::NonOrientable { simplex: seed });
                }
            }
        }
        members.sort_unstable();
        // 2. Outward (closed) or the majority's orientation (open).
        let turn = if closed {
            enclosed_volume(mesh, &members, &flip) < 0.0
        } else {
            2 * members.iter().filter(|&&m| flip[m]).count() > members.len()
        };
        if turn {
            for &m in &members {
                flip[m] = !flip[m];
            }
        }
        pieces.push(Piece {
            simplices: members.len(),
            closed,
            consistent,
            flipped: members.iter().filter(|&&m| flip[m]).count(),
        });
    }
    Ok(Repair { flip, pieces })
}

/// N!·V of the simplices `members` with the orientations `flip` (module docs), about the mean
/// of their centroids, summed in simplex order.
fn enclosed_volume<const N: usize>(mesh: &Mesh<N>, members: &[usize], flip: &[bool]) -> f64 {
    let mut sum = [0.0; N];
    for &m in members {
        for p in mesh.simplex_points(m) {
            sum = add(&sum, &p);
        }
    }
    let c = scale(&sum, 1.0 / (members.len() * N) as f64);
    // The terms in parallel, summed in order (the same bits for any number of threads).
    let terms: Vec<f64> = members
        .par_iter()
        .map(|&m| {
            let p = mesh.simplex_points(m);
            let v = dot(&simplex_normal(&p), &sub(&p[0], &c));
            if flip[m] {
                -v
            } else {
                v
            }
        })
        .collect();
    terms.iter().sum()
}

/// The load-time check of a mesh object: `Some((flipped, simplices))` when the mesh is closed
/// and some piece of it is not consistently oriented, with the number of simplices of such
/// pieces that [`orient`] flips (those facing inward); `None` for an open or consistent mesh.
/// A closed mesh that cannot be oriented gives `Some((0, simplices))`.
pub fn inconsistency<const N: usize>(mesh: &Mesh<N>) -> Option<(usize, usize)> {
    match entries_fit_u32(mesh) {
        true => inconsistency_of::<N, u32>(mesh),
        false => inconsistency_of::<N, u64>(mesh),
    }
}

/// [`inconsistency`] with the filed ridges held as `T`.
fn inconsistency_of<const N: usize, T: RidgeEntry>(mesh: &Mesh<N>) -> Option<(usize, usize)> {
    let (filed, degenerate) = file::<N, T>(mesh);
    // Counts first, without the lists of pairs: a closed, consistently oriented mesh needs no
    // more.
    let tally = || (0usize, true);
    let add = |(boundary, agree): &mut (usize, bool), m: Shared| match m {
        Shared::Pair(_, _, a) => *agree &= a,
        Shared::Boundary(_) => *boundary += 1,
    };
    let runs = match_filed(mesh, &filed, tally, add).ok()?;
    let closed = degenerate.is_empty() && runs.iter().all(|r| r.0 == 0);
    if !closed || runs.iter().all(|r| r.1) {
        return None;
    }
    let ridges = lists(mesh, &filed, degenerate).ok()?;
    drop(filed);
    let count = mesh.simplices.len();
    match orient_along(mesh, &ridges) {
        Ok(repair) => Some((
            repair
                .pieces
                .iter()
                .filter(|p| !p.consistent)
                .map(|p| p.flipped)
                .sum(),
            count,
        )),
        Err(_) => Some((0, count)),
    }
}

/// [`orient`] for a runtime dimension `dim`, over row-major buffers of vertices (V, dim) and
/// simplices (S, dim): which simplices to flip. Errors name the argument.
pub fn orient_rows(dim: usize, vertices: &[f64], simplices: &[u32]) -> NdResult<Vec<bool>> {
    with_dim!(dim, N => {
        let shape = |arg: &str, len: usize| NdError::Shape {
            arg: arg.into(),
            expected: format!("a multiple of {N} values"),
            got: format!("{len}"),
        };
        if !vertices.len().is_multiple_of(N) {
            return Err(shape("vertices", vertices.len()));
        }
        if !simplices.len().is_multiple_of(N) {
            return Err(shape("simplices", simplices.len()));
        }
        let nv = vertices.len() / N;
        if let Some(i) = simplices.iter().position(|&k| k as usize >= nv) {
            return Err(NdError::Value {
                arg: format!("simplices[{}][{}]", i / N, i % N),
                message: format!("vertex index {} out of range: there are {nv} vertices", simplices[i]),
            });
        }
        let mesh = Mesh::<N> {
            vertices: vertices.chunks_exact(N).map(|v| std::array::from_fn(|k| v[k])).collect(),
            simplices: simplices.chunks_exact(N).map(|s| std::array::from_fn(|k| s[k])).collect(),
        };
        orient(&mesh).map(|r| r.flip).map_err(|e| NdError::Value {
            arg: "simplices".into(),
            message: e.to_string(),
        })
    })?
}

#[cfg(test)]
mod tests;
