/// A fuzzed header (`fuzz/`, target npz): 14 unclosed braces outside quotes kept the
/// literal parser busy for minutes. Unbalanced headers are refused before parsing.
#[test]
fn unbalanced_headers_are_refused_at_once() {
    for text in [
        "{'descr': '<i4', 'shape': {{{{{{{{{{{{{{",
        "{'descr': '<i4', 'fortran_order': False, 'shape': (2, 3)}}",
        "{'descr': '<i4', 'fortran_order': False, 'shape': (2, 3), 'x': '(((}",
    ] {
        let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
        bytes.extend_from_slice(&(text.len() as u16).to_le_bytes());
        bytes.extend_from_slice(text.as_bytes());
        let t = std::time::Instant::now();
        let e = super::parse_npy(&bytes).unwrap_err();
        assert!(e.contains("unbalanced"), "{text}: {e}");
        assert!(t.elapsed().as_secs_f64() < 1.0, "{text}: {:?}", t.elapsed());
    }
}

use super::*;

fn npy_with(version: u8, descr: &str, order: &str, shape: &str, payload: &[u8]) -> Vec<u8> {
    let mut header =
        format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape}, }}");
    let prefix = if version == 1 { 10 } else { 12 };
    while (prefix + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = vec![0x93, b'N', b'U', b'M', b'P', b'Y', version, 0];
    if version == 1 {
        out.extend((header.len() as u16).to_le_bytes());
    } else {
        out.extend((header.len() as u32).to_le_bytes());
    }
    out.extend(header.as_bytes());
    out.extend(payload);
    out
}

fn npy(descr: &str, shape: &str, payload: &[u8]) -> Vec<u8> {
    npy_with(1, descr, "False", shape, payload)
}

fn bytes<T: Copy, const K: usize>(values: &[T], to: impl Fn(T) -> [u8; K]) -> Vec<u8> {
    values.iter().flat_map(|&v| to(v)).collect()
}

#[test]
fn parses_float_and_integer_arrays_of_either_byte_order() {
    let v = [1.5f64, -2.0, 3.0, 4.25];
    for (descr, payload) in [
        ("<f8", bytes(&v, f64::to_le_bytes)),
        (">f8", bytes(&v, f64::to_be_bytes)),
        ("<f4", bytes(&v.map(|x| x as f32), f32::to_le_bytes)),
        (">f4", bytes(&v.map(|x| x as f32), f32::to_be_bytes)),
        // float16: 1.5 = 0x3e00, -2 = 0xc000, 3 = 0x4200, 4.25 = 0x4440 (exact in half).
        (
            "<f2",
            bytes(&[0x3e00u16, 0xc000, 0x4200, 0x4440], u16::to_le_bytes),
        ),
        (
            ">f2",
            bytes(&[0x3e00u16, 0xc000, 0x4200, 0x4440], u16::to_be_bytes),
        ),
    ] {
        let a = parse_npy(&npy(descr, "(2, 2)", &payload)).unwrap();
        assert_eq!(a.shape, (2, 2), "{descr}");
        assert_eq!(a.data, v, "{descr}");
        assert!(!a.integer, "{descr}");
    }
    let i = [7i64, -8, 9];
    for (descr, payload) in [
        ("<i8", bytes(&i, i64::to_le_bytes)),
        (">i8", bytes(&i, i64::to_be_bytes)),
        ("<i4", bytes(&i.map(|x| x as i32), i32::to_le_bytes)),
        (">i4", bytes(&i.map(|x| x as i32), i32::to_be_bytes)),
        (">i2", bytes(&i.map(|x| x as i16), i16::to_be_bytes)),
        ("|i1", bytes(&i.map(|x| x as i8), i8::to_le_bytes)),
    ] {
        let a = parse_npy(&npy(descr, "(1, 3)", &payload)).unwrap();
        assert_eq!((a.shape, a.integer), ((1, 3), true), "{descr}");
        assert_eq!(a.data, [7.0, -8.0, 9.0], "{descr}");
    }
    let u = [0u64, 1, u32::MAX as u64 + 1];
    for (descr, payload) in [
        ("<u8", bytes(&u, u64::to_le_bytes)),
        (">u8", bytes(&u, u64::to_be_bytes)),
    ] {
        let a = parse_npy(&npy(descr, "(3, 1)", &payload)).unwrap();
        assert_eq!(a.data, [0.0, 1.0, 4294967296.0], "{descr}");
    }
    let a = parse_npy(&npy(
        ">u2",
        "(1, 2)",
        &bytes(&[3u16, 65535], u16::to_be_bytes),
    ))
    .unwrap();
    assert_eq!(a.data, [3.0, 65535.0]);
    // bool: 0 and 1, not integers (so never vertex indices).
    let a = parse_npy(&npy("|b1", "(1, 3)", &[1, 0, 1])).unwrap();
    assert_eq!((a.data, a.integer), (vec![1.0, 0.0, 1.0], false));
}

#[test]
fn fortran_order_and_later_versions_read_as_rows() {
    // [[1, 2, 3], [4, 5, 6]] stored column by column.
    let payload = bytes(&[1.0f64, 4.0, 2.0, 5.0, 3.0, 6.0], f64::to_le_bytes);
    let a = parse_npy(&npy_with(1, "<f8", "True", "(2, 3)", &payload)).unwrap();
    assert_eq!(a.shape, (2, 3));
    assert_eq!(a.data, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    for version in [2, 3] {
        let a = parse_npy(&npy_with(version, "<f8", "False", "(3, 2)", &payload)).unwrap();
        assert_eq!((a.shape, a.data[1]), ((3, 2), 4.0), "version {version}");
    }
    // Empty arrays are fine here (the mesh checks reject what they must).
    let a = parse_npy(&npy("<i8", "(0, 4)", &[])).unwrap();
    assert_eq!((a.shape, a.data.len()), ((0, 4), 0));
}

#[test]
fn arrays_that_are_not_2_d_or_not_numbers_are_refused_by_name() {
    let e = parse_npy(&npy("<f8", "(3,)", &[0; 24])).unwrap_err();
    assert_eq!(e, "expected a 2-D array, got a 1-D array of shape (3,) (dtype '<f8'); save it with shape (rows, columns), e.g. a.reshape(-1, dim)");
    let e = parse_npy(&npy("<f8", "(1, 1, 1)", &[0; 8])).unwrap_err();
    assert!(e.contains("got a 3-D array of shape (1, 1, 1)"), "{e}");
    let e = parse_npy(&npy("<f8", "()", &[0; 8])).unwrap_err();
    assert!(e.contains("got a 0-D array"), "{e}");
    for descr in ["<c16", "|S4", "<U1", "<M8[s]", "|V8", "<f16"] {
        let e = parse_npy(&npy(descr, "(1, 1)", &[0; 16])).unwrap_err();
        assert!(e.starts_with("unsupported dtype"), "{descr}: {e}");
    }
    let e = parse_npy(&npy_with(1, "|O", "False", "(1, 1)", &[0; 8])).unwrap_err();
    assert!(e.starts_with("unsupported dtype"), "{e}");
    let e = parse_npy(&npy("|b1", "(1, 2)", &[1, 2])).unwrap_err();
    assert!(e.contains("invalid value for bool"), "{e}");
}

#[test]
fn claimed_sizes_are_checked_before_anything_is_allocated() {
    assert!(parse_npy(b"").is_err());
    assert!(parse_npy(b"hello world").unwrap_err().contains("magic"));
    assert!(parse_npy(b"\x93NUMPY\x01\x00\x10")
        .unwrap_err()
        .contains("truncated"));
    assert!(parse_npy(b"\x93NUMPY\x02\x00\x10\x00")
        .unwrap_err()
        .contains("truncated"));
    assert!(parse_npy(b"\x93NUMPY\x04\x00\x00\x00")
        .unwrap_err()
        .contains("version 4.0"));
    // A 4 GiB header claimed by 12 bytes.
    let e = parse_npy(b"\x93NUMPY\x02\x00\xff\xff\xff\xff").unwrap_err();
    assert!(e.contains("4294967295 bytes"), "{e}");
    // A header longer than the entry.
    let mut cut = npy("<f8", "(1, 1)", &[0; 8]);
    cut.truncate(40);
    assert!(parse_npy(&cut)
        .unwrap_err()
        .starts_with("truncated .npy header"));
    // Too little data, and shapes whose products overflow (in either order, with zeros).
    let e = parse_npy(&npy("<f8", "(2, 2)", &[0; 8])).unwrap_err();
    assert_eq!(
        e,
        "truncated data: shape (2, 2) of '<f8' needs 32 bytes, the array holds 8"
    );
    let e = parse_npy(&npy("<f8", "(1000000, 1000000)", &[0; 8])).unwrap_err();
    assert!(
        e.starts_with("truncated data: the shape claims 1000000000000 elements"),
        "{e}"
    );
    for shape in [
        "(4294967296, 4294967296)",
        "(0, 4294967296, 4294967296)",
        "(4294967296, 4294967296, 0)",
        "(18446744073709551615, 2)",
    ] {
        let e = parse_npy(&npy("<f8", shape, &[0; 8])).unwrap_err();
        assert!(e.contains("overflow"), "{shape}: {e}");
    }
    let e = parse_npy(&npy("<f8", "(18446744073709551616, 1)", &[])).unwrap_err();
    assert!(e.contains("bad dimension"), "{e}");
    let e = parse_npy(&npy("<f8", "(-1, 2)", &[])).unwrap_err();
    assert!(e.contains("bad dimension -1"), "{e}");
    // 2 elements of 8 bytes each in 15 bytes: the count fits, the byte count does not.
    let e = parse_npy(&npy("<f8", "(1, 2)", &[0; 15])).unwrap_err();
    assert!(e.contains("needs 16 bytes"), "{e}");
    // Deep nesting and malformed headers are errors, not stack overflows or panics.
    let deep = format!(
        "{{'descr': {}'<f8'{}, }}",
        "[".repeat(2000),
        "]".repeat(2000)
    );
    let mut bad = b"\x93NUMPY\x01\x00".to_vec();
    bad.extend((deep.len() as u16).to_le_bytes());
    bad.extend(deep.as_bytes());
    assert!(parse_npy(&bad).unwrap_err().contains("nests 2001 brackets"));
    for header in [
        "{",
        "{'descr': '<f8'}",
        "{'descr': '<f8', 'fortran_order': 3, 'shape': (1, 1)}",
        "{'descr': '<f8', 'fortran_order': False, 'shape': (1.5, 1)}",
        "[1, 2]",
        "\u{1}",
    ] {
        let mut bad = b"\x93NUMPY\x01\x00".to_vec();
        bad.extend((header.len() as u16).to_le_bytes());
        bad.extend(header.as_bytes());
        bad.extend([0; 16]);
        assert!(parse_npy(&bad).is_err(), "{header}");
    }
}

#[test]
fn every_truncation_and_byte_flip_of_a_valid_array_is_an_error_or_an_array() {
    // A cheap stand-in for fuzzing: no prefix and no single-byte change may panic.
    let good = npy_with(
        2,
        ">i4",
        "False",
        "(2, 3)",
        &bytes(&[1i32, 2, 3, 4, 5, 6], i32::to_be_bytes),
    );
    for n in 0..good.len() {
        let _ = parse_npy(&good[..n]);
    }
    for i in 0..good.len() {
        for v in [0u8, 1, b'(', b')', b'9', b'[', 0x7f, 0xff] {
            let mut b = good.clone();
            b[i] = v;
            let _ = parse_npy(&b);
        }
    }
}
