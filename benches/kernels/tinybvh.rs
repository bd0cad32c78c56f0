//! tinybvh (Jacco Bikker's C++ header library; 1.6.8 as bundled by the `tinybvh-rs` 0.1.0-beta.3 wrapper)
//! behind the `bench-tinybvh` feature, on our rays. Built as the wrapper documents: its binned SAH `BVH`
//! over the scene's triangles, leaves split to 4 triangles, converted to its 8-wide `MBVH` and then to
//! `BVH8_CPU` (after Fuetterling et al. 2017, "Accelerated Single Ray Tracing for Wide Vector Units": AVX2
//! nodes with per-octant child order, SSE leaves of 4 triangles, its own Möller–Trumbore test). The
//! wrapper exposes `BVH8_CPU`'s traversal only when compiled with AVX2 (`cfg(target_feature = "avx2")`,
//! i.e. `RUSTFLAGS="-C target-cpu=native"`; its C++ side is always built with `-march=native`); without
//! it the bench says so and tries the plain Wald-layout `BVH` (binary, scalar) instead, which fails the
//! hit-count check on the dragons ([`Tiny::usable`]) and is then left out. tinybvh-rs offers closest hit
//! only: the shadow rays are answered by a closest-hit query limited to the light distance.

use std::time::Instant;

use tinybvh_rs::{Intersection, Intersector, Ray as TRay, bvh};
use whitted::geometry::ray::Ray;
use whitted::scene::Scene;

use crate::Set;
use crate::contestant::{Contestant, FirstHit, Segment, Side};

/// The rows' bench id: tinybvh's BVH8_CPU, or its Wald BVH without AVX2.
pub const ID: &str = if cfg!(target_feature = "avx2") {
    "tinybvh-8"
} else {
    "tinybvh-bvh2"
};

#[cfg(target_feature = "avx2")]
type Layout = tinybvh_rs::bvh8_cpu::BVH;
/// The Wald BVH keeps a reference to the vertices it was built from (leaked: the bench's lifetime).
#[cfg(not(target_feature = "avx2"))]
type Layout = bvh::BVH<'static>;

/// A tinybvh hierarchy over a scene's triangles (`prim` of a hit = our triangle index).
pub struct Tiny {
    bvh: Layout,
}

/// tinybvh's C++ `Ray` is 128 bytes (`ALIGNED(64)`, the hit record followed by 64 bytes of user data in
/// 1.6.8), the wrapper's Rust mirror 64: the first 64 bytes coincide (origin, mask, direction, instance,
/// reciprocal direction, hit), and the traversals touch only those, but the C++ side gets its whole
/// struct anyway. (Hence also no `Ray::new`: it returns the 128-byte C++ struct into a 64-byte slot, and
/// it would renormalise the direction.)
#[repr(C, align(64))]
struct Slot {
    ray: TRay,
    _user: [u8; 64],
}

/// tinybvh's `tinybvh_safercp`: 1/x, or ±1e30 for |x| ≤ 1e-12.
fn safe_rcp(x: f32) -> f32 {
    if x.abs() > 1e-12 {
        1.0 / x
    } else if x >= 0.0 {
        tinybvh_rs::INFINITE
    } else {
        -tinybvh_rs::INFINITE
    }
}

impl Slot {
    fn new() -> Self {
        Slot {
            ray: TRay::default(),
            _user: [0; 64],
        }
    }

    /// The ray as it is (not renormalised), over `(0, t_max)` (∞ as tinybvh's 1e30); the same fields as
    /// tinybvh's `Ray` constructor sets. Returns that bound: a hit is a `hit.t` below it.
    #[inline(always)]
    fn set(&mut self, ray: &Ray, t_max: f32) -> f32 {
        let t_max = t_max.min(tinybvh_rs::INFINITE);
        let r = &mut self.ray;
        r.origin = ray.origin.to_array();
        r.padding_0 = 0xFFFF; // RAY_MASK_INTERSECT_ALL
        r.dir = ray.dir.to_array();
        r.padding_1 = 0; // instance index
        r.r_d = ray.dir.to_array().map(safe_rcp);
        r.hit = Intersection {
            t: t_max,
            ..Intersection::default()
        };
        t_max
    }
}

impl Tiny {
    /// Builds the hierarchy over `scene`'s triangles, given as tinybvh takes them: three `[x, y, z, w]`
    /// vertices each (`v0`, `v0 + e1`, `v0 + e2`, as the obvhs peer gets them).
    pub fn new(scene: &Scene) -> Self {
        let primitives: Vec<[f32; 4]> = (0..scene.triangles.len())
            .flat_map(|i| scene.triangles.vertices(i).map(|v| v.extend(0.0).to_array()))
            .collect();
        let start = Instant::now();
        #[cfg(target_feature = "avx2")]
        let bvh = {
            use tinybvh_rs::{bvh8_cpu, mbvh};
            let mut wald = bvh::BVH::new(primitives.as_slice().into()).expect("whole triangles");
            wald.split_leaves(4);
            let mbvh = mbvh::BVH::new(&wald);
            bvh8_cpu::BVH::new(&mbvh).expect("leaves of at most 4 triangles")
        };
        #[cfg(not(target_feature = "avx2"))]
        let bvh = {
            eprintln!(
                "tinybvh: its BVH8_CPU rows need AVX2 at compile time \
                 (RUSTFLAGS=\"-C target-cpu=native\"); trying its Wald-layout BVH as {ID} instead"
            );
            let primitives: &'static [[f32; 4]] = primitives.leak();
            bvh::BVH::new(primitives.into()).expect("whole triangles")
        };
        eprintln!("tinybvh: {ID} built in {:.2} s", start.elapsed().as_secs_f64());
        Tiny { bvh }
    }

    /// The triangle a segment hits first, if any.
    pub fn hit(&self, ray: &Ray, t_max: f32) -> Option<u32> {
        let mut slot = Slot::new();
        let t_max = slot.set(ray, t_max);
        self.bvh.intersect(&mut slot.ray);
        (slot.ray.hit.t < t_max).then_some(slot.ray.hit.prim)
    }

    /// The Wald BVH's scalar triangle test (without AVX2) rejects |det| < 1e-6 (`MOLLER_TRUMBORE_TEST`
    /// in `tiny_bvh.h`, with the direction's length in it): below that on 99% of the full dragon's
    /// triangles, it misses most real hits. Where its hit counts differ from ours on `sets` it is left
    /// out (`None`), with the reason. BVH8_CPU is checked with every other contestant.
    pub fn usable(self, sets: &[Set]) -> Option<Self> {
        if cfg!(target_feature = "avx2") {
            return Some(self);
        }
        for set in sets {
            let theirs = self.closest(&set.rays);
            eprintln!("{ID} {}: {theirs} hits, ours {}", set.name, set.hits);
            if theirs != set.hits {
                eprintln!(
                    "{ID}: not measured: its triangle test drops hits on triangles with |e1 x e2| < 1e-6 \
                     (build with RUSTFLAGS=\"-C target-cpu=native\" for the BVH8_CPU rows)"
                );
                return None;
            }
        }
        Some(self)
    }
}

// SAFETY: tinybvh's `Intersect` is a `const` member function of classes without `mutable` members
// (`tiny_bvh.h`, `BVH` and `BVH8_CPU`): traversals only read the hierarchy, so any number of threads may
// trace it at once, and nothing changes it after `new`.
unsafe impl Sync for Tiny {}

impl FirstHit for Tiny {
    fn triangle(&self, (ray, t_max): &Segment) -> Option<u32> {
        self.hit(ray, *t_max)
    }
}

impl Contestant for Tiny {
    fn id(&self) -> &str {
        ID
    }

    fn side(&self) -> Side {
        Side::Peer
    }

    fn packets(&self) -> bool {
        false
    }

    /// Closest hits of segments (`t_max` ∞ for unbounded rays): how many hit.
    fn closest(&self, rays: &[Segment]) -> usize {
        let mut slot = Slot::new();
        let mut hits = 0;
        for (ray, t_max) in rays {
            let t_max = slot.set(ray, *t_max);
            self.bvh.intersect(&mut slot.ray);
            hits += (slot.ray.hit.t < t_max) as usize;
        }
        hits
    }

    /// tinybvh-rs has no any-hit query: the closest hit within the segment.
    fn occluded(&self, rays: &[Segment]) -> usize {
        self.closest(rays)
    }

    /// Its own Möller–Trumbore test, which may round differently from ours at edges.
    fn first_hit(&self) -> Option<&dyn FirstHit> {
        Some(self)
    }
}
