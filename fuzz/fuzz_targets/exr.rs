//! The EXR reader: any bytes as a retina or picture file. Any Err is fine.
#![no_main]
use libfuzzer_sys::fuzz_target;
mod common;

fuzz_target!(|data: &[u8]| {
    common::init();
    let _ = ndtrace::files::read_exr_bytes(data, std::path::Path::new("fuzz.exr"));
});
