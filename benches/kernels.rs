//! Kernel throughput on the dragon workload (`shared/bench/dragon-workload.md`), one thread, in Mrays/s
//! through criterion's throughput: primary rays (closest hit), shadow rays (any hit, and closest hit on
//! the same rays for comparison, and both on the blocked ones alone) and diffuse bounces (closest hit,
//! incoherent), for every accelerator,
//! and for the BVH4's packet kernel (8 consecutive rays a packet). Brute force runs on an evenly spaced
//! sample of each set. The workload's primary-hit count and Σt, and every structure's hit counts, are
//! checked first: a wrong benchmark measures nothing.
//!
//! `cargo bench --bench kernels`; `WHITTED_BENCH_QUICK=1` for a smoke run; `WHITTED_BENCH_SCENE` to
//! point at another scene (default `scenes/dragon_full.p3f`).

mod common;

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use whitted::accel::bvh2::Builder;
use whitted::accel::bvh4::Bvh4;
use whitted::accel::bvh4::packet::PACKET;
use whitted::accel::policy::{AnyHit, Closest};
use whitted::accel::{Accel, AccelKind, BuildOptions, Hit, Prims};
use whitted::geometry::ray::Ray;
use whitted::workload::{self, Workload};

/// Rays of each set that brute force traces (it tests all 871k triangles per ray).
const BRUTE_SAMPLE: usize = 64;

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

/// Closest hit on segments (the shadow rays): the same rays as [`any`], the other kernel.
fn closest_within(accel: &Accel, rays: &[(Ray, f32)]) -> usize {
    let mut hits = 0;
    for (ray, t_max) in rays {
        let mut hit = Hit::miss(*t_max);
        hits += accel.intersect(ray, 0.0, &mut hit) as usize;
    }
    hits
}

/// Rays in packets of eight, each with its `t_max`.
type Packets = Vec<([Ray; PACKET], [f32; PACKET], u8)>;

fn packets(rays: &[(Ray, f32)]) -> Packets {
    rays.chunks(PACKET)
        .map(|c| {
            let mut r = [c[0].0; PACKET];
            let mut t = [0.0; PACKET];
            for (k, (ray, t_max)) in c.iter().enumerate() {
                (r[k], t[k]) = (*ray, *t_max);
            }
            (r, t, (1u16 << c.len()).wrapping_sub(1) as u8)
        })
        .collect()
}

fn packet_hits<const ANY: bool>(bvh: &Bvh4, packets: &Packets) -> usize {
    let mut hits = 0;
    for (rays, t_max, active) in packets {
        let mut h = t_max.map(Hit::miss);
        let found = if ANY {
            bvh.traverse_packet::<AnyHit>(rays, *active, 0.0, &mut h)
        } else {
            bvh.traverse_packet::<Closest>(rays, *active, 0.0, &mut h)
        };
        hits += found.count_ones() as usize;
    }
    hits
}

fn sample<T: Copy>(v: &[T]) -> Vec<T> {
    let step = (v.len() / BRUTE_SAMPLE).max(1);
    v.iter().step_by(step).take(BRUTE_SAMPLE).copied().collect()
}

fn kernels(c: &mut Criterion) {
    let path = common::scene_path();
    let scene = whitted::scene::load(&path).expect("the bench scene loads");
    let prims = Prims::new(&scene);
    let with = |kind, builder| Accel::build_with(prims, kind, BuildOptions { builder, bins: 12 });
    let sah = Builder::Sah { bins: 12 };
    let accels = [
        ("bvh4", with(AccelKind::Bvh4, sah)),
        ("bvh2-sah", with(AccelKind::Bvh2, sah)),
        ("bvh2-midpoint", with(AccelKind::Bvh2, Builder::Midpoint)),
        ("grid", with(AccelKind::Grid, sah)),
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
        // The workload document's independent figures.
        assert_eq!(w.primary_hits, 396_492, "primary hit count");
        assert!(
            (w.sum_t - 85_298.78).abs() < 85_298.78 * 1e-3,
            "primary sum t {}",
            w.sum_t
        );
    }
    let hits_shadow = any(&accels[0].1, &w.shadow);
    let hits_diffuse = closest(&accels[0].1, &w.diffuse);
    for (name, accel) in &accels {
        // Every structure finds the same hits on the same rays, with either kernel.
        assert_eq!(closest(accel, &w.primary), w.primary_hits, "{name} primary hits");
        assert_eq!(any(accel, &w.shadow), hits_shadow, "{name} shadow hits");
        assert_eq!(
            closest_within(accel, &w.shadow),
            hits_shadow,
            "{name} shadow hits"
        );
        assert_eq!(closest(accel, &w.diffuse), hits_diffuse, "{name} diffuse hits");
    }
    let Accel::Bvh4(bvh4) = &accels[0].1 else {
        panic!("the bench scene fits a BVH4")
    };
    let unbounded = |rays: &[Ray]| rays.iter().map(|r| (*r, f32::INFINITY)).collect::<Vec<_>>();
    let primary_packets = packets(&unbounded(&w.primary));
    let shadow_packets = packets(&w.shadow);
    let diffuse_packets = packets(&unbounded(&w.diffuse));
    assert_eq!(packet_hits::<false>(bvh4, &primary_packets), w.primary_hits);
    assert_eq!(packet_hits::<true>(bvh4, &shadow_packets), hits_shadow);
    assert_eq!(packet_hits::<false>(bvh4, &diffuse_packets), hits_diffuse);

    let mut g = common::group(c, "dragon", 4);
    for (name, accel) in &accels {
        g.throughput(Throughput::Elements(w.primary.len() as u64));
        g.bench_function(format!("{name}/primary"), |b| {
            b.iter(|| closest(accel, black_box(&w.primary)))
        });
        g.throughput(Throughput::Elements(w.shadow.len() as u64));
        g.bench_function(format!("{name}/shadow-any"), |b| {
            b.iter(|| any(accel, black_box(&w.shadow)))
        });
        g.bench_function(format!("{name}/shadow-closest"), |b| {
            b.iter(|| closest_within(accel, black_box(&w.shadow)))
        });
        g.throughput(Throughput::Elements(w.diffuse.len() as u64));
        g.bench_function(format!("{name}/diffuse"), |b| {
            b.iter(|| closest(accel, black_box(&w.diffuse)))
        });
    }
    // The shadow rays that something blocks (6.4% on the full dragon): where any hit can stop early
    // and closest hit cannot. On the unblocked rest both must prove the whole segment empty.
    let blocked: Vec<(Ray, f32)> = w
        .shadow
        .iter()
        .filter(|(r, t)| accels[0].1.occluded(r, 0.0, *t))
        .copied()
        .collect();
    eprintln!(
        "{} of the {} shadow rays are blocked",
        blocked.len(),
        w.shadow.len()
    );
    for (name, accel) in &accels[..2] {
        g.throughput(Throughput::Elements(blocked.len() as u64));
        g.bench_function(format!("{name}/blocked-any"), |b| {
            b.iter(|| any(accel, black_box(&blocked)))
        });
        g.bench_function(format!("{name}/blocked-closest"), |b| {
            b.iter(|| closest_within(accel, black_box(&blocked)))
        });
    }
    for (set, p, any) in [
        ("primary", &primary_packets, false),
        ("shadow-any", &shadow_packets, true),
        ("diffuse", &diffuse_packets, false),
    ] {
        g.throughput(Throughput::Elements(
            p.iter().map(|p| p.2.count_ones() as u64).sum(),
        ));
        g.bench_function(format!("bvh4-packet/{set}"), |b| {
            b.iter(|| match any {
                true => packet_hits::<true>(bvh4, black_box(p)),
                false => packet_hits::<false>(bvh4, black_box(p)),
            })
        });
    }
    g.finish();

    let brute = Accel::build(prims, AccelKind::None);
    let (primary, shadow, diffuse) = (sample(&w.primary), sample(&w.shadow), sample(&w.diffuse));
    for (name, accel) in &accels {
        assert_eq!(
            closest(&brute, &primary),
            closest(accel, &primary),
            "{name} vs brute force"
        );
    }
    let mut g = common::group(c, "dragon-sample", 4);
    g.throughput(Throughput::Elements(primary.len() as u64));
    g.bench_function("brute/primary", |b| {
        b.iter(|| closest(&brute, black_box(&primary)))
    });
    g.throughput(Throughput::Elements(shadow.len() as u64));
    g.bench_function("brute/shadow-any", |b| b.iter(|| any(&brute, black_box(&shadow))));
    g.throughput(Throughput::Elements(diffuse.len() as u64));
    g.bench_function("brute/diffuse", |b| {
        b.iter(|| closest(&brute, black_box(&diffuse)))
    });
    g.finish();
}

criterion_group!(benches, kernels);
criterion_main!(benches);
