//! What once crashed the renderer: ray trees deeper than a worker's stack, and trees that double at
//! every bounce. A camera inside many nested glass spheres is the worst case for both: every hit spawns
//! a reflected and a refracted ray, and every bounce recurses.

use glam::Vec3;
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::{Kernel, Options, Renderer};
use whitted::render::{MAX_DEPTH, MAX_SPP};
use whitted::scene::{Camera, Material, Scene};

/// `n` concentric glass spheres (radii 1 to n) seen from `eye` through a field of view of `fov`
/// degrees, a light inside the innermost.
fn nested_glass(n: usize, eye: Vec3, fov: f32, width: u32, height: u32) -> Scene {
    let camera = Camera::new(eye, Vec3::ZERO, Vec3::Y, fov, width, height);
    let mut scene = Scene::new(camera);
    let glass = scene.add_material(Material {
        diffuse: Vec3::splat(0.9),
        kd: 0.1,
        ks: 0.5,
        transmission: 0.9,
        ior: 1.5,
        ..Material::default()
    });
    for i in 0..n {
        scene.add_sphere(Vec3::ZERO, 1.0 + i as f32, glass);
    }
    scene.add_point_light(Vec3::new(0.3, 0.4, 0.0), Vec3::ONE);
    scene
}

/// Renders on one worker whose stack is rayon's default, 2 MiB, as a pool the caller did not size.
fn render_on_a_2_mib_stack(scene: &Scene, options: Options) -> (Vec<u8>, whitted::render::RayCounts) {
    let accel = Accel::build(Prims::new(scene), AccelKind::Bvh4);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .stack_size(2 << 20)
        .build()
        .unwrap();
    let renderer = Renderer::new(scene, &accel, options);
    let never = std::sync::atomic::AtomicBool::new(false);
    let (film, rays) = pool.install(|| renderer.render_pass(1, &|| {}, &never)).unwrap();
    (film.to_rgb8(false), rays)
}

/// At the deepest depth allowed, among 99 nested glass spheres, every kernel finishes on a 2 MiB stack,
/// agrees on every byte, and spends no more secondary rays per pixel than the split budget allows
/// (1,024 splits, then each open branch as one chain of at most 64 bounces). Without the budget a
/// pixel's tree would hold about 2⁶⁵ rays; without the bound on the depth a stack would overflow. Two
/// views: from the centre (rays in every direction: the packets' secondary rays go ray by ray) and
/// from far away through a narrow field of view (nearly parallel rays: packets recurse as packets).
#[test]
fn deep_glass_trees_fit_the_stack_and_the_ray_budget() {
    for (eye, fov) in [
        (Vec3::new(0.0, 0.0, 0.1), 60.0),
        (Vec3::new(40.0, 30.0, 150.0), 0.05),
    ] {
        deep_glass(&nested_glass(99, eye, fov, 4, 3));
    }
}

fn deep_glass(scene: &Scene) {
    let mut options = Options::new(scene);
    options.max_depth = MAX_DEPTH;
    options.validate().unwrap();
    let mut images = Vec::new();
    for kernel in Kernel::ALL {
        options.kernel = kernel;
        let (image, rays) = render_on_a_2_mib_stack(scene, options);
        let pixels = 12;
        let secondary = rays.reflected + rays.refracted;
        assert!(
            secondary > pixels * 1024,
            "{kernel:?}: {secondary} secondary rays: the trees should reach the budget"
        );
        assert!(
            secondary <= pixels * (1024 + 1025 * u64::from(MAX_DEPTH)),
            "{kernel:?}: {secondary} secondary rays for {pixels} pixels: more than the budget allows"
        );
        images.push((image, rays));
    }
    for (kernel, other) in Kernel::ALL.iter().zip(&images).skip(1) {
        assert_eq!(
            &images[0], other,
            "{kernel:?} and single rays cut different branches"
        );
    }
}

/// Depths beyond the bound, and more samples per pixel than a pattern may hold, are refused by the
/// options with one line, before anything is allocated or traced.
#[test]
fn options_out_of_range_are_refused_before_rendering() {
    let scene = nested_glass(1, Vec3::Z, 60.0, 4, 3);
    let mut options = Options::new(&scene);
    options.max_depth = 3000;
    assert_eq!(
        options.validate().unwrap_err().to_string(),
        "a depth of 3000 bounces is more than the most, 64"
    );
    options.max_depth = 6;
    options.spp = u32::MAX;
    let message = options.validate().unwrap_err().to_string();
    assert!(
        message.contains(&format!("more than the most, {MAX_SPP}")),
        "{message}"
    );
}
