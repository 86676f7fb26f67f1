//! Traversal counters: global with the feature `traversal-stats`, per thread in unit tests (so
//! that a test can check what a query visits), no-ops otherwise.

#[cfg(test)]
thread_local! {
    /// This thread's counts, as in `VISITS`.
    pub static LOCAL: std::cell::Cell<[u64; 4]> = const { std::cell::Cell::new([0; 4]) };
}

#[cfg(feature = "traversal-stats")]
use std::sync::atomic::{AtomicU64, Ordering};

/// Inner nodes visited (once per packet), leaf blocks tested (per ray), node slab tests
/// (per ray), exact tests of unsure lanes.
#[cfg(feature = "traversal-stats")]
pub static VISITS: [AtomicU64; 4] = [const { AtomicU64::new(0) }; 4];

/// Counts one visit of kind `k` (0: node, 1: leaf, 2: node slab test, 3: exact test).
#[inline(always)]
pub fn count(_k: usize) {
    #[cfg(feature = "traversal-stats")]
    VISITS[_k].fetch_add(1, Ordering::Relaxed);
    #[cfg(test)]
    LOCAL.with(|c| {
        let mut v = c.get();
        v[_k] += 1;
        c.set(v);
    });
}

/// Inner nodes, leaf blocks, slab tests and exact tests of all traversals so far (feature
/// `traversal-stats`).
#[cfg(feature = "traversal-stats")]
pub fn traversal_stats() -> [u64; 4] {
    use std::sync::atomic::Ordering;
    VISITS.each_ref().map(|v| v.load(Ordering::Relaxed))
}
