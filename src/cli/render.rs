//! `whitted render`: a scene to an image, or to a `.partial` file of part of one.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use whitted::accel::{Accel, Prims};
use whitted::parts::partial::Part;
use whitted::render::progressive::Progressive;
use whitted::render::{Renderer, memory};

use super::args::{
    BuildKind, FrameArgs, load_scene, non_negative, part_of, pass_range, positive, thread_pool,
};
use super::outputs;
use super::plan::{Plan, Target, writes_partial};

/// Arguments of `whitted render`.
#[derive(Args)]
pub struct RenderArgs {
    /// The scene (.p3f, .nff, .ply, .obj, optionally .gz); the built-in default scene if omitted.
    pub scene: Option<PathBuf>,
    /// Output image: .png, .ppm, .jpg (8-bit) or .exr (linear float); or a .partial file (see --tiles).
    #[arg(short, long, default_value = "render.png")]
    pub output: PathBuf,
    /// Render only part K of N of the image (K from 0; a fixed split of its tiles, balanced by area)
    /// into a .partial file, for `whitted merge` to combine with the other parts.
    #[arg(long, value_name = "K/N", value_parser = part_of)]
    pub tiles: Option<(u32, u32)>,
    /// Render only passes A to B-1 (from 0) of the --passes of a progressive render, into a .partial
    /// file, for `whitted merge`.
    #[arg(long, value_name = "A..B", value_parser = pass_range)]
    pub passes_range: Option<(u32, u32)>,
    /// Write the sums of the passes as a .partial file (implied by an output name ending in .partial).
    #[arg(long)]
    pub partial: bool,
    /// With a .partial output: if the file is already there, whole, and holds exactly this part of this
    /// render, do nothing (rerun a job array with --resume to redo only the missing or damaged parts).
    #[arg(long)]
    pub resume: bool,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Most bounces after the primary hit.
    #[arg(long, default_value_t = 6)]
    pub max_depth: u32,
    /// The BVH2 builder when `--accel bvh2`: sah or midpoint.
    #[arg(long, default_value = "sah")]
    pub build: BuildKind,
    /// SAH bins per axis (2 to 64).
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(2..=64))]
    pub bins: u32,
    /// Samples per pixel (overrides the file's `spp`): 0 for one ray through each pixel centre, else
    /// n x n jittered samples (rounded up to a square).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Seed of every random number (the same seed gives the same image, on any number of threads).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Lens aperture in pixels of the view plane (overrides the file's; 0 = pinhole).
    #[arg(long, value_parser = non_negative)]
    pub aperture: Option<f32>,
    /// Focal distance as a ratio of the view-plane distance (overrides the file's).
    #[arg(long, value_parser = positive)]
    pub focal: Option<f32>,
    /// Roughness of materials whose `f` line gives none (0 = perfect mirrors; the course used 0.3).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    pub roughness: f32,
    /// Progressive rendering: this many passes of one jittered sample per pixel, averaged.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub passes: u32,
    /// With --passes: write the image every K passes, so the render can be watched converging.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub every: Option<u32>,
    /// With --passes: also keep each written snapshot in this directory, numbered by pass.
    #[arg(long)]
    pub progressive_out: Option<PathBuf>,
    /// Encode the output with the sRGB curve (default: linear values, the course's convention).
    #[arg(long)]
    pub srgb: bool,
    /// No progress bar or summary.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Set by Ctrl-C: the render stops at the next tile and keeps the last complete pass.
static STOP: AtomicBool = AtomicBool::new(false);

/// Renders and writes the image.
pub fn run(args: &RenderArgs) -> whitted::Result<()> {
    let start = Instant::now();
    check_outputs(args)?;
    let mut scene = load_scene(args.scene.as_deref())?;
    warn(&scene.warnings);
    let plan = Plan::new(args, &mut scene)?;
    // A part's sums cover its tiles only; a whole frame is refused here rather than aborted later.
    if plan.tiles.is_none() {
        memory::check(plan.options.width, plan.options.height).map_err(whitted::Error::msg)?;
    }
    let pool = thread_pool(plan.threads)?;
    let loaded = start.elapsed();
    let build_start = Instant::now();
    let accel = Accel::build_with(Prims::new(&scene), plan.accel, plan.build);
    let built = build_start.elapsed();
    warn(&plan.warnings);
    let renderer = Renderer::new(&scene, &accel, plan.options);
    warn(&renderer.warnings);
    // Ctrl-C stops at the next tile; what was written stays whole (files are renamed into place).
    // Installing fails only if another handler is set, as in tests that call `run` twice: keep it.
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::Relaxed));

    let render_start = Instant::now();
    let mut acc = plan.accumulator();
    if done_already(&plan, &acc) {
        if !plan.quiet {
            let output = plan.output.display();
            eprintln!("whitted: {output} holds this part already; not rendered again");
        }
        return Ok(());
    }
    render_passes(&plan, &pool, &renderer, &mut acc)?;
    let rendered = render_start.elapsed();
    if acc.passes() == 0 {
        return Err(whitted::Error::msg(
            "interrupted before the first pass was complete; nothing written",
        ));
    }
    write(&plan, &acc)?;
    if !plan.quiet {
        let threads = pool.current_num_threads();
        eprintln!(
            "whitted: {}",
            summary(&plan, &acc, [loaded, built, rendered], threads)
        );
    }
    Ok(())
}

/// Checks the files the render writes (the output, and the snapshots of `--progressive-out`), before
/// the scene is loaded.
fn check_outputs(args: &RenderArgs) -> whitted::Result<()> {
    let partial = writes_partial(args);
    outputs::check(&args.output, partial)?;
    match &args.progressive_out {
        Some(dir) if !partial && args.passes > 1 => outputs::check_snapshots(dir, &args.output),
        _ => Ok(()),
    }
}

/// Prints `warnings` on stderr, one a line.
fn warn(warnings: &[String]) {
    for w in warnings {
        eprintln!("whitted: warning: {w}");
    }
}

/// With `--resume`: whether the output holds exactly this part of this render already (a missing or
/// damaged file, or one of other settings, is rendered again and replaced).
fn done_already(plan: &Plan, acc: &Progressive) -> bool {
    let Target::Partial {
        settings,
        resume: true,
    } = &plan.target
    else {
        return false;
    };
    Part::read(&plan.output).is_ok_and(|done| {
        done.settings == *settings && done.passes == plan.passes() && done.tiles == acc.tile_indices()
    })
}

/// Renders the plan's passes into `acc`, writing the output every `plan.every` passes before the last;
/// Ctrl-C stops it after the last complete pass.
fn render_passes(
    plan: &Plan,
    pool: &rayon::ThreadPool,
    renderer: &Renderer,
    acc: &mut Progressive,
) -> whitted::Result<()> {
    let passes = plan.passes();
    for pass in passes.start + 1..=passes.end {
        let mut label = Vec::new();
        if let Some((k, n)) = plan.tiles {
            label.push(format!("part {k}/{n}"));
        }
        if plan.total_passes > 1 {
            label.push(format!("pass {pass}/{}", plan.total_passes));
        }
        let label = label.join(", ");
        if pool
            .install(|| render_with_progress(renderer, acc, pass, label, plan.quiet))
            .is_none()
        {
            break;
        }
        if acc.passes() % plan.every == 0 && pass < passes.end {
            write(plan, acc)?;
        }
    }
    Ok(())
}

/// Writes the sums or the mean so far to the output and, with `--progressive-out`, a numbered copy.
fn write(plan: &Plan, acc: &Progressive) -> whitted::Result<()> {
    let (srgb, snapshots) = match &plan.target {
        Target::Partial { settings, .. } => {
            let part = Part::new(*settings, acc, plan.passes().start, plan.tiles.unwrap_or((0, 1)));
            return part.write(&plan.output);
        }
        Target::Image { srgb, snapshots } => (*srgb, snapshots),
    };
    let film = acc.film();
    film.write(&plan.output, srgb)?;
    if let Some(dir) = snapshots {
        film.write(&outputs::snapshot(dir, &plan.output, acc.passes()), srgb)?;
    }
    Ok(())
}

/// The line printed after a render: size, times (load, build, render), accelerator, kernel, threads,
/// passes and part.
fn summary(
    plan: &Plan,
    acc: &Progressive,
    [loaded, built, rendered]: [Duration; 3],
    threads: usize,
) -> String {
    let range = plan.passes();
    let passes = match range.end - range.start {
        1 => String::new(),
        n if acc.passes() < n => format!(", interrupted after {} of {n} passes", acc.passes()),
        n => format!(", {n} passes"),
    };
    let part = match (plan.tiles, &plan.pass_range) {
        (None, None) => String::new(),
        (tiles, range) => {
            let tiles = tiles.map(|(k, n)| format!("part {k}/{n}, "));
            let range = range
                .as_ref()
                .map(|r| format!("passes {}..{} of {}, ", r.start, r.end, plan.total_passes));
            format!(", {}{}", tiles.unwrap_or_default(), range.unwrap_or_default())
                .trim_end_matches(", ")
                .to_string()
        }
    };
    format!(
        "{}x{} in {:.3} s (load {:.3} s, build {:.3} s, accel {:?}, kernel {:?}, {threads} threads{passes}{part}) -> {}",
        plan.options.width,
        plan.options.height,
        rendered.as_secs_f64(),
        loaded.as_secs_f64(),
        built.as_secs_f64(),
        plan.accel,
        plan.options.kernel,
        plan.output.display()
    )
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
    done.ok().map(|_| ())
}
