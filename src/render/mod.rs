//! Rendering: camera rays per tile, traced and shaded in parallel, into a linear film.
//!
//! At `spp` 0 each pixel gets one ray through its centre and quad lights their regular grids of point
//! lights (the course's model). With `spp` = n² > 0 each pixel averages n × n jittered samples, each
//! with its own lens point (depth of field), its paired, shuffled light point on every quad light (soft
//! shadows) and its own random numbers for fuzzy reflections ([`sampler`]); progressive rendering
//! averages passes of one such sample ([`progressive`]).

pub mod camera;
pub mod env;
pub mod film;
pub mod light;
pub mod optics;
mod options;
mod packets;
pub mod progressive;
pub mod sampler;
pub mod shade;
pub mod tiles;

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::accel::{Accel, Prims};
use crate::geometry::ray::Ray;
use crate::scene::{Camera, QuadLight, Scene};
use camera::RayCamera;
use env::{Background, CubeMap};
use film::Film;
use light::{LightSample, Lights};
use sampler::{PixelPattern, Sampler};
use shade::{PixelSample, RayCounts};
use tiles::{TILE, Tile};

pub use options::{Kernel, Options};

/// Everything a worker needs to shade a pixel, set up once per frame and shared read-only.
pub struct Renderer<'a> {
    scene: &'a Scene,
    prims: Prims<'a>,
    accel: &'a Accel<'a>,
    background: Background,
    camera: RayCamera,
    /// Point lights, and at spp 0 the quad lights' regular grids.
    fixed_lights: Vec<LightSample>,
    /// Quad lights sampled per pixel sample (none at spp 0).
    quads: &'a [QuadLight],
    /// Each material's roughness (the file's, or the options' default).
    roughness: Vec<f32>,
    /// Samples per pixel side: n × n per pixel, 0 for one ray through the centre.
    side: u32,
    options: Options,
    /// What the renderer fell back on (a skybox that did not load, say), for the user to see.
    pub warnings: Vec<String>,
}

impl<'a> Renderer<'a> {
    /// Prepares a frame of `scene` through `accel`.
    pub fn new(scene: &'a Scene, accel: &'a Accel<'a>, options: Options) -> Self {
        let mut warnings = Vec::new();
        let background = match &scene.env {
            Some(dir) if dir.is_dir() => match CubeMap::load(dir) {
                Ok(sky) => Background::sky(scene.background, sky),
                Err(e) => {
                    warnings.push(format!("{e}; using the background colour"));
                    Background::color(scene.background)
                }
            },
            // A missing directory was reported by the loader already.
            _ => Background::color(scene.background),
        };
        Self::assemble(scene, accel, options, &scene.camera, background, warnings)
    }

    /// A renderer of the same scene and background, seen through `camera` instead of the scene's, with
    /// `accel` and `options`: for a viewer that renders again at every camera move or change of
    /// setting, without reading the skybox from disk each time as [`Renderer::new`] does (the clone
    /// shares its images). `accel` may live shorter than `self`. Its warnings are about `options` and
    /// `camera` only.
    pub fn with_view<'b>(&self, camera: &Camera, accel: &'b Accel<'b>, options: Options) -> Renderer<'b>
    where
        'a: 'b,
    {
        let background = self.background.clone();
        Renderer::assemble(self.scene, accel, options, camera, background, Vec::new())
    }

    /// Quad lights as their regular grids of point lights whatever the samples per pixel, as at spp 0:
    /// hard-edged, banded shadows without noise (the viewer's soft-shadow switch).
    pub fn with_regular_lights(mut self) -> Self {
        self.fixed_lights = light::regular_samples(self.scene);
        self.quads = &[];
        self
    }

    /// The renderer of `scene` through `camera`, with the background loaded and the warnings so far.
    fn assemble(
        scene: &'a Scene,
        accel: &'a Accel<'a>,
        options: Options,
        camera: &Camera,
        background: Background,
        mut warnings: Vec<String>,
    ) -> Self {
        let side = (options.spp as f64).sqrt().ceil() as u32;
        if side * side != options.spp {
            warnings.push(format!(
                "{} samples per pixel is not a square: taking {side} x {side} = {}",
                options.spp,
                side * side
            ));
        }
        if side == 0 && camera.aperture > 0.0 {
            warnings.push(
                "depth of field needs samples (spp 1 or more): rendering through a pinhole".to_string(),
            );
        }
        // At spp 0 the camera rays go through the pixel centres from the eye (a pinhole).
        let camera = RayCamera::new(camera, options.width, options.height);
        let (fixed_lights, quads) = if side == 0 {
            (light::regular_samples(scene), &[][..])
        } else {
            (light::point_samples(scene), &scene.area_lights[..])
        };
        Renderer {
            scene,
            prims: Prims::new(scene),
            accel,
            background,
            camera,
            fixed_lights,
            quads,
            roughness: scene
                .materials
                .iter()
                .map(|m| m.roughness.unwrap_or(options.roughness))
                .collect(),
            side,
            options,
            warnings,
        }
    }

    /// The image size.
    pub fn size(&self) -> (u32, u32) {
        (self.options.width, self.options.height)
    }

    /// The light samples and random numbers of sample `s` of pixel `index` in pass `pass` (the light
    /// point `uv` is the sample's paired point of the pattern; unused at spp 0).
    fn pixel_sample(&self, pass: u32, index: u64, s: u32, uv: Vec2) -> PixelSample<'_> {
        PixelSample {
            lights: Lights::new(&self.fixed_lights, self.quads, uv),
            rng: Sampler::new(self.options.seed, pass, index, 1 + s),
            rays: RayCounts::default(),
        }
    }

    /// Sample `s` of pixel `(x, y)`: its camera ray and what it carries (the pattern must be the
    /// pixel's, filled for this pass).
    fn camera_sample(
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
                self.camera.ray(x + 0.5, y + 0.5),
                self.pixel_sample(pass, index, 0, Vec2::splat(0.5)),
            );
        }
        let (p, uv) = (pattern.pixel[s as usize], pattern.light[s as usize]);
        let mut sample = self.pixel_sample(pass, index, s, uv);
        // The lens point is drawn even for a pinhole, so that a sample's random numbers do not depend
        // on the camera.
        let lens = sample.rng.in_unit_disc();
        (self.camera.lens_ray(x + p.x, y + p.y, lens), sample)
    }

    /// Samples per pixel actually taken (at least one).
    fn samples(&self) -> u32 {
        (self.side * self.side).max(1)
    }

    /// Fills `pattern` for pixel `(x, y)` in pass `pass` (nothing to fill at spp 0).
    fn fill_pattern(&self, x: u32, y: u32, pass: u32, pattern: &mut PixelPattern) {
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
            sum += self.trace(&ray, 0, &mut sample);
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
        self.trace(ray, 0, &mut self.pixel_sample(1, 0, 0, Vec2::splat(0.5)))
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
        let mut film = Film::new(w, h);
        let rays = self.render_tiles(pass, &tiles::tiles(w, h), on_tile, stop, |_, tile, buf| {
            for y in tile.y0..tile.y1 {
                let row = (y * w) as usize;
                let src = ((y - tile.y0) * TILE) as usize;
                let n = (tile.x1 - tile.x0) as usize;
                film.pixels[row + tile.x0 as usize..row + tile.x0 as usize + n]
                    .copy_from_slice(&buf[src..src + n]);
            }
        })?;
        Some((film, rays))
    }

    /// Renders pass `pass` of `tiles` only (a part of the frame), in parallel, then hands each tile's
    /// pixels to `sink` in the order of `tiles`, as `(index in tiles, tile, pixels)` with the pixels
    /// row-major at a stride of [`TILE`]. A pixel's colour depends only on the seed, the pixel and the
    /// pass, so any split of the tiles renders the same pixels. `on_tile` and `stop` are as for
    /// [`Renderer::render_pass`]; `None` if stopped, and then `sink` has seen nothing.
    pub fn render_tiles(
        &self,
        pass: u32,
        tiles: &[Tile],
        on_tile: &(dyn Fn() + Sync),
        stop: &AtomicBool,
        mut sink: impl FnMut(usize, Tile, &[Vec3]),
    ) -> Option<RayCounts> {
        // Each tile fills a fixed-size buffer; the sample pattern is allocated once per tile and
        // reused, so nothing is allocated per pixel or per ray.
        type Done = (Tile, [Vec3; (TILE * TILE) as usize], RayCounts);
        let done: Option<Vec<Done>> = tiles
            .par_iter()
            .map(|&tile| {
                if stop.load(Ordering::Relaxed) {
                    return None;
                }
                let mut buf = [Vec3::ZERO; (TILE * TILE) as usize];
                let mut rays = RayCounts::default();
                match (self.options.kernel, self.accel) {
                    (Kernel::Packet, Accel::Bvh4(bvh)) => {
                        self.tile_packets(bvh, tile, pass, &mut buf, &mut rays)
                    }
                    (Kernel::Packet, Accel::Bvh8(bvh)) => {
                        self.tile_packets(bvh, tile, pass, &mut buf, &mut rays)
                    }
                    _ => {
                        let mut pattern = PixelPattern::default();
                        for y in tile.y0..tile.y1 {
                            for x in tile.x0..tile.x1 {
                                buf[((y - tile.y0) * TILE + (x - tile.x0)) as usize] =
                                    self.pixel_in_pass(x, y, pass, &mut pattern, &mut rays);
                            }
                        }
                    }
                }
                on_tile();
                Some((tile, buf, rays))
            })
            .collect();
        let mut rays = RayCounts::default();
        for (i, (tile, buf, tile_rays)) in done?.iter().enumerate() {
            rays += *tile_rays;
            sink(i, *tile, buf);
        }
        Some(rays)
    }
}
