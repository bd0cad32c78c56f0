//! The packet kernel, the Whitted integrator's packet twin: eight rays (the camera rays of 4x2 pixels)
//! traced as a packet, and then, packet by packet, the shadow rays of their hits (one
//! packet per light sample) and their reflected and refracted rays (one packet per kind), recursively
//! to the depth limit. Rays that leave neighbouring pixels' hits toward one light, or off one smooth
//! surface, stay about as coherent as the camera rays.
//!
//! The camera rays and the local shading (shadow-ray set-up and Blinn-Phong, light sample by light
//! sample) run in lanes ([`super::super::lanes`]), with the single-ray path's operations in its order;
//! each hit's bounces come from [`Whitted::bounces`] and its colour is finished by
//! [`Whitted::add_bounces`], as on the single-ray path, and the accelerators' packet verbs answer each
//! ray as their single-ray verbs do: the image is the single-ray path's, bit for bit.

use glam::{Vec2, Vec3};
use wide::f32x8;

use super::{BLOCK_H, BLOCK_W, PerRay, TilePixels, coherent};
use crate::accel::counters;
use crate::accel::packet::{PACKET, bits};
use crate::accel::{Hit, Surface};
use crate::geometry::ray::Ray;
use crate::render::lanes::{Vec3x8, lane_mask, positive};
use crate::render::renderer::Renderer;
use crate::render::sampler::PixelPattern;
use crate::render::tiles::{TILE, Tile};
use crate::render::whitted::{
    Bounces, EPSILON, PixelSample, RayCounts, RayKind, Whitted, charge, take_steps,
};
use crate::scene::{Material, MaterialId, Scene};

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
        let local = self.local_packet(rays, &surfaces, hit, samples);

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
            out[k] = match &surfaces[k] {
                None => self.shade(&rays[k], &hits[k], depth, &mut samples[k]),
                Some(s) => self.add_bounces(local[k], s, &bounces[k], &mut |i, _| seen[i][k]),
            };
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

    /// The local colour of the packet's hits (the lanes of `live`, at `surfaces`, seen along `rays`):
    /// [`Whitted::shade_surface`]'s Blinn-Phong sum in lanes, light sample by light sample, each
    /// sample's shadow rays set up in lanes and traced as one packet (lane `k` aims at its own pixel
    /// sample's light). The same operations in the same order as the single-ray path's, so the same
    /// bits; only `powf` goes lane by lane, as the scalar function.
    // Not inlined: a phase of `profiles/frame.sh`, called once a packet.
    #[inline(never)]
    fn local_packet(
        &self,
        rays: &PerRay<Ray>,
        surfaces: &PerRay<Option<Surface>>,
        live: u8,
        samples: &mut PerRay<PixelSample>,
    ) -> PerRay<Vec3> {
        let Some(first) = bits(live).next() else {
            return [Vec3::ZERO; PACKET];
        };
        let of = |f: fn(&Surface) -> Vec3| {
            Vec3x8::from_lanes(&std::array::from_fn(|k| {
                surfaces[k].as_ref().map_or(Vec3::ZERO, f)
            }))
        };
        let (p, ng, ns) = (of(|s| s.point), of(|s| s.geometric), of(|s| s.shading));
        let v = -Vec3x8::from_lanes(&rays.map(|r| r.dir));
        let m = Materials::gather(self.scene(), surfaces, first);
        let mut color = Vec3x8::ZERO;
        for i in 0..samples[first].lights.len() {
            let at = if samples[first].lights.shared(i) {
                Vec3x8::splat(samples[first].lights.get(i).position)
            } else {
                Vec3x8::from_lanes(&std::array::from_fn(|k| samples[k].lights.get(i).position))
            };
            // `ShadowRay::new` in lanes: toward the light, from just off the side it lies on.
            let l = (at - p).normalize();
            let n_dot_l = ns.dot(l);
            let lit = live & positive(n_dot_l);
            if lit == 0 {
                continue;
            }
            let eps = f32x8::splat(EPSILON);
            let origin = p + ng * ng.dot(l).simd_ge(f32x8::ZERO).select(eps, -eps);
            let distance = (at - origin).length().to_array();
            let (origins, dirs) = (origin.lanes(), l.lanes());
            let shadows: PerRay<Ray> = std::array::from_fn(|k| Ray::new(origins[k], dirs[k]));
            for k in bits(lit) {
                samples[k].rays.shadow += 1;
            }
            let blocked = if self.counts() {
                blocked_counted(self, &shadows, lit, &distance, samples)
            } else {
                self.accel.occluded_packet(&shadows, lit, 0.0, &distance)
            };
            let seen = lit & !blocked;
            if seen == 0 {
                continue;
            }
            // Blinn-Phong: Kd·Cd·(n·L), plus Ks·Cs·(n·h)^shine where Ks > 0.
            let mut c = m.diffuse * (m.kd * n_dot_l);
            let glossy = seen & m.glossy;
            if glossy != 0 {
                let n_dot_h = (l + v).normalize().dot(ns).to_array();
                let mut power = [0.0; PACKET];
                for k in bits(glossy) {
                    power[k] = n_dot_h[k].max(0.0).powf(m.shininess[k]);
                }
                let highlight = m.specular * (m.ks * f32x8::from(power));
                c = Vec3x8::select(lane_mask(glossy), c + highlight, c);
            }
            let light = Vec3x8::splat(samples[first].lights.get(i).color);
            color = Vec3x8::select(lane_mask(seen), color + light * c, color);
        }
        color.lanes()
    }
}

/// The materials of a packet's hits in lanes, gathered once a packet (one load where every live lane
/// hit the same material, the usual case).
struct Materials {
    kd: f32x8,
    ks: f32x8,
    shininess: [f32; PACKET],
    diffuse: Vec3x8,
    specular: Vec3x8,
    /// The lanes whose material has a highlight (Ks > 0).
    glossy: u8,
}

impl Materials {
    /// The materials at `surfaces` (`first` live), dead lanes given `first`'s.
    fn gather(scene: &Scene, surfaces: &PerRay<Option<Surface>>, first: usize) -> Self {
        let id = |k: usize| surfaces[k].as_ref().map(|s| s.material);
        let one = id(first).expect("a live lane");
        let ids: PerRay<MaterialId> = std::array::from_fn(|k| id(k).unwrap_or(one));
        let glossy = |m: &Material| m.ks > 0.0;
        if ids.iter().all(|&i| i == one) {
            let m = &scene.materials[one as usize];
            return Materials {
                kd: f32x8::splat(m.kd),
                ks: f32x8::splat(m.ks),
                shininess: [m.shininess; PACKET],
                diffuse: Vec3x8::splat(m.diffuse),
                specular: Vec3x8::splat(m.specular),
                glossy: if glossy(m) { !0 } else { 0 },
            };
        }
        let m = ids.map(|i| &scene.materials[i as usize]);
        Materials {
            kd: f32x8::from(m.map(|m| m.kd)),
            ks: f32x8::from(m.map(|m| m.ks)),
            shininess: m.map(|m| m.shininess),
            diffuse: Vec3x8::from_lanes(&m.map(|m| m.diffuse)),
            specular: Vec3x8::from_lanes(&m.map(|m| m.specular)),
            glossy: m
                .iter()
                .enumerate()
                .fold(0, |g, (k, m)| g | u8::from(glossy(m)) << k),
        }
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
    /// Sample `s` of the pixels of a packet's `active` lanes (lane `k` at `pixel(k)`, its pattern
    /// `patterns[k]`): their camera rays, a pinhole's eight at once ([`RayCamera::rays8`]), and what
    /// each carries, its slot its lane.
    ///
    /// [`RayCamera::rays8`]: crate::render::camera::RayCamera::rays8
    // Not inlined: a phase of `profiles/frame.sh`, called once a packet.
    #[inline(never)]
    fn camera_packet(
        &self,
        pixel: impl Fn(usize) -> (u32, u32),
        active: u8,
        pass: u32,
        s: u32,
        patterns: &PerRay<PixelPattern>,
    ) -> (PerRay<Ray>, PerRay<PixelSample<'_>>) {
        let mut at = [Vec2::ZERO; PACKET];
        let mut lens = [None; PACKET];
        let samples = std::array::from_fn(|k| {
            if active >> k & 1 == 0 {
                return self.pixel_sample(pass, self.pixel_key(0, 0), 0, Vec2::ZERO);
            }
            let (x, y) = pixel(k);
            let (point, lens_point, sample) = self.sample_start(x, y, pass, s, &patterns[k]);
            (at[k], lens[k]) = (point, lens_point);
            PixelSample {
                slot: k as u32,
                ..sample
            }
        });
        let camera = self.camera();
        let mut rays = camera.rays8(at.map(|p| p.x), at.map(|p| p.y));
        for k in bits(active) {
            if let Some(lens) = lens[k] {
                rays[k] = camera.lens_ray(at[k].x, at[k].y, lens);
            }
        }
        (rays, samples)
    }

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
                    let (rays, mut samples) = self.camera_packet(pixel, active, pass, s, &patterns);
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
