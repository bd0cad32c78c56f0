//! Kernel throughput on the dragon workload (`docs/dragon-workload.md`), in Mrays/s through
//! criterion's throughput: one loop over the contestants × the ray sets × one thread and all of them.
//! The contestants: every structure of the test kit (`whitted::kit::contestants`) with its single-ray
//! kernel, the wide BVHs with their packet kernel (8 consecutive rays a packet) too, and the table's
//! with their hybrid rows (a packet whose rays point into different octants ray by ray, the renderer's
//! rule for its secondary rays), the BVH8 on every instruction set and the others on the one `auto`
//! picks (`Ours::all`); obvhs 0.4's CWBVH and BVH2
//! (`very_slow_build`, its best trees, traced with our triangle test); with `--features bench-embree`, Embree 3's single rays and
//! 8-wide packets on its high-quality (spatial split) BVH, through the library's binding
//! (`whitted::accel::embree`); with `--features bench-tinybvh`, tinybvh's BVH8_CPU (needs
//! `RUSTFLAGS="-C target-cpu=native"`, `tinybvh.rs`). The ray sets: primary rays (closest hit, our
//! single rays through `intersect_coherent`, as the renderer sends camera rays), shadow rays (any hit)
//! and diffuse bounces (closest hit, incoherent).
//!
//! The comparison table's rows are the peers' and ours that "our best" is taken over: the BVH4 and the
//! BVH8 on the instruction set `auto` picks, single rays, packets and hybrid packets
//! (`contestant::table_structures`).
//! Every contestant runs on one thread; on all threads, those rows alone. `cargo bench --bench kernels
//! -- table` runs the table's rows alone, on one thread: `table` is this bench's name for them (as
//! criterion's regex it would match no id), and of the other contestants only the grid, the reference,
//! is built, and none is checked or measured. Any other filter is criterion's regex over the ids
//! (`kernels-dragon_full/bvh8-avx512-packets/primary/2-threads`): every contestant is built and
//! checked, the rows that do not match are not measured, and the tables show them as `-`.
//!
//! Before anything is measured, the workload's primary-hit count and Σt are checked (against the
//! workload document's figures on the full dragon), the reference's hit counts against brute force on a
//! sample of each set, and every contestant's hit counts on every set against the reference's: a wrong
//! benchmark measures nothing. Brute force is timed on those samples. At the end, a table of the medians
//! side by side, per thread count, and, once the other build (portable or native) has run on this CPU,
//! native over portable per row with the rows where native is slower (`builds.rs`).
//!
//! `cargo bench --bench kernels`; `-- table` for the table's rows alone; `WHITTED_BENCH_QUICK=1` for a
//! smoke run; `WHITTED_BENCH_SCENE` for one other scene (default: the full dragon, the field of ten
//! full dragons, then res2); `WHITTED_BENCH_ISA=avx2` (or `avx512`) races the table's rows of ours and
//! Embree on that instruction set, so that an AVX-512 CPU measures the AVX2 race too.

mod builds;
#[path = "../common/mod.rs"]
mod common;
mod contestant;
#[cfg(feature = "bench-embree")]
mod embree;
mod peer;
#[cfg(feature = "bench-tinybvh")]
mod tinybvh;

use std::hint::black_box;
use std::time::{Duration, SystemTime};

use common::{obvhs as obvhs_build, table};
use contestant::{Contestant, Ours, Query, Segment, Side, TABLE, Verb};
use criterion::measurement::WallTime;
use criterion::{BenchmarkFilter, BenchmarkGroup, Criterion, SamplingMode, Throughput};
use peer::Traced;
use rayon::prelude::*;
use whitted::accel::{Accel, AccelKind, Hit, PrimKind, Prims};
use whitted::geometry::ray::Ray;
use whitted::kit::agreement::edge_margin;
use whitted::kit::contestants::{self as kit, Contestant as Built};
use whitted::kit::workload::{self, Workload};

/// Rays of each set that brute force traces (it tests all 871k triangles per ray).
const BRUTE_SAMPLE: usize = 64;

/// Seconds criterion measures each row for: long enough for 10 samples of the faster rows (a tenth to
/// a third of a second an iteration) to read within the machine's own drift.
const MEASURE: u64 = 2;

/// A [`common::group`] for many rows of a tenth of a second to a second an iteration: half a second of
/// warm-up rather than criterion's three (it doubles its iterations until past it, so it runs up to
/// twice that), and flat sampling (10 samples of as many iterations each), where criterion's linear
/// sampling (1 to 10 times a count, 55 counts in all) runs such rows for twice [`MEASURE`] or more.
fn brief<'a>(c: &'a mut Criterion, name: &str) -> BenchmarkGroup<'a, WallTime> {
    let mut g = common::group(c, name, MEASURE);
    if !common::quick() {
        g.warm_up_time(Duration::from_millis(500))
            .sampling_mode(SamplingMode::Flat);
    }
    g
}

/// Which rows a run measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Rows {
    /// Every contestant on one thread, the table's on all threads too.
    All,
    /// The table's alone, on one thread (the filter [`TABLE`]).
    Table,
}

impl Rows {
    /// [`Rows::Table`] where criterion's filter is [`TABLE`].
    fn from_args() -> Rows {
        if filter().as_deref() == Some(TABLE) {
            Rows::Table
        } else {
            Rows::All
        }
    }

    /// Whether `c` runs on `threads` threads.
    fn wants(self, c: &dyn Contestant, threads: usize) -> bool {
        match self {
            Rows::All => threads == 1 || c.in_table(),
            Rows::Table => threads == 1 && c.in_table(),
        }
    }

    /// The thread counts it runs: one, and all of the rayon pool's unless they are one too.
    fn threads(self) -> Vec<usize> {
        let all = rayon::current_num_threads();
        match self {
            Rows::All if all > 1 => vec![1, all],
            _ => vec![1],
        }
    }
}

/// Criterion's filter: the first argument that is neither an option nor an option's value
/// (`cargo bench --bench kernels -- FILTER` runs this binary as `kernels FILTER --bench`).
fn filter() -> Option<String> {
    // criterion's options that take a value (`Criterion::configure_from_args`).
    const VALUED: [&str; 20] = [
        "-c",
        "--color",
        "--colour",
        "-s",
        "--save-baseline",
        "-b",
        "--baseline",
        "--baseline-lenient",
        "--format",
        "--profile-time",
        "--load-baseline",
        "--sample-size",
        "--warm-up-time",
        "--measurement-time",
        "--nresamples",
        "--noise-threshold",
        "--confidence-level",
        "--significance-level",
        "--plotting-backend",
        "--output-format",
    ];
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if !a.starts_with('-') {
            return Some(a);
        }
        if VALUED.contains(&a.as_str()) {
            args.next();
        }
    }
    None
}

/// A ray set: its name in bench ids, its segments, which query it asks and the reference's hit count.
pub struct Set {
    pub name: &'static str,
    pub rays: Vec<Segment>,
    /// What it asks: closest hits (of coherent rays for the primary set) or any hit.
    pub query: Query,
    pub hits: usize,
}

impl Set {
    /// `c`'s answer to this set's query on `rays` (the set's rays or a part of them).
    fn trace(&self, c: &dyn Contestant, rays: &[Segment]) -> usize {
        match self.query {
            Query::Closest => c.closest(rays),
            Query::Coherent => c.coherent(rays),
            Query::Any => c.occluded(rays),
        }
    }
}

/// Counts over `items` split across the rayon pool in chunks of 256 rays (32 packets): the all-threads
/// rows.
fn par<T: Sync>(items: &[T], count: impl Fn(&[T]) -> usize + Sync + Send) -> usize {
    items.par_chunks(256).map(count).sum()
}

/// An evenly spaced sample of `v`.
fn sample<T: Copy>(v: &[T]) -> Vec<T> {
    let step = (v.len() / BRUTE_SAMPLE).max(1);
    v.iter().step_by(step).take(BRUTE_SAMPLE).copied().collect()
}

/// A peer with its own triangle test may round differently from ours on rays that cross within f32
/// precision of an edge (ours is not watertight, `geometry/triangle.rs`): where its hit count on `set`
/// differs from ours, every ray on which it (`theirs`: the triangle a segment hits first) and the
/// reference disagree must cross within 1e-5 of an edge of the triangle that the side that hit reports.
/// Anything else is a bug and fails the bench.
fn reconcile(
    peer: &str,
    set: &Set,
    theirs: &dyn contestant::FirstHit,
    ours: &Accel,
    scene: &whitted::scene::Scene,
) {
    const EDGE: f64 = 1e-5;
    let prims = Prims::new(scene);
    let (mut differ, mut worst) = (0, 0.0f64);
    for (i, r) in set.rays.iter().enumerate() {
        let mut hit = Hit::miss(r.1);
        let ours = ours
            .intersect(&r.0, 0.0, &mut hit)
            .then(|| match prims.kind(hit.prim) {
                PrimKind::Triangle(t) => t as u32,
                _ => panic!("the bench scene holds triangles only"),
            });
        let theirs = theirs.triangle(r);
        let Some(tri) = (match (ours, theirs) {
            (Some(_), Some(_)) | (None, None) => None,
            (hit, None) | (None, hit) => hit,
        }) else {
            continue;
        };
        let margin = edge_margin(&r.0, scene.triangles.vertices(tri as usize));
        assert!(
            margin.abs() < EDGE,
            "{peer} {}: ray {i} {:?} (t_max {}): ours {ours:?}, theirs {theirs:?}, {margin} from an edge",
            set.name,
            r.0,
            r.1
        );
        differ += 1;
        worst = worst.max(margin.abs());
    }
    eprintln!(
        "{peer} {}: {differ} of {} rays differ from ours, all within {worst:.1e} of a triangle edge",
        set.name,
        set.rays.len()
    );
}

/// Checks `c`'s hit count on every set against the reference's; a peer with its own triangle test is
/// reconciled ray by ray where they differ ([`reconcile`]), anything else must match exactly.
fn check(c: &dyn Contestant, sets: &[Set], reference: &Accel, scene: &whitted::scene::Scene) {
    for set in sets {
        let got = set.trace(c, &set.rays);
        if got == set.hits {
            continue;
        }
        match c.first_hit() {
            Some(theirs) => reconcile(c.id(), set, theirs, reference, scene),
            None => panic!("{} {}: {got} hits, the reference {}", c.id(), set.name, set.hits),
        }
    }
}

fn main() {
    let rows = Rows::from_args();
    let mut c = Criterion::default().configure_from_args();
    if rows == Rows::Table {
        // The loop registers the table's rows alone; as a regex, `table` would match none of them.
        c = c.with_benchmark_filter(BenchmarkFilter::AcceptAll);
    }
    let since = SystemTime::now();
    let mut scenes = common::scenes();
    if std::env::var_os("WHITTED_BENCH_SCENE").is_none() && !common::quick() {
        // Ten full dragons side by side, 8.7 M triangles: a tree that does not fit the caches.
        let field = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon_field.p3f");
        scenes.insert(1, field);
    }
    for path in scenes {
        scene(&mut c, &path, since, rows);
    }
    c.final_summary();
}

/// Our structures that `rows` needs, built once each: every build of the kit, or the grid (the
/// reference) and the table's structures.
fn structures(prims: Prims<'_>, rows: Rows) -> Vec<Built<'_>> {
    if rows == Rows::All {
        return kit::all(prims);
    }
    kit::BUILDS
        .iter()
        .filter(|b| b.kind == AccelKind::Grid || b.each_simd)
        .map(|b| {
            let mut accel = b.build(prims);
            // As the kit names them, where a scene past the wide BVHs' limit gets a BVH2 without a set.
            let name = match accel.simd() {
                Some(_) => {
                    assert!(
                        accel.set_simd(contestant::race_isa()),
                        "{}: the race's set refused",
                        b.name
                    );
                    format!("{} {}", b.name, contestant::auto_set())
                }
                None => b.name.to_string(),
            };
            Built { name, accel }
        })
        .collect()
}

fn scene(c: &mut Criterion, path: &std::path::Path, since: SystemTime, rows: Rows) {
    let scene = whitted::scene::load(path).expect("the bench scene loads");
    let prims = Prims::new(&scene);
    let built = structures(prims, rows);
    // The reference: the grid, brute force's answer bit for bit (`tests/accel/accel_vs_brute.rs`).
    let reference = &built
        .iter()
        .find(|b| b.is_grid())
        .expect("the kit lists the grid")
        .accel;
    let w: Workload = workload::generate(&scene, reference, 1);
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
    let whole = |rays: &[Ray]| rays.iter().map(|r| (*r, f32::INFINITY)).collect();
    let mut sets = [
        Set {
            name: "primary",
            rays: whole(&w.primary),
            query: Query::Coherent,
            hits: w.primary_hits,
        },
        Set {
            name: "shadow-any",
            rays: w.shadow.clone(),
            query: Query::Any,
            hits: 0,
        },
        Set {
            name: "diffuse",
            rays: whole(&w.diffuse),
            query: Query::Closest,
            hits: 0,
        },
    ];
    let ours = Ours::all(&built);
    let brute = Accel::build(prims, AccelKind::None);
    let brute = Ours::new("brute", &brute, Verb::Single);
    let reference_row = Ours::new("grid", reference, Verb::Single);
    for set in &mut sets {
        set.hits = set.trace(&reference_row, &set.rays);
        // The reference against brute force on a sample.
        let s = sample(&set.rays);
        assert_eq!(
            set.trace(&brute, &s),
            set.trace(&reference_row, &s),
            "the grid against brute force, {} sample",
            set.name
        );
    }

    // The peers, on their best trees.
    let tris = obvhs_build::triangles(&scene);
    let params = obvhs::BvhBuildParams::very_slow_build();
    let cwbvh = Traced::new("obvhs-cwbvh", obvhs_build::cwbvh(&tris, params), &tris);
    let obvh2 = Traced::new("obvhs-bvh2", obvhs_build::bvh2(&tris, params), &tris);
    #[cfg(feature = "bench-embree")]
    let embree_scene = {
        let all = std::thread::available_parallelism().map_or(1, |n| n.get());
        use whitted::accel::embree::{Embree, Quality};
        Embree::new(prims, Quality::High, all, Some(contestant::race_isa())).expect("Embree builds")
    };
    #[cfg(feature = "bench-embree")]
    let embree = embree::Embree::both(&embree_scene, contestant::auto_set());
    #[cfg(feature = "bench-tinybvh")]
    let tiny = tinybvh::Tiny::new(&scene).usable(&sets);

    let mut contestants: Vec<&dyn Contestant> = ours.iter().map(|o| o as &dyn Contestant).collect();
    contestants.extend([&cwbvh as &dyn Contestant, &obvh2]);
    #[cfg(feature = "bench-embree")]
    contestants.extend(embree.iter().map(|e| e as &dyn Contestant));
    #[cfg(feature = "bench-tinybvh")]
    contestants.extend(tiny.as_ref().map(|t| t as &dyn Contestant));
    contestants.retain(|c| rows.wants(*c, 1));
    // Every contestant finds the reference's hits on every set: a mismatch is a bug on one side.
    for c in &contestants {
        check(*c, &sets, reference, &scene);
    }

    let name = common::scene_name(path);
    let group = format!("kernels-{name}");
    let mut g = brief(c, &group);
    let suffix = |threads: usize| match threads {
        1 => String::new(),
        t => format!("/{t}-threads"),
    };
    let on = |threads: usize| -> Vec<&dyn Contestant> {
        let mut run = contestants.clone();
        run.retain(|c| rows.wants(*c, threads));
        run
    };
    for threads in rows.threads() {
        for c in &on(threads) {
            for set in &sets {
                g.throughput(Throughput::Elements(set.rays.len() as u64));
                g.bench_function(format!("{}/{}{}", c.id(), set.name, suffix(threads)), |b| {
                    b.iter(|| match threads {
                        1 => set.trace(*c, black_box(&set.rays)),
                        _ => par(black_box(&set.rays), |r| set.trace(*c, r)),
                    })
                });
            }
        }
    }
    g.finish();

    if rows == Rows::All {
        let sample_group = format!("{group}-sample");
        let mut g = brief(c, &sample_group);
        for set in &sets {
            let s = sample(&set.rays);
            g.throughput(Throughput::Elements(s.len() as u64));
            g.bench_function(format!("brute/{}", set.name), |b| {
                b.iter(|| set.trace(&brute, black_box(&s)))
            });
        }
        g.finish();
    }

    // The side-by-side table in Mrays/s, one row per contestant run, then our best of each kind (single
    // rays, packets; over the table's rows) over each peer of that kind where both ran.
    let mrays = |id: &str, set: &Set, threads: usize| {
        table::median(&group, &format!("{id}/{}{}", set.name, suffix(threads)), since)
            .map(|s| set.rays.len() as f64 / s * 1e-6)
    };
    let mut header = vec!["contestant"];
    header.extend(sets.iter().map(|s| s.name));
    for threads in rows.threads() {
        let run = on(threads);
        let speed = |c: &dyn Contestant| sets.iter().map(|s| mrays(c.id(), s, threads)).collect::<Vec<_>>();
        let mut lines: Vec<(String, Vec<Option<String>>)> = run
            .iter()
            .map(|c| {
                let cells = speed(*c).iter().map(|v| v.map(|v| format!("{v:.2}"))).collect();
                (c.id().to_string(), cells)
            })
            .collect();
        let best = |packets: bool| {
            let mine: Vec<Vec<Option<f64>>> = run
                .iter()
                .filter(|c| c.side() == Side::Ours && c.in_table() && c.packets() == packets)
                .map(|c| speed(*c))
                .collect();
            (0..sets.len())
                .map(|i| mine.iter().filter_map(|v| v[i]).reduce(f64::max))
                .collect::<Vec<_>>()
        };
        for peer in run.iter().filter(|c| c.side() == Side::Peer) {
            let kind = if peer.packets() { "packets" } else { "single rays" };
            let cells = best(peer.packets())
                .into_iter()
                .zip(speed(*peer))
                .map(|(a, b)| a.zip(b).map(|(a, b)| format!("{:.2}x", a / b)))
                .collect();
            lines.push((format!("our best {kind} / {}", peer.id()), cells));
        }
        let title = format!(
            "{}: Mrays/s, {threads} thread{} (criterion medians, {} build)",
            path.display(),
            if threads == 1 { "" } else { "s" },
            builds::this_build()
        );
        table::print(&title, &header, &lines);
        let figures: Vec<(String, Vec<Option<f64>>)> =
            run.iter().map(|c| (c.id().to_string(), speed(*c))).collect();
        builds::record_and_compare(&format!("{group}-{threads}t"), &header[1..], &figures);
    }
    // A peer whose feature is off has no row: said, so that the table is not read as complete.
    if !cfg!(feature = "bench-embree") {
        println!("\n(no Embree rows: built without `--features bench-embree`)");
    }
    if !cfg!(feature = "bench-tinybvh") {
        println!(
            "\n(no tinybvh row: built without `--features bench-tinybvh`, which needs \
             RUSTFLAGS=\"-C target-cpu=native\")"
        );
    }
    // What each of our rows spends a ray on, counted apart from the timing (the counting verbs).
    let steps: Vec<(String, Vec<Option<String>>)> = ours
        .iter()
        .filter(|o| rows.wants(*o, 1))
        .map(|o| {
            let cells = sets
                .iter()
                .map(|set| {
                    let (nodes, prims) = o.steps_per_ray(&set.rays, set.query);
                    Some(format!("{nodes:.1} / {prims:.1}"))
                })
                .collect();
            (o.id().to_string(), cells)
        })
        .collect();
    table::print(
        &format!("{}: nodes visited / primitives tested per ray", path.display()),
        &header,
        &steps,
    );
    #[cfg(feature = "bench-tinybvh")]
    println!(
        "\n{}: its shadow-any is a closest hit within the light distance (tinybvh-rs has no any hit)",
        tinybvh::ID
    );
}
