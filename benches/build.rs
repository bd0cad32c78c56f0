//! Build times of every structure over the full Stanford dragon (871,414 triangles): the BVH2 by
//! midpoint and by binned SAH, the BVH4 (SAH BVH2 collapsed), the uniform grid; on one thread and on all
//! of them (the builders split large subtrees across rayon's workers).
//!
//! `cargo bench --bench build`; `WHITTED_BENCH_QUICK=1` for a smoke run; `WHITTED_BENCH_SCENE` to point
//! at another scene.

use std::path::PathBuf;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use whitted::accel::bvh2::Builder;
use whitted::accel::{Accel, AccelKind, BuildOptions, Prims};

fn build(c: &mut Criterion) {
    let path = std::env::var("WHITTED_BENCH_SCENE")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon_full.p3f"));
    let scene = whitted::scene::load(&path).expect("the bench scene loads");
    let prims = Prims::new(&scene);
    let sah = Builder::Sah { bins: 12 };
    let structures = [
        ("bvh2-midpoint", AccelKind::Bvh2, Builder::Midpoint),
        ("bvh2-sah", AccelKind::Bvh2, sah),
        ("bvh4", AccelKind::Bvh4, sah),
        ("grid", AccelKind::Grid, sah),
    ];
    let mut g = c.benchmark_group("build");
    if std::env::var_os("WHITTED_BENCH_QUICK").is_some() {
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(100))
            .measurement_time(Duration::from_millis(500));
    } else {
        g.sample_size(10).measurement_time(Duration::from_secs(8));
    }
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    for threads in [1, all] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        for (name, kind, builder) in structures {
            let options = BuildOptions { builder, bins: 12 };
            g.bench_function(format!("{name}/{threads}-threads"), |b| {
                b.iter(|| pool.install(|| Accel::build_with(prims, kind, options)))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, build);
criterion_main!(benches);
