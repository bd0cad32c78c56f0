//! A frame's set-up, as its kernels see it: the integrator, the camera and the sampling, and each
//! pixel sample's camera ray and what it carries (its light points and random numbers). The
//! [`Renderer`](super::Renderer) holds one and hands it to the scheduler and the kernels.
//!
//! At `spp` 0 each pixel gets one ray through its centre and quad lights their regular grids of point
//! lights (the course's model). With `spp` = n² > 0 each pixel averages n × n jittered samples, each
//! with its own lens point (depth of field), its paired, shuffled light point on every quad light (soft
//! shadows) and its own random numbers for fuzzy reflections ([`super::sampler`]); progressive rendering
//! averages passes of one such sample ([`super::progressive`]).

use glam::Vec2;

use super::camera::RayCamera;
use super::env::Background;
use super::options::{Kernel, Options};
use super::sampler::{PixelKey, PixelPattern, Sampler};
use super::stats::{Count, SampleRays};
use super::whitted::{PixelSample, Whitted};
use crate::accel::{Accel, Simd};
use crate::digest::mix;
use crate::scene::{Camera, Scene};

/// What a frame's kernels need: set up once per frame and shared read-only by the workers.
pub(super) struct Setup<'a> {
    pub whitted: Whitted<'a>,
    camera: RayCamera,
    /// Samples per pixel side: n × n per pixel, 0 for one ray through the centre.
    side: u32,
    /// Where a pixel's one ray goes at spp 0, from its top-left corner: 0.5 (its centre), or 0 for
    /// corner rays.
    centre: f32,
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
    /// The image size and the kernel that traces its tiles.
    size: (u32, u32),
    kernel: Kernel,
}

impl<'a> Setup<'a> {
    /// The set-up of a frame of `scene` through `accel` under `options`, seen through `camera`
    /// against `background`.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel<'a>,
        options: &Options,
        camera: &Camera,
        background: Background,
    ) -> Self {
        let whitted = Whitted::new(scene, accel, background, options);
        let camera = if options.spd {
            // Corners 0..=w of a w-pixel-wide image: the camera of the image, rays at whole pixel
            // coordinates.
            RayCamera::new(camera, options.width.max(2) - 1, options.height.max(2) - 1)
        } else {
            RayCamera::new(camera, options.width, options.height)
        };
        let draws = camera.has_lens() || whitted.has_rough_mirrors();
        Setup {
            whitted,
            // At spp 0 the camera rays go through the pixel centres from the eye (a pinhole).
            camera,
            side: options.side(),
            centre: if options.spd { 0.0 } else { 0.5 },
            seed_key: mix(options.seed),
            draws,
            simd: accel.simd().and_then(Simd::new).unwrap_or_else(Simd::detect),
            counting: options.count_steps && accel.counts_steps(),
            size: (options.width, options.height),
            kernel: options.kernel,
        }
    }

    /// The image size.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The kernel that traces the frame's tiles.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// The key of pixel `(x, y)`'s generators.
    #[inline]
    pub fn pixel_key(&self, x: u32, y: u32) -> PixelKey {
        PixelKey::new(
            self.seed_key,
            u64::from(y) * u64::from(self.size.0) + u64::from(x),
        )
    }

    /// The light samples and random numbers of sample `s` of pixel `pixel` in pass `pass` (the light
    /// point `uv` is the sample's paired point of the pattern; unused at spp 0).
    #[inline]
    pub fn pixel_sample<C: Count>(&self, pass: u32, pixel: PixelKey, s: u32, uv: Vec2) -> PixelSample<'_, C> {
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
    pub fn sample_start<C: Count>(
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
    pub fn simd(&self) -> Simd {
        self.simd
    }

    /// Whether the frame counts each ray's steps.
    pub fn counting(&self) -> bool {
        self.counting
    }

    /// The camera, for the kernels' rays.
    pub fn camera(&self) -> &RayCamera {
        &self.camera
    }

    /// Samples per pixel actually taken (at least one).
    pub fn samples(&self) -> u32 {
        (self.side * self.side).max(1)
    }

    /// Fills `pattern` for pixel `(x, y)` in pass `pass`: only where a pixel takes more than one
    /// sample ([`sample_start`](Self::sample_start) draws a single one's numbers itself).
    pub fn fill_pattern(&self, x: u32, y: u32, pass: u32, pattern: &mut PixelPattern) {
        if self.side > 1 {
            pattern.fill(self.side, self.pixel_key(x, y), pass);
        }
    }
}
