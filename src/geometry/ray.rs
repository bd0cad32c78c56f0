//! Rays.

use glam::Vec3;

/// The half-line `origin + t * dir`.
///
/// The parametric form of E. Haines, "Essential Ray Tracing Algorithms", ch. 2 of A. Glassner (ed.), *An
/// Introduction to Ray Tracing*, 1989. `dir` need not be unit length and `t` is measured in units of `dir`: keeping the unnormalised direction lets a ray be carried into an instance's local
/// frame by a linear map without renormalising, and the hit distances found there stay valid in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction (any non-zero length).
    pub dir: Vec3,
}

impl Ray {
    /// The ray from `origin` along `dir`.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray { origin, dir }
    }

    /// The point at parameter `t`, `R(t) = R0 + t Rd` (Haines 1989).
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        // Plain multiply-add rather than `mul_add`: without an FMA target feature the fused form is a libm call.
        self.origin + self.dir * t
    }
}

/// The start of a search along a ray as the accelerators take it: never behind the origin. A negative
/// (or NaN) `t_min` is +0, not −0: the wide BVHs compare distances as the integers of their bits, where
/// the search's start must be at least +0 (`accel::wide`'s slab test).
#[inline]
pub fn ahead(t_min: f32) -> f32 {
    if t_min > 0.0 { t_min } else { 0.0 }
}

/// `1 / dir` with zero (and tiny) components replaced by ±1e-18 first, as Embree does: every slab
/// product `(bound − origin) · inv` is then finite (an origin exactly on a slab plane gives 0, never the
/// NaN of 0 · ∞), so hierarchy tests need no NaN handling in their inner loop. The price: a ray with a
/// zero direction component whose origin lies exactly on one of a box's planes on that axis (a ray
/// running along the box's face) is cut off at t = 0 by that plane. Such rays graze the box; the
/// triangles lying in that face are never hit by them either (the determinant is zero).
#[inline]
pub fn safe_inverse(dir: Vec3) -> Vec3 {
    const TINY: f32 = 1e-18;
    let fix = |d: f32| if d.abs() < TINY { TINY.copysign(d) } else { d };
    Vec3::new(fix(dir.x), fix(dir.y), fix(dir.z)).recip()
}

/// Factor applied to a box's exit distance so that a slab test never rejects a primitive that touches
/// the box's boundary: 1 + 2γ₃ (Ize 2013, "Robust BVH Ray Traversal"), the rounding error bound of the
/// subtract-and-multiply that computed it (the wide BVHs' fused form rounds less). Without it a hit on a
/// flat node's edge can fall one ulp outside.
pub const SLAB_ROBUST: f32 = 1.000_000_4;

/// Factor on the closest hit's `t` below which a node is still visited. Boxes bound the exact
/// primitives, but the primitive tests report `t` with their own rounding error, which at grazing angles
/// near a shared vertex reaches ~1e-5 relative (measured on the SPD gears): a neighbour's hit at the same
/// vertex can come out slightly before its box's entry. Culling only beyond this margin keeps every
/// hierarchy's answer identical to brute force in such ties, at no measurable cost.
pub const CULL_MARGIN: f32 = 1.0 + 1.0 / 4096.0;

/// The test kit's generator under the path `accel/wide/packet.rs`'s tests import it from.
#[cfg(test)]
pub(crate) mod testing {
    pub(crate) use crate::kit::rays::TestRng;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_scales_by_unnormalised_dir() {
        let r = Ray::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(r.at(0.0), r.origin);
        assert_eq!(r.at(1.5), Vec3::new(1.0, 2.0, 6.0));
        assert_eq!(r.at(-1.0), Vec3::new(1.0, 2.0, 1.0));
    }
}
