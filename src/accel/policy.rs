//! What a hit does during traversal: closest-hit shrinks the search interval and goes on, any-hit stops.
//! Every traversal is written once, generic over this policy, and the compiler specialises each.

/// A traversal's reaction to a hit.
pub trait HitPolicy {
    /// True: return at the first hit (shadow rays). False: keep the closest.
    const ANY: bool;
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
