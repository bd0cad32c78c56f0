//! Kernel throughput on the dragon workload (`shared/bench/dragon-workload.md`): primary rays
//! (closest hit), shadow rays (any hit) and diffuse bounces (closest hit, incoherent), one thread, in
//! Mrays/s through criterion's throughput. The workload's primary-hit count and Σt are checked first.
//!
//! `cargo bench --bench kernels`; `WHITTED_BENCH_QUICK=1` for a smoke run; `WHITTED_BENCH_SCENE` to
//! point at another scene (default `scenes/dragon_full.p3f`).

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use whitted::accel::{Accel, AccelKind, Hit, Prims};
use whitted::geometry::ray::Ray;
use whitted::workload::{self, Workload};

fn closest(accel: &Accel, rays: &[Ray]) -> usize {
    let mut hits = 0;
    for ray in rays {
        let mut hit = Hit::miss(f32::INFINITY);
        hits += accel.intersect(ray, 0.0, &mut hit) as usize;
    }
    hits
}

fn any(accel: &Accel, rays: &[(Ray, f32)]) -> usize {
    rays.iter()
        .filter(|(ray, t_max)| accel.occluded(ray, 0.0, *t_max))
        .count()
}

fn kernels(c: &mut Criterion) {
    let path = std::env::var("WHITTED_BENCH_SCENE")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon_full.p3f"));
    let scene = whitted::scene::load(&path).expect("the bench scene loads");
    let prims = Prims::new(&scene);
    let accels = [
        ("bvh4", Accel::build(prims, AccelKind::Bvh4)),
        ("bvh2", Accel::build(prims, AccelKind::Bvh2)),
    ];
    let w: Workload = workload::generate(&scene, &accels[0].1, 1);
    eprintln!(
        "{}: {} primary rays, {} hits, sum t = {:.2}; {} shadow and {} diffuse rays",
        path.display(),
        w.primary.len(),
        w.primary_hits,
        w.sum_t,
        w.shadow.len(),
        w.diffuse.len()
    );
    if path.ends_with("dragon_full.p3f") {
        // The workload document's independent figures: a wrong benchmark measures nothing.
        assert_eq!(w.primary_hits, 396_492, "primary hit count");
        assert!(
            (w.sum_t - 85_298.78).abs() < 85_298.78 * 1e-3,
            "primary sum t {}",
            w.sum_t
        );
    }
    for (name, accel) in &accels {
        // Every kernel finds the same hits on the same rays.
        assert_eq!(closest(accel, &w.primary), w.primary_hits, "{name} primary hits");
    }
    let hits_shadow = any(&accels[0].1, &w.shadow);
    let hits_diffuse = closest(&accels[0].1, &w.diffuse);
    for (name, accel) in &accels[1..] {
        assert_eq!(any(accel, &w.shadow), hits_shadow, "{name} shadow hits");
        assert_eq!(closest(accel, &w.diffuse), hits_diffuse, "{name} diffuse hits");
    }

    let mut group = c.benchmark_group("dragon");
    if std::env::var_os("WHITTED_BENCH_QUICK").is_some() {
        group
            .sample_size(10)
            .warm_up_time(Duration::from_millis(100))
            .measurement_time(Duration::from_millis(500));
    } else {
        group.sample_size(10).measurement_time(Duration::from_secs(5));
    }
    for (name, accel) in &accels {
        group.throughput(Throughput::Elements(w.primary.len() as u64));
        group.bench_function(format!("{name}/primary"), |b| {
            b.iter(|| closest(accel, black_box(&w.primary)))
        });
        group.throughput(Throughput::Elements(w.shadow.len() as u64));
        group.bench_function(format!("{name}/shadow"), |b| {
            b.iter(|| any(accel, black_box(&w.shadow)))
        });
        group.throughput(Throughput::Elements(w.diffuse.len() as u64));
        group.bench_function(format!("{name}/diffuse"), |b| {
            b.iter(|| closest(accel, black_box(&w.diffuse)))
        });
    }
    group.finish();
}

criterion_group!(benches, kernels);
criterion_main!(benches);
