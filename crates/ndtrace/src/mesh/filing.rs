//! A mesh's ridges filed under their smallest vertex: the parallel counting sort that matching
//! the simplices along their ridges ([`super::orientation::ridges`]) starts from.

use rayon::prelude::*;

/// An entry of the filed ridges, `simplex·N + slot` (the ridge of the simplex opposite that
/// slot): `u32` where every entry of the mesh fits (half the memory), else `u64`.
pub(crate) trait RidgeEntry: Copy + Send + Sync + Into<u64> + 'static {
    const ZERO: Self;
    /// `x`, which the caller knows to fit.
    fn of(x: usize) -> Self;
}

impl RidgeEntry for u32 {
    const ZERO: Self = 0;
    #[inline(always)]
    fn of(x: usize) -> Self {
        x as u32
    }
}

impl RidgeEntry for u64 {
    const ZERO: Self = 0;
    #[inline(always)]
    fn of(x: usize) -> Self {
        x as u64
    }
}

/// The ridges filed: those whose smallest vertex is v are `entries[start[v]..start[v + 1]]`,
/// in increasing order.
pub(crate) struct Filed<T> {
    pub(crate) start: Vec<usize>,
    pub(crate) entries: Vec<T>,
}

/// Most runs of the counting sort: each has a count per vertex.
const MAX_RUNS: usize = 4;

/// The smallest vertex of the ridge opposite each slot of a simplex without a repeated vertex:
/// its second smallest vertex for the slot of its smallest, else its smallest.
#[inline(always)]
fn lows<const N: usize>(idx: &[u32; N]) -> [u32; N] {
    let (mut first, mut second) = (u32::MAX, u32::MAX);
    for &v in idx {
        if v < first {
            second = first;
            first = v;
        } else if v < second {
            second = v;
        }
    }
    idx.map(|v| if v == first { second } else { first })
}

/// Where the runs write: each position once (see [`file_ridges`]).
struct Slots<T>(*mut T);

// SAFETY: the runs write disjoint positions of one live buffer, each once, and nothing reads
// it until they have all finished.
unsafe impl<T: Send> Sync for Slots<T> {}

impl<T> Slots<T> {
    /// # Safety
    /// `at` is within the buffer, and no other write or read of it overlaps this one.
    #[inline(always)]
    unsafe fn write(&self, at: usize, x: T) {
        unsafe { self.0.add(at).write(x) }
    }
}

/// Files the ridges of the simplices of `s` that `keep` (which have no repeated vertex) under
/// their smallest vertex, over `buckets` vertices (more than any index).
///
/// A stable counting sort, in parallel: the simplices are cut into runs (one per thread, at
/// most [`MAX_RUNS`]); each run counts its ridges per vertex; the counts, summed vertex by
/// vertex and run by run, give every run its own place in every vertex's list; the runs then
/// write their ridges there in parallel. The result is the sequential pass's whatever the
/// number of threads, and nothing is sorted by comparison.
pub(crate) fn file_ridges<const N: usize, T: RidgeEntry>(
    s: &[[u32; N]],
    buckets: usize,
    keep: impl Fn(&[u32; N]) -> bool + Sync,
) -> Filed<T> {
    let runs = rayon::current_num_threads().clamp(1, MAX_RUNS);
    let per = s.len().div_ceil(runs).max(1);
    let mut cursors: Vec<Vec<usize>> = s
        .par_chunks(per)
        .map(|run| {
            let mut count = vec![0usize; buckets];
            for idx in run.iter().filter(|idx| keep(idx)) {
                for v in lows(idx) {
                    count[v as usize] += 1;
                }
            }
            count
        })
        .collect();
    // Each count becomes the place where its run writes its first ridge of that vertex.
    let mut start = vec![0usize; buckets + 1];
    let mut total = 0;
    for (v, first) in start.iter_mut().take(buckets).enumerate() {
        *first = total;
        for cursor in &mut cursors {
            let n = cursor[v];
            cursor[v] = total;
            total += n;
        }
    }
    start[buckets] = total;
    let mut entries = vec![T::ZERO; total];
    let slots = Slots(entries.as_mut_ptr());
    (s.par_chunks(per).zip(&mut cursors).enumerate()).for_each(|(r, (run, cursor))| {
        let first = r * per;
        for (i, idx) in run.iter().enumerate().filter(|(_, idx)| keep(idx)) {
            for (k, v) in lows(idx).into_iter().enumerate() {
                let at = &mut cursor[v as usize];
                // SAFETY: run r's ridges of vertex v go to `at`, from where the counts put it
                // on: the places `[at, at + its count)` of the runs and vertices tile
                // `0..total` without overlap, and each is written once.
                unsafe { slots.write(*at, T::of((first + i) * N + k)) };
                *at += 1;
            }
        }
    });
    Filed { start, entries }
}

#[cfg(test)]
mod tests;
