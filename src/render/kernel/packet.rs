//! The packet kernel, the Whitted integrator's packet twin: eight rays (the camera rays of 4x2 pixels)
//! traced as a packet, and then, packet by packet, the shadow rays of their hits (one
//! packet per light sample) and their reflected and refracted rays (one packet per kind), recursively
//! to the depth limit. Rays that leave neighbouring pixels' hits toward one light, or off one smooth
//! surface, stay about as coherent as the camera rays.
//!
//! The camera rays, the hit points, the local shading (shadow-ray set-up and Blinn-Phong, light
//! sample by light sample), smooth materials' refracted and reflected rays (Snell, Schlick's Fresnel
//! split) and the sum of what they see run in lanes (`shade.rs`, `render/lanes.rs`), with the
//! single-ray path's operations in its order; a fuzzy mirror's rays (its random draws), and a
//! transmitter's once its sample has spent the split budget, come from [`Whitted::bounces`] lane by
//! lane, and Beer's absorption from [`Whitted::absorbed`], as on the single-ray path. The
//! accelerators' packet verbs answer each ray as their single-ray verbs do: the image is the
//! single-ray path's, bit for bit.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Vec2, Vec3};

use super::shade::{HitLanes, light};
use super::{BLOCK_H, BLOCK_W, PerRay, TilePixels, coherent};
use crate::accel::counters;
use crate::accel::lanes::{Lanes8, OnLanes8};
use crate::accel::packet::PACKET;
use crate::accel::{Counting, Hit, Plain, Tally};
use crate::geometry::ray::Ray;
use crate::render::lanes::{Fx, V3, each};
use crate::render::renderer::Renderer;
use crate::render::sampler::PixelPattern;
use crate::render::tiles::{TILE, Tile};
use crate::render::whitted::{
    Bounces, PixelSample, RayCounts, RayKind, Whitted, charge, out_of_line, take_steps,
};

impl Whitted<'_> {
    /// The colours seen along the rays of `rays` in `active` after `depth` bounces (others are zero):
    /// the closest hits as a packet, then their shadow rays and secondary rays as packets. Each lane
    /// draws its random numbers from its own sample, in the order the single-ray path draws them (its
    /// bounce here, then its refracted ray's tree, then its reflected ray's).
    // Not inlined (it recurses): its body on the frame's lanes (`Lanes::call`).
    #[inline(never)]
    fn shade_packet<L: Lanes8>(
        &self,
        rays: &PerRay<Ray>,
        active: u32,
        depth: u32,
        kind: RayKind,
        samples: &mut PerRay<PixelSample>,
    ) -> V3<L, PACKET> {
        L::call(
            #[inline(always)]
            || {
                let mut hits = [Hit::miss(f32::INFINITY); PACKET];
                let hit = if self.counts() {
                    out_of_line(|| closest_tallied::<Counting>(self, rays, active, kind, samples, &mut hits))
                } else {
                    closest_tallied::<Plain>(self, rays, active, kind, samples, &mut hits)
                };
                if depth == 0 {
                    for k in each(hit) {
                        samples[k].rays.primary_hits += 1;
                    }
                }
                let mut out = [Vec3::ZERO; PACKET];
                for k in each(active & !hit) {
                    // A miss: what the ray sees leaving the scene.
                    out[k] = self.shade(&rays[k], &hits[k], depth, &mut samples[k]);
                }
                let out = V3::from_lanes(&out);
                let Some(h) = HitLanes::<L, PACKET>::of_hits(&self.prims, rays, &hits, hit) else {
                    return out;
                };
                let mut color = self.local_packet(&h, samples);
                if depth < self.max_depth() {
                    // Smooth materials' rays are set up in lanes; a fuzzy mirror's (its draws) and those of
                    // a transmitter hit by a sample that spent its split budget lane by lane, as on the
                    // single-ray path.
                    let spent = each(hit & h.transmits())
                        .fold(0, |m, k| m | u32::from(samples[k].rays.budget_spent()) << k);
                    let alone = h.materials_where(|m| self.rough(m)) | spent;
                    let lanes = h.bounces(self.prims.scene, hit & !alone, self.spd());
                    let bounces = (alone != 0).then(|| {
                        std::array::from_fn::<_, PACKET, _>(|k| match alone >> k & 1 {
                            0 => Bounces::default(),
                            _ => self.bounces(&rays[k], &h.surface(k), depth, &mut samples[k]),
                        })
                    });
                    for k in each(hit) {
                        let r = &mut samples[k].rays;
                        r.refracted += u64::from(lanes[0].lanes >> k & 1);
                        r.reflected += u64::from(lanes[1].lanes >> k & 1);
                    }
                    for (k, b) in bounces.iter().flatten().enumerate() {
                        samples[k].rays.add_bounces(b);
                    }
                    // What the refracted (0) and reflected (1) rays see, each kind as one packet (the lanes
                    // of `mask`; the others keep whatever ray they held, never traced), added in that order.
                    let mut next = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET];
                    for (i, spawned) in lanes.iter().enumerate() {
                        let (mut mask, mut weight) = (spawned.lanes, spawned.weight.to_array());
                        let (origins, dirs) = (spawned.origin.lanes(), spawned.dir.lanes());
                        for k in each(mask) {
                            next[k] = Ray::new(origins[k], dirs[k]);
                        }
                        for (k, b) in bounces.iter().flatten().enumerate() {
                            if let Some((r, w)) = if i == 0 { b.refracted } else { b.reflected } {
                                (next[k], weight[k], mask) = (r, w, mask | 1 << k);
                            }
                        }
                        if mask != 0 {
                            let seen =
                                self.trace_lanes(&next, mask, depth + 1, RayKind::secondary(i), samples);
                            color = V3::blend(mask, color + seen * Fx::from(weight), color);
                        }
                    }
                }
                if h.inside() != 0 {
                    let mut lanes = color.lanes();
                    for k in each(h.inside()) {
                        lanes[k] = self.absorbed(lanes[k], &h.surface(k));
                    }
                    color = V3::from_lanes(&lanes);
                }
                V3::blend(hit, color, out)
            },
        )
    }

    /// [`shade_packet`](Self::shade_packet), or ray by ray when too few lanes are live to share nodes
    /// or their directions point into different octants (rays off a curved mirror, say), which share
    /// few nodes (faster: `profiles/README.md`, tuned constants).
    #[inline(always)]
    fn trace_lanes<L: Lanes8>(
        &self,
        rays: &PerRay<Ray>,
        mask: u32,
        depth: u32,
        kind: RayKind,
        samples: &mut PerRay<PixelSample>,
    ) -> V3<L, PACKET> {
        if coherent(each(mask).map(|k| &rays[k])) {
            return self.shade_packet(rays, mask, depth, kind, samples);
        }
        let mut out = [Vec3::ZERO; PACKET];
        for k in each(mask) {
            out[k] = self.trace(&rays[k], depth, kind, &mut samples[k]);
        }
        V3::from_lanes(&out)
    }

    /// The local colour of the packet's hits `hits`: light sample by light sample, the
    /// eight shadow rays set up in lanes and traced as one packet (lane `k` aims at its own pixel
    /// sample's light), and the Blinn-Phong sum in lanes.
    // Not inlined: a phase of `profiles/frame.sh`, called once a packet (its body on the frame's
    // lanes, `Lanes::call`).
    #[inline(never)]
    fn local_packet<L: Lanes8>(
        &self,
        hits: &HitLanes<L, PACKET>,
        samples: &mut PerRay<PixelSample>,
    ) -> V3<L, PACKET> {
        L::call(
            #[inline(always)]
            || {
                let lights = samples.each_ref().map(|s| s.lights);
                let mut color = V3::zero();
                for i in 0..lights[0].len() {
                    let (at, light) = light(i, &lights);
                    let toward = hits.toward(at);
                    let lit = toward.lit;
                    if lit == 0 {
                        continue;
                    }
                    for k in each(lit) {
                        samples[k].rays.shadow += 1;
                    }
                    let (shadows, distance) = hits.shadow_rays(&toward);
                    let blocked = if self.counts() {
                        out_of_line(|| blocked_tallied::<Counting>(self, &shadows, lit, &distance, samples))
                    } else {
                        blocked_tallied::<Plain>(self, &shadows, lit, &distance, samples)
                    };
                    hits.add_light(&mut color, &toward, lit & !blocked, light);
                }
                color
            },
        )
    }
}

/// [`Whitted::shade_packet`]'s closest hits through the verbs of `T`, counted into each lane's sample
/// as rays of `kind` when `T` counts.
#[inline(always)]
fn closest_tallied<T: Tally>(
    whitted: &Whitted,
    rays: &PerRay<Ray>,
    active: u32,
    kind: RayKind,
    samples: &PerRay<PixelSample>,
    hits: &mut PerRay<Hit>,
) -> u32 {
    let hit = whitted
        .accel
        .verbs::<T>()
        .intersect_packet(rays, active as u8, 0.0, hits);
    if T::COUNTS {
        for k in each(active) {
            charge(samples[k].slot, kind, counters::lane(k));
        }
    }
    u32::from(hit)
}

/// Which of a packet of shadow rays are blocked, through the verbs of `T`, counted into each lane's
/// sample when `T` counts.
#[inline(always)]
fn blocked_tallied<T: Tally>(
    whitted: &Whitted,
    rays: &PerRay<Ray>,
    active: u32,
    t_max: &[f32; PACKET],
    samples: &PerRay<PixelSample>,
) -> u32 {
    let hit = whitted
        .accel
        .verbs::<T>()
        .occluded_packet(rays, active as u8, 0.0, t_max);
    if T::COUNTS {
        for k in each(active) {
            charge(samples[k].slot, RayKind::Shadow, counters::lane(k));
        }
    }
    u32::from(hit)
}

impl Renderer<'_> {
    /// Sample `s` of the pixels of a packet's `active` lanes (lane `k` at `pixel(k)`, its pattern
    /// `patterns[k]`): their camera rays, a pinhole's eight at once ([`RayCamera::rays`]), and what
    /// each carries, its slot its lane, written in place into the block's `rays` and `samples`.
    ///
    /// [`RayCamera::rays`]: crate::render::camera::RayCamera::rays
    // Not inlined: a phase of `profiles/frame.sh`, called once a packet (its body on the frame's
    // lanes, `Lanes::call`).
    #[inline(never)]
    fn camera_packet<'s, L: Lanes8>(
        &'s self,
        pixel: impl Fn(usize) -> (u32, u32),
        active: u32,
        pass: u32,
        s: u32,
        patterns: &PerRay<PixelPattern>,
        (rays, samples): (&mut PerRay<Ray>, &mut PerRay<PixelSample<'s>>),
    ) {
        L::call(
            #[inline(always)]
            || {
                let mut at = [Vec2::ZERO; PACKET];
                let mut lens = [None; PACKET];
                for (k, sample) in samples.iter_mut().enumerate() {
                    *sample = if active >> k & 1 == 0 {
                        self.pixel_sample(pass, self.pixel_key(0, 0), 0, Vec2::ZERO)
                    } else {
                        let (x, y) = pixel(k);
                        let (point, lens_point, sample) = self.sample_start(x, y, pass, s, &patterns[k]);
                        (at[k], lens[k]) = (point, lens_point);
                        PixelSample {
                            slot: k as u32,
                            ..sample
                        }
                    };
                }
                let camera = self.camera();
                *rays = camera.rays::<L, PACKET>(at.map(|p| p.x), at.map(|p| p.y));
                for k in each(active) {
                    if let Some(lens) = lens[k] {
                        rays[k] = camera.lens_ray(at[k].x, at[k].y, lens);
                    }
                }
            },
        )
    }

    /// Shades `tile` for pass `pass`, packet by packet (pixels outside the image are inactive lanes),
    /// into `buf`: sample `s` of eight pixels at a time, each lane with its pixel's own pattern and
    /// random numbers, summed per pixel in sample order as the single-ray path sums them; given
    /// `pixels`, each pixel's rays are counted into its own (row by row, [`TILE`] a row). Leaves the
    /// tile half done once `stop` is set. The whole tile, camera rays to film, runs on the lanes of
    /// the instruction set chosen for the frame.
    pub(in crate::render) fn tile_packets(
        &self,
        tile: Tile,
        pass: u32,
        buf: &mut TilePixels,
        rays_traced: &mut RayCounts,
        pixels: Option<&mut [RayCounts]>,
        stop: &AtomicBool,
    ) {
        self.simd().run8(TilePackets {
            renderer: self,
            tile,
            pass,
            buf,
            rays_traced,
            pixels,
            stop,
        });
    }
}

/// [`Renderer::tile_packets`]'s work, for `Simd::run8` to run on the lanes it chose.
struct TilePackets<'r, 'a> {
    renderer: &'r Renderer<'a>,
    tile: Tile,
    pass: u32,
    buf: &'r mut TilePixels,
    rays_traced: &'r mut RayCounts,
    pixels: Option<&'r mut [RayCounts]>,
    stop: &'r AtomicBool,
}

impl OnLanes8 for TilePackets<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn run<L: Lanes8>(self) {
        let TilePackets {
            renderer: r,
            tile,
            pass,
            buf,
            rays_traced,
            mut pixels,
            stop,
        } = self;
        let mut patterns: PerRay<PixelPattern> = Default::default();
        // Filled in place for each sample of each block (built here once: no copy of the eight).
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET];
        let mut samples: PerRay<PixelSample> =
            std::array::from_fn(|_| r.pixel_sample(pass, r.pixel_key(0, 0), 0, Vec2::ZERO));
        for y0 in (tile.y0..tile.y1).step_by(BLOCK_H as usize) {
            for x0 in (tile.x0..tile.x1).step_by(BLOCK_W as usize) {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                let pixel = |k: usize| (x0 + k as u32 % BLOCK_W, y0 + k as u32 / BLOCK_W);
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
                    r.camera_packet::<L>(pixel, active, pass, s, &patterns, (&mut rays, &mut samples));
                    let colors = r
                        .whitted
                        .shade_packet::<L>(&rays, active, 0, RayKind::Camera, &mut samples);
                    sums = sums + colors;
                    for k in each(active) {
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
                let means = (sums / Fx::splat(r.samples() as f32)).lanes();
                for k in each(active) {
                    let (x, y) = pixel(k);
                    buf[((y - tile.y0) * TILE + (x - tile.x0)) as usize] = means[k];
                }
            }
        }
    }
}
