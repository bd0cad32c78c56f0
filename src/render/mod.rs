//! Rendering: camera rays per tile, traced and shaded in parallel, into a linear film.

pub mod camera;
pub mod env;
pub mod film;
pub mod light;
pub mod optics;
mod packets;
pub mod shade;
pub mod tiles;

use glam::Vec3;
use rayon::prelude::*;

use crate::accel::{Accel, Prims};
use crate::scene::Scene;
use camera::RayCamera;
use env::{Background, CubeMap};
use film::Film;
use light::LightSample;
use tiles::{TILE, Tile};

/// How camera rays are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// One ray at a time.
    Single,
    /// Camera rays in packets of 8 (4x2 pixels) through the BVH4's packet kernel, and their hits'
    /// shadow rays in packets per light sample; other accelerators, and the reflected and refracted
    /// rays, go one at a time. The image is identical to `Single`'s.
    Packet,
}

impl std::str::FromStr for Kernel {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "single" => Ok(Kernel::Single),
            "packet" => Ok(Kernel::Packet),
            _ => Err(format!("unknown kernel \"{s}\": expected single or packet")),
        }
    }
}

/// What to render, beyond the scene itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Most bounces after the primary hit; at the limit only the local colour is computed.
    pub max_depth: u32,
    /// Single rays or packets for the camera rays.
    pub kernel: Kernel,
}

impl Options {
    /// The scene's own resolution, 6 bounces.
    pub fn new(scene: &Scene) -> Self {
        Options {
            width: scene.camera.width,
            height: scene.camera.height,
            max_depth: 6,
            kernel: Kernel::Packet,
        }
    }
}

/// Everything a worker needs to shade a pixel, set up once per frame and shared read-only.
pub struct Renderer<'a> {
    scene: &'a Scene,
    prims: Prims<'a>,
    accel: &'a Accel<'a>,
    background: Background,
    camera: RayCamera,
    lights: Vec<LightSample>,
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
        Renderer {
            scene,
            prims: Prims::new(scene),
            accel,
            background,
            camera: RayCamera::new(&scene.camera, options.width, options.height),
            lights: light::regular_samples(scene),
            options,
            warnings,
        }
    }

    /// The colour of pixel `(x, y)`: one ray through its centre.
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        let ray = self.camera.ray(x as f32 + 0.5, y as f32 + 0.5);
        self.trace(&ray, 0)
    }

    /// Renders the frame on the current rayon pool.
    pub fn render(&self) -> Film {
        self.render_with(&|| {})
    }

    /// Renders the frame, calling `on_tile` after each tile (for a progress bar).
    pub fn render_with(&self, on_tile: &(dyn Fn() + Sync)) -> Film {
        let (w, h) = (self.options.width, self.options.height);
        let tiles = tiles::tiles(w, h);
        // Each tile fills a fixed-size buffer on the stack; no allocation per pixel or per ray.
        let done: Vec<(Tile, [Vec3; (TILE * TILE) as usize])> = tiles
            .par_iter()
            .map(|&tile| {
                let mut buf = [Vec3::ZERO; (TILE * TILE) as usize];
                match (self.options.kernel, self.accel) {
                    (Kernel::Packet, Accel::Bvh4(bvh)) => self.tile_packets(bvh, tile, &mut buf),
                    _ => {
                        for y in tile.y0..tile.y1 {
                            for x in tile.x0..tile.x1 {
                                buf[((y - tile.y0) * TILE + (x - tile.x0)) as usize] = self.pixel(x, y);
                            }
                        }
                    }
                }
                on_tile();
                (tile, buf)
            })
            .collect();
        let mut film = Film::new(w, h);
        for (tile, buf) in &done {
            for y in tile.y0..tile.y1 {
                let row = (y * w) as usize;
                let src = ((y - tile.y0) * TILE) as usize;
                let n = (tile.x1 - tile.x0) as usize;
                film.pixels[row + tile.x0 as usize..row + tile.x0 as usize + n]
                    .copy_from_slice(&buf[src..src + n]);
            }
        }
        film
    }
}
