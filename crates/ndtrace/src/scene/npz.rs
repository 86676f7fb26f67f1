//! Reading 2-D numeric arrays from numpy `.npz` archives (zip files of `.npy` arrays), for mesh
//! objects given by `file`.
//!
//! The `.npy` format is read by [`npyz`]: versions 1–3, either byte order, C or Fortran order.
//! Floats (`f2`, `f4`, `f8`), integers (`i1`…`i8`, `u1`…`u8`) and `bool` become `f64`; any
//! other element type, and arrays that are not 2-D, are refused with the array's name, shape and
//! dtype. Every size a file claims is checked against the bytes it holds before anything is
//! allocated or parsed, so that a broken or hostile file is an error and never a panic, a
//! huge allocation or a deep recursion:
//! - an array is read header first: the memory its shape needs is checked by the memory guard
//!   before the rest is read or inflated, and an archive member is read to its end, so that
//!   its CRC-32 is checked;
//! - the header length must fit in the entry, and is capped as numpy caps it (10,000 bytes);
//! - the header's bracket nesting is bounded before the Python-literal parser sees it;
//! - the shape's element count and byte count are products checked for overflow (npyz
//!   multiplies the dimensions unchecked) and must fit in the data that follows the header.

use npyz::{NpyFile, Order, TypeChar};
use std::io::Read;
use std::path::Path;

/// A 2-D array read from an `.npz`, converted to f64, in C order.
#[derive(Debug, Clone, PartialEq)]
pub struct Array2 {
    /// Rows and columns.
    pub shape: (usize, usize),
    /// Row-major data.
    pub data: Vec<f64>,
    /// Whether the stored dtype was an integer type.
    pub integer: bool,
}

/// The longest `.npy` header read: numpy's own default limit (`max_header_size`), far above
/// what a numeric array's header needs.
const MAX_HEADER_LEN: usize = 10_000;

/// The deepest bracket nesting allowed in a header (a numeric array's has depth 2).
const MAX_HEADER_DEPTH: usize = 8;

/// Reads the named 2-D arrays from an `.npz` file; errors name the file and the array.
pub fn read_npz(path: &Path, names: &[&str]) -> Result<Vec<Array2>, String> {
    let file =
        std::fs::File::open(path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    let mut zip = zip::ZipArchive::new(std::io::BufReader::new(file))
        .map_err(|e| format!("{} is not an .npz (zip) archive: {e}", path.display()))?;
    names
        .iter()
        .map(|name| {
            let entry = zip
                .by_name(&npyz::npz::file_name_from_array_name(name))
                .map_err(|_| format!("{} has no array named \"{name}\"", path.display()))?;
            let claimed = entry.size();
            let bytes = read_member(entry, claimed)
                .map_err(|e| format!("{}: array \"{name}\": {e}", path.display()))?;
            parse_npy(&bytes).map_err(|e| format!("{}: array \"{name}\": {e}", path.display()))
        })
        .collect()
}

/// An array of any number of axes read from an `.npy`, converted to f64, in C order.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayNd {
    /// Lengths of its axes.
    pub shape: Vec<usize>,
    /// C-order (last axis fastest) data.
    pub data: Vec<f64>,
    /// Whether the stored dtype was an integer type.
    pub integer: bool,
    /// The stored dtype, as numpy writes it (e.g. `<f8`).
    pub dtype: String,
}

/// Parses an `.npy` buffer holding a 2-D numeric array.
pub fn parse_npy(bytes: &[u8]) -> Result<Array2, String> {
    let a = parse_npy_nd(bytes)?;
    match a.shape[..] {
        [rows, cols] => Ok(Array2 {
            shape: (rows, cols),
            data: a.data,
            integer: a.integer,
        }),
        _ => Err(format!(
            "expected a 2-D array, got a {}-D array of shape {} (dtype {}); save it with shape (rows, columns), e.g. a.reshape(-1, dim)",
            a.shape.len(),
            shape_text(&a.shape.iter().map(|&d| d as u64).collect::<Vec<_>>()),
            a.dtype
        )),
    }
}

/// Parses an `.npy` buffer holding a numeric array of any shape.
pub fn parse_npy_nd(bytes: &[u8]) -> Result<ArrayNd, String> {
    // 1. The sizes the header claims, checked before npyz parses or allocates anything.
    let data_len = check_header(bytes, bytes.len())?;
    let npy = NpyFile::new(bytes).map_err(|e| format!("not a valid .npy array: {e}"))?;
    let header = npy.header();
    let shape = header.shape().to_vec();
    let dtype = header.dtype();
    let descr = dtype.descr();
    let dims = shape
        .iter()
        .map(|&d| usize::try_from(d).map_err(|_| too_big(&shape)))
        .collect::<Result<Vec<usize>, String>>()?;
    // 2. The element type: a scalar float, integer or bool.
    let unsupported = || {
        format!(
            "unsupported dtype {descr} (use a float, integer or bool type such as float64 or int64)"
        )
    };
    let ty = match &dtype {
        npyz::DType::Plain(ty) => ty.clone(),
        _ => return Err(unsupported()),
    };
    let width = match (ty.type_char(), ty.size_field()) {
        (TypeChar::Float, 2 | 4 | 8)
        | (TypeChar::Int | TypeChar::Uint, 1 | 2 | 4 | 8)
        | (TypeChar::Bool, 1) => ty.size_field(),
        _ => return Err(unsupported()),
    };
    // 3. The data must hold every element.
    let count = dims
        .iter()
        .try_fold(1usize, |c, &d| c.checked_mul(d))
        .ok_or_else(|| too_big(&shape))?;
    let need = (count as u64)
        .checked_mul(width)
        .ok_or_else(|| too_big(&shape))?;
    if need > data_len as u64 {
        return Err(format!(
            "truncated data: shape {} of {descr} needs {need} bytes, the array holds {data_len}",
            shape_text(&shape)
        ));
    }
    let order = header.order();
    let read = |e: std::io::Error| format!("reading the data ({descr}): {e}");
    let values: Vec<f64> = match (ty.type_char(), width) {
        (TypeChar::Float, 2) => convert(npy.into_vec::<npyz::half::f16>(), f64::from),
        (TypeChar::Float, 4) => convert(npy.into_vec::<f32>(), f64::from),
        (TypeChar::Float, 8) => npy.into_vec::<f64>(),
        (TypeChar::Int, 1) => convert(npy.into_vec::<i8>(), f64::from),
        (TypeChar::Int, 2) => convert(npy.into_vec::<i16>(), f64::from),
        (TypeChar::Int, 4) => convert(npy.into_vec::<i32>(), f64::from),
        (TypeChar::Int, _) => convert(npy.into_vec::<i64>(), |v| v as f64),
        (TypeChar::Uint, 1) => convert(npy.into_vec::<u8>(), f64::from),
        (TypeChar::Uint, 2) => convert(npy.into_vec::<u16>(), f64::from),
        (TypeChar::Uint, 4) => convert(npy.into_vec::<u32>(), f64::from),
        (TypeChar::Uint, _) => convert(npy.into_vec::<u64>(), |v| v as f64),
        _ => convert(npy.into_vec::<bool>(), |b| f64::from(u8::from(b))),
    }
    .map_err(read)?;
    // 4. Fortran order stores the first axis fastest: reorder to C order.
    let data = match order {
        Order::C => values,
        Order::Fortran => fortran_to_c(&values, &dims),
    };
    Ok(ArrayNd {
        shape: dims,
        data,
        integer: matches!(ty.type_char(), TypeChar::Int | TypeChar::Uint),
        dtype: descr,
    })
}

/// Reorders `values`, stored first axis fastest, to C order (last axis fastest).
fn fortran_to_c(values: &[f64], dims: &[usize]) -> Vec<f64> {
    // Fortran strides: 1, d0, d0·d1, …
    let mut strides = vec![1usize; dims.len()];
    for k in 1..dims.len() {
        strides[k] = strides[k - 1] * dims[k - 1];
    }
    (0..values.len())
        .map(|c| {
            let (mut rest, mut f) = (c, 0);
            for k in (0..dims.len()).rev() {
                f += (rest % dims[k]) * strides[k];
                rest /= dims[k];
            }
            values[f]
        })
        .collect()
}

/// Reads the array called `name` from an `.npz` archive, or its only array when `name` is
/// `None`; errors name the file and list the arrays there are.
pub fn read_npz_array(path: &Path, name: Option<&str>) -> Result<ArrayNd, String> {
    let file =
        std::fs::File::open(path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    let mut zip = zip::ZipArchive::new(std::io::BufReader::new(file))
        .map_err(|e| format!("{} is not an .npz (zip) archive: {e}", path.display()))?;
    let arrays: Vec<String> = zip
        .file_names()
        .filter_map(|f| f.ok())
        .filter_map(|f| f.strip_suffix(".npy").map(str::to_string))
        .collect();
    let name = match name {
        Some(n) => n.to_string(),
        None if arrays.len() == 1 => arrays[0].clone(),
        None => {
            return Err(format!(
                "{} holds {} arrays ({}): say which with key",
                path.display(),
                arrays.len(),
                arrays.join(", ")
            ))
        }
    };
    let entry = zip
        .by_name(&npyz::npz::file_name_from_array_name(&name))
        .map_err(|_| {
            format!(
                "{} has no array named \"{name}\" (arrays: {})",
                path.display(),
                arrays.join(", ")
            )
        })?;
    let claimed = entry.size();
    let bytes = read_member(entry, claimed)
        .map_err(|e| format!("{}: array \"{name}\": {e}", path.display()))?;
    parse_npy_nd(&bytes).map_err(|e| format!("{}: array \"{name}\": {e}", path.display()))
}

/// Reads an `.npy` file; errors name the file. Its header is read first and the memory the
/// array needs checked by the guard before the rest of the file is read.
pub fn read_npy(path: &Path) -> Result<ArrayNd, String> {
    let file =
        std::fs::File::open(path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    let len = file
        .metadata()
        .map_err(|e| format!("cannot open {}: {e}", path.display()))?
        .len();
    let bytes = read_member(std::io::BufReader::new(file), len)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    parse_npy_nd(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// The bytes of an `.npy` array of `claimed` bytes (an archive member, or a file), read from
/// `source` in three steps, so that neither a claimed size nor a shape is an allocation before
/// it has been checked:
/// 1. the header alone (at most [`MAX_HEADER_LEN`] bytes after the magic), its sizes checked
///    as [`parse_npy_nd`] checks them;
/// 2. the memory the array needs — its stored bytes and its values as f64, twice for a
///    Fortran-ordered array — checked by the [memory guard](crate::memory::check) (a 9 MB
///    archive of zeros may inflate to gigabytes);
/// 3. the rest, read to its end, so that an archive member's CRC-32 is checked (a member that
///    does not match its checksum, or holds more than it claims, is an error).
fn read_member(mut source: impl Read, claimed: u64) -> Result<Vec<u8>, String> {
    let reading = |e: std::io::Error| format!("reading it: {e}");
    // 1. The header.
    let head_len = usize::try_from(claimed.min((12 + MAX_HEADER_LEN) as u64)).unwrap_or(0);
    let mut bytes = Vec::with_capacity(head_len);
    (&mut source)
        .take(head_len as u64)
        .read_to_end(&mut bytes)
        .map_err(reading)?;
    let total =
        usize::try_from(claimed).map_err(|_| format!("claims {claimed} bytes, too many"))?;
    let data_len = check_header(&bytes, total)?;
    // 2. The memory it needs, from the header's shape and dtype.
    let npy = NpyFile::new(&bytes[..]).map_err(|e| format!("not a valid .npy array: {e}"))?;
    let header = npy.header();
    let count = header.shape().iter().fold(1f64, |c, &d| c * d as f64);
    let copies = if header.order() == Order::Fortran {
        2.0
    } else {
        1.0
    };
    let shape = shape_text(header.shape());
    crate::memory::check(
        total as f64 + count * 8.0 * copies + data_len as f64,
        &format!(
            "reading an array of shape {shape} ({})",
            header.dtype().descr().trim_matches('\'')
        ),
    )?;
    // 3. The rest, to its end (where the CRC-32 is checked).
    bytes.reserve_exact(total.saturating_sub(bytes.len()));
    source.read_to_end(&mut bytes).map_err(reading)?;
    if bytes.len() as u64 != claimed {
        return Err(format!(
            "holds {} bytes, not the {claimed} it claims",
            bytes.len()
        ));
    }
    Ok(bytes)
}

fn convert<T>(
    values: std::io::Result<Vec<T>>,
    to_f64: impl Fn(T) -> f64,
) -> std::io::Result<Vec<f64>> {
    values.map(|v| v.into_iter().map(to_f64).collect())
}

fn shape_text(shape: &[u64]) -> String {
    match shape {
        [d] => format!("({d},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(u64::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

fn too_big(shape: &[u64]) -> String {
    format!("shape {} is too large", shape_text(shape))
}

/// Checks the sizes an `.npy` header claims against the bytes there are, before npyz parses it:
/// the header fits in the buffer, is no longer than [`MAX_HEADER_LEN`] and nests no deeper than
/// [`MAX_HEADER_DEPTH`]; its shape's dimensions multiply without overflow and their product
/// fits in the data. `bytes` holds at least the header; `total` is the length of the whole
/// array, header and data. Returns the data's length in bytes.
fn check_header(bytes: &[u8], total: usize) -> Result<usize, String> {
    if bytes.len() < 8 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not an .npy array (no \\x93NUMPY magic)".into());
    }
    let (header_len, start) = match bytes[6] {
        1 => match bytes.get(8..10) {
            Some(b) => (usize::from(u16::from_le_bytes([b[0], b[1]])), 10),
            None => return Err("truncated .npy header".into()),
        },
        2 | 3 => match bytes.get(8..12) {
            Some(b) => (
                usize::try_from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])).unwrap_or(usize::MAX),
                12,
            ),
            None => return Err("truncated .npy header".into()),
        },
        v => return Err(format!("unsupported .npy version {v}.{}", bytes[7])),
    };
    if header_len > MAX_HEADER_LEN {
        return Err(format!(
            "the .npy header claims {header_len} bytes, more than the {MAX_HEADER_LEN} allowed"
        ));
    }
    let text = bytes
        .get(start..start + header_len)
        .filter(|_| start + header_len <= total)
        .ok_or_else(|| {
            format!(
                "truncated .npy header: it claims {header_len} bytes, the array holds {}",
                total - start.min(total)
            )
        })?;
    let data_len = total - start - header_len;
    let text = std::str::from_utf8(text).map_err(|_| "the .npy header is not text")?;
    // The nesting depth, ignoring brackets inside quotes (a crude scan is enough for a bound).
    let (mut depth, mut deepest, mut quote) = (0usize, 0usize, None);
    for c in text.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '\'' | '"') => quote = Some(c),
            (None, '(' | '[' | '{') => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            (None, ')' | ']' | '}') => match depth.checked_sub(1) {
                Some(d) => depth = d,
                None => {
                    return Err(
                        "the .npy header is not a Python literal: unbalanced brackets".into(),
                    )
                }
            },
            _ => {}
        }
    }
    // Unbalanced brackets are no literal, and the literal parser backtracks exponentially in
    // the depth of unclosed ones (a fuzzed 228-byte header took minutes).
    if depth != 0 || quote.is_some() {
        return Err(
            "the .npy header is not a Python literal: unbalanced brackets or quotes".into(),
        );
    }
    if deepest > MAX_HEADER_DEPTH {
        return Err(format!(
            "the .npy header nests {deepest} brackets deep (at most {MAX_HEADER_DEPTH})"
        ));
    }
    let value: py_literal::Value = text
        .trim_end_matches('\n')
        .parse()
        .map_err(|e| format!("the .npy header is not a Python literal: {e}"))?;
    let shape = match value {
        py_literal::Value::Dict(entries) => entries.into_iter().find_map(|(k, v)| {
            matches!(&k, py_literal::Value::String(s) if s == "shape").then_some(v)
        }),
        _ => None,
    };
    // Any dimension and any product of dimensions npyz forms (it multiplies them in either
    // order, skipping none) is at most the product of max(d, 1), which must fit in u64; the
    // element count itself (the plain product) cannot exceed the data's bytes.
    if let Some(py_literal::Value::Tuple(dims) | py_literal::Value::List(dims)) = shape {
        let (mut bound, mut count) = (1u64, 1u64);
        for d in &dims {
            let py_literal::Value::Integer(d) = d else {
                continue; // npyz reports non-integer dimensions
            };
            let d = u64::try_from(d).map_err(|_| format!("bad dimension {d} in the shape"))?;
            bound = bound
                .checked_mul(d.max(1))
                .ok_or_else(|| "the shape's dimensions overflow when multiplied".to_string())?;
            count = count.saturating_mul(d);
        }
        if count > data_len as u64 {
            return Err(format!(
                "truncated data: the shape claims {count} elements, the array holds {data_len} bytes"
            ));
        }
    }
    Ok(data_len)
}

#[cfg(test)]
mod tests;
