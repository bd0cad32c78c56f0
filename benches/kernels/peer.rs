//! obvhs' two layouts traced on our rays. Its traversals take the leaf test as a closure: we give them
//! our own triangle test (Möller–Trumbore on `(v0, e1, e2)`, `geometry::triangle::intersect`), with the
//! triangles stored in its leaf order as its own examples do, so that the rows differ only in the
//! hierarchy and its traversal.

use glam::Vec3;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as ORay, RayHit};
use obvhs::triangle::Triangle;
use whitted::geometry::ray::Ray;
use whitted::geometry::triangle;

use crate::contestant::{Contestant, Segment, Side};

/// What the two layouts share: the primitive order of their leaves and their closest-hit and miss
/// traversals (same signatures, separate types).
pub trait Layout: Sync {
    fn indices(&self) -> &[u32];
    fn closest<F: FnMut(&ORay, usize) -> f32>(&self, ray: ORay, hit: &mut RayHit, f: F) -> bool;
    fn missed<F: FnMut(&ORay, usize) -> f32>(&self, ray: ORay, f: F) -> bool;
}

macro_rules! layout {
    ($t:ty) => {
        impl Layout for $t {
            fn indices(&self) -> &[u32] {
                &self.primitive_indices
            }
            #[inline(always)]
            fn closest<F: FnMut(&ORay, usize) -> f32>(&self, ray: ORay, hit: &mut RayHit, f: F) -> bool {
                self.ray_traverse(ray, hit, f)
            }
            #[inline(always)]
            fn missed<F: FnMut(&ORay, usize) -> f32>(&self, ray: ORay, f: F) -> bool {
                self.ray_traverse_miss(ray, f)
            }
        }
    };
}
layout!(CwBvh);
layout!(Bvh2);

/// An obvhs hierarchy and its triangles in leaf order, as `(v0, e1, e2)`, under its bench id.
pub struct Traced<B> {
    id: &'static str,
    bvh: B,
    tris: Vec<[Vec3; 3]>,
}

impl<B: Layout> Traced<B> {
    pub fn new(id: &'static str, bvh: B, tris: &[Triangle]) -> Self {
        let tris = bvh
            .indices()
            .iter()
            .map(|&i| {
                let t = &tris[i as usize];
                [t.v0.into(), (t.v1 - t.v0).into(), (t.v2 - t.v0).into()]
            })
            .collect();
        Traced { id, bvh, tris }
    }

    /// Our triangle test of leaf slot `id` within `(0, t_max)`; ∞ for a miss.
    #[inline(always)]
    fn test(&self, ray: &Ray, id: usize, t_max: f32) -> f32 {
        let [v0, e1, e2] = self.tris[id];
        triangle::intersect(v0, e1, e2, ray, 0.0, t_max).map_or(f32::INFINITY, |h| h.0)
    }

    fn to_obvhs(ray: &Ray, t_max: f32) -> ORay {
        ORay::new(ray.origin.into(), ray.dir.into(), 0.0, t_max)
    }
}

impl<B: Layout> Contestant for Traced<B> {
    fn id(&self) -> &str {
        self.id
    }

    fn side(&self) -> Side {
        Side::Peer
    }

    fn packets(&self) -> bool {
        false
    }

    /// `ray_traverse`, closest hit.
    fn closest(&self, rays: &[Segment]) -> usize {
        rays.iter()
            .filter(|(ray, t_max)| {
                let mut hit = RayHit::none();
                let o = Self::to_obvhs(ray, *t_max);
                self.bvh.closest(o, &mut hit, |o, id| self.test(ray, id, o.tmax))
            })
            .count()
    }

    /// `ray_traverse_miss`, which stops at the first hit.
    fn occluded(&self, rays: &[Segment]) -> usize {
        rays.iter()
            .filter(|(ray, t_max)| {
                let o = Self::to_obvhs(ray, *t_max);
                !self.bvh.missed(o, |o, id| self.test(ray, id, o.tmax))
            })
            .count()
    }
}
