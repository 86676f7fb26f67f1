//! The one place where a runtime dimension becomes a compile-time one.
//!
//! Everything numeric in ndtrace is generic over `const N: usize`; code that starts from a
//! runtime `dim` (a scene file, a numpy array) goes through [`with_dim!`], which is the only
//! `match` from `usize` to `N` in the code base.

/// Smallest supported dimension N.
pub const MIN_DIM: usize = 2;
/// Largest supported dimension N.
pub const MAX_DIM: usize = 8;

/// Largest number of points a simplex can have (an N-simplex in R^MAX_DIM has MAX_DIM + 1).
pub const MAX_POINTS: usize = MAX_DIM + 1;

/// Checks that `dim` lies in `MIN_DIM..=MAX_DIM`.
pub fn check_dim(dim: usize) -> crate::NdResult<usize> {
    if (MIN_DIM..=MAX_DIM).contains(&dim) {
        Ok(dim)
    } else {
        Err(crate::NdError::Dimension { dim })
    }
}

/// Runs `$body` with `$N` bound to the compile-time constant equal to the runtime `$dim`.
///
/// Evaluates to `Ok(body)` for `dim` in 2..=8 and to `Err(NdError::Dimension)` otherwise.
///
/// ```
/// use ndtrace::with_dim;
/// let n: usize = 5;
/// let zeros = with_dim!(n, N => [0.0f64; N].len()).unwrap();
/// assert_eq!(zeros, 5);
/// assert!(with_dim!(9usize, N => N).is_err());
/// ```
#[macro_export]
macro_rules! with_dim {
    ($dim:expr, $N:ident => $body:expr) => {{
        #[allow(clippy::redundant_closure_call)]
        match $dim {
            2 => {
                const $N: usize = 2;
                Ok($body)
            }
            3 => {
                const $N: usize = 3;
                Ok($body)
            }
            4 => {
                const $N: usize = 4;
                Ok($body)
            }
            5 => {
                const $N: usize = 5;
                Ok($body)
            }
            6 => {
                const $N: usize = 6;
                Ok($body)
            }
            7 => {
                const $N: usize = 7;
                Ok($body)
            }
            8 => {
                const $N: usize = 8;
                Ok($body)
            }
            d => Err($crate::NdError::Dimension { dim: d }),
        }
    }};
}

#[cfg(test)]
mod tests {
    use crate::NdError;

    #[test]
    fn every_supported_dimension_binds_its_constant() {
        for d in 2..=8usize {
            assert_eq!(with_dim!(d, N => N).unwrap(), d);
        }
    }

    #[test]
    fn dimensions_outside_the_range_are_errors() {
        for d in [0usize, 1, 9, 100] {
            match with_dim!(d, N => N) {
                Err(NdError::Dimension { dim }) => assert_eq!(dim, d),
                other => panic!("dim {d}: expected a Dimension error, got {other:?}"),
            }
        }
        let msg = super::check_dim(9).unwrap_err().to_string();
        assert!(msg.contains("2..=8") && msg.contains('9'), "{msg}");
    }
}
