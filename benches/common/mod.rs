//! What the benches share: the scene they load, how long criterion measures, the peer they are measured
//! against and the table they print.

pub mod obvhs;
pub mod table;

use std::path::{Path, PathBuf};
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion};

/// The scenes a bench runs on: `WHITTED_BENCH_SCENE` alone, or the workload document's two dragons,
/// the full one (871,414 triangles, `scenes/dragon_full.p3f`) and res2 (202,520; loaded bare, its
/// default camera and light are the document's, computed from its bounds); res2 alone for a smoke run
/// (`WHITTED_BENCH_QUICK`).
pub fn scenes() -> Vec<PathBuf> {
    if let Some(path) = std::env::var_os("WHITTED_BENCH_SCENE") {
        return vec![PathBuf::from(path)];
    }
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let res2 = dir.join("models/dragon_vrip_res2.ply.gz");
    if quick() {
        return vec![res2];
    }
    vec![dir.join("dragon_full.p3f"), res2]
}

/// True for a smoke run: `WHITTED_BENCH_QUICK` is set.
pub fn quick() -> bool {
    std::env::var_os("WHITTED_BENCH_QUICK").is_some()
}

/// A short name for a scene in bench ids: its file name up to the first dot.
pub fn scene_name(path: &Path) -> String {
    let name = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    name.split('.').next().unwrap_or_default().to_string()
}

/// A group of 10 samples over `seconds` each, or a quick smoke run with `WHITTED_BENCH_QUICK`.
pub fn group<'a>(c: &'a mut Criterion, name: &str, seconds: u64) -> BenchmarkGroup<'a, WallTime> {
    let mut g = c.benchmark_group(name);
    g.sample_size(10);
    if quick() {
        g.warm_up_time(Duration::from_millis(100))
            .measurement_time(Duration::from_millis(500));
    } else {
        g.measurement_time(Duration::from_secs(seconds));
    }
    g
}
