//! The SPD test procedure (`render::spd`) against the ray counts of the SPD Readme, an independent
//! reference, on the seven databases at their default sizes in `scenes/spd/`: every count within the
//! Readme's 10%, with both kernels counting (and drawing) the same; and the Readme's rules 8 and 9 on a
//! transmitter without a specular coefficient.

use glam::Vec3;
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::geometry::ray::Ray;
use whitted::render::spd::{self, Counts};
use whitted::render::{Kernel, Options, Renderer};
use whitted::scene::{Camera, Material, Scene};

use crate::common;

fn counts(file: &str, kernel: Kernel) -> (Counts, Vec<u8>) {
    let scene = whitted::scene::load(&common::root().join("scenes/spd").join(file)).unwrap();
    let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh4);
    let options = whitted::render::Options {
        kernel,
        ..spd::options(&scene)
    };
    options.validate().unwrap();
    let renderer = Renderer::new(&scene, &accel, options);
    let never = std::sync::atomic::AtomicBool::new(false);
    let (film, rays) = renderer.render_pass(1, &|| {}, &never).unwrap();
    assert_eq!(rays.primary, 513 * 513, "{file}: one eye ray per corner");
    let image = spd::corners_to_pixels(&film);
    assert_eq!((image.width, image.height), (512, 512));
    (Counts::of(&rays), image.to_rgb8(false))
}

/// `file`'s counts with the packet kernel within 10% of the Readme's row, and the single-ray kernel's
/// counts and image the same.
fn matches_the_readme(file: &str) {
    let want = spd::readme_counts(file).unwrap();
    let (got, image) = counts(file, Kernel::Packet);
    eprintln!("{file}: {got:?}, readme {want:?}");
    assert!(
        got.within(&want, 0.10),
        "{file}: {got:?} against the Readme's {want:?}"
    );
    assert_eq!(counts(file, Kernel::Single), (got, image), "{file}");
}

#[test]
fn balls_matches_the_readme_within_ten_percent() {
    matches_the_readme("balls_default.nff.gz");
}

#[test]
fn gears_matches_the_readme_within_ten_percent() {
    matches_the_readme("gears_default.nff.gz");
}

#[test]
fn mount_matches_the_readme_within_ten_percent() {
    matches_the_readme("mount_default.nff.gz");
}

#[test]
fn rings_matches_the_readme_within_ten_percent() {
    matches_the_readme("rings_default.nff.gz");
}

#[test]
fn teapot_matches_the_readme_within_ten_percent() {
    matches_the_readme("teapot_default.nff");
}

#[test]
fn tetra_matches_the_readme_within_ten_percent() {
    matches_the_readme("tetra_default.nff");
}

#[test]
fn tree_matches_the_readme_within_ten_percent() {
    matches_the_readme("tree_default.nff.gz");
}

/// A square of gears' glass (`f 1 .9 .7 0.2 0 100000 0.8 1.1`: Ks 0, T 0.8) facing the eye, lit from
/// the eye's side, with nothing else in the scene.
fn glass_square() -> Scene {
    let mut scene = Scene::new(Camera::new(
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::ZERO,
        Vec3::Y,
        30.0,
        8,
        8,
    ));
    let glass = scene.add_material(Material {
        diffuse: Vec3::new(1.0, 0.9, 0.7),
        kd: 0.2,
        specular: Vec3::new(1.0, 0.9, 0.7),
        ks: 0.0,
        shininess: 100_000.0,
        transmission: 0.8,
        ior: 1.1,
        roughness: None,
    });
    let [a, b, c, d] =
        [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)].map(|(x, y)| Vec3::new(x, y, 0.0));
    scene.add_triangle(a, b, c, glass);
    scene.add_triangle(a, c, d, glass);
    scene.add_point_light(Vec3::new(1.0, 2.0, 5.0), Vec3::ONE);
    scene
}

/// The rays of a 9 × 9 frame of the glass square at four bounces, in SPD mode or not, and the colour
/// of the ray straight down the axis.
fn glass_square_rays(spd: bool) -> (Counts, Vec3) {
    let scene = glass_square();
    let accel = Accel::build(Prims::new(&scene), AccelKind::None);
    let options = Options {
        width: 9,
        height: 9,
        max_depth: spd::SPD_DEPTH,
        spp: 0,
        spd,
        ..Options::new(&scene)
    };
    options.validate().unwrap();
    let renderer = Renderer::new(&scene, &accel, options);
    let never = std::sync::atomic::AtomicBool::new(false);
    let (_, rays) = renderer.render_pass(1, &|| {}, &never).unwrap();
    let axis = renderer.radiance(&Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z));
    (Counts::of(&rays), axis)
}

/// The Readme's rules 8 and 9: every ray hitting a transmitter spawns a reflection ray ("all
/// transmitters in the SPD are also reflective"), even where the file gives it no specular coefficient,
/// as gears does. Each eye ray that hits the square spawns one reflection ray (back toward the eye) and
/// one refraction ray (on through the square), both of which leave the scene; outside SPD mode a Ks of 0
/// spawns no reflection ray. The SPD's reflection ray has weight 0: the colour is the same either way.
#[test]
fn a_transmitter_without_ks_spawns_its_reflection_ray_in_spd_mode_only() {
    let (spd, spd_colour) = glass_square_rays(true);
    assert!(spd.eye_hits > 0 && spd.eye_hits < 81, "{spd:?}");
    assert_eq!(
        (spd.reflected, spd.refracted, spd.shadow),
        (spd.eye_hits, spd.eye_hits, spd.eye_hits),
        "{spd:?}"
    );
    let (plain, plain_colour) = glass_square_rays(false);
    assert!(plain.eye_hits > 0, "{plain:?}");
    assert_eq!(
        (plain.reflected, plain.refracted, plain.shadow),
        (0, plain.eye_hits, plain.eye_hits),
        "{plain:?}"
    );
    assert!(spd_colour.cmpgt(Vec3::ZERO).all(), "{spd_colour}");
    assert_eq!(spd_colour.to_array(), plain_colour.to_array());
}
