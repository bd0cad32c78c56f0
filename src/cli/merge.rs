//! `whitted merge`: the parts of a frame rendered apart (`render --tiles K/N`, `--passes-range A..B`)
//! into one image.

use std::path::PathBuf;

use clap::Args;
use whitted::parts;

use whitted::files;

use super::Failure;

/// Arguments of `whitted merge`.
#[derive(Args)]
pub struct MergeArgs {
    /// The image to write: .png, .ppm, .jpg or .exr.
    output: PathBuf,
    /// The .partial files: together they must cover every pixel and pass exactly once.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// Encode the output with the sRGB curve (as `render --srgb`).
    #[arg(long)]
    srgb: bool,
    /// No summary.
    #[arg(short, long)]
    quiet: bool,
}

/// Checks the output, then checks and merges the parts and writes the image (nothing is written if
/// any check fails).
pub fn run(args: &MergeArgs) -> Result<(), Failure> {
    whitted::image::check_output(&args.output, false)?;
    if let Some(part) = args.parts.iter().find(|p| files::same_file(&args.output, p)) {
        return Err(Failure::Usage(whitted::Error::file(
            &args.output,
            format!(
                "is one of the parts ({}): the merged image would replace it; name another output",
                part.display()
            ),
        )));
    }
    let film = parts::merge::merge(&args.parts)?;
    film.write(&args.output, args.srgb)?;
    if !args.quiet {
        crate::cli::console::note(format!(
            "whitted: merged {} parts into {}x{} -> {}",
            args.parts.len(),
            film.width,
            film.height,
            args.output.display()
        ));
    }
    Ok(())
}
