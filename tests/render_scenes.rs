//! Every scene renders, deterministically, and every accelerator and kernel (the kit's contestants,
//! each built once per scene) gives the same image, which is brute force's.

mod common;

use std::path::Path;
use std::time::Instant;

use whitted::accel::{Accel, AccelKind, Prims};
use whitted::kit::contestants::{self, Contestant};
use whitted::render::{Kernel, Options, Renderer};
use whitted::scene::{self, Scene};

fn render(scene: &Scene, accel: &Accel, size: u32, kernel: Kernel) -> Vec<u8> {
    let mut options = Options::new(scene);
    (options.width, options.height) = (size, size);
    options.kernel = kernel;
    Renderer::new(scene, accel, options).render().to_rgb8(false)
}

/// The side of the brute-force render a scene's image is compared with: 128, but 24 for scenes of more
/// than 10,000 primitives (brute force at 128x128 would take minutes) and 8 for more than 500,000 (the
/// full dragon, where 24x24 takes 24 s of CPU: the exhaustive tier renders that,
/// `full_dragon_matches_brute_force_at_24x24`).
fn brute_size(scene: &Scene) -> u32 {
    match scene.bounded_count() {
        0..=10_000 => 128,
        10_001..=500_000 => 24,
        _ => 8,
    }
}

fn check(path: &Path) {
    let start = Instant::now();
    let scene = scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    let prims = Prims::new(&scene);
    // Embree (with the `embree` feature) renders within a tolerance of these: tests/embree.rs.
    let list: Vec<Contestant> = contestants::all(prims)
        .into_iter()
        .filter(|c| c.same_images())
        .collect();
    let built = start.elapsed();
    // The reference: the first wide BVH's single rays (the fastest to render), itself rendered twice
    // (here and in the loop), and compared with brute force below.
    let first = list
        .iter()
        .find(|c| c.has_packet_kernel())
        .expect("a wide BVH is listed");
    let a = render(&scene, &first.accel, 128, Kernel::Single);
    // 128 is a multiple of the 4x2 packets; 125 leaves partial packets at the tiles' edges.
    let a125 = render(&scene, &first.accel, 125, Kernel::Single);
    for c in &list {
        for kernel in Kernel::ALL {
            assert!(
                render(&scene, &c.accel, 128, kernel) == a,
                "{}: {}, {kernel:?}, differs from {}'s single rays",
                path.display(),
                c.name,
                first.name
            );
        }
        if c.has_packet_kernel() {
            for kernel in [Kernel::Packet, Kernel::Stream] {
                assert!(
                    render(&scene, &c.accel, 125, kernel) == a125,
                    "{}: {}'s {kernel:?} kernel differs from {}'s single rays at 125x125",
                    path.display(),
                    c.name,
                    first.name
                );
            }
        }
    }
    let size = brute_size(&scene);
    let brute = Accel::build(prims, AccelKind::None);
    assert!(
        render(&scene, &brute, size, Kernel::Single) == render(&scene, &first.accel, size, Kernel::Single),
        "{}: {} differs from brute force at {size}x{size}",
        path.display(),
        first.name
    );
    eprintln!(
        "{}: {} contestants built in {:.2} s, checked in {:.2} s",
        path.display(),
        list.len(),
        built.as_secs_f64(),
        (start.elapsed() - built).as_secs_f64()
    );
}

#[test]
#[ignore = "exhaustive tier: brute force over 871k triangles at 24x24, 24 s of CPU"]
fn full_dragon_matches_brute_force_at_24x24() {
    let scene = scene::load(&common::root().join("scenes/dragon_full.p3f")).unwrap();
    let prims = Prims::new(&scene);
    let brute = Accel::build(prims, AccelKind::None);
    let best = Accel::build(prims, AccelKind::best());
    assert!(render(&scene, &brute, 24, Kernel::Single) == render(&scene, &best, 24, Kernel::Single));
}

#[test]
fn every_scene_in_scenes_renders_the_same_with_every_accelerator() {
    for path in common::scene_files(&common::root().join("scenes")) {
        check(&path);
    }
}

/// The same render with 1 and 2 worker threads: tiles are independent, so the bytes are identical.
#[test]
fn thread_count_does_not_change_the_image() {
    let scene = scene::load(&common::root().join("scenes/balls_medium.p3f")).unwrap();
    let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh4);
    let images: Vec<Vec<u8>> = [1, 2]
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
                .install(|| render(&scene, &accel, 96, Kernel::Single))
        })
        .collect();
    assert!(images[0] == images[1]);
}

/// `whitted render` with no scene writes the default scene's image; an output in a missing directory is
/// refused (before rendering) and leaves nothing.
#[test]
fn cli_renders_the_default_scene() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("default.png");
    let run = common::whitted(&["render", "-o", out.to_str().unwrap(), "--width", "80", "--quiet"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (80, 60));
    let bad = dir.path().join("nowhere").join("x.png");
    let run = common::whitted(&["render", "-o", bad.to_str().unwrap(), "--width", "8", "--quiet"]);
    assert_eq!(run.status.code(), Some(1));
    assert_eq!(
        String::from_utf8_lossy(&run.stderr),
        format!(
            "whitted: {}: the directory {} does not exist\n",
            bad.display(),
            dir.path().join("nowhere").display()
        )
    );
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temporary file left behind"
    );
}

/// More light samples than the packet path traces as packets (81 from a 9x9 quad light, one point
/// light), glass and mirrors several bounces deep: packets and single rays still give the same image.
#[test]
fn packets_match_single_rays_with_many_light_samples_and_deep_bounces() {
    use glam::Vec3;
    use whitted::scene::{Camera, Material, QuadLight};

    let mut s = Scene::new(Camera::new(
        Vec3::new(0.0, 2.0, 8.0),
        Vec3::ZERO,
        Vec3::Y,
        45.0,
        64,
        64,
    ));
    s.add_point_light(Vec3::new(-4.0, 6.0, 4.0), Vec3::splat(0.5));
    s.area_lights.push(QuadLight {
        corner: Vec3::new(-1.0, 5.0, -1.0),
        edge_u: Vec3::X * 2.0,
        edge_v: Vec3::Z * 2.0,
        color: Vec3::ONE,
        grid: 9,
    });
    let glass = s.add_material(Material {
        ks: 0.2,
        transmission: 0.9,
        ior: 1.5,
        ..Material::default()
    });
    let mirror = s.add_material(Material {
        ks: 0.9,
        ..Material::default()
    });
    let matte = s.add_material(Material::default());
    s.add_sphere(Vec3::new(-1.0, 1.0, 0.0), 1.0, glass);
    s.add_sphere(Vec3::new(1.5, 0.7, -0.5), 0.7, mirror);
    s.add_box(Vec3::new(-3.0, 0.0, -3.0), Vec3::new(3.0, 2.5, -2.5), mirror);
    s.add_triangle(
        Vec3::new(-5.0, 0.0, 5.0),
        Vec3::new(5.0, 0.0, 5.0),
        Vec3::new(0.0, 0.0, -5.0),
        matte,
    );
    for c in contestants::all(Prims::new(&s))
        .into_iter()
        .filter(|c| c.same_images())
    {
        for size in [64, 61] {
            let single = render(&s, &c.accel, size, Kernel::Single);
            for kernel in [Kernel::Packet, Kernel::Stream] {
                assert!(
                    render(&s, &c.accel, size, kernel) == single,
                    "{}: {kernel:?} and single-ray kernels differ at {size}x{size}",
                    c.name
                );
            }
        }
    }
}

/// `whitted bench --json` counts the same rays with either kernel (`tests/cli_report.rs` checks its keys).
#[test]
fn cli_bench_json() {
    let run = |kernel: &str| {
        let out = common::whitted(&[
            "bench",
            "scenes/balls_low.p3f",
            "--frames",
            "2",
            "--width",
            "40",
            "--kernel",
            kernel,
            "--json",
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v["rays_per_frame"].clone()
    };
    let packet = run("packet");
    assert_eq!(packet["primary"], 1600, "{packet}");
    assert_eq!(packet, run("single"));
}
