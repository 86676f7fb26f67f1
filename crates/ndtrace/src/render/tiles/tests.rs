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
