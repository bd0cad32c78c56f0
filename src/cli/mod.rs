//! Command-line interface: parses arguments with clap and calls the library.
//!
//! Exit statuses: 0 when the command is done; 1 on an error in what the command met (a file, the
//! disk, the scene), reported in one line on stderr (`whitted: path:line:col: message`); 2 on a usage
//! error, the command line's own fault (clap's: an unknown option, a value that does not parse or is
//! out of its range; ours, once the scene is read: options that do not go together, or overrides that
//! make an impossible frame or camera); 130, 143 or 129 when SIGINT (Ctrl-C), SIGTERM or SIGHUP
//! interrupted a render, after writing what was finished and saying so on stderr, or ended another
//! command (128 + the signal's number, what a shell reports for a process the signal killed).

mod bench;
mod completions;
mod console;
mod frame;
mod info;
mod man;
mod merge;
mod render;
mod report;
mod setup;
mod signals;
mod values;
#[cfg(feature = "view")]
mod view;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use render::Ended;

/// A data-oriented SIMD CPU Whitted ray tracer for .p3f / NFF / PLY / OBJ scenes.
#[derive(Parser)]
#[command(name = "whitted", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print what a scene holds: primitive counts, lights, materials, camera, bounds and load time.
    Info(info::InfoArgs),
    /// Render a scene (the built-in default scene if none is given) to an image.
    Render(render::RenderArgs),
    /// Time frames of a scene (the course's dragon scene if none is given): fps, rays, Mrays/s.
    Bench(bench::BenchArgs),
    /// Merge the .partial files of a frame rendered in parts (render --tiles / --passes-range) into one
    /// image, after checking that they belong together and cover every pixel and pass exactly once.
    Merge(merge::MergeArgs),
    /// Open a window on a scene (the built-in default scene if none is given), rendered as the camera
    /// moves and refined while it stands still (`whitted view --help` lists the keys).
    #[cfg(feature = "view")]
    View(view::ViewArgs),
    /// Print the completion script of a shell (bash, zsh, fish, powershell or elvish).
    Completions(completions::CompletionsArgs),
    /// Print the man page (roff) of the command, or of a subcommand (`whitted man render`):
    /// `whitted man | man -l -` shows it.
    Man(man::ManArgs),
}

/// The exit status of a usage error (clap's).
const USAGE: u8 = 2;

/// Why a command failed, which sets its exit status.
pub enum Failure {
    /// Something the command met: a file, the disk, the scene (status 1).
    Error(whitted::Error),
    /// The command line itself, found wrong once the scene is read (status 2, as clap's usage errors).
    Usage(whitted::Error),
}

impl From<whitted::Error> for Failure {
    fn from(e: whitted::Error) -> Self {
        Failure::Error(e)
    }
}

/// Reports a command line clap refused, as clap does (help and version included), except `embree`
/// asked of a build without it: one line that says how to build with it, and the usage error status.
fn usage_error(e: clap::Error) -> ExitCode {
    if e.kind() == clap::error::ErrorKind::ValueValidation
        && e.to_string().contains(whitted::accel::NO_EMBREE)
    {
        console::note(format!("whitted: {}", whitted::accel::NO_EMBREE));
        return ExitCode::from(USAGE);
    }
    e.exit()
}

/// Runs the command line and turns errors into a message and an exit status.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    let done = |result: Result<(), Failure>| result.map(|()| Ended::Done);
    let result = match cli.command {
        Command::Info(args) => done(info::run(&args)),
        Command::Render(args) => render::run(&args),
        Command::Bench(args) => done(bench::run(&args)),
        Command::Merge(args) => {
            signals::handle(false);
            done(merge::run(&args))
        }
        #[cfg(feature = "view")]
        Command::View(args) => {
            signals::handle(false);
            done(view::run(&args))
        }
        Command::Completions(args) => done(completions::run(&args)),
        Command::Man(args) => done(man::run(&args)),
    };
    match result {
        Ok(Ended::Done) => ExitCode::SUCCESS,
        Ok(Ended::Interrupted) => ExitCode::from(signals::status(
            signals::received().unwrap_or(signal_hook::consts::SIGINT),
        )),
        Err(Failure::Error(e)) => {
            console::note(format!("whitted: {e}"));
            ExitCode::FAILURE
        }
        Err(Failure::Usage(e)) => {
            console::note(format!("whitted: {e}"));
            ExitCode::from(USAGE)
        }
    }
}
