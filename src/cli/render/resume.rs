//! `render --resume`: where a render starts again from what an interrupted run of it wrote.

use whitted::parts::partial::{Part, PartSettings};
use whitted::render::progressive::Progressive;
use whitted::scene::Scene;

use super::plan::{Plan, Target};
use crate::cli::setup::warn;

/// Where the render starts: at nothing (with a warning where a stop file is there without `--resume`),
/// or with `--resume` at what the stop file holds of this very
/// render (same settings, the first passes of this run over its tiles). A stop file that cannot be
/// read, is damaged or is of another render is ignored with a warning that says why (it is replaced
/// or, beside a finished image, removed, as one resumed from is). Returns the accumulator to render
/// into and, when the earlier run stopped in its first pass, the tiles it finished (the accumulator
/// then covers the others, for that pass).
pub fn starting_point(plan: &Plan, scene: &Scene) -> (Progressive, Option<Progressive>) {
    let fresh = || (plan.accumulator(), None);
    let stop = plan.stop_file();
    let there = std::fs::symlink_metadata(&stop).is_ok();
    if there && !plan.resume && matches!(plan.target, Target::Image { .. }) {
        warn(&[format!(
            "{} holds an interrupted render of {}: this render starts over without it (--resume goes \
             on from it), and replaces it, or removes it once the image is whole",
            stop.display(),
            plan.output.display()
        )]);
    }
    if !plan.resume || !there {
        return fresh();
    }
    let (passes, tiles) = (plan.passes(), plan.tile_indices());
    let part = match usable(plan, scene, &tiles) {
        Ok(part) => part,
        Err(why) => {
            warn(&[format!(
                "--resume ignores {}: {why}; rendering from the start",
                stop.display()
            )]);
            return fresh();
        }
    };
    let say = |what: String| {
        if !plan.quiet {
            crate::cli::console::note(format!("whitted: resuming from {}: {what}", stop.display()));
        }
    };
    if part.tiles == tiles {
        if part.passes.len() < passes.len() {
            say(format!("{} of {} passes done", part.passes.len(), passes.len()));
        }
        return (part.into_progressive(), None);
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

/// The stop file's part, if this run can go on from it: of this render (same settings), over the
/// first passes of this run and within its tiles (all of them, or some of them in one pass); else
/// why not.
fn usable(plan: &Plan, scene: &Scene, tiles: &[u32]) -> Result<Part, String> {
    let part = Part::read(&plan.stop_file()).map_err(|e| e.message)?;
    let settings = PartSettings::new(scene, &plan.options, plan.total_passes);
    let differences = settings.differences(&part.settings);
    if !differences.is_empty() {
        return Err(format!(
            "it is of another render (this render's vs the file's: {})",
            differences.join(", ")
        ));
    }
    let passes = plan.passes();
    let (start, end) = (part.passes.start, part.passes.end);
    if start != passes.start || end > passes.end {
        return Err(format!(
            "it holds passes {start}..{end}, not the first of this run's {}..{}",
            passes.start, passes.end
        ));
    }
    if part.part != plan.tiles.unwrap_or((0, 1)) || part.tiles.iter().any(|t| tiles.binary_search(t).is_err())
    {
        let (k, n) = part.part;
        return Err(format!("it holds tiles of part {k}/{n}, not of this run's"));
    }
    if part.tiles.len() < tiles.len() && part.passes.len() != 1 {
        return Err(format!(
            "it holds {} passes of {} of the {} tiles, where an interrupted run keeps one pass",
            part.passes.len(),
            part.tiles.len(),
            tiles.len()
        ));
    }
    Ok(part)
}

/// With `--resume` and a `.partial` output: whether the output holds exactly this part of this render
/// already, so that there is nothing to render.
pub fn done_already(plan: &Plan, acc: &Progressive, earlier: bool) -> bool {
    let passes = plan.passes();
    plan.resume
        && !earlier
        && matches!(plan.target, Target::Partial { .. })
        && acc.passes() == passes.end - passes.start
}

/// `earlier` (the tiles of a first pass an earlier run finished) and `acc` (the rest) as one.
pub fn joined(earlier: Option<Progressive>, acc: Progressive) -> Progressive {
    match earlier {
        Some(earlier) => earlier.join(acc),
        None => acc,
    }
}
