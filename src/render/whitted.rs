//! The Whitted integrator (Whitted 1980): local Blinn-Phong colour from every light sample not in shadow,
//! plus mirror reflection and Snell refraction weighted by Schlick's Fresnel term, with Beer absorption
//! inside transparent objects. It answers "what colour do these rays see", for one ray or a packet of
//! eight with the same code: the walk of each sample's ray tree here, the shading of its hits in lanes
//! (`super::shade`); which rays to ask it about (pixels, samples, tiles, passes) is the kernels' and
//! the frame's business (`super::kernel`, [`super::frame`]).
//!
//! In Whitted's model a transparent object casts a full shadow: shadow rays do not pass through glass.

use glam::{Vec2, Vec3};

use super::env::Background;
use super::lanes::{Lanes, V3, each};
use super::light::{self, LightSample, Lights};
use super::optics::beer;
use super::options::{MAX_DEPTH, Options};
use super::sampler::Sampler;
use super::shade::{HitLanes, light};
use super::spd::Spawning;
use super::stats::{Count, RayKind, SampleRays};
use crate::accel::lanes::Lanes8;
use crate::accel::{Accel, Hit, PACKET, Prims, Tally, Verbs, coherent_rays};
use crate::geometry::ray::Ray;
use crate::scene::{QuadLight, Scene};

/// What one pixel sample carries down its ray tree: the light samples it sees, its random numbers, and
/// the rays it traced (and, in a counting render, their steps).
pub struct PixelSample<'a, C: Count> {
    /// Light samples (the quad lights at this sample's paired point).
    pub lights: Lights<'a>,
    /// This sample's generator (fuzzy reflections).
    pub rng: Sampler,
    /// Rays traced for this sample so far.
    pub rays: SampleRays,
    /// Their steps, by kind: nothing unless `C` counts.
    pub steps: C::Steps,
}

/// Tries at drawing a fuzzy reflection above the surface before settling for the mirror direction.
const FUZZ_TRIES: u32 = 16;

/// Secondary rays a pixel sample may spend on split paths: past this count, a hit that would spawn
/// both a refracted and a reflected ray spawns only the heavier of the two. A transparent surface
/// doubles the rays at every bounce, so without a bound a camera among nested glass spheres at
/// [`super::options::MAX_DEPTH`] bounces would trace 2⁶⁵ rays; with it a sample's tree holds at most
/// this many splits and each of its at most this many open branches then goes on as one chain of at
/// most `MAX_DEPTH` rays. Trees of up to 9 bounces (1,022 secondary rays) never reach it, so images
/// at the usual depths are untouched (the default of 6 spawns at most 126). A sample's rays are counted
/// in the same depth-first order whatever its lane count, so every kernel cuts the same branches.
const SPLIT_BUDGET: u64 = 1024;

/// The integrator of one frame: the scene, the structure that answers its rays, what a ray that leaves
/// the scene sees, the light samples and each material's roughness; shared read-only by the workers.
pub struct Whitted<'a> {
    scene: &'a Scene,
    prims: Prims<'a>,
    accel: &'a Accel<'a>,
    background: Background,
    /// Point lights, and without sampling the quad lights' regular grids.
    fixed_lights: Vec<LightSample>,
    /// Quad lights sampled at one point per pixel sample (none without sampling).
    quads: &'a [QuadLight],
    /// Each material's roughness (the file's, or the default).
    roughness: Vec<f32>,
    /// Most bounces after the primary hit.
    max_depth: u32,
    /// Which secondary rays a hit spawns: by weight, or under the SPD's rules.
    spawning: Spawning,
}

impl<'a> Whitted<'a> {
    /// The integrator of `scene` through `accel` under `options`: with samples per pixel, each quad
    /// light is sampled at one point per pixel sample (soft shadows); without, it is its regular grid
    /// of point lights (the course's spp-0 model). Materials without a roughness of their own get
    /// the options' roughness.
    pub fn new(scene: &'a Scene, accel: &'a Accel<'a>, background: Background, options: &Options) -> Self {
        let (fixed_lights, quads) = if options.side() > 0 {
            (light::point_samples(scene), &scene.area_lights[..])
        } else {
            (light::regular_samples(scene), &[][..])
        };
        Whitted {
            scene,
            prims: Prims::new(scene),
            accel,
            background,
            fixed_lights,
            quads,
            roughness: scene
                .materials
                .iter()
                .map(|m| m.roughness.unwrap_or(options.roughness))
                .collect(),
            // Unvalidated options are clamped rather than allowed to overflow the stack.
            max_depth: options.max_depth.min(MAX_DEPTH),
            spawning: Spawning::of(options),
        }
    }

    /// Quad lights as their regular grids of point lights whatever the sampling: hard-edged, banded
    /// shadows without noise (the viewer's soft-shadow switch).
    pub fn with_regular_lights(mut self) -> Self {
        self.fixed_lights = light::regular_samples(self.scene);
        self.quads = &[];
        self
    }

    /// The light samples a pixel sample sees: the fixed lights, and each quad light at the point `uv`
    /// of its area.
    pub fn lights(&self, uv: Vec2) -> Lights<'_> {
        Lights::new(&self.fixed_lights, self.quads, uv)
    }

    /// Whether some material has a roughness: where it reflects, its mirror rays draw from the pixel
    /// sample's generator ([`fuzz`]).
    pub(super) fn has_rough_mirrors(&self) -> bool {
        self.roughness.iter().any(|&r| r > 0.0)
    }

    /// Whether pixel samples sample quad lights at their own points (soft shadows).
    pub(super) fn samples_quads(&self) -> bool {
        !self.quads.is_empty()
    }

    /// The colour seen along `ray` (unit direction), a ray of `kind`, after `depth` bounces: the
    /// one-lane instance of the integrator's walk over lanes (`Whitted::trace_lanes`), which the packet
    /// kernel runs on eight.
    pub fn trace<C: Count>(&self, ray: &Ray, depth: u32, kind: RayKind, sample: &mut PixelSample<C>) -> Vec3 {
        let seen = self.trace_lanes::<C, f32, 1>(
            std::array::from_ref(ray),
            1,
            depth,
            kind,
            std::array::from_mut(sample),
        );
        seen.lanes()[0]
    }

    /// The colours seen along the rays of `rays` in `active` (unit directions; the other lanes are
    /// zero), rays of `kind` after `depth` bounces, each lane the ray of its own pixel sample: their
    /// closest hits, then for each hit the local colour (a shadow ray toward each light sample, the
    /// lanes' rays toward one sample traced together) and what its refracted and reflected rays see
    /// (each kind traced together, recursively to the depth limit), absorbed by Beer's law where the
    /// ray crossed a transmitter. Each lane draws its random numbers and counts its rays in its own
    /// sample's depth-first order, so a sample gets the same colour whatever lanes it shares.
    // Not inlined (it recurses): its body on the lanes' instructions (`Lanes::call`).
    #[inline(never)]
    pub(super) fn trace_lanes<C: Count, L: Width<N>, const N: usize>(
        &self,
        rays: &[Ray; N],
        active: u32,
        depth: u32,
        kind: RayKind,
        samples: &mut [PixelSample<C>; N],
    ) -> V3<L, N> {
        L::call(
            #[inline(always)]
            || {
                let mut hits = [Hit::miss(f32::INFINITY); N];
                let hit = closest_tallied::<C, L, N>(self, rays, active, kind, samples, &mut hits);
                if depth == 0 {
                    for k in each::<N>(hit) {
                        samples[k].rays.primary_hits += 1;
                    }
                }
                let mut missed = [Vec3::ZERO; N];
                for k in each::<N>(active & !hit) {
                    // What a ray that leaves the scene sees.
                    missed[k] = self.background.sample(rays[k].dir);
                }
                let missed = V3::from_lanes(&missed);
                let Some(h) = HitLanes::<L, N>::of_hits(&self.prims, rays, &hits, hit) else {
                    return missed;
                };
                let mut color = self.local_lanes(&h, samples);
                if depth < self.max_depth {
                    let spawned = self.spawn(&h, samples);
                    // What the refracted (0) and reflected (1) rays see, each kind traced together (the
                    // lanes of `spawned.lanes`; the others keep whatever ray they held, never traced),
                    // added in that order.
                    let mut next = [Ray::new(Vec3::ZERO, Vec3::Z); N];
                    for (i, s) in spawned.iter().enumerate() {
                        if s.lanes == 0 {
                            continue;
                        }
                        let (origin, dir) = (s.origin.lanes(), s.dir.lanes());
                        for k in each::<N>(s.lanes) {
                            next[k] = Ray::new(origin[k], dir[k]);
                        }
                        let seen =
                            self.trace_spawned(&next, s.lanes, depth + 1, RayKind::secondary(i), samples);
                        color = V3::blend(s.lanes, color + seen * s.weight, color);
                    }
                }
                V3::blend(hit, self.absorbed(&h, color), missed)
            },
        )
    }

    /// [`trace_lanes`](Self::trace_lanes), or ray by ray when too few lanes are live to share nodes
    /// or their directions point into different octants (rays off a curved mirror, say), which share
    /// few nodes (faster: `profiles/README.md`, tuned constants).
    #[inline(always)]
    fn trace_spawned<C: Count, L: Width<N>, const N: usize>(
        &self,
        rays: &[Ray; N],
        mask: u32,
        depth: u32,
        kind: RayKind,
        samples: &mut [PixelSample<C>; N],
    ) -> V3<L, N> {
        if N == 1 || coherent_rays(each::<N>(mask).map(|k| &rays[k])) {
            return self.trace_lanes(rays, mask, depth, kind, samples);
        }
        let mut out = [Vec3::ZERO; N];
        for k in each::<N>(mask) {
            out[k] = self.trace(&rays[k], depth, kind, &mut samples[k]);
        }
        V3::from_lanes(&out)
    }

    /// The local colour of the hits `h`: light sample by light sample, their shadow rays set up in
    /// lanes and traced together (lane `k` aims at its own pixel sample's light), and the Blinn-Phong
    /// sum in lanes.
    // Its body on the lanes' instructions (`Lanes::call`: for eight lanes a function of its own, a
    // phase of `profiles/frame.sh`).
    #[inline(always)]
    fn local_lanes<C: Count, L: Width<N>, const N: usize>(
        &self,
        h: &HitLanes<L, N>,
        samples: &mut [PixelSample<C>; N],
    ) -> V3<L, N> {
        L::call(
            #[inline(always)]
            || {
                let lights = samples.each_ref().map(|s| s.lights);
                let mut color = V3::zero();
                for i in 0..lights[0].len() {
                    let (at, light) = light(i, &lights);
                    let toward = h.toward(at);
                    let lit = toward.lit;
                    if lit == 0 {
                        continue;
                    }
                    for k in each::<N>(lit) {
                        samples[k].rays.shadow += 1;
                    }
                    let (shadows, distance) = h.shadow_rays(&toward);
                    let blocked = blocked_tallied::<C, L, N>(self, &shadows, lit, &distance, samples);
                    h.add_light(&mut color, &toward, lit & !blocked, light);
                }
                color
            },
        )
    }

    /// The refracted (0) and reflected (1) rays of the hits `h`, counted into their samples: a rough
    /// material's mirror direction drawn from its sample's generator ([`fuzz`]), and only the heavier
    /// of the two where a sample has spent its [`SPLIT_BUDGET`] (on a tie the mirror ray, the one a
    /// total internal reflection keeps).
    #[inline(always)]
    fn spawn<C: Count, L: Lanes<N>, const N: usize>(
        &self,
        h: &HitLanes<L, N>,
        samples: &mut [PixelSample<C>; N],
    ) -> [super::shade::Spawned<L, N>; 2] {
        let rough = h.materials_where(|m| self.roughness[m as usize] > 0.0);
        let [mut refracted, mut reflected] =
            h.bounces(self.scene, h.live(), self.spawning, rough, |k, mirror, ng| {
                let roughness = self.roughness[h.material(k) as usize];
                fuzz(mirror, ng, roughness, &mut samples[k].rng)
            });
        let both = refracted.lanes & reflected.lanes;
        let spent = each::<N>(both).fold(0, |m, k| m | u32::from(budget_spent(&samples[k].rays)) << k);
        if spent != 0 {
            let heavier = spent & refracted.weight.gt(reflected.weight);
            reflected.lanes &= !heavier;
            refracted.lanes &= !(spent & !heavier);
        }
        for k in each::<N>(h.live()) {
            let r = &mut samples[k].rays;
            r.refracted += u64::from(refracted.lanes >> k & 1);
            r.reflected += u64::from(reflected.lanes >> k & 1);
        }
        [refracted, reflected]
    }

    /// `color` seen at the hits `h`, absorbed by Beer's law where the ray crossed a transmitter's
    /// interior from its entry point to here.
    #[inline(always)]
    fn absorbed<L: Lanes<N>, const N: usize>(&self, h: &HitLanes<L, N>, color: V3<L, N>) -> V3<L, N> {
        let inside = h.inside_transmitters();
        if inside == 0 {
            return color;
        }
        let (mut lanes, t) = (color.lanes(), h.distances());
        for k in each::<N>(inside) {
            lanes[k] *= beer(self.scene.materials[h.material(k) as usize].diffuse, t[k]);
        }
        V3::from_lanes(&lanes)
    }
}

/// The lanes the integrator traces on: one ray ([`f32`]) or a packet of eight, and the verbs that
/// trace them.
pub(super) trait Width<const N: usize>: Lanes<N> {
    /// The closest hits of the rays of `rays` in `active`, rays of `kind`, through `verbs`: the lanes
    /// that hit.
    fn closest<T: Tally>(
        verbs: Verbs<'_, '_, T>,
        rays: &[Ray; N],
        active: u32,
        kind: RayKind,
        hits: &mut [Hit; N],
    ) -> u32;
    /// Which of the rays of `rays` in `active` are blocked before `t_max`.
    fn blocked<T: Tally>(verbs: Verbs<'_, '_, T>, rays: &[Ray; N], active: u32, t_max: &[f32; N]) -> u32;
}

/// One ray: camera rays by the coherent verb.
impl Width<1> for f32 {
    #[inline(always)]
    fn closest<T: Tally>(
        verbs: Verbs<'_, '_, T>,
        rays: &[Ray; 1],
        active: u32,
        kind: RayKind,
        hits: &mut [Hit; 1],
    ) -> u32 {
        if active == 0 {
            return 0;
        }
        let hit = if kind == RayKind::Camera {
            verbs.intersect_coherent(&rays[0], 0.0, &mut hits[0])
        } else {
            verbs.intersect(&rays[0], 0.0, &mut hits[0])
        };
        u32::from(hit)
    }

    #[inline(always)]
    fn blocked<T: Tally>(verbs: Verbs<'_, '_, T>, rays: &[Ray; 1], active: u32, t_max: &[f32; 1]) -> u32 {
        u32::from(active != 0 && verbs.occluded(&rays[0], 0.0, t_max[0]))
    }
}

/// A packet of eight rays.
impl<L: Lanes8> Width<PACKET> for L {
    #[inline(always)]
    fn closest<T: Tally>(
        verbs: Verbs<'_, '_, T>,
        rays: &[Ray; PACKET],
        active: u32,
        _: RayKind,
        hits: &mut [Hit; PACKET],
    ) -> u32 {
        u32::from(verbs.intersect_packet(rays, active as u8, 0.0, hits))
    }

    #[inline(always)]
    fn blocked<T: Tally>(
        verbs: Verbs<'_, '_, T>,
        rays: &[Ray; PACKET],
        active: u32,
        t_max: &[f32; PACKET],
    ) -> u32 {
        u32::from(verbs.occluded_packet(rays, active as u8, 0.0, t_max))
    }
}

/// [`Whitted::trace_lanes`]' closest hits through the verbs of `C`, their steps charged to each
/// lane's sample as rays of `kind` when `C` counts.
#[inline(always)]
fn closest_tallied<C: Count, L: Width<N>, const N: usize>(
    whitted: &Whitted,
    rays: &[Ray; N],
    active: u32,
    kind: RayKind,
    samples: &mut [PixelSample<C>; N],
    hits: &mut [Hit; N],
) -> u32 {
    let hit = L::closest(whitted.accel.verbs::<C>(), rays, active, kind, hits);
    if C::COUNTS {
        for k in each::<N>(active) {
            C::charge(&mut samples[k].steps, kind, k);
        }
    }
    hit
}

/// Which of the shadow rays `rays` in `active` are blocked, through the verbs of `C`, their steps
/// charged to each lane's sample when `C` counts.
#[inline(always)]
fn blocked_tallied<C: Count, L: Width<N>, const N: usize>(
    whitted: &Whitted,
    rays: &[Ray; N],
    active: u32,
    t_max: &[f32; N],
    samples: &mut [PixelSample<C>; N],
) -> u32 {
    let blocked = L::blocked(whitted.accel.verbs::<C>(), rays, active, t_max);
    if C::COUNTS {
        for k in each::<N>(active) {
            C::charge(&mut samples[k].steps, RayKind::Shadow, k);
        }
    }
    blocked
}

/// Whether a sample's rays have spent the [`SPLIT_BUDGET`]: a hit that would spawn both a refracted and
/// a reflected ray then spawns only the heavier.
#[inline]
fn budget_spent(rays: &SampleRays) -> bool {
    rays.reflected + rays.refracted >= SPLIT_BUDGET
}

/// A fuzzy reflection (the course's glossy mirror; Shirley's "fuzz"): the mirror direction plus a
/// uniform point of the ball of radius `roughness`, normalised, drawn again while it points below the
/// surface (geometric normal `ng`, turned toward the viewer); after [`FUZZ_TRIES`] the mirror itself.
fn fuzz(mirror: Vec3, ng: Vec3, roughness: f32, rng: &mut Sampler) -> Vec3 {
    for _ in 0..FUZZ_TRIES {
        let d = (mirror + roughness * rng.in_unit_ball()).normalize();
        if d.dot(ng) > 0.0 {
            return d;
        }
    }
    mirror
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fuzzy reflections stay above the surface, within asin(roughness) of the mirror direction, and
    /// centred on it; roughness 0 is the mirror itself.
    #[test]
    fn fuzzy_reflections() {
        let ng = Vec3::Y;
        let mirror = Vec3::new(1.0, 1.0, 0.0).normalize();
        let mut rng = Sampler::new(1, 1, 0, 1);
        let mut mean = Vec3::ZERO;
        for _ in 0..20_000 {
            let d = fuzz(mirror, ng, 0.3, &mut rng);
            assert!(d.dot(ng) > 0.0);
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!(d.angle_between(mirror) <= 0.3f32.asin() + 1e-4);
            mean += d;
        }
        assert!(mean.normalize().angle_between(mirror) < 0.01);
        // Grazing: a wide fuzz still never goes below the surface.
        let grazing = Vec3::new(1.0, 0.02, 0.0).normalize();
        for _ in 0..2_000 {
            assert!(fuzz(grazing, ng, 0.9, &mut rng).dot(ng) > 0.0);
        }
    }
}
