//! `whitted render`: a scene to an image.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::progressive::Progressive;
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
    #[command(flatten)]
    frame: FrameArgs,
    /// Most bounces after the primary hit.
    #[arg(long, default_value_t = 6)]
    max_depth: u32,
    /// The BVH2 builder when `--accel bvh2`: sah or midpoint.
    #[arg(long, default_value = "sah")]
    build: BuildKind,
    /// SAH bins per axis (2 to 64).
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(2..=64))]
    bins: u32,
    /// Samples per pixel (overrides the file's `spp`): 0 for one ray through each pixel centre, else
    /// n x n jittered samples (rounded up to a square).
    #[arg(long)]
    spp: Option<u32>,
    /// Seed of every random number (the same seed gives the same image, on any number of threads).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Lens aperture in pixels of the view plane (overrides the file's; 0 = pinhole).
    #[arg(long, value_parser = non_negative)]
    aperture: Option<f32>,
    /// Focal distance as a ratio of the view-plane distance (overrides the file's).
    #[arg(long, value_parser = positive)]
    focal: Option<f32>,
    /// Roughness of materials whose `f` line gives none (0 = perfect mirrors; the course used 0.3).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    roughness: f32,
    /// Progressive rendering: this many passes of one jittered sample per pixel, averaged.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    passes: u32,
    /// With --passes: write the image every K passes, so the render can be watched converging.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    every: Option<u32>,
    /// With --passes: also keep each written snapshot in this directory, numbered by pass.
    #[arg(long)]
    progressive_out: Option<PathBuf>,
    /// Encode the output with the sRGB curve (default: linear values, the course's convention).
    #[arg(long)]
    srgb: bool,
    /// No progress bar or summary.
    #[arg(short, long)]
    quiet: bool,
}

fn number(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .parse()
        .map_err(|_| format!("expected a number, found \"{s}\""))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("expected a finite number, found {s}"))
    }
}

fn non_negative(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("expected a number of at least 0, found {s}"))
    }
}

fn positive(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("expected a number above 0, found {s}"))
    }
}

/// Set by Ctrl-C: the render stops at the next tile and keeps the last complete pass.
static STOP: AtomicBool = AtomicBool::new(false);

/// The frame's size, the threads and the structure and kernel that trace it (`render` and `bench`).
#[derive(Args)]
pub struct FrameArgs {
    /// Image width (keeps the vertical field of view; the height follows the aspect ratio if not given).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Acceleration structure: none, grid, bvh2 or bvh4.
    #[arg(long, default_value = "bvh4")]
    pub accel: AccelKind,
    /// Camera rays one at a time (single) or in packets of 8 (packet, BVH4 only; same image).
    #[arg(long, default_value = "packet")]
    pub kernel: Kernel,
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
    let mut scene = load_scene(args.scene.as_deref())?;
    for w in &scene.warnings {
        eprintln!("whitted: warning: {w}");
    }
    if let Some(a) = args.aperture {
        scene.camera.aperture = a;
    }
    if let Some(f) = args.focal {
        scene.camera.focal = f;
    }
    let (width, height) = resolution(&scene, args.frame.width, args.frame.height)?;
    let pool = thread_pool(args.frame.threads)?;
    let loaded = start.elapsed();
    if args.passes == 1 && (args.every.is_some() || args.progressive_out.is_some()) {
        return Err(whitted::Error::msg(
            "--every and --progressive-out need --passes 2 or more",
        ));
    }

    let build_start = Instant::now();
    let accel = Accel::build_with(
        Prims::new(&scene),
        args.frame.accel,
        build_options(args.build, args.bins as usize),
    );
    let built = build_start.elapsed();

    let spp = args.spp.unwrap_or(scene.spp);
    if args.passes > 1 && spp > 1 {
        eprintln!(
            "whitted: warning: progressive passes take one jittered sample per pixel each; spp {spp} ignored"
        );
    }
    let options = Options {
        width,
        height,
        max_depth: args.max_depth,
        kernel: args.frame.kernel,
        spp: if args.passes > 1 { 1 } else { spp },
        seed: args.seed,
        roughness: args.roughness,
    };
    let renderer = Renderer::new(&scene, &accel, options);
    for w in &renderer.warnings {
        eprintln!("whitted: warning: {w}");
    }
    // Ctrl-C stops at the next tile; what was written stays whole (files are renamed into place).
    // Installing fails only if another handler is set, as in tests that call `run` twice: keep it.
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::Relaxed));
    if let Some(dir) = &args.progressive_out {
        std::fs::create_dir_all(dir)
            .map_err(|e| whitted::Error::file(dir, format!("cannot create the directory: {e}")))?;
    }

    let render_start = Instant::now();
    let mut mean = Progressive::new(width, height);
    let every = args.every.unwrap_or(if args.progressive_out.is_some() {
        1
    } else {
        u32::MAX
    });
    for pass in 1..=args.passes {
        let label = (args.passes > 1).then(|| format!("pass {pass}/{}", args.passes));
        let Some(film) = pool.install(|| render_with_progress(&renderer, pass, label, args.quiet)) else {
            break;
        };
        mean.add(&film);
        if pass % every == 0 && pass < args.passes {
            write_snapshot(args, &mean)?;
        }
    }
    let rendered = render_start.elapsed();
    if mean.passes() == 0 {
        return Err(whitted::Error::msg(
            "interrupted before the first pass was complete; nothing written",
        ));
    }
    write_snapshot(args, &mean)?;
    if !args.quiet {
        let passes = match args.passes {
            1 => String::new(),
            n if mean.passes() < n => format!(", interrupted after {} of {n} passes", mean.passes()),
            n => format!(", {n} passes"),
        };
        eprintln!(
            "whitted: {}x{} in {:.3} s (load {:.3} s, build {:.3} s, accel {:?}, kernel {:?}, {} threads{passes}) -> {}",
            width,
            height,
            rendered.as_secs_f64(),
            loaded.as_secs_f64(),
            built.as_secs_f64(),
            args.frame.accel,
            args.frame.kernel,
            pool.current_num_threads(),
            args.output.display()
        );
    }
    Ok(())
}

/// Writes the mean so far to the output and, with `--progressive-out`, to a numbered copy there.
fn write_snapshot(args: &RenderArgs, mean: &Progressive) -> whitted::Result<()> {
    mean.film().write(&args.output, args.srgb)?;
    if let Some(dir) = &args.progressive_out {
        let stem = args.output.file_stem().unwrap_or_default().to_string_lossy();
        let ext = args.output.extension().unwrap_or_default().to_string_lossy();
        let name = format!("{stem}-{:04}.{ext}", mean.passes());
        mean.film().write(&dir.join(name), args.srgb)?;
    }
    Ok(())
}

/// Renders pass `pass` with a progress bar on stderr that appears only if the pass takes more than a
/// second; `None` if Ctrl-C stopped it.
fn render_with_progress(renderer: &Renderer, pass: u32, label: Option<String>, quiet: bool) -> Option<Film> {
    let (width, height) = renderer.size();
    let total = tiles::tiles(width, height).len() as u64;
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} {msg} [{bar:40}] {percent}% tiles, eta {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    if let Some(label) = label {
        bar.set_message(label);
    }
    // Short frames never flash a bar: it is drawn from the first tile finished after this instant.
    let show_from = Instant::now() + Duration::from_secs(1);
    let shown = AtomicBool::new(quiet);
    let film = renderer.render_pass(
        pass,
        &|| {
            bar.inc(1);
            if !shown.load(Ordering::Relaxed) && Instant::now() >= show_from {
                shown.store(true, Ordering::Relaxed);
                bar.set_draw_target(ProgressDrawTarget::stderr());
            }
        },
        &STOP,
    );
    bar.finish_and_clear();
    film.map(|(film, _)| film)
}
