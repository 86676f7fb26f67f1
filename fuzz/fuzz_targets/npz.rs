//! The `.npz`/`.npy` path: the bytes as one `.npy` array, and as an `.npz` archive read for a
//! mesh's `vertices` and `simplices`. Any Err is fine.
#![no_main]
use libfuzzer_sys::fuzz_target;
mod common;

fuzz_target!(|data: &[u8]| {
    common::init();
    let _ = ndtrace::scene::npz::parse_npy(data);
    let path = std::env::temp_dir().join(format!("ndtrace-fuzz-{}.npz", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = ndtrace::scene::npz::read_npz(&path, &["vertices", "simplices"]);
    }
});
