//! The single-ray kernel: each pixel sample's camera ray traced and shaded on its own by the Whitted
//! integrator (`Whitted::trace`, its walk at one lane), which recurses into its shadow, reflected and
//! refracted rays.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;

use super::{Driver, Single, TilePixels};
use crate::accel::Plain;
use crate::render::sampler::PixelPattern;
use crate::render::setup::Setup;
use crate::render::stats::{Count, RayKind, TileRays};
use crate::render::tiles::Tile;
use crate::render::whitted::PixelSample;

impl Driver for Single {
    fn tile<C: Count>(
        setup: &Setup,
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
                let i = tile.index(x, y);
                buf[i] = Single::pixel_in_pass::<C>(setup, x, y, pass, &mut pattern, |sample| {
                    rays.add::<C>(i, &sample.rays, &sample.steps)
                });
            }
        }
    }
}

impl Single {
    /// The colour of pixel `(x, y)` in pass `pass`: the mean of its samples, traced one by one, each
    /// handed to `done` once traced.
    fn pixel_in_pass<C: Count>(
        setup: &Setup,
        x: u32,
        y: u32,
        pass: u32,
        pattern: &mut PixelPattern,
        mut done: impl FnMut(&PixelSample<C>),
    ) -> Vec3 {
        setup.fill_pattern(x, y, pass, pattern);
        let mut sum = Vec3::ZERO;
        for s in 0..setup.samples() {
            let (at, lens, mut sample) = setup.sample_start::<C>(x, y, pass, s, pattern);
            let ray = setup.camera().sample_ray(at, lens);
            sum += setup.whitted.trace(&ray, 0, RayKind::Camera, &mut sample);
            done(&sample);
        }
        sum / setup.samples() as f32
    }

    /// The colour of pixel `(x, y)` of `setup`'s frame (first pass).
    #[cfg(feature = "kit")]
    pub(in crate::render) fn pixel(setup: &Setup, x: u32, y: u32) -> Vec3 {
        Single::pixel_in_pass::<Plain>(setup, x, y, 1, &mut PixelPattern::default(), |_| {})
    }
}
