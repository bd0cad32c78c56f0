//! `whitted view`: a window on a scene, rendered with `render`'s kernels as the camera moves.

use std::path::PathBuf;

use clap::Args;
use whitted::render::Options;
use whitted::view::{self, Config, MAX_WINDOW, state::MAX_VIEW_DEPTH};

use super::Failure;
use super::frame::{DEFAULT_DEPTH, FrameArgs};
use super::setup::{load_scene, thread_pool, warn};

/// Arguments of `whitted view`.
#[derive(Args)]
#[command(after_help = "\
Keys: W/A/S/D/Q/E move (forward, left, back, right, down, up); arrow keys turn; drag with the left \
button to orbit the point looked at; the wheel zooms (field of view); R returns to the file's camera. \
1-5: accelerator none/grid/bvh2/bvh4/bvh8 (6: embree, with the embree feature); K: single/packet kernel; H: soft shadows; F: depth of field; \
[ and ]: fewer/more bounces; P: progressive refinement; C: cost heatmap (nodes visited, primitives tested, off; with its \
legend); F12 or Ctrl-S: save the image; Escape: quit.")]
pub struct ViewArgs {
    /// The scene (.p3f, .nff, .ply, .obj, optionally .gz; `-` reads it from standard input); the
    /// built-in default scene if omitted.
    scene: Option<PathBuf>,
    /// The scene's format, whatever its name: p3f, nff, ply or obj (for `-`, standard input, the
    /// format is otherwise told from its first statement).
    #[arg(long, value_parser = crate::cli::values::scene_format)]
    pub format: Option<whitted::scene::Format>,
    #[command(flatten)]
    frame: FrameArgs,
    /// Most bounces after the primary hit, to begin with ([ and ] change it).
    #[arg(long, default_value_t = DEFAULT_DEPTH, value_parser = clap::value_parser!(u32).range(0..=MAX_VIEW_DEPTH as i64),
          allow_negative_numbers = true)]
    max_depth: u32,
    /// Show and save the image sRGB-encoded (default: linear values, as `render` writes them).
    #[arg(long)]
    srgb: bool,
    /// Close the window after this many frames (for scripted checks; a still camera's frames are its
    /// passes, so the last is `render --passes N`'s image).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..), allow_negative_numbers = true)]
    frames: Option<u32>,
    /// With --frames: save the last frame to this image (.png, .ppm, .jpg or .exr; checked before the
    /// scene is loaded).
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
}

/// Opens the window.
pub fn run(args: &ViewArgs) -> Result<(), Failure> {
    if let Some(path) = &args.screenshot {
        whitted::image::check_output(path, false)?;
    }
    let pool = thread_pool(args.frame.threads)?;
    let scene = pool.install(|| load_scene(args.scene.as_deref(), args.format))?;
    warn(&scene.warnings);
    let options = args.frame.options(&scene, args.max_depth);
    check_window(&args.frame, &options).map_err(Failure::Usage)?;
    options.validate().map_err(Failure::Usage)?;
    let name = match &args.scene {
        Some(path) => path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned(),
        None => "default.p3f".to_string(),
    };
    let config = Config {
        name,
        scene: args.scene.clone(),
        options,
        accel: args.frame.accel,
        srgb: args.srgb,
        frames: args.frames,
        screenshot: args.screenshot.clone(),
    };
    Ok(view::run(&scene, &pool, &config)?)
}

/// Refuses a window side over [`MAX_WINDOW`], naming its option: given, or made from the scene's
/// resolution (alone, or at the aspect ratio of the other side given).
fn check_window(frame: &FrameArgs, options: &Options) -> whitted::Result<()> {
    let sides = [
        ("--width", frame.width, options.width, ("--height", frame.height)),
        ("--height", frame.height, options.height, ("--width", frame.width)),
    ];
    for (option, given, side, (other, other_given)) in sides {
        if side <= MAX_WINDOW {
            continue;
        }
        let found = match (given, other_given) {
            (Some(_), _) => side.to_string(),
            (None, Some(v)) => format!("{side} (the scene's aspect ratio at {other} {v})"),
            (None, None) => format!("{side} (the scene's resolution)"),
        };
        return Err(whitted::Error::msg(format!(
            "{option}: expected 1 to {MAX_WINDOW} for the viewer's window (X11's largest), found {found}"
        )));
    }
    Ok(())
}
