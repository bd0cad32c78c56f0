//! Brute force: every primitive for every ray. The reference every other accelerator is tested against.

use super::counters;
use super::policy::HitPolicy;
use super::prims::{Hit, Prims};
use super::structure::Structure;
use crate::geometry::ray::Ray;

/// Tests all primitives, in id order.
#[derive(Clone, Copy, Debug)]
pub struct Brute<'a> {
    prims: Prims<'a>,
}

impl<'a> Brute<'a> {
    /// Wraps the scene's primitives; nothing to build.
    pub fn new(prims: Prims<'a>) -> Self {
        Brute { prims }
    }

    /// The scene's primitives.
    pub fn prims(&self) -> Prims<'a> {
        self.prims
    }

    /// The one traversal: all ids, planes included; `hit.t` is the upper limit and shrinks on each hit.
    #[inline]
    pub fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        // One node of all the primitives.
        counters::node::<P>();
        self.prims
            .intersect_each::<P>(0..self.prims.total(), ray, t_min, hit)
    }
}

impl<'a> Structure<'a> for Brute<'a> {
    fn prims(&self) -> Prims<'a> {
        self.prims
    }

    fn describe(&self) -> String {
        "brute force: every primitive for every ray".to_string()
    }

    #[inline(always)]
    fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        Brute::traverse::<P>(self, ray, t_min, hit)
    }
}
