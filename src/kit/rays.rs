//! Seeded test rays: one generator of random numbers for every test (so a failure reproduces from its
//! seed), and the rays the accelerators are compared on.

use glam::Vec3;
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};

use crate::accel::{Accel, Hit, PrimKind, Prims};
use crate::geometry::aabb::Aabb;
use crate::geometry::ray::Ray;
use crate::render::camera::RayCamera;
use crate::scene::Scene;

/// A deterministic generator of test floats and vectors.
pub struct TestRng(Xoshiro256PlusPlus);

impl TestRng {
    /// A generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        TestRng(Xoshiro256PlusPlus::seed_from_u64(seed))
    }

    /// Uniform in [0, 1): the top 24 bits are exactly representable in an f32.
    pub fn unit_f32(&mut self) -> f32 {
        (self.0.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit_f32()
    }

    /// Uniform in the box [lo, hi)^3.
    pub fn vec3(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }

    /// Uniform on the unit sphere, by rejection from the cube.
    pub fn direction(&mut self) -> Vec3 {
        loop {
            let v = self.vec3(-1.0, 1.0);
            let l2 = v.length_squared();
            if l2 > 1e-4 && l2 <= 1.0 {
                return v / l2.sqrt();
            }
        }
    }

    /// Uniform in `0..n` (`n` > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.0.next_u64() % n as u64) as usize
    }
}

/// A ray and the interval searched along it: the closest hit with `t` in `(t_min, t_max)`, and whether
/// anything lies in that interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Case {
    /// The ray.
    pub ray: Ray,
    /// Hits at or before this are not wanted (0, or a small offset for rays that leave a surface).
    pub t_min: f32,
    /// Hits at or beyond this are not wanted (∞, or a segment's end as for shadow rays).
    pub t_max: f32,
}

impl Case {
    /// The whole ray from `t_min` on.
    pub fn ray(ray: Ray, t_min: f32) -> Self {
        Case {
            ray,
            t_min,
            t_max: f32::INFINITY,
        }
    }
}

/// How many kinds of ray [`cases`] makes, in turn.
const KINDS: usize = 4;

/// `n` test rays over `scene`, of four kinds in turn (so that any prefix, and any sample at an odd
/// stride, mixes them):
///
/// - random: origins uniform in [`origin_box`], uniform directions; every third of them with one
///   component zero and every fifth along an axis (the directions whose slab tests divide by zero);
/// - camera rays through random points of the scene's image;
/// - aimed at a random primitive: at a triangle's vertex or at a point of one of its edges (grazing hits
///   and shared edges, where rounding decides), or at a random point of another primitive's box (so that
///   small primitives in big scenes get hit too);
/// - leaving a surface, as secondary rays do: from the hit point of a random ray, in a random direction;
///   `t_min` 0 for every other one (the surface itself lies at `t` = 0) and 1e-5 of [`origin_box`]'s
///   diagonal for the rest; half of them segments ending at a random `t` within that diagonal, as
///   shadow rays are.
///
/// `finder` only finds the points to start from: any structure will do, and nothing here checks it.
pub fn cases(scene: &Scene, finder: &Accel, n: usize, seed: u64) -> Vec<Case> {
    let mut rng = TestRng::new(seed);
    let prims = Prims::new(scene);
    let (lo, hi) = origin_box(&prims);
    let diag = (hi - lo).length();
    let camera = RayCamera::new(&scene.camera, scene.camera.width, scene.camera.height);
    let (w, h) = (scene.camera.width as f32, scene.camera.height as f32);
    let axes = [Vec3::X, Vec3::Y, Vec3::Z, Vec3::NEG_X, Vec3::NEG_Y, Vec3::NEG_Z];
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let i = out.len();
        let j = i / KINDS;
        let origin = lo + (hi - lo) * rng.vec3(0.0, 1.0);
        let case = match i % KINDS {
            0 => {
                let mut dir = rng.direction();
                if j.is_multiple_of(3) {
                    dir[j % 7 % 3] = 0.0;
                }
                if j.is_multiple_of(5) {
                    dir = axes[j % 6];
                }
                Case::ray(Ray::new(origin, dir), 0.0)
            }
            1 => Case::ray(camera.ray(rng.range(0.0, w), rng.range(0.0, h)), 0.0),
            2 => {
                let target = aim(&prims, scene, &mut rng).unwrap_or(origin + rng.direction());
                let dir = (target - origin).normalize();
                let dir = if dir.is_finite() { dir } else { rng.direction() };
                Case::ray(Ray::new(origin, dir), 0.0)
            }
            _ => {
                let probe = Ray::new(origin, rng.direction());
                let mut hit = Hit::miss(f32::INFINITY);
                if finder.intersect(&probe, 0.0, &mut hit) {
                    let t_min = if j.is_multiple_of(2) { 0.0 } else { 1e-5 * diag };
                    let t_max = if j % 4 < 2 {
                        f32::INFINITY
                    } else {
                        rng.range(0.0, diag)
                    };
                    Case {
                        ray: Ray::new(probe.at(hit.t), rng.direction()),
                        t_min,
                        t_max,
                    }
                } else {
                    Case::ray(probe, 0.0)
                }
            }
        };
        out.push(case);
    }
    out
}

/// The box random origins are drawn from: the box around the primitives with finite bounds, grown by
/// half its size on every side (at least 1e-3 of its largest side, or of 1, so that flat and point-like
/// scenes get a volume), or [-5, 5]^3 when no primitive has finite bounds (planes only).
pub fn origin_box(prims: &Prims) -> (Vec3, Vec3) {
    let b = (0..prims.bounded())
        .map(|id| prims.bounds(id))
        .filter(|b| b.min.is_finite() && b.max.is_finite())
        .fold(Aabb::EMPTY, Aabb::union);
    if b.is_empty() {
        return (Vec3::splat(-5.0), Vec3::splat(5.0));
    }
    let e = b
        .extent()
        .max(Vec3::splat((1e-3 * b.extent().max_element()).max(1e-3)));
    (b.min - 0.5 * e, b.max + 0.5 * e)
}

/// A point to aim at on a random bounded primitive: a triangle's vertex, edge midpoint or point along
/// an edge; a random point of any other primitive's box. `None` for a scene without bounded primitives.
fn aim(prims: &Prims, scene: &Scene, rng: &mut TestRng) -> Option<Vec3> {
    if prims.bounded() == 0 {
        return None;
    }
    let id = rng.below(prims.bounded() as usize) as u32;
    Some(match prims.kind(id) {
        PrimKind::Triangle(t) => {
            let [a, b, c] = scene.triangles.vertices(t);
            match rng.below(4) {
                0 => a,
                1 => (a + b) * 0.5,
                2 => b + (c - b) * rng.unit_f32(),
                _ => (a + c) * 0.5,
            }
        }
        _ => {
            let b = prims.bounds(id);
            b.min + b.extent() * rng.vec3(0.0, 1.0)
        }
    })
}
