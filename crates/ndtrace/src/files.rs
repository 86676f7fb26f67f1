//! Pictures and retinas on disk: OpenEXR (the `exr` crate) and 8-bit sRGB PNG (the `image`
//! crate). Every file is written to a temporary file beside its destination and renamed into
//! place, so an interrupted or failed write never leaves a broken file where a good one was.
//!
//! The retina layout is documented in `docs/retina-format.md`: a 2D image is one RGBA part
//! (plus `Z` when depth is present); a retina is one part per 2D slice `retina[k]` (leading
//! axes flattened in C order), R_1 wide and R_2 high, with channels `R G B A` (premultiplied),
//! `Z`, `N.0 … N.{N−1}`, `objectId` (id + 1, 0 = miss) and `primitiveId.lo`/`primitiveId.hi`
//! (id + 1 as two 32-bit halves), and header attributes `ndtrace.dim`, `ndtrace.retinaShape`,
//! `ndtrace.slice` and `ndtrace.camera`.

use crate::render::Retina;
use crate::{NdError, NdResult};
use exr::prelude::*;
use std::path::{Path, PathBuf};

fn file_err(path: &Path, message: impl std::fmt::Display) -> NdError {
    NdError::File {
        path: path.display().to_string(),
        message: message.to_string(),
    }
}

/// Writes through `write(tmp)` to a temporary file next to `path`, then renames it over
/// `path`. On failure the temporary file is removed and `path` is untouched.
pub fn write_atomically<F>(path: &Path, write: F) -> NdResult<()>
where
    F: FnOnce(&Path) -> std::result::Result<(), String>,
{
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(file_err(
            path,
            format!("cannot write: folder {} does not exist", dir.display()),
        ));
    }
    let name = path
        .file_name()
        .ok_or_else(|| file_err(path, "not a file name"))?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_string())
        .unwrap_or_default();
    // Keep the extension last: some writers choose the format from it.
    let tmp = dir.join(format!(
        ".{}.tmp-{}.{}",
        name.to_string_lossy(),
        std::process::id(),
        ext
    ));
    let result = write(&tmp).and_then(|_| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(file_err(path, format!("cannot write: {e}")));
    }
    Ok(())
}

/// A 2D picture: linear float RGBA, (H, W, 4) row-major, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    /// Width W.
    pub width: usize,
    /// Height H.
    pub height: usize,
    /// RGBA, premultiplied by alpha.
    pub rgba: Vec<f32>,
    /// Optional depth per pixel.
    pub depth: Option<Vec<f32>>,
}

/// What an EXR file holds.
#[derive(Debug, Clone, PartialEq)]
pub enum ExrContents {
    /// A 2D picture (any single-part RGB(A) EXR).
    Picture(Picture),
    /// A retina written by ndtrace, with its camera text.
    Retina(Retina, Option<String>),
}

fn encoding() -> Encoding {
    Encoding {
        compression: Compression::ZIP16,
        ..Encoding::SMALL_LOSSLESS
    }
}

fn f32_channel(name: &str, v: Vec<f32>) -> AnyChannel<FlatSamples> {
    AnyChannel::new(name, FlatSamples::F32(v))
}

/// Writes a 2D picture as one RGBA part (plus `Z`).
pub fn write_picture_exr(path: &Path, p: &Picture) -> NdResult<()> {
    let n = p.width * p.height;
    if p.rgba.len() != n * 4 || p.width == 0 || p.height == 0 {
        return Err(NdError::Value {
            arg: "image".into(),
            message: format!("expected ({}, {}, 4) values", p.height, p.width),
        });
    }
    let mut channels = vec![];
    for (k, name) in ["R", "G", "B", "A"].iter().enumerate() {
        channels.push(f32_channel(
            name,
            p.rgba.iter().skip(k).step_by(4).copied().collect(),
        ));
    }
    if let Some(d) = &p.depth {
        channels.push(f32_channel("Z", d.clone()));
    }
    let layer = Layer::new(
        (p.width, p.height),
        LayerAttributes::default(),
        encoding(),
        AnyChannels::sort(channels.into()),
    );
    let image = Image::from_layer(layer);
    write_atomically(path, |tmp| {
        image.write().to_file(tmp).map_err(|e| e.to_string())
    })
}

/// Writes a retina (any N): one part per 2D slice for N ≥ 4, a single part for N ≤ 3.
pub fn write_retina_exr(path: &Path, r: &Retina, camera: Option<&str>) -> NdResult<()> {
    let n = r.dim;
    let (w, h) = match r.shape.len() {
        1 => (r.shape[0], 1),
        _ => (r.shape[r.shape.len() - 1], r.shape[r.shape.len() - 2]),
    };
    let per = w * h;
    let parts = r.depth.len() / per.max(1);
    let shape_text = r
        .shape
        .iter()
        .map(|s| s.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let mut layers = vec![];
    for k in 0..parts {
        let cells = k * per..(k + 1) * per;
        let mut ch = vec![];
        for (c, name) in ["R", "G", "B", "A"].iter().enumerate() {
            ch.push(f32_channel(
                name,
                cells.clone().map(|i| r.rgba[i * 4 + c]).collect(),
            ));
        }
        ch.push(f32_channel("Z", r.depth[cells.clone()].to_vec()));
        for a in 0..n {
            ch.push(f32_channel(
                &format!("N.{a}"),
                cells.clone().map(|i| r.normal[i * n + a]).collect(),
            ));
        }
        ch.push(AnyChannel::new(
            "objectId",
            FlatSamples::U32(cells.clone().map(|i| (r.object_id[i] + 1) as u32).collect()),
        ));
        let pid: Vec<u64> = cells
            .clone()
            .map(|i| (r.primitive_id[i] + 1) as u64)
            .collect();
        ch.push(AnyChannel::new(
            "primitiveId.lo",
            FlatSamples::U32(pid.iter().map(|&p| p as u32).collect()),
        ));
        ch.push(AnyChannel::new(
            "primitiveId.hi",
            FlatSamples::U32(pid.iter().map(|&p| (p >> 32) as u32).collect()),
        ));
        let mut attrs = LayerAttributes::named(format!("slice.{k:05}").as_str());
        attrs
            .other
            .insert(Text::from("ndtrace.dim"), AttributeValue::I32(n as i32));
        attrs.other.insert(
            Text::from("ndtrace.retinaShape"),
            AttributeValue::Text(Text::from(shape_text.as_str())),
        );
        attrs
            .other
            .insert(Text::from("ndtrace.slice"), AttributeValue::I32(k as i32));
        if let Some(c) = camera {
            attrs.other.insert(
                Text::from("ndtrace.camera"),
                AttributeValue::Text(Text::from(c)),
            );
        }
        layers.push(Layer::new(
            (w, h),
            attrs,
            encoding(),
            AnyChannels::sort(ch.into()),
        ));
    }
    let image = Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions((w, h))),
        layers,
    );
    write_atomically(path, |tmp| {
        image.write().to_file(tmp).map_err(|e| e.to_string())
    })
}

fn channel<'a>(layer: &'a Layer<AnyChannels<FlatSamples>>, name: &str) -> Option<&'a FlatSamples> {
    layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == name)
        .map(|c| &c.sample_data)
}

fn as_f32(s: &FlatSamples) -> Vec<f32> {
    s.values_as_f32().collect()
}

fn as_u32(s: &FlatSamples) -> Vec<u32> {
    match s {
        FlatSamples::U32(v) => v.clone(),
        other => other.values_as_f32().map(|x| x as u32).collect(),
    }
}

/// Reads an EXR: a retina if it carries ndtrace's attributes, else a 2D RGBA picture (the
/// first part; a missing `A` channel means opaque, a missing colour channel is an error).
pub fn read_exr(path: &Path) -> NdResult<ExrContents> {
    let image = exr::prelude::read_all_flat_layers_from_file(path).map_err(|e| match e {
        exr::error::Error::Io(io) => file_err(path, format!("cannot read: {io}")),
        other => file_err(path, format!("not a readable OpenEXR file: {other}")),
    })?;
    let first = image
        .layer_data
        .first()
        .ok_or_else(|| file_err(path, "the file has no image parts"))?;
    let attr = |k: &str| first.attributes.other.get(&Text::from(k));
    if let (Some(AttributeValue::I32(dim)), Some(AttributeValue::Text(shape))) =
        (attr("ndtrace.dim"), attr("ndtrace.retinaShape"))
    {
        let dim = *dim as usize;
        let shape: Vec<usize> = shape
            .to_string()
            .split(',')
            .map(|s| s.trim().parse::<usize>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| file_err(path, "bad ndtrace.retinaShape attribute"))?;
        let cells: usize = shape.iter().product();
        if shape.len() + 1 != dim || cells == 0 {
            return Err(file_err(
                path,
                "ndtrace.retinaShape does not match ndtrace.dim",
            ));
        }
        let camera = match attr("ndtrace.camera") {
            Some(AttributeValue::Text(t)) => Some(t.to_string()),
            _ => None,
        };
        let mut r = Retina {
            dim,
            shape: shape.clone(),
            rgba: Vec::with_capacity(cells * 4),
            depth: Vec::with_capacity(cells),
            normal: Vec::with_capacity(cells * dim),
            object_id: Vec::with_capacity(cells),
            primitive_id: Vec::with_capacity(cells),
        };
        // Parts in slice order.
        let mut layers: Vec<&Layer<AnyChannels<FlatSamples>>> = image.layer_data.iter().collect();
        layers.sort_by_key(
            |l| match l.attributes.other.get(&Text::from("ndtrace.slice")) {
                Some(AttributeValue::I32(k)) => *k,
                _ => i32::MAX,
            },
        );
        for layer in layers {
            let need = |name: &str| {
                channel(layer, name)
                    .ok_or_else(|| file_err(path, format!("retina part lacks channel {name}")))
            };
            let rgba: Vec<Vec<f32>> = ["R", "G", "B", "A"]
                .iter()
                .map(|c| need(c).map(as_f32))
                .collect::<NdResult<_>>()?;
            let normals: Vec<Vec<f32>> = (0..dim)
                .map(|a| need(&format!("N.{a}")).map(as_f32))
                .collect::<NdResult<_>>()?;
            let z = as_f32(need("Z")?);
            let oid = as_u32(need("objectId")?);
            let (lo, hi) = (
                as_u32(need("primitiveId.lo")?),
                as_u32(need("primitiveId.hi")?),
            );
            for i in 0..z.len() {
                r.rgba.extend((0..4).map(|c| rgba[c][i]));
                r.depth.push(z[i]);
                r.normal.extend((0..dim).map(|a| normals[a][i]));
                r.object_id.push(oid[i] as i32 - 1);
                r.primitive_id
                    .push(((hi[i] as u64) << 32 | lo[i] as u64) as i64 - 1);
            }
        }
        if r.depth.len() != cells {
            return Err(file_err(
                path,
                format!(
                    "the parts hold {} cells, the retina shape needs {cells}",
                    r.depth.len()
                ),
            ));
        }
        return Ok(ExrContents::Retina(r, camera));
    }
    let size = first.size;
    let n = size.width() * size.height();
    let get = |name: &str| channel(first, name).map(as_f32);
    let (rr, gg, bb) = match (get("R"), get("G"), get("B")) {
        (Some(r), Some(g), Some(b)) => (r, g, b),
        _ => match get("Y") {
            Some(y) => (y.clone(), y.clone(), y),
            None => {
                return Err(file_err(
                    path,
                    "no R, G, B (or Y) channels in the first part",
                ))
            }
        },
    };
    let aa = get("A").unwrap_or_else(|| vec![1.0; n]);
    let mut rgba = Vec::with_capacity(n * 4);
    for i in 0..n {
        rgba.extend([rr[i], gg[i], bb[i], aa[i]]);
    }
    Ok(ExrContents::Picture(Picture {
        width: size.width(),
        height: size.height(),
        rgba,
        depth: get("Z"),
    }))
}

/// Linear → sRGB transfer function.
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// A picture as 8-bit sRGB bytes, row-major: RGBA with straight (un-premultiplied) alpha, or,
/// with `opaque`, RGB of the picture's colour as it is (the composite over its background).
pub fn to_srgb8(p: &Picture, opaque: bool) -> NdResult<Vec<u8>> {
    let n = p.width * p.height;
    if p.rgba.len() != n * 4 || n == 0 {
        return Err(NdError::Value {
            arg: "image".into(),
            message: format!("expected ({}, {}, 4) values", p.height, p.width),
        });
    }
    let encode = |c: f32| (linear_to_srgb(c) * 255.0 + 0.5) as u8;
    let mut bytes = Vec::with_capacity(n * if opaque { 3 } else { 4 });
    for px in p.rgba.chunks_exact(4) {
        if opaque {
            bytes.extend(px[..3].iter().map(|&c| encode(c)));
            continue;
        }
        let a = px[3].clamp(0.0, 1.0);
        bytes.extend(
            px[..3]
                .iter()
                .map(|&c| encode(if a > 0.0 { c / a } else { 0.0 })),
        );
        bytes.push((a * 255.0 + 0.5) as u8);
    }
    Ok(bytes)
}

/// Writes a picture as an 8-bit sRGB PNG with straight (un-premultiplied) alpha.
pub fn write_png(path: &Path, p: &Picture) -> NdResult<()> {
    let bytes = to_srgb8(p, false)?;
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            &bytes,
            p.width as u32,
            p.height as u32,
            image::ColorType::Rgba8,
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())
    })
}

#[cfg(test)]
mod tests {
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
            .contains(".tmp-")));
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
        let e = write_png(
            Path::new("/nonexistent/dir/x.png"),
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
    fn srgb_transfer_matches_its_definition() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_to_srgb(0.5) - 0.735_356_6).abs() < 1e-5);
        assert!((linear_to_srgb(0.002) - 0.02584).abs() < 1e-5);
    }
}
