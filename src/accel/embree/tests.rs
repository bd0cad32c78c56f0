use glam::Vec3;

use super::*;
use crate::accel::packet::PACKET;
use crate::accel::prims::Hit;
use crate::geometry::ray::Ray;
use crate::geometry::triangle;
use crate::kit::rays::TestRng;
use crate::scene::{Camera, Material, Scene};

fn scene() -> Scene {
    Scene::new(Camera::new(
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::ZERO,
        Vec3::Y,
        45.0,
        32,
        32,
    ))
}

/// Embree's `u, v` on a triangle are ours: the weights of the second and third vertices, to
/// rounding, and `t` too; and the primitive id maps back to ours.
#[test]
fn barycentrics_and_t_match_moller_trumbore() {
    let mut s = scene();
    let m = s.add_material(Material::default());
    s.add_sphere(Vec3::new(10.0, 10.0, 10.0), 0.5, m);
    let (a, b, c) = (
        Vec3::new(-1.0, -0.5, 0.0),
        Vec3::new(2.0, -1.0, 0.3),
        Vec3::new(0.2, 1.5, -0.4),
    );
    s.add_triangle(a, b, c, m);
    let prims = Prims::new(&s);
    let e = Embree::new(prims, Quality::High, 1, None).unwrap();
    let mut rng = TestRng::new(3);
    let mut compared = 0;
    for _ in 0..1000 {
        let target = a + (b - a) * rng.unit_f32() + (c - a) * rng.unit_f32() * 0.999;
        let origin = Vec3::new(rng.unit_f32() - 0.5, rng.unit_f32() - 0.5, 4.0 + rng.unit_f32());
        let ray = Ray::new(origin, target - origin);
        let t = &s.triangles;
        let ours = triangle::intersect(t.v0.get(0), t.e1.get(0), t.e2.get(0), &ray, 0.0, f32::INFINITY);
        let mut hit = Hit::miss(f32::INFINITY);
        let found = e.intersect(&ray, 0.0, &mut hit);
        let Some((t, u, v)) = ours else {
            continue;
        };
        // Well inside: Embree must agree on the hit.
        if u.min(v).min(1.0 - u - v) < 1e-4 {
            continue;
        }
        assert!(found, "{ray:?}");
        assert_eq!(hit.prim, prims.triangle_id(0));
        assert!((hit.t - t).abs() <= 1e-6 * t, "t {} vs {t}", hit.t);
        assert!(
            (hit.u - u).abs() < 1e-5 && (hit.v - v).abs() < 1e-5,
            "({}, {}) vs ({u}, {v})",
            hit.u,
            hit.v
        );
        compared += 1;
    }
    assert!(compared > 300, "{compared}");
}

/// Spheres, boxes and cones through the user geometry, planes beside: every kind answers as brute
/// force, single rays and packets, closest and any hit, and the interval is open at both ends.
#[test]
fn user_geometry_and_planes() {
    let mut s = scene();
    let m = s.add_material(Material::default());
    s.add_sphere(Vec3::new(0.0, 0.0, 0.0), 1.0, m);
    s.add_box(Vec3::new(-3.0, -1.0, -1.0), Vec3::new(-2.0, 1.0, 1.0), m);
    let z = |x: f32, y: f32| Vec3::new(x, y, -3.0);
    assert!(s.add_plane(z(0.0, 0.0), z(1.0, 0.0), z(0.0, 1.0), m));
    let prims = Prims::new(&s);
    let e = Embree::new(prims, Quality::Medium, 2, None).unwrap();
    assert_eq!(e.counts(), (0, 2));
    let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
    let mut hit = Hit::miss(f32::INFINITY);
    assert!(e.intersect(&ray, 0.0, &mut hit));
    assert_eq!((hit.t, hit.prim), (4.0, 0));
    // Open at t_max: the sphere at exactly 4 is not before 4; the plane at 8 is beyond.
    assert!(!e.occluded(&ray, 0.0, 4.0));
    assert!(e.occluded(&ray, 0.0, 4.0f32.next_up()));
    // Open at t_min: from 4 on, the sphere's far side at 6.
    let mut hit = Hit::miss(f32::INFINITY);
    assert!(e.intersect(&ray, 4.0, &mut hit));
    assert_eq!((hit.t, hit.prim), (6.0, 0));
    let mut hit = Hit::miss(f32::INFINITY);
    assert!(e.intersect(&ray, 6.0, &mut hit));
    assert_eq!((hit.t, hit.prim), (8.0, prims.planes().start));
    // The box, and a packet of both.
    let to_box = Ray::new(Vec3::new(-2.5, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
    let mut rays = [ray; PACKET];
    rays[3] = to_box;
    let mut hits = [Hit::miss(f32::INFINITY); PACKET];
    hits[5].t = -1.0;
    let found = e.intersect_packet(&rays, 0b0010_1011, 0.0, &mut hits);
    assert_eq!(found, 0b0000_1011);
    assert_eq!((hits[3].t, hits[3].prim), (4.0, 1));
    assert_eq!((hits[0].t, hits[0].prim), (4.0, 0));
    assert_eq!(hits[2], Hit::miss(f32::INFINITY));
    let t_max = [4.0, 4.5, 9.0, 3.5, 1.0, 1.0, 1.0, 1.0];
    assert_eq!(e.occluded_packet(&rays, 0b0000_1111, 0.0, &t_max), 0b0000_0110);
    assert!(e.error().is_ok());
}

/// A ray from beyond Embree's largest coordinate (its traversal asserts against it, which aborts the
/// process) is traced from where it enters Embree's range: our own test's hit at its `t`, single rays
/// and packets, closest and any hit; one that never comes within range misses. A scene that reaches
/// past it is refused.
#[test]
fn rays_from_beyond_flt_large_find_our_hits() {
    let mut s = scene();
    let m = s.add_material(Material::default());
    s.add_sphere(Vec3::ZERO, 1e17, m);
    let prims = Prims::new(&s);
    let e = Embree::new(prims, Quality::High, 1, None).unwrap();
    let toward = Ray::new(Vec3::new(3e18, 0.0, 0.0), Vec3::NEG_X);
    let away = Ray::new(toward.origin, Vec3::X);
    let near = Ray::new(Vec3::new(0.0, 0.0, 5e17), Vec3::NEG_Z);
    let close = |got: f32, ray: &Ray| {
        let (t, _, _) = prims.intersect(0, ray, 0.0, f32::INFINITY).unwrap();
        assert!((got - t).abs() <= 1e-6 * t, "t {got} vs {t}");
    };
    let mut hit = Hit::miss(f32::INFINITY);
    assert!(e.intersect(&toward, 0.0, &mut hit));
    assert_eq!(hit.prim, 0);
    close(hit.t, &toward);
    assert!(!e.intersect(&away, 0.0, &mut Hit::miss(f32::INFINITY)));
    assert!(e.occluded(&toward, 0.0, f32::INFINITY));
    assert!(!e.occluded(&toward, 0.0, 2.8e18));
    assert!(!e.occluded(&away, 0.0, f32::INFINITY));
    let rays = [toward, away, near, toward, away, near, toward, away];
    let mut hits = [Hit::miss(f32::INFINITY); PACKET];
    assert_eq!(e.intersect_packet(&rays, 0xff, 0.0, &mut hits), 0b0110_1101);
    for k in [0, 2, 3, 5, 6] {
        close(hits[k].t, &rays[k]);
    }
    let t_max = [f32::INFINITY; PACKET];
    assert_eq!(e.occluded_packet(&rays, 0xff, 0.0, &t_max), 0b0110_1101);
    assert!(e.error().is_ok());

    let mut huge = scene();
    let m = huge.add_material(Material::default());
    huge.add_sphere(Vec3::ZERO, 2e18, m);
    let refused = Embree::new(Prims::new(&huge), Quality::High, 1, None).unwrap_err();
    assert!(refused.message.contains("reach 2e18"), "{refused}");
}

/// An empty scene and one of planes only answer without Embree's scene; clones share one.
#[test]
fn empty_and_planes_only() {
    let s = scene();
    let e = Embree::new(Prims::new(&s), Quality::High, 1, None).unwrap();
    let ray = Ray::new(Vec3::ZERO, Vec3::Z);
    assert!(!e.intersect(&ray, 0.0, &mut Hit::miss(f32::INFINITY)));
    let mut s = scene();
    let m = s.add_material(Material::default());
    let z = |x: f32, y: f32| Vec3::new(x, y, 2.0);
    assert!(s.add_plane(z(0.0, 0.0), z(1.0, 0.0), z(0.0, 1.0), m));
    let e = Embree::new(Prims::new(&s), Quality::High, 1, None).unwrap();
    let copy = e.clone();
    drop(e);
    let mut hit = Hit::miss(f32::INFINITY);
    assert!(copy.intersect(&ray, 0.0, &mut hit));
    assert_eq!(hit.t, 2.0);
}

#[test]
fn send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Embree<'static>>();
}

/// A device made for one instruction set: AVX2 (where the CPU has it) answers as Embree's own choice
/// does and says so; a set the CPU lacks is refused with a message, not a crash.
#[test]
fn a_device_runs_the_instruction_set_asked_for() {
    let mut s = scene();
    let m = s.add_material(Material::default());
    let mut rng = TestRng::new(11);
    for _ in 0..200 {
        let p = Vec3::new(rng.unit_f32(), rng.unit_f32(), rng.unit_f32()) * 4.0 - 2.0;
        s.add_triangle(p, p + Vec3::X * 0.3, p + Vec3::Y * 0.3, m);
    }
    let prims = Prims::new(&s);
    let own = Embree::new(prims, Quality::High, 1, None).unwrap();
    assert!(own.describe().contains("its best kernels"), "{}", own.describe());
    for isa in [Isa::Avx2, Isa::Avx512] {
        let Ok(forced) = Embree::new(prims, Quality::High, 1, Some(isa)) else {
            let e = Embree::new(prims, Quality::High, 1, Some(isa)).unwrap_err();
            assert!(!isa.available(), "{isa:?} refused on a CPU that has it: {e}");
            assert!(e.message.contains("lacks the instructions"), "{e}");
            continue;
        };
        assert!(
            forced.describe().contains(&format!("{isa:?} kernels")),
            "{}",
            forced.describe()
        );
        for _ in 0..500 {
            let origin = Vec3::new(rng.unit_f32(), rng.unit_f32(), 0.0) * 4.0 - Vec3::new(2.0, 2.0, -5.0);
            let ray = Ray::new(
                origin,
                Vec3::new(rng.unit_f32() * 0.2 - 0.1, rng.unit_f32() * 0.2 - 0.1, -1.0),
            );
            let (mut a, mut b) = (Hit::miss(f32::INFINITY), Hit::miss(f32::INFINITY));
            assert_eq!(
                own.intersect(&ray, 0.0, &mut a),
                forced.intersect(&ray, 0.0, &mut b),
                "{ray:?}"
            );
            assert_eq!((a.prim, a.t), (b.prim, b.t), "{isa:?}, {ray:?}");
        }
    }
}
