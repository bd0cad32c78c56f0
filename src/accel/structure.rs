//! What every acceleration structure answers, written once as a trait so that [`super::Accel`]
//! dispatches each verb in one place and a new structure is one implementation. The packet verbs
//! default to ray by ray; the wide BVHs (and Embree) override them with their kernels.

use super::packet::{HitPacket, RayPacket, ray_by_ray};
use super::policy::HitPolicy;
use super::prims::{Hit, Prims};
use super::wide::isa::Isa;
use crate::geometry::ray::Ray;

/// An acceleration structure over a scene's primitives. Each verb is generic over the hit policy
/// (closest or any hit); `t_min` is already at least 0 ([`crate::geometry::ray::ahead`]).
pub trait Structure<'a> {
    /// The scene's primitives the structure was built over.
    fn prims(&self) -> Prims<'a>;

    /// A one-line description of the built structure.
    fn describe(&self) -> String;

    /// True where a packet's rays are traced together.
    fn has_packet_kernel(&self) -> bool {
        false
    }

    /// The instruction set of the structure's SIMD kernels, where it has a choice of them.
    fn simd(&self) -> Option<Isa> {
        None
    }

    /// Whether its kernels count their steps under a counted policy ([`super::counters`]).
    fn counts_steps(&self) -> bool {
        true
    }

    /// Makes the kernels use `simd`; false, with nothing changed, when the CPU lacks it or the
    /// structure has no such choice.
    fn set_simd(&mut self, _simd: Isa) -> bool {
        false
    }

    /// The closest (or any) hit with `t` in `(t_min, hit.t)`: updates `hit`, true if there is one.
    fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool;

    /// [`Structure::traverse`] for the rays of `rays` in `active`, each against its own `hits[k]`;
    /// the mask of those that hit.
    #[inline]
    fn traverse_packet<P: HitPolicy>(
        &self,
        rays: &RayPacket,
        active: u8,
        t_min: f32,
        hits: &mut HitPacket,
    ) -> u8 {
        ray_by_ray::<P>(active, |k| self.traverse::<P>(&rays[k], t_min, &mut hits[k]))
    }
}
