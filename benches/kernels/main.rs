//! Kernel throughput on the dragon workload (`shared/bench/dragon-workload.md`), one thread, in Mrays/s
//! through criterion's throughput: primary rays (closest hit), shadow rays (any hit, and closest hit on
//! the same rays for comparison, and both on the blocked ones alone) and diffuse bounces (closest hit,
//! incoherent), for every accelerator, for the BVH4's packet kernel (8 consecutive rays a packet) and for
//! obvhs 0.4's CWBVH and BVH2 (`very_slow_build`, its best trees, traced with our triangle test); then the
//! BVH4 and the peers on all threads. Brute force runs on an evenly spaced sample of each set. The
//! workload's primary-hit count and Σt, and every structure's hit counts (ours and the peers'), are
//! checked first: a wrong benchmark measures nothing. At the end, a table of the medians side by side.
//! With `--features bench-embree`, Embree 3 joins them: single rays and 8-wide packets, on its
//! high-quality (spatial split) BVH. With `--features bench-tinybvh`, tinybvh's BVH8_CPU (closest hit only:
//! the shadow rays within the light distance; needs `RUSTFLAGS="-C target-cpu=native"`, `tinybvh.rs`).
//!
//! `cargo bench --bench kernels`; `WHITTED_BENCH_QUICK=1` for a smoke run; `WHITTED_BENCH_SCENE` for one
//! other scene (default: the full dragon, then res2).

#[path = "../common/mod.rs"]
mod common;
#[cfg(feature = "bench-embree")]
mod embree;
mod peer;
#[cfg(feature = "bench-tinybvh")]
mod tinybvh;

use std::hint::black_box;
use std::time::SystemTime;

use common::{obvhs as obvhs_build, table};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use peer::Traced;
use rayon::prelude::*;
use whitted::accel::PACKET;
#[cfg(any(feature = "bench-embree", feature = "bench-tinybvh"))]
use whitted::accel::PrimKind;
use whitted::accel::bvh2::Builder;
use whitted::accel::policy::{AnyHit, Closest};
use whitted::accel::wide::{Simd, WideBvh};
use whitted::accel::{Accel, AccelKind, BuildOptions, Hit, Prims};
use whitted::geometry::ray::Ray;
use whitted::kit::workload::{self, Workload};

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
type Packet = ([Ray; PACKET], [f32; PACKET], u8);
type Packets = Vec<Packet>;

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

fn packet_hits<const ANY: bool, const W: usize>(bvh: &WideBvh<W>, packets: &[Packet]) -> usize {
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

#[cfg(any(feature = "bench-embree", feature = "bench-tinybvh"))]
/// Barycentric distance (exact enough: f64) of the point where `ray` crosses the plane of triangle
/// `[a, b, c]` from the triangle's nearest edge: min(u, v, 1 − u − v), negative outside.
fn edge_margin(ray: &Ray, [a, b, c]: [glam::Vec3; 3]) -> f64 {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (a, e1, e2) = (a.as_dvec3(), (b - a).as_dvec3(), (c - a).as_dvec3());
    let p = d.cross(e2);
    let det = e1.dot(p);
    let s = o - a;
    let u = s.dot(p) / det;
    let v = d.dot(s.cross(e1)) / det;
    u.min(v).min(1.0 - u - v)
}

#[cfg(any(feature = "bench-embree", feature = "bench-tinybvh"))]
/// A peer with its own triangle test may round differently from ours on rays that cross within f32
/// precision of an edge (ours is not watertight, `geometry/triangle.rs`): where the hit counts differ,
/// every ray on which the peer (`theirs`: the triangle a segment hits first) and we disagree must cross
/// within 1e-5 of an edge of the triangle that the side that hit reports. Anything else is a bug and
/// fails the bench.
fn reconcile(
    peer: &str,
    rays: &[(Ray, f32)],
    theirs: impl Fn(&(Ray, f32)) -> Option<u32>,
    ours: &Accel,
    scene: &whitted::scene::Scene,
) {
    const EDGE: f64 = 1e-5;
    let prims = Prims::new(scene);
    let (mut differ, mut worst) = (0, 0.0f64);
    for (i, r) in rays.iter().enumerate() {
        let mut hit = Hit::miss(r.1);
        let ours = ours
            .intersect(&r.0, 0.0, &mut hit)
            .then(|| match prims.kind(hit.prim) {
                PrimKind::Triangle(t) => t as u32,
                _ => panic!("the bench scene holds triangles only"),
            });
        let theirs = theirs(r);
        let Some(tri) = (match (ours, theirs) {
            (Some(_), Some(_)) | (None, None) => None,
            (hit, None) | (None, hit) => hit,
        }) else {
            continue;
        };
        let margin = edge_margin(&r.0, scene.triangles.vertices(tri as usize));
        assert!(
            margin.abs() < EDGE,
            "{peer}: ray {i} {:?} (t_max {}): ours {ours:?}, theirs {theirs:?}, {margin} from an edge",
            r.0,
            r.1
        );
        differ += 1;
        worst = worst.max(margin.abs());
    }
    eprintln!(
        "{peer}: {differ} of {} rays differ from ours, all within {worst:.1e} of a triangle edge",
        rays.len()
    );
}

fn sample<T: Copy>(v: &[T]) -> Vec<T> {
    let step = (v.len() / BRUTE_SAMPLE).max(1);
    v.iter().step_by(step).take(BRUTE_SAMPLE).copied().collect()
}

/// Counts over `items` split across the rayon pool: the all-threads rows.
fn par<T: Sync>(items: &[T], count: impl Fn(&[T]) -> usize + Sync + Send) -> usize {
    items.par_chunks(256).map(count).sum()
}

/// The three ray sets in the table: name, rays traced, and the ids of each column's bench.
const SETS: [&str; 3] = ["primary", "shadow-any", "diffuse"];

fn kernels(c: &mut Criterion) {
    let since = SystemTime::now();
    for path in common::scenes() {
        scene(c, &path, since);
    }
}

fn scene(c: &mut Criterion, path: &std::path::Path, since: SystemTime) {
    let scene = whitted::scene::load(path).expect("the bench scene loads");
    let prims = Prims::new(&scene);
    let with = |kind, builder| Accel::build_with(prims, kind, BuildOptions { builder, bins: 12 });
    let sah = Builder::Sah { bins: 12 };
    // The BVH8 on its portable slab test too (two SSE halves), beside the AVX2 one where the CPU has it.
    let mut bvh8_portable = with(AccelKind::Bvh8, sah);
    if let Accel::Bvh8(b) = &mut bvh8_portable {
        b.set_simd(Simd::Portable);
    }
    let accels = [
        ("bvh4", with(AccelKind::Bvh4, sah)),
        ("bvh8", with(AccelKind::Bvh8, sah)),
        ("bvh8-portable", bvh8_portable),
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
    let (Accel::Bvh4(bvh4), Accel::Bvh8(bvh8)) = (&accels[0].1, &accels[1].1) else {
        panic!("the bench scene fits the wide BVHs")
    };
    let unbounded = |rays: &[Ray]| rays.iter().map(|r| (*r, f32::INFINITY)).collect::<Vec<_>>();
    let primary_segments = unbounded(&w.primary);
    let diffuse_segments = unbounded(&w.diffuse);
    let primary_packets = packets(&primary_segments);
    let shadow_packets = packets(&w.shadow);
    let diffuse_packets = packets(&diffuse_segments);
    assert_eq!(packet_hits::<false, 4>(bvh4, &primary_packets), w.primary_hits);
    assert_eq!(packet_hits::<true, 4>(bvh4, &shadow_packets), hits_shadow);
    assert_eq!(packet_hits::<false, 4>(bvh4, &diffuse_packets), hits_diffuse);
    assert_eq!(packet_hits::<false, 8>(bvh8, &primary_packets), w.primary_hits);
    assert_eq!(packet_hits::<true, 8>(bvh8, &shadow_packets), hits_shadow);
    assert_eq!(packet_hits::<false, 8>(bvh8, &diffuse_packets), hits_diffuse);

    // The peers, on their best trees, must find the same hits: a mismatch is a bug on one side.
    let tris = obvhs_build::triangles(&scene);
    let params = obvhs::BvhBuildParams::very_slow_build();
    let cwbvh = Traced::new(obvhs_build::cwbvh(&tris, params), &tris);
    let obvh2 = Traced::new(obvhs_build::bvh2(&tris, params), &tris);
    assert_eq!(
        cwbvh.closest(&w.primary),
        w.primary_hits,
        "obvhs cwbvh primary hits"
    );
    assert_eq!(cwbvh.occluded(&w.shadow), hits_shadow, "obvhs cwbvh shadow hits");
    assert_eq!(
        cwbvh.closest(&w.diffuse),
        hits_diffuse,
        "obvhs cwbvh diffuse hits"
    );
    assert_eq!(
        obvh2.closest(&w.primary),
        w.primary_hits,
        "obvhs bvh2 primary hits"
    );
    assert_eq!(obvh2.occluded(&w.shadow), hits_shadow, "obvhs bvh2 shadow hits");
    assert_eq!(obvh2.closest(&w.diffuse), hits_diffuse, "obvhs bvh2 diffuse hits");
    #[cfg(feature = "bench-embree")]
    let embree = {
        use common::embree::EmbreeScene;
        let all = std::thread::available_parallelism().map_or(1, |n| n.get());
        let e = EmbreeScene::new(&scene, all, true);
        for (set, rays, any, hits) in [
            ("primary", &primary_segments, false, w.primary_hits),
            ("shadow", &w.shadow, true, hits_shadow),
            ("diffuse", &diffuse_segments, false, hits_diffuse),
        ] {
            let (one, eight) = match any {
                true => (e.occluded(rays), e.occluded8(rays)),
                false => (e.closest(rays), e.closest8(rays)),
            };
            if one != hits || eight != hits {
                reconcile(
                    &format!("Embree {set}"),
                    rays,
                    |(r, t)| e.hit(r, *t),
                    &accels[0].1,
                    &scene,
                );
            }
        }
        e
    };
    #[cfg(feature = "bench-tinybvh")]
    let tiny = tinybvh::Tiny::new(&scene).checked(
        [
            ("primary", &primary_segments, w.primary_hits),
            ("shadow", &w.shadow, hits_shadow),
            ("diffuse", &diffuse_segments, hits_diffuse),
        ],
        &accels[0].1,
        &scene,
    );

    let name = common::scene_name(path);
    let group = format!("kernels-{name}");
    let mut g = common::group(c, &group, 4);
    let (n_primary, n_shadow, n_diffuse) = (
        w.primary.len() as u64,
        w.shadow.len() as u64,
        w.diffuse.len() as u64,
    );
    for (name, accel) in &accels {
        g.throughput(Throughput::Elements(n_primary));
        g.bench_function(format!("{name}/primary"), |b| {
            b.iter(|| closest(accel, black_box(&w.primary)))
        });
        g.throughput(Throughput::Elements(n_shadow));
        g.bench_function(format!("{name}/shadow-any"), |b| {
            b.iter(|| any(accel, black_box(&w.shadow)))
        });
        g.bench_function(format!("{name}/shadow-closest"), |b| {
            b.iter(|| closest_within(accel, black_box(&w.shadow)))
        });
        g.throughput(Throughput::Elements(n_diffuse));
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
    for (name, accel) in accels
        .iter()
        .filter(|(n, _)| ["bvh4", "bvh8", "bvh2-sah"].contains(n))
    {
        g.throughput(Throughput::Elements(blocked.len() as u64));
        g.bench_function(format!("{name}/blocked-any"), |b| {
            b.iter(|| any(accel, black_box(&blocked)))
        });
        g.bench_function(format!("{name}/blocked-closest"), |b| {
            b.iter(|| closest_within(accel, black_box(&blocked)))
        });
    }
    let packet_sets = [
        (&primary_packets, false),
        (&shadow_packets, true),
        (&diffuse_packets, false),
    ];
    for (set, (p, any)) in SETS.iter().zip(packet_sets) {
        g.throughput(Throughput::Elements(
            p.iter().map(|p| p.2.count_ones() as u64).sum(),
        ));
        g.bench_function(format!("bvh4-packet/{set}"), |b| {
            b.iter(|| match any {
                true => packet_hits::<true, 4>(bvh4, black_box(p)),
                false => packet_hits::<false, 4>(bvh4, black_box(p)),
            })
        });
        g.bench_function(format!("bvh8-packet/{set}"), |b| {
            b.iter(|| match any {
                true => packet_hits::<true, 8>(bvh8, black_box(p)),
                false => packet_hits::<false, 8>(bvh8, black_box(p)),
            })
        });
    }
    macro_rules! peer {
        ($id:literal, $t:expr) => {
            g.throughput(Throughput::Elements(n_primary));
            g.bench_function(concat!($id, "/primary"), |b| {
                b.iter(|| $t.closest(black_box(&w.primary)))
            });
            g.throughput(Throughput::Elements(n_shadow));
            g.bench_function(concat!($id, "/shadow-any"), |b| {
                b.iter(|| $t.occluded(black_box(&w.shadow)))
            });
            g.throughput(Throughput::Elements(n_diffuse));
            g.bench_function(concat!($id, "/diffuse"), |b| {
                b.iter(|| $t.closest(black_box(&w.diffuse)))
            });
        };
    }
    peer!("obvhs-cwbvh", cwbvh);
    peer!("obvhs-bvh2", obvh2);
    // tinybvh: closest hit on every set (the shadow rays within the light distance: it has no any hit).
    #[cfg(feature = "bench-tinybvh")]
    if let Some(tiny) = &tiny {
        for (set, rays, n) in [
            ("primary", &primary_segments, n_primary),
            ("shadow-any", &w.shadow, n_shadow),
            ("diffuse", &diffuse_segments, n_diffuse),
        ] {
            g.throughput(Throughput::Elements(n));
            g.bench_function(format!("{}/{set}", tinybvh::ID), |b| {
                b.iter(|| tiny.closest(black_box(rays)))
            });
        }
    }

    // All threads: the same work split in chunks of 256 rays (32 packets) across rayon's pool.
    let all = rayon::current_num_threads();
    for (name, accel) in accels.iter().filter(|(n, _)| ["bvh4", "bvh8"].contains(n)) {
        g.throughput(Throughput::Elements(n_primary));
        g.bench_function(format!("{name}/primary/{all}-threads"), |b| {
            b.iter(|| par(black_box(&w.primary), |r| closest(accel, r)))
        });
        g.throughput(Throughput::Elements(n_shadow));
        g.bench_function(format!("{name}/shadow-any/{all}-threads"), |b| {
            b.iter(|| par(black_box(&w.shadow), |r| any(accel, r)))
        });
        g.throughput(Throughput::Elements(n_diffuse));
        g.bench_function(format!("{name}/diffuse/{all}-threads"), |b| {
            b.iter(|| par(black_box(&w.diffuse), |r| closest(accel, r)))
        });
    }
    g.throughput(Throughput::Elements(n_primary));
    g.bench_function(format!("bvh4-packet/primary/{all}-threads"), |b| {
        b.iter(|| par(black_box(&primary_packets), |p| packet_hits::<false, 4>(bvh4, p)))
    });
    g.bench_function(format!("obvhs-cwbvh/primary/{all}-threads"), |b| {
        b.iter(|| par(black_box(&w.primary), |r| cwbvh.closest(r)))
    });
    g.throughput(Throughput::Elements(n_shadow));
    g.bench_function(format!("bvh4-packet/shadow-any/{all}-threads"), |b| {
        b.iter(|| par(black_box(&shadow_packets), |p| packet_hits::<true, 4>(bvh4, p)))
    });
    g.bench_function(format!("obvhs-cwbvh/shadow-any/{all}-threads"), |b| {
        b.iter(|| par(black_box(&w.shadow), |r| cwbvh.occluded(r)))
    });
    g.throughput(Throughput::Elements(n_diffuse));
    g.bench_function(format!("bvh4-packet/diffuse/{all}-threads"), |b| {
        b.iter(|| par(black_box(&diffuse_packets), |p| packet_hits::<false, 4>(bvh4, p)))
    });
    g.bench_function(format!("obvhs-cwbvh/diffuse/{all}-threads"), |b| {
        b.iter(|| par(black_box(&w.diffuse), |r| cwbvh.closest(r)))
    });
    // Embree, single rays and 8-wide packets, on one thread and on all of them.
    #[cfg(feature = "bench-embree")]
    for threaded in [false, true] {
        type Kernel<'k> = &'k (dyn Fn(&[(Ray, f32)]) -> usize + Sync);
        let suffix = if threaded {
            format!("/{all}-threads")
        } else {
            String::new()
        };
        let run = |rays: &[(Ray, f32)], f: Kernel| if threaded { par(rays, f) } else { f(rays) };
        for (set, rays, any, n) in [
            ("primary", &primary_segments, false, n_primary),
            ("shadow-any", &w.shadow, true, n_shadow),
            ("diffuse", &diffuse_segments, false, n_diffuse),
        ] {
            g.throughput(Throughput::Elements(n));
            g.bench_function(format!("embree/{set}{suffix}"), |b| {
                b.iter(|| match any {
                    true => run(black_box(rays), &|r| embree.occluded(r)),
                    false => run(black_box(rays), &|r| embree.closest(r)),
                })
            });
            g.bench_function(format!("embree-8/{set}{suffix}"), |b| {
                b.iter(|| match any {
                    true => run(black_box(rays), &|r| embree.occluded8(r)),
                    false => run(black_box(rays), &|r| embree.closest8(r)),
                })
            });
        }
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
    let sample_group = format!("{group}-sample");
    let mut g = common::group(c, &sample_group, 4);
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

    // The side-by-side table, in Mrays/s, with our kernels' ratios to the best peer of each kind.
    let counts = [n_primary, n_shadow, n_diffuse].map(|n| n as f64);
    let mrays = |id: String, n: f64| table::median(&group, &id, since).map(|s| n / s * 1e-6);
    let ratio = |a: Option<f64>, b: Option<f64>| a.zip(b).map(|(a, b)| format!("{:.2}x", a / b));
    let mut columns = vec![
        "bvh4",
        "bvh8",
        "bvh4-packet",
        "bvh8-packet",
        "bvh2-sah",
        "obvhs-cwbvh",
        "obvhs-bvh2",
    ];
    if cfg!(feature = "bench-embree") {
        columns.extend(["embree", "embree-8"]);
    }
    #[cfg(feature = "bench-tinybvh")]
    columns.push(tinybvh::ID);
    let mut header = vec!["rays"];
    header.extend(&columns);
    header.extend(["best single / best obvhs", "best packets / best obvhs"]);
    if cfg!(feature = "bench-embree") {
        header.extend(["best single / embree", "best packets / embree-8"]);
    }
    #[cfg(feature = "bench-tinybvh")]
    let tiny_ratio = format!("best single / {}", tinybvh::ID);
    #[cfg(feature = "bench-tinybvh")]
    header.push(&tiny_ratio);
    for threads in [1, all] {
        let suffix = match threads {
            1 => String::new(),
            t => format!("/{t}-threads"),
        };
        let rows: Vec<(String, Vec<Option<String>>)> = SETS
            .iter()
            .zip(counts)
            .map(|(set, n)| {
                let v: Vec<Option<f64>> = columns
                    .iter()
                    .map(|col| mrays(format!("{col}/{set}{suffix}"), n))
                    .collect();
                let col = |name: &str| v[columns.iter().position(|c| *c == name).expect("a column")];
                let obvhs = col("obvhs-cwbvh")
                    .into_iter()
                    .chain(col("obvhs-bvh2"))
                    .reduce(f64::max);
                let mut cells: Vec<Option<String>> = v.iter().map(|x| x.map(|x| format!("{x:.2}"))).collect();
                let single = col("bvh4").into_iter().chain(col("bvh8")).reduce(f64::max);
                let packets = col("bvh4-packet")
                    .into_iter()
                    .chain(col("bvh8-packet"))
                    .reduce(f64::max);
                cells.push(ratio(single, obvhs));
                cells.push(ratio(packets, obvhs));
                if cfg!(feature = "bench-embree") {
                    cells.push(ratio(single, col("embree")));
                    cells.push(ratio(packets, col("embree-8")));
                }
                #[cfg(feature = "bench-tinybvh")]
                cells.push(ratio(single, col(tinybvh::ID)));
                (set.to_string(), cells)
            })
            .collect();
        let title = format!(
            "{}: Mrays/s, {threads} thread{} (criterion medians)",
            path.display(),
            if threads == 1 { "" } else { "s" }
        );
        table::print(&title, &header, &rows);
    }
    #[cfg(feature = "bench-tinybvh")]
    println!(
        "\n{}: its shadow-any is a closest hit within the light distance (tinybvh-rs has no any hit)",
        tinybvh::ID
    );
}

criterion_group!(benches, kernels);
criterion_main!(benches);
