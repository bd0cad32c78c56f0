//! `whitted render`'s arguments, the parsers of its parts, and the rules that read them alone.

use std::path::PathBuf;

use clap::Args;

use crate::cli::frame::{BuildKind, CameraArgs, FrameArgs, spd_refuses, spp};
use crate::cli::report::Format;
use crate::cli::values::{non_negative, positive, whole};
use whitted::heatmap::Scale;
use whitted::heatmap::cost::CostKind;
use whitted::image::film::ImageFormat;

/// Arguments of `whitted render`.
#[derive(Args)]
pub struct RenderArgs {
    /// The scene (.p3f, .nff, .ply, .obj, optionally .gz; `-` reads it from standard input); the
    /// built-in default scene if omitted.
    pub scene: Option<PathBuf>,
    /// The scene's format, whatever its name: p3f, nff, ply or obj (for `-`, standard input, the
    /// format is otherwise told from its first statement).
    #[arg(long, value_parser = crate::cli::values::scene_format)]
    pub format: Option<whitted::scene::Format>,
    /// Output image: .png, .ppm, .jpg (8-bit) or .exr (linear float); or a .partial file (see --tiles);
    /// `-` writes the image to standard output (PNG, or as --output-format says).
    #[arg(short, long, default_value = "render.png")]
    pub output: PathBuf,
    /// The format of the image written to standard output (`-o -`): png, ppm, jpg or exr (a file's
    /// name gives its own).
    #[arg(long, value_parser = crate::cli::values::image_format)]
    pub output_format: Option<ImageFormat>,
    /// Render only part K of N of the image (K from 0; a fixed split of its tiles, balanced by area)
    /// into a .partial file, for `whitted merge` to combine with the other parts.
    #[arg(long, value_name = "K/N", value_parser = part_of, allow_hyphen_values = true)]
    pub tiles: Option<(u32, u32)>,
    /// Render only passes A to B-1 (from 0) of the --passes of a progressive render, into a .partial
    /// file, for `whitted merge`.
    #[arg(long, value_name = "A..B", value_parser = pass_range, allow_hyphen_values = true)]
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
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=whitted::render::MAX_DEPTH as i64),
          allow_negative_numbers = true)]
    pub max_depth: Option<u32>,
    /// How the BVHs are built: auto (today optimized), sah, optimized (binned SAH, then
    /// reinsertion) or midpoint (the BVH2 only; the wide BVHs collapse a binned-SAH BVH2).
    #[arg(long, default_value = "auto")]
    pub build: BuildKind,
    /// SAH bins per axis (2 to 64).
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(2..=64),
          allow_negative_numbers = true)]
    pub bins: u32,
    /// Samples per pixel (overrides the file's `spp`): 0 for one ray through each pixel centre, else
    /// n x n jittered samples (rounded up to a square), at most 65536.
    #[arg(long, value_parser = spp(), allow_negative_numbers = true)]
    pub spp: Option<u32>,
    /// Seed of every random number (the same seed gives the same image, on any number of threads).
    #[arg(long, default_value_t = 0, value_parser = whole, allow_negative_numbers = true)]
    pub seed: u64,
    /// Lens aperture in pixels of the view plane (overrides the file's; 0 = pinhole).
    #[arg(long, value_parser = non_negative, allow_hyphen_values = true)]
    pub aperture: Option<f32>,
    /// Focal distance as a ratio of the view-plane distance (overrides the file's).
    #[arg(long, value_parser = positive, allow_hyphen_values = true)]
    pub focal: Option<f32>,
    /// Roughness of materials whose `f` line gives none (0 = perfect mirrors; the course used 0.3).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative, allow_hyphen_values = true)]
    pub roughness: f32,
    /// Progressive rendering: this many passes of one jittered sample per pixel, averaged.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..),
          allow_negative_numbers = true)]
    pub passes: u32,
    /// With --passes: write the image every K passes, so the render can be watched converging.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..), allow_negative_numbers = true)]
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

/// `render`'s `--stats` and `--spd`.
#[derive(Args)]
pub struct ReportArgs {
    /// Print the rays by kind, Mrays/s, the times, the accelerator, kernel, instruction set, threads
    /// and version: `--stats` as text on stderr (even with --quiet), `--stats=json` as one JSON object
    /// on stdout. With --spd, also the SPD counts beside the Readme's.
    #[arg(long, value_name = "FORMAT", num_args = 0..=1, require_equals = true, default_missing_value = "text")]
    pub stats: Option<Format>,
    /// Also write a cost heatmap of the render: `nodes` (BVH nodes visited), `prims` (primitive tests)
    /// or `rays` (rays traced), summed over every ray each pixel sends, or over one kind of them
    /// (`nodes:camera`, `prims:shadow`, `rays:reflected`, `nodes:refracted`). Beside the output OUT.EXT:
    /// OUT.heatmap.png (false colour, with a legend), OUT.heatmap.exr (the counts) and
    /// OUT.heatmap.json (mean, median, p99 and max per ray kind).
    #[arg(long, value_name = "KIND")]
    pub heatmap: Option<CostKind>,
    /// With --heatmap: how counts map to the colours of OUT.heatmap.png, from 0 at the bottom of the
    /// colour bar: `log:p99` (the default) log(1 + count) up to the 99th percentile of the counts
    /// (nearest rank), higher counts in the top colour; `log` up to the largest count; `p99`, `p95`,
    /// ... (`pNN`, 1 to 99) the count itself up to that percentile; `linear` up to the largest count.
    #[arg(long, value_name = "SCALE", requires = "heatmap")]
    pub heatmap_scale: Option<Scale>,
    /// With --stats: also count the nodes visited and primitives tested by each ray, and report their
    /// means per ray kind (counting makes the render slower; its times are the counted render's).
    #[arg(long, requires = "stats")]
    pub counters: bool,
    /// Render with the Standard Procedural Databases' test procedure: a 512x512 image from 513x513
    /// corner rays, spp 0, 4 bounces (refuses --spp, --passes, --tiles, --passes-range, --width,
    /// --height, --max-depth and .partial outputs).
    #[arg(long)]
    pub spd: bool,
}

impl RenderArgs {
    /// Whether the image goes to standard output (`-o -`).
    pub fn to_stdout(&self) -> bool {
        self.output == std::path::Path::new("-")
    }

    /// Whether the output is a `.partial` file (`--partial`, or its name) rather than an image.
    pub fn writes_partial(&self) -> bool {
        self.partial
            || self
                .output
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("partial"))
    }

    /// Refuses, with `--spd`, the options that would change the procedure's frame ([`spd_refuses`]).
    pub fn spd_refuses(&self) -> whitted::Result<()> {
        spd_refuses(
            self.report.spd,
            &[
                ("--spp", self.spp.is_some()),
                ("--passes", self.passes > 1),
                ("--tiles", self.tiles.is_some()),
                ("--passes-range", self.passes_range.is_some()),
                ("--width", self.frame.width.is_some()),
                ("--height", self.frame.height.is_some()),
                ("--max-depth", self.max_depth.is_some()),
                ("a .partial output", self.writes_partial()),
            ],
        )
    }
}

/// Two whole numbers `a` and `b` written `a{sep}b`, each at most `u32::MAX`: `expected` says what the
/// whole should look like, and `check` refuses a pair out of its range (negative numbers reach it, to
/// be refused with the range rather than as malformed).
fn u32_pair(
    s: &str,
    sep: &str,
    expected: &str,
    check: impl Fn(i64, i64) -> Result<(), String>,
) -> Result<(u32, u32), String> {
    let bad = || format!("expected {expected}; found \"{s}\"");
    let (a, b) = s.split_once(sep).ok_or_else(bad)?;
    let number = |t: &str| t.trim().parse::<i64>().map_err(|_| bad());
    let (a, b) = (number(a)?, number(b)?);
    check(a, b)?;
    let small = |v: i64| u32::try_from(v).map_err(|_| bad());
    Ok((small(a)?, small(b)?))
}

/// `K/N` with 0 <= K < N.
fn part_of(s: &str) -> Result<(u32, u32), String> {
    u32_pair(s, "/", "K/N, part K (from 0) of N parts, such as 3/8", |k, n| {
        if k < 0 || k >= n {
            return Err(format!("part {k}/{n} does not exist: K counts from 0 to N-1"));
        }
        Ok(())
    })
}

/// `A..B` with 0 <= A < B.
fn pass_range(s: &str) -> Result<(u32, u32), String> {
    u32_pair(
        s,
        "..",
        "A..B, passes A to B-1 (from 0), such as 0..16",
        |a, b| {
            if a < 0 {
                return Err(format!(
                    "the pass range {a}..{b} starts before pass 0: passes count from 0"
                ));
            }
            if a >= b {
                return Err(format!("the pass range {a}..{b} is empty"));
            }
            Ok(())
        },
    )
}

/// `whitted render`'s arguments alone, for the tests that parse them.
#[cfg(test)]
#[derive(clap::Parser)]
pub(super) struct Render {
    #[command(flatten)]
    pub args: RenderArgs,
}
