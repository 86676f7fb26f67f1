//! Named qualitative palettes for `material.palette` (`material.color_by`, and the edges with
//! `composite.edge_color_by = "direction"`): matplotlib's own lists, written once into
//! `data/palettes.txt` by `data/make_palettes.py` (not typed by hand) and read at first use.
//! The lists are sRGB; ndtrace shades in linear RGB, so entries are converted on reading.

use super::colormap::srgb_to_linear;
use std::sync::OnceLock;

/// The palette `color_by` uses when a material names none.
pub const DEFAULT_PALETTE: &str = "tab10";

/// A qualitative palette: distinct linear-RGB colours, used in order (and again from the first
/// after the last).
#[derive(Debug, Clone, PartialEq)]
pub struct Palette {
    /// The palette's name (matplotlib's).
    pub name: &'static str,
    /// Its colours, linear RGB.
    pub colors: Vec<[f64; 3]>,
}

impl Palette {
    /// Colour k, counting again from the first after the last.
    pub fn color(&self, k: usize) -> [f64; 3] {
        self.colors[k % self.colors.len()]
    }
}

const DATA: &str = include_str!("../../data/palettes.txt");

fn all() -> &'static [Palette] {
    static PALETTES: OnceLock<Vec<Palette>> = OnceLock::new();
    PALETTES.get_or_init(|| {
        DATA.lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|line| {
                let mut words = line.split_ascii_whitespace();
                let name = words.next().expect("palettes.txt: a line without a name");
                let values: Vec<f64> = words
                    .map(|w| w.parse().expect("palettes.txt: not a number"))
                    .collect();
                assert!(
                    !values.is_empty() && values.len().is_multiple_of(3),
                    "palettes.txt: {name} needs RGB triples"
                );
                Palette {
                    name,
                    colors: values
                        .chunks_exact(3)
                        .map(|c| std::array::from_fn(|k| srgb_to_linear(c[k])))
                        .collect(),
                }
            })
            .collect()
    })
}

/// The names of every palette, in the data file's order.
pub fn names() -> Vec<&'static str> {
    all().iter().map(|p| p.name).collect()
}

/// The palette called `name` (matplotlib's spelling).
pub fn get(name: &str) -> Option<Palette> {
    all().iter().find(|p| p.name == name).cloned()
}
