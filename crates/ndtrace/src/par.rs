//! Parallel loops over index ranges, with rayon's machinery compiled once for the whole crate.
//!
//! A rayon iterator pipeline (`par_iter().zip(…).map(…).collect()`) instantiates rayon's
//! splitting, joining and job code for its own closure types, and most of the crate is compiled
//! once per dimension N = 2…8: those instantiations were about 40 % of the code LLVM compiled.
//! The loops here hand their work to rayon as `&dyn Fn` over ranges of indices, so rayon's code
//! is instantiated once; each caller's loop body runs over a whole range and stays monomorphic
//! and inlined (one indirect call per range, not per index).
//!
//! The ranges depend on the number of threads, the results do not: each index's work is its own,
//! and the reductions these loops offer are exact (first by index, min, max, box unions), so any
//! grouping gives the same bits.

use rayon::prelude::*;
use std::ops::Range;

/// Ranges per thread: enough for rayon to balance uneven work, few enough that the per-range
/// call costs nothing.
const RANGES_PER_THREAD: usize = 8;

/// The length of the ranges of `0..n` (at least `min_len`, so that short work is not split).
fn range_len(n: usize, min_len: usize) -> usize {
    let threads = rayon::current_num_threads().max(1);
    n.div_ceil(threads * RANGES_PER_THREAD).max(min_len).max(1)
}

/// Calls `f` on consecutive ranges covering `0..n` (each `min_len` long or more, but the last),
/// in parallel on the current rayon pool; on this thread when there is one range.
pub fn for_ranges(n: usize, min_len: usize, f: &(dyn Fn(Range<usize>) + Sync)) {
    if n == 0 {
        return;
    }
    let len = range_len(n, min_len);
    let count = n.div_ceil(len);
    if count == 1 {
        f(0..n);
        return;
    }
    (0..count)
        .into_par_iter()
        .for_each(|c| f(c * len..((c + 1) * len).min(n)));
}

/// A pointer that may be shared between the threads of [`for_ranges`], each reading and
/// writing its own range of the elements.
struct Shared<T>(*mut T);
// SAFETY: the loops below hand each thread a range of indices no other thread touches.
unsafe impl<T: Send> Sync for Shared<T> {}

/// `[f(0), f(1), …, f(n − 1)]`, computed in parallel (ranges of `min_len` indices or more).
#[inline]
pub fn map_collect<T: Send>(n: usize, min_len: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let mut out: Vec<T> = Vec::with_capacity(n);
    let at = Shared(out.spare_capacity_mut().as_mut_ptr());
    for_ranges(n, min_len, &|r: Range<usize>| {
        let at = &at;
        for i in r {
            // SAFETY: `i < n`, within the capacity, and written by this range only.
            unsafe { (*at.0.add(i)).write(f(i)) };
        }
    });
    // SAFETY: every one of the first n elements was written above (a panic in `f` propagates
    // before this point and leaves `out` empty, leaking what was written).
    unsafe { out.set_len(n) };
    out
}

/// The items `f(range, out)` pushes onto `out` for the ranges of `0..n` (see [`for_ranges`]),
/// in the order of the ranges: a parallel `flat_map`/`filter` … `collect` whose result does not
/// depend on the number of threads, as long as `f` pushes the items of its range in order.
#[inline]
pub fn flat_collect<T: Send>(
    n: usize,
    min_len: usize,
    f: impl Fn(Range<usize>, &mut Vec<T>) + Sync,
) -> Vec<T> {
    if n == 0 {
        return Vec::new();
    }
    let len = range_len(n, min_len);
    let parts = map_collect(n.div_ceil(len), 1, |c| {
        let mut part = Vec::new();
        f(c * len..((c + 1) * len).min(n), &mut part);
        part
    });
    let mut out = Vec::with_capacity(parts.iter().map(Vec::len).sum());
    for mut part in parts {
        out.append(&mut part);
    }
    out
}

/// `op` folded over `f(range)` of the ranges of `0..n` (see [`for_ranges`]), from `identity`.
/// The ranges depend on the number of threads: `op` must be associative and commutative
/// exactly (min, max, box unions, the first by index, logical and/or — not floating-point
/// sums), so that every grouping gives the same value.
#[inline]
pub fn reduce_ranges<R: Send>(
    n: usize,
    min_len: usize,
    identity: R,
    f: impl Fn(Range<usize>) -> R + Sync,
    op: impl Fn(R, R) -> R,
) -> R {
    if n == 0 {
        return identity;
    }
    let len = range_len(n, min_len);
    let parts = map_collect(n.div_ceil(len), 1, |c| f(c * len..((c + 1) * len).min(n)));
    parts.into_iter().fold(identity, op)
}

/// [`reduce_ranges`] over the items of `out`, `width` elements each: `f(first, chunk)` gets a
/// run of whole items, `chunk = out[first·width ..]`, to read and write.
///
/// # Panics
/// If `width` is 0 or does not divide `out.len()`.
#[inline]
pub fn reduce_chunks_mut<T: Send, R: Send>(
    out: &mut [T],
    (width, min_items): (usize, usize),
    identity: R,
    f: impl Fn(usize, &mut [T]) -> R + Sync,
    op: impl Fn(R, R) -> R,
) -> R {
    assert!(
        width > 0 && out.len().is_multiple_of(width),
        "items of {width} in {}",
        out.len()
    );
    let at = Shared(out.as_mut_ptr());
    let f = |r: Range<usize>| {
        let at = &at;
        // SAFETY: the items of `r` lie in `out`, and no other range overlaps them.
        let chunk =
            unsafe { std::slice::from_raw_parts_mut(at.0.add(r.start * width), r.len() * width) };
        f(r.start, chunk)
    };
    reduce_ranges(out.len() / width, min_items, identity, f, op)
}

/// [`reduce_chunks_mut`] without a result: `f(first, chunk)` on runs of whole items of `out`.
#[inline]
pub fn for_chunks_mut<T: Send>(
    out: &mut [T],
    (width, min_items): (usize, usize),
    f: impl Fn(usize, &mut [T]) + Sync,
) {
    reduce_chunks_mut(out, (width, min_items), (), f, |(), ()| ())
}

#[cfg(test)]
mod tests;
