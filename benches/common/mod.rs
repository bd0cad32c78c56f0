//! What the benches share: the scene they load and how long criterion measures.

use std::path::PathBuf;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion};

/// `WHITTED_BENCH_SCENE`, or the full dragon of the workload document.
pub fn scene_path() -> PathBuf {
    std::env::var("WHITTED_BENCH_SCENE")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon_full.p3f"))
}

/// A group of 10 samples over `seconds` each, or a quick smoke run with `WHITTED_BENCH_QUICK`.
pub fn group<'a>(c: &'a mut Criterion, name: &str, seconds: u64) -> BenchmarkGroup<'a, WallTime> {
    let mut g = c.benchmark_group(name);
    g.sample_size(10);
    if std::env::var_os("WHITTED_BENCH_QUICK").is_some() {
        g.warm_up_time(Duration::from_millis(100))
            .measurement_time(Duration::from_millis(500));
    } else {
        g.measurement_time(Duration::from_secs(seconds));
    }
    g
}
