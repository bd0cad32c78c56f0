//! Every accelerator against brute force on many rays over real geometry: same hit or miss, the same
//! primitive (or, where two primitives tie, the same `t` within 1e-5 relative), and any-hit agreeing with
//! "closest hit before t_max".

mod common;

use std::path::Path;

use glam::Vec3;
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};
use rayon::prelude::*;
use whitted::accel::PACKET;
use whitted::accel::bvh2::Builder;
use whitted::accel::policy::{AnyHit, Closest};
use whitted::accel::wide::{Simd, WideBvh};
use whitted::accel::{Accel, AccelKind, BuildOptions, Hit, Prims};
use whitted::geometry::ray::Ray;
use whitted::render::camera::RayCamera;
use whitted::scene::{self, Scene};

struct Case {
    ray: Ray,
    t_min: f32,
}

fn unit(rng: &mut Xoshiro256PlusPlus) -> f32 {
    (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32
}

fn direction(rng: &mut Xoshiro256PlusPlus) -> Vec3 {
    loop {
        let v = Vec3::new(unit(rng), unit(rng), unit(rng)) * 2.0 - 1.0;
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

/// `n` rays of four kinds: random, camera, aimed at triangle edges and vertices (grazing), and starting
/// on a surface (at a hit point of a random ray, half with t_min = 0, half with a small offset).
fn rays(scene: &Scene, n: usize, seed: u64) -> Vec<Case> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let b = scene.bounds();
    let (centre, size) = (b.center(), b.extent() * 1.5);
    let diag = b.extent().length();
    let cam = RayCamera::new(&scene.camera, scene.camera.width, scene.camera.height);
    // Only to find points on surfaces to start from; which structure finds them does not matter.
    let finder = Accel::build(Prims::new(scene), AccelKind::Bvh4);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let k = out.len() % 4;
        let origin = centre + (Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) - 0.5) * size;
        match k {
            0 => out.push(Case {
                ray: Ray::new(origin, direction(&mut rng)),
                t_min: 0.0,
            }),
            1 => {
                let (x, y) = (unit(&mut rng) * cam_w(scene), unit(&mut rng) * cam_h(scene));
                out.push(Case {
                    ray: cam.ray(x, y),
                    t_min: 0.0,
                });
            }
            2 if !scene.triangles.is_empty() => {
                let i = rng.next_u32() as usize % scene.triangles.len();
                let [a, bb, c] = scene.triangles.vertices(i);
                let target = match rng.next_u32() % 4 {
                    0 => a,
                    1 => (a + bb) * 0.5,
                    2 => bb + (c - bb) * unit(&mut rng),
                    _ => (a + c) * 0.5,
                };
                if (target - origin).length_squared() > 0.0 {
                    out.push(Case {
                        ray: Ray::new(origin, (target - origin).normalize()),
                        t_min: 0.0,
                    });
                }
            }
            _ => {
                // Start on a surface: a random ray's hit point, leaving in a new direction.
                let probe = Ray::new(origin, direction(&mut rng));
                let mut hit = Hit::miss(f32::INFINITY);
                if finder.intersect(&probe, 0.0, &mut hit) {
                    let t_min = if out.len() % 8 == 3 { 0.0 } else { 1e-5 * diag };
                    out.push(Case {
                        ray: Ray::new(probe.at(hit.t), direction(&mut rng)),
                        t_min,
                    });
                } else {
                    out.push(Case {
                        ray: probe,
                        t_min: 0.0,
                    });
                }
            }
        }
    }
    out
}

fn cam_w(s: &Scene) -> f32 {
    s.camera.width as f32
}

fn cam_h(s: &Scene) -> f32 {
    s.camera.height as f32
}

/// Compares every accelerator with brute force on `rays`; panics with the first disagreement.
fn check(scene: &Scene, cases: &[Case], name: &str) {
    let prims = Prims::new(scene);
    let brute = Accel::build(prims, AccelKind::None);
    let reference: Vec<Hit> = cases
        .par_iter()
        .map(|c| {
            let mut hit = Hit::miss(f32::INFINITY);
            brute.intersect(&c.ray, c.t_min, &mut hit);
            hit
        })
        .collect();
    // The BVH8 on each slab instruction set this CPU has (the portable one always).
    let bvh8 = |simd: Simd| {
        let mut accel = Accel::build(prims, AccelKind::Bvh8);
        if let Accel::Bvh8(b) = &mut accel {
            b.set_simd(simd).then_some(accel)
        } else {
            None
        }
    };
    if !Simd::Avx2.available() {
        eprintln!("{name}: this CPU has no AVX2; the BVH8 is checked on its portable slab test only");
    }
    let wide8 = [
        bvh8(Simd::Portable).map(|a| ("bvh8 portable", a)),
        bvh8(Simd::Avx2).map(|a| ("bvh8 avx2", a)),
    ];
    let accels = [
        ("grid", Accel::build(prims, AccelKind::Grid)),
        (
            "bvh2 midpoint",
            Accel::build_with(
                prims,
                AccelKind::Bvh2,
                BuildOptions {
                    builder: Builder::Midpoint,
                    bins: 12,
                },
            ),
        ),
        ("bvh2 sah", Accel::build(prims, AccelKind::Bvh2)),
        ("bvh4", Accel::build(prims, AccelKind::Bvh4)),
        (
            "bvh4 4 bins",
            Accel::build_with(
                prims,
                AccelKind::Bvh4,
                BuildOptions {
                    bins: 4,
                    ..BuildOptions::default()
                },
            ),
        ),
    ];
    for (label, accel) in accels.iter().chain(wide8.iter().flatten()) {
        match accel {
            Accel::Bvh4(bvh) => check_packets(bvh, cases, &reference, &format!("{name}, {label}")),
            Accel::Bvh8(bvh) => check_packets(bvh, cases, &reference, &format!("{name}, {label}")),
            _ => {}
        }
        cases
            .par_iter()
            .zip(&reference)
            .enumerate()
            .for_each(|(i, (c, want))| {
                let mut got = Hit::miss(f32::INFINITY);
                let found = accel.intersect(&c.ray, c.t_min, &mut got);
                let ctx = || {
                    format!(
                        "{name}, {label}, ray {i} {:?} t_min {}: got {got:?}, brute force {want:?}",
                        c.ray, c.t_min
                    )
                };
                assert_eq!(found, want.is_hit(), "hit/miss differs: {}", ctx());
                if want.is_hit() && got.prim != want.prim {
                    assert!(
                        (got.t - want.t).abs() <= 1e-5 * want.t.max(1.0),
                        "different primitive and t: {}",
                        ctx()
                    );
                }
                if want.is_hit() {
                    assert!(
                        (got.t - want.t).abs() <= 1e-5 * want.t.max(1.0),
                        "t differs: {}",
                        ctx()
                    );
                    // Any hit within a little beyond the closest hit: yes; well before it: no.
                    assert!(
                        accel.occluded(&c.ray, c.t_min, want.t * 1.001 + 1e-6),
                        "any-hit missed: {}",
                        ctx()
                    );
                    assert!(
                        !accel.occluded(&c.ray, c.t_min, want.t * 0.999),
                        "any-hit too early: {}",
                        ctx()
                    );
                } else {
                    assert!(
                        !accel.occluded(&c.ray, c.t_min, f32::INFINITY),
                        "any-hit on a miss: {}",
                        ctx()
                    );
                }
            });
    }
}

/// The packet kernel on the same rays, eight at a time (one lane left inactive): the same hits or misses
/// as brute force at the same `t` (within 1e-5 relative), any hit as "closest hit before t_max". Rays are grouped by `t_min` and sorted by direction octant, so that most packets share their
/// direction signs (the kernel's coherent path) and the rest mix them.
fn check_packets<const W: usize>(bvh: &WideBvh<W>, cases: &[Case], reference: &[Hit], name: &str) {
    let octant = |c: &Case| c.ray.dir.cmplt(Vec3::ZERO).bitmask();
    let mut order: Vec<usize> = (0..cases.len()).collect();
    order.sort_by_key(|&i| (cases[i].t_min.to_bits(), octant(&cases[i]), i));
    let groups: Vec<&[usize]> = order
        .chunk_by(|&a, &b| cases[a].t_min == cases[b].t_min)
        .flat_map(|g| g.chunks(PACKET))
        .collect();
    groups.par_iter().for_each(|ids| {
        let t_min = cases[ids[0]].t_min;
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET];
        for (k, &i) in ids.iter().enumerate() {
            rays[k] = cases[i].ray;
        }
        // A lane left out of the mask keeps its hit untouched.
        let active = (1u16 << ids.len()) as u8;
        let active = active.wrapping_sub(1) & if ids.len() > 2 { !2 } else { 0xff };
        let mut hits = [Hit::miss(f32::INFINITY); PACKET];
        let found = bvh.traverse_packet::<Closest>(&rays, active, t_min, &mut hits);
        for (k, &i) in ids.iter().enumerate() {
            let (got, want) = (&hits[k], &reference[i]);
            let ctx = || {
                format!(
                    "{name}, packet lane {k}, ray {i} {:?}: got {got:?}, brute force {want:?}",
                    rays[k]
                )
            };
            if active >> k & 1 == 0 {
                assert!(
                    !got.is_hit() && found >> k & 1 == 0,
                    "inactive lane touched: {}",
                    ctx()
                );
                continue;
            }
            assert_eq!(found >> k & 1 == 1, want.is_hit(), "hit/miss differs: {}", ctx());
            if want.is_hit() {
                assert!(
                    (got.t - want.t).abs() <= 1e-5 * want.t.max(1.0),
                    "t differs: {}",
                    ctx()
                );
            }
        }
        // Any hit: each ray up to just past, then to just before, its closest hit.
        for (scale, margin) in [(1.001f32, 1e-6f32), (0.999, 0.0)] {
            let mut limits = [Hit::miss(f32::INFINITY); PACKET];
            for (k, &i) in ids.iter().enumerate() {
                let want = &reference[i];
                if want.is_hit() {
                    limits[k] = Hit::miss(want.t * scale + margin);
                }
            }
            let blocked = bvh.traverse_packet::<AnyHit>(&rays, active, t_min, &mut limits);
            for (k, &i) in ids.iter().enumerate() {
                if active >> k & 1 == 1 {
                    assert_eq!(
                        blocked >> k & 1 == 1,
                        reference[i].is_hit() && scale > 1.0,
                        "{name}, packet any-hit lane {k}, ray {i} {:?}, limit {}",
                        rays[k],
                        limits[k].t
                    );
                }
            }
        }
    });
}

fn check_file(path: &Path, n: usize) {
    let scene = scene::load(path).unwrap();
    let cases = rays(&scene, n, 7);
    check(&scene, &cases, &path.display().to_string());
}

/// How many rays: `RAYS` overrides (e.g. `RAYS=1000000` for a long run).
fn count(default: usize) -> usize {
    std::env::var("RAYS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

#[test]
fn spd_balls_gears_rings_and_tree() {
    for name in ["balls_1", "gears_1", "rings_1", "tree_1", "teapot_1", "lattice_1"] {
        check_file(
            &common::root().join(format!("scenes/spd/{name}.nff")),
            count(100_000),
        );
    }
}

#[test]
fn course_scenes() {
    for name in ["balls_box", "mount_low", "dof"] {
        check_file(&common::root().join(format!("scenes/{name}.p3f")), count(100_000));
    }
}

#[test]
fn stanford_dragon_res2() {
    // Brute force costs ~5 ms a ray on 202k triangles: 100,000 rays take about 4 minutes on 2 cores.
    check_file(
        &common::root().join("scenes/models/dragon_vrip_res2.ply.gz"),
        count(100_000),
    );
}

/// The full dragon: brute force on 871k triangles is slow, so this one runs on request
/// (`cargo test --release -- --ignored`).
#[test]
#[ignore]
fn stanford_dragon_full() {
    check_file(&common::root().join("scenes/dragon_full.p3f"), count(10_000));
}

/// Random soups of every kind, sizes spanning four orders of magnitude, planes included.
#[test]
fn random_mixed_scenes() {
    for seed in 0..4u64 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut s = Scene::new(whitted::scene::Camera::new(
            Vec3::new(0.0, 0.0, 30.0),
            Vec3::ZERO,
            Vec3::Y,
            60.0,
            64,
            64,
        ));
        let m = s.add_material(whitted::scene::Material::default());
        for i in 0..600 {
            let p = (Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) - 0.5) * 20.0;
            let size = 10f32.powf(unit(&mut rng) * 4.0 - 3.0);
            match i % 5 {
                0 => s.add_sphere(p, size * if i % 7 == 0 { -1.0 } else { 1.0 }, m),
                1 => s.add_triangle(
                    p,
                    p + direction(&mut rng) * size,
                    p + direction(&mut rng) * size,
                    m,
                ),
                2 => s.add_box(
                    p,
                    p + Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) * size,
                    m,
                ),
                3 => s.add_cone(
                    p,
                    size,
                    p + direction(&mut rng) * size * 3.0,
                    size * unit(&mut rng),
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
        let cases = rays(&s, count(20_000), seed);
        check(&s, &cases, &format!("random scene {seed}"));
    }
}
