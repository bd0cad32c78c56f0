//! What the subcommands share: the frame's arguments, the scene they load, the threads they render on,
//! and the parsers of their numbers.

use std::path::Path;

use clap::Args;
use whitted::accel::AccelKind;
use whitted::render::Kernel;
use whitted::scene::{self, Scene};

/// The scene drawn when none is given, compiled into the binary so the first command works anywhere.
const DEFAULT_SCENE: &str = include_str!("../../scenes/default.p3f");

/// The frame's size, the threads and the structure and kernel that trace it (`render`, `bench`, `view`).
#[derive(Args)]
pub struct FrameArgs {
    /// Image width (keeps the vertical field of view; the height follows the aspect ratio if not given).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Worker threads, 1 to 1024 (default: all cores).
    #[arg(long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=1024))]
    pub threads: Option<usize>,
    /// Acceleration structure: none, grid, bvh2, bvh4, bvh8 (8-wide nodes, AVX2 where the CPU has it)
    /// or auto (bvh8 on CPUs with AVX2, else bvh4).
    #[arg(long, default_value = "auto")]
    pub accel: AccelKind,
    /// Camera rays one at a time (single) or in packets of 8 (packet, BVH4 and BVH8; same image).
    #[arg(long, default_value = "packet")]
    pub kernel: Kernel,
}

/// The BVH2 builder, as a command-line value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BuildKind {
    /// Binned surface area heuristic.
    Sah,
    /// Centroid midpoint of the longest axis.
    Midpoint,
}

/// The library's build options from the command line's.
pub fn build_options(build: BuildKind, bins: usize) -> whitted::accel::BuildOptions {
    let builder = match build {
        BuildKind::Sah => whitted::accel::bvh2::Builder::Sah { bins },
        BuildKind::Midpoint => whitted::accel::bvh2::Builder::Midpoint,
    };
    whitted::accel::BuildOptions { builder, bins }
}

/// Loads the named scene, or the built-in one.
pub fn load_scene(path: Option<&Path>) -> whitted::Result<Scene> {
    match path {
        Some(p) => scene::load(p),
        None => scene::p3f::parse(Path::new("(default scene)"), Box::new(DEFAULT_SCENE.as_bytes())),
    }
}

/// The resolution after `--width`/`--height`: one given alone keeps the file's aspect ratio. It is
/// checked with the rest of the [`whitted::render::Options`] it goes into.
pub fn resolution(scene: &Scene, width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let (fw, fh) = (scene.camera.width as u64, scene.camera.height as u64);
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, ((w as u64 * fh).div_ceil(fw)).min(u32::MAX as u64) as u32),
        (None, Some(h)) => (((h as u64 * fw).div_ceil(fh)).min(u32::MAX as u64) as u32, h),
        (None, None) => (fw as u32, fh as u32),
    }
}

/// A rayon pool of `threads` workers (all cores when `None`; clap bounds the count).
pub fn thread_pool(threads: Option<usize>) -> whitted::Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| whitted::Error::msg(format!("cannot start the worker threads: {e}")))
}

/// A finite number.
pub fn number(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .parse()
        .map_err(|_| format!("expected a number, found \"{s}\""))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("expected a finite number, found {s}"))
    }
}

/// A finite number of at least 0.
pub fn non_negative(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("expected a number of at least 0, found {s}"))
    }
}

/// A finite number above 0.
pub fn positive(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("expected a number above 0, found {s}"))
    }
}

/// Two numbers `a` and `b` written `a{sep}b`; `expected` says what the whole should look like.
fn u32_pair(s: &str, sep: &str, expected: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected {expected}; found \"{s}\"");
    let (a, b) = s.split_once(sep).ok_or_else(bad)?;
    Ok((
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    ))
}

/// `K/N` with K < N.
pub fn part_of(s: &str) -> Result<(u32, u32), String> {
    let (k, n) = u32_pair(s, "/", "K/N, part K (from 0) of N parts, such as 3/8")?;
    if n == 0 || k >= n {
        return Err(format!("part {k}/{n} does not exist: K counts from 0 to N-1"));
    }
    Ok((k, n))
}

/// `A..B` with A < B.
pub fn pass_range(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = u32_pair(s, "..", "A..B, passes A to B-1 (from 0), such as 0..16")?;
    if a >= b {
        return Err(format!("the pass range {a}..{b} is empty"));
    }
    Ok((a, b))
}
