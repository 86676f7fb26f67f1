//! Reading 2-D numeric arrays from numpy `.npz` archives (zip files of `.npy` arrays), for mesh
//! objects given by `file`.

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

/// Reads the named 2-D arrays from an `.npz` file.
pub fn read_npz(path: &Path, names: &[&str]) -> Result<Vec<Array2>, String> {
    let file =
        std::fs::File::open(path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    let mut zip = zip::ZipArchive::new(file)
        .map_err(|e| format!("{} is not an .npz (zip) archive: {e}", path.display()))?;
    names
        .iter()
        .map(|name| {
            let mut entry = zip
                .by_name(&format!("{name}.npy"))
                .map_err(|_| format!("{} has no array named \"{name}\"", path.display()))?;
            let mut bytes = Vec::with_capacity(entry.size() as usize);
            entry
                .read_to_end(&mut bytes)
                .map_err(|e| format!("{}: reading \"{name}\": {e}", path.display()))?;
            parse_npy(&bytes).map_err(|e| format!("{}: array \"{name}\": {e}", path.display()))
        })
        .collect()
}

/// Parses a version 1–3 `.npy` buffer holding a 2-D little-endian numeric array.
pub fn parse_npy(bytes: &[u8]) -> Result<Array2, String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not an .npy array".into());
    }
    let (header_len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("unsupported .npy version {v}")),
    };
    let header = bytes
        .get(start..start + header_len)
        .and_then(|h| std::str::from_utf8(h).ok())
        .ok_or("truncated .npy header")?;
    let field = |key: &str| -> Result<&str, String> {
        let at = header
            .find(&format!("'{key}'"))
            .ok_or(format!("header lacks '{key}'"))?;
        Ok(header[at + key.len() + 2..]
            .trim_start()
            .trim_start_matches(':')
            .trim_start())
    };
    let descr = field("descr")?;
    let descr = descr
        .trim_start_matches('\'')
        .split('\'')
        .next()
        .unwrap_or("");
    if field("fortran_order")?.starts_with("True") {
        return Err(
            "Fortran-ordered arrays are not supported (use numpy.ascontiguousarray)".into(),
        );
    }
    let shape_text = field("shape")?;
    let shape_text = &shape_text[1..shape_text.find(')').ok_or("bad shape")?];
    let dims: Vec<usize> = shape_text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| format!("bad shape ({shape_text})"))
        })
        .collect::<Result<_, _>>()?;
    let (rows, cols) = match dims[..] {
        [r, c] => (r, c),
        _ => return Err(format!("expected a 2-D array, got shape ({shape_text})")),
    };
    let data = &bytes[start + header_len..];
    let count = rows * cols;
    let (width, integer): (usize, bool) = match descr {
        "<f8" | "<f4" | "|f1" => (descr[2..].parse().unwrap_or(8), false),
        "<i8" | "<i4" | "<i2" | "|i1" | "<u8" | "<u4" | "<u2" | "|u1" => {
            (descr[2..].parse().unwrap_or(8), true)
        }
        other => {
            return Err(format!(
                "unsupported dtype {other} (use float64 or an integer type)"
            ))
        }
    };
    if data.len() < count * width {
        return Err(format!(
            "truncated data: {} bytes for {count} values of {width} bytes",
            data.len()
        ));
    }
    let conv = |c: &[u8]| -> f64 {
        match descr {
            "<f8" => f64::from_le_bytes(c.try_into().unwrap()),
            "<f4" => f32::from_le_bytes(c.try_into().unwrap()) as f64,
            "<i8" => i64::from_le_bytes(c.try_into().unwrap()) as f64,
            "<i4" => i32::from_le_bytes(c.try_into().unwrap()) as f64,
            "<i2" => i16::from_le_bytes(c.try_into().unwrap()) as f64,
            "|i1" => c[0] as i8 as f64,
            "<u8" => u64::from_le_bytes(c.try_into().unwrap()) as f64,
            "<u4" => u32::from_le_bytes(c.try_into().unwrap()) as f64,
            "<u2" => u16::from_le_bytes(c.try_into().unwrap()) as f64,
            _ => c[0] as f64,
        }
    };
    let values = data[..count * width]
        .chunks_exact(width)
        .map(conv)
        .collect();
    Ok(Array2 {
        shape: (rows, cols),
        data: values,
        integer,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy(descr: &str, shape: &str, payload: &[u8]) -> Vec<u8> {
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend((header.len() as u16).to_le_bytes());
        out.extend(header.as_bytes());
        out.extend(payload);
        out
    }

    #[test]
    fn parses_float_and_integer_arrays() {
        let payload: Vec<u8> = [1.5f64, -2.0, 3.0, 4.25]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let a = parse_npy(&npy("<f8", "(2, 2)", &payload)).unwrap();
        assert_eq!(a.shape, (2, 2));
        assert_eq!(a.data, vec![1.5, -2.0, 3.0, 4.25]);
        let payload: Vec<u8> = [7i32, 8, 9].iter().flat_map(|v| v.to_le_bytes()).collect();
        let a = parse_npy(&npy("<i4", "(1, 3)", &payload)).unwrap();
        assert!(a.integer);
        assert_eq!(a.data, vec![7.0, 8.0, 9.0]);
    }

    #[test]
    fn rejects_bad_arrays() {
        assert!(parse_npy(b"hello world").is_err());
        let e = parse_npy(&npy("<f8", "(3,)", &[0; 24])).unwrap_err();
        assert!(e.contains("2-D"), "{e}");
        let e = parse_npy(&npy("<f8", "(2, 2)", &[0; 8])).unwrap_err();
        assert!(e.contains("truncated"), "{e}");
        let e = parse_npy(&npy("<c16", "(1, 1)", &[0; 16])).unwrap_err();
        assert!(e.contains("dtype"), "{e}");
    }
}
