//! `whitted render`: a scene to an image.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::{Kernel, Options, Renderer, film::Film, tiles};
use whitted::scene::{self, Scene, check_resolution};

use super::{BuildKind, build_options};

/// The scene `render` draws when given none, compiled into the binary so the first command works anywhere.
const DEFAULT_SCENE: &str = include_str!("../../scenes/default.p3f");

/// Arguments of `whitted render`.
#[derive(Args)]
pub struct RenderArgs {
    /// The scene (.p3f, .nff, .ply, .obj, optionally .gz); the built-in default scene if omitted.
    scene: Option<PathBuf>,
    /// Output image: .png, .ppm (8-bit) or .exr (linear float).
    #[arg(short, long, default_value = "render.png")]
    output: PathBuf,
    /// Image width (keeps the vertical field of view; the height follows the aspect ratio if not given).
    #[arg(long)]
    width: Option<u32>,
    /// Image height.
    #[arg(long)]
    height: Option<u32>,
    /// Most bounces after the primary hit.
    #[arg(long, default_value_t = 6)]
    max_depth: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Acceleration structure: none, grid, bvh2 or bvh4.
    #[arg(long, default_value = "bvh4")]
    accel: AccelKind,
    /// Camera rays one at a time (single) or in packets of 8 (packet, BVH4 only; same image).
    #[arg(long, default_value = "packet")]
    kernel: Kernel,
    /// The BVH2 builder when `--accel bvh2`: sah or midpoint.
    #[arg(long, default_value = "sah")]
    build: BuildKind,
    /// SAH bins per axis (2 to 64).
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(2..=64))]
    bins: u32,
    /// Encode the output with the sRGB curve (default: linear values, the course's convention).
    #[arg(long)]
    srgb: bool,
    /// No progress bar or summary.
    #[arg(short, long)]
    quiet: bool,
}

/// Loads the named scene, or the built-in one.
pub fn load_scene(path: Option<&Path>) -> whitted::Result<Scene> {
    match path {
        Some(p) => scene::load(p),
        None => scene::p3f::parse(Path::new("(default scene)"), Box::new(DEFAULT_SCENE.as_bytes())),
    }
}

/// The resolution after `--width`/`--height`: one given alone keeps the file's aspect ratio.
pub fn resolution(scene: &Scene, width: Option<u32>, height: Option<u32>) -> whitted::Result<(u32, u32)> {
    let (fw, fh) = (scene.camera.width as u64, scene.camera.height as u64);
    let (w, h) = match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, ((w as u64 * fh).div_ceil(fw)).min(u32::MAX as u64) as u32),
        (None, Some(h)) => (((h as u64 * fw).div_ceil(fh)).min(u32::MAX as u64) as u32, h),
        (None, None) => (fw as u32, fh as u32),
    };
    check_resolution(w, h).map_err(whitted::Error::msg)?;
    Ok((w, h))
}

/// A rayon pool of `threads` workers (all cores when `None`).
pub fn thread_pool(threads: Option<usize>) -> whitted::Result<rayon::ThreadPool> {
    if threads == Some(0) {
        return Err(whitted::Error::msg("--threads must be at least 1"));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| whitted::Error::msg(format!("cannot start the worker threads: {e}")))
}

/// Renders and writes the image.
pub fn run(args: &RenderArgs) -> whitted::Result<()> {
    let start = Instant::now();
    let scene = load_scene(args.scene.as_deref())?;
    for w in &scene.warnings {
        eprintln!("whitted: warning: {w}");
    }
    let (width, height) = resolution(&scene, args.width, args.height)?;
    let pool = thread_pool(args.threads)?;
    let loaded = start.elapsed();

    let build_start = Instant::now();
    let accel = Accel::build_with(
        Prims::new(&scene),
        args.accel,
        build_options(args.build, args.bins as usize),
    );
    let built = build_start.elapsed();

    let options = Options {
        width,
        height,
        max_depth: args.max_depth,
        kernel: args.kernel,
    };
    let renderer = Renderer::new(&scene, &accel, options);
    for w in &renderer.warnings {
        eprintln!("whitted: warning: {w}");
    }
    let render_start = Instant::now();
    let film = pool.install(|| render_with_progress(&renderer, width, height, args.quiet));
    let rendered = render_start.elapsed();
    film.write(&args.output, args.srgb)?;
    if !args.quiet {
        eprintln!(
            "whitted: {}x{} in {:.3} s (load {:.3} s, build {:.3} s, accel {:?}, kernel {:?}, {} threads) -> {}",
            width,
            height,
            rendered.as_secs_f64(),
            loaded.as_secs_f64(),
            built.as_secs_f64(),
            args.accel,
            args.kernel,
            pool.current_num_threads(),
            args.output.display()
        );
    }
    Ok(())
}

/// Renders with a progress bar on stderr that appears only if the frame takes more than a second.
fn render_with_progress(renderer: &Renderer, width: u32, height: u32, quiet: bool) -> Film {
    let total = tiles::tiles(width, height).len() as u64;
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {percent}% tiles, eta {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    // Short frames never flash a bar: it is drawn from the first tile finished after this instant.
    let show_from = Instant::now() + Duration::from_secs(1);
    let shown = AtomicBool::new(quiet);
    let film = renderer.render_with(&|| {
        bar.inc(1);
        if !shown.load(Ordering::Relaxed) && Instant::now() >= show_from {
            shown.store(true, Ordering::Relaxed);
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    });
    bar.finish_and_clear();
    film
}
