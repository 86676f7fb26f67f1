//! Python bindings of ndtrace: a thin layer that moves numpy buffers in and out of the pure-Rust
//! core, releases the GIL while the core works, and converts core errors in one place
//! (`errors.rs`). Argument checking that speaks numpy (shapes, broadcasting) lives in the Python
//! package `ndtrace`; the kernels here re-check sizes through the core's batch layer.

use pyo3::prelude::*;

mod arrays;
mod buffers;
mod composite;
mod edges;
mod errors;
mod files;
mod geometry;
mod mesh;
mod rotation;
mod scene;

/// A rayon pool of `threads` workers, or `None` (the global pool, every core) for `None`.
pub(crate) fn thread_pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    match threads {
        Some(0) => Err(pyo3::exceptions::PyValueError::new_err(
            "threads: must be at least 1 (or None for every core)",
        )),
        Some(k) => rayon::ThreadPoolBuilder::new()
            .num_threads(k)
            .build()
            .map(Some)
            .map_err(|e| {
                pyo3::exceptions::PyValueError::new_err(format!(
                    "threads: cannot start {k} threads: {e}"
                ))
            }),
        None => Ok(None),
    }
}

/// The compiled part of ndtrace. Use the `ndtrace` package, not this module.
#[pymodule]
fn _ndtrace(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("MIN_DIM", ndtrace::MIN_DIM)?;
    m.add("MAX_DIM", ndtrace::MAX_DIM)?;
    errors::register(m)?;
    geometry::register(m)?;
    rotation::register(m)?;
    scene::register(m)?;
    composite::register(m)?;
    edges::register(m)?;
    files::register(m)?;
    mesh::register(m)?;
    Ok(())
}
