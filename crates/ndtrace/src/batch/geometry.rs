//! Batched geometry over flat `f64` buffers with a runtime dimension: the layer the Python
//! bindings call. Each function checks buffer sizes, dispatches on `dim` through
//! [`crate::with_dim!`], and runs the per-item functions of [`crate::geometry`] in parallel.
//!
//! Buffers are C-ordered: a batch of B items of shape `(…, K+1, N)` is `B·(K+1)·N` floats.
//! Results that are a tuple in Python (`hyperplane`, `point_hyperplane_distance`) are packed
//! per item (`[n̂…, c]`, `[h, p…]`).

use super::{as_vectors, batch_len, check_len};
use crate::geometry::{self, Degenerate};
use crate::linalg::Vector;
use crate::{with_dim, NdError, NdResult};

/// What to do with a degenerate item (zero-volume simplex, parallel ray or segment).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnDegenerate {
    /// Fail with [`NdError::Degenerate`] naming the first degenerate batch index.
    Error,
    /// Fill that item's result with NaN and go on.
    Nan,
}

/// What [`run_items`] runs for item `i`, writing its output row.
type ItemFn<'a> = dyn Fn(usize, &mut [f64]) -> Result<(), Degenerate> + Sync + 'a;

/// Runs `f(i, out_i)` for every item in parallel; a degenerate item is filled with NaN and,
/// under [`OnDegenerate::Error`], the first one (by index) becomes the error.
fn run_items(
    arg: &str,
    out: &mut [f64],
    width: usize,
    on: OnDegenerate,
    f: &ItemFn<'_>,
) -> NdResult<()> {
    // The first degenerate item of each run of items, then of all: the least index.
    let first = crate::par::reduce_chunks_mut(
        out,
        (width, 1),
        None,
        |start, chunk| {
            let mut first = None;
            for (k, o) in chunk.chunks_mut(width).enumerate() {
                if let Err(d) = f(start + k, o) {
                    o.fill(f64::NAN);
                    first = first.or(Some((start + k, d)));
                }
            }
            first
        },
        |a, b| match (a, b) {
            (Some(a), Some(b)) => Some(if a.0 < b.0 { a } else { b }),
            (a, b) => a.or(b),
        },
    );
    match (first, on) {
        (Some((index, d)), OnDegenerate::Error) => {
            // A degenerate simplex is the fault of `points`; a parallel direction of `arg`.
            let arg = if d == Degenerate::Simplex {
                "points"
            } else {
                arg
            };
            Err(NdError::Degenerate {
                arg: arg.into(),
                index,
                reason: d.reason(),
            })
        }
        _ => Ok(()),
    }
}

/// Batched [`geometry::generalized_cross`]: edges `(B, N−1, N)` → `(B, N)`.
pub fn generalized_cross(dim: usize, edges: &[f64], out: &mut [f64]) -> NdResult<()> {
    with_dim!(dim, N => {
        let b = batch_len("edges", edges, (N - 1) * N, "(N−1, N)")?;
        check_len("out", out, N, b, "(N,)")?;
        let e = as_vectors::<N>(edges);
        run_items("edges", out, N, OnDegenerate::Nan, &|i, o| {
            o.copy_from_slice(&geometry::generalized_cross(&e[i * (N - 1)..(i + 1) * (N - 1)]));
            Ok(())
        })
    })?
}

/// Batched [`geometry::signed_volume`]: points `(B, N+1, N)` → `(B,)`.
pub fn signed_volume(dim: usize, points: &[f64], out: &mut [f64]) -> NdResult<()> {
    with_dim!(dim, N => {
        let b = batch_len("points", points, (N + 1) * N, "(N+1, N)")?;
        check_len("out", out, 1, b, "()")?;
        let p = as_vectors::<N>(points);
        run_items("points", out, 1, OnDegenerate::Nan, &|i, o| {
            o[0] = geometry::signed_volume(&p[i * (N + 1)..(i + 1) * (N + 1)]);
            Ok(())
        })
    })?
}

fn check_k(k: usize, dim: usize) -> NdResult<()> {
    if !(1..=dim).contains(&k) {
        return Err(NdError::Shape {
            arg: "points".into(),
            expected: format!("(..., K+1, {dim}) with 1 ≤ K ≤ {dim}"),
            got: format!("K = {k}"),
        });
    }
    Ok(())
}

/// Batched [`geometry::gram_volume`]: points `(B, K+1, N)` → `(B,)`, 1 ≤ K ≤ N.
pub fn gram_volume(dim: usize, k: usize, points: &[f64], out: &mut [f64]) -> NdResult<()> {
    check_k(k, dim)?;
    with_dim!(dim, N => {
        let b = batch_len("points", points, (k + 1) * N, "(K+1, N)")?;
        check_len("out", out, 1, b, "()")?;
        let p = as_vectors::<N>(points);
        run_items("points", out, 1, OnDegenerate::Nan, &|i, o| {
            o[0] = geometry::gram_volume(&p[i * (k + 1)..(i + 1) * (k + 1)]);
            Ok(())
        })
    })?
}

/// Batched [`geometry::hyperplane`]: points `(B, N, N)` → `(B, N+1)` packed as `[n̂…, c]`.
pub fn hyperplane(dim: usize, points: &[f64], out: &mut [f64], on: OnDegenerate) -> NdResult<()> {
    with_dim!(dim, N => {
        let b = batch_len("points", points, N * N, "(N, N)")?;
        check_len("out", out, N + 1, b, "(N+1,)")?;
        let p = as_vectors::<N>(points);
        run_items("points", out, N + 1, on, &|i, o| {
            let h = geometry::hyperplane(&p[i * N..(i + 1) * N])?;
            o[..N].copy_from_slice(&h.normal);
            o[N] = h.offset;
            Ok(())
        })
    })?
}

/// Batched [`geometry::point_hyperplane_distance`]: x `(B, N)`, points `(B, N, N)` →
/// `(B, N+1)` packed as `[h, p…]`.
pub fn point_hyperplane_distance(
    dim: usize,
    x: &[f64],
    points: &[f64],
    out: &mut [f64],
    on: OnDegenerate,
) -> NdResult<()> {
    with_dim!(dim, N => {
        let b = batch_len("points", points, N * N, "(N, N)")?;
        check_len("x", x, N, b, "(N,)")?;
        check_len("out", out, N + 1, b, "(N+1,)")?;
        let (xs, p) = (as_vectors::<N>(x), as_vectors::<N>(points));
        run_items("points", out, N + 1, on, &|i, o| {
            let (h, foot) = geometry::point_hyperplane_distance(&xs[i], &p[i * N..(i + 1) * N])?;
            o[0] = h;
            o[1..].copy_from_slice(&foot);
            Ok(())
        })
    })?
}

/// Batched [`geometry::barycentric`]: x `(B, N)`, points `(B, K+1, N)` → `(B, K+1)`.
pub fn barycentric(
    dim: usize,
    k: usize,
    x: &[f64],
    points: &[f64],
    out: &mut [f64],
    on: OnDegenerate,
) -> NdResult<()> {
    if k == 0 || k > dim {
        check_k(k, dim)?;
    }
    with_dim!(dim, N => {
        let b = batch_len("points", points, (k + 1) * N, "(K+1, N)")?;
        check_len("x", x, N, b, "(N,)")?;
        check_len("out", out, k + 1, b, "(K+1,)")?;
        let (xs, p) = (as_vectors::<N>(x), as_vectors::<N>(points));
        run_items("points", out, k + 1, on, &|i, o| {
            geometry::barycentric(&xs[i], &p[i * (k + 1)..(i + 1) * (k + 1)], o)
        })
    })?
}

/// Batched [`geometry::side`]: x `(B, N)`, points `(B, N, N)` → `(B,)` of −1, 0, +1.
pub fn side(dim: usize, x: &[f64], points: &[f64], out: &mut [f64]) -> NdResult<()> {
    with_dim!(dim, N => {
        let b = batch_len("points", points, N * N, "(N, N)")?;
        check_len("x", x, N, b, "(N,)")?;
        check_len("out", out, 1, b, "()")?;
        let (xs, p) = (as_vectors::<N>(x), as_vectors::<N>(points));
        run_items("points", out, 1, OnDegenerate::Nan, &|i, o| {
            o[0] = f64::from(geometry::side(&xs[i], &p[i * N..(i + 1) * N]));
            Ok(())
        })
    })?
}

/// Batched [`geometry::clip_segment`]: a, b `(B, N)`, points `(B, N, N)` → `(B,)`.
pub fn clip_segment(
    dim: usize,
    a: &[f64],
    b: &[f64],
    points: &[f64],
    out: &mut [f64],
    on: OnDegenerate,
) -> NdResult<()> {
    with_dim!(dim, N => {
        let n = batch_len("points", points, N * N, "(N, N)")?;
        check_len("a", a, N, n, "(N,)")?;
        check_len("b", b, N, n, "(N,)")?;
        check_len("out", out, 1, n, "()")?;
        let (av, bv, p) = (as_vectors::<N>(a), as_vectors::<N>(b), as_vectors::<N>(points));
        run_items("segment", out, 1, on, &|i, o| {
            o[0] = geometry::clip_segment(&av[i], &bv[i], &p[i * N..(i + 1) * N])?;
            Ok(())
        })
    })?
}

/// Batched [`geometry::ray_hyperplane`]: origin, direction `(B, N)`, points `(B, N, N)` → `(B,)`.
pub fn ray_hyperplane(
    dim: usize,
    origin: &[f64],
    direction: &[f64],
    points: &[f64],
    out: &mut [f64],
    on: OnDegenerate,
) -> NdResult<()> {
    with_dim!(dim, N => {
        let n = batch_len("points", points, N * N, "(N, N)")?;
        check_len("origin", origin, N, n, "(N,)")?;
        check_len("direction", direction, N, n, "(N,)")?;
        check_len("out", out, 1, n, "()")?;
        let (c, d, p) = (as_vectors::<N>(origin), as_vectors::<N>(direction), as_vectors::<N>(points));
        run_items("ray", out, 1, on, &|i, o| {
            o[0] = geometry::ray_hyperplane(&c[i], &d[i], &p[i * N..(i + 1) * N])?;
            Ok(())
        })
    })?
}

/// Batched [`geometry::transform_normal`]: matrix `(B, N, N)`, normal `(B, N)` → `(B, N)`.
pub fn transform_normal(
    dim: usize,
    matrix: &[f64],
    normal: &[f64],
    out: &mut [f64],
) -> NdResult<()> {
    with_dim!(dim, N => {
        let b = batch_len("matrix", matrix, N * N, "(N, N)")?;
        check_len("normal", normal, N, b, "(N,)")?;
        check_len("out", out, N, b, "(N,)")?;
        let (m, nv) = (as_vectors::<N>(matrix), as_vectors::<N>(normal));
        run_items("matrix", out, N, OnDegenerate::Nan, &|i, o| {
            let mi: [Vector<N>; N] = std::array::from_fn(|r| m[i * N + r]);
            o.copy_from_slice(&geometry::transform_normal(&mi, &nv[i]));
            Ok(())
        })
    })?
}

#[cfg(test)]
mod tests;
