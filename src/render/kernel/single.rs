//! The single-ray kernel: each pixel sample's camera ray traced and shaded on its own by the Whitted
//! integrator ([`Whitted::trace`](super::super::whitted::Whitted::trace)), which recurses into its
//! shadow, reflected and refracted rays.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;

use super::TilePixels;
use crate::accel::Plain;
use crate::render::renderer::Renderer;
use crate::render::sampler::PixelPattern;
use crate::render::stats::{Count, RayKind, TileRays};
use crate::render::tiles::{TILE, Tile};
use crate::render::whitted::PixelSample;

impl Renderer<'_> {
    /// Shades `tile` for pass `pass` pixel by pixel into `buf`, counting the rays into `rays`; leaves
    /// the tile half done once `stop` is set.
    pub(in crate::render) fn tile_single<C: Count>(
        &self,
        tile: Tile,
        pass: u32,
        buf: &mut TilePixels,
        rays: &mut TileRays,
        stop: &AtomicBool,
    ) {
        let mut pattern = PixelPattern::default();
        for y in tile.y0..tile.y1 {
            for x in tile.x0..tile.x1 {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                let i = ((y - tile.y0) * TILE + (x - tile.x0)) as usize;
                buf[i] = self.pixel_in_pass::<C>(x, y, pass, &mut pattern, |sample| {
                    rays.add::<C>(i, &sample.rays, &sample.steps)
                });
            }
        }
    }

    /// The colour of pixel `(x, y)` in pass `pass`: the mean of its samples, traced one by one, each
    /// handed to `done` once traced.
    fn pixel_in_pass<C: Count>(
        &self,
        x: u32,
        y: u32,
        pass: u32,
        pattern: &mut PixelPattern,
        mut done: impl FnMut(&PixelSample<C>),
    ) -> Vec3 {
        self.fill_pattern(x, y, pass, pattern);
        let mut sum = Vec3::ZERO;
        for s in 0..self.samples() {
            let (at, lens, mut sample) = self.sample_start::<C>(x, y, pass, s, pattern);
            let ray = self.camera().sample_ray(at, lens);
            sum += self.whitted.trace(&ray, 0, RayKind::Camera, &mut sample);
            done(&sample);
        }
        sum / self.samples() as f32
    }

    /// The colour of pixel `(x, y)` (first pass).
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        self.pixel_in_pass::<Plain>(x, y, 1, &mut PixelPattern::default(), |_| {})
    }
}
