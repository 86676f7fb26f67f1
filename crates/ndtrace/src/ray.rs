//! Rays `X(t) = C + t·d` and their hits: what the camera casts and what the accelerator
//! ([`crate::accel::Bvh`]) returns.

use crate::linalg::Vector;

/// A ray `X(t) = origin + t·dir`; `dir` need not be unit, so t is in units of `|dir|`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray<const N: usize> {
    /// The camera focal point C (or any ray start).
    pub origin: Vector<N>,
    /// `P − C`, the direction (not necessarily normalized).
    pub dir: Vector<N>,
}

impl<const N: usize> Ray<N> {
    /// The point `origin + t·dir`.
    #[inline]
    pub fn at(&self, t: f64) -> Vector<N> {
        std::array::from_fn(|i| self.origin[i] + t * self.dir[i])
    }
}

/// A ray hit: parameter t, the caller's id of the simplex, barycentric coordinates `t_0 … t_{N−1}`
/// and the simplex's unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit<const N: usize> {
    /// Ray parameter (units of `|dir|`).
    pub t: f64,
    /// The caller's id of the simplex hit.
    pub prim: u32,
    /// Barycentric coordinates of the hit point, summing to 1.
    pub bary: [f64; N],
    /// The unit normal n̂ of the simplex ([`crate::accel::PreparedSimplex::normal`], eq. 6
    /// normalized), taken
    /// from the leaf just tested so that shading needs no lookup by id.
    pub normal: [f64; N],
}
