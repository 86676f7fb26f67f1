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
mod tests {
    use super::*;

    #[test]
    fn tile_order_covers_each_cell_once_in_compact_packets() {
        assert_eq!(chunking(37, 1), (CHUNK_CELLS, false));
        assert_eq!(chunking(512, 2), (4096, true));
        assert_eq!(chunking(128, 3), (4096, true));
        assert_eq!(chunking(100, 2), (4800, true));
        assert_eq!(chunking(2048, 2), (16384, true));
        assert_eq!(chunking(3000, 2), (CHUNK_CELLS, false));
        for (row, rows) in [
            (512, 8),
            (128, 32),
            (100, 48),
            (37, 13),
            (8, 6),
            (5, 1),
            (1, 7),
        ] {
            let order = tile_order(row, rows);
            let mut seen = vec![false; row * rows];
            for &(cell, r, c) in &order {
                assert_eq!(cell as usize, r as usize * row + c as usize);
                assert!(
                    !std::mem::replace(&mut seen[cell as usize], true),
                    "{row}×{rows}"
                );
            }
            assert!(seen.iter().all(|&s| s), "{row}×{rows}");
            // Where rows and columns divide evenly, every packet is 4 columns × 2 rows and every
            // 64 slots fill one 8×8 tile.
            if row.is_multiple_of(TILE_SIDE) && rows.is_multiple_of(TILE_SIDE) {
                for p in order.chunks(PACKET) {
                    let (r, c) = (p[0].1, p[0].2);
                    assert!(r % 2 == 0 && c % 4 == 0, "{row}×{rows}");
                    for (k, &(_, rk, ck)) in p.iter().enumerate() {
                        assert_eq!((rk, ck), (r + k as u32 / 4, c + k as u32 % 4));
                    }
                }
                for tile in order.chunks(TILE_SIDE * TILE_SIDE) {
                    let (r, c) = (tile[0].1 / 8 * 8, tile[0].2 / 8 * 8);
                    assert!(tile
                        .iter()
                        .all(|&(_, rk, ck)| rk - r < 8 && ck >= c && ck - c < 8));
                }
            }
        }
    }
}
