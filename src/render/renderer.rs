//! A frame's set-up: the [`Renderer`] holds the integrator, the camera and the sampling options, and
//! makes each pixel sample's camera ray and what it carries; the kernels (`super::kernel`) trace them
//! and `super::frame` schedules the tiles.
//!
//! At `spp` 0 each pixel gets one ray through its centre and quad lights their regular grids of point
//! lights (the course's model). With `spp` = n² > 0 each pixel averages n × n jittered samples, each
//! with its own lens point (depth of field), its paired, shuffled light point on every quad light (soft
//! shadows) and its own random numbers for fuzzy reflections ([`super::sampler`]); progressive rendering
//! averages passes of one such sample ([`super::progressive`]).

use glam::{Vec2, Vec3};

use super::camera::RayCamera;
use super::env::Background;
use super::options::Options;
use super::sampler::{PixelKey, PixelPattern, Sampler};
use super::stats::{Count, RayKind, SampleRays};
use super::whitted::{PixelSample, Whitted};
use crate::accel::{Accel, Plain, Simd};
use crate::digest::mix;
use crate::geometry::ray::Ray;
use crate::scene::{Camera, Scene};

/// A frame: the integrator, the camera, the samples per pixel and the options; set up once per frame
/// and shared read-only by the workers.
pub struct Renderer<'a> {
    pub(super) whitted: Whitted<'a>,
    camera: RayCamera,
    /// Samples per pixel side: n × n per pixel, 0 for one ray through the centre.
    side: u32,
    /// Where a pixel's one ray goes at spp 0, from its top-left corner: 0.5 (its centre), or 0 for
    /// corner rays.
    centre: f32,
    pub(super) options: Options,
    /// The seed, mixed once for every pixel's generators ([`PixelKey`]).
    seed_key: u64,
    /// Whether a pixel sample's own generator is ever drawn from (a lens, or a rough mirror): where it
    /// is not, it is not seeded either, and the image is the same.
    draws: bool,
    /// The instruction set the packet kernel's tiles run on: the wide BVH's, else the CPU's best.
    simd: Simd,
    /// Whether the frame counts each ray's steps: asked for ([`Options::count_steps`]) and counted by
    /// the accelerator ([`Accel::counts_steps`]).
    counting: bool,
    /// What the renderer fell back on (a skybox that did not load, say), for the user to see.
    pub warnings: Vec<String>,
}

impl<'a> Renderer<'a> {
    /// Prepares a frame of `scene` through `accel`, its skybox read from disk ([`Background::load`]).
    pub fn new(scene: &'a Scene, accel: &'a Accel<'a>, options: Options) -> Self {
        let (background, warning) = Background::load(scene);
        let mut renderer = Renderer::with_view(scene, accel, options, &scene.camera, background);
        renderer.warnings.splice(0..0, warning);
        renderer
    }

    /// A frame of `scene` through `accel`, seen through `camera` instead of the scene's, against
    /// `background`: for a viewer that renders again at every camera move or change of setting and
    /// reads the skybox once (clones of a background share its images). Its warnings are about
    /// `options` and `camera`.
    pub fn with_view(
        scene: &'a Scene,
        accel: &'a Accel<'a>,
        options: Options,
        camera: &Camera,
        background: Background,
    ) -> Self {
        let mut warnings = Vec::new();
        let side = options.side();
        if options.spp_taken() != options.spp {
            warnings.push(format!(
                "{} samples per pixel is not a square: taking {side} x {side} = {}",
                options.spp,
                options.spp_taken()
            ));
        }
        if side == 0 && camera.aperture > 0.0 {
            warnings.push(
                "depth of field needs samples (spp 1 or more): rendering through a pinhole".to_string(),
            );
        }
        let whitted = Whitted::new(
            scene,
            accel,
            background,
            side > 0,
            options.max_depth,
            options.roughness,
            options.spd,
        );
        let camera = if options.spd {
            // Corners 0..=w of a w-pixel-wide image: the camera of the image, rays at whole pixel
            // coordinates.
            RayCamera::new(camera, options.width.max(2) - 1, options.height.max(2) - 1)
        } else {
            RayCamera::new(camera, options.width, options.height)
        };
        let draws = camera.has_lens() || whitted.has_rough_mirrors();
        Renderer {
            whitted,
            // At spp 0 the camera rays go through the pixel centres from the eye (a pinhole).
            camera,
            side,
            centre: if options.spd { 0.0 } else { 0.5 },
            seed_key: mix(options.seed),
            draws,
            simd: accel.simd().and_then(Simd::new).unwrap_or_else(Simd::detect),
            counting: options.count_steps && accel.counts_steps(),
            options,
            warnings,
        }
    }

    /// Quad lights as their regular grids of point lights whatever the samples per pixel, as at spp 0:
    /// hard-edged, banded shadows without noise (the viewer's soft-shadow switch).
    pub fn with_regular_lights(mut self) -> Self {
        self.whitted = self.whitted.with_regular_lights();
        self
    }

    /// The image size.
    pub fn size(&self) -> (u32, u32) {
        (self.options.width, self.options.height)
    }

    /// The key of pixel `(x, y)`'s generators.
    #[inline]
    pub(super) fn pixel_key(&self, x: u32, y: u32) -> PixelKey {
        PixelKey::new(
            self.seed_key,
            u64::from(y) * u64::from(self.options.width) + u64::from(x),
        )
    }

    /// The light samples and random numbers of sample `s` of pixel `pixel` in pass `pass` (the light
    /// point `uv` is the sample's paired point of the pattern; unused at spp 0).
    #[inline]
    pub(super) fn pixel_sample<C: Count>(
        &self,
        pass: u32,
        pixel: PixelKey,
        s: u32,
        uv: Vec2,
    ) -> PixelSample<'_, C> {
        PixelSample {
            lights: self.whitted.lights(uv),
            rng: if self.draws {
                Sampler::of_pixel(pixel, pass, 1 + s)
            } else {
                Sampler::unused()
            },
            rays: SampleRays::default(),
            steps: C::Steps::default(),
        }
    }

    /// Sample `s` of pixel `(x, y)` up to its camera ray: the image point the ray passes through, the
    /// lens point it leaves from (`None`: the pinhole's ray, which the packet kernel computes eight
    /// at a time) and what the sample carries. `pattern` must be the pixel's, filled for this pass
    /// ([`fill_pattern`](Self::fill_pattern)); at one sample a pixel it is not read.
    #[inline]
    pub(super) fn sample_start<C: Count>(
        &self,
        x: u32,
        y: u32,
        pass: u32,
        s: u32,
        pattern: &PixelPattern,
    ) -> (Vec2, Option<Vec2>, PixelSample<'_, C>) {
        let key = self.pixel_key(x, y);
        let corner = Vec2::new(x as f32, y as f32);
        if self.side == 0 {
            let sample = self.pixel_sample(pass, key, 0, Vec2::splat(0.5));
            return (corner + self.centre, None, sample);
        }
        let (p, uv) = match self.side {
            1 => PixelPattern::single(key, pass, self.whitted.samples_quads()),
            _ => (pattern.pixel[s as usize], pattern.light[s as usize]),
        };
        let mut sample = self.pixel_sample(pass, key, s, uv);
        // The lens point's two numbers are drawn even for a pinhole (where a rough mirror draws
        // later), so that a sample's later random numbers do not depend on the camera; only a lens
        // maps them onto the disc (its sine and cosine would cost a pinhole ray: profiles/README.md).
        let lens = if self.camera.has_lens() {
            Some(sample.rng.in_unit_disc())
        } else {
            if self.draws {
                sample.rng.next2();
            }
            None
        };
        (corner + p, lens, sample)
    }

    /// The instruction set the packet kernel's tiles run on.
    pub(super) fn simd(&self) -> Simd {
        self.simd
    }

    /// Whether the frame counts each ray's steps.
    pub(super) fn counting(&self) -> bool {
        self.counting
    }

    /// The camera, for the kernels' rays.
    pub(super) fn camera(&self) -> &RayCamera {
        &self.camera
    }

    /// Samples per pixel actually taken (at least one).
    pub(super) fn samples(&self) -> u32 {
        (self.side * self.side).max(1)
    }

    /// Fills `pattern` for pixel `(x, y)` in pass `pass`: only where a pixel takes more than one
    /// sample ([`sample_start`](Self::sample_start) draws a single one's numbers itself).
    pub(super) fn fill_pattern(&self, x: u32, y: u32, pass: u32, pattern: &mut PixelPattern) {
        if self.side > 1 {
            pattern.fill(self.side, self.pixel_key(x, y), pass);
        }
    }

    /// What `ray` sees from the eye (depth 0), with the first sample's light points and random numbers
    /// of pixel 0: for probing the shading with rays of one's own.
    pub fn radiance(&self, ray: &Ray) -> Vec3 {
        self.whitted.trace(
            ray,
            0,
            RayKind::Camera,
            &mut self.pixel_sample::<Plain>(1, self.pixel_key(0, 0), 0, Vec2::splat(0.5)),
        )
    }
}
