//! Every accelerator and kernel (the kit's contestants: single rays and packets) against brute force on
//! the kit's test rays over real geometry: the same hit or miss at the same `t` (bit for bit for the
//! grid, within 1e-5 for the hierarchies), and any hit agreeing with "closest hit before t_max".
//!
//! Brute force answers every ray of the small scenes. On the 202k-triangle dragon it answers an evenly
//! spaced sample, where the grid must match it bit for bit, and the grid answers all of the rays for the
//! others (`kit::oracle::against_grid`). The exhaustive tier (`cargo test --release -- --ignored`) has
//! brute force answer every ray there and on the full 871k-triangle dragon.

use std::path::Path;

use glam::Vec3;
use whitted::accel::Prims;
use whitted::kit::oracle;
use whitted::kit::rays::{self, TestRng};
use whitted::kit::{contestants, contestants::Contestant};
use whitted::scene::{self, Camera, Material, Scene};

use crate::common;

/// How many rays: `RAYS` overrides (e.g. `RAYS=1000000` for a long run).
fn count(default: usize) -> usize {
    common::env_number("RAYS", default)
}

/// How brute force takes part.
#[derive(Clone, Copy)]
enum BruteForce {
    /// It answers every ray.
    Everywhere,
    /// It answers this many rays, the grid the rest.
    Sample(usize),
}

/// Builds every contestant once over `scene`, makes `n` test rays and checks them all.
fn check(scene: &Scene, label: &str, n: usize, seed: u64, brute_force: BruteForce) {
    let prims = Prims::new(scene);
    let list: Vec<Contestant> = contestants::all(prims);
    // The points rays start from on surfaces: whichever structure finds them does not matter.
    let cases = rays::cases(scene, &list[0].accel, n, seed);
    let tally = match brute_force {
        BruteForce::Everywhere => oracle::against_brute_force(label, prims, &list, &cases),
        BruteForce::Sample(s) => oracle::against_grid(label, prims, &list, &cases, s),
    };
    eprintln!("{label}: {tally:?}");
    // Rays worth checking: a good part of them hit something.
    assert!(tally.hits > tally.rays / 10, "{label}: {tally:?}");
}

fn check_file(path: &Path, n: usize, brute_force: BruteForce) {
    let scene = scene::load(path).unwrap();
    check(&scene, &path.display().to_string(), n, 7, brute_force);
}

#[test]
fn spd_balls_gears_rings_and_tree() {
    for name in ["balls_1", "gears_1", "rings_1", "tree_1", "teapot_1", "lattice_1"] {
        check_file(
            &common::root().join(format!("scenes/spd/{name}.nff")),
            count(100_000),
            BruteForce::Everywhere,
        );
    }
}

#[test]
fn course_scenes() {
    for name in ["balls_box", "mount_low", "dof"] {
        check_file(
            &common::root().join(format!("scenes/{name}.p3f")),
            count(100_000),
            BruteForce::Everywhere,
        );
    }
}

/// Brute force costs ~3 ms of CPU a ray on 202k triangles: it answers about 2,000 of the 100,000 rays,
/// the grid (bit for bit brute force's answer there) the rest.
#[test]
fn stanford_dragon_res2() {
    check_file(
        &common::root().join("scenes/models/dragon_vrip_res2.ply.gz"),
        count(100_000),
        BruteForce::Sample(2_000),
    );
}

#[test]
#[ignore = "exhaustive tier: brute force on all 100,000 rays, 320 s of CPU"]
fn stanford_dragon_res2_exhaustive() {
    check_file(
        &common::root().join("scenes/models/dragon_vrip_res2.ply.gz"),
        count(100_000),
        BruteForce::Everywhere,
    );
}

#[test]
#[ignore = "exhaustive tier: brute force on 10,000 rays over 871k triangles, 143 s of CPU"]
fn stanford_dragon_full_exhaustive() {
    check_file(
        &common::root().join("scenes/dragon_full.p3f"),
        count(10_000),
        BruteForce::Everywhere,
    );
}

/// Random soups of every kind, sizes spanning four orders of magnitude, planes included.
#[test]
fn random_mixed_scenes() {
    for seed in 0..4u64 {
        let mut rng = TestRng::new(seed);
        let mut s = Scene::new(Camera::new(
            Vec3::new(0.0, 0.0, 30.0),
            Vec3::ZERO,
            Vec3::Y,
            60.0,
            64,
            64,
        ));
        let m = s.add_material(Material::default());
        for i in 0..600 {
            let p = rng.vec3(-10.0, 10.0);
            let size = 10f32.powf(rng.range(-3.0, 1.0));
            match i % 5 {
                0 => s.add_sphere(p, size * if i % 7 == 0 { -1.0 } else { 1.0 }, m),
                1 => s.add_triangle(p, p + rng.direction() * size, p + rng.direction() * size, m),
                2 => s.add_box(p, p + rng.vec3(0.0, 1.0) * size, m),
                3 => s.add_cone(
                    p,
                    size,
                    p + rng.direction() * size * 3.0,
                    size * rng.unit_f32(),
                    m,
                ),
                // A flat layer: zero thickness boxes and triangles in z = 0.
                _ => s.add_triangle(
                    p.with_z(0.0),
                    (p + Vec3::X * size).with_z(0.0),
                    (p + Vec3::Y * size).with_z(0.0),
                    m,
                ),
            }
        }
        s.add_plane(
            Vec3::new(0.0, -15.0, 0.0),
            Vec3::new(0.0, -15.0, 1.0),
            Vec3::new(1.0, -15.0, 0.0),
            m,
        );
        check(
            &s,
            &format!("random scene {seed}"),
            count(20_000),
            seed,
            BruteForce::Everywhere,
        );
    }
}
