//! `whitted bench`: frames per second of a scene (by default the course's dragon scene), with the
//! report `render --stats` prints (rays by kind, Mrays/s, times, structure, threads) and each frame's
//! time.

mod args;
mod plan;
mod print;
mod timing;

use std::time::Instant;

use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::memory;

pub use args::BenchArgs;

use super::Failure;
use super::report::Report;
use super::setup::{load_scene, thread_pool, warn};

/// Renders the frames and prints their timing.
pub fn run(args: &BenchArgs) -> Result<(), Failure> {
    let path = plan::scene(args)?;
    let pool = thread_pool(args.frame.threads)?;
    let start = Instant::now();
    let mut scene = pool.install(|| load_scene(Some(&path), args.format))?;
    warn(&scene.warnings);
    args.camera.apply(&mut scene.camera).map_err(Failure::Usage)?;
    let loaded = start.elapsed();
    let options = plan::options(args, &scene).map_err(Failure::Usage)?;
    // Checked before the structures are built: the frames are allocated after.
    memory::check(options.width, options.height, options.count_steps, false).map_err(whitted::Error::msg)?;
    let build = |kind: AccelKind| {
        let start = Instant::now();
        let accel = pool.install(|| Accel::try_build_with(Prims::new(&scene), kind, Default::default()))?;
        Ok::<_, whitted::Error>((accel, start.elapsed()))
    };
    let (accel, built) = build(args.frame.accel)?;
    let other = args.compare.map(build).transpose()?;
    let accels = std::iter::once((&accel, built)).chain(other.as_ref().map(|(a, b)| (a, *b)));
    let timed = timing::time(&scene, options, &pool, accels, args.frames);
    let threads = pool.current_num_threads();
    let reports: Vec<Report> = timed
        .iter()
        .map(|t| t.report(&path, &options, loaded, threads))
        .collect();
    if args.json {
        Ok(print::json(&timed, &reports)?)
    } else {
        Ok(print::text(&timed, &reports)?)
    }
}
