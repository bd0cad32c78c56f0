//! Every scene renders, deterministically, and every accelerator gives the same image.

mod common;

use std::path::Path;

use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::{Kernel, Options, Renderer};
use whitted::scene::{self, Scene};

fn render(scene: &Scene, kind: AccelKind, size: u32) -> Vec<u8> {
    render_with(scene, kind, size, Kernel::Single)
}

fn render_with(scene: &Scene, kind: AccelKind, size: u32, kernel: Kernel) -> Vec<u8> {
    let accel = Accel::build(Prims::new(scene), kind);
    let mut options = Options::new(scene);
    (options.width, options.height) = (size, size);
    options.kernel = kernel;
    Renderer::new(scene, &accel, options).render().to_rgb8(false)
}

/// Scenes whose brute-force render at 128x128 takes minutes: compared with brute force at 24x24.
fn is_big(scene: &Scene) -> bool {
    scene.bounded_count() > 10_000
}

fn check(path: &Path) {
    let scene = scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    let a = render(&scene, AccelKind::Bvh4, 128);
    let b = render(&scene, AccelKind::Bvh4, 128);
    assert!(a == b, "{}: two renders differ", path.display());
    // 128 is a multiple of the 4x2 packets; 125 leaves partial packets at the tiles' edges.
    for size in [128, 125] {
        assert!(
            render_with(&scene, AccelKind::Bvh4, size, Kernel::Packet)
                == render(&scene, AccelKind::Bvh4, size),
            "{}: packet and single-ray kernels differ at {size}x{size}",
            path.display()
        );
    }
    assert_eq!(
        render(&scene, AccelKind::Bvh2, 128),
        a,
        "{}: bvh2 differs from bvh4",
        path.display()
    );
    assert_eq!(
        render(&scene, AccelKind::Grid, 128),
        a,
        "{}: the grid differs from bvh4",
        path.display()
    );
    assert_eq!(
        render(&scene, AccelKind::Bvh8, 128),
        a,
        "{}: bvh8 differs from bvh4",
        path.display()
    );
    assert!(
        render_with(&scene, AccelKind::Bvh8, 128, Kernel::Packet) == a,
        "{}: bvh8's packets differ from bvh4",
        path.display()
    );
    let size = if is_big(&scene) { 24 } else { 128 };
    let reference = render(&scene, AccelKind::None, size);
    assert_eq!(
        render(&scene, AccelKind::Bvh4, size),
        reference,
        "{}: bvh4 differs from brute force",
        path.display()
    );
}

#[test]
fn every_scene_in_scenes_renders_the_same_with_every_accelerator() {
    for path in common::scene_files(&common::root().join("scenes")) {
        check(&path);
    }
}

#[test]
fn every_scene_in_shared_renders_the_same_with_every_accelerator() {
    if let Some(shared) = common::shared() {
        for path in common::scene_files(&shared.join("scenes")) {
            check(&path);
        }
    }
}

/// The same render with 1 and 2 worker threads: tiles are independent, so the bytes are identical.
#[test]
fn thread_count_does_not_change_the_image() {
    let scene = scene::load(&common::root().join("scenes/balls_medium.p3f")).unwrap();
    let images: Vec<Vec<u8>> = [1, 2]
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
                .install(|| render(&scene, AccelKind::Bvh4, 96))
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
    for size in [64, 61] {
        assert!(
            render_with(&s, AccelKind::Bvh4, size, Kernel::Packet)
                == render_with(&s, AccelKind::Bvh4, size, Kernel::Single),
            "packet and single-ray kernels differ at {size}x{size}"
        );
    }
}

/// `whitted bench --json` prints the keys the README names, and counts the same rays with either kernel.
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
        String::from_utf8(out.stdout).unwrap()
    };
    let packet = run("packet");
    for key in [
        "scene",
        "width",
        "height",
        "frames",
        "fps_median",
        "frame_ms_median",
        "rays_per_frame",
        "mrays_per_s",
        "threads",
        "accel",
        "kernel",
    ] {
        assert!(
            packet.contains(&format!("\"{key}\": ")),
            "{key} missing: {packet}"
        );
    }
    let rays =
        |s: &str| s[s.find("\"rays_per_frame\"").unwrap()..s.find("\"mrays_per_s\"").unwrap()].to_string();
    assert!(rays(&packet).contains("\"primary\": 1600,"), "{packet}");
    assert_eq!(rays(&packet), rays(&run("single")));
}
