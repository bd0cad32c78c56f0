//! Command-line interface: parses arguments with clap and calls the library. Every failure is one line on
//! stderr, `whitted: path:line:col: message`, and exit status 1; clap's usage errors exit with 2.

mod args;
mod bench;
mod info;
mod merge;
mod outputs;
mod plan;
mod render;
#[cfg(feature = "view")]
mod view;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
}

/// Runs the command line and turns errors into a message and an exit status.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(args) => info::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Merge(args) => merge::run(&args),
        #[cfg(feature = "view")]
        Command::View(args) => view::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("whitted: {e}");
            ExitCode::FAILURE
        }
    }
}
