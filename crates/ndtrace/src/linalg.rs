//! Small fixed-size linear algebra over `[f64; N]`: vectors, row-major `[[f64; N]; N]` matrices,
//! determinants by LU with partial pivoting, Gaussian solves and cofactor matrices.
//!
//! Square sub-problems of size `k ≤ N` (Gram matrices of K < N edges, minors) live in the
//! leading `k × k` block of an `N × N` array, since stable Rust cannot name `[f64; N − 1]`.

/// A point or vector of R^N.
pub type Vector<const N: usize> = [f64; N];
/// A colour: linear red, green and blue.
pub type Rgb = [f64; 3];
/// A row-major N × N matrix: `m[row][col]`.
pub type Matrix<const N: usize> = [[f64; N]; N];

/// Dot product a·b.
#[inline]
pub fn dot<const N: usize>(a: &Vector<N>, b: &Vector<N>) -> f64 {
    let mut s = 0.0;
    for i in 0..N {
        s += a[i] * b[i];
    }
    s
}

/// a − b.
#[inline]
pub fn sub<const N: usize>(a: &Vector<N>, b: &Vector<N>) -> Vector<N> {
    std::array::from_fn(|i| a[i] - b[i])
}

/// a + b.
#[inline]
pub fn add<const N: usize>(a: &Vector<N>, b: &Vector<N>) -> Vector<N> {
    std::array::from_fn(|i| a[i] + b[i])
}

/// s·a.
#[inline]
pub fn scale<const N: usize>(a: &Vector<N>, s: f64) -> Vector<N> {
    std::array::from_fn(|i| a[i] * s)
}

/// a + s·b.
#[inline]
pub fn add_scaled<const N: usize>(a: &Vector<N>, s: f64, b: &Vector<N>) -> Vector<N> {
    std::array::from_fn(|i| a[i] + s * b[i])
}

/// Euclidean length |a|.
#[inline]
pub fn norm<const N: usize>(a: &Vector<N>) -> f64 {
    dot(a, a).sqrt()
}

/// The identity matrix.
pub fn identity<const N: usize>() -> Matrix<N> {
    std::array::from_fn(|i| std::array::from_fn(|j| if i == j { 1.0 } else { 0.0 }))
}

/// Transpose.
pub fn transpose<const N: usize>(m: &Matrix<N>) -> Matrix<N> {
    std::array::from_fn(|i| std::array::from_fn(|j| m[j][i]))
}

/// Matrix–vector product m·v.
#[inline]
pub fn mat_vec<const N: usize>(m: &Matrix<N>, v: &Vector<N>) -> Vector<N> {
    std::array::from_fn(|i| dot(&m[i], v))
}

/// Matrix product a·b.
pub fn mat_mul<const N: usize>(a: &Matrix<N>, b: &Matrix<N>) -> Matrix<N> {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..N).map(|k| a[i][k] * b[k][j]).sum()))
}

/// Determinant of the leading `k × k` block of `m`, destroying it (LU with partial pivoting).
pub fn det_block_in_place<const N: usize>(m: &mut Matrix<N>, k: usize) -> f64 {
    debug_assert!(k <= N);
    let mut det = 1.0;
    for col in 0..k {
        // Choose the pivot of largest magnitude in this column.
        let mut p = col;
        for r in col + 1..k {
            if m[r][col].abs() > m[p][col].abs() {
                p = r;
            }
        }
        if m[p][col] == 0.0 {
            return 0.0;
        }
        if p != col {
            m.swap(p, col);
            det = -det;
        }
        let pivot = m[col][col];
        det *= pivot;
        // Eliminate below the pivot.
        for r in col + 1..k {
            let f = m[r][col] / pivot;
            if f != 0.0 {
                for c in col + 1..k {
                    m[r][c] -= f * m[col][c];
                }
            }
        }
    }
    det
}

/// Determinant of the leading `k × k` block of `m`.
pub fn det_block<const N: usize>(m: &Matrix<N>, k: usize) -> f64 {
    let mut a = *m;
    det_block_in_place(&mut a, k)
}

/// Determinant of an N × N matrix.
pub fn det<const N: usize>(m: &Matrix<N>) -> f64 {
    det_block(m, N)
}

/// The `(n−1) × (n−1)` minor of the leading `n × n` block of `m` without `row` and `col`,
/// stored in the leading block of the result.
pub fn minor<const N: usize>(m: &Matrix<N>, n: usize, row: usize, col: usize) -> Matrix<N> {
    let mut out = [[0.0; N]; N];
    for (ri, r) in (0..n).filter(|&r| r != row).enumerate() {
        for (ci, c) in (0..n).filter(|&c| c != col).enumerate() {
            out[ri][ci] = m[r][c];
        }
    }
    out
}

/// The cofactor matrix C with `C[i][j] = (−1)^(i+j) det(minor(i, j))`, i.e. `det(m)·m^(−T)`
/// for invertible `m`, and still defined (by continuity) for singular `m`.
pub fn cofactor_matrix<const N: usize>(m: &Matrix<N>) -> Matrix<N> {
    if N == 1 {
        return [[1.0; N]; N];
    }
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
            sign * det_block(&minor(m, N, i, j), N - 1)
        })
    })
}

/// Solves the leading `k × k` system `a·x = b` by Gaussian elimination with partial pivoting.
/// Returns `None` when a pivot is exactly zero. Only the first `k` entries of the result are
/// meaningful.
pub fn solve_block<const N: usize>(a: Matrix<N>, b: Vector<N>, k: usize) -> Option<Vector<N>> {
    let x = solve_many(a, b.map(|v| [v]), k)?;
    Some(std::array::from_fn(|r| x[0][r]))
}

/// The inverse of the leading `k × k` block of `a`, by the eliminations of [`solve_block`]
/// done once for the k right-hand sides ê_0 … ê_{k−1} together: row j of the result holds, bit
/// for bit, `solve_block(a, ê_j, k)`. `None` when a pivot is exactly zero.
#[inline(always)]
pub fn inverse_rows_block<const N: usize>(a: Matrix<N>, k: usize) -> Option<Matrix<N>> {
    let unit = std::array::from_fn(|r| std::array::from_fn(|j| f64::from(r == j)));
    solve_many(a, unit, k)
}

/// Gaussian elimination with partial pivoting of the leading `k × k` block of `a` for M
/// right-hand sides at once (`b[r][j]`: entry r of right-hand side j); row j of the result
/// is solution j. Each right-hand side undergoes exactly the operations a lone solve gives it.
#[inline(always)]
fn solve_many<const N: usize, const M: usize>(
    mut a: Matrix<N>,
    mut b: [[f64; M]; N],
    k: usize,
) -> Option<[[f64; N]; M]> {
    let m = M.min(k.max(1));
    for col in 0..k {
        let mut p = col;
        for r in col + 1..k {
            if a[r][col].abs() > a[p][col].abs() {
                p = r;
            }
        }
        if a[p][col] == 0.0 {
            return None;
        }
        a.swap(p, col);
        b.swap(p, col);
        for r in col + 1..k {
            let f = a[r][col] / a[col][col];
            if f != 0.0 {
                for c in col..k {
                    a[r][c] -= f * a[col][c];
                }
                for j in 0..m {
                    b[r][j] -= f * b[col][j];
                }
            }
        }
    }
    let mut x = [[0.0; N]; M];
    for j in 0..m {
        for r in (0..k).rev() {
            let mut s = b[r][j];
            for c in r + 1..k {
                s -= a[r][c] * x[j][c];
            }
            x[j][r] = s / a[r][r];
        }
    }
    Some(x)
}

/// n! as a float (exact for the n ≤ 8 used here).
pub fn factorial(n: usize) -> f64 {
    (1..=n).map(|k| k as f64).product()
}

#[cfg(test)]
mod tests;
