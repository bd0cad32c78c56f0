//! `whitted render`: a scene to an image.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use whitted::accel::{Accel, Prims};
use whitted::parts::partial::{Part, Settings};
use whitted::render::progressive::Progressive;
use whitted::render::{Options, Renderer, tiles};

use super::args::{
    BuildKind, FrameArgs, build_options, load_scene, non_negative, part_of, pass_range, positive, resolution,
    thread_pool,
};

/// Arguments of `whitted render`.
#[derive(Args)]
pub struct RenderArgs {
    /// The scene (.p3f, .nff, .ply, .obj, optionally .gz); the built-in default scene if omitted.
    scene: Option<PathBuf>,
    /// Output image: .png, .ppm (8-bit) or .exr (linear float); or a .partial file (see --tiles).
    #[arg(short, long, default_value = "render.png")]
    output: PathBuf,
    /// Render only part K of N of the image (K from 0; a fixed split of its tiles, balanced by area)
    /// into a .partial file, for `whitted merge` to combine with the other parts.
    #[arg(long, value_name = "K/N", value_parser = part_of)]
    tiles: Option<(u32, u32)>,
    /// Render only passes A to B-1 (from 0) of the --passes of a progressive render, into a .partial
    /// file, for `whitted merge`.
    #[arg(long, value_name = "A..B", value_parser = pass_range)]
    passes_range: Option<(u32, u32)>,
    /// Write the sums of the passes as a .partial file (implied by an output name ending in .partial).
    #[arg(long)]
    partial: bool,
    /// With a .partial output: if the file is already there, whole, and holds exactly this part of this
    /// render, do nothing (rerun a job array with --resume to redo only the missing or damaged parts).
    #[arg(long)]
    resume: bool,
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

/// Set by Ctrl-C: the render stops at the next tile and keeps the last complete pass.
static STOP: AtomicBool = AtomicBool::new(false);

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

    let partial = args.partial
        || args
            .output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("partial"));
    if !partial && (args.tiles.is_some() || args.passes_range.is_some()) {
        return Err(whitted::Error::msg(
            "--tiles and --passes-range render part of a frame: write it to a .partial file (-o part.partial) and combine the parts with `whitted merge`",
        ));
    }
    if args.resume && !partial {
        return Err(whitted::Error::msg("--resume applies to .partial outputs only"));
    }
    if partial && args.progressive_out.is_some() {
        return Err(whitted::Error::msg(
            "--progressive-out writes images; a .partial render cannot keep snapshots",
        ));
    }
    let passes = args.passes_range.unwrap_or((0, args.passes));
    if passes.1 > args.passes {
        return Err(whitted::Error::msg(format!(
            "--passes-range {}..{} goes beyond the render's {} passes (set --passes to the whole render's count)",
            passes.0, passes.1, args.passes
        )));
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
    let (first, last) = passes;
    let mut acc = match args.tiles {
        Some((k, n)) => Progressive::for_tiles(width, height, tiles::part(width, height, k, n)),
        None => Progressive::new(width, height),
    };
    let every = args.every.unwrap_or(if args.progressive_out.is_some() {
        1
    } else {
        u32::MAX
    });
    let out = Output {
        args,
        partial: partial.then(|| Settings::new(&scene, &options, args.passes)),
        first,
    };
    if let (true, Some(settings)) = (args.resume, out.partial) {
        // A missing or damaged file, or one of other settings, is rendered again and replaced.
        if let Ok(done) = Part::read(&args.output) {
            if done.settings == settings && done.passes == (first..last) && done.tiles == acc.tile_indices() {
                if !args.quiet {
                    eprintln!(
                        "whitted: {} holds this part already; not rendered again",
                        args.output.display()
                    );
                }
                return Ok(());
            }
        }
    }
    for pass in first + 1..=last {
        let mut label = Vec::new();
        if let Some((k, n)) = args.tiles {
            label.push(format!("part {k}/{n}"));
        }
        if args.passes > 1 {
            label.push(format!("pass {pass}/{}", args.passes));
        }
        if pool
            .install(|| render_with_progress(&renderer, &mut acc, pass, label.join(", "), args.quiet))
            .is_none()
        {
            break;
        }
        if acc.passes() % every == 0 && pass < last {
            out.write(&acc)?;
        }
    }
    let rendered = render_start.elapsed();
    if acc.passes() == 0 {
        return Err(whitted::Error::msg(
            "interrupted before the first pass was complete; nothing written",
        ));
    }
    out.write(&acc)?;
    if !args.quiet {
        let wanted = last - first;
        let passes = match wanted {
            1 => String::new(),
            n if acc.passes() < n => format!(", interrupted after {} of {n} passes", acc.passes()),
            n => format!(", {n} passes"),
        };
        let part = match (args.tiles, args.passes_range) {
            (None, None) => String::new(),
            (tiles, range) => {
                let tiles = tiles.map(|(k, n)| format!("part {k}/{n}, "));
                let range = range.map(|(a, b)| format!("passes {a}..{b} of {}, ", args.passes));
                format!(", {}{}", tiles.unwrap_or_default(), range.unwrap_or_default())
                    .trim_end_matches(", ")
                    .to_string()
            }
        };
        eprintln!(
            "whitted: {}x{} in {:.3} s (load {:.3} s, build {:.3} s, accel {:?}, kernel {:?}, {} threads{passes}{part}) -> {}",
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

/// Where and how the render is written.
struct Output<'a> {
    args: &'a RenderArgs,
    /// The settings a .partial file records; `None` for an image.
    partial: Option<Settings>,
    /// The first pass rendered (from 0).
    first: u32,
}

impl Output<'_> {
    /// Writes the sums or the mean so far to the output and, with `--progressive-out`, a numbered copy.
    fn write(&self, acc: &Progressive) -> whitted::Result<()> {
        let args = self.args;
        if let Some(settings) = self.partial {
            let part = Part::new(settings, acc, self.first, args.tiles.unwrap_or((0, 1)));
            return part.write(&args.output);
        }
        let film = acc.film();
        film.write(&args.output, args.srgb)?;
        if let Some(dir) = &args.progressive_out {
            let stem = args.output.file_stem().unwrap_or_default().to_string_lossy();
            let ext = args.output.extension().unwrap_or_default().to_string_lossy();
            let name = format!("{stem}-{:04}.{ext}", acc.passes());
            film.write(&dir.join(name), args.srgb)?;
        }
        Ok(())
    }
}

/// Renders pass `pass` into `acc` with a progress bar on stderr that appears only if the pass takes
/// more than a second; `None` if Ctrl-C stopped it.
fn render_with_progress(
    renderer: &Renderer,
    acc: &mut Progressive,
    pass: u32,
    label: String,
    quiet: bool,
) -> Option<()> {
    let total = acc.tile_indices().len() as u64;
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} {msg} [{bar:40}] {percent}% tiles, eta {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(label);
    // Short frames never flash a bar: it is drawn from the first tile finished after this instant.
    let show_from = Instant::now() + Duration::from_secs(1);
    let shown = AtomicBool::new(quiet);
    let done = acc.render_pass(
        renderer,
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
    done.map(|_| ())
}
