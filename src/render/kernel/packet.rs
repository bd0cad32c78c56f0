//! The packet kernel, the Whitted integrator's packet twin: eight rays (the camera rays of 4x2 pixels)
//! traced as a packet, and then, packet by packet, the shadow rays of their hits (one
//! packet per light sample) and their reflected and refracted rays (one packet per kind), recursively
//! to the depth limit. Rays that leave neighbouring pixels' hits toward one light, or off one smooth
//! surface, stay about as coherent as the camera rays.
//!
//! Every lane is shaded by [`Whitted::shade_surface`] from the same rays the single-ray path traces
//! ([`ShadowRay::new`], [`Whitted::bounces`]) and the accelerators' packet verbs answer each ray as
//! their single-ray verbs do, so the image is the single-ray path's, bit for bit.

use glam::{Vec2, Vec3};

use super::{BLOCK_H, BLOCK_W, PerRay, TilePixels, coherent};
use crate::accel::counters::{self, Steps};
use crate::accel::packet::{PACKET, bits};
use crate::accel::{Hit, Surface};
use crate::geometry::ray::Ray;
use crate::render::renderer::Renderer;
use crate::render::sampler::PixelPattern;
use crate::render::tiles::{TILE, Tile};
use crate::render::whitted::{
    Bounces, PixelSample, RayCounts, RayKind, ShadowRay, Whitted, charge, take_steps,
};

/// Light samples whose shadow rays are traced as packets (one bit each in a lane's mask); the shading
/// asks for any more ray by ray.
const PACKET_LIGHTS: usize = 64;

impl Whitted<'_> {
    /// The colours seen along the rays of `rays` in `active` after `depth` bounces (others are zero):
    /// the closest hits as a packet, then their shadow rays and secondary rays as packets. Each lane
    /// draws its random numbers from its own sample, in the order the single-ray path draws them (its
    /// bounce here, then its refracted ray's tree, then its reflected ray's).
    pub(super) fn shade_packet(
        &self,
        rays: &PerRay<Ray>,
        active: u8,
        depth: u32,
        kind: RayKind,
        samples: &mut PerRay<PixelSample>,
    ) -> PerRay<Vec3> {
        let mut hits = [Hit::miss(f32::INFINITY); PACKET];
        let hit = if self.counts() {
            closest_counted(self, rays, active, kind, samples, &mut hits)
        } else {
            self.accel.intersect_packet(rays, active, 0.0, &mut hits)
        };
        if depth == 0 {
            for k in bits(hit) {
                samples[k].rays.primary_hits += 1;
            }
        }
        let surfaces: PerRay<Option<Surface>> =
            std::array::from_fn(|k| (hit >> k & 1 == 1).then(|| self.prims.surface(&rays[k], &hits[k])));
        let blocked = self.shadow_packets(&surfaces, samples);

        let bounces: PerRay<Bounces> = std::array::from_fn(|k| match &surfaces[k] {
            Some(s) => self.bounces(&rays[k], s, depth, &mut samples[k]),
            None => Bounces::default(),
        });
        for (sample, b) in samples.iter_mut().zip(&bounces) {
            sample.rays.add_bounces(b);
        }
        // What the refracted (0) and reflected (1) rays see, each kind as one packet.
        let mut seen = [[Vec3::ZERO; PACKET]; 2];
        for (i, seen) in seen.iter_mut().enumerate() {
            let mut next = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET];
            let mut mask = 0u8;
            for (k, b) in bounces.iter().enumerate() {
                if let Some((r, _)) = [b.refracted, b.reflected][i] {
                    (next[k], mask) = (r, mask | 1 << k);
                }
            }
            *seen = self.trace_lanes(&next, mask, depth + 1, RayKind::secondary(i), samples);
        }

        let mut out = [Vec3::ZERO; PACKET];
        for k in bits(active) {
            let (mut extra_shadows, mut steps) = (0, Steps::default());
            out[k] = match &surfaces[k] {
                None => self.shade(&rays[k], &hits[k], depth, &mut samples[k]),
                Some(s) => self.shade_surface(
                    &rays[k],
                    s,
                    &bounces[k],
                    &samples[k].lights,
                    &mut |i, shadow| match i {
                        0..PACKET_LIGHTS => blocked[k] >> i & 1 == 1,
                        _ => {
                            extra_shadows += 1;
                            self.blocked(shadow, &mut steps)
                        }
                    },
                    &mut |i, _| seen[i][k],
                ),
            };
            samples[k].rays.shadow += extra_shadows;
            if self.counts() {
                charge(samples[k].slot, RayKind::Shadow, steps);
            }
        }
        out
    }

    /// [`shade_packet`](Self::shade_packet), or ray by ray when too few lanes are live to share nodes
    /// or their directions point into different octants (rays off a curved mirror, say), which share
    /// few nodes (faster: `profiles/README.md`, tuned constants).
    fn trace_lanes(
        &self,
        rays: &PerRay<Ray>,
        mask: u8,
        depth: u32,
        kind: RayKind,
        samples: &mut PerRay<PixelSample>,
    ) -> PerRay<Vec3> {
        if coherent(bits(mask).map(|k| &rays[k])) {
            return self.shade_packet(rays, mask, depth, kind, samples);
        }
        let mut out = [Vec3::ZERO; PACKET];
        for k in bits(mask) {
            out[k] = self.trace(&rays[k], depth, kind, &mut samples[k]);
        }
        out
    }

    /// Traces the shadow rays of a packet's hits, one packet per light sample (the first
    /// [`PACKET_LIGHTS`]; lane `k` aims at its own sample's light `i`): bit `i` of lane `k` says whether
    /// light sample `i` is blocked from hit `k`.
    fn shadow_packets(
        &self,
        surfaces: &PerRay<Option<Surface>>,
        samples: &mut PerRay<PixelSample>,
    ) -> PerRay<u64> {
        let mut blocked = [0u64; PACKET];
        let count = samples[0].lights.len().min(PACKET_LIGHTS);
        for i in 0..count {
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET];
            let mut t_max = [0.0; PACKET];
            let mut active = 0u8;
            for (k, s) in surfaces.iter().enumerate() {
                let Some(s) = s else { continue };
                let light = samples[k].lights.get(i);
                if let Some(shadow) = ShadowRay::new(s.point, s.geometric, s.shading, &light) {
                    (rays[k], t_max[k]) = (shadow.ray, shadow.distance);
                    active |= 1 << k;
                }
            }
            if active != 0 {
                for k in bits(active) {
                    samples[k].rays.shadow += 1;
                }
                let hit = if self.counts() {
                    blocked_counted(self, &rays, active, &t_max, samples)
                } else {
                    self.accel.occluded_packet(&rays, active, 0.0, &t_max)
                };
                for k in bits(hit) {
                    blocked[k] |= 1 << i;
                }
            }
        }
        blocked
    }
}

/// [`Whitted::shade_packet`]'s closest hits, counted into each lane's sample as rays of `kind`: out
/// of the way of the plain path.
#[cold]
#[inline(never)]
fn closest_counted(
    whitted: &Whitted,
    rays: &PerRay<Ray>,
    active: u8,
    kind: RayKind,
    samples: &PerRay<PixelSample>,
    hits: &mut PerRay<Hit>,
) -> u8 {
    let hit = whitted.accel.counting().intersect_packet(rays, active, 0.0, hits);
    for k in bits(active) {
        charge(samples[k].slot, kind, counters::lane(k));
    }
    hit
}

/// A packet of shadow rays, counted into each lane's sample.
#[cold]
#[inline(never)]
fn blocked_counted(
    whitted: &Whitted,
    rays: &PerRay<Ray>,
    active: u8,
    t_max: &[f32; PACKET],
    samples: &PerRay<PixelSample>,
) -> u8 {
    let hit = whitted.accel.counting().occluded_packet(rays, active, 0.0, t_max);
    for k in bits(active) {
        charge(samples[k].slot, RayKind::Shadow, counters::lane(k));
    }
    hit
}

impl Renderer<'_> {
    /// Shades `tile` for pass `pass`, packet by packet (pixels outside the image are inactive lanes),
    /// into `buf`: sample `s` of eight pixels at a time, each lane with its pixel's own pattern and
    /// random numbers, summed per pixel in sample order as the single-ray path sums them; given
    /// `pixels`, each pixel's rays are counted into its own (row by row, [`TILE`] a row).
    pub(in crate::render) fn tile_packets(
        &self,
        tile: Tile,
        pass: u32,
        buf: &mut TilePixels,
        rays_traced: &mut RayCounts,
        mut pixels: Option<&mut [RayCounts]>,
    ) {
        let mut patterns: PerRay<PixelPattern> = Default::default();
        for y0 in (tile.y0..tile.y1).step_by(BLOCK_H as usize) {
            for x0 in (tile.x0..tile.x1).step_by(BLOCK_W as usize) {
                let pixel = |k: usize| (x0 + k as u32 % BLOCK_W, y0 + k as u32 / BLOCK_W);
                let mut active = 0u8;
                for (k, pattern) in patterns.iter_mut().enumerate() {
                    let (x, y) = pixel(k);
                    if x < tile.x1 && y < tile.y1 {
                        self.fill_pattern(x, y, pass, pattern);
                        active |= 1 << k;
                    }
                }
                let mut sums = [Vec3::ZERO; PACKET];
                for s in 0..self.samples() {
                    let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET];
                    let mut samples: PerRay<PixelSample> = std::array::from_fn(|k| {
                        let (x, y) = pixel(k);
                        if active >> k & 1 == 0 {
                            return self.pixel_sample(pass, 0, 0, Vec2::ZERO);
                        }
                        let (ray, sample) = self.camera_sample(x, y, pass, s, &patterns[k]);
                        rays[k] = ray;
                        PixelSample {
                            slot: k as u32,
                            ..sample
                        }
                    });
                    let colors = self
                        .whitted
                        .shade_packet(&rays, active, 0, RayKind::Camera, &mut samples);
                    for k in bits(active) {
                        sums[k] += colors[k];
                        samples[k].rays.primary += 1;
                        *rays_traced += samples[k].rays;
                        if let Some(p) = pixels.as_deref_mut() {
                            let (x, y) = pixel(k);
                            let steps = take_steps(k as u32);
                            rays_traced.steps += steps;
                            let p = &mut p[((y - tile.y0) * TILE + (x - tile.x0)) as usize];
                            *p += samples[k].rays;
                            p.steps += steps;
                        }
                    }
                }
                for k in bits(active) {
                    let (x, y) = pixel(k);
                    buf[((y - tile.y0) * TILE + (x - tile.x0)) as usize] = sums[k] / self.samples() as f32;
                }
            }
        }
    }
}
