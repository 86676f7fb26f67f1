//! Pictures and retinas on disk: OpenEXR (the `exr` crate), and the 8-bit sRGB bytes of a
//! picture ([`to_srgb8`]) that the Python package writes as PNG, JPEG, WebP or TIFF through
//! Pillow. Every file is written to a temporary file beside its destination and renamed into
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
    if path.file_name().is_none() {
        return Err(file_err(path, "not a file name"));
    }
    if path.is_dir() {
        return Err(file_err(path, "cannot write: it is a folder"));
    }
    // A short name, whatever the destination's length (a legal 250-byte name must not make a
    // temporary name longer than the file system allows); the extension kept last: some
    // writers choose the format from it.
    static SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_string())
        .filter(|e| e.len() <= 16)
        .unwrap_or_default();
    let tmp = dir.join(format!(
        ".ndtrace-{}-{}.tmp.{ext}",
        std::process::id(),
        SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    // The temporary file is created with the mode the umask gives; a file it replaces keeps
    // its own mode.
    let result = write(&tmp)
        .and_then(|_| match std::fs::metadata(path) {
            Ok(old) => std::fs::set_permissions(&tmp, old.permissions()).map_err(|e| e.to_string()),
            Err(_) => Ok(()),
        })
        .and_then(|_| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
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
    let n = p.width.saturating_mul(p.height);
    if n.checked_mul(4) != Some(p.rgba.len()) || p.width == 0 || p.height == 0 {
        return Err(NdError::Value {
            arg: "image".into(),
            message: format!("expected ({}, {}, 4) values", p.height, p.width),
        });
    }
    if let Some(d) = p.depth.as_ref().filter(|d| d.len() != n) {
        return Err(NdError::Value {
            arg: "depth".into(),
            message: format!(
                "expected ({}, {}) values, got {}",
                p.height,
                p.width,
                d.len()
            ),
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
    check_retina(r)?;
    let n = r.dim;
    let (w, h) = match r.shape.len() {
        1 => (r.shape[0], 1),
        _ => (r.shape[r.shape.len() - 1], r.shape[r.shape.len() - 2]),
    };
    let per = w * h;
    let parts = r.depth.len() / per.max(1);
    let shape_text = shape_text(&r.shape);
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
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| file_err(path, format!("cannot write: {e}")))?;
    let mut bytes = bytes.into_inner();
    sort_header_attributes(&mut bytes).map_err(|e| file_err(path, format!("cannot write: {e}")))?;
    write_atomically(path, |tmp| {
        std::fs::write(tmp, &bytes).map_err(|e| e.to_string())
    })
}

/// Checks a retina's arrays against its dimension and shape and against each other (the
/// Python bindings accept them from the user): every index the writer makes is then in range.
pub fn check_retina(r: &Retina) -> NdResult<()> {
    let value = |arg: &str, message: String| NdError::Value {
        arg: arg.into(),
        message,
    };
    if !(crate::MIN_DIM..=crate::MAX_DIM).contains(&r.dim) {
        return Err(NdError::Dimension { dim: r.dim });
    }
    if r.shape.len() + 1 != r.dim || r.shape.contains(&0) {
        return Err(value(
            "shape",
            format!(
                "a retina of dimension {} has {} positive axes, got {:?}",
                r.dim,
                r.dim - 1,
                r.shape
            ),
        ));
    }
    let cells = crate::memory::product(&r.shape)
        .filter(|c| c.checked_mul(4.max(r.dim)).is_some())
        .ok_or_else(|| value("shape", format!("{:?} has too many cells", r.shape)))?;
    for (name, len, per) in [
        ("rgba", r.rgba.len(), 4),
        ("depth", r.depth.len(), 1),
        ("normal", r.normal.len(), r.dim),
        ("object_id", r.object_id.len(), 1),
        ("primitive_id", r.primitive_id.len(), 1),
    ] {
        if len != cells * per {
            return Err(value(
                name,
                format!(
                    "holds {len} values, the retina's shape {:?} needs {} ({per} per cell)",
                    r.shape,
                    cells * per
                ),
            ));
        }
    }
    // Ids are written plus one, 0 meaning a miss.
    if let Some(i) = r.object_id.iter().position(|&o| o < -1 || o == i32::MAX) {
        return Err(value(
            "object_id",
            format!(
                "{} at cell {i} is not an object index or -1",
                r.object_id[i]
            ),
        ));
    }
    if let Some(i) = r.primitive_id.iter().position(|&p| p < -1 || p == i64::MAX) {
        return Err(value(
            "primitive_id",
            format!(
                "{} at cell {i} is not a simplex index or -1",
                r.primitive_id[i]
            ),
        ));
    }
    Ok(())
}

/// Sorts the attributes of every header of an EXR file in memory by name, so that the same
/// image always gives the same bytes: the `exr` crate writes a part's custom attributes in the
/// order of a `HashMap`, which changes from run to run. The OpenEXR format lets attributes come
/// in any order, and a header keeps its length, so the offset tables after it stay valid.
fn sort_header_attributes(bytes: &mut [u8]) -> std::result::Result<(), String> {
    const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
    const MULTIPART: u32 = 0x1000;
    let bad = || "unexpected EXR header layout".to_string();
    if bytes.len() < 8 || bytes[..4] != MAGIC {
        return Err(bad());
    }
    let multipart = u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]) & MULTIPART != 0;
    let cstr_end = |b: &[u8], at: usize| -> std::result::Result<usize, String> {
        b.get(at..)
            .and_then(|t| t.iter().position(|&c| c == 0))
            .map(|n| at + n + 1)
            .ok_or_else(bad)
    };
    let mut at = 8;
    loop {
        // One header: attributes (name\0 type\0 size:i32 value) up to an empty name.
        let start = at;
        let mut attrs: Vec<std::ops::Range<usize>> = vec![];
        while *bytes.get(at).ok_or_else(bad)? != 0 {
            let name_end = cstr_end(bytes, at)?;
            let type_end = cstr_end(bytes, name_end)?;
            let size = bytes.get(type_end..type_end + 4).ok_or_else(bad)?;
            let size = u32::from_le_bytes([size[0], size[1], size[2], size[3]]) as usize;
            let end = type_end + 4 + size;
            if end > bytes.len() {
                return Err(bad());
            }
            attrs.push(at..end);
            at = end;
        }
        let mut sorted: Vec<&[u8]> = attrs.iter().map(|r| &bytes[r.clone()]).collect();
        // The name (up to its NUL) is a prefix of each attribute; names are unique.
        sorted.sort();
        let sorted = sorted.concat();
        bytes[start..at].copy_from_slice(&sorted);
        at += 1;
        // A multi-part file ends its list of headers with one more empty name.
        if !multipart || *bytes.get(at).ok_or_else(bad)? == 0 {
            return Ok(());
        }
    }
}

/// "4,5,6": the `ndtrace.retinaShape` attribute.
fn shape_text(shape: &[usize]) -> String {
    shape
        .iter()
        .map(|s| s.to_string())
        .collect::<Vec<_>>()
        .join(",")
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
    let bytes = std::fs::read(path).map_err(|e| file_err(path, format!("cannot read: {e}")))?;
    read_exr_bytes(&bytes, path)
}

/// Checks an EXR's headers before the `exr` crate allocates every channel of every part at
/// the size its header declares (a 600-byte file can declare 34 GB): the declared samples,
/// counted with checked arithmetic, must fit the memory guard twice (the crate's buffers and
/// the retina or picture built from them), and an uncompressed file must hold them.
fn check_exr_header(bytes: &[u8], path: &Path) -> NdResult<()> {
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| file_err(path, format!("not a readable OpenEXR file: {e}")))?;
    let mut total: u128 = 0;
    let mut uncompressed = true;
    for header in meta.headers.iter() {
        let area = header.layer_size.width() as u128 * header.layer_size.height() as u128;
        let per_pixel: u128 = header
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample() as u128)
            .sum();
        total = total.saturating_add(area.saturating_mul(per_pixel));
        uncompressed &= header.compression == Compression::Uncompressed;
    }
    if uncompressed && total > bytes.len() as u128 {
        return Err(file_err(
            path,
            format!(
                "not a readable OpenEXR file: its headers declare {total} bytes of uncompressed samples, the file has {}",
                bytes.len()
            ),
        ));
    }
    // f32 samples in the crate's buffers (f16 widen to f32 in ours), then our copy.
    crate::memory::check(total as f64 * 4.0, "reading its samples").map_err(|e| file_err(path, e))
}

/// [`read_exr`] of a file's bytes already in memory; `path` names it in errors.
pub fn read_exr_bytes(bytes: &[u8], path: &Path) -> NdResult<ExrContents> {
    check_exr_header(bytes, path)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| match e {
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
        let dim = usize::try_from(*dim)
            .ok()
            .filter(|d| (crate::MIN_DIM..=crate::MAX_DIM).contains(d))
            .ok_or_else(|| file_err(path, format!("ndtrace.dim = {dim} is not in 2..=8")))?;
        let shape: Vec<usize> = shape
            .to_string()
            .split(',')
            .map(|s| s.trim().parse::<usize>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| file_err(path, "bad ndtrace.retinaShape attribute"))?;
        if shape.len() + 1 != dim || shape.contains(&0) {
            return Err(file_err(
                path,
                "ndtrace.retinaShape does not match ndtrace.dim",
            ));
        }
        // The parts must tile the retina: each one R_1 × R_2 cells, one per leading index.
        let (w, h) = match shape.len() {
            1 => (shape[0], 1),
            m => (shape[m - 1], shape[m - 2]),
        };
        let cells = crate::memory::product(&shape);
        let parts = image.layer_data.len();
        if cells != Some(w * h * parts)
            || image
                .layer_data
                .iter()
                .any(|l| (l.size.width(), l.size.height()) != (w, h))
        {
            return Err(file_err(
                path,
                format!(
                    "ndtrace.retinaShape ({}) does not match its {parts} parts of {}",
                    shape_text(&shape),
                    image
                        .layer_data
                        .first()
                        .map_or("no cells".into(), |l| format!(
                            "{} × {} cells",
                            l.size.width(),
                            l.size.height()
                        )),
                ),
            ));
        }
        let cells = w * h * parts;
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
            // Subsampled channels hold fewer samples than the part has pixels.
            let n = w * h;
            if rgba
                .iter()
                .chain(&normals)
                .chain([&z])
                .any(|c| c.len() != n)
                || [&oid, &lo, &hi].iter().any(|c| c.len() != n)
            {
                return Err(file_err(path, "a retina channel is subsampled"));
            }
            for i in 0..n {
                r.rgba.extend((0..4).map(|c| rgba[c][i]));
                r.depth.push(z[i]);
                r.normal.extend((0..dim).map(|a| normals[a][i]));
                // Ids are stored plus one (0 = miss): objectId up to 2^31, primitiveId up to
                // 2^63, so that they come back as i32 and i64.
                let object = i32::try_from(i64::from(oid[i]) - 1)
                    .map_err(|_| file_err(path, format!("objectId {} is out of range", oid[i])))?;
                let pid = (hi[i] as u64) << 32 | lo[i] as u64;
                let primitive = i64::try_from(pid as i128 - 1)
                    .map_err(|_| file_err(path, format!("primitiveId {pid} is out of range")))?;
                r.object_id.push(object);
                r.primitive_id.push(primitive);
            }
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

#[cfg(test)]
mod tests;
