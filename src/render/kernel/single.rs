//! The single-ray kernel: each pixel sample's camera ray traced and shaded on its own by the Whitted
//! integrator ([`Whitted::trace`](super::super::whitted::Whitted::trace)), which recurses into its
//! shadow, reflected and refracted rays.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;

use super::TilePixels;
use crate::render::renderer::Renderer;
use crate::render::sampler::PixelPattern;
use crate::render::tiles::{TILE, Tile};
use crate::render::whitted::{RayCounts, RayKind, take_steps};

impl Renderer<'_> {
    /// Shades `tile` for pass `pass` pixel by pixel into `buf`, counting the rays into `rays` and,
    /// given `pixels`, each pixel's into its own (row by row, [`TILE`] a row); leaves the tile half
    /// done once `stop` is set.
    pub(in crate::render) fn tile_single(
        &self,
        tile: Tile,
        pass: u32,
        buf: &mut TilePixels,
        rays: &mut RayCounts,
        mut pixels: Option<&mut [RayCounts]>,
        stop: &AtomicBool,
    ) {
        let mut pattern = PixelPattern::default();
        for y in tile.y0..tile.y1 {
            for x in tile.x0..tile.x1 {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                let i = ((y - tile.y0) * TILE + (x - tile.x0)) as usize;
                // A counting render keeps each pixel's rays apart; the others count into the tile's.
                buf[i] = match pixels.as_deref_mut() {
                    Some(p) => {
                        let colour = self.pixel_in_pass(x, y, pass, &mut pattern, &mut p[i]);
                        *rays += p[i];
                        colour
                    }
                    None => self.pixel_in_pass(x, y, pass, &mut pattern, rays),
                };
            }
        }
    }

    /// The colour of pixel `(x, y)` in pass `pass`: the mean of its samples, traced one by one; the rays
    /// are counted into `rays`.
    fn pixel_in_pass(
        &self,
        x: u32,
        y: u32,
        pass: u32,
        pattern: &mut PixelPattern,
        rays: &mut RayCounts,
    ) -> Vec3 {
        self.fill_pattern(x, y, pass, pattern);
        let mut sum = Vec3::ZERO;
        for s in 0..self.samples() {
            let (at, lens, mut sample) = self.sample_start(x, y, pass, s, pattern);
            let ray = self.camera().sample_ray(at, lens);
            sum += self.whitted.trace(&ray, 0, RayKind::Camera, &mut sample);
            sample.rays.primary += 1;
            *rays += sample.rays;
            if self.whitted.counts() {
                rays.steps += take_steps(sample.slot);
            }
        }
        sum / self.samples() as f32
    }

    /// The colour of pixel `(x, y)` (first pass).
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        self.pixel_in_pass(x, y, 1, &mut PixelPattern::default(), &mut RayCounts::default())
    }
}
