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
mod tests;
