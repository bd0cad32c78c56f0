//! `whitted render`: a scene to an image, or to a `.partial` file of part of one.

mod args;
mod plan;
mod progress;
mod resume;
mod write;

use std::time::{Duration, Instant};

use whitted::accel::{Accel, Prims};
use whitted::parts::partial::PartSettings;
use whitted::render::env::Background;
use whitted::render::progressive::Progressive;
use whitted::render::{Renderer, memory};

pub use args::RenderArgs;
use plan::{Plan, Target};
use progress::Progress;
use resume::{done_already, joined, starting_point};
use write::{check_outputs, write, write_heatmap, write_sums};

use super::console::note;
use super::report::{Report, image_size};
use super::setup::{load_scene, thread_pool, warn};
use super::{Failure, signals};

/// How a command that did not fail ended.
pub enum Ended {
    /// It did all it was asked.
    Done,
    /// A signal stopped it ([`signals`]); what was finished is written.
    Interrupted,
}

/// Renders and writes the image, or, when Ctrl-C stops the render, what is finished.
pub fn run(args: &RenderArgs) -> Result<Ended, Failure> {
    let start = Instant::now();
    check_outputs(args)?;
    // The scene's includes load on the render's threads.
    let pool = thread_pool(args.frame.threads)?;
    let mut scene = pool.install(|| load_scene(args.scene.as_deref(), args.format))?;
    warn(&scene.warnings);
    let mut plan = Plan::new(args, &mut scene).map_err(Failure::Usage)?;
    // A part's sums cover its tiles only; a whole frame is refused here rather than aborted later, and
    // so is any counting render (its pixels' rays and heatmap span the frame, even for a part).
    let counted = plan.options.count_steps;
    let mut frame = 0;
    if plan.tiles.is_none() || counted {
        let (w, h) = (plan.options.width, plan.options.height);
        memory::check(w, h, counted, true).map_err(whitted::Error::msg)?;
        frame = memory::frame_bytes(w, h, counted);
    }
    // The skybox is read whole for a part too.
    memory::check_skybox(Background::bytes(&scene), frame).map_err(whitted::Error::msg)?;
    let loaded = start.elapsed();
    let build_start = Instant::now();
    let accel = pool.install(|| Accel::try_build_with(Prims::new(&scene), plan.accel, plan.build))?;
    let built = build_start.elapsed();
    if plan.heatmap.is_some() && !accel.counts_steps() {
        return Err(Failure::Usage(whitted::Error::msg(
            "Embree's traversal is its own: --heatmap cannot count its steps (choose another --accel)",
        )));
    }
    if plan.options.count_steps && !accel.counts_steps() {
        plan.warnings
            .push("Embree's traversal is its own: --counters counts no steps of it".into());
        plan.options.count_steps = false;
    }
    warn(&plan.warnings);
    let renderer = Renderer::new(&scene, &accel, plan.options);
    warn(&renderer.warnings);
    // Ctrl-C, SIGTERM or SIGHUP stops at the next block; what was written stays whole.
    signals::handle(true);

    let render_start = Instant::now();
    let (acc, earlier) = starting_point(&plan, &scene);
    if done_already(&plan, &acc, earlier.is_some()) {
        if !plan.quiet {
            let output = plan.output.display();
            note(format!(
                "whitted: {output} holds this part already; not rendered again"
            ));
        }
        // The report of this run, which traced no rays.
        if let Some(format) = args.report.stats {
            let times = [loaded, built, Duration::ZERO];
            stats(args, &plan, &accel, &acc, times, pool.current_num_threads()).print(format)?;
        }
        return Ok(Ended::Done);
    }
    let progress = Progress::new(&plan, &acc);
    let settings = PartSettings::new(&scene, &plan.options, plan.total_passes);
    let rendered = render_passes(&plan, &settings, &pool, &renderer, &progress, acc, earlier);
    progress.bar.finish_and_clear();
    let (acc, complete) = rendered?;
    if !complete {
        return Ok(interrupted(&plan, &settings, &acc)?);
    }
    let rendered = render_start.elapsed();
    write(&plan, &acc).map_err(|e| kept(&plan, &settings, &acc, e))?;
    if let Some((kind, scale)) = plan.heatmap {
        write_heatmap(&plan, kind, scale, &acc)?;
    }
    if matches!(plan.target, Target::Image { .. }) {
        // The image is whole: the sums it was resumed from are spent, as is a stop file --resume
        // ignored or a render without --resume started over from (a warning said so at the start).
        let _ = std::fs::remove_file(plan.stop_file());
    }
    let (times, threads) = ([loaded, built, rendered], pool.current_num_threads());
    if !plan.quiet {
        note(format!("whitted: {}", summary(&plan, times, threads)));
    }
    if let Some(format) = args.report.stats {
        stats(args, &plan, &accel, &acc, times, threads).print(format)?;
    }
    Ok(Ended::Done)
}

/// Renders the plan's passes into `acc` from where it stands, joining `earlier` to it once the first
/// pass is whole, and writes the output every `plan.every` passes before the last. Returns the sums
/// and whether every pass is done: Ctrl-C stops the render at the next tile, keeping the complete
/// passes, or in the first pass the tiles finished.
fn render_passes(
    plan: &Plan,
    settings: &PartSettings,
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
        if let Err(stopped) = pool.install(|| acc.render_pass(renderer, pass, &on_tile, &signals::STOP)) {
            if acc.passes() == 0 {
                acc = acc.keep_finished(&stopped);
            }
            return Ok((joined(earlier, acc), false));
        }
        acc = joined(earlier.take(), acc);
        if acc.passes().is_multiple_of(plan.every) && pass < passes.end {
            write(plan, &acc).map_err(|e| kept(plan, settings, &acc, e))?;
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

/// After a signal ([`signals`]): writes what is finished and says on stderr, even with `--quiet`, what was written
/// and how to go on. The sums go to the stop file ([`Plan::stop_file`]) for `--resume`; an image render
/// with whole passes also writes their mean as the image (and its snapshot).
fn interrupted(plan: &Plan, settings: &PartSettings, acc: &Progressive) -> whitted::Result<Ended> {
    let passes = plan.passes();
    let (done, of) = (acc.passes(), passes.end - passes.start);
    let by = match signals::received() {
        Some(signal) if signal != signal_hook::consts::SIGINT => format!(" by {}", signals::name(signal)),
        _ => String::new(),
    };
    if done == 0 {
        note(format!(
            "whitted: interrupted{by} before any tile was finished; nothing written"
        ));
        return Ok(Ended::Interrupted);
    }
    if matches!(plan.target, Target::Stdout { .. }) {
        note(format!(
            "whitted: interrupted{by}; nothing written: standard output takes the whole image or none"
        ));
        return Ok(Ended::Interrupted);
    }
    let stop = plan.stop_file();
    let (tiles, all) = (acc.tile_indices().len(), plan.tile_indices().len());
    let image = matches!(plan.target, Target::Image { .. });
    if image {
        write_sums(plan, settings, acc, &stop)?;
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
    // A heatmap counts the rays of one whole run, so a --heatmap render cannot go on from its sums.
    let how = if plan.heatmap.is_some() {
        "; a --heatmap render cannot go on from them: the same command renders it again from the start, \
         or, without --heatmap, with --resume renders the rest without the map"
    } else {
        "; the same command with --resume renders the rest"
    };
    note(format!("whitted: interrupted{by}{what}{how}"));
    Ok(Ended::Interrupted)
}

/// The error of a write that failed after the passes in `acc` were rendered (a snapshot, the image:
/// a full disk, a name taken since it was checked), after keeping their sums in an image render's stop
/// file, so that the work is not lost: the same command with `--resume` goes on from them. (A
/// `.partial` render's output is its stop file, and standard output has none: there is nowhere else
/// to keep them.)
fn kept(plan: &Plan, settings: &PartSettings, acc: &Progressive, e: whitted::Error) -> whitted::Error {
    let stop = plan.stop_file();
    if !matches!(plan.target, Target::Image { .. }) || write_sums(plan, settings, acc, &stop).is_err() {
        return e;
    }
    whitted::Error {
        message: format!(
            "{}; {} kept in {}: the same command with --resume goes on from them",
            e.message,
            passes_finished(acc.passes()),
            stop.display()
        ),
        ..e
    }
}

/// "the N passes finished are", in words that agree with N.
fn passes_finished(n: u32) -> String {
    match n {
        1 => "the 1 pass finished is".into(),
        n => format!("the {n} passes finished are"),
    }
}

/// `--stats`' report of the passes in `acc`, rendered on `threads` threads in `times` (load, build,
/// render).
fn stats(
    args: &RenderArgs,
    plan: &Plan,
    accel: &Accel,
    acc: &Progressive,
    times: [Duration; 3],
    threads: usize,
) -> Report {
    let report = Report::new(
        args.scene.as_deref(),
        &plan.options,
        accel,
        threads,
        times,
        acc.rays(),
    );
    Report {
        passes: acc.passes(),
        ..report
    }
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
    let (width, height) = image_size(&plan.options);
    format!(
        "{width}x{height} in {:.3} s (load {:.3} s, build {:.3} s, accel {:?}, kernel {:?}, {threads} threads{passes}{part}) -> {}",
        rendered.as_secs_f64(),
        loaded.as_secs_f64(),
        built.as_secs_f64(),
        plan.accel,
        plan.options.kernel,
        match plan.target {
            Target::Stdout { .. } => "standard output".to_string(),
            _ => plan.output.display().to_string(),
        }
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn one_pass_is_one_pass() {
        assert_eq!(super::passes_finished(1), "the 1 pass finished is");
        assert_eq!(super::passes_finished(7), "the 7 passes finished are");
    }
}
