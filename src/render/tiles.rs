//! The image cut into tiles: the unit of parallel work (rayon steals tiles, not pixels) and, later, of
//! ray packets and of distributed rendering.

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

#[cfg(test)]
mod tests {
    use super::*;

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
