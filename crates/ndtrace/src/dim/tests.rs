use super::*;
use crate::NdError;

#[test]
fn the_list_is_two_to_eight() {
    assert_eq!(SUPPORTED_DIMS, &[2, 3, 4, 5, 6, 7, 8]);
    assert_eq!((MIN_DIM, MAX_DIM, MAX_POINTS), (2, 8, 9));
}

#[test]
fn every_supported_dimension_binds_its_constant() {
    for &d in SUPPORTED_DIMS {
        assert_eq!(with_dim!(d, N => N).unwrap(), d);
        // The constant is a compile-time one: it sizes an array.
        assert_eq!(with_dim!(d, N => [0u8; N].len()).unwrap(), d);
        assert_eq!(check_dim(d), Ok(d));
    }
}

#[test]
fn dimensions_outside_the_range_are_errors() {
    for d in [0usize, 1, MIN_DIM - 1, MAX_DIM + 1, 100] {
        match with_dim!(d, N => N) {
            Err(NdError::Dimension { dim }) => assert_eq!(dim, d),
            other => panic!("dim {d}: expected a Dimension error, got {other:?}"),
        }
        assert_eq!(check_dim(d), Err(NdError::Dimension { dim: d }));
    }
    // The message (in `error.rs`, which does not depend on this module) names the range.
    let msg = check_dim(9).unwrap_err().to_string();
    assert!(
        msg.contains(&format!("{MIN_DIM}..={MAX_DIM}")) && msg.contains('9'),
        "{msg}"
    );
}

#[test]
fn the_body_is_evaluated_once_in_the_matching_arm_only() {
    let mut calls = vec![];
    for &d in SUPPORTED_DIMS {
        with_dim!(d, N => calls.push(N)).unwrap();
    }
    assert_eq!(calls, SUPPORTED_DIMS);
    // `$dim` is evaluated once.
    let mut evaluated = 0;
    let r = with_dim!({ evaluated += 1; 4usize }, N => N * 10);
    assert_eq!((r, evaluated), (Ok(40), 1));
}

/// The examples of `supported_dims!` and `with_dim!`'s documentation, which `cargo test` runs
/// here (the crate's doc examples are not compiled as doctests).
#[test]
fn the_doc_examples_hold() {
    macro_rules! count {
        ($what:literal ; $($n:literal $variant:ident),*) => {
            ($what, [$($n),*].len())
        };
    }
    assert_eq!(
        crate::supported_dims!((count) "dimensions"),
        ("dimensions", 7)
    );
    let n: usize = 5;
    let zeros = crate::with_dim!(n, N => [0.0f64; N].len()).unwrap();
    assert_eq!(zeros, 5);
    assert!(crate::with_dim!(9usize, N => N).is_err());
}
