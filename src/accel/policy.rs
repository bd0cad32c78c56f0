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
}

/// Closest hit (camera, reflection and refraction rays).
pub struct Closest;

impl HitPolicy for Closest {
    const ANY: bool = false;
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
}
