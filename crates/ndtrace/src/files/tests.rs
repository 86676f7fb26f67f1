use super::*;

fn retina(dim: usize, shape: Vec<usize>) -> Retina {
    let cells: usize = shape.iter().product();
    Retina {
        dim,
        shape,
        rgba: (0..cells * 4).map(|i| (i % 7) as f32 * 0.125).collect(),
        depth: (0..cells)
            .map(|i| if i % 3 == 0 { f32::INFINITY } else { i as f32 })
            .collect(),
        normal: (0..cells * dim).map(|i| (i % 5) as f32 - 2.0).collect(),
        object_id: (0..cells).map(|i| (i % 4) as i32 - 1).collect(),
        primitive_id: (0..cells)
            .map(|i| if i % 4 == 0 { -1 } else { (i as i64) << 20 })
            .collect(),
    }
}

#[test]
fn retinas_round_trip_through_exr_in_every_dimension() {
    let dir = std::env::temp_dir().join(format!("ndtrace-files-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (dim, shape) in [
        (2, vec![5]),
        (3, vec![3, 4]),
        (4, vec![2, 3, 4]),
        (5, vec![2, 2, 3, 4]),
    ] {
        let r = retina(dim, shape);
        let path = dir.join(format!("r{dim}.exr"));
        write_retina_exr(&path, &r, Some("camera text")).unwrap();
        match read_exr(&path).unwrap() {
            ExrContents::Retina(back, cam) => {
                assert_eq!(back, r, "dim {dim}");
                assert_eq!(cam.as_deref(), Some("camera text"));
            }
            other => panic!("read a picture: {other:?}"),
        }
    }
    // Writing over an existing file replaces it only on success.
    let path = dir.join("keep.exr");
    std::fs::write(&path, b"precious").unwrap();
    let bad = Picture {
        width: 2,
        height: 2,
        rgba: vec![0.0; 3],
        depth: None,
    };
    assert!(write_picture_exr(&path, &bad).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), b"precious");
    assert!(std::fs::read_dir(&dir).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .contains(".tmp")));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn written_files_keep_the_replaced_files_mode_and_long_names_work() {
    use std::os::unix::fs::PermissionsExt;
    let dir = std::env::temp_dir().join(format!("ndtrace-modes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let picture = Picture {
        width: 2,
        height: 1,
        rgba: vec![0.5; 8],
        depth: None,
    };
    // A legal name of 250 bytes: the temporary file's name must not be longer than 255.
    let long = dir.join(format!("{}.exr", "p".repeat(246)));
    write_picture_exr(&long, &picture).unwrap();
    assert!(long.is_file());
    // A file replaced keeps its mode (0640 here), not the temporary file's.
    let path = dir.join("mode.exr");
    std::fs::write(&path, b"old").unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).unwrap();
    write_picture_exr(&path, &picture).unwrap();
    let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);
    // A folder is refused before anything is written.
    let e = write_picture_exr(&dir, &picture).unwrap_err().to_string();
    assert!(e.contains("it is a folder"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn unreadable_files_are_clear_errors() {
    let e = read_exr(Path::new("/nonexistent/x.exr"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("/nonexistent/x.exr") && e.contains("cannot read"),
        "{e}"
    );
    let p = std::env::temp_dir().join(format!("ndtrace-notexr-{}.exr", std::process::id()));
    std::fs::write(&p, b"hello").unwrap();
    let e = read_exr(&p).unwrap_err().to_string();
    assert!(e.contains("not a readable OpenEXR file"), "{e}");
    std::fs::remove_file(&p).unwrap();
    let e = write_picture_exr(
        Path::new("/nonexistent/dir/x.exr"),
        &Picture {
            width: 1,
            height: 1,
            rgba: vec![0.0; 4],
            depth: None,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("does not exist"), "{e}");
}

#[test]
fn retina_files_are_the_same_bytes_every_time() {
    // Each write builds new attribute maps (new hash seeds): without sorting, the custom
    // attributes of a part come out in a different order most times.
    let dir = std::env::temp_dir().join(format!("ndtrace-bytes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let r = retina(5, vec![2, 2, 3, 4]);
    let bytes: Vec<Vec<u8>> = (0..6)
        .map(|k| {
            let path = dir.join(format!("r{k}.exr"));
            write_retina_exr(&path, &r, Some("camera")).unwrap();
            std::fs::read(&path).unwrap()
        })
        .collect();
    assert!(bytes.iter().all(|b| b == &bytes[0]));
    // Sorting keeps a valid file: it reads back as written.
    match read_exr_bytes(&bytes[0], Path::new("r.exr")).unwrap() {
        ExrContents::Retina(back, _) => assert_eq!(back, r),
        other => panic!("{other:?}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A picture file whose data and display windows are patched to (0, 0)–(x_max, y_max).
fn lying_picture(x_max: i32, y_max: i32) -> Vec<u8> {
    let path = std::env::temp_dir().join(format!("ndtrace-lie-{}.exr", std::process::id()));
    let p = Picture {
        width: 4,
        height: 5,
        rgba: vec![0.25; 80],
        depth: None,
    };
    write_picture_exr(&path, &p).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    for name in [&b"dataWindow\0box2i\0"[..], b"displayWindow\0box2i\0"] {
        let at = bytes.windows(name.len()).position(|w| w == name).unwrap() + name.len() + 4;
        for (k, v) in [0, 0, x_max, y_max].into_iter().enumerate() {
            bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    bytes
}

#[test]
fn headers_are_checked_before_the_exr_crate_allocates() {
    // 10^10 pixels of 4 f32 channels declared by a 0.4 KB file.
    let e = read_exr_bytes(&lying_picture(99_999, 99_999), Path::new("lie.exr"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("lie.exr: reading its samples needs about 596.0 GiB of memory"),
        "{e}"
    );
    // The real size still reads.
    let ok = read_exr_bytes(&lying_picture(3, 4), Path::new("ok.exr")).unwrap();
    assert!(matches!(ok, ExrContents::Picture(p) if p.width == 4 && p.height == 5));
}

#[test]
fn retinas_are_checked_before_they_are_written() {
    let path = Path::new("/nonexistent/never-written.exr");
    let check = |r: Retina| write_retina_exr(path, &r, None).unwrap_err().to_string();
    let mut r = retina(4, vec![2, 3, 4]);
    r.depth.pop();
    assert_eq!(
        check(r),
        "depth: holds 23 values, the retina's shape [2, 3, 4] needs 24 (1 per cell)"
    );
    let mut r = retina(4, vec![2, 3, 4]);
    r.dim = 5;
    assert!(check(r).starts_with("shape: a retina of dimension 5 has 4 positive axes"));
    let mut r = retina(3, vec![3, 4]);
    r.object_id[5] = -2;
    assert_eq!(
        check(r),
        "object_id: -2 at cell 5 is not an object index or -1"
    );
    let mut r = retina(3, vec![3, 4]);
    r.shape = vec![usize::MAX / 2, 3];
    assert!(check(r).contains("too many cells"));
    let mut r = retina(3, vec![3, 4]);
    r.dim = 0;
    assert!(check(r).contains("dimension 0 is not supported"));
}

#[test]
fn srgb_transfer_matches_its_definition() {
    assert_eq!(linear_to_srgb(0.0), 0.0);
    assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
    assert!((linear_to_srgb(0.5) - 0.735_356_6).abs() < 1e-5);
    assert!((linear_to_srgb(0.002) - 0.02584).abs() < 1e-5);
}
