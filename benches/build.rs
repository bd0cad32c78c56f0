//! Build times over the Stanford dragon (871,414 and 202,520 triangles): ours (every build of the test
//! kit, `whitted::kit::contestants::BUILDS`: the uniform grid, the BVH2 by midpoint and by binned SAH,
//! the BVH4 and BVH8 collapsed from an SAH BVH2) on one thread and on all of them,
//! and obvhs 0.4's CWBVH and BVH2 with its `fast`, `medium` and `very_slow` presets on all threads; then
//! a table of the median times beside each tree's SAH cost (traversal and intersection cost 1, areas
//! relative to the root: binary trees compare with binary trees, wide with wide). With
//! `--features bench-embree`, Embree 3's builds (medium and high quality, the library's binding:
//! `whitted::accel::embree`) join them.
//!
//! `cargo bench --bench build`; `WHITTED_BENCH_QUICK=1` for a smoke run; `WHITTED_BENCH_SCENE` for one
//! other scene.

mod common;

use std::time::SystemTime;

use common::{obvhs as peer, table};
use criterion::{Criterion, criterion_group, criterion_main};
use obvhs::bvh2::Bvh2 as OBvh2;
use obvhs::cwbvh::CwBvh;
use whitted::accel::{Accel, Prims};
use whitted::kit::contestants::BUILDS;

type Preset = (&'static str, fn() -> obvhs::BvhBuildParams);

/// obvhs' build presets, from the fastest to the best trees.
const PRESETS: [Preset; 3] = [
    ("fast", obvhs::BvhBuildParams::fast_build),
    ("medium", obvhs::BvhBuildParams::medium_build),
    ("very-slow", obvhs::BvhBuildParams::very_slow_build),
];

/// SAH cost of obvhs' BVH2, by the same rule as our `Stats::sah`.
fn sah_obvhs_bvh2(bvh: &OBvh2) -> f64 {
    let Some(root) = bvh.nodes.first() else {
        return 0.0;
    };
    let root_area = f64::from(root.aabb.half_area());
    let mut cost = 0.0;
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        let n = &bvh.nodes[i];
        let rel = f64::from(n.aabb.half_area()) / root_area;
        if n.prim_count > 0 {
            cost += rel * f64::from(n.prim_count);
        } else {
            cost += rel;
            stack.extend([n.first_index as usize, n.first_index as usize + 1]);
        }
    }
    cost
}

/// SAH cost of obvhs' CWBVH over its (quantised, as traversed) child boxes.
fn sah_cwbvh(bvh: &CwBvh) -> f64 {
    let Some(root) = bvh.nodes.first() else {
        return 0.0;
    };
    let root_area = f64::from(root.aabb().half_area());
    let mut cost = 0.0;
    let mut stack = vec![(0usize, 1.0f64)];
    while let Some((i, rel)) = stack.pop() {
        cost += rel;
        let n = &bvh.nodes[i];
        for k in (0..8).filter(|&k| !n.is_child_empty(k)) {
            let rel = f64::from(n.child_aabb(k).half_area()) / root_area;
            if n.is_leaf(k) {
                cost += rel * f64::from(n.child_primitives(k).1);
            } else {
                stack.push((n.child_node_index(k) as usize, rel));
            }
        }
    }
    cost
}

fn build(c: &mut Criterion) {
    let since = SystemTime::now();
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    let pools: Vec<(usize, rayon::ThreadPool)> = [1, all]
        .into_iter()
        .map(|n| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build();
            (n, pool.expect("a thread pool"))
        })
        .collect();
    let id = |name: &str| name.replace(' ', "-");
    for path in common::scenes() {
        let scene = whitted::scene::load(&path).expect("the bench scene loads");
        let name = common::scene_name(&path);
        let group = format!("build-{name}");
        let prims = Prims::new(&scene);
        let tris = peer::triangles(&scene);
        let mut g = common::group(c, &group, 8);
        for (threads, pool) in &pools {
            for build in &BUILDS {
                g.bench_function(format!("{}/{threads}-threads", id(build.name)), |b| {
                    b.iter(|| pool.install(|| build.build(prims)))
                });
            }
        }
        // obvhs on all threads only: its very_slow preset takes seconds a build even there.
        let (threads, pool) = pools.last().expect("two pools");
        for (preset, params) in PRESETS {
            g.bench_function(format!("obvhs-cwbvh-{preset}/{threads}-threads"), |b| {
                b.iter(|| pool.install(|| peer::cwbvh(&tris, params())))
            });
            g.bench_function(format!("obvhs-bvh2-{preset}/{threads}-threads"), |b| {
                b.iter(|| pool.install(|| peer::bvh2(&tris, params())))
            });
        }
        #[cfg(feature = "bench-embree")]
        for (threads, _) in &pools {
            use whitted::accel::embree::{Embree, Quality};
            for quality in [Quality::Medium, Quality::High] {
                g.bench_function(format!("embree-{}/{threads}-threads", quality.name()), |b| {
                    b.iter(|| Embree::new(prims, quality, *threads, None).expect("Embree builds"))
                });
            }
        }
        g.finish();

        // The table: one row per structure, its SAH cost from one more build.
        let time = |id: &str, threads: usize| {
            table::median(&group, &format!("{id}/{threads}-threads"), since).map(|s| format!("{s:.3}"))
        };
        let mut rows = Vec::new();
        for build in &BUILDS {
            let id = id(build.name);
            let sah = match &build.build(prims) {
                Accel::Bvh2(b) => Some(format!("{:.1}", b.stats().sah)),
                Accel::Bvh4(b) => Some(format!("{:.1}", b.stats().sah)),
                Accel::Bvh8(b) => Some(format!("{:.1}", b.stats().sah)),
                _ => None,
            };
            rows.push((id.clone(), vec![time(&id, 1), time(&id, all), sah]));
        }
        for (preset, params) in PRESETS {
            let id = format!("obvhs-cwbvh-{preset}");
            let sah = sah_cwbvh(&peer::cwbvh(&tris, params()));
            rows.push((id.clone(), vec![None, time(&id, all), Some(format!("{sah:.1}"))]));
            let id = format!("obvhs-bvh2-{preset}");
            let sah = sah_obvhs_bvh2(&peer::bvh2(&tris, params()));
            rows.push((id.clone(), vec![None, time(&id, all), Some(format!("{sah:.1}"))]));
        }
        if cfg!(feature = "bench-embree") {
            for q in ["medium", "high"] {
                let id = format!("embree-{q}");
                rows.push((id.clone(), vec![time(&id, 1), time(&id, all), None]));
            }
        }
        let all_threads = format!("s, {all} threads");
        table::print(
            &format!("Build of {} ({} triangles), medians", path.display(), tris.len()),
            &["structure", "s, 1 thread", &all_threads, "SAH cost"],
            &rows,
        );
    }
}

criterion_group!(benches, build);
criterion_main!(benches);
