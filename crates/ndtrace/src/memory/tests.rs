use super::*;

#[test]
fn limits_rows_are_parsed_and_unlimited_is_none() {
    let limits = "Limit                     Soft Limit           Hard Limit           Units     \n\
                      Max data size             unlimited            unlimited            bytes     \n\
                      Max address space         4294967296           unlimited            bytes     \n";
    assert_eq!(soft_limit(limits, "Max address space"), Some(4 << 30));
    assert_eq!(soft_limit(limits, "Max data size"), None);
    assert_eq!(soft_limit(limits, "Max stack size"), None);
    assert_eq!(
        status_kib("VmSize:\t  123 kB\nVmData: 7 kB", "VmData:"),
        Some(7)
    );
}

#[test]
fn the_cap_binds_and_refusals_say_what_and_how_much() {
    // A cap far below any real limit decides (the environment variable is not set in
    // tests; the cap is process-wide, so this test restores it).
    set_cap(Some(1 << 20));
    let (avail, source) = available();
    assert_eq!((avail, source), (1 << 20, Source::Cap));
    assert!(check(100_000.0, "x").is_ok());
    let e = check(600_000.0, "a retina of 9 cells").unwrap_err();
    assert!(
        e.starts_with("a retina of 9 cells needs about 585.9 KiB of memory")
            && e.contains("(512.0 KiB: half of the 1.0 MiB allowed by NDTRACE_MEMORY_LIMIT)"),
        "{e}"
    );
    assert!(check(f64::INFINITY, "x").is_err() && check(f64::NAN, "x").is_err());
    set_cap(None);
    assert_ne!(available().1, Source::Cap);
    assert!(available().0 > 1 << 20);
}

#[test]
fn products_overflow_to_none() {
    assert_eq!(product(&[3, 4, 5]), Some(60));
    assert_eq!(product(&[]), Some(1));
    assert_eq!(product(&[1 << 40, 1 << 30]), None);
}
