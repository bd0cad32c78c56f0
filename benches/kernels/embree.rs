//! Embree 3's tracing calls on our rays: single rays (`rtcIntersect1`, `rtcOccluded1`) and 8-wide packets
//! (`rtcIntersect8`, `rtcOccluded8`, consecutive rays as our packet kernel takes them). The structs
//! mirror `rtcore_ray.h` (Embree 3.13, one instance level).

use whitted::geometry::ray::Ray;

use crate::common::embree::{EmbreeScene, Handle};
use crate::contestant::{Contestant, FirstHit, Segment, Side};

const INVALID_ID: u32 = u32::MAX;

#[repr(C)]
struct Context {
    flags: u32,
    filter: Option<unsafe extern "C" fn()>,
    inst_id: [u32; 1],
}

impl Context {
    /// `rtcInitIntersectContext` (an inline function in the header).
    fn new() -> Self {
        Context {
            flags: 0,
            filter: None,
            inst_id: [INVALID_ID],
        }
    }
}

#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Ray1 {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Hit1 {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
}

#[repr(C)]
struct RayHit1 {
    ray: Ray1,
    hit: Hit1,
}

#[repr(C, align(32))]
#[derive(Default)]
struct Ray8 {
    org: [[f32; 8]; 3],
    tnear: [f32; 8],
    dir: [[f32; 8]; 3],
    time: [f32; 8],
    tfar: [f32; 8],
    mask: [u32; 8],
    id: [u32; 8],
    flags: [u32; 8],
}

#[repr(C, align(32))]
#[derive(Default)]
struct Hit8 {
    ng: [[f32; 8]; 3],
    u: [f32; 8],
    v: [f32; 8],
    prim_id: [u32; 8],
    geom_id: [u32; 8],
    inst_id: [[u32; 8]; 1],
}

#[repr(C)]
#[derive(Default)]
struct RayHit8 {
    ray: Ray8,
    hit: Hit8,
}

/// A packet's lane mask (-1 active, 0 not), which Embree loads as one aligned vector.
#[repr(C, align(32))]
#[derive(Default)]
struct Valid([i32; 8]);

#[link(name = "embree3")]
unsafe extern "C" {
    fn rtcIntersect1(scene: Handle, context: *mut Context, rayhit: *mut RayHit1);
    fn rtcOccluded1(scene: Handle, context: *mut Context, ray: *mut Ray1);
    fn rtcIntersect8(valid: *const Valid, scene: Handle, context: *mut Context, rayhit: *mut RayHit8);
    fn rtcOccluded8(valid: *const Valid, scene: Handle, context: *mut Context, ray: *mut Ray8);
}

fn ray1(ray: &Ray, t_max: f32) -> Ray1 {
    Ray1 {
        org: ray.origin.to_array(),
        tnear: 0.0,
        dir: ray.dir.to_array(),
        time: 0.0,
        tfar: t_max,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// Fills lane `k` of `r` and returns the packet's `valid` word for it.
fn lane(r: &mut Ray8, k: usize, ray: &Ray, t_max: f32) -> i32 {
    for a in 0..3 {
        r.org[a][k] = ray.origin[a];
        r.dir[a][k] = ray.dir[a];
    }
    (r.tnear[k], r.tfar[k], r.mask[k]) = (0.0, t_max, u32::MAX);
    -1
}

impl EmbreeScene {
    /// The triangle a segment hits first (`rtcIntersect1`), if any.
    pub fn hit(&self, ray: &Ray, t_max: f32) -> Option<u32> {
        let mut rh = RayHit1 {
            ray: ray1(ray, t_max),
            hit: Hit1 {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: INVALID_ID,
                geom_id: INVALID_ID,
                inst_id: [INVALID_ID],
            },
        };
        // SAFETY: a valid committed scene, an initialised context and an aligned ray/hit.
        unsafe { rtcIntersect1(self.scene, &mut Context::new(), &mut rh) };
        (rh.hit.geom_id != INVALID_ID).then_some(rh.hit.prim_id)
    }

    /// Closest hits of segments: how many hit.
    pub fn closest(&self, rays: &[(Ray, f32)]) -> usize {
        rays.iter().filter(|(r, t)| self.hit(r, *t).is_some()).count()
    }

    /// Any hit on segments (`rtcOccluded1`): how many are blocked.
    pub fn occluded(&self, rays: &[(Ray, f32)]) -> usize {
        let mut context = Context::new();
        let mut hits = 0;
        for (ray, t_max) in rays {
            let mut r = ray1(ray, *t_max);
            // SAFETY: as in `hit`.
            unsafe { rtcOccluded1(self.scene, &mut context, &mut r) };
            hits += (r.tfar == f32::NEG_INFINITY) as usize;
        }
        hits
    }

    /// Closest hits, eight consecutive rays a packet (`rtcIntersect8`).
    pub fn closest8(&self, rays: &[(Ray, f32)]) -> usize {
        let mut context = Context::new();
        let mut hits = 0;
        for chunk in rays.chunks(8) {
            let mut rh = RayHit8::default();
            let mut valid = Valid::default();
            for (k, (ray, t_max)) in chunk.iter().enumerate() {
                valid.0[k] = lane(&mut rh.ray, k, ray, *t_max);
            }
            rh.hit.geom_id = [INVALID_ID; 8];
            // SAFETY: as in `hit`, with a 32-byte aligned packet and its valid mask.
            unsafe { rtcIntersect8(&valid, self.scene, &mut context, &mut rh) };
            hits += rh.hit.geom_id[..chunk.len()]
                .iter()
                .filter(|&&g| g != INVALID_ID)
                .count();
        }
        hits
    }

    /// Any hit, eight consecutive rays a packet (`rtcOccluded8`).
    pub fn occluded8(&self, rays: &[(Ray, f32)]) -> usize {
        let mut context = Context::new();
        let mut hits = 0;
        for chunk in rays.chunks(8) {
            let mut r = Ray8::default();
            let mut valid = Valid::default();
            for (k, (ray, t_max)) in chunk.iter().enumerate() {
                valid.0[k] = lane(&mut r, k, ray, *t_max);
            }
            // SAFETY: as in `closest8`.
            unsafe { rtcOccluded8(&valid, self.scene, &mut context, &mut r) };
            hits += r.tfar[..chunk.len()]
                .iter()
                .filter(|&&t| t == f32::NEG_INFINITY)
                .count();
        }
        hits
    }
}

impl FirstHit for EmbreeScene {
    fn triangle(&self, (ray, t_max): &Segment) -> Option<u32> {
        self.hit(ray, *t_max)
    }
}

/// Embree's single rays (`embree`) or its 8-wide packets (`embree-8`) on one scene.
pub struct Embree<'a> {
    scene: &'a EmbreeScene,
    eight: bool,
}

impl<'a> Embree<'a> {
    /// Both kernels on `scene`.
    pub fn both(scene: &'a EmbreeScene) -> [Embree<'a>; 2] {
        [false, true].map(|eight| Embree { scene, eight })
    }
}

impl Contestant for Embree<'_> {
    fn id(&self) -> &str {
        if self.eight { "embree-8" } else { "embree" }
    }

    fn side(&self) -> Side {
        Side::Peer
    }

    fn packets(&self) -> bool {
        self.eight
    }

    fn closest(&self, rays: &[Segment]) -> usize {
        match self.eight {
            true => self.scene.closest8(rays),
            false => self.scene.closest(rays),
        }
    }

    fn occluded(&self, rays: &[Segment]) -> usize {
        match self.eight {
            true => self.scene.occluded8(rays),
            false => self.scene.occluded(rays),
        }
    }

    /// Embree's triangle test is watertight, ours is not: they may part at edges.
    fn first_hit(&self) -> Option<&dyn FirstHit> {
        Some(self.scene)
    }
}
