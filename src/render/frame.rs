//! What drives a frame: tiles on rayon, the pixels of each tile, the samples of each pixel (jittered
//! positions, lens points, paired light points, their random numbers) and passes; each camera ray is
//! handed to the Whitted integrator ([`super::whitted`]), one at a time or, with [`Kernel::Packet`], as
//! packets of eight neighbouring pixels ([`super::packets`]).
//!
//! At `spp` 0 each pixel gets one ray through its centre and quad lights their regular grids of point
//! lights (the course's model). With `spp` = n² > 0 each pixel averages n × n jittered samples, each
//! with its own lens point (depth of field), its paired, shuffled light point on every quad light (soft
//! shadows) and its own random numbers for fuzzy reflections ([`super::sampler`]); progressive rendering
//! averages passes of one such sample ([`super::progressive`]).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::camera::RayCamera;
use super::env::Background;
use super::film::Film;
use super::options::{Kernel, Options};
use super::packets::PerRay;
use super::sampler::{PixelPattern, Sampler};
use super::streams::{STREAM_TILES, StreamBuffers};
use super::tiles::{self, TILE, Tile};
use super::whitted::{PixelSample, RayCounts, Whitted};
use crate::accel::Accel;
use crate::accel::packet::{PACKET, bits};
use crate::geometry::ray::Ray;
use crate::scene::{Camera, Scene};

/// Packet width in pixels (and `PACKET / PACKET_W` rows).
const PACKET_W: u32 = 4;

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
    options: Options,
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
        Renderer {
            whitted,
            // At spp 0 the camera rays go through the pixel centres from the eye (a pinhole).
            camera: if options.spd {
                // Corners 0..=w of a w-pixel-wide image: the camera of the image, rays at whole
                // pixel coordinates.
                RayCamera::new(camera, options.width.max(2) - 1, options.height.max(2) - 1)
            } else {
                RayCamera::new(camera, options.width, options.height)
            },
            side,
            centre: if options.spd { 0.0 } else { 0.5 },
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

    /// The light samples and random numbers of sample `s` of pixel `index` in pass `pass` (the light
    /// point `uv` is the sample's paired point of the pattern; unused at spp 0).
    pub(super) fn pixel_sample(&self, pass: u32, index: u64, s: u32, uv: Vec2) -> PixelSample<'_> {
        PixelSample {
            lights: self.whitted.lights(uv),
            rng: Sampler::new(self.options.seed, pass, index, 1 + s),
            rays: RayCounts::default(),
        }
    }

    /// Sample `s` of pixel `(x, y)`: its camera ray and what it carries (the pattern must be the
    /// pixel's, filled for this pass).
    pub(super) fn camera_sample(
        &self,
        x: u32,
        y: u32,
        pass: u32,
        s: u32,
        pattern: &PixelPattern,
    ) -> (Ray, PixelSample<'_>) {
        let index = u64::from(y) * u64::from(self.options.width) + u64::from(x);
        let (x, y) = (x as f32, y as f32);
        if self.side == 0 {
            return (
                self.camera.ray(x + self.centre, y + self.centre),
                self.pixel_sample(pass, index, 0, Vec2::splat(0.5)),
            );
        }
        let (p, uv) = (pattern.pixel[s as usize], pattern.light[s as usize]);
        let mut sample = self.pixel_sample(pass, index, s, uv);
        // The lens point's two numbers are drawn even for a pinhole, so that a sample's later random
        // numbers do not depend on the camera; only a lens maps them onto the disc (the map's sine
        // and cosine were a third of a pinhole camera ray's instructions: profiles/frame.txt).
        let lens = if self.camera.has_lens() {
            sample.rng.in_unit_disc()
        } else {
            sample.rng.next2();
            Vec2::ZERO
        };
        (self.camera.lens_ray(x + p.x, y + p.y, lens), sample)
    }

    /// Samples per pixel actually taken (at least one).
    pub(super) fn samples(&self) -> u32 {
        (self.side * self.side).max(1)
    }

    /// Fills `pattern` for pixel `(x, y)` in pass `pass` (nothing to fill at spp 0).
    pub(super) fn fill_pattern(&self, x: u32, y: u32, pass: u32, pattern: &mut PixelPattern) {
        if self.side > 0 {
            let index = u64::from(y) * u64::from(self.options.width) + u64::from(x);
            pattern.fill(self.side, self.options.seed, pass, index);
        }
    }

    /// The colour of pixel `(x, y)` in pass `pass`: the mean of its samples, traced one by one; the rays
    /// are counted into `rays`.
    fn pixel_in_pass(
        &self,
        x: u32,
        y: u32,
        pass: u32,
        pattern: &mut PixelPattern,
        rays: &mut RayCounts,
    ) -> Vec3 {
        self.fill_pattern(x, y, pass, pattern);
        let mut sum = Vec3::ZERO;
        for s in 0..self.samples() {
            let (ray, mut sample) = self.camera_sample(x, y, pass, s, pattern);
            sum += self.whitted.trace(&ray, 0, &mut sample);
            sample.rays.primary += 1;
            *rays += sample.rays;
        }
        sum / self.samples() as f32
    }

    /// The colour of pixel `(x, y)` (first pass).
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        self.pixel_in_pass(x, y, 1, &mut PixelPattern::default(), &mut RayCounts::default())
    }

    /// What `ray` sees from the eye (depth 0), with the first sample's light points and random numbers
    /// of pixel 0: for probing the shading with rays of one's own.
    pub fn radiance(&self, ray: &Ray) -> Vec3 {
        self.whitted
            .trace(ray, 0, &mut self.pixel_sample(1, 0, 0, Vec2::splat(0.5)))
    }

    /// Renders the frame (pass 1) on the current rayon pool.
    pub fn render(&self) -> Film {
        let never = AtomicBool::new(false);
        self.render_pass(1, &|| {}, &never).expect("not stopped").0
    }

    /// Renders pass `pass` (from 1; each pass draws its own random numbers), calling `on_tile` after
    /// each tile (for a progress bar), and counts the rays it traced. Returns `None`, promptly and with
    /// nothing half-done handed out, once `stop` is set.
    pub fn render_pass(
        &self,
        pass: u32,
        on_tile: &(dyn Fn() + Sync),
        stop: &AtomicBool,
    ) -> Option<(Film, RayCounts)> {
        let (w, h) = (self.options.width, self.options.height);
        let rendered = self.render_tiles(pass, &tiles::tiles(w, h), on_tile, stop);
        if !rendered.is_complete() {
            return None;
        }
        let mut film = Film::new(w, h);
        rendered.for_each(|tile, buf| {
            for y in tile.y0..tile.y1 {
                let row = (y * w) as usize;
                let src = ((y - tile.y0) * TILE) as usize;
                let n = (tile.x1 - tile.x0) as usize;
                film.pixels[row + tile.x0 as usize..row + tile.x0 as usize + n]
                    .copy_from_slice(&buf[src..src + n]);
            }
        });
        Some((film, rendered.rays()))
    }

    /// Renders pass `pass` of `tiles` only (a part of the frame), in parallel. A pixel's colour depends
    /// only on the seed, the pixel and the pass, so any split of the tiles renders the same pixels.
    /// `on_tile` is as for [`Renderer::render_pass`]; once `stop` is set, the tiles not yet started are
    /// skipped and the [`TilePass`] holds the ones finished, for a caller that keeps them.
    pub fn render_tiles(
        &self,
        pass: u32,
        tiles: &[Tile],
        on_tile: &(dyn Fn() + Sync),
        stop: &AtomicBool,
    ) -> TilePass {
        // Each tile fills a fixed-size buffer; the sample pattern is allocated once per tile and
        // reused, so nothing is allocated per pixel or per ray.
        //
        // One tile per rayon job (`with_max_len(1)`): tiles differ in cost by orders of magnitude (the
        // dragon's glass and metal against empty sky), and rayon's adaptive split otherwise stops
        // splitting after a few levels, leaving a worker folding a long run of expensive tiles that no
        // idle worker can steal. Measured on dragon.p3f, 2 threads: 224 ms a frame with the adaptive
        // split, as slow as giving each thread a fixed half of the image, and 160 ms with one tile a
        // job, as fast as two threads on interleaved tiles (one thread: 315 ms).
        let tiles = match self.options.kernel {
            Kernel::Stream => self.stream_tiles(pass, tiles, on_tile, stop),
            kernel => tiles
                .par_iter()
                .with_max_len(1)
                .map(|&tile| {
                    if stop.load(Ordering::Relaxed) {
                        return None;
                    }
                    let mut buf = [Vec3::ZERO; (TILE * TILE) as usize];
                    let mut rays = RayCounts::default();
                    if kernel == Kernel::Packet {
                        self.tile_packets(tile, pass, &mut buf, &mut rays);
                    } else {
                        let mut pattern = PixelPattern::default();
                        for y in tile.y0..tile.y1 {
                            for x in tile.x0..tile.x1 {
                                buf[((y - tile.y0) * TILE + (x - tile.x0)) as usize] =
                                    self.pixel_in_pass(x, y, pass, &mut pattern, &mut rays);
                            }
                        }
                    }
                    on_tile();
                    Some((tile, buf, rays))
                })
                .collect(),
        };
        TilePass { tiles }
    }

    /// [`Renderer::render_tiles`] with [`Kernel::Stream`]: [`STREAM_TILES`] tiles a rayon job, traced
    /// together as streams, each worker with its own buffers kept from job to job.
    fn stream_tiles(
        &self,
        pass: u32,
        tiles: &[Tile],
        on_tile: &(dyn Fn() + Sync),
        stop: &AtomicBool,
    ) -> Vec<Option<TileDone>> {
        thread_local! {
            static BUFFERS: RefCell<StreamBuffers> = RefCell::default();
        }
        let done: Vec<Vec<Option<TileDone>>> = tiles
            .par_chunks(STREAM_TILES)
            .with_max_len(1)
            .map(|set| {
                if stop.load(Ordering::Relaxed) {
                    return vec![None; set.len()];
                }
                let mut bufs = vec![[Vec3::ZERO; (TILE * TILE) as usize]; set.len()];
                let mut counts = vec![RayCounts::default(); set.len()];
                BUFFERS.with_borrow_mut(|b| self.tiles_streamed(set, pass, &mut bufs, &mut counts, b));
                set.iter()
                    .zip(bufs)
                    .zip(counts)
                    .map(|((&tile, buf), rays)| {
                        on_tile();
                        Some((tile, buf, rays))
                    })
                    .collect()
            })
            .collect();
        done.into_iter().flatten().collect()
    }

    /// Shades `tile` for pass `pass`, packet by packet (pixels outside the image are inactive lanes),
    /// into `buf`: sample `s` of eight pixels at a time, each lane with its pixel's own pattern and
    /// random numbers, summed per pixel in sample order as the single-ray path sums them.
    fn tile_packets(
        &self,
        tile: Tile,
        pass: u32,
        buf: &mut [Vec3; (TILE * TILE) as usize],
        rays_traced: &mut RayCounts,
    ) {
        let h = PACKET as u32 / PACKET_W;
        let mut patterns: PerRay<PixelPattern> = Default::default();
        for y0 in (tile.y0..tile.y1).step_by(h as usize) {
            for x0 in (tile.x0..tile.x1).step_by(PACKET_W as usize) {
                let pixel = |k: usize| (x0 + k as u32 % PACKET_W, y0 + k as u32 / PACKET_W);
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
                        sample
                    });
                    let colors = self.whitted.shade_packet(&rays, active, 0, &mut samples);
                    for k in bits(active) {
                        sums[k] += colors[k];
                        samples[k].rays.primary += 1;
                        *rays_traced += samples[k].rays;
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

/// A tile's pixels, row-major at a stride of [`TILE`], and the rays they took.
type TileDone = (Tile, [Vec3; (TILE * TILE) as usize], RayCounts);

/// A pass over some tiles as [`Renderer::render_tiles`] left it: every tile's pixels, or, if it was
/// stopped, those of the tiles finished before the stop (so that an interrupted render can keep them).
#[derive(Debug)]
pub struct TilePass {
    /// Per tile asked for, in order: its pixels, or `None` if the stop skipped it.
    tiles: Vec<Option<TileDone>>,
}

impl TilePass {
    /// Whether every tile was rendered (the pass was not stopped, or stopped after its last tile).
    pub fn is_complete(&self) -> bool {
        self.tiles.iter().all(Option::is_some)
    }

    /// Whether each tile asked for was rendered, in order.
    pub fn finished(&self) -> impl Iterator<Item = bool> + '_ {
        self.tiles.iter().map(Option::is_some)
    }

    /// The rays the finished tiles traced.
    pub fn rays(&self) -> RayCounts {
        let mut rays = RayCounts::default();
        for (_, _, r) in self.tiles.iter().flatten() {
            rays += *r;
        }
        rays
    }

    /// Hands each finished tile and its pixels (row-major at a stride of [`TILE`]) to `sink`, in the
    /// order the tiles were asked for.
    pub fn for_each(&self, mut sink: impl FnMut(Tile, &[Vec3])) {
        for (tile, buf, _) in self.tiles.iter().flatten() {
            sink(*tile, buf);
        }
    }
}
