//! Build times of every structure over the full Stanford dragon (871,414 triangles): the BVH2 by
//! midpoint and by binned SAH, the BVH4 (SAH BVH2 collapsed), the uniform grid; on one thread and on all
//! of them (the builders split large subtrees across rayon's workers).
//!
//! `cargo bench --bench build`; `WHITTED_BENCH_QUICK=1` for a smoke run; `WHITTED_BENCH_SCENE` to point
//! at another scene.

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use whitted::accel::bvh2::Builder;
use whitted::accel::{Accel, AccelKind, BuildOptions, Prims};

fn build(c: &mut Criterion) {
    let scene = whitted::scene::load(&common::scene_path()).expect("the bench scene loads");
    let prims = Prims::new(&scene);
    let sah = Builder::Sah { bins: 12 };
    let structures = [
        ("bvh2-midpoint", AccelKind::Bvh2, Builder::Midpoint),
        ("bvh2-sah", AccelKind::Bvh2, sah),
        ("bvh4", AccelKind::Bvh4, sah),
        ("grid", AccelKind::Grid, sah),
    ];
    let mut g = common::group(c, "build", 8);
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
