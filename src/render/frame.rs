//! What schedules a frame: its tiles on rayon, one job per tile, each rendered by the chosen kernel
//! (`super::kernel`) into a fixed-size buffer; a pass's tiles are gathered into a [`Film`] or handed to
//! a caller that keeps a part of the frame.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::kernel::{Driver, Packets, Single, TilePixels};
use super::options::Kernel;
use super::setup::Setup;
use super::stats::{Count, RayCounts, TileRays};
use super::tiles::{self, TILE, Tile};
use crate::accel::{Counting, Plain};
use crate::image::Film;

/// Renders pass `pass` (from 1) of the whole frame of `setup`: [`Renderer::render_pass`].
///
/// [`Renderer::render_pass`]: super::Renderer::render_pass
pub(super) fn render_pass(
    setup: &Setup,
    pass: u32,
    on_tile: &(dyn Fn() + Sync),
    stop: &AtomicBool,
) -> Option<(Film, RayCounts)> {
    let (w, h) = setup.size();
    let rendered = render_tiles(setup, pass, &tiles::tiles(w, h), on_tile, stop);
    if !rendered.is_complete() {
        return None;
    }
    let mut film = Film::new(w, h);
    rendered.for_each(|tile, buf| {
        for y in tile.y0..tile.y1 {
            let row = (y * w) as usize;
            let src = ((y - tile.y0) * TILE) as usize;
            let n = (tile.x1 - tile.x0) as usize;
            film.pixels[row + tile.x0 as usize..row + tile.x0 as usize + n]
                .copy_from_slice(&buf[src..src + n]);
        }
    });
    Some((film, rendered.rays()))
}

/// Renders pass `pass` of `setup`'s `tiles` only, in parallel: [`Renderer::render_tiles`].
///
/// [`Renderer::render_tiles`]: super::Renderer::render_tiles
pub(super) fn render_tiles(
    setup: &Setup,
    pass: u32,
    tiles: &[Tile],
    on_tile: &(dyn Fn() + Sync),
    stop: &AtomicBool,
) -> TilePass {
    // Each tile fills a fixed-size buffer and each kernel keeps its per-tile state (sample
    // patterns) from tile to tile, so nothing is allocated per pixel or per ray.
    //
    // One job per tile (`with_max_len(1)`): tiles differ in cost by orders of magnitude (the
    // dragon's glass and metal against empty sky), and rayon's adaptive split otherwise stops
    // splitting after a few levels, leaving a worker folding a long run of expensive tiles that no
    // idle worker can steal (`profiles/README.md`).
    let tiles = tiles
        .par_iter()
        .with_max_len(1)
        .map(|&tile| {
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            let mut buf = [Vec3::ZERO; (TILE * TILE) as usize];
            // Each pixel's rays kept apart where the render counts steps (for heatmaps).
            let mut rays = TileRays::new(setup.counting());
            if setup.counting() {
                tile_with::<Counting>(setup, tile, pass, &mut buf, &mut rays, stop);
            } else {
                tile_with::<Plain>(setup, tile, pass, &mut buf, &mut rays, stop);
            }
            // A kernel stops within its tile once `stop` is set (a tile of many samples a pixel
            // takes long): what it left may be half done, so none of it is kept.
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            on_tile();
            Some((tile, buf, rays))
        })
        .collect();
    TilePass { tiles }
}

/// Renders `tile` for pass `pass` with the frame's kernel into `buf`, its rays counted into `rays`
/// (and their steps where `C` counts them).
fn tile_with<C: Count>(
    setup: &Setup,
    tile: Tile,
    pass: u32,
    buf: &mut TilePixels,
    rays: &mut TileRays,
    stop: &AtomicBool,
) {
    match setup.kernel() {
        Kernel::Single => Single::tile::<C>(setup, tile, pass, buf, rays, stop),
        Kernel::Packet => Packets::tile::<C>(setup, tile, pass, buf, rays, stop),
    }
}

/// A tile's pixels and the rays they took.
type TileDone = (Tile, TilePixels, TileRays);

/// A pass over some tiles as [`Renderer::render_tiles`](super::Renderer::render_tiles) left it: every tile's pixels, or, if it was
/// stopped, those of the tiles finished before the stop (so that an interrupted render can keep them).
#[derive(Debug)]
pub struct TilePass {
    /// Per tile asked for, in order: its pixels, or `None` if the stop skipped it.
    tiles: Vec<Option<TileDone>>,
}

impl TilePass {
    /// Whether every tile was rendered (the pass was not stopped, or stopped after its last tile).
    pub fn is_complete(&self) -> bool {
        self.tiles.iter().all(Option::is_some)
    }

    /// Whether each tile asked for was rendered, in order.
    pub fn finished(&self) -> impl Iterator<Item = bool> + '_ {
        self.tiles.iter().map(Option::is_some)
    }

    /// The rays the finished tiles traced.
    pub fn rays(&self) -> RayCounts {
        let mut rays = RayCounts::default();
        for (_, _, r) in self.tiles.iter().flatten() {
            rays += r.total;
        }
        rays
    }

    /// Hands each finished tile and its pixels (row-major at a stride of [`TILE`]) to `sink`, in the
    /// order the tiles were asked for.
    pub fn for_each(&self, mut sink: impl FnMut(Tile, &[Vec3])) {
        for (tile, buf, _) in self.tiles.iter().flatten() {
            sink(*tile, buf);
        }
    }

    /// Each finished tile and its pixels' rays (row by row, [`TILE`] a row), where the render counted
    /// steps ([`super::Options::count_steps`]).
    pub fn for_each_pixel_rays(&self, mut sink: impl FnMut(Tile, &[RayCounts])) {
        for (tile, _, rays) in self.tiles.iter().flatten() {
            if let Some(p) = &rays.pixels {
                sink(*tile, p);
            }
        }
    }
}
