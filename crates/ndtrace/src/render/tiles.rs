//! How a retina is cut into chunks of parallel work, and the order in which a chunk's cells are
//! traced: neighbouring cells together, so that the rays of a packet and of consecutive
//! packets are close and meet mostly the same BVH nodes and leaves, still in cache.

use crate::accel::PACKET;

/// Cells per unit of parallel work (and of progress reporting and cancellation checks) of a
/// retina whose chunks are not whole strips of rows (see [`chunking`]).
pub(super) const CHUNK_CELLS: usize = 4096;
/// Rows of a strip and columns of a tile of the tracing order (see [`tile_order`]).
pub(super) const TILE_SIDE: usize = 8;

/// Cells per chunk for rows of `row` cells on a retina of `axes` axes, and whether chunks are
/// whole rows traced in [`tile_order`]: with two axes or more, whole strips of [`TILE_SIDE`]
/// rows, as many as make at least [`CHUNK_CELLS`] cells, unless one strip would exceed
/// `4·CHUNK_CELLS` cells; else (one axis, or very long rows) `CHUNK_CELLS` cells in memory
/// order.
pub(super) fn chunking(row: usize, axes: usize) -> (usize, bool) {
    let strip = TILE_SIDE * row;
    if axes >= 2 && strip <= 4 * CHUNK_CELLS {
        (strip * CHUNK_CELLS.div_ceil(strip), true)
    } else {
        (CHUNK_CELLS, false)
    }
}

/// The order in which the cells of a chunk of `rows` whole rows of `row` cells are traced
/// (retinas of at least two axes): by strips of [`TILE_SIDE`] rows (the last may have fewer),
/// each strip by tiles of `TILE_SIDE` columns (the last may have fewer), each tile by pairs of
/// rows, each pair by packets of `PACKET/2` columns × 2 rows. A packet's rays are then closer
/// together than along one row (fewer node visits per packet), and consecutive packets meet
/// mostly the same leaves. Slot s of the order holds `(cell, row, column)`, chunk-relative.
pub(super) fn tile_order(row: usize, rows: usize) -> Vec<(u32, u32, u32)> {
    let w = PACKET / 2;
    let mut order = Vec::with_capacity(row * rows);
    for r0 in (0..rows).step_by(TILE_SIDE) {
        let r_end = (r0 + TILE_SIDE).min(rows);
        for c0 in (0..row).step_by(TILE_SIDE) {
            let c_end = (c0 + TILE_SIDE).min(row);
            for pair in (r0..r_end).step_by(2) {
                for col0 in (c0..c_end).step_by(w) {
                    for r in pair..(pair + 2).min(r_end) {
                        for col in col0..(col0 + w).min(c_end) {
                            order.push(((r * row + col) as u32, r as u32, col as u32));
                        }
                    }
                }
            }
        }
    }
    order
}

#[cfg(test)]
mod tests;
