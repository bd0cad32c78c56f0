//! The Whitted integrator (Whitted 1980): local Blinn-Phong colour from every light sample not in shadow,
//! plus mirror reflection and Snell refraction weighted by Schlick's Fresnel term, with Beer absorption
//! inside transparent objects. It answers "what colour does this ray see"; which rays to ask it about
//! (pixels, samples, tiles, passes) is the kernels' and the frame's business (`super::kernel`,
//! [`super::frame`]). Its packet twin, the same shading for eight rays at a time, is
//! `kernel/packet.rs`.
//!
//! Conventions (those of NFF/p3f renderers; the README lists them): surfaces are two-sided, so normals
//! are turned toward the incoming ray; no ambient term; lights have no falloff; secondary and shadow rays
//! start [`EPSILON`] along the geometric normal on the side they leave from. In Whitted's model a
//! transparent object casts a full shadow: shadow rays do not pass through glass.

use glam::{Vec2, Vec3};

use super::env::Background;
use super::light::{self, LightSample, Lights};
use super::optics::{beer, reflect, refract, schlick};
use super::options::MAX_DEPTH;
use super::sampler::Sampler;
use crate::accel::counters::{self, Steps};
use crate::accel::{Accel, Counting, Hit, Plain, Prims, Surface, Tally, Verbs};
use crate::geometry::ray::Ray;
use crate::scene::{Material, MaterialId, QuadLight, Scene};

/// Offset of secondary and shadow ray origins along the geometric normal, in scene units.
pub const EPSILON: f32 = 1e-4;

/// A shadow ray toward one light sample.
#[derive(Clone, Copy, Debug)]
pub struct ShadowRay {
    /// From just off the surface toward the light (unit direction).
    pub ray: Ray,
    /// Distance to the light: anything hit before it casts the shadow.
    pub distance: f32,
    /// Cosine between the shading normal and the direction to the light.
    pub n_dot_l: f32,
}

impl ShadowRay {
    /// The shadow ray from `p` (geometric normal `ng`, shading normal `ns`) to `light`, or `None` when
    /// the light is behind the shading normal (it then adds nothing, neither diffuse nor highlight). The
    /// single-ray path builds its shadow rays here, the packet kernel the same rays in
    /// lanes (`kernel/shade.rs`).
    #[inline]
    pub fn new(p: Vec3, ng: Vec3, ns: Vec3, light: &LightSample) -> Option<Self> {
        let l = (light.position - p).normalize();
        let n_dot_l = ns.dot(l);
        if n_dot_l.is_nan() || n_dot_l <= 0.0 {
            return None;
        }
        let origin = p + ng * if ng.dot(l) >= 0.0 { EPSILON } else { -EPSILON };
        Some(ShadowRay {
            ray: Ray::new(origin, l),
            distance: (light.position - origin).length(),
            n_dot_l,
        })
    }
}

/// The rays a hit spawns: the refracted ray (with Fresnel's transmitted share) and the mirror ray
/// (with Ks times Fresnel's reflected share), each when its weight is not zero.
#[derive(Clone, Copy, Debug, Default)]
pub struct Bounces {
    /// Refracted ray and weight.
    pub refracted: Option<(Ray, f32)>,
    /// Reflected ray and weight.
    pub reflected: Option<(Ray, f32)>,
}

/// Rays traced, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Camera rays.
    pub primary: u64,
    /// Camera rays that hit something (not counted in [`RayCounts::total`]: they are camera rays).
    pub primary_hits: u64,
    /// Shadow rays (any hit).
    pub shadow: u64,
    /// Mirror rays.
    pub reflected: u64,
    /// Refracted rays.
    pub refracted: u64,
    /// The steps of the rays of each kind, when the render counts them ([`Options::count_steps`]).
    ///
    /// [`Options::count_steps`]: super::options::Options::count_steps
    pub steps: KindSteps,
}

/// Which kind a traced ray is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// From the camera.
    Camera,
    /// Toward a light sample (any hit).
    Shadow,
    /// Off a mirror.
    Reflected,
    /// Through a transmitter.
    Refracted,
}

impl RayKind {
    /// The kind of a hit's secondary ray `i`: 0 refracted, 1 reflected (the order of
    /// [`Whitted::shade_surface`]'s rays).
    pub fn secondary(i: usize) -> RayKind {
        if i == 0 {
            RayKind::Refracted
        } else {
            RayKind::Reflected
        }
    }
}

/// Steps ([`Steps`]: nodes visited, primitives tested) summed over the rays of each kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KindSteps {
    /// Camera rays'.
    pub camera: Steps,
    /// Shadow rays'.
    pub shadow: Steps,
    /// Mirror rays'.
    pub reflected: Steps,
    /// Refracted rays'.
    pub refracted: Steps,
}

impl KindSteps {
    /// The steps of `kind`.
    pub fn get(&self, kind: RayKind) -> Steps {
        match kind {
            RayKind::Camera => self.camera,
            RayKind::Shadow => self.shadow,
            RayKind::Reflected => self.reflected,
            RayKind::Refracted => self.refracted,
        }
    }

    /// The steps of `kind`, to add to.
    pub fn of(&mut self, kind: RayKind) -> &mut Steps {
        match kind {
            RayKind::Camera => &mut self.camera,
            RayKind::Shadow => &mut self.shadow,
            RayKind::Reflected => &mut self.reflected,
            RayKind::Refracted => &mut self.refracted,
        }
    }

    /// All kinds' steps.
    pub fn total(&self) -> Steps {
        let mut all = self.camera;
        for s in [self.shadow, self.reflected, self.refracted] {
            all += s;
        }
        all
    }
}

impl std::ops::AddAssign for KindSteps {
    fn add_assign(&mut self, o: KindSteps) {
        self.camera += o.camera;
        self.shadow += o.shadow;
        self.reflected += o.reflected;
        self.refracted += o.refracted;
    }
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.primary + self.shadow + self.reflected + self.refracted
    }
}

/// The rays one pixel sample traced, by kind: [`RayCounts`] without the steps, which a counting
/// render keeps apart (`charge`), so that a sample carries no more than it did before counting.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SampleRays {
    /// Camera rays.
    pub primary: u64,
    /// Camera rays that hit something.
    pub primary_hits: u64,
    /// Shadow rays.
    pub shadow: u64,
    /// Mirror rays.
    pub reflected: u64,
    /// Refracted rays.
    pub refracted: u64,
}

impl SampleRays {
    /// Whether these rays have spent the split budget (`SPLIT_BUDGET`): a hit that would spawn
    /// both a refracted and a reflected ray then spawns only the heavier.
    #[inline]
    pub fn budget_spent(&self) -> bool {
        self.reflected + self.refracted >= SPLIT_BUDGET
    }

    /// Counts the secondary rays of `bounces`.
    pub fn add_bounces(&mut self, bounces: &Bounces) {
        self.refracted += bounces.refracted.is_some() as u64;
        self.reflected += bounces.reflected.is_some() as u64;
    }
}

impl std::ops::AddAssign<SampleRays> for RayCounts {
    fn add_assign(&mut self, o: SampleRays) {
        self.primary += o.primary;
        self.primary_hits += o.primary_hits;
        self.shadow += o.shadow;
        self.reflected += o.reflected;
        self.refracted += o.refracted;
    }
}

thread_local! {
    /// A counting render's steps of each pixel sample in flight on this worker, by its slot
    /// ([`PixelSample::slot`]): charged as its rays are traced, taken when the sample is summed.
    static SAMPLE_STEPS: std::cell::RefCell<Vec<KindSteps>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Runs `f` in a call of its own, marked cold: a counting render's verbs, kept out of the plain
/// frame's hot loops (inlined there, they lengthen the plain frame, `profiles/frame.sh`).
#[cold]
#[inline(never)]
pub(super) fn out_of_line<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Adds `steps`, of a ray of `kind`, to the sample in `slot`.
pub(super) fn charge(slot: u32, kind: RayKind, steps: Steps) {
    SAMPLE_STEPS.with_borrow_mut(|all| {
        let slot = slot as usize;
        if all.len() <= slot {
            all.resize(slot + 1, KindSteps::default());
        }
        *all[slot].of(kind) += steps;
    });
}

/// The steps charged to the sample in `slot`, which starts again from none.
pub(super) fn take_steps(slot: u32) -> KindSteps {
    SAMPLE_STEPS.with_borrow_mut(|all| all.get_mut(slot as usize).map(std::mem::take).unwrap_or_default())
}

impl std::ops::AddAssign for RayCounts {
    fn add_assign(&mut self, o: RayCounts) {
        self.primary += o.primary;
        self.primary_hits += o.primary_hits;
        self.shadow += o.shadow;
        self.reflected += o.reflected;
        self.refracted += o.refracted;
        self.steps += o.steps;
    }
}

/// What one pixel sample carries down its ray tree: the light samples it sees, its random numbers, and
/// the count of rays it traced.
pub struct PixelSample<'a> {
    /// Light samples (the quad lights at this sample's paired point).
    pub lights: Lights<'a>,
    /// This sample's generator (fuzzy reflections).
    pub rng: Sampler,
    /// Rays traced for this sample so far.
    pub rays: SampleRays,
    /// Where a counting render keeps this sample's steps (`charge`): unique among the samples a
    /// worker has in flight.
    pub slot: u32,
}

/// Tries at drawing a fuzzy reflection above the surface before settling for the mirror direction.
const FUZZ_TRIES: u32 = 16;

/// Secondary rays a pixel sample may spend on split paths: past this count, a hit that would spawn
/// both a refracted and a reflected ray spawns only the heavier of the two. A transparent surface
/// doubles the rays at every bounce, so without a bound a camera among nested glass spheres at
/// [`super::options::MAX_DEPTH`] bounces would trace 2⁶⁵ rays; with it a sample's tree holds at most
/// this many splits and each of its at most this many open branches then goes on as one chain of at
/// most `MAX_DEPTH` rays. Trees of up to 9 bounces (1,022 secondary rays) never reach it, so images
/// at the usual depths are untouched (the default of 6 spawns at most 126). Both kernels count a
/// sample's rays in the same order, so they cut the same branches.
const SPLIT_BUDGET: u64 = 1024;

/// The integrator of one frame: the scene, the structure that answers its rays, what a ray that leaves
/// the scene sees, the light samples and each material's roughness; shared read-only by the workers.
pub struct Whitted<'a> {
    scene: &'a Scene,
    pub(super) prims: Prims<'a>,
    pub(super) accel: &'a Accel<'a>,
    background: Background,
    /// Point lights, and without sampling the quad lights' regular grids.
    fixed_lights: Vec<LightSample>,
    /// Quad lights sampled at one point per pixel sample (none without sampling).
    quads: &'a [QuadLight],
    /// Each material's roughness (the file's, or the default).
    roughness: Vec<f32>,
    /// Most bounces after the primary hit.
    max_depth: u32,
    /// The SPD rules ([`super::spd`]): a hit on a transmitter always spawns its mirror ray (of weight
    /// zero where Ks is 0) and, but for a total internal reflection, its refracted ray.
    spd: bool,
    /// Count each ray's steps ([`Whitted::counting`]).
    count: bool,
}

impl<'a> Whitted<'a> {
    /// The integrator of `scene` through `accel`. With `sampled_lights`, each quad light is sampled at
    /// one point per pixel sample (soft shadows); without, it is its regular grid of point lights (the
    /// course's spp-0 model). Materials without a roughness of their own get `roughness`.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel<'a>,
        background: Background,
        sampled_lights: bool,
        max_depth: u32,
        roughness: f32,
        spd: bool,
    ) -> Self {
        let (fixed_lights, quads) = if sampled_lights {
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
                .map(|m| m.roughness.unwrap_or(roughness))
                .collect(),
            // Unvalidated options are clamped rather than allowed to overflow the stack.
            max_depth: max_depth.min(MAX_DEPTH),
            spd,
            count: false,
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

    /// The integrator counting each ray's steps into its sample's [`RayCounts::steps`], where the
    /// accelerator counts them ([`Accel::counts_steps`]).
    pub fn counting(mut self) -> Self {
        self.count = self.accel.counts_steps();
        self
    }

    /// Whether the integrator counts steps.
    pub fn counts(&self) -> bool {
        self.count
    }

    /// The colour seen along `ray` (unit direction), a ray of `kind`, after `depth` bounces.
    pub fn trace(&self, ray: &Ray, depth: u32, kind: RayKind, sample: &mut PixelSample) -> Vec3 {
        let mut hit = Hit::miss(f32::INFINITY);
        if self.count {
            out_of_line(|| self.closest_tallied::<Counting>(ray, kind, sample, &mut hit));
        } else {
            self.closest_tallied::<Plain>(ray, kind, sample, &mut hit);
        }
        self.shade(ray, &hit, depth, sample)
    }

    /// [`Whitted::trace`]'s closest hit through the verbs of `T`, its steps charged to the sample's
    /// slot when `T` counts.
    #[inline(always)]
    fn closest_tallied<T: Tally>(&self, ray: &Ray, kind: RayKind, sample: &PixelSample, hit: &mut Hit) {
        closest(self.accel.verbs::<T>(), ray, kind, hit);
        if T::COUNTS {
            charge(sample.slot, kind, counters::lane(0));
        }
    }

    /// Whether `shadow` is blocked, its steps added to `steps` when counting.
    pub(super) fn blocked(&self, shadow: &ShadowRay, steps: &mut Steps) -> bool {
        if self.count {
            out_of_line(|| self.blocked_tallied::<Counting>(shadow, steps))
        } else {
            self.blocked_tallied::<Plain>(shadow, steps)
        }
    }

    /// [`Whitted::blocked`] through the verbs of `T`.
    #[inline(always)]
    fn blocked_tallied<T: Tally>(&self, shadow: &ShadowRay, steps: &mut Steps) -> bool {
        let blocked = self
            .accel
            .verbs::<T>()
            .occluded(&shadow.ray, 0.0, shadow.distance);
        if T::COUNTS {
            *steps += counters::lane(0);
        }
        blocked
    }

    /// The colour of `ray` given its closest hit: the background for a miss, else
    /// [`shade_surface`](Self::shade_surface) with shadow and secondary rays traced one by one.
    pub fn shade(&self, ray: &Ray, hit: &Hit, depth: u32, sample: &mut PixelSample) -> Vec3 {
        if !hit.is_hit() {
            return self.background.sample(ray.dir);
        }
        sample.rays.primary_hits += u64::from(depth == 0);
        let surface = self.prims.surface(ray, hit);
        let bounces = self.bounces(ray, &surface, depth, sample);
        sample.rays.add_bounces(&bounces);
        let lights = sample.lights;
        let (mut shadows, mut steps) = (0, Steps::default());
        let color = self.shade_surface(
            ray,
            &surface,
            &bounces,
            &lights,
            &mut |_, shadow| {
                shadows += 1;
                self.blocked(shadow, &mut steps)
            },
            &mut |i, r| self.trace(r, depth + 1, RayKind::secondary(i), sample),
        );
        sample.rays.shadow += shadows;
        if self.count {
            charge(sample.slot, RayKind::Shadow, steps);
        }
        color
    }

    /// The refracted and reflected rays of `ray`'s hit at `surface`; none at the depth limit, and only
    /// the heavier one once `sample` has spent its `SPLIT_BUDGET`. A rough material's mirror
    /// direction is perturbed within a ball of its roughness, drawn from the sample's generator.
    pub fn bounces(&self, ray: &Ray, surface: &Surface, depth: u32, sample: &mut PixelSample) -> Bounces {
        let mut out = self.split(ray, surface, depth, &mut sample.rng);
        if let (Some((_, t)), Some((_, r))) = (out.refracted, out.reflected)
            && sample.rays.budget_spent()
        {
            // On a tie the mirror ray goes on: it is the one a total internal reflection keeps.
            if t > r {
                out.reflected = None;
            } else {
                out.refracted = None;
            }
        }
        out
    }

    /// Both rays a hit spawns, before the split budget.
    fn split(&self, ray: &Ray, surface: &Surface, depth: u32, rng: &mut Sampler) -> Bounces {
        let mut out = Bounces::default();
        if depth >= self.max_depth {
            return out;
        }
        let m = &self.scene.materials[surface.material as usize];
        let (p, ng, ns) = (surface.point, surface.geometric, surface.shading);
        // Fresnel splits light between the mirror and the refracted ray; opaque surfaces reflect Ks.
        let (mut kr, mut total_internal) = (1.0, false);
        if m.transmission > 0.0 {
            let (eta_i, eta_t) = if surface.inside {
                (m.ior, 1.0)
            } else {
                (1.0, m.ior)
            };
            let cos_i = (-ray.dir.dot(ns)).clamp(0.0, 1.0);
            kr = schlick(cos_i, eta_i, eta_t);
            if let Some(t) = refract(ray.dir, ns, eta_i / eta_t) {
                let weight = m.transmission * (1.0 - kr);
                // The SPD's rule 9 counts the refracted ray even where Schlick leaves it nothing (grazing).
                if weight > 0.0 || self.spd {
                    out.refracted = Some((Ray::new(p - EPSILON * ng, t.normalize()), weight));
                }
            } else {
                kr = 1.0;
                total_internal = true;
            }
        }
        let weight = if total_internal && self.spd {
            // The SPD rule: the light that found no way out is all reflected, whatever Ks says.
            m.ks + m.transmission
        } else {
            m.ks * kr
        };
        // The SPD's rules 8 and 9 count a transmitter's mirror ray whatever its Ks (its transmitters
        // are meant to be reflective too): at Ks 0 it is traced with weight 0 and adds nothing.
        if weight > 0.0 || (self.spd && m.transmission > 0.0) {
            let mirror = reflect(ray.dir, ns).normalize();
            let roughness = self.roughness[surface.material as usize];
            let dir = if roughness > 0.0 {
                fuzz(mirror, ng, roughness, rng)
            } else {
                mirror
            };
            out.reflected = Some((Ray::new(p + EPSILON * ng, dir), weight));
        }
        out
    }

    /// Local colour plus the light of `bounces` at `surface`, hit by `ray`. `occluded(i, shadow)` says
    /// whether the shadow ray toward light sample `i` is blocked and `trace(i, ray)` what secondary ray
    /// `i` (0 refracted, 1 reflected) sees: traced there and then, or looked up from packets traced beforehand.
    pub fn shade_surface(
        &self,
        ray: &Ray,
        surface: &Surface,
        bounces: &Bounces,
        lights: &Lights,
        occluded: &mut impl FnMut(usize, &ShadowRay) -> bool,
        trace: &mut impl FnMut(usize, &Ray) -> Vec3,
    ) -> Vec3 {
        let m = &self.scene.materials[surface.material as usize];
        let local = self.local(surface, -ray.dir, m, lights, occluded);
        self.add_bounces(local, surface, bounces, trace)
    }

    /// The colour at `surface` from its `local` colour (the light samples') and what its `bounces`
    /// see (`trace`, as in [`shade_surface`](Self::shade_surface)), absorbed by Beer's law where
    /// the ray crossed a transmitter's interior.
    pub(super) fn add_bounces(
        &self,
        local: Vec3,
        surface: &Surface,
        bounces: &Bounces,
        trace: &mut impl FnMut(usize, &Ray) -> Vec3,
    ) -> Vec3 {
        let mut color = local;
        for (i, bounce) in [bounces.refracted, bounces.reflected].iter().enumerate() {
            if let Some((r, weight)) = bounce {
                color += *weight * trace(i, r);
            }
        }
        self.absorbed(color, surface)
    }

    /// `color` seen at `surface`, absorbed by Beer's law where the ray crossed a transmitter's
    /// interior from its entry point to here.
    #[inline]
    pub(super) fn absorbed(&self, color: Vec3, surface: &Surface) -> Vec3 {
        let m = &self.scene.materials[surface.material as usize];
        if surface.inside && m.transmission > 0.0 {
            color * beer(m.diffuse, surface.t)
        } else {
            color
        }
    }

    /// Whether `material`'s mirror rays are fuzzy ([`fuzz`]: drawn from the sample's generator).
    #[inline]
    pub(super) fn rough(&self, material: MaterialId) -> bool {
        self.roughness[material as usize] > 0.0
    }

    /// Most bounces after the primary hit.
    pub(super) fn max_depth(&self) -> u32 {
        self.max_depth
    }

    /// Whether the SPD's rules apply ([`super::spd`]).
    pub(super) fn spd(&self) -> bool {
        self.spd
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

    /// Blinn-Phong local colour: Σ C_light (Kd·Cd·max(0, n·L) + Ks·Cs·max(0, n·h)^shine), h = |L + V|,
    /// over the light samples whose shadow ray is not blocked.
    fn local(
        &self,
        surface: &Surface,
        v: Vec3,
        m: &Material,
        lights: &Lights,
        occluded: &mut impl FnMut(usize, &ShadowRay) -> bool,
    ) -> Vec3 {
        let (p, ng, ns) = (surface.point, surface.geometric, surface.shading);
        let mut color = Vec3::ZERO;
        for (i, light) in lights.iter().enumerate() {
            let Some(shadow) = ShadowRay::new(p, ng, ns, &light) else {
                continue;
            };
            if occluded(i, &shadow) {
                continue;
            }
            let l = shadow.ray.dir;
            let mut c = m.kd * shadow.n_dot_l * m.diffuse;
            if m.ks > 0.0 {
                let h = (l + v).normalize();
                c += m.ks * h.dot(ns).max(0.0).powf(m.shininess) * m.specular;
            }
            color += light.color * c;
        }
        color
    }
}

/// The closest hit of `ray`, a ray of `kind`, through `verbs`: camera rays by the coherent verb.
#[inline(always)]
fn closest<T: Tally>(verbs: Verbs<'_, '_, T>, ray: &Ray, kind: RayKind, hit: &mut Hit) {
    if kind == RayKind::Camera {
        verbs.intersect_coherent(ray, 0.0, hit);
    } else {
        verbs.intersect(ray, 0.0, hit);
    }
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
