//! What a hit does during traversal: closest-hit shrinks the search interval and goes on, any-hit stops.
//! Every traversal is written once, generic over this policy, and the compiler specialises each; the
//! counted policies ([`Counted`]) add the traversal's steps to [`super::counters`], and the others
//! compile the counting away.

use std::marker::PhantomData;

/// A traversal's reaction to a hit, and whether it counts its steps.
pub trait HitPolicy {
    /// True: return at the first hit (shadow rays). False: keep the closest.
    const ANY: bool;
    /// True: count nodes visited and primitives tested ([`super::counters`]).
    const COUNT: bool = false;
    /// True: closest hit for rays that take the same way as the rays traced just before them (camera
    /// rays of neighbouring pixels), so that the kernels may take steps that pay only then. The same
    /// answers.
    const COHERENT: bool = false;
}

/// Closest hit (camera, reflection and refraction rays).
pub struct Closest;

impl HitPolicy for Closest {
    const ANY: bool = false;
}

/// Closest hit for coherent rays: camera rays, traced pixel after pixel.
pub struct Coherent;

impl HitPolicy for Coherent {
    const ANY: bool = false;
    const COHERENT: bool = true;
}

/// Any hit (shadow rays): the first hit in the interval ends the search.
pub struct AnyHit;

impl HitPolicy for AnyHit {
    const ANY: bool = true;
}

/// `P`, counting its steps.
pub struct Counted<P>(PhantomData<P>);

impl<P: HitPolicy> HitPolicy for Counted<P> {
    const ANY: bool = P::ANY;
    const COUNT: bool = true;
    const COHERENT: bool = P::COHERENT;
}
