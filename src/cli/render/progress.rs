//! The progress bar of a render: every tile of every pass left, with an ETA, on stderr.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use whitted::render::progressive::Progressive;

use super::plan::Plan;

/// One progress bar for the whole render, every tile of every pass left, with an ETA, on stderr. It is
/// drawn only once the render has taken a second (short renders never flash one), never with
/// `--quiet`, and only if stderr is a terminal (indicatif hides a bar drawn to anything else).
pub struct Progress {
    pub bar: ProgressBar,
    show_from: Instant,
    shown: AtomicBool,
}

impl Progress {
    /// A hidden bar for the render of `plan` from `acc`: the first pass left covers the tiles of
    /// `acc` (fewer than the plan's when resuming from part of it), the others all of the plan's.
    pub fn new(plan: &Plan, acc: &Progressive) -> Progress {
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
    pub fn tile(&self) {
        self.bar.inc(1);
        if !self.shown.load(Ordering::Relaxed) && Instant::now() >= self.show_from {
            self.shown.store(true, Ordering::Relaxed);
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }
}

#[cfg(test)]
mod tests {
    use std::io::IsTerminal;

    use clap::Parser;

    use super::super::args::Render;
    use super::*;
    use crate::cli::setup::load_scene;

    /// The plan of `whitted render ARGS` for the built-in scene (640x480: 40 x 30 tiles).
    fn plan(args: &str) -> Plan {
        let words = std::iter::once("render").chain(args.split_whitespace());
        let render = Render::try_parse_from(words).expect("arguments clap accepts");
        let mut scene = load_scene(None, None).expect("the built-in scene");
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
