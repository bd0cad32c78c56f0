//! The steps a traversal takes, counted per ray when its hit policy is [`Counted`]: inner nodes
//! visited (one box test of all the node's children: one SIMD slab test in the wide BVHs, two box
//! tests in the BVH2; a grid cell walked; brute force's one pass over everything) and primitives
//! tested. The counts live in this thread's lanes, one per ray of the verb's call (the ray of a
//! single-ray verb is lane 0, a packet's ray `k` lane `k`); a packet visiting a node counts it once for
//! each of its rays that take part. Every function is a
//! no-op, compiled away, for the other policies.
//!
//! [`Counted`]: super::policy::Counted

use std::cell::{Cell, RefCell};
use std::ops::AddAssign;

use super::policy::HitPolicy;

/// What one ray (or a sum of rays) cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Steps {
    /// Inner nodes visited.
    pub nodes: u64,
    /// Primitives tested.
    pub prims: u64,
}

impl AddAssign for Steps {
    fn add_assign(&mut self, o: Steps) {
        self.nodes += o.nodes;
        self.prims += o.prims;
    }
}

thread_local! {
    static LANES: RefCell<Vec<Steps>> = const { RefCell::new(Vec::new()) };
    static CURRENT: Cell<usize> = const { Cell::new(0) };
}

/// Zeroes lanes `0..n` and makes lane 0 current (before a counted verb).
pub fn reset(n: usize) {
    LANES.with_borrow_mut(|lanes| {
        lanes.clear();
        lanes.resize(n, Steps::default());
    });
    CURRENT.set(0);
}

/// The steps counted in `lane` since [`reset`].
pub fn lane(lane: usize) -> Steps {
    LANES.with_borrow(|lanes| lanes.get(lane).copied().unwrap_or_default())
}

/// Makes `lane` the one [`node`] and [`prims`] count into.
#[inline(always)]
pub fn at<P: HitPolicy>(lane: usize) {
    if P::COUNT {
        CURRENT.set(lane);
    }
}

/// One inner node visited by the current lane's ray.
#[inline(always)]
pub fn node<P: HitPolicy>() {
    if P::COUNT {
        add(CURRENT.get(), 1, 0);
    }
}

/// One inner node visited by each ray of `mask` (bit `k`: lane `k`).
#[inline(always)]
pub fn nodes<P: HitPolicy>(mut mask: u32) {
    if P::COUNT {
        while mask != 0 {
            add(mask.trailing_zeros() as usize, 1, 0);
            mask &= mask - 1;
        }
    }
}

/// `n` primitives tested by the current lane's ray.
#[inline(always)]
pub fn prims<P: HitPolicy>(n: usize) {
    if P::COUNT {
        add(CURRENT.get(), 0, n as u64);
    }
}

fn add(lane: usize, nodes: u64, prims: u64) {
    LANES.with_borrow_mut(|lanes| {
        if lanes.len() <= lane {
            lanes.resize(lane + 1, Steps::default());
        }
        lanes[lane] += Steps { nodes, prims };
    });
}
