//! Pictures of 2D arrays: the slice montage of
//! [`CompositeMode::Slices`](super::CompositeMode::Slices), the 2D retina (N = 3) and the 1D
//! strip (N = 2).

use super::{over, CompositeOptions, Volume};
use rayon::prelude::*;

/// Colour of the separators of the slice montage.
pub const SEPARATOR: [f32; 3] = [0.35, 0.35, 0.35];

/// Where the slice montage puts its tiles: a grid of `cols × rows` tiles of `tile_w × tile_h`
/// pixels separated (and framed) by `gap`-pixel separators, centred in the picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Tiles per row of the montage: ⌈√count⌉.
    pub cols: usize,
    /// Rows of tiles: ⌈count / cols⌉.
    pub rows: usize,
    /// Width of a tile in pixels.
    pub tile_w: usize,
    /// Height of a tile in pixels.
    pub tile_h: usize,
    /// Separator width in pixels.
    pub gap: usize,
    /// Pixel coordinates of the montage's top-left corner (its outer separator).
    pub origin: (usize, usize),
}

impl Layout {
    /// Top-left pixel of tile `k`: tile k sits in montage row k / cols, column k % cols.
    pub fn tile_origin(&self, k: usize) -> (usize, usize) {
        let (r, c) = (k / self.cols, k % self.cols);
        (
            self.origin.0 + self.gap + c * (self.tile_w + self.gap),
            self.origin.1 + self.gap + r * (self.tile_h + self.gap),
        )
    }
}

/// The montage layout for `count` tiles of `tw × th` cells in a `w × h` picture with
/// separators of `gap` pixels (the slice montage uses gap 1; a 2D retina uses 1 tile and gap 0).
///
/// The cell scale s = min((w − (cols+1)·gap) / (cols·tw), (h − (rows+1)·gap) / (rows·th)) is
/// rounded down to a whole number when ≥ 1 (each cell an s × s block of pixels); tiles are
/// max(1, ⌊tw·s⌋) × max(1, ⌊th·s⌋) pixels, and the montage is centred (offsets rounded down).
/// A pixel of a tile shows the cell under its centre (nearest).
pub fn slice_layout(w: usize, h: usize, count: usize, tw: usize, th: usize, gap: usize) -> Layout {
    let cols = ((count as f64).sqrt().ceil() as usize).max(1);
    let cols = if (cols - 1) * (cols - 1) >= count && cols > 1 {
        cols - 1
    } else {
        cols
    };
    let rows = count.div_ceil(cols).max(1);
    let sw = w.saturating_sub((cols + 1) * gap) as f64 / (cols * tw) as f64;
    let sh = h.saturating_sub((rows + 1) * gap) as f64 / (rows * th) as f64;
    let mut s = sw.min(sh);
    if s >= 1.0 {
        s = s.floor();
    }
    let tile_w = ((tw as f64 * s).floor() as usize).max(1);
    let tile_h = ((th as f64 * s).floor() as usize).max(1);
    let mw = cols * tile_w + (cols + 1) * gap;
    let mh = rows * tile_h + (rows + 1) * gap;
    Layout {
        cols,
        rows,
        tile_w,
        tile_h,
        gap,
        origin: (w.saturating_sub(mw) / 2, h.saturating_sub(mh) / 2),
    }
}

/// The 3×5 digits of the slice labels, one row per entry, bit 2 = left column.
const DIGITS: [[u8; 5]; 10] = [
    [0b111, 0b101, 0b101, 0b101, 0b111],
    [0b010, 0b110, 0b010, 0b010, 0b111],
    [0b111, 0b001, 0b111, 0b100, 0b111],
    [0b111, 0b001, 0b111, 0b001, 0b111],
    [0b101, 0b101, 0b111, 0b001, 0b001],
    [0b111, 0b100, 0b111, 0b001, 0b111],
    [0b111, 0b100, 0b111, 0b101, 0b111],
    [0b111, 0b001, 0b001, 0b001, 0b001],
    [0b111, 0b101, 0b111, 0b101, 0b111],
    [0b111, 0b101, 0b111, 0b001, 0b111],
];

/// The label of tile `k` at scale `ls`: is pixel (x, y) of the tile (relative to its top-left
/// corner) part of the label's box, and if so is it ink? The box is a dark plate one font
/// pixel larger than the digits on every side.
fn label_pixel(k: usize, ls: usize, x: usize, y: usize) -> Option<bool> {
    let text = k.to_string();
    let (bw, bh) = ((text.len() * 4 + 1) * ls, 7 * ls);
    if x >= bw || y >= bh {
        return None;
    }
    let (fx, fy) = (x / ls, y / ls);
    if fx == 0 || fy == 0 || fy > 5 {
        return Some(false);
    }
    let (ch, col) = ((fx - 1) / 4, (fx - 1) % 4);
    if col == 3 {
        return Some(false);
    }
    let digit = (text.as_bytes()[ch] - b'0') as usize;
    Some(DIGITS[digit][fy - 1] >> (2 - col) & 1 == 1)
}

/// What [`render_tiles`] draws: `count` tiles of `tw × th` cells from `cells`, separated by
/// `gap`-pixel separators, with or without labels.
pub(super) struct Tiles<'a> {
    pub(super) cells: &'a [[f32; 4]],
    pub(super) tw: usize,
    pub(super) th: usize,
    pub(super) count: usize,
    pub(super) gap: usize,
    pub(super) labels: bool,
}

/// Draws tiles: tile k's pixel shows the cell `at(k, x, y)` of the cell (x, y) ∈ [0, tw) ×
/// [0, th) under its centre.
pub(super) fn render_tiles(
    w: usize,
    h: usize,
    t: &Tiles<'_>,
    bg: [f32; 3],
    at: impl Fn(usize, usize, usize) -> usize + Sync,
) -> Vec<f32> {
    let Tiles {
        cells,
        tw,
        th,
        count,
        gap,
        labels,
    } = *t;
    let lay = slice_layout(w, h, count, tw, th, gap);
    let (mw, mh) = (
        lay.cols * lay.tile_w + (lay.cols + 1) * gap,
        lay.rows * lay.tile_h + (lay.rows + 1) * gap,
    );
    let ls = (lay.tile_h / 40).clamp(1, 4);
    let mut img = vec![0f32; w * h * 4];
    img.par_chunks_mut(w * 4).enumerate().for_each(|(py, row)| {
        for px in 0..w {
            let mut v = [bg[0], bg[1], bg[2], 0.0];
            let (ox, oy) = lay.origin;
            if px >= ox && py >= oy && px < ox + mw && py < oy + mh {
                let (mx, my) = (px - ox, py - oy);
                let pitch_x = lay.tile_w + gap;
                let pitch_y = lay.tile_h + gap;
                let (c, xin) = (
                    mx.saturating_sub(gap) / pitch_x,
                    mx.saturating_sub(gap) % pitch_x,
                );
                let (r, yin) = (
                    my.saturating_sub(gap) / pitch_y,
                    my.saturating_sub(gap) % pitch_y,
                );
                let on_sep = mx < gap || my < gap || xin >= lay.tile_w || yin >= lay.tile_h;
                let k = r * lay.cols + c;
                if on_sep {
                    v = [SEPARATOR[0], SEPARATOR[1], SEPARATOR[2], 1.0];
                } else if k < count {
                    let label = if labels
                        && lay.tile_w >= (k.to_string().len() * 4 + 3) * ls
                        && lay.tile_h >= 9 * ls
                    {
                        label_pixel(k, ls, xin, yin)
                    } else {
                        None
                    };
                    v = match label {
                        Some(true) => [1.0, 1.0, 1.0, 1.0],
                        Some(false) => [0.0, 0.0, 0.0, 1.0],
                        None => {
                            let cx = (((xin as f64 + 0.5) * tw as f64 / lay.tile_w as f64)
                                as usize)
                                .min(tw - 1);
                            let cy = (((yin as f64 + 0.5) * th as f64 / lay.tile_h as f64)
                                as usize)
                                .min(th - 1);
                            over(cells[at(k, cx, cy)], bg)
                        }
                    };
                }
            }
            row[px * 4..px * 4 + 4].copy_from_slice(&v);
        }
    });
    img
}

/// The slice montage of a 3D volume. Tile of slice k, at pixel (x, y) of its cell grid:
/// axis 0 → volume[k, y, x] (rows, columns); axis 1 → volume[y, k, x] (slices down, columns
/// across); axis 2 → volume[x, y, k] (rows down, slices across). So image rows stay rows and
/// columns stay columns whenever they remain.
pub(super) fn render_slices(vol: &Volume, o: &CompositeOptions, bg: [f32; 3]) -> Vec<f32> {
    let [nx, ny, nz] = [vol.shape[2], vol.shape[1], vol.shape[0]];
    let (count, tw, th) = match o.axis {
        0 => (nz, nx, ny),
        1 => (ny, nx, nz),
        _ => (nx, nz, ny),
    };
    let idx = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
    let axis = o.axis;
    let at = move |k: usize, x: usize, y: usize| match axis {
        0 => idx(x, y, k),
        1 => idx(x, k, y),
        _ => idx(k, y, x),
    };
    let (w, h) = o.size;
    let tiles = Tiles {
        cells: &vol.cells,
        tw,
        th,
        count,
        gap: 1,
        labels: o.labels,
    };
    render_tiles(w, h, &tiles, bg, at)
}

/// A 1D retina as a strip: full width, `strip_height` rows (clipped to h) centred vertically.
pub(super) fn render_strip(
    cells: &[[f32; 4]],
    w: usize,
    h: usize,
    strip_height: usize,
    bg: [f32; 3],
) -> Vec<f32> {
    let sh = strip_height.min(h);
    let top = (h - sh) / 2;
    let r = cells.len();
    let mut img = vec![0f32; w * h * 4];
    img.par_chunks_mut(w * 4).enumerate().for_each(|(py, row)| {
        for px in 0..w {
            let v = if py >= top && py < top + sh {
                let i = (((px as f64 + 0.5) * r as f64 / w as f64) as usize).min(r - 1);
                over(cells[i], bg)
            } else {
                [bg[0], bg[1], bg[2], 0.0]
            };
            row[px * 4..px * 4 + 4].copy_from_slice(&v);
        }
    });
    img
}
