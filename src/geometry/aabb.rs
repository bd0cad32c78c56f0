//! Axis-aligned bounding boxes.

use glam::Vec3;

/// An axis-aligned box; the empty box has `min > max` (+inf / -inf) so that growing it by anything works.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box (the identity of `union`).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// The box spanning two corners.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Aabb { min, max }
    }

    /// True if nothing was added.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Grows the box to contain `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both.
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// Edge lengths (zero or negative for an empty box).
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// The centre.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Surface area (0 for an empty box), the measure the SAH weighs children by.
    pub fn area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// The hierarchies' slab test (Kay & Kajiya 1986): where a ray with origin `origin` and safe inverse
    /// direction `inv` ([`super::ray::safe_inverse`]) enters the box within `[t_min, t_max]`, if it
    /// does. The exit is widened by [`super::ray::SLAB_ROBUST`], so a ray through any point of the box,
    /// its faces, edges and corners included, is never rejected by rounding.
    #[inline(always)]
    pub fn ray_entry(&self, origin: Vec3, inv: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        let t0 = (self.min - origin) * inv;
        let t1 = (self.max - origin) * inv;
        let near = t0.min(t1).max_element().max(t_min);
        let far = (t0.max(t1).min_element() * super::ray::SLAB_ROBUST).min(t_max);
        (near <= far).then_some(near)
    }

    /// True if `other` lies inside this box (borders included).
    pub fn contains(&self, other: &Aabb) -> bool {
        self.min.cmple(other.min).all() && self.max.cmpge(other.max).all()
    }
}
