//! Named colormaps for `material.colormap`: matplotlib's own tables, written once into
//! `data/colormaps.txt` by `data/make_colormaps.py` (not typed by hand) and read at first use.
//! The tables are sRGB; ndtrace shades in linear RGB, so entries are converted on reading and a
//! picture written as sRGB shows matplotlib's colours (times the lighting).

use std::sync::OnceLock;

/// A colormap: 256 linear-RGB entries, looked up with linear interpolation.
#[derive(Debug, Clone, PartialEq)]
pub struct Colormap {
    /// The map's name (matplotlib's).
    pub name: &'static str,
    /// Linear RGB at k / 255, k = 0 … 255.
    pub table: Vec<[f64; 3]>,
}

impl Colormap {
    /// The colour at t ∈ [0, 1] (clamped; NaN gives the first entry).
    pub fn at(&self, t: f64) -> [f64; 3] {
        let n = self.table.len() - 1;
        let u = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * n as f64;
        let k = (u.floor() as usize).min(n - 1);
        let f = u - k as f64;
        let (a, b) = (&self.table[k], &self.table[k + 1]);
        std::array::from_fn(|c| a[c] + f * (b[c] - a[c]))
    }
}

const DATA: &str = include_str!("../../data/colormaps.txt");

/// sRGB → linear transfer function.
pub(crate) fn srgb_to_linear(x: f64) -> f64 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

fn all() -> &'static [Colormap] {
    static MAPS: OnceLock<Vec<Colormap>> = OnceLock::new();
    MAPS.get_or_init(|| {
        DATA.lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|line| {
                let mut words = line.split_ascii_whitespace();
                let name = words.next().expect("colormaps.txt: a line without a name");
                let values: Vec<f64> = words
                    .map(|w| w.parse().expect("colormaps.txt: not a number"))
                    .collect();
                assert_eq!(
                    values.len(),
                    768,
                    "colormaps.txt: {name} needs 256 RGB triples"
                );
                Colormap {
                    name,
                    table: values
                        .chunks_exact(3)
                        .map(|c| std::array::from_fn(|k| srgb_to_linear(c[k])))
                        .collect(),
                }
            })
            .collect()
    })
}

/// The names of every colormap, in the data file's order.
pub fn names() -> Vec<&'static str> {
    all().iter().map(|m| m.name).collect()
}

/// The colormap called `name` (matplotlib's spelling; a `_r` suffix reverses it).
pub fn get(name: &str) -> Option<Colormap> {
    let (base, reversed) = match name.strip_suffix("_r") {
        Some(b) => (b, true),
        None => (name, false),
    };
    let m = all().iter().find(|m| m.name == base)?;
    let mut m = m.clone();
    if reversed {
        m.table.reverse();
    }
    Some(m)
}
