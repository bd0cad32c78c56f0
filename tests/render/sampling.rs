//! Distribution ray tracing (`src/render/sampler.rs`, `camera.rs`, `whitted.rs`, `progressive.rs`):
//! soft shadows against their closed-form visible fraction, depth of field against the pinhole image on
//! the focal plane and against the circle of confusion off it, reproducibility across threads and
//! kernels, progressive passes and what a stopped pass keeps (Ctrl-C from the command line is in
//! tests/cli/interrupt.rs).

use glam::Vec3;
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::{Kernel, Options, Renderer};
use whitted::scene::{Camera, Material, QuadLight, Scene};

use crate::common;

/// Height of the quad light above the floor, its half size, and the blocker's height.
const H: f32 = 4.0;
const A: f32 = 1.0;
const BLOCKER: f32 = 2.0;

/// A white diffuse floor (y = 0, Kd = 1) under a 2 × 2 quad light of colour 1 at height 4, and a thin
/// box at height 2 over x < 0 that hides exactly the half x < 0 of the light from the origin. The camera
/// looks at the origin from the side through a one-pixel image a hundredth of a degree wide, so every
/// sample of the pixel lands within a hair of the origin.
fn penumbra_scene(grid: u32) -> Scene {
    let mut s = Scene::new(Camera::new(
        Vec3::new(5.0, 0.5, 0.0),
        Vec3::ZERO,
        Vec3::Y,
        0.01,
        1,
        1,
    ));
    s.area_lights.push(QuadLight {
        corner: Vec3::new(-A, H, -A),
        edge_u: Vec3::X * 2.0 * A,
        edge_v: Vec3::Z * 2.0 * A,
        color: Vec3::ONE,
        grid,
    });
    let white = s.add_material(Material {
        diffuse: Vec3::ONE,
        ..Material::default()
    });
    s.add_triangle(
        Vec3::new(-50.0, 0.0, -50.0),
        Vec3::new(50.0, 0.0, -50.0),
        Vec3::new(0.0, 0.0, 80.0),
        white,
    );
    s.add_box(
        Vec3::new(-20.0, BLOCKER - 0.01, -20.0),
        Vec3::new(0.0, BLOCKER + 0.01, 20.0),
        white,
    );
    s
}

/// cos θ between the floor's normal (+y) and the direction from the origin to a light point.
fn cos_to(p: Vec3) -> f64 {
    (p.y / p.length()) as f64
}

fn render_pixel(scene: &Scene, spp: u32, seed: u64) -> Vec3 {
    let accel = Accel::build(Prims::new(scene), AccelKind::Bvh4);
    let options = Options {
        spp,
        seed,
        ..Options::new(scene)
    };
    Renderer::new(scene, &accel, options).pixel(0, 0)
}

/// spp 0: the quad is N × N point lights at its cells' centres, each of colour 1/N²; the blocker hides
/// exactly the columns with x < 0, so the pixel is Σ over the other half of cos θ / N², exactly.
#[test]
fn regular_soft_shadow_is_the_visible_half_of_the_grid() {
    for n in [2u32, 4, 6] {
        let mut want = 0.0;
        for j in 0..n {
            for i in n / 2..n {
                let x = -A + 2.0 * A * (i as f32 + 0.5) / n as f32;
                let z = -A + 2.0 * A * (j as f32 + 0.5) / n as f32;
                want += cos_to(Vec3::new(x, H, z)) / (n * n) as f64;
            }
        }
        let got = render_pixel(&penumbra_scene(n), 0, 0);
        for c in 0..3 {
            assert!(
                (got[c] as f64 - want).abs() < 1e-5,
                "grid {n}: got {got}, want {want}"
            );
        }
    }
}

/// spp 64: 8 × 8 jittered light samples, one per cell, so exactly 32 fall on the hidden half whatever the
/// jitter; the pixel is the mean of the visible ones' cos θ, close to the analytic mean over the lit half
/// of the light, and it changes with the seed (it is sampled, not regular) while staying that close.
#[test]
fn jittered_soft_shadow_converges_on_the_visible_half() {
    // ∫ over the lit half (x in [0, A], z in [−A, A]) of cos θ, by the midpoint rule on a fine grid, as a
    // mean over the whole light (the hidden half contributes 0).
    let m = 400;
    let mut want = 0.0;
    for j in 0..m {
        for i in 0..m {
            let x = A * (i as f32 + 0.5) / m as f32;
            let z = -A + 2.0 * A * (j as f32 + 0.5) / m as f32;
            want += cos_to(Vec3::new(x, H, z));
        }
    }
    want /= (2 * m * m) as f64;
    let scene = penumbra_scene(1);
    let a = render_pixel(&scene, 64, 1);
    let b = render_pixel(&scene, 64, 2);
    assert_ne!(a, b, "two seeds, one image: not sampled");
    for got in [a, b] {
        // cos θ varies by ~3% over the light; 32 jittered samples average it to well within 1%.
        assert!(
            (got.x as f64 - want).abs() < 0.005 * want,
            "got {got}, want {want}"
        );
    }
    assert_eq!(render_pixel(&scene, 64, 1), a, "the same seed, the same pixel");
}

/// A grey quad filling the left half of the view, on the focal plane or in front of it, over a black
/// background; 64 × 64 pixels, spp 16.
fn edge_scene(quad_distance: f32, aperture: f32) -> Scene {
    let mut cam = Camera::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -10.0), Vec3::Y, 40.0, 64, 64);
    (cam.aperture, cam.focal) = (aperture, 1.0);
    let mut s = Scene::new(cam);
    s.add_point_light(Vec3::new(0.0, 0.0, 1.0), Vec3::splat(0.5));
    let m = s.add_material(Material::default());
    let z = -quad_distance;
    s.add_triangle(
        Vec3::new(-100.0, -100.0, z),
        Vec3::new(0.0, -100.0, z),
        Vec3::new(0.0, 100.0, z),
        m,
    );
    s.add_triangle(
        Vec3::new(-100.0, -100.0, z),
        Vec3::new(0.0, 100.0, z),
        Vec3::new(-100.0, 100.0, z),
        m,
    );
    s
}

fn render(scene: &Scene, spp: u32, kernel: Kernel) -> Vec<Vec3> {
    let accel = Accel::build(Prims::new(scene), AccelKind::Bvh4);
    let options = Options {
        spp,
        kernel,
        ..Options::new(scene)
    };
    Renderer::new(scene, &accel, options).render().pixels
}

/// Pixels of row 32 that are neither background nor fully covered.
fn blurred_columns(pixels: &[Vec3], full: f32) -> usize {
    pixels[32 * 64..33 * 64]
        .iter()
        .filter(|p| p.x > 1e-4 && p.x < full - 1e-4)
        .count()
}

/// On the focal plane the lens changes nothing: every lens ray of a pixel sample meets the pinhole ray
/// there, so the edge is exactly as sharp as without a lens. Off it, a point spreads over the circle of
/// confusion, and so does the edge.
#[test]
fn depth_of_field_is_sharp_on_the_focal_plane_only() {
    let sharp = render(&edge_scene(10.0, 0.0), 16, Kernel::Single);
    let lens = render(&edge_scene(10.0, 8.0), 16, Kernel::Single);
    let full = sharp[32 * 64].x;
    assert!(full > 0.1);
    for (a, b) in sharp.iter().zip(&lens) {
        assert!((*a - *b).abs().max_element() < 1e-4, "{a} vs {b}");
    }
    assert!(blurred_columns(&sharp, full) <= 1);
    // The quad at 5 (focal plane at 10): circle of confusion diameter = aperture · (10 − 5) / 5 = 8
    // view-plane pixels at distance 10, which is 8 image pixels there; the edge blurs over ~8 columns.
    let near = render(&edge_scene(5.0, 8.0), 16, Kernel::Single);
    let blurred = blurred_columns(&near, full);
    assert!((6..=10).contains(&blurred), "{blurred} blurred columns");
}

/// A scene with everything stochastic at once: a quad light (soft shadows), a lens, a rough mirror, glass.
fn everything_scene() -> Scene {
    let mut cam = Camera::new(Vec3::new(0.0, 2.0, 8.0), Vec3::ZERO, Vec3::Y, 45.0, 48, 40);
    (cam.aperture, cam.focal) = (3.0, 1.0);
    let mut s = Scene::new(cam);
    s.add_point_light(Vec3::new(-4.0, 6.0, 4.0), Vec3::splat(0.4));
    s.area_lights.push(QuadLight {
        corner: Vec3::new(-1.0, 5.0, -1.0),
        edge_u: Vec3::X * 2.0,
        edge_v: Vec3::Z * 2.0,
        color: Vec3::splat(0.8),
        grid: 3,
    });
    let rough = s.add_material(Material {
        ks: 0.8,
        roughness: Some(0.3),
        ..Material::default()
    });
    let glass = s.add_material(Material {
        ks: 0.1,
        transmission: 0.9,
        ior: 1.5,
        ..Material::default()
    });
    let floor = s.add_material(Material::default());
    s.add_sphere(Vec3::new(-1.0, 1.0, 0.0), 1.0, rough);
    s.add_sphere(Vec3::new(1.5, 0.7, 1.0), 0.7, glass);
    s.add_triangle(
        Vec3::new(-9.0, 0.0, 9.0),
        Vec3::new(9.0, 0.0, 9.0),
        Vec3::new(0.0, 0.0, -9.0),
        floor,
    );
    s
}

/// The same bytes on 1 and 2 threads and with every kernel: every random number comes from
/// (seed, pass, pixel, sample), never from a thread or from the order tiles are taken in.
#[test]
fn sampled_renders_are_reproducible_across_threads_and_kernels() {
    let scene = everything_scene();
    let bytes = |threads: usize, kernel: Kernel| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let pixels = pool.install(|| render(&scene, 9, kernel));
        pixels
            .iter()
            .flat_map(|p| p.to_array())
            .map(f32::to_bits)
            .collect::<Vec<_>>()
    };
    let reference = bytes(1, Kernel::Single);
    assert!(bytes(2, Kernel::Single) == reference, "1 vs 2 threads");
    assert!(bytes(1, Kernel::Packet) == reference, "packet vs single");
    assert!(bytes(2, Kernel::Packet) == reference, "packet on 2 threads");
}

/// Progressive passes average to what many samples converge to: the regular soft shadow's value within
/// sampling noise after 256 passes of one sample.
#[test]
fn progressive_passes_converge() {
    use std::sync::atomic::AtomicBool;
    use whitted::render::progressive::Progressive;

    let scene = penumbra_scene(8);
    let exact = render_pixel(&scene, 0, 0).x;
    let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh4);
    let options = Options {
        spp: 1,
        ..Options::new(&scene)
    };
    let r = Renderer::new(&scene, &accel, options);
    let mut mean = Progressive::new(1, 1);
    let never = AtomicBool::new(false);
    // The documented mean, computed here from each pass's own film: the f64 sum of the passes' f32
    // colours over their count.
    let mut sum = 0.0f64;
    for pass in 1..=256 {
        mean.render_pass(&r, pass, &|| {}, &never).unwrap();
        sum += f64::from(r.render_pass(pass, &|| {}, &never).unwrap().0.pixels[0].x);
        assert_eq!(
            mean.film().pixels[0].x,
            (sum / f64::from(pass)) as f32,
            "the mean of {pass} passes"
        );
    }
    assert_eq!(mean.passes(), 256);
    let got = mean.film().pixels[0].x;
    // Each pass is 0 or cos θ (about 0.95): σ of the mean ≈ 0.5 / 16 ≈ 0.03.
    assert!((got - exact).abs() < 0.1, "{got} vs {exact}");
    let stopped = AtomicBool::new(true);
    assert!(r.render_pass(257, &|| {}, &stopped).is_none());
    assert!(mean.render_pass(&r, 257, &|| {}, &stopped).is_err());
    assert_eq!(mean.passes(), 256, "a stopped pass is not counted");
}

/// A first pass stopped after some tiles keeps exactly those tiles, over that pass; the other tiles
/// rendered apart and joined to them make the whole pass, bit for bit. A later pass stopped keeps
/// nothing, so that the mean stays one of whole passes.
#[test]
fn a_stopped_first_pass_keeps_its_tiles_and_joins_into_the_whole_pass() {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use whitted::render::progressive::Progressive;

    let scene = everything_scene();
    let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh4);
    let options = Options {
        spp: 4,
        ..Options::new(&scene)
    };
    let r = Renderer::new(&scene, &accel, options);
    // One worker: the tile that raises the stop is the last one finished.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let never = AtomicBool::new(false);
    let mut whole = Progressive::new(48, 40);
    pool.install(|| whole.render_pass(&r, 1, &|| {}, &never)).unwrap();

    // 48 x 40 is 3 x 3 tiles: stop after the fourth.
    let (stop, finished) = (AtomicBool::new(false), AtomicUsize::new(0));
    let on_tile = || {
        if finished.fetch_add(1, Ordering::Relaxed) + 1 == 4 {
            stop.store(true, Ordering::Relaxed);
        }
    };
    let mut first = Progressive::new(48, 40);
    let stopped = pool
        .install(|| first.render_pass(&r, 1, &on_tile, &stop))
        .unwrap_err();
    assert!(!stopped.is_complete());
    assert_eq!(first.passes(), 0, "a stopped pass is not folded in");
    let kept = first.keep_finished(&stopped);
    assert_eq!((kept.tile_indices().len(), kept.passes()), (4, 1));

    let rest: Vec<u32> = (0..9).filter(|i| !kept.tile_indices().contains(i)).collect();
    let mut others = Progressive::for_tiles(48, 40, rest);
    pool.install(|| others.render_pass(&r, 1, &|| {}, &never))
        .unwrap();
    let joined = kept.join(others);
    let bits = |p: &Progressive| -> Vec<u64> { p.sums().iter().flatten().map(|v| v.to_bits()).collect() };
    assert_eq!(joined.tile_indices(), whole.tile_indices());
    assert_eq!(joined.passes(), 1);
    assert!(
        bits(&joined) == bits(&whole),
        "the joined pass differs from the whole one"
    );
    assert_eq!(joined.film(), whole.film());

    // Nothing finished: nothing kept, and joining it adds nothing.
    let stopped =
        pool.install(|| Progressive::new(48, 40).render_pass(&r, 1, &|| {}, &AtomicBool::new(true)));
    let none = Progressive::new(48, 40).keep_finished(&stopped.unwrap_err());
    assert_eq!((none.tile_indices().len(), none.passes()), (0, 0));
    assert!(bits(&whole.clone().join(none)) == bits(&whole));
    // A second pass stopped keeps nothing of itself.
    let before = bits(&whole);
    assert!(
        pool.install(|| whole.render_pass(&r, 2, &on_tile, &stop))
            .is_err()
    );
    assert_eq!(whole.passes(), 1);
    assert!(bits(&whole) == before);
}

/// `--passes` with `--every` and `--progressive-out` writes numbered snapshots; a count that is not a
/// square is rounded up, and says so.
#[test]
fn cli_progressive_snapshots_and_spp_rounding() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.png");
    let snaps = dir.path().join("snaps");
    let run = common::whitted(&[
        "render",
        "--width",
        "24",
        "--passes",
        "4",
        "--every",
        "2",
        "--progressive-out",
        snaps.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    common::images::rgb(&out);
    let mut names: Vec<String> = std::fs::read_dir(&snaps)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["p-0002.png", "p-0004.png"]);
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(snaps.join("p-0004.png")).unwrap()
    );

    let run = common::whitted(&[
        "render",
        "--width",
        "8",
        "--spp",
        "5",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success());
    assert!(
        String::from_utf8_lossy(&run.stderr)
            .contains("5 samples per pixel is not a square: taking 3 x 3 = 9"),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let run = common::whitted(&["render", "--aperture", "-1", "-o", out.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(2));
}
