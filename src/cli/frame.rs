//! The argument groups several subcommands share (the frame, the camera overrides, the BVH2 builder)
//! and the render options they make of a scene.

use clap::Args;
use glam::Vec3;
use whitted::accel::{AccelKind, BuildOptions, bvh2};
use whitted::render::{Kernel, MAX_SPP, Options, spd};
use whitted::scene::{Camera, MAX_RESOLUTION, Scene};

use super::values::{angle, point};

/// The bounce limit when `--max-depth` is not given.
pub use whitted::render::DEFAULT_DEPTH;

/// The frame's size, the threads and the structure and kernel that trace it (`render`, `bench`, `view`).
#[derive(Args)]
pub struct FrameArgs {
    /// Image width, 1 to 65536, or 65535 for the viewer's window (keeps the vertical field of view; the
    /// height follows the aspect ratio if not given).
    #[arg(long, value_parser = side(), allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Image height, 1 to 65536, or 65535 for the viewer's window.
    #[arg(long, value_parser = side(), allow_negative_numbers = true)]
    pub height: Option<u32>,
    /// Worker threads, 1 to 1024 (default: all cores).
    #[arg(long, value_parser = clap::builder::RangedI64ValueParser::<usize>::new().range(1..=1024),
          allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Acceleration structure: none, grid, bvh2, bvh4, bvh8 (8-wide nodes, AVX2 where the CPU has it),
    /// auto (bvh8 on CPUs with AVX2, else bvh4) or embree (Embree 3; builds with `--features embree`).
    #[arg(long, default_value = "auto")]
    pub accel: AccelKind,
    /// Rays one at a time (single) or in packets of 8 neighbouring pixels (packet, BVH4 and BVH8); same
    /// image.
    #[arg(long, default_value = "packet")]
    pub kernel: Kernel,
}

impl FrameArgs {
    /// The scene's options at the size asked for, with `max_depth` bounces and the kernel asked for.
    pub fn options(&self, scene: &Scene, max_depth: u32) -> Options {
        let (width, height) = resolution(scene, self.width, self.height);
        Options {
            width,
            height,
            max_depth,
            kernel: self.kernel,
            ..Options::new(scene)
        }
    }
}

/// The parser of an image side: 1 to [`MAX_RESOLUTION`].
fn side() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=MAX_RESOLUTION as i64)
}

/// The parser of `--spp`: 0 to [`MAX_SPP`].
pub fn spp() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(0..=MAX_SPP as i64)
}

/// The resolution after `--width`/`--height`: one given alone keeps the file's aspect ratio. It is
/// checked with the rest of the [`Options`] it goes into.
fn resolution(scene: &Scene, width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let (fw, fh) = (scene.camera.width as u64, scene.camera.height as u64);
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, ((w as u64 * fh).div_ceil(fw)).min(u32::MAX as u64) as u32),
        (None, Some(h)) => (((h as u64 * fw).div_ceil(fh)).min(u32::MAX as u64) as u32, h),
        (None, None) => (fw as u32, fh as u32),
    }
}

/// Where the camera is and looks, over the scene file's (`render`, `bench`). Points are `X,Y,Z`: one
/// word, so that a printed command line needs no quotes.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct CameraArgs {
    /// The eye position, `X,Y,Z` (overrides the file's `from`).
    #[arg(long, value_name = "X,Y,Z", value_parser = point, allow_hyphen_values = true)]
    pub from: Option<Vec3>,
    /// The point looked at, seen at the image centre, `X,Y,Z` (overrides `at`).
    #[arg(long, value_name = "X,Y,Z", value_parser = point, allow_hyphen_values = true)]
    pub at: Option<Vec3>,
    /// The up vector, `X,Y,Z` (overrides `up`).
    #[arg(long, value_name = "X,Y,Z", value_parser = point, allow_hyphen_values = true)]
    pub up: Option<Vec3>,
    /// The vertical field of view in degrees, edge to edge, between 0 and 180 (overrides `angle`).
    #[arg(long, value_name = "DEG", value_parser = angle, allow_hyphen_values = true)]
    pub fov: Option<f32>,
}

impl CameraArgs {
    /// Puts the overrides into `camera` and checks the camera they make, with its own message (the
    /// file's camera was checked when it was read: without overrides there is nothing new to check).
    pub fn apply(&self, camera: &mut Camera) -> whitted::Result<()> {
        if *self == CameraArgs::default() {
            return Ok(());
        }
        camera.from = self.from.unwrap_or(camera.from);
        camera.at = self.at.unwrap_or(camera.at);
        camera.up = self.up.unwrap_or(camera.up);
        camera.fov_y = self.fov.unwrap_or(camera.fov_y);
        camera
            .validate()
            .map_err(|e| whitted::Error::msg(format!("the camera of --from/--at/--up/--fov: {e}")))
    }
}

/// How the BVHs are built, as a command-line value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BuildKind {
    /// The best build within twice Embree's medium build time: today `optimized`.
    Auto,
    /// Binned surface area heuristic.
    Sah,
    /// Binned SAH, then insertion-based optimization (Bittner et al. 2013).
    Optimized,
    /// Centroid midpoint of the longest axis (the BVH2 only).
    Midpoint,
}

/// The library's build options from the command line's.
pub fn build_options(build: BuildKind, bins: usize) -> BuildOptions {
    let builder = match build {
        BuildKind::Auto | BuildKind::Sah | BuildKind::Optimized => bvh2::Builder::Sah { bins },
        BuildKind::Midpoint => bvh2::Builder::Midpoint,
    };
    BuildOptions {
        builder,
        bins,
        reinsert: matches!(build, BuildKind::Auto | BuildKind::Optimized),
    }
}

/// The options rendered, checked: `options`, or with `spd` the SPD test procedure's ([`spd::options`]:
/// 513 x 513 corner rays, spp 0, 4 bounces) keeping what it leaves open (kernel, seed, roughness,
/// counting).
pub fn checked(spd: bool, options: Options, scene: &Scene) -> whitted::Result<Options> {
    let options = if spd {
        Options {
            kernel: options.kernel,
            seed: options.seed,
            roughness: options.roughness,
            count_steps: options.count_steps,
            ..spd::options(scene)
        }
    } else {
        options
    };
    options.validate()?;
    Ok(options)
}

/// Refuses, with `--spd`, the first of the options `given` (its name, and whether it was given): the
/// procedure fixes the frame they would change, and the Readme's counts hold for that frame only.
pub fn spd_refuses(spd: bool, given: &[(&str, bool)]) -> whitted::Result<()> {
    match given.iter().find(|(_, g)| *g) {
        Some((option, _)) if spd => Err(whitted::Error::msg(format!(
            "--spd renders the SPD test procedure's frame (512x512 pixels from 513x513 corner rays, spp 0, \
             {} bounces, one pass) and cannot be combined with {option}",
            spd::SPD_DEPTH
        ))),
        _ => Ok(()),
    }
}
