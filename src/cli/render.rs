//! `whitted render`: a scene to an image, or to a `.partial` file of part of one.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use whitted::accel::{Accel, Prims};
use whitted::parts::partial::{Part, Settings};
use whitted::render::progressive::Progressive;
use whitted::render::{Renderer, memory};
use whitted::scene::Scene;

use super::Ended;
use super::args::{
    BuildKind, CameraArgs, FrameArgs, image, load_scene, non_negative, part_of, pass_range, positive,
    thread_pool, warn,
};
use super::outputs;
use super::plan::{Plan, Target, writes_partial};
use super::report::{self, Report, ReportArgs};

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
    /// Go on from what an interrupted run of this very render wrote: OUT.partial beside an image, or the
    /// .partial output itself (a part already whole there is not rendered again, so a job array rerun
    /// with --resume redoes only the missing, damaged or interrupted parts).
    #[arg(long)]
    pub resume: bool,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Most bounces after the primary hit (default 6, at most 64).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=whitted::render::MAX_DEPTH as i64))]
    pub max_depth: Option<u32>,
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
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub report: ReportArgs,
}

/// Set by Ctrl-C: the render stops at the next tile and writes what is finished.
static STOP: AtomicBool = AtomicBool::new(false);

/// Renders and writes the image, or, when Ctrl-C stops the render, what is finished.
pub fn run(args: &RenderArgs) -> whitted::Result<Ended> {
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
    let accel = pool.install(|| Accel::try_build_with(Prims::new(&scene), plan.accel, plan.build))?;
    let built = build_start.elapsed();
    warn(&plan.warnings);
    let renderer = Renderer::new(&scene, &accel, plan.options);
    warn(&renderer.warnings);
    // Ctrl-C stops at the next tile; what was written stays whole (files are renamed into place).
    // Installing fails only if another handler is set, as in tests that call `run` twice: keep it.
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::Relaxed));

    let render_start = Instant::now();
    let (acc, earlier) = starting_point(&plan, &scene);
    let resumed = earlier.is_some() || acc.passes() > 0;
    if done_already(&plan, &acc, earlier.is_some()) {
        if !plan.quiet {
            let output = plan.output.display();
            eprintln!("whitted: {output} holds this part already; not rendered again");
        }
        return Ok(Ended::Done);
    }
    let progress = Progress::new(&plan, &acc);
    let rendered = render_passes(&plan, &pool, &renderer, &progress, acc, earlier);
    progress.bar.finish_and_clear();
    let (acc, complete) = rendered?;
    if !complete {
        return interrupted(&plan, &scene, &acc);
    }
    let rendered = render_start.elapsed();
    write(&plan, &acc)?;
    if resumed && matches!(plan.target, Target::Image { .. }) {
        // The image is whole: the sums it was resumed from are spent.
        let _ = std::fs::remove_file(stop_file(&plan));
    }
    if !plan.quiet {
        let threads = pool.current_num_threads();
        eprintln!("whitted: {}", summary(&plan, [loaded, built, rendered], threads));
    }
    if let Some(format) = args.report.stats {
        let times = [loaded, built, rendered];
        Report::of_render(args, &plan, &accel, &pool, times, &acc).print(format);
    }
    Ok(Ended::Done)
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

/// Where an interrupted render writes its sums and `--resume` looks for them: a `.partial` output
/// itself, or beside an image `OUT.partial` (`render.png.partial`).
fn stop_file(plan: &Plan) -> PathBuf {
    match plan.target {
        Target::Partial { .. } => plan.output.clone(),
        Target::Image { .. } => {
            let mut name = plan.output.clone().into_os_string();
            name.push(".partial");
            name.into()
        }
    }
}

/// Where the render starts: at nothing, or with `--resume` at what the stop file holds of this very
/// render (same settings, the first passes of this run over its tiles; a file that is missing,
/// damaged or of another render is ignored). Returns the accumulator to render into and, when the
/// earlier run stopped in its first pass, the tiles it finished (the accumulator then covers the
/// others, for that pass).
fn starting_point(plan: &Plan, scene: &Scene) -> (Progressive, Option<Progressive>) {
    let fresh = || (plan.accumulator(), None);
    let Some(part) = plan.resume.then(|| Part::read(&stop_file(plan)).ok()).flatten() else {
        return fresh();
    };
    let (passes, tiles) = (plan.passes(), plan.tile_indices());
    let settings = Settings::new(scene, &plan.options, plan.total_passes);
    let ours = part.tiles.iter().all(|t| tiles.binary_search(t).is_ok());
    let within = part.passes.start == passes.start && part.passes.end <= passes.end;
    if part.settings != settings || !within || !ours {
        return fresh();
    }
    let say = |what: String| {
        if !plan.quiet {
            eprintln!("whitted: resuming from {}: {what}", stop_file(plan).display());
        }
    };
    if part.tiles == tiles {
        if part.passes.len() < passes.len() {
            say(format!("{} of {} passes done", part.passes.len(), passes.len()));
        }
        return (part.into_progressive(), None);
    }
    if part.passes.len() != 1 {
        return fresh();
    }
    say(format!(
        "{} of {} tiles of the first pass done",
        part.tiles.len(),
        tiles.len()
    ));
    let rest = tiles.into_iter().filter(|t| part.tiles.binary_search(t).is_err());
    let (w, h) = (plan.options.width, plan.options.height);
    let rest = Progressive::for_tiles(w, h, rest.collect());
    (rest, Some(part.into_progressive()))
}

/// With `--resume` and a `.partial` output: whether the output holds exactly this part of this render
/// already, so that there is nothing to render.
fn done_already(plan: &Plan, acc: &Progressive, earlier: bool) -> bool {
    let passes = plan.passes();
    plan.resume
        && !earlier
        && matches!(plan.target, Target::Partial { .. })
        && acc.passes() == passes.end - passes.start
}

/// `earlier` (the tiles of a first pass an earlier run finished) and `acc` (the rest) as one.
fn joined(earlier: Option<Progressive>, acc: Progressive) -> Progressive {
    match earlier {
        Some(earlier) => earlier.join(acc),
        None => acc,
    }
}

/// Renders the plan's passes into `acc` from where it stands, joining `earlier` to it once the first
/// pass is whole, and writes the output every `plan.every` passes before the last. Returns the sums
/// and whether every pass is done: Ctrl-C stops the render at the next tile, keeping the complete
/// passes, or in the first pass the tiles finished.
fn render_passes(
    plan: &Plan,
    pool: &rayon::ThreadPool,
    renderer: &Renderer,
    progress: &Progress,
    mut acc: Progressive,
    mut earlier: Option<Progressive>,
) -> whitted::Result<(Progressive, bool)> {
    let passes = plan.passes();
    let on_tile = || progress.tile();
    for pass in passes.start + acc.passes() + 1..=passes.end {
        progress.bar.set_message(label(plan, pass));
        if let Err(stopped) = pool.install(|| acc.render_pass(renderer, pass, &on_tile, &STOP)) {
            if acc.passes() == 0 {
                acc = acc.keep_finished(&stopped);
            }
            return Ok((joined(earlier, acc), false));
        }
        acc = joined(earlier.take(), acc);
        if acc.passes().is_multiple_of(plan.every) && pass < passes.end {
            write(plan, &acc)?;
        }
    }
    Ok((acc, true))
}

/// The progress bar's words for pass `pass`: the part and the pass, when there is more than one.
fn label(plan: &Plan, pass: u32) -> String {
    let mut label = Vec::new();
    if let Some((k, n)) = plan.tiles {
        label.push(format!("part {k}/{n}"));
    }
    if plan.total_passes > 1 {
        label.push(format!("pass {pass}/{}", plan.total_passes));
    }
    label.join(", ")
}

/// After Ctrl-C: writes what is finished and says on stderr, even with `--quiet`, what was written
/// and how to go on. The sums go to the stop file ([`stop_file`]) for `--resume`; an image render
/// with whole passes also writes their mean as the image (and its snapshot).
fn interrupted(plan: &Plan, scene: &Scene, acc: &Progressive) -> whitted::Result<Ended> {
    let passes = plan.passes();
    let (done, of) = (acc.passes(), passes.end - passes.start);
    if done == 0 {
        eprintln!("whitted: interrupted before any tile was finished; nothing written");
        return Ok(Ended::Interrupted);
    }
    let stop = stop_file(plan);
    let (tiles, all) = (acc.tile_indices().len(), plan.tile_indices().len());
    let image = matches!(plan.target, Target::Image { .. });
    if image {
        let settings = Settings::new(scene, &plan.options, plan.total_passes);
        write_sums(plan, &settings, acc, &stop)?;
    }
    if !image || tiles == all {
        write(plan, acc)?;
    }
    let stop = stop.display();
    let what = if tiles < all {
        let first = match of {
            1 => String::new(),
            n => format!(" in the first of {n} passes"),
        };
        format!("{first}: wrote the {tiles} of {all} tiles finished to {stop}")
    } else if image {
        let out = plan.output.display();
        format!(" after {done} of {of} passes: wrote their mean to {out} and their sums to {stop}")
    } else {
        format!(" after {done} of {of} passes: wrote their sums to {stop}")
    };
    eprintln!("whitted: interrupted{what}; the same command with --resume renders the rest");
    Ok(Ended::Interrupted)
}

/// Writes the sums or the mean so far to the output and, with `--progressive-out`, a numbered copy.
fn write(plan: &Plan, acc: &Progressive) -> whitted::Result<()> {
    let (srgb, snapshots) = match &plan.target {
        Target::Partial { settings } => return write_sums(plan, settings, acc, &plan.output),
        Target::Image { srgb, snapshots } => (*srgb, snapshots),
    };
    let film = image(&plan.options, acc.film());
    film.write(&plan.output, srgb)?;
    if let Some(dir) = snapshots {
        film.write(&outputs::snapshot(dir, &plan.output, acc.passes()), srgb)?;
    }
    Ok(())
}

/// Writes the sums of `acc`, this run's part of the render of `settings`, as a `.partial` file.
fn write_sums(plan: &Plan, settings: &Settings, acc: &Progressive, path: &Path) -> whitted::Result<()> {
    let part = Part::new(*settings, acc, plan.passes().start, plan.tiles.unwrap_or((0, 1)));
    part.write(path)
}

/// The line printed after a render: size, times (load, build, render), accelerator, kernel, threads,
/// passes and part.
fn summary(plan: &Plan, [loaded, built, rendered]: [Duration; 3], threads: usize) -> String {
    let passes = match plan.passes().len() {
        1 => String::new(),
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
    let (width, height) = report::image_size(&plan.options);
    format!(
        "{width}x{height} in {:.3} s (load {:.3} s, build {:.3} s, accel {:?}, kernel {:?}, {threads} threads{passes}{part}) -> {}",
        rendered.as_secs_f64(),
        loaded.as_secs_f64(),
        built.as_secs_f64(),
        plan.accel,
        plan.options.kernel,
        plan.output.display()
    )
}

/// One progress bar for the whole render, every tile of every pass left, with an ETA, on stderr. It is
/// drawn only once the render has taken a second (short renders never flash one), never with
/// `--quiet`, and only if stderr is a terminal (indicatif hides a bar drawn to anything else).
struct Progress {
    bar: ProgressBar,
    show_from: Instant,
    shown: AtomicBool,
}

impl Progress {
    /// A hidden bar for the render of `plan` from `acc`: the first pass left covers the tiles of
    /// `acc` (fewer than the plan's when resuming from part of it), the others all of the plan's.
    fn new(plan: &Plan, acc: &Progressive) -> Progress {
        let passes = plan.passes();
        let left = u64::from(passes.end - passes.start - acc.passes());
        let all = plan.tile_indices().len() as u64;
        let ticks = match left {
            0 => 0,
            n => acc.tile_indices().len() as u64 + (n - 1) * all,
        };
        let bar = ProgressBar::with_draw_target(Some(ticks), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template("{elapsed_precise} {msg} [{wide_bar}] {percent}%, eta {eta}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        Progress {
            bar,
            show_from: Instant::now() + Duration::from_secs(1),
            shown: AtomicBool::new(plan.quiet),
        }
    }

    /// A tile is done: moves the bar, and draws it from the first tile after its first second.
    fn tile(&self) {
        self.bar.inc(1);
        if !self.shown.load(Ordering::Relaxed) && Instant::now() >= self.show_from {
            self.shown.store(true, Ordering::Relaxed);
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }
}

/// `whitted render`'s arguments alone, for the tests of the modules that take them.
#[cfg(test)]
#[derive(clap::Parser)]
pub(super) struct Render {
    #[command(flatten)]
    pub args: RenderArgs,
}

#[cfg(test)]
mod tests {
    use std::io::IsTerminal;

    use clap::Parser;

    use super::*;

    /// The plan of `whitted render ARGS` for the built-in scene (640x480: 40 x 30 tiles).
    fn plan(args: &str) -> Plan {
        let words = std::iter::once("render").chain(args.split_whitespace());
        let render = Render::try_parse_from(words).expect("arguments clap accepts");
        let mut scene = load_scene(None).expect("the built-in scene");
        Plan::new(&render.args, &mut scene).expect("a valid plan")
    }

    /// One bar for the whole render: every tile of every pass left (a first pass resumed counts the
    /// tiles it lacks), drawn from the first tile after its first second, unless `--quiet` or stderr
    /// is not a terminal.
    #[test]
    fn one_bar_counts_every_tile_of_every_pass_left() {
        let p = plan("--passes 60");
        let progress = Progress::new(&p, &p.accumulator());
        assert_eq!(progress.bar.length(), Some(60 * 1200));
        let lacking_200 = Progressive::for_tiles(640, 480, (200..1200).collect());
        assert_eq!(
            Progress::new(&p, &lacking_200).bar.length(),
            Some(1000 + 59 * 1200)
        );
        let part = plan("--passes 4 --passes-range 1..3 --tiles 1/4 --partial");
        assert_eq!(
            Progress::new(&part, &part.accumulator()).bar.length(),
            Some(2 * 300)
        );

        assert!(progress.bar.is_hidden(), "not in its first second");
        for (args, shown) in [("", std::io::stderr().is_terminal()), ("-q", false)] {
            let p = plan(args);
            let mut progress = Progress::new(&p, &p.accumulator());
            progress.show_from = Instant::now();
            progress.tile();
            assert_eq!(progress.bar.position(), 1);
            assert_eq!(!progress.bar.is_hidden(), shown, "{args}");
            progress.bar.finish_and_clear();
        }
    }
}
