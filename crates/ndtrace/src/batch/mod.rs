//! The flat-buffer layers the Python bindings call: the course's geometry ([`geometry`],
//! `ndtrace.geometry`) and rotations ([`rotation`], `ndtrace.rotation`) over C-ordered `f64`
//! buffers with a runtime dimension.
//!
//! Each function checks its buffers' sizes (naming the argument), dispatches on `dim` through
//! [`crate::with_dim!`] and runs the generic per-item functions of [`crate::geometry`] and
//! [`crate::rotation`]. A batch of B items of shape `(…, K, N)` is `B·K·N` floats; the batch
//! size is inferred from the buffer lengths.

pub mod geometry;
pub mod rotation;

use crate::linalg::{Matrix, Vector};
use crate::{NdError, NdResult};

/// Checks that `buf` holds `batch` items of `per_item` floats.
pub fn check_len(
    arg: &str,
    buf: &[f64],
    per_item: usize,
    batch: usize,
    shape: &str,
) -> NdResult<()> {
    if buf.len() != per_item * batch {
        return Err(NdError::Shape {
            arg: arg.into(),
            expected: format!("{batch} items of {shape} ({} floats)", per_item * batch),
            got: format!("{} floats", buf.len()),
        });
    }
    Ok(())
}

/// Number of items in a batch buffer, checking that it divides evenly.
pub fn batch_len(arg: &str, buf: &[f64], per_item: usize, shape: &str) -> NdResult<usize> {
    if per_item == 0 || !buf.len().is_multiple_of(per_item) {
        return Err(NdError::Shape {
            arg: arg.into(),
            expected: format!("a multiple of {per_item} floats ({shape})"),
            got: format!("{} floats", buf.len()),
        });
    }
    Ok(buf.len() / per_item)
}

/// Views a flat buffer as vectors of R^N (its length a multiple of N).
#[inline]
fn as_vectors<const N: usize>(flat: &[f64]) -> &[Vector<N>] {
    let (vectors, rest) = flat.as_chunks::<N>();
    debug_assert!(rest.is_empty());
    vectors
}

/// Views a flat buffer as N×N matrices, row-major (its length a multiple of N²).
fn as_matrices<const N: usize>(flat: &[f64]) -> &[Matrix<N>] {
    flat.as_chunks::<N>().0.as_chunks::<N>().0
}

/// [`as_matrices`], mutable.
fn as_matrices_mut<const N: usize>(flat: &mut [f64]) -> &mut [Matrix<N>] {
    flat.as_chunks_mut::<N>().0.as_chunks_mut::<N>().0
}
