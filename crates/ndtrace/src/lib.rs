//! # ndtrace — N-dimensional ray tracing core
//!
//! A pure-Rust implementation of the geometry and rendering of Andrew J. Hanson's SIGGRAPH '98
//! course "Computer Graphics beyond the Third Dimension" (SIGGRAPH '98 Course Notes; see
//! `CITATION.cff` at the repository's root). Equation numbers in doc comments refer to the
//! paper "Geometry for N-Dimensional Graphics" printed in those notes; `docs/architecture.md`
//! maps each module to the part of the notes it implements.
//!
//! Numeric code is written once over `const N: usize` with `[f64; N]` storage; the single place
//! that turns a runtime dimension into a compile-time one is the [`with_dim!`] macro.
//!
//! ```
//! # // Run by `geometry::tests::the_crate_doc_example_holds`.
//! use ndtrace::geometry::{generalized_cross, signed_volume};
//! // The edges e_1, e_2, e_3 of R^4 give +e_4 (eq. 6).
//! let n = generalized_cross::<4>(&[[1., 0., 0., 0.], [0., 1., 0., 0.], [0., 0., 1., 0.]]);
//! assert_eq!(n, [0., 0., 0., 1.]);
//! // The standard 2-simplex has area +1/2! (eqs. 2–3).
//! assert_eq!(signed_volume::<2>(&[[0., 0.], [1., 0.], [0., 1.]]), 0.5);
//! ```

// `!(x > tol)` is deliberate: it also rejects NaN. Index loops mirror the matrix formulas.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod accel;
pub mod batch;
pub mod camera;
pub mod composite;
pub mod convex;
pub mod dim;
pub mod edges;
pub mod error;
pub mod files;
pub mod geometry;
pub mod linalg;
pub mod memory;
pub mod mesh;
pub mod names;
pub mod par;
pub mod ray;
pub mod render;
pub mod rotation;
pub mod scene;
pub mod shapes;
pub mod surface;
pub mod texture;

#[cfg(test)]
pub(crate) mod testutil;

pub use dim::{MAX_DIM, MIN_DIM};
pub use error::{NdError, NdResult};
