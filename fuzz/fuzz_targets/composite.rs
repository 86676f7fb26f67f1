//! Compositing a retina with any options: the input is `options TOML \0 retina`, the retina
//! being one byte for its number of axes (1..=5, N = 2..=6), one per axis length (1..=8), a
//! flag byte (depth present) and raw little-endian f32s (NaN, inf and all), repeated to fill
//! the cells. Any Err is fine; the picture must have the size asked for.
#![no_main]
use libfuzzer_sys::fuzz_target;
use ndtrace::composite::{composite, CompositeOptions};
mod common;

fuzz_target!(|data: &[u8]| {
    common::init();
    let split = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let Ok(text) = std::str::from_utf8(&data[..split]) else {
        return;
    };
    let Ok(mut opts) = toml::from_str::<CompositeOptions>(text) else {
        return;
    };
    let rest = data.get(split + 1..).unwrap_or(&[]);
    let Some((&axes, rest)) = rest.split_first() else {
        return;
    };
    let axes = 1 + axes as usize % 5;
    if rest.len() < axes + 1 {
        return;
    }
    let shape: Vec<usize> = rest[..axes].iter().map(|&b| 1 + b as usize % 8).collect();
    let with_depth = rest[axes] & 1 == 1;
    let floats: Vec<f32> = rest[axes + 1..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let cells: usize = shape.iter().product();
    let fill = |n: usize, skip: usize| -> Vec<f32> {
        if floats.is_empty() {
            vec![0.5; n]
        } else {
            (0..n).map(|i| floats[(i + skip) % floats.len()]).collect()
        }
    };
    let rgba = fill(cells * 4, 0);
    let depth = with_depth.then(|| fill(cells, cells * 4));
    // Keep each run short: pictures up to 64 × 64 (the size checks are unit-tested).
    opts.size = (opts.size.0.min(64), opts.size.1.min(64));
    if let Ok(img) = composite(&rgba, depth.as_deref(), &shape, &opts) {
        assert_eq!((img.width, img.height), opts.size);
        assert_eq!(img.rgba.len(), img.width * img.height * 4);
    }
});
