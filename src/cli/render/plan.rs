//! `whitted render`'s arguments made into a plan (as ripgrep turns its low-level arguments into
//! high-level ones): every rule between options is checked and every value the render needs is derived
//! here, before anything is built, rendered or written, so that each rule is unit-tested without
//! running the binary and the render itself has nothing left to decide.

use std::ops::Range;
use std::path::{Path, PathBuf};

use whitted::accel::{AccelKind, BuildOptions};
use whitted::heatmap::Scale;
use whitted::heatmap::cost::CostKind;
use whitted::image::film::ImageFormat;
use whitted::parts::partial::PartSettings;
use whitted::render::progressive::Progressive;
use whitted::render::{Options, tiles};
use whitted::scene::Scene;

use super::args::RenderArgs;
use crate::cli::frame::{DEFAULT_DEPTH, build_options, checked};

/// A render, checked and ready to run.
pub struct Plan {
    /// What the renderer is given, within its ranges.
    pub options: Options,
    /// The acceleration structure.
    pub accel: AccelKind,
    /// How a BVH2 is built.
    pub build: BuildOptions,
    /// Passes of the whole render (`--passes`).
    pub total_passes: u32,
    /// The passes `--passes-range` picks (from 0), within the total; `None` for all of them.
    pub pass_range: Option<Range<u32>>,
    /// Part K of N of the frame's tiles (`--tiles`); `None` for the whole frame.
    pub tiles: Option<(u32, u32)>,
    /// The output is written after every this many passes (`u32::MAX`: at the end only).
    pub every: u32,
    /// The file written.
    pub output: PathBuf,
    /// What is written to it.
    pub target: Target,
    /// Go on from what an interrupted run of the same render wrote (`--resume`).
    pub resume: bool,
    /// The cost heatmap to write beside the output (`--heatmap`) and the scale of its colours
    /// (`--heatmap-scale`).
    pub heatmap: Option<(CostKind, Scale)>,
    /// What the arguments asked for that is not done, for the user to see.
    pub warnings: Vec<String>,
    /// No progress bar or summary.
    pub quiet: bool,
}

/// What a render writes.
#[derive(Debug, PartialEq)]
pub enum Target {
    /// An image (sRGB-encoded or linear), and with `--progressive-out` a numbered copy of each one
    /// written in that directory.
    Image { srgb: bool, snapshots: Option<PathBuf> },
    /// A `.partial` file of this part's sums, headed by the render's settings.
    Partial { settings: PartSettings },
    /// An image on standard output (`-o -`), written once, when whole.
    Stdout { srgb: bool, format: ImageFormat },
}

impl Plan {
    /// The plan of `args` for `scene`, whose camera takes the `--aperture` and `--focal` overrides first
    /// (the scene's fingerprint in a `.partial` file covers them).
    pub fn new(args: &RenderArgs, scene: &mut Scene) -> whitted::Result<Plan> {
        if let Some(a) = args.aperture {
            scene.camera.aperture = a;
        }
        if let Some(f) = args.focal {
            scene.camera.focal = f;
        }
        args.camera.apply(&mut scene.camera)?;
        args.spd_refuses()?;
        let (spp, mut warnings) = spp_per_pass(args, scene);
        if args.partial && ImageFormat::of(&args.output).is_ok() {
            warnings.push(format!(
                "{} gets a .partial part of the frame, not an image, though its name says one; \
                 `whitted merge` makes the image",
                args.output.display()
            ));
        }
        let depth = args.max_depth.unwrap_or(DEFAULT_DEPTH);
        let options = Options {
            spp,
            seed: args.seed,
            roughness: args.roughness,
            count_steps: args.report.counters || args.report.heatmap.is_some(),
            ..args.frame.options(scene, depth)
        };
        let options = checked(args.report.spd, options, scene)?;
        let every = every(args)?;
        let target = target(args, scene, &options)?;
        Ok(Plan {
            options,
            accel: args.frame.accel,
            build: build_options(args.build, args.bins as usize),
            total_passes: args.passes,
            pass_range: pass_range(args)?,
            tiles: args.tiles,
            every,
            output: args.output.clone(),
            target,
            resume: args.resume,
            heatmap: heatmap(args)?,
            warnings,
            quiet: args.quiet,
        })
    }

    /// The passes this run renders, from 0.
    pub fn passes(&self) -> Range<u32> {
        self.pass_range.clone().unwrap_or(0..self.total_passes)
    }

    /// The indices of the tiles this run renders, increasing.
    pub fn tile_indices(&self) -> Vec<u32> {
        let (w, h) = (self.options.width, self.options.height);
        match self.tiles {
            Some((k, n)) => tiles::part(w, h, k, n),
            None => (0..tiles::tiles(w, h).len() as u32).collect(),
        }
    }

    /// No pass yet over the tiles this run renders.
    pub fn accumulator(&self) -> Progressive {
        let (w, h) = (self.options.width, self.options.height);
        Progressive::for_tiles(w, h, self.tile_indices())
    }

    /// Where an interrupted render writes its sums and `--resume` looks for them ([`stop_file`]).
    pub fn stop_file(&self) -> PathBuf {
        stop_file(&self.output, matches!(self.target, Target::Partial { .. }))
    }
}

/// Where an interrupted render of `output` writes its sums and `--resume` looks for them: a `.partial`
/// output itself, or beside an image `OUT.partial` (`render.png.partial`).
pub fn stop_file(output: &Path, partial: bool) -> PathBuf {
    if partial {
        return output.to_path_buf();
    }
    let mut name = output.as_os_str().to_os_string();
    name.push(".partial");
    name.into()
}

/// Samples per pixel in each pass: a progressive pass takes one, whatever `--spp` or the file say (with
/// a warning if they said more).
fn spp_per_pass(args: &RenderArgs, scene: &Scene) -> (u32, Vec<String>) {
    let spp = args.spp.unwrap_or(scene.spp);
    if args.passes == 1 {
        return (spp, Vec::new());
    }
    let warnings = if spp > 1 {
        vec![format!(
            "progressive passes take one jittered sample per pixel each; spp {spp} ignored"
        )]
    } else {
        Vec::new()
    };
    (1, warnings)
}

/// The image or `.partial` file to write, checked against the options that need one or the other.
fn target(args: &RenderArgs, scene: &Scene, options: &Options) -> whitted::Result<Target> {
    let error = |message: &str| Err(whitted::Error::msg(message));
    let partial = args.writes_partial();
    if args.to_stdout() {
        // Standard output takes one image, once: nothing beside it, nothing to go on from.
        let refused = [
            (
                partial || args.tiles.is_some() || args.passes_range.is_some(),
                "a part of a frame (write it to a .partial file)",
            ),
            (
                args.report.heatmap.is_some(),
                "--heatmap (its files go beside a named output)",
            ),
            (
                args.resume,
                "--resume (an image on standard output keeps no stop file)",
            ),
            (
                args.every.is_some(),
                "--every (standard output takes the image once)",
            ),
            (
                args.progressive_out.is_some(),
                "--progressive-out (snapshots are named after the output)",
            ),
        ];
        if let Some((_, what)) = refused.iter().find(|(given, _)| *given) {
            return Err(whitted::Error::msg(format!(
                "-o - writes one image to standard output: it cannot take {what}"
            )));
        }
        return Ok(Target::Stdout {
            srgb: args.srgb,
            format: args.output_format.unwrap_or(ImageFormat::Png),
        });
    }
    if !partial && (args.tiles.is_some() || args.passes_range.is_some()) {
        return error(
            "--tiles and --passes-range render part of a frame: write it to a .partial file (-o part.partial) and combine the parts with `whitted merge`",
        );
    }
    if partial && args.progressive_out.is_some() {
        return error("--progressive-out writes images; a .partial render cannot keep snapshots");
    }
    if args.output_format.is_some() {
        return error("--output-format is for -o - (standard output): a file's name gives its format");
    }
    Ok(if partial {
        Target::Partial {
            settings: PartSettings::new(scene, options, args.passes),
        }
    } else {
        Target::Image {
            srgb: args.srgb,
            snapshots: args.progressive_out.clone(),
        }
    })
}

/// `--heatmap`, which counts the rays of one run: it cannot go on from an earlier one's sums; and its
/// `--heatmap-scale`, the viewer's by default.
fn heatmap(args: &RenderArgs) -> whitted::Result<Option<(CostKind, Scale)>> {
    match args.report.heatmap {
        Some(_) if args.resume => Err(whitted::Error::msg(
            "--heatmap counts the rays of one whole run: it cannot go on from an earlier run (--resume)",
        )),
        kind => Ok(kind.map(|k| (k, args.report.heatmap_scale.unwrap_or_default()))),
    }
}

/// `--passes-range`, which must lie within `--passes`.
fn pass_range(args: &RenderArgs) -> whitted::Result<Option<Range<u32>>> {
    match args.passes_range {
        Some((a, b)) if b > args.passes => Err(whitted::Error::msg(format!(
            "--passes-range {a}..{b} goes beyond the render's {} passes (set --passes to the whole render's count)",
            args.passes
        ))),
        range => Ok(range.map(|(a, b)| a..b)),
    }
}

/// How often the output is written: every `--every` passes; with `--progressive-out` and no `--every`,
/// every pass (each is a snapshot kept); otherwise only at the end. Both need passes to write between.
fn every(args: &RenderArgs) -> whitted::Result<u32> {
    if args.passes == 1 && (args.every.is_some() || args.progressive_out.is_some()) {
        return Err(whitted::Error::msg(
            "--every and --progressive-out need --passes 2 or more",
        ));
    }
    Ok(match (args.every, &args.progressive_out) {
        (Some(k), _) => k,
        (None, Some(_)) => 1,
        (None, None) => u32::MAX,
    })
}

#[cfg(test)]
mod tests;
