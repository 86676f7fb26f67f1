//! The tracer: rays from the N-D camera through every cell of the (N−1)-D retina, nearest hits
//! from the BVH, N-D Lambert + Blinn–Phong shading with hard shadows (course notes, "Ray
//! Tracing" and Part II(B) "4D Shading"), written into a [`Retina`].
//!
//! The pipeline, one file per step:
//! - [`trace()`] (`trace.rs`): back-face culling, then the retina in chunks of cells traced in
//!   parallel with rayon, each chunk in groups of cells, each cell's value from its rays;
//! - `tiles.rs`: the chunks (whole strips of rows) and the order of their cells (8×8 tiles,
//!   packets of 4 × 2 cells), so that the rays of a packet are close together;
//! - `sampling.rs`: one ray through each cell's centre, or a seeded Latin-hypercube jitter of
//!   several;
//! - [`shade`]: the shading of one ray's nearest hit ([`shade_hit`]), the plain statement of
//!   the lighting model;
//! - `packets.rs`: the same shading for a group of rays at once, as the tracer runs it: camera
//!   rays to the BVH as packets ([`crate::accel::PACKET`] rays), the shadow rays of their hits
//!   as packets toward each light, constants computed once per trace, shadow rays that cannot
//!   be blocked not traced. It gives [`shade_hit`]'s bits for every ray (tested cell by cell);
//! - [`clip`]: clip hyperplanes, checked only in scenes that have them: a ray's nearest hit
//!   beyond one of its object's hyperplanes is rejected and the ray traced again without it;
//! - [`pool`]: the retina's output buffers, reused between traces;
//! - `splat.rs` and `surface.rs`: after the trace, the surfaces drawn directly
//!   ([`crate::surface`]) projected into the retina as thin sheets, occluded by depth and
//!   blended by opacity, each point lit by the limit of its thickening's lighting.
//!
//! A ray's hit does not depend on the rays it travels with, and every cell's result depends
//! only on the scene, the seed and the cell index, so the retina is bit-identical whatever the
//! number of threads.

pub mod clip;
mod gouraud;
mod packets;
pub mod pool;
mod sampling;
pub mod shade;
mod splat;
mod surface;
mod tiles;
mod trace;

#[cfg(test)]
mod tests;

pub use shade::shade_hit;
pub use trace::{slabs, trace, trace_slab};

use std::sync::atomic::{AtomicBool, AtomicUsize};

/// A traced (N−1)-D retina. Arrays are C-ordered in numpy order `[i_{N−1}, …, i_1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Retina {
    /// Dimension N of the scene.
    pub dim: usize,
    /// Retina shape in numpy order `[R_{N−1}, …, R_1]`.
    pub shape: Vec<usize>,
    /// Linear RGBA, premultiplied by alpha (the covered fraction of the cell).
    pub rgba: Vec<f32>,
    /// Distance to the nearest hit (see [`crate::camera::Camera::depth`]); inf on a miss.
    pub depth: Vec<f32>,
    /// Unit shading normal of the nearest hit (N per cell); zero on a miss.
    pub normal: Vec<f32>,
    /// Object index of the nearest hit; −1 on a miss.
    pub object_id: Vec<i32>,
    /// Index into that object's simplices; −1 on a miss.
    pub primitive_id: Vec<i64>,
}

/// Shared progress of a trace: cells done, and a flag that cancels it.
#[derive(Debug, Default)]
pub struct Progress {
    /// Cells finished so far.
    pub done: AtomicUsize,
    /// Set to stop the trace early (it then returns [`crate::NdError::Cancelled`]).
    pub cancel: AtomicBool,
}

/// What a cell records of its nearest hit (the retina's depth, normal and ids).
#[derive(Clone, Copy, Debug, PartialEq)]
struct NearestHit<const N: usize> {
    depth: f64,
    normal: crate::linalg::Vector<N>,
    object: i32,
    primitive: i64,
}

impl<const N: usize> NearestHit<N> {
    /// The record of a miss, as the retina holds it.
    const MISS: Self = NearestHit {
        depth: f64::INFINITY,
        normal: [0.0; N],
        object: -1,
        primitive: -1,
    };
}
