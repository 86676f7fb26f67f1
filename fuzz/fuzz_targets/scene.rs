//! The scene path: TOML text → description → built scene (meshes, BVH, camera), and every
//! animation frame's description and build. Any Err is fine; a panic, abort, hang or
//! allocation beyond the limits is a finding.
#![no_main]
use libfuzzer_sys::fuzz_target;
mod common;

fuzz_target!(|data: &[u8]| {
    common::init_scene();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // Mesh files resolve against the repository's scenes/ (data/icosphere.npz).
    let base = &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let Ok((desc, _scene)) = ndtrace::scene::load_toml_str(text, "fuzz.toml", Some(base)) else {
        return;
    };
    let _ = ndtrace::scene::to_toml(&desc);
    if let Some(a) = &desc.animation {
        // The first, a middle and the last frame (and one past the end, an error).
        let k = a.frames;
        for f in [0, k / 2, k.saturating_sub(1), k] {
            if let Ok(frame) = ndtrace::scene::animation_frame(&desc, f, "fuzz.toml") {
                let _ = ndtrace::scene::build_desc(&frame, "fuzz.toml", Some(base));
            }
        }
    }
});
