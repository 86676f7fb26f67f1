//! The one place where a runtime dimension becomes a compile-time one.
//!
//! Everything numeric in ndtrace is generic over `const N: usize`; code that starts from a
//! runtime `dim` (a scene file, a numpy array) goes through [`with_dim!`](crate::with_dim) (or, for a built
//! scene, [`crate::with_scene!`] on a [`crate::scene::AnyScene`]).
//!
//! The supported dimensions are written once, in [`supported_dims!`](crate::supported_dims): the `match` arms of
//! [`with_dim!`](crate::with_dim) and [`crate::with_scene!`], the variants of [`crate::scene::AnyScene`] and
//! [`SUPPORTED_DIMS`] (so [`MIN_DIM`] and [`MAX_DIM`]) are all generated from that list.

/// Calls the macro `$then` with the supported dimensions: `supported_dims!(($then) ARGS)`
/// expands to `$then! { ARGS ; 2 D2, 3 D3, …, 8 D8 }`, each N with the name of its
/// [`crate::scene::AnyScene`] variant. This list is the only place the dimensions are written:
/// extending it extends every dispatch generated from it.
///
/// `$then` is a path in parentheses (`($crate::some_macro)` from inside an exported macro).
///
/// ```
/// # // Run by `dim::tests::the_doc_examples_hold`.
/// macro_rules! count {
///     ($what:literal ; $($n:literal $variant:ident),*) => {
///         ($what, [$($n),*].len())
///     };
/// }
/// assert_eq!(ndtrace::supported_dims!((count) "dimensions"), ("dimensions", 7));
/// ```
#[macro_export]
macro_rules! supported_dims {
    (($($then:tt)+) $($args:tt)*) => {
        $($then)+! { $($args)* ; 2 D2, 3 D3, 4 D4, 5 D5, 6 D6, 7 D7, 8 D8 }
    };
}

/// The list of [`supported_dims!`](crate::supported_dims) as an array expression.
#[doc(hidden)]
#[macro_export]
macro_rules! __dims_array {
    (; $($n:literal $variant:ident),*) => {
        [$($n),*]
    };
}

/// The supported dimensions N, in increasing order (from [`supported_dims!`](crate::supported_dims)).
pub const SUPPORTED_DIMS: &[usize] = &crate::supported_dims!((crate::__dims_array));
/// Smallest supported dimension N.
pub const MIN_DIM: usize = SUPPORTED_DIMS[0];
/// Largest supported dimension N.
pub const MAX_DIM: usize = SUPPORTED_DIMS[SUPPORTED_DIMS.len() - 1];

// The list is every N in MIN_DIM..=MAX_DIM, in order ([`check_dim`] and the error messages
// speak of that range; a test checks that `NdError::Dimension` names it).
const _: () = {
    let mut k = 0;
    while k < SUPPORTED_DIMS.len() {
        assert!(SUPPORTED_DIMS[k] == MIN_DIM + k);
        k += 1;
    }
    assert!(MIN_DIM >= 2);
};

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

/// `value` as the type `U`, when `T` is `U` (else `value` back): code written for one
/// dimension only — the elevation map and the surfaces live in R^4 — is compiled once, for
/// `Foo<4>`, and reached from code generic over N after checking `N == 4`, instead of being
/// compiled for every N of [`SUPPORTED_DIMS`].
pub fn same<T: 'static, U: 'static>(value: T) -> Result<U, T> {
    let mut slot = Some(value);
    match (&mut slot as &mut dyn std::any::Any).downcast_mut::<Option<U>>() {
        Some(u) => Ok(u.take().expect("just filled")),
        None => Err(slot.expect("not taken")),
    }
}

/// [`same`] for a reference.
pub fn same_ref<T: 'static, U: 'static>(value: &T) -> Option<&U> {
    (value as &dyn std::any::Any).downcast_ref::<U>()
}

/// Runs `$body` with `$N` bound to the compile-time constant equal to the runtime `$dim`.
///
/// Evaluates to `Ok(body)` for `dim` in [`SUPPORTED_DIMS`] (2..=8) and to
/// `Err(NdError::Dimension)` otherwise.
///
/// ```
/// # // Run by `dim::tests::the_doc_examples_hold`.
/// use ndtrace::with_dim;
/// let n: usize = 5;
/// let zeros = with_dim!(n, N => [0.0f64; N].len()).unwrap();
/// assert_eq!(zeros, 5);
/// assert!(with_dim!(9usize, N => N).is_err());
/// ```
#[macro_export]
macro_rules! with_dim {
    ($dim:expr, $N:ident => $body:expr) => {
        $crate::supported_dims!(($crate::__with_dim_arms) $dim, $N, $body)
    };
}

/// The `match` of [`with_dim!`](crate::with_dim), one arm per supported dimension.
#[doc(hidden)]
#[macro_export]
macro_rules! __with_dim_arms {
    ($dim:expr, $N:ident, $body:expr ; $($n:literal $variant:ident),*) => {{
        #[allow(clippy::redundant_closure_call)]
        match $dim {
            $(
                $n => {
                    const $N: usize = $n;
                    Ok($body)
                }
            )*
            d => Err($crate::NdError::Dimension { dim: d }),
        }
    }};
}

#[cfg(test)]
mod tests;
