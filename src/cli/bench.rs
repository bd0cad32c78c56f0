//! `whitted bench`: frames per second of a scene (by default the course's dragon scene), with the
//! rays each frame traces, by kind.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use clap::Args;
use whitted::accel::{Accel, Prims};
use whitted::render::RayCounts;
use whitted::render::{Options, Renderer};

use super::args::{FrameArgs, load_scene, resolution, thread_pool};

/// Arguments of `whitted bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// The scene (default: the course's `scenes/dragon.p3f`, 100k triangles, 800x600, 1 spp).
    scene: Option<PathBuf>,
    /// Frames timed (after one frame of warm-up).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    #[command(flatten)]
    frame: FrameArgs,
    /// Samples per pixel (default: the file's).
    #[arg(long)]
    spp: Option<u32>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// The dragon scene: `scenes/dragon.p3f` under the current directory, else in the source tree the
/// binary was built from.
fn default_scene() -> PathBuf {
    let here = PathBuf::from("scenes/dragon.p3f");
    if here.is_file() {
        here
    } else {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon.p3f")
    }
}

/// Renders the frames and prints their timing.
pub fn run(args: &BenchArgs) -> whitted::Result<()> {
    let path = args.scene.clone().unwrap_or_else(default_scene);
    let scene = load_scene(Some(&path))?;
    let (width, height) = resolution(&scene, args.frame.width, args.frame.height);
    let options = Options {
        width,
        height,
        kernel: args.frame.kernel,
        spp: args.spp.unwrap_or(scene.spp),
        ..Options::new(&scene)
    };
    options.validate()?;
    let pool = thread_pool(args.frame.threads)?;
    let accel = pool.install(|| Accel::build(Prims::new(&scene), args.frame.accel));
    let renderer = Renderer::new(&scene, &accel, options);
    let never = AtomicBool::new(false);
    // Every frame is pass 1: the same rays, so the frames time the same work.
    let frame = || pool.install(|| renderer.render_pass(1, &|| {}, &never).expect("never stopped"));
    let (_, rays) = frame();
    let ms: Vec<f64> = (0..args.frames)
        .map(|_| {
            let start = Instant::now();
            frame();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    let (median, min, max) = spread(ms);
    let fps = 1e3 / median;
    let mrays = rays.total() as f64 / median / 1e3;
    let threads = pool.current_num_threads();
    if args.json {
        println!(
            "{}",
            json(
                &path, width, height, args, median, min, max, fps, &rays, mrays, threads
            )
        );
    } else {
        println!(
            "{}: {width}x{height}, {} frames on {threads} threads ({:?}, {:?} kernel)",
            path.display(),
            args.frames,
            args.frame.accel,
            args.frame.kernel
        );
        println!("frame: median {median:.1} ms (min {min:.1}, max {max:.1}), {fps:.2} fps");
        println!(
            "rays per frame: {} primary, {} shadow, {} reflected, {} refracted, {} in all; {mrays:.2} Mrays/s",
            rays.primary,
            rays.shadow,
            rays.reflected,
            rays.refracted,
            rays.total()
        );
    }
    Ok(())
}

/// The median, least and most of the frame times `ms` (at least one).
fn spread(mut ms: Vec<f64>) -> (f64, f64, f64) {
    ms.sort_by(f64::total_cmp);
    let median = if ms.len() % 2 == 1 {
        ms[ms.len() / 2]
    } else {
        (ms[ms.len() / 2 - 1] + ms[ms.len() / 2]) / 2.0
    };
    (median, ms[0], ms[ms.len() - 1])
}

/// The `--json` object.
#[allow(clippy::too_many_arguments)]
fn json(
    path: &std::path::Path,
    width: u32,
    height: u32,
    args: &BenchArgs,
    median: f64,
    min: f64,
    max: f64,
    fps: f64,
    rays: &RayCounts,
    mrays: f64,
    threads: usize,
) -> String {
    let scene = path
        .display()
        .to_string()
        .replace('\\', "\\\\")
        .replace('"', "\\\"");
    format!(
        "{{\"scene\": \"{scene}\", \"width\": {width}, \"height\": {height}, \"frames\": {}, \
         \"fps_median\": {fps:.3}, \"frame_ms_median\": {median:.3}, \"frame_ms_min\": {min:.3}, \
         \"frame_ms_max\": {max:.3}, \"rays_per_frame\": {{\"primary\": {}, \"shadow\": {}, \
         \"reflected\": {}, \"refracted\": {}, \"total\": {}}}, \"mrays_per_s\": {mrays:.3}, \
         \"threads\": {threads}, \"accel\": \"{}\", \"kernel\": \"{}\"}}",
        args.frames,
        rays.primary,
        rays.shadow,
        rays.reflected,
        rays.refracted,
        rays.total(),
        format!("{:?}", args.frame.accel).to_lowercase(),
        format!("{:?}", args.frame.kernel).to_lowercase(),
    )
}
