//! The packet kernel: the camera rays of 4x2 pixels traced as one packet of eight through the
//! integrator's lanes walk ([`Whitted::trace_lanes`] at eight lanes), which traces their hits' shadow
//! rays (one packet per light sample) and their reflected and refracted rays (one packet per kind)
//! recursively to the depth limit: rays that leave neighbouring pixels' hits toward one light, or off
//! one smooth surface, stay about as coherent as the camera rays. The accelerators' packet verbs
//! answer each ray as their single-ray verbs do, and the walk is the one the single-ray kernel runs at
//! one lane: the image is the single-ray kernel's, bit for bit. A tile runs on the lanes of the
//! instruction set chosen for the frame (`Simd::run8`).
//!
//! [`Whitted::trace_lanes`]: crate::render::whitted::Whitted::trace_lanes

use std::marker::PhantomData;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Vec2, Vec3};

use super::{BLOCK_H, BLOCK_W, Driver, Packets, PerRay, TilePixels};
use crate::accel::lanes::{Lanes8, OnLanes8};
use crate::accel::packet::PACKET;
use crate::geometry::ray::Ray;
use crate::render::lanes::{Fx, V3, each};
use crate::render::sampler::PixelPattern;
use crate::render::setup::Setup;
use crate::render::stats::{Count, RayKind, TileRays};
use crate::render::tiles::Tile;
use crate::render::whitted::PixelSample;

/// Each tile, packet by packet (pixels outside the image are inactive lanes): sample `s` of eight
/// pixels at a time, each lane with its pixel's own pattern and random numbers, summed per pixel in
/// sample order as the single-ray kernel sums them. The whole tile, camera rays to film, runs on the
/// lanes of the instruction set chosen for the frame.
impl Driver for Packets {
    fn tile<C: Count>(
        setup: &Setup,
        tile: Tile,
        pass: u32,
        buf: &mut TilePixels,
        rays: &mut TileRays,
        stop: &AtomicBool,
    ) {
        C::run_tile(
            setup.simd(),
            TilePackets::<C> {
                setup,
                tile,
                pass,
                buf,
                rays,
                stop,
                count: PhantomData,
            },
        );
    }
}

/// A tile's work for [`Packets`], for `Simd::run8` to run on the lanes it chose.
struct TilePackets<'r, 'a, C> {
    setup: &'r Setup<'a>,
    tile: Tile,
    pass: u32,
    buf: &'r mut TilePixels,
    rays: &'r mut TileRays,
    stop: &'r AtomicBool,
    count: PhantomData<C>,
}

impl<C: Count> OnLanes8 for TilePackets<'_, '_, C> {
    type Output = ();

    #[inline(always)]
    fn run<L: Lanes8>(self) {
        let TilePackets {
            setup: r,
            tile,
            pass,
            buf,
            rays: traced,
            stop,
            ..
        } = self;
        let mut patterns: PerRay<PixelPattern> = Default::default();
        // Filled in place for each sample of each block (built here once: no copy of the eight).
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET];
        let mut samples: PerRay<PixelSample<C>> =
            std::array::from_fn(|_| r.pixel_sample(pass, r.pixel_key(0, 0), 0, Vec2::ZERO));
        for y0 in (tile.y0..tile.y1).step_by(BLOCK_H as usize) {
            for x0 in (tile.x0..tile.x1).step_by(BLOCK_W as usize) {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                let pixel = |k: usize| (x0 + k as u32 % BLOCK_W, y0 + k as u32 / BLOCK_W);
                let index = |k: usize| {
                    let (x, y) = pixel(k);
                    tile.index(x, y)
                };
                let mut active = 0u32;
                for (k, pattern) in patterns.iter_mut().enumerate() {
                    let (x, y) = pixel(k);
                    if x < tile.x1 && y < tile.y1 {
                        r.fill_pattern(x, y, pass, pattern);
                        active |= 1 << k;
                    }
                }
                let mut sums = V3::<L, PACKET>::zero();
                for s in 0..r.samples() {
                    camera_packet::<C, L>(r, pixel, active, pass, s, &patterns, (&mut rays, &mut samples));
                    let colors = r.whitted.trace_lanes::<C, L, PACKET>(
                        &rays,
                        active,
                        0,
                        RayKind::Camera,
                        &mut samples,
                    );
                    sums = sums + colors;
                    for k in each::<PACKET>(active) {
                        traced.add::<C>(index(k), &samples[k].rays, &samples[k].steps);
                    }
                }
                let means = (sums / Fx::splat(r.samples() as f32)).lanes();
                for k in each::<PACKET>(active) {
                    buf[index(k)] = means[k];
                }
            }
        }
    }
}

/// Sample `s` of the pixels of a packet's `active` lanes (lane `k` at `pixel(k)`, its pattern
/// `patterns[k]`): their camera rays, a pinhole's eight at once ([`RayCamera::rays`]), and what
/// each carries, written in place into the block's `rays` and `samples`.
///
/// [`RayCamera::rays`]: crate::render::camera::RayCamera::rays
// Not inlined: a phase of `profiles/frame.sh`, called once a packet (its body on the frame's
// lanes, `Lanes::call`).
#[inline(never)]
fn camera_packet<'s, C: Count, L: Lanes8>(
    setup: &'s Setup,
    pixel: impl Fn(usize) -> (u32, u32),
    active: u32,
    pass: u32,
    s: u32,
    patterns: &PerRay<PixelPattern>,
    (rays, samples): (&mut PerRay<Ray>, &mut PerRay<PixelSample<'s, C>>),
) {
    L::call(
        #[inline(always)]
        || {
            let mut at = [Vec2::ZERO; PACKET];
            let mut lens = [None; PACKET];
            for (k, sample) in samples.iter_mut().enumerate() {
                *sample = if active >> k & 1 == 0 {
                    setup.pixel_sample(pass, setup.pixel_key(0, 0), 0, Vec2::ZERO)
                } else {
                    let (x, y) = pixel(k);
                    let (point, lens_point, sample) = setup.sample_start(x, y, pass, s, &patterns[k]);
                    (at[k], lens[k]) = (point, lens_point);
                    sample
                };
            }
            let camera = setup.camera();
            *rays = camera.rays::<L, PACKET>(at.map(|p| p.x), at.map(|p| p.y));
            for k in each::<PACKET>(active) {
                if let Some(lens) = lens[k] {
                    rays[k] = camera.lens_ray(at[k].x, at[k].y, lens);
                }
            }
        },
    )
}
