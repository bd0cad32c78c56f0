//! The frames `bench` times: each accelerator's, alternated frame by frame, and their spread.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use rayon::ThreadPool;
use whitted::accel::Accel;
use whitted::render::{Options, RayCounts, Renderer};
use whitted::scene::Scene;

use crate::cli::report::Report;
use crate::cli::setup::warn;

/// One accelerator's frames: the renderer and the frame times.
pub struct Timed<'a> {
    renderer: Renderer<'a>,
    accel: &'a Accel<'a>,
    built: Duration,
    /// Each timed frame's milliseconds.
    pub ms: Vec<f64>,
    rays: RayCounts,
}

/// Times `frames` frames of `scene` with each of `accels` (and the time it took to build) after one
/// frame of warm-up, which counts the rays' steps if `options` ask for it (the timed frames never
/// count: counting costs time). With two (--compare) they alternate frame by frame, so that a change
/// in the machine's load falls on both.
pub fn time<'a>(
    scene: &'a Scene,
    options: Options,
    pool: &ThreadPool,
    accels: impl Iterator<Item = (&'a Accel<'a>, Duration)>,
    frames: u32,
) -> Vec<Timed<'a>> {
    let never = AtomicBool::new(false);
    // Every frame is pass 1: the same rays, so the frames time the same work.
    let frame = |r: &Renderer| pool.install(|| r.render_pass(1, &|| {}, &never).expect("never stopped"));
    let mut timed: Vec<Timed> = accels
        .map(|(accel, built)| {
            let (_, rays) = frame(&Renderer::new(scene, accel, options));
            let renderer = Renderer::new(
                scene,
                accel,
                Options {
                    count_steps: false,
                    ..options
                },
            );
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
    for _ in 0..frames {
        for t in &mut timed {
            let start = Instant::now();
            frame(&t.renderer);
            t.ms.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    timed
}

impl Timed<'_> {
    /// The median frame's milliseconds.
    pub fn median(&self) -> f64 {
        spread(&self.ms).0
    }

    /// The report of the median frame of `scene`, loaded in `loaded`, on `threads` threads.
    pub fn report(&self, scene: &Path, options: &Options, loaded: Duration, threads: usize) -> Report {
        let times = [loaded, self.built, Duration::from_secs_f64(self.median() / 1e3)];
        // Embree's steps are not counted: no columns of zeros for it.
        let options = Options {
            count_steps: options.count_steps && self.accel.counts_steps(),
            ..*options
        };
        Report {
            per_frame: true,
            ..Report::new(Some(scene), &options, self.accel, threads, times, self.rays)
        }
    }
}

/// The median, least and most of the frame times `ms` (at least one).
pub fn spread(ms: &[f64]) -> (f64, f64, f64) {
    let mut ms = ms.to_vec();
    ms.sort_by(f64::total_cmp);
    let median = if ms.len() % 2 == 1 {
        ms[ms.len() / 2]
    } else {
        (ms[ms.len() / 2 - 1] + ms[ms.len() / 2]) / 2.0
    };
    (median, ms[0], ms[ms.len() - 1])
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
}
