use super::det_bareiss;

/// Leibniz expansion over all permutations: a slow, obviously correct reference.
fn det_leibniz(m: &[Vec<i128>]) -> i128 {
    fn perms(n: usize) -> Vec<Vec<usize>> {
        if n == 0 {
            return vec![vec![]];
        }
        let mut out = vec![];
        for p in perms(n - 1) {
            for pos in 0..=p.len() {
                let mut q = p.clone();
                q.insert(pos, n - 1);
                out.push(q);
            }
        }
        out
    }
    let n = m.len();
    perms(n)
        .into_iter()
        .map(|p| {
            let inversions = (0..n)
                .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
                .filter(|&(i, j)| p[i] > p[j])
                .count();
            let s = if inversions % 2 == 0 { 1 } else { -1 };
            s * (0..n).map(|i| m[i][p[i]]).product::<i128>()
        })
        .sum()
}

#[test]
fn bareiss_matches_leibniz() {
    let mut seed = 12345u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 33) % 11) as i128 - 5
    };
    for n in 1..=6 {
        for _ in 0..40 {
            let mut m: Vec<Vec<i128>> = (0..n).map(|_| (0..n).map(|_| next()).collect()).collect();
            if n > 1 && next() > 3 {
                m[0][0] = 0; // exercise pivoting
            }
            assert_eq!(det_bareiss(&m), det_leibniz(&m), "{m:?}");
        }
    }
    assert_eq!(det_bareiss(&[vec![2, 0], vec![1, 3]]), 6);
    assert_eq!(det_bareiss(&[vec![1, 2], vec![2, 4]]), 0);
    assert_eq!(det_bareiss(&[vec![0, 1], vec![1, 0]]), -1);
}
