//! The benchmark ray sets of `docs/dragon-workload.md`, generated from a scene: primary rays
//! through every pixel centre, a shadow ray from each primary hit to the first point light (any-hit), and
//! one cosine-weighted diffuse bounce from each hit (closest-hit, incoherent). The kernels bench and the
//! profiles trace these same rays, so their figures compare.

use glam::Vec3;
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};

use crate::accel::{Accel, Hit, PACKET, Prims, packet};
use crate::geometry::ray::Ray;
use crate::render::camera::RayCamera;
use crate::scene::Scene;

/// Offset of secondary ray origins along the geometric normal (the workload's 1e-4).
const OFFSET: f32 = 1e-4;

/// The three ray sets and the primary rays' checksums.
#[derive(Clone, Debug)]
pub struct Workload {
    /// One ray per pixel centre, row by row; `t` in `[0, ∞)`.
    pub primary: Vec<Ray>,
    /// From each primary hit toward the light, with its `t_max` (the light's distance less 1e-4 of it).
    pub shadow: Vec<(Ray, f32)>,
    /// From each primary hit, one cosine-weighted direction about the normal on the incoming side.
    pub diffuse: Vec<Ray>,
    /// Primary rays that hit something.
    pub primary_hits: usize,
    /// Σ t over the primary hits (the workload document's checksum).
    pub sum_t: f64,
}

/// Segments (rays with their `t_max`) eight at a time, in order, as the renderer's tiles and the kernels
/// bench form packets: each packet's rays, limits and active mask (a short last packet's spare lanes
/// repeat its first ray, inactive) passed to `trace`; the sum of the bits of the masks it returns.
#[inline(always)]
pub fn packets_of(
    segments: &[(Ray, f32)],
    trace: impl Fn(&[Ray; PACKET], u8, &[f32; PACKET]) -> u8,
) -> usize {
    let mut found = 0;
    for chunk in segments.chunks(PACKET) {
        let mut r = [chunk[0].0; PACKET];
        let mut t = [0.0; PACKET];
        for (k, (ray, t_max)) in chunk.iter().enumerate() {
            (r[k], t[k]) = (*ray, *t_max);
        }
        let active = packet::first(chunk.len());
        found += trace(&r, active, &t).count_ones() as usize;
    }
    found
}

/// Builds the workload for `scene` at its resolution, using `accel` to find the primary hits; the
/// shadow rays aim at the first point light (or straight up when there is none). `seed` fixes the
/// diffuse directions.
pub fn generate(scene: &Scene, accel: &Accel, seed: u64) -> Workload {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let camera = RayCamera::new(&scene.camera, w, h);
    let prims = Prims::new(scene);
    let light = scene.point_lights.first().map(|l| l.position);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut out = Workload {
        primary: Vec::with_capacity((w * h) as usize),
        shadow: Vec::new(),
        diffuse: Vec::new(),
        primary_hits: 0,
        sum_t: 0.0,
    };
    for y in 0..h {
        for x in 0..w {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            out.primary.push(ray);
            let mut hit = Hit::miss(f32::INFINITY);
            if !accel.intersect(&ray, 0.0, &mut hit) {
                continue;
            }
            out.primary_hits += 1;
            out.sum_t += hit.t as f64;
            // The surface's normals come turned toward the incoming ray.
            let n = prims.surface(&ray, &hit).geometric;
            let origin = ray.at(hit.t) + OFFSET * n;
            let to_light = light.map_or(n, |l| l - origin);
            let distance = to_light.length();
            out.shadow
                .push((Ray::new(origin, to_light / distance), distance * (1.0 - 1e-4)));
            out.diffuse.push(Ray::new(origin, cosine_direction(n, &mut rng)));
        }
    }
    out
}

/// A cosine-weighted direction about the unit normal `n` (Malley's method: a uniform point on the unit
/// disc lifted to the hemisphere).
fn cosine_direction(n: Vec3, rng: &mut Xoshiro256PlusPlus) -> Vec3 {
    let u1 = (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
    let u2 = (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
    let r = u1.sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let (a, b) = n.any_orthonormal_pair();
    (a * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize()
}
