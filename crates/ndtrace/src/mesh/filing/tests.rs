use super::*;
use crate::testutil::rng;
use rand::Rng;

/// The parallel filing is the sequential counting sort (a stable sort of the ridges by
/// their smallest vertex), in u32 and u64 entries and in 1, 2 and 3 threads, over random
/// simplices (some with a repeated vertex, left out).
#[test]
fn filing_is_the_stable_sort_by_smallest_vertex() {
    fn check<const N: usize, T: RidgeEntry>(threads: usize) {
        let mut r = rng(90 + N as u64 + threads as u64);
        let verts = 40u32;
        let s: Vec<[u32; N]> = (0..r.random_range(0..500))
            .map(|_| std::array::from_fn(|_| r.random_range(0..verts)))
            .collect();
        let keep = |idx: &[u32; N]| (1..N).all(|a| !idx[..a].contains(&idx[a]));
        let mut want: Vec<(u32, usize)> = Vec::new();
        for (i, idx) in s.iter().enumerate().filter(|(_, idx)| keep(idx)) {
            for k in 0..N {
                let low = (0..N).filter(|&j| j != k).map(|j| idx[j]).min().unwrap();
                want.push((low, i * N + k));
            }
        }
        want.sort_by_key(|w| w.0);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let f: Filed<T> = pool.install(|| file_ridges(&s, verts as usize + 1, keep));
        let got: Vec<u64> = f.entries.iter().map(|&e| e.into()).collect();
        let expect: Vec<u64> = want.iter().map(|w| w.1 as u64).collect();
        assert_eq!(got, expect, "N = {N}, {threads} threads");
        for v in 0..=verts as usize {
            let here = &want[f.start[v]..f.start[v + 1]];
            assert!(
                here.iter().all(|w| w.0 as usize == v),
                "N = {N}, vertex {v}"
            );
        }
        assert_eq!(f.start[verts as usize + 1], want.len());
    }
    for threads in [1, 2, 3] {
        check::<2, u32>(threads);
        check::<3, u32>(threads);
        check::<3, u64>(threads);
        check::<4, u32>(threads);
        check::<5, u64>(threads);
        check::<8, u32>(threads);
    }
}
