//! `whitted bench`: frames per second of a scene (by default the course's dragon scene), with the
//! report `render --stats` prints (rays by kind, Mrays/s, times, structure, threads) and each frame's
//! time.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use clap::Args;
use serde_json::Value;
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::{Options, Renderer};
use whitted::scene::Scene;

use super::args::{
    CameraArgs, DEFAULT_DEPTH, FrameArgs, load_scene, resolution, spd_frame, spd_refuses, thread_pool, warn,
};
use super::report::Report;

/// Arguments of `whitted bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// The scene (default: the course's `scenes/dragon.p3f`, 100k triangles, 800x600, 1 spp, looked
    /// for in the source tree the binary was built from, then under the current directory).
    scene: Option<PathBuf>,
    /// Frames timed (after one frame of warm-up).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    #[command(flatten)]
    frame: FrameArgs,
    /// Samples per pixel (default: the file's).
    #[arg(long)]
    spp: Option<u32>,
    /// Most bounces after the primary hit (default 6, at most 64).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=whitted::render::MAX_DEPTH as i64))]
    max_depth: Option<u32>,
    /// Time frames of the SPD test procedure (513x513 corner rays, spp 0, 4 bounces) and compare their
    /// counts with the SPD Readme's (refuses --spp, --width, --height and --max-depth).
    #[arg(long)]
    spd: bool,
    #[command(flatten)]
    camera: CameraArgs,
    /// Also time the same frames with this accelerator (`embree`, with the `embree` feature, or any of
    /// --accel's), alternating frame by frame with --accel's, and print both and their speed ratio.
    #[arg(long, value_name = "ACCEL")]
    compare: Option<AccelKind>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// The benchmark scene, relative to a source tree or to the current directory.
const DRAGON: &str = "scenes/dragon.p3f";

/// The first of `candidates` that is a file, or an error that names them all and says how to pass a
/// scene.
fn find_scene(candidates: &[PathBuf]) -> whitted::Result<PathBuf> {
    if let Some(found) = candidates.iter().find(|p| p.is_file()) {
        return Ok(found.clone());
    }
    let tried: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
    Err(whitted::Error::msg(format!(
        "no scene given, and the default benchmark scene is not at {}; pass one: whitted bench SCENE",
        tried.join(" nor at ")
    )))
}

/// The dragon scene: in the source tree this binary was built from while that tree exists (a
/// `cargo install`ed binary outlives its build directory), else under the current directory.
fn default_scene() -> whitted::Result<PathBuf> {
    let sources = Path::new(env!("CARGO_MANIFEST_DIR")).join(DRAGON);
    find_scene(&[sources, PathBuf::from(DRAGON)])
}

/// The frames' options: the scene's with the arguments', or the SPD procedure's.
fn options(args: &BenchArgs, scene: &Scene) -> whitted::Result<Options> {
    spd_refuses(
        args.spd,
        &[
            ("--spp", args.spp.is_some()),
            ("--width", args.frame.width.is_some()),
            ("--height", args.frame.height.is_some()),
            ("--max-depth", args.max_depth.is_some()),
        ],
    )?;
    let (width, height) = resolution(scene, args.frame.width, args.frame.height);
    let options = Options {
        width,
        height,
        max_depth: args.max_depth.unwrap_or(DEFAULT_DEPTH),
        kernel: args.frame.kernel,
        spp: args.spp.unwrap_or(scene.spp),
        ..Options::new(scene)
    };
    let options = spd_frame(args.spd, options, scene);
    options.validate()?;
    Ok(options)
}

/// One accelerator's frames: the renderer and the frame times.
struct Timed<'a> {
    renderer: Renderer<'a>,
    accel: &'a Accel<'a>,
    built: Duration,
    ms: Vec<f64>,
    rays: whitted::render::RayCounts,
}

/// Renders the frames and prints their timing.
pub fn run(args: &BenchArgs) -> whitted::Result<()> {
    let path = match &args.scene {
        Some(path) => path.clone(),
        None => default_scene()?,
    };
    let start = Instant::now();
    let mut scene = load_scene(Some(&path))?;
    warn(&scene.warnings);
    args.camera.apply(&mut scene.camera)?;
    let loaded = start.elapsed();
    let options = options(args, &scene)?;
    let pool = thread_pool(args.frame.threads)?;
    let build = |kind: AccelKind| {
        let start = Instant::now();
        let accel = pool.install(|| Accel::try_build_with(Prims::new(&scene), kind, Default::default()))?;
        Ok::<_, whitted::Error>((accel, start.elapsed()))
    };
    let (accel, built) = build(args.frame.accel)?;
    let other = args.compare.map(build).transpose()?;
    let never = AtomicBool::new(false);
    // Every frame is pass 1: the same rays, so the frames time the same work.
    let frame = |r: &Renderer| pool.install(|| r.render_pass(1, &|| {}, &never).expect("never stopped"));
    let mut timed: Vec<Timed> = std::iter::once((&accel, built))
        .chain(other.as_ref().map(|(a, b)| (a, *b)))
        .map(|(accel, built)| {
            let renderer = Renderer::new(&scene, accel, options);
            let (_, rays) = frame(&renderer);
            Timed {
                renderer,
                accel,
                built,
                ms: Vec::new(),
                rays,
            }
        })
        .collect();
    // As render says them: a sample count rounded up to a square, a skybox not found (once: both
    // renderers have the same).
    warn(&timed[0].renderer.warnings);
    // With --compare, the two alternate frame by frame, so that a change in the machine's load falls on
    // both.
    for _ in 0..args.frames {
        for t in &mut timed {
            let start = Instant::now();
            frame(&t.renderer);
            t.ms.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    let threads = pool.current_num_threads();
    let reports: Vec<Report> = timed
        .iter()
        .map(|t| {
            let (median, _, _) = spread(&t.ms);
            let times = [loaded, t.built, Duration::from_secs_f64(median / 1e3)];
            Report {
                per_frame: true,
                ..Report::new(Some(&path), &options, t.accel, threads, times, t.rays)
            }
        })
        .collect();
    let median = |k: usize| spread(&timed[k].ms).0;
    if args.json {
        let mut out = json(&reports[0], &timed[0].ms);
        if timed.len() == 2 {
            out["compare"] = json(&reports[1], &timed[1].ms);
            out["speed_ratio"] = (median(1) / median(0)).into();
        }
        println!("{out}");
    } else {
        println!("frames     {} timed after one of warm-up", timed[0].ms.len());
        for (t, report) in timed.iter().zip(&reports) {
            if timed.len() == 2 {
                println!("\n{}:", report.accel);
            }
            let (median, min, max) = spread(&t.ms);
            let fps = 1e3 / median;
            println!("frame      median {median:.1} ms (min {min:.1}, max {max:.1}), {fps:.2} fps");
            print!("{}", report.text());
        }
        if timed.len() == 2 {
            let (a, b) = (reports[0].accel, reports[1].accel);
            println!(
                "\nspeed      {a} / {b}: {:.3}x (median {:.1} ms against {:.1} ms; frames alternated)",
                median(1) / median(0),
                median(0),
                median(1)
            );
        }
    }
    Ok(())
}

/// The median, least and most of the frame times `ms` (at least one).
fn spread(ms: &[f64]) -> (f64, f64, f64) {
    let mut ms = ms.to_vec();
    ms.sort_by(f64::total_cmp);
    let median = if ms.len() % 2 == 1 {
        ms[ms.len() / 2]
    } else {
        (ms[ms.len() / 2 - 1] + ms[ms.len() / 2]) / 2.0
    };
    (median, ms[0], ms[ms.len() - 1])
}

/// The `--json` object: the frames' times, then the report's figures.
fn json(report: &Report, ms: &[f64]) -> Value {
    let (median, min, max) = spread(ms);
    let mut out = serde_json::Map::new();
    out.insert("frames".into(), ms.len().into());
    out.insert("frame_ms".into(), ms.into());
    out.insert("frame_ms_median".into(), median.into());
    out.insert("frame_ms_min".into(), min.into());
    out.insert("frame_ms_max".into(), max.into());
    out.insert("fps_median".into(), (1e3 / median).into());
    out.extend(report.json());
    Value::Object(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_of_an_odd_count_is_the_middle_and_of_an_even_count_the_mean_of_two() {
        assert_eq!(spread(&[3.0, 1.0, 2.0]), (2.0, 1.0, 3.0));
        assert_eq!(spread(&[4.0, 1.0, 2.0, 8.0]), (3.0, 1.0, 8.0));
        assert_eq!(spread(&[5.0]), (5.0, 5.0, 5.0));
    }

    #[test]
    fn the_default_scene_is_the_first_file_found_or_an_error_naming_where_it_looked() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.p3f"), dir.path().join("b.p3f"));
        let error = find_scene(&[a.clone(), b.clone()]).unwrap_err().to_string();
        let expected = format!(
            "no scene given, and the default benchmark scene is not at {} nor at {}; pass one: \
             whitted bench SCENE",
            a.display(),
            b.display()
        );
        assert_eq!(error, expected);
        std::fs::write(&b, "").unwrap();
        assert_eq!(find_scene(&[a.clone(), b.clone()]).unwrap(), b);
        std::fs::write(&a, "").unwrap();
        assert_eq!(find_scene(&[a.clone(), b]).unwrap(), a);
        // A directory of that name is not the scene.
        let c = dir.path().join("c.p3f");
        std::fs::create_dir(&c).unwrap();
        assert!(find_scene(&[c]).is_err());
    }
}
