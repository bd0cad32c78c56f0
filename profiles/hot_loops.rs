//! The hot loops, one at a time, on a fixed and reduced workload, for `valgrind --tool=callgrind`
//! (the scripts beside this file). Each loop runs inside a function named `measured_*` that is never
//! inlined, so callgrind's `--toggle-collect` counts that loop's instructions and nothing of the loading,
//! building or ray generation around it.
//!
//! The workload: the 202,520-triangle dragon (`scenes/models/dragon_vrip_res2.ply.gz`) with the
//! benchmark's camera and light (`docs/dragon-workload.md`) at 320x180, traced by the BVH4 (and
//! by the BVH8 for the `-bvh8` loops, by Embree 3 for the `-embree` ones);
//! the shading loop renders the course's `scenes/dragon.p3f` at 320x180, Whitted, 1 sample per pixel, on
//! one thread.
//!
//! `HOT_LOOPS_SCENE=scenes/dragon_field.p3f` (a path from the repository's root) runs the kernel loops on
//! that scene's rays instead, at its own resolution: the field of ten dragons for a tree past the caches.
//!
//! `hot_loops LOOP` prints `rays N` (or `triangles N` for the build): the figure the scripts divide the
//! instruction count by.

use std::hint::black_box;
use std::path::Path;
use std::process::ExitCode;

use whitted::accel::policy::{AnyHit, Closest};
use whitted::accel::wide::Bvh4;
use whitted::accel::{Accel, AccelKind, Hit, Prims};
use whitted::geometry::ray::Ray;
use whitted::kit::workload::{Workload, generate, packets_of};
use whitted::render::{Options, RayCounts, Renderer};
use whitted::scene::Scene;

const LOOPS: &str = "closest-primary, closest-diffuse, any-shadow, packet-primary, packet-shadow, \
                     packet-diffuse, build-sah, shade, frame, each but the last three with the suffix -bvh8 \
                     (closest-primary-bvh8, ...), and with the `embree` feature each of those with -embree";
const WIDTH: u32 = 320;
const HEIGHT: u32 = 180;

/// Closest hits of `rays` by `trace` (a wide BVH's kernel, inlined here).
#[inline(never)]
fn measured_closest(trace: impl Fn(&Ray, &mut Hit) -> bool, rays: &[Ray]) -> usize {
    let mut hits = 0;
    for ray in rays {
        let mut hit = Hit::miss(f32::INFINITY);
        hits += trace(ray, &mut hit) as usize;
    }
    hits
}

/// Any hits of the segments `rays` by `trace`.
#[inline(never)]
fn measured_any(trace: impl Fn(&Ray, &mut Hit) -> bool, rays: &[(Ray, f32)]) -> usize {
    let mut hits = 0;
    for (ray, t_max) in rays {
        let mut hit = Hit::miss(*t_max);
        hits += trace(ray, &mut hit) as usize;
    }
    hits
}

/// Consecutive rays in packets of eight, as the renderer's tiles and the kernels bench form them
/// (`kit::workload::packets_of`), through the accelerator's packet verbs.
#[inline(never)]
fn measured_packets<const ANY: bool>(accel: &Accel, rays: &[(Ray, f32)]) -> usize {
    packets_of(rays, |r, active, t_max| match ANY {
        true => accel.occluded_packet(r, active, 0.0, t_max),
        false => {
            let mut hits = t_max.map(Hit::miss);
            accel.intersect_packet(r, active, 0.0, &mut hits)
        }
    })
}

/// Turns callgrind's instrumentation on (`CALLGRIND_START_INSTRUMENTATION` of `valgrind/callgrind.h`),
/// called once the loop's inputs are built: `callgrind.sh` starts valgrind with `--instr-atstart=no`,
/// so that loading and building a scene of millions of triangles runs uninstrumented, not under the
/// cache model. It flushes the simulated caches: the loop starts cold. Outside valgrind a no-op.
fn start_instrumentation() {
    // VG_USERREQ_TOOL_BASE('C', 'T') + 4 (callgrind.h's enum).
    const START: u64 = ((b'C' as u64) << 24 | (b'T' as u64) << 16) + 4;
    let args: [u64; 6] = [START, 0, 0, 0, 0, 0];
    #[cfg(target_arch = "x86_64")]
    // SAFETY: valgrind's client-request sequence for amd64 (valgrind.h): the four rotations of `rdi` add
    // up to 128 bits and leave it unchanged, `xchg rbx, rbx` changes nothing; under valgrind it reads
    // `args` through `rax` and writes its answer to `rdx`.
    unsafe {
        std::arch::asm!(
            "rol rdi, 3", "rol rdi, 13", "rol rdi, 61", "rol rdi, 51", "xchg rbx, rbx",
            in("rax") args.as_ptr(),
            inout("rdx") 0u64 => _,
            out("rdi") _,
        );
    }
    black_box(args);
}

#[inline(never)]
fn measured_build(prims: Prims) -> usize {
    Bvh4::new(prims, 12).map_or(0, |b| b.stats().nodes)
}

#[inline(never)]
fn measured_render(renderer: &Renderer) -> RayCounts {
    let never = std::sync::atomic::AtomicBool::new(false);
    let (_, rays) = renderer.render_pass(1, &|| {}, &never).expect("not stopped");
    rays
}

fn load(relative: &str) -> Result<Scene, String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(relative);
    whitted::scene::load(&path).map_err(|e| e.to_string())
}

fn run(name: &str) -> Result<(), String> {
    // One thread: callgrind runs threads one at a time anyway, and a single worker keeps the counts
    // independent of scheduling.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| e.to_string())?;
    if name == "shade" || name == "frame" {
        let scene = load("scenes/dragon.p3f")?;
        // `shade` keeps the BVH4 it was first recorded with; `frame` is what `whitted render` runs.
        let kind = if name == "shade" {
            AccelKind::Bvh4
        } else {
            AccelKind::best()
        };
        let accel = Accel::build(Prims::new(&scene), kind);
        let mut options = Options::new(&scene);
        (options.width, options.height) = (WIDTH, HEIGHT);
        let renderer = Renderer::new(&scene, &accel, options);
        start_instrumentation();
        let rays = pool.install(|| measured_render(&renderer));
        println!("rays {}", rays.total());
        if name == "frame" {
            // The counts by kind that profiles/frame.sh divides each phase by.
            let secondary = rays.reflected + rays.refracted;
            println!(
                "kinds primary {} shadow {} secondary {secondary}",
                rays.primary, rays.shadow
            );
        }
        return Ok(());
    }
    let file = std::env::var("HOT_LOOPS_SCENE");
    let mut scene = load(file.as_deref().unwrap_or("scenes/models/dragon_vrip_res2.ply.gz"))?;
    if file.is_err() {
        (scene.camera.width, scene.camera.height) = (WIDTH, HEIGHT);
    }
    let prims = Prims::new(&scene);
    if name == "build-sah" {
        start_instrumentation();
        let nodes = pool.install(|| measured_build(prims));
        black_box(nodes);
        println!("triangles {}", scene.triangles.len());
        return Ok(());
    }
    let accel = Accel::build(prims, AccelKind::Bvh4);
    let Accel::Bvh4(bvh) = &accel else {
        return Err("the dragon did not get a BVH4".into());
    };
    let w = generate(&scene, &accel, 1);
    #[cfg(feature = "embree")]
    if let Some(base) = name.strip_suffix("-embree") {
        // Embree 3 on the same rays, for its instruction count beside ours (valgrind's CPU model has
        // AVX2 and no AVX-512, so Embree dispatches to its AVX2 kernels, as ours do).
        let embree = Accel::build(prims, AccelKind::Embree);
        eprintln!("{}", embree.describe());
        if let Some(counts) = packets(base, &w, &embree) {
            return report(name, counts);
        }
        let closest = |r: &Ray, h: &mut Hit| embree.intersect(r, 0.0, h);
        let any = |r: &Ray, h: &mut Hit| embree.occluded(r, 0.0, h.t);
        return report(name, single_rays(name, base, &w, closest, any)?);
    }
    if let Some(base) = name.strip_suffix("-bvh8") {
        // The BVH8 on the best slab test this CPU (or valgrind's model of it) has.
        let accel8 = Accel::build(prims, AccelKind::Bvh8);
        let Accel::Bvh8(bvh8) = &accel8 else {
            return Err("the dragon did not get a BVH8".into());
        };
        eprintln!("bvh8 slab tests: {:?}", bvh8.simd());
        if let Some(counts) = packets(base, &w, &accel8) {
            return report(name, counts);
        }
        let closest = |r: &Ray, h: &mut Hit| bvh8.traverse::<Closest>(r, 0.0, h);
        let any = |r: &Ray, h: &mut Hit| bvh8.traverse::<AnyHit>(r, 0.0, h);
        return report(name, single_rays(name, base, &w, closest, any)?);
    }
    if let Some(counts) = packets(name, &w, &accel) {
        return report(name, counts);
    }
    let closest = |r: &Ray, h: &mut Hit| bvh.traverse::<Closest>(r, 0.0, h);
    let any = |r: &Ray, h: &mut Hit| bvh.traverse::<AnyHit>(r, 0.0, h);
    report(name, single_rays(name, name, &w, closest, any)?)
}

/// The packet loop `base` over the workload `w` through `accel`'s packet verbs: `(rays, hits)`, or
/// `None` for a name that is not a packet loop.
fn packets(base: &str, w: &Workload, accel: &Accel) -> Option<(usize, usize)> {
    let unbounded = |rays: &[Ray]| rays.iter().map(|r| (*r, f32::INFINITY)).collect::<Vec<_>>();
    let (rays, any) = match base {
        "packet-primary" => (unbounded(&w.primary), false),
        "packet-shadow" => (w.shadow.clone(), true),
        "packet-diffuse" => (unbounded(&w.diffuse), false),
        _ => return None,
    };
    start_instrumentation();
    let hits = match any {
        true => measured_packets::<true>(accel, &rays),
        false => measured_packets::<false>(accel, &rays),
    };
    Some((rays.len(), hits))
}

/// The single-ray loop `base` (the loop `name` less its structure's suffix) over the workload `w` with a
/// structure's closest- and any-hit kernels: `(rays, hits)`, or the error for a name that is not one.
fn single_rays(
    name: &str,
    base: &str,
    w: &Workload,
    closest: impl Fn(&Ray, &mut Hit) -> bool,
    any: impl Fn(&Ray, &mut Hit) -> bool,
) -> Result<(usize, usize), String> {
    start_instrumentation();
    Ok(match base {
        "closest-primary" => (w.primary.len(), measured_closest(closest, &w.primary)),
        "closest-diffuse" => (w.diffuse.len(), measured_closest(closest, &w.diffuse)),
        "any-shadow" => (w.shadow.len(), measured_any(any, &w.shadow)),
        _ => return Err(format!("unknown loop \"{name}\": expected one of {LOOPS}")),
    })
}

/// Prints the ray count for the script (stdout) and the hits for the reader (stderr).
fn report(name: &str, (rays, hits): (usize, usize)) -> Result<(), String> {
    println!("rays {rays}");
    eprintln!("{name}: {hits} of {rays} rays hit");
    Ok(())
}

fn main() -> ExitCode {
    let Some(name) = std::env::args().nth(1) else {
        eprintln!("usage: hot_loops LOOP (one of {LOOPS})");
        return ExitCode::FAILURE;
    };
    match run(&name) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hot_loops: {e}");
            ExitCode::FAILURE
        }
    }
}
