//! Typed errors of the core. The bindings convert them to Python exceptions in one place.

use thiserror::Error;

/// Result alias used throughout the core.
pub type NdResult<T> = Result<T, NdError>;

/// Everything that can go wrong in the core, each saying what and where.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum NdError {
    /// A dimension outside the supported range.
    #[error("dimension {dim} is not supported: N must be in 2..=8")]
    Dimension { dim: usize },

    /// An array of the wrong shape.
    #[error("{arg}: expected shape {expected}, got {got}")]
    Shape {
        arg: String,
        expected: String,
        got: String,
    },

    /// A NaN or infinite input value.
    #[error("{arg}: non-finite value {value} at index {index}")]
    NonFinite {
        arg: String,
        index: usize,
        value: f64,
    },

    /// A degenerate item of a batch (zero-volume simplex, parallel ray or segment).
    #[error("{arg}: {reason} at batch index {index}")]
    Degenerate {
        arg: String,
        index: usize,
        reason: &'static str,
    },

    /// A problem in a scene, located in its source (`file:line:col` or `<dict>`).
    #[error("{location}: {}{message}", if path.is_empty() { String::new() } else { format!("{path}: ") })]
    Scene {
        location: String,
        path: String,
        message: String,
    },

    /// A file that cannot be read or written.
    #[error("{path}: {message}")]
    File { path: String, message: String },

    /// The user interrupted the work.
    #[error("interrupted")]
    Cancelled,

    /// A value outside its allowed range.
    #[error("{arg}: {message}")]
    Value { arg: String, message: String },
}
