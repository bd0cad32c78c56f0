//! The [`Renderer`]: a frame of a scene through an accelerator under [`Options`], rendered whole, by
//! passes or by tiles. Its set-up (`super::setup`: the integrator, the camera, the sampling) is made
//! once; `super::frame` schedules its tiles on rayon and the kernels (`super::kernel`) trace them.

use std::sync::atomic::AtomicBool;

use super::env::Background;
use super::frame::{self, TilePass};
use super::options::Options;
use super::setup::Setup;
use super::stats::RayCounts;
use super::tiles::Tile;
use crate::accel::Accel;
use crate::image::Film;
use crate::scene::{Camera, Scene};

/// A frame: its set-up, made once per frame and shared read-only by the workers.
pub struct Renderer<'a> {
    setup: Setup<'a>,
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
        Renderer {
            setup: Setup::new(scene, accel, &options, camera, background),
            warnings,
        }
    }

    /// Quad lights as their regular grids of point lights whatever the samples per pixel, as at spp 0:
    /// hard-edged, banded shadows without noise (the viewer's soft-shadow switch).
    pub fn with_regular_lights(mut self) -> Self {
        self.setup.whitted = self.setup.whitted.with_regular_lights();
        self
    }

    /// The image size.
    pub fn size(&self) -> (u32, u32) {
        self.setup.size()
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
        frame::render_pass(&self.setup, pass, on_tile, stop)
    }

    /// Renders pass `pass` of `tiles` only (a part of the frame), in parallel. A pixel's colour depends
    /// only on the seed, the pixel and the pass, so any split of the tiles renders the same pixels.
    /// `on_tile` is as for [`Renderer::render_pass`]; once `stop` is set, the tiles not yet finished
    /// are left (a tile being rendered within a pixel or block) and the [`TilePass`] holds the ones
    /// finished, for a caller that keeps them.
    pub fn render_tiles(
        &self,
        pass: u32,
        tiles: &[Tile],
        on_tile: &(dyn Fn() + Sync),
        stop: &AtomicBool,
    ) -> TilePass {
        frame::render_tiles(&self.setup, pass, tiles, on_tile, stop)
    }
}

/// Test hooks (the `kit` feature): probing the shading pixel by pixel and with rays of one's own.
#[cfg(feature = "kit")]
impl Renderer<'_> {
    /// The colour of pixel `(x, y)` (first pass), traced by the single-ray kernel.
    pub fn pixel(&self, x: u32, y: u32) -> glam::Vec3 {
        super::kernel::Single::pixel(&self.setup, x, y)
    }

    /// What `ray` sees from the eye (depth 0), with the first sample's light points and random numbers
    /// of pixel 0.
    pub fn radiance(&self, ray: &crate::geometry::ray::Ray) -> glam::Vec3 {
        let key = self.setup.pixel_key(0, 0);
        let mut sample = self
            .setup
            .pixel_sample::<crate::accel::Plain>(1, key, 0, glam::Vec2::splat(0.5));
        self.setup
            .whitted
            .trace(ray, 0, super::RayKind::Camera, &mut sample)
    }
}
