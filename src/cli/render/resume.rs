//! `render --resume`: where a render starts again from what an interrupted run of it wrote.

use whitted::parts::partial::{Part, PartSettings};
use whitted::render::progressive::Progressive;
use whitted::scene::Scene;

use super::plan::{Plan, Target};

/// Where the render starts: at nothing, or with `--resume` at what the stop file holds of this very
/// render (same settings, the first passes of this run over its tiles; a file that is missing,
/// damaged or of another render is ignored). Returns the accumulator to render into and, when the
/// earlier run stopped in its first pass, the tiles it finished (the accumulator then covers the
/// others, for that pass).
pub fn starting_point(plan: &Plan, scene: &Scene) -> (Progressive, Option<Progressive>) {
    let fresh = || (plan.accumulator(), None);
    let Some(part) = plan.resume.then(|| Part::read(&plan.stop_file()).ok()).flatten() else {
        return fresh();
    };
    let (passes, tiles) = (plan.passes(), plan.tile_indices());
    let settings = PartSettings::new(scene, &plan.options, plan.total_passes);
    let ours = part.tiles.iter().all(|t| tiles.binary_search(t).is_ok());
    let within = part.passes.start == passes.start && part.passes.end <= passes.end;
    if part.settings != settings || !within || !ours {
        return fresh();
    }
    let say = |what: String| {
        if !plan.quiet {
            crate::cli::console::note(format!(
                "whitted: resuming from {}: {what}",
                plan.stop_file().display()
            ));
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
