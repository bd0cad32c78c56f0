//! `whitted bench`'s arguments.

use std::path::PathBuf;

use clap::Args;
use whitted::accel::AccelKind;

use crate::cli::frame::{CameraArgs, FrameArgs, spp};

/// Arguments of `whitted bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// The scene (default: the course's `scenes/dragon.p3f`, 100k triangles, 800x600, 1 spp, looked
    /// for in the source tree the binary was built from, then under the current directory; `-` reads
    /// it from standard input).
    pub scene: Option<PathBuf>,
    /// The scene's format, whatever its name: p3f, nff, ply or obj (for `-`, standard input, the
    /// format is otherwise told from its first statement).
    #[arg(long, value_parser = crate::cli::values::scene_format)]
    pub format: Option<whitted::scene::Format>,
    /// Frames timed (after one frame of warm-up).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..),
          allow_negative_numbers = true)]
    pub frames: u32,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Samples per pixel, 0 to 65536 (default: the file's).
    #[arg(long, value_parser = spp(), allow_negative_numbers = true)]
    pub spp: Option<u32>,
    /// Most bounces after the primary hit (default 6, at most 64).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=whitted::render::MAX_DEPTH as i64),
          allow_negative_numbers = true)]
    pub max_depth: Option<u32>,
    /// Time frames of the SPD test procedure (513x513 corner rays, spp 0, 4 bounces) and compare their
    /// counts with the SPD Readme's (refuses --spp, --width, --height and --max-depth).
    #[arg(long)]
    pub spd: bool,
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Also time the same frames with this accelerator (`embree`, with the `embree` feature, or any of
    /// --accel's), alternating frame by frame with --accel's, and print both and their speed ratio.
    #[arg(long, value_name = "ACCEL")]
    pub compare: Option<AccelKind>,
    /// Also count the nodes visited and primitives tested by each ray (in the warm-up frame, so that
    /// the timed frames do not pay for counting) and print their means per ray kind.
    #[arg(long)]
    pub counters: bool,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}
