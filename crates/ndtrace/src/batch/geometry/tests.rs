use super::*;

#[test]
fn batches_match_single_items_and_report_the_first_degenerate_index() {
    // Two 2D segments' hyperplanes: a good one and a repeated point.
    let pts = [
        0.0, 0.0, 1.0, 0.0, /* degenerate: */ 2.0, 2.0, 2.0, 2.0,
    ];
    let mut out = [0.0; 6];
    let err = hyperplane(2, &pts, &mut out, OnDegenerate::Error).unwrap_err();
    assert_eq!(
        err,
        NdError::Degenerate {
            arg: "points".into(),
            index: 1,
            reason: Degenerate::Simplex.reason()
        }
    );
    hyperplane(2, &pts, &mut out, OnDegenerate::Nan).unwrap();
    assert_eq!(&out[..3], &[0.0, 1.0, 0.0]);
    assert!(out[3..].iter().all(|v| v.is_nan()));
}

#[test]
fn wrong_sizes_and_dimensions_are_errors() {
    let mut out = [0.0; 3];
    assert!(matches!(
        generalized_cross(3, &[1.0; 5], &mut out),
        Err(NdError::Shape { .. })
    ));
    assert_eq!(
        generalized_cross(9, &[], &mut []),
        Err(NdError::Dimension { dim: 9 })
    );
    assert!(matches!(
        gram_volume(3, 4, &[0.0; 15], &mut [0.0]),
        Err(NdError::Shape { .. })
    ));
}
