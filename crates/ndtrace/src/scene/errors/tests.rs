use super::*;

#[test]
fn unknown_names_get_suggestions() {
    let m = friendly_message(
        "unknown variant `hypercub`, expected one of `mesh`, `simplex`, `hypercube`",
        "objects[1].shape",
    );
    assert_eq!(
        m,
        "unknown shape \"hypercub\" (did you mean \"hypercube\"?)"
    );
    let m = friendly_message(
        "unknown field `colr`, expected one of `color`, `smooth`",
        "objects[0].material",
    );
    assert_eq!(m, "unknown key \"colr\" (did you mean \"color\"?)");
    let m = friendly_message("unknown field `zzzzzz`, expected `color` or `smooth`", "x");
    assert_eq!(
        m,
        "unknown key \"zzzzzz\" (expected one of \"color\", \"smooth\")"
    );
    assert_eq!(friendly_message("invalid type", "x"), "invalid type");
    let m = friendly_message("OverflowError: can't convert negative int to unsigned", "x");
    assert_eq!(
        m,
        "integer out of range: expected a non-negative integer of sensible size"
    );
    let m = friendly_message(
        "TypeError: 'float' object cannot be interpreted as an integer",
        "x",
    );
    assert_eq!(m, "expected an integer, got float");
    let m = friendly_message("TypeError: must be real number, not str", "x");
    assert_eq!(m, "expected a number, got str");
}

#[test]
fn paths_are_located_in_the_toml_source() {
    let text = "dim = 3\n[camera]\nposition = [0, 0, 5]\n\n[[objects]]\nshape = \"sphere\"\n[[objects]]\nshape = \"mesh\"\nmaterial = { color = [1, 2] }\n";
    let root = DeTable::parse(text).unwrap();
    let (l, c) = line_col(text, span_of(&root, "objects[1].material.color").start);
    assert_eq!((l, c), (9, 22));
    let (l, _) = line_col(text, span_of(&root, "camera.position").start);
    assert_eq!(l, 3);
    // A missing key points at its parent.
    let (l, _) = line_col(text, span_of(&root, "objects[0].vertices").start);
    assert!(l == 5 || l == 6, "line {l}");
}
