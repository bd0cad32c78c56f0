//! The image cut into tiles: the unit of parallel work (rayon steals tiles, not pixels), of ray packets,
//! and of distributed rendering (`--tiles K/N` renders one of N parts of the tile list).

/// A rectangle of pixels `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

/// Side of a tile: 16 × 16 pixels is 256 primary rays, small enough to balance two to sixteen cores on a
/// 512 × 512 frame, large enough that scheduling costs nothing.
pub const TILE: u32 = 16;

/// The tiles of a `width` × `height` image in row-major order (edge tiles are cut to the image).
pub fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut out = Vec::with_capacity((width.div_ceil(TILE) * height.div_ceil(TILE)) as usize);
    for y0 in (0..height).step_by(TILE as usize) {
        for x0 in (0..width).step_by(TILE as usize) {
            out.push(Tile {
                x0,
                y0,
                x1: (x0 + TILE).min(width),
                y1: (y0 + TILE).min(height),
            });
        }
    }
    out
}

/// The indices (into [`tiles`]) of part `k` of `n` of a `width` × `height` image.
///
/// Tiles are dealt in row-major order, each to the part with the least area so far (the lowest such
/// part on a tie): the parts' areas differ by at most one tile's, and each part's tiles are spread over
/// the whole image, so a part is not all sky or all dragon and the parts take about equally long. The
/// deal depends only on the image size and `n`, so every machine computes the same partition.
pub fn part(width: u32, height: u32, k: u32, n: u32) -> Vec<u32> {
    assert!(k < n, "part {k} of {n}");
    let mut area = vec![0u64; n as usize];
    let mut mine = Vec::new();
    for (i, t) in tiles(width, height).iter().enumerate() {
        let (j, _) = area
            .iter()
            .enumerate()
            .min_by_key(|&(j, &a)| (a, j))
            .expect("n > 0");
        area[j] += u64::from(t.x1 - t.x0) * u64::from(t.y1 - t.y0);
        if j == k as usize {
            mine.push(i as u32);
        }
    }
    mine
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_cover_every_tile_once_and_balance_area() {
        for (w, h) in [(1, 1), (17, 33), (100, 75), (800, 600)] {
            let all = tiles(w, h);
            for n in [1, 2, 3, 7, 32] {
                let mut seen = vec![0u8; all.len()];
                let mut areas = Vec::new();
                for k in 0..n {
                    let p = part(w, h, k, n);
                    areas.push(
                        p.iter()
                            .map(|&i| {
                                let t = all[i as usize];
                                (t.x1 - t.x0) * (t.y1 - t.y0)
                            })
                            .sum::<u32>(),
                    );
                    for i in p {
                        seen[i as usize] += 1;
                    }
                }
                assert!(seen.iter().all(|&c| c == 1), "{w}x{h} in {n}");
                let (lo, hi) = (areas.iter().min().unwrap(), areas.iter().max().unwrap());
                assert!(hi - lo <= TILE * TILE, "{w}x{h} in {n}: {areas:?}");
            }
        }
    }

    #[test]
    fn tiles_cover_every_pixel_once() {
        for (w, h) in [(1, 1), (16, 16), (17, 33), (800, 600)] {
            let mut seen = vec![0u8; (w * h) as usize];
            for t in tiles(w, h) {
                for y in t.y0..t.y1 {
                    for x in t.x0..t.x1 {
                        seen[(y * w + x) as usize] += 1;
                    }
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "{w}x{h}");
        }
    }
}
