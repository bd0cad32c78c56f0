//! Progressive rendering: passes of one jittered sample per pixel averaged into a running mean that can
//! be shown or written at any point while it converges.
//!
//! The course writes the mean incrementally, col_n = col_{n−1} + (c_n − col_{n−1}) / n. Here the same
//! mean is kept as a per-pixel `f64` sum of the passes' `f32` colours divided by n when asked for: a sum
//! of a few thousand `f32` values is exact in `f64`'s 53 bits, so the mean does not drift with n as the
//! incremental `f32` form does, and, unlike a mean, sums of passes rendered apart (on other machines, or
//! other days) add up to exactly the sum of all of them. That is what makes a frame split into pass
//! ranges ([`crate::parts`]) merge into the same image as one long render.
//!
//! A `Progressive` covers the whole frame or a subset of its tiles (`--tiles K/N`).

use std::sync::atomic::AtomicBool;

use glam::Vec3;

use super::Renderer;
use super::frame::TilePass;
use super::stats::RayCounts;
use super::tiles::{self, Tile};
use crate::image::Film;

/// Per-pixel sums of the passes so far over a set of tiles.
#[derive(Clone, Debug)]
pub struct Progressive {
    width: u32,
    height: u32,
    /// Indices of the tiles covered, into [`tiles::tiles`] of the frame.
    indices: Vec<u32>,
    tiles: Vec<Tile>,
    /// The tiles' pixels, tile after tile, each tile row-major at its own width.
    sums: Vec<[f64; 3]>,
    passes: u32,
    /// The rays the passes folded in by [`Progressive::render_pass`] traced.
    rays: RayCounts,
    /// Those rays pixel by pixel over the whole frame (row-major), where the passes counted steps
    /// ([`super::Options::count_steps`]; for heatmaps); empty otherwise, and after a join.
    pixel_rays: Vec<RayCounts>,
}

impl Progressive {
    /// No pass yet over the whole `width` × `height` frame.
    pub fn new(width: u32, height: u32) -> Self {
        let n = tiles::tiles(width, height).len() as u32;
        Progressive::for_tiles(width, height, (0..n).collect())
    }

    /// No pass yet over the tiles `indices` (into [`tiles::tiles`]) of a `width` × `height` frame.
    ///
    /// # Panics
    /// If the indices are out of range or not increasing (the callers take them from [`tiles::part`]).
    pub fn for_tiles(width: u32, height: u32, indices: Vec<u32>) -> Self {
        assert!(indices.windows(2).all(|w| w[0] < w[1]), "tile indices increase");
        let all = tiles::tiles(width, height);
        let tiles: Vec<Tile> = indices.iter().map(|&i| all[i as usize]).collect();
        let pixels = tiles.iter().map(|t| area(*t)).sum();
        Progressive {
            width,
            height,
            indices,
            tiles,
            sums: vec![[0.0; 3]; pixels],
            passes: 0,
            rays: RayCounts::default(),
            pixel_rays: Vec::new(),
        }
    }

    /// The sums `sums` of `passes` passes over the tiles `indices` of a `width` × `height` frame, laid
    /// out as [`Progressive::sums`] gives them: an accumulator read back from a `.partial` file, to go on
    /// from.
    ///
    /// # Panics
    /// As [`Progressive::for_tiles`], or if `sums` does not hold one entry per pixel of those tiles.
    pub fn with_sums(width: u32, height: u32, indices: Vec<u32>, sums: Vec<[f64; 3]>, passes: u32) -> Self {
        let mut progressive = Progressive::for_tiles(width, height, indices);
        assert_eq!(sums.len(), progressive.sums.len(), "one sum per pixel");
        progressive.sums = sums;
        progressive.passes = passes;
        progressive
    }

    /// Folds in pass `pass` (from 1) of the renderer, which must render this size. If `stop` was set,
    /// nothing is folded in and the stopped pass is handed back with the tiles it finished (see
    /// [`Renderer::render_tiles`] and [`Progressive::keep_finished`]).
    pub fn render_pass(
        &mut self,
        renderer: &Renderer,
        pass: u32,
        on_tile: &(dyn Fn() + Sync),
        stop: &AtomicBool,
    ) -> Result<RayCounts, TilePass> {
        assert_eq!(
            renderer.size(),
            (self.width, self.height),
            "a pass of another size"
        );
        let rendered = renderer.render_tiles(pass, &self.tiles, on_tile, stop);
        if !rendered.is_complete() {
            return Err(rendered);
        }
        self.fold(&rendered);
        self.passes += 1;
        self.rays += rendered.rays();
        let w = self.width as usize;
        rendered.for_each_pixel_rays(|tile, rays| {
            if self.pixel_rays.is_empty() {
                self.pixel_rays = vec![RayCounts::default(); w * self.height as usize];
            }
            for y in tile.y0..tile.y1 {
                for x in tile.x0..tile.x1 {
                    let r = rays[tile.index(x, y)];
                    self.pixel_rays[y as usize * w + x as usize] += r;
                }
            }
        });
        Ok(rendered.rays())
    }

    /// What a first pass over these tiles that was stopped finished: the tiles done, over that one pass
    /// (no tile and no pass if none was done). A later pass stopped cannot be kept so, as its tiles
    /// would hold one pass more than the others.
    ///
    /// # Panics
    /// If a pass was folded in already, or `stopped` is not a pass over these tiles.
    pub fn keep_finished(self, stopped: &TilePass) -> Progressive {
        assert_eq!(self.passes, 0, "only a first pass can be kept in part");
        assert_eq!(
            stopped.finished().count(),
            self.indices.len(),
            "a pass over these tiles"
        );
        let finished: Vec<u32> = self
            .indices
            .iter()
            .zip(stopped.finished())
            .filter_map(|(&i, done)| done.then_some(i))
            .collect();
        let mut kept = Progressive::for_tiles(self.width, self.height, finished);
        kept.fold(stopped);
        kept.passes = u32::from(!kept.indices.is_empty());
        kept.rays = stopped.rays();
        kept
    }

    /// Adds the tiles `rendered` finished to the sums of these tiles, which must be those tiles in the
    /// same order.
    fn fold(&mut self, rendered: &TilePass) {
        let mut at = 0;
        rendered.for_each(|tile, buf| {
            let w = (tile.x1 - tile.x0) as usize;
            for row in 0..(tile.y1 - tile.y0) as usize {
                let src = &buf[row * tiles::TILE as usize..][..w];
                for (sum, c) in self.sums[at..at + w].iter_mut().zip(src) {
                    for (s, v) in sum.iter_mut().zip(c.to_array()) {
                        *s += f64::from(v);
                    }
                }
                at += w;
            }
        });
    }

    /// The tiles of `self` and `other`, accumulators of one frame over the same passes and disjoint
    /// tiles, as one: a render resumed from the finished tiles of its first pass ([`Progressive::keep_finished`])
    /// joins them to the rest. An accumulator of no pass (nothing finished) adds nothing.
    ///
    /// # Panics
    /// If the frames or the passes differ, or the tiles overlap.
    pub fn join(self, other: Progressive) -> Progressive {
        if other.passes == 0 {
            return self;
        }
        if self.passes == 0 {
            return other;
        }
        assert_eq!(
            (self.size(), self.passes),
            (other.size(), other.passes),
            "parts of one render"
        );
        let mut indices: Vec<u32> = self.indices.iter().chain(&other.indices).copied().collect();
        indices.sort_unstable();
        let mut joined = Progressive::for_tiles(self.width, self.height, indices);
        joined.passes = self.passes;
        joined.rays = self.rays;
        joined.rays += other.rays;
        // Each tile's sums, found by walking both sources in tile order.
        let (mut a, mut b) = (
            self.tile_sums().into_iter().peekable(),
            other.tile_sums().into_iter(),
        );
        let mut at = 0;
        for &i in &joined.indices {
            let source: &mut dyn Iterator<Item = _> = if a.peek().is_some_and(|(j, _)| *j == i) {
                &mut a
            } else {
                &mut b
            };
            let (_, sums) = source.next().expect("every tile from one of the two");
            joined.sums[at..at + sums.len()].copy_from_slice(sums);
            at += sums.len();
        }
        joined
    }

    /// Each tile's index and its pixels' sums.
    fn tile_sums(&self) -> Vec<(u32, &[[f64; 3]])> {
        let mut rest = &self.sums[..];
        self.indices
            .iter()
            .zip(&self.tiles)
            .map(|(&i, &t)| {
                let (sums, tail) = rest.split_at(area(t));
                rest = tail;
                (i, sums)
            })
            .collect()
    }

    /// Passes folded in so far.
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// The rays traced by the passes folded in so far, summed (for `render --stats`: a stopped pass
    /// adds none).
    pub fn rays(&self) -> RayCounts {
        self.rays
    }

    /// The rays of each pixel of the frame (row-major) over the passes folded in, where they counted
    /// steps (zero outside the tiles covered); `None` where they did not.
    pub fn pixel_rays(&self) -> Option<&[RayCounts]> {
        (!self.pixel_rays.is_empty()).then_some(&self.pixel_rays[..])
    }

    /// The frame's size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The indices of the tiles covered.
    pub fn tile_indices(&self) -> &[u32] {
        &self.indices
    }

    /// The per-pixel sums, tile after tile in the order of [`Progressive::tile_indices`].
    pub fn sums(&self) -> &[[f64; 3]] {
        &self.sums
    }

    /// The mean so far: sum / passes per pixel of the tiles covered, black elsewhere (and everywhere
    /// before the first pass).
    pub fn film(&self) -> Film {
        let mut film = Film::new(self.width, self.height);
        let n = f64::from(self.passes.max(1));
        let mut sums = self.sums.iter();
        for t in &self.tiles {
            for y in t.y0..t.y1 {
                for x in t.x0..t.x1 {
                    let s = sums.next().expect("one sum per pixel");
                    film.pixels[(y * self.width + x) as usize] = mean(*s, n);
                }
            }
        }
        film
    }
}

/// A tile's pixel count.
pub(crate) fn area(t: Tile) -> usize {
    (t.x1 - t.x0) as usize * (t.y1 - t.y0) as usize
}

/// The mean colour of `n` samples summing to `sum`; the one rounding to `f32` happens here, so a sum
/// merged from parts gives the same bits as the same sum made in one go.
pub(crate) fn mean(sum: [f64; 3], n: f64) -> Vec3 {
    Vec3::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32)
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicBool;

    use super::*;
    use crate::accel::{Accel, AccelKind, Prims};
    use crate::render::Options;
    use crate::scene::{Camera, Material, Scene};

    #[test]
    fn the_rays_of_the_passes_add_up() {
        let camera = Camera::new(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 45.0, 20, 10);
        let mut scene = Scene::new(camera);
        let m = scene.add_material(Material::default());
        scene.add_sphere(Vec3::ZERO, 1.0, m);
        scene.add_point_light(Vec3::new(0.0, 5.0, 5.0), Vec3::ONE);
        let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh4);
        let options = Options {
            spp: 1,
            ..Options::new(&scene)
        };
        let renderer = Renderer::new(&scene, &accel, options);
        let mut acc = Progressive::new(20, 10);
        let never = AtomicBool::new(false);
        let first = acc.render_pass(&renderer, 1, &|| {}, &never).unwrap();
        let mut both = first;
        both += acc.render_pass(&renderer, 2, &|| {}, &never).unwrap();
        assert_eq!(acc.rays(), both);
        assert_eq!(acc.rays().primary, 2 * 200);
        // One shadow ray per hit that faces the light, none for the hits that face away.
        let r = first;
        assert!(
            r.primary_hits > 0 && r.shadow > 0 && r.shadow <= r.primary_hits,
            "{r:?}"
        );
    }
}
