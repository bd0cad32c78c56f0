//! What a render writes: the image and its snapshots, or the sums of its passes as a `.partial` file.

use std::path::{Path, PathBuf};

use whitted::files::{self, check_writable, write_atomically};
use whitted::heatmap::Scale;
use whitted::heatmap::cost::CostKind;
use whitted::image::film::Film;
use whitted::parts::partial::{Part, PartSettings};
use whitted::render::progressive::Progressive;
use whitted::render::{Options, spd};

use super::args::RenderArgs;
use super::plan::{Plan, Target, stop_file};
use crate::cli::{Failure, console};

/// Checks every file the render may write, before the scene is loaded: the output, the stop file an
/// interrupted image render keeps its sums in, and the snapshots of `--progressive-out`.
pub fn check_outputs(args: &RenderArgs) -> Result<(), Failure> {
    if args.to_stdout() {
        // No file: what may go with standard output is the plan's to say.
        return Ok(());
    }
    let partial = args.writes_partial();
    whitted::image::check_output(&args.output, partial)?;
    let stop = stop_file(&args.output, partial);
    if let Some(dir) = &args.progressive_out {
        let heatmaps = heatmap_paths(&args.output);
        let mut files = vec![
            (args.output.as_path(), "the output image"),
            (stop.as_path(), "the file an interrupted render keeps its sums in"),
        ];
        if args.report.heatmap.is_some() {
            files.extend(heatmaps.iter().map(|p| (p.as_path(), "a file of the heatmap")));
        }
        files::apart(dir, &files).map_err(Failure::Usage)?;
    }
    if !partial {
        check_writable(&stop).map_err(|e| {
            whitted::Error::file(
                &stop,
                format!("{} (Ctrl-C keeps the finished tiles in this file)", e.message),
            )
        })?;
    }
    if args.report.heatmap.is_some() {
        for path in heatmap_paths(&args.output) {
            check_writable(&path)?;
        }
    }
    match &args.progressive_out {
        Some(dir) if !partial && args.passes > 1 => {
            Ok(files::check_snapshots(dir, &args.output, args.passes)?)
        }
        _ => Ok(()),
    }
}

/// The files `--heatmap` writes beside `output` (OUT.EXT): OUT.heatmap.png, .exr and .json.
pub fn heatmap_paths(output: &Path) -> [PathBuf; 3] {
    ["png", "exr", "json"].map(|ext| output.with_extension(format!("heatmap.{ext}")))
}

/// Writes the heatmap `kind` of the passes in `acc`, coloured on `scale`, beside the output.
pub fn write_heatmap(plan: &Plan, kind: CostKind, scale: Scale, acc: &Progressive) -> whitted::Result<()> {
    let (w, h) = acc.size();
    let pixels = acc.pixel_rays().expect("a heatmap's render counts its steps");
    let [png, exr, json] = heatmap_paths(&plan.output);
    let map = kind.heatmap(w, h, pixels, scale);
    map.write_png(&png)?;
    map.write_exr(&exr)?;
    let summary = kind.summary(w, h, pixels, &map.ramp());
    let mut text = serde_json::to_string_pretty(&summary).expect("JSON of plain values");
    text.push('\n');
    write_atomically(&json, |file| {
        std::io::Write::write_all(file, text.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(|e| whitted::Error::file(&json, e))
}

/// Writes the sums or the mean so far to the output and, with `--progressive-out`, a numbered copy.
pub fn write(plan: &Plan, acc: &Progressive) -> whitted::Result<()> {
    let (srgb, snapshots) = match &plan.target {
        Target::Partial { settings } => return write_sums(plan, settings, acc, &plan.output),
        Target::Image { srgb, snapshots } => (*srgb, snapshots),
        Target::Stdout { srgb, format } => {
            let bytes = image(&plan.options, acc.film())
                .encoded(*format, *srgb)
                .map_err(|e| whitted::Error::msg(format!("cannot encode the image: {e}")))?;
            return console::out_bytes(&bytes);
        }
    };
    let film = image(&plan.options, acc.film());
    film.write(&plan.output, srgb)?;
    if let Some(dir) = snapshots {
        std::fs::create_dir_all(dir)
            .map_err(|e| whitted::Error::file(dir, format!("cannot create the directory: {e}")))?;
        film.write(&files::snapshot(dir, &plan.output, acc.passes()), srgb)?;
    }
    Ok(())
}

/// Writes the sums of `acc`, this run's part of the render of `settings`, as a `.partial` file.
pub fn write_sums(
    plan: &Plan,
    settings: &PartSettings,
    acc: &Progressive,
    path: &Path,
) -> whitted::Result<()> {
    let part = Part::new(*settings, acc, plan.passes().start, plan.tiles.unwrap_or((0, 1)));
    part.write(path)
}

/// The image of a frame rendered with `options`: an SPD frame's corners averaged into its pixels.
fn image(options: &Options, film: Film) -> Film {
    if options.spd {
        spd::corners_to_pixels(&film)
    } else {
        film
    }
}
