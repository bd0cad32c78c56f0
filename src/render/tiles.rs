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

impl Tile {
    /// Where pixel `(x, y)` of the tile lies in a tile's buffer (row-major, [`TILE`] a row).
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        ((y - self.y0) * TILE + (x - self.x0)) as usize
    }
}

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

/// The indices (into [`tiles`]) of part `k` of `n` of a `width` × `height` image, increasing.
///
/// The tiles, taken by decreasing area (the whole 16 × 16 ones in row-major order, then the cut ones
/// of the right column and of the bottom row, the larger kind first, then the corner), are dealt round
/// the parts as cards are: the `j`-th goes to part `j mod n`. Dealt in decreasing order, the parts'
/// areas differ by at most the largest tile's (in each round a part's tile is no smaller than a later
/// part's, and no smaller than its own next one), and each part's tiles are spread over the whole
/// image, so a part is not all sky or all dragon. Part `k` is found from its own positions
/// `k, k + n, ...` alone, so choosing it costs the tiles it holds, not the frame's; the deal depends
/// only on the image size and `n`, so every machine computes the same partition.
pub fn part(width: u32, height: u32, k: u32, n: u32) -> Vec<u32> {
    assert!(k < n, "part {k} of {n}");
    let deal = Deal::new(width, height);
    let mut mine: Vec<u32> = (u64::from(k)..deal.len())
        .step_by(n as usize)
        .map(|j| deal.tile(j))
        .collect();
    mine.sort_unstable();
    mine
}

/// The tiles of an image by decreasing area: `full` columns × rows of whole tiles, then the cut
/// tiles of the right column (`cut_x` pixels wide) and of the bottom row (`cut_y` high), the larger
/// kind first, then the corner.
struct Deal {
    columns: u64,
    full_x: u64,
    full_y: u64,
    cut_x: u32,
    cut_y: u32,
}

impl Deal {
    fn new(width: u32, height: u32) -> Self {
        Deal {
            columns: u64::from(width.div_ceil(TILE)),
            full_x: u64::from(width / TILE),
            full_y: u64::from(height / TILE),
            cut_x: width % TILE,
            cut_y: height % TILE,
        }
    }

    /// The right column's cut tiles, then the bottom row's, or the other way when those are larger:
    /// `(count, first row, first column, step is down a column)` of each run.
    fn edges(&self) -> [(u64, u64, u64, bool); 2] {
        let right = (if self.cut_x > 0 { self.full_y } else { 0 }, 0, self.full_x, true);
        let bottom = (
            if self.cut_y > 0 { self.full_x } else { 0 },
            self.full_y,
            0,
            false,
        );
        // A right-column tile is cut_x x 16, a bottom-row one 16 x cut_y.
        if self.cut_x >= self.cut_y {
            [right, bottom]
        } else {
            [bottom, right]
        }
    }

    fn len(&self) -> u64 {
        let corner = u64::from(self.cut_x > 0 && self.cut_y > 0);
        let [a, b] = self.edges();
        self.full_x * self.full_y + a.0 + b.0 + corner
    }

    /// The index (into [`tiles`]) of the `j`-th tile of the deal.
    fn tile(&self, mut j: u64) -> u32 {
        let full = self.full_x * self.full_y;
        let at = |row: u64, column: u64| (row * self.columns + column) as u32;
        if j < full {
            return at(j / self.full_x, j % self.full_x);
        }
        j -= full;
        for (count, row, column, down) in self.edges() {
            if j < count {
                return if down {
                    at(row + j, column)
                } else {
                    at(row, column + j)
                };
            }
            j -= count;
        }
        at(self.full_y, self.full_x)
    }
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

    /// A part of a frame split in as many parts as it has tiles holds one tile, and is chosen from
    /// its own positions in the deal: 1,048,576 parts of 65536 x 4096 (the most pixels a frame may
    /// have) each take one tile (dealing all tiles to the least-filled part took parts x tiles steps,
    /// 55 s for 32 of them from the command line).
    #[test]
    fn a_part_costs_its_own_tiles_not_the_frames() {
        let (w, h) = (65_536, 4_096);
        let n = tiles(w, h).len() as u32;
        assert_eq!(n, 1 << 20);
        let mut seen = std::collections::HashSet::new();
        for k in [0, 1, 4_095, 4_096, n / 2, n - 2, n - 1] {
            let p = part(w, h, k, n);
            assert_eq!(p.len(), 1, "part {k}");
            assert!(seen.insert(p[0]), "part {k}");
        }
        assert_eq!(part(w, h, 0, n), [0]);
        assert_eq!(part(w, h, 4_097, n), [4_097]);
        // Beyond the tiles there is nothing left to deal.
        assert_eq!(part(w, h, n, n + 1), Vec::<u32>::new());
    }

    /// Cut tiles come after the whole ones, the larger cut kind first: on a 40 x 20 image (whole
    /// tiles 0 and 1; the right column's 8 x 16 tile 2; the bottom row's 16 x 4 tiles 3 and 4; the
    /// 8 x 4 corner 5) are dealt in the order 0 1 2 3 4 5, round three parts.
    #[test]
    fn the_deal_takes_tiles_by_decreasing_area() {
        assert_eq!(part(40, 20, 0, 3), [0, 3]);
        assert_eq!(part(40, 20, 1, 3), [1, 4]);
        assert_eq!(part(40, 20, 2, 3), [2, 5]);
        // 20 x 40 (whole tiles 0 and 2; the right column's 4 x 16 tiles 1 and 3; the bottom row's
        // 16 x 8 tile 4; the corner 5): the bottom row's larger tile comes before the right column's.
        assert_eq!(part(20, 40, 0, 6), [0]);
        assert_eq!(part(20, 40, 1, 6), [2]);
        assert_eq!(part(20, 40, 2, 6), [4]);
        assert_eq!(part(20, 40, 3, 6), [1]);
        assert_eq!(part(20, 40, 4, 6), [3]);
        assert_eq!(part(20, 40, 5, 6), [5]);
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
