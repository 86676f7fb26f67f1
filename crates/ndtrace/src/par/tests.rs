use super::*;
use std::sync::atomic::{AtomicU32, Ordering};

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

#[test]
fn the_ranges_cover_every_index_once_whatever_the_threads() {
    for threads in [1, 2, 3, 8] {
        for n in [0, 1, 2, 7, 64, 1000, 4099] {
            for min_len in [1, 3, 100, 10_000] {
                let seen: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(0)).collect();
                pool(threads).install(|| {
                    for_ranges(n, min_len, &|r| {
                        assert!(r.len() >= min_len.min(n) || r.end == n, "{r:?}");
                        for i in r {
                            seen[i].fetch_add(1, Ordering::Relaxed);
                        }
                    })
                });
                assert!(seen.iter().all(|s| s.load(Ordering::Relaxed) == 1), "n {n}");
            }
        }
    }
}

#[test]
fn collected_and_reduced_values_are_the_sequential_ones() {
    let f = |i: usize| (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 17;
    for threads in [1, 2, 3] {
        for n in [0, 1, 5, 333, 5000] {
            let (v, min, first) = pool(threads).install(|| {
                let v = map_collect(n, 7, f);
                let min = reduce_ranges(
                    n,
                    7,
                    u64::MAX,
                    |r| r.map(f).min().unwrap_or(u64::MAX),
                    u64::min,
                );
                // The first index whose value is below a third of the range: an exact reduction.
                let first = reduce_ranges(
                    n,
                    7,
                    None,
                    |r| r.clone().find(|&i| f(i) < u64::MAX >> 19),
                    |a: Option<usize>, b| match (a, b) {
                        (Some(a), Some(b)) => Some(a.min(b)),
                        (a, b) => a.or(b),
                    },
                );
                (v, min, first)
            });
            let want: Vec<u64> = (0..n).map(f).collect();
            assert_eq!(v, want);
            assert_eq!(min, want.iter().copied().min().unwrap_or(u64::MAX));
            assert_eq!(first, (0..n).find(|&i| f(i) < u64::MAX >> 19));
        }
    }
}

#[test]
fn chunks_are_the_slice_s_own_parts() {
    let mut out = vec![0usize; 1234];
    pool(3).install(|| {
        for_chunks_mut(&mut out, (2, 10), |first, chunk| {
            assert_eq!(chunk.len() % 2, 0);
            for (k, x) in chunk.iter_mut().enumerate() {
                *x = 2 * first + k;
            }
        })
    });
    assert!(out.iter().enumerate().all(|(i, &x)| x == i));
}
