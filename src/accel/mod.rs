//! Accelerators. Each answers the same two questions (as tinybvh does on every layout): the closest hit
//! along a ray (`intersect`) and whether anything lies on a segment (`occluded`); that shared interface is
//! what lets every structure be checked against brute force with one loop.

pub mod brute;
pub mod policy;
pub mod prims;

use std::str::FromStr;

pub use prims::{Hit, PrimKind, Prims, Surface};

use crate::geometry::ray::Ray;
use brute::Brute;
use policy::{AnyHit, Closest};

/// Which structure to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelKind {
    /// Test every primitive.
    None,
}

impl FromStr for AccelKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "none" | "brute" => Ok(AccelKind::None),
            _ => Err(format!("unknown accelerator \"{s}\": expected none")),
        }
    }
}

/// A built accelerator over a scene's primitives. One match per ray, not per primitive.
#[derive(Clone, Debug)]
pub enum Accel<'a> {
    /// Brute force.
    Brute(Brute<'a>),
}

impl<'a> Accel<'a> {
    /// Builds the chosen structure.
    pub fn build(prims: Prims<'a>, kind: AccelKind) -> Self {
        match kind {
            AccelKind::None => Accel::Brute(Brute::new(prims)),
        }
    }

    /// Finds the closest hit with `t` in `(t_min, hit.t)`; updates `hit` and returns true if there is one.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        match self {
            Accel::Brute(b) => b.traverse::<Closest>(ray, t_min, hit),
        }
    }

    /// True if anything is hit with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        let mut hit = Hit::miss(t_max);
        match self {
            Accel::Brute(b) => b.traverse::<AnyHit>(ray, t_min, &mut hit),
        }
    }
}
