//! Exact integer determinants: a test oracle, the independent reference for the f64 volume
//! code.

/// Determinant of a square integer matrix by fraction-free Bareiss elimination, exact in i128
/// as long as every intermediate minor fits (|entries| ≲ 10³ for N ≤ 8).
pub fn det_bareiss(m: &[Vec<i128>]) -> i128 {
    let n = m.len();
    assert!(
        m.iter().all(|row| row.len() == n),
        "det_bareiss needs a square matrix"
    );
    if n == 0 {
        return 1;
    }
    let mut a: Vec<Vec<i128>> = m.to_vec();
    let mut sign = 1i128;
    let mut prev = 1i128;
    for k in 0..n - 1 {
        // Pivot: any non-zero entry in column k at or below row k.
        if a[k][k] == 0 {
            match (k + 1..n).find(|&r| a[r][k] != 0) {
                Some(r) => {
                    a.swap(k, r);
                    sign = -sign;
                }
                None => return 0,
            }
        }
        for i in k + 1..n {
            for j in k + 1..n {
                // Sylvester's identity makes this division exact.
                a[i][j] = (a[i][j] * a[k][k] - a[i][k] * a[k][j]) / prev;
            }
        }
        prev = a[k][k];
    }
    sign * a[n - 1][n - 1]
}

#[cfg(test)]
mod tests {
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
                let mut m: Vec<Vec<i128>> =
                    (0..n).map(|_| (0..n).map(|_| next()).collect()).collect();
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
}
