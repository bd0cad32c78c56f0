//! Ray packets: the eight-ray form of the accelerators' two verbs ([`super::Accel::intersect_packet`],
//! [`super::Accel::occluded_packet`]). A packet is eight rays side by side and a mask of those in use
//! (bit `k` for ray `k`); every accelerator answers it, the wide BVHs with their packet kernel and the
//! others ray by ray, with the answers each ray would get alone.

use super::counters;
use super::policy::HitPolicy;
use super::prims::Hit;
use crate::geometry::ray::Ray;

/// Rays per packet: the eight lanes of one AVX2 register (two SSE registers elsewhere).
pub const PACKET: usize = 8;

/// A packet's rays (ray `k` is lane `k`).
pub type RayPacket = [Ray; PACKET];

/// A packet's hits: each ray's search limit on the way in (`t`), its closest hit on the way out.
pub type HitPacket = [Hit; PACKET];

/// The rays of a packet's mask, by index, the first ray first.
#[inline(always)]
pub fn bits(mask: u8) -> impl Iterator<Item = usize> {
    let mut mask = mask as u32;
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            k
        })
    })
}

/// The mask of a packet's first `n` rays (`n` at most [`PACKET`]).
#[inline(always)]
pub fn first(n: usize) -> u8 {
    (1u16 << n).wrapping_sub(1) as u8
}

/// The mask of the rays in `active` for which `answer` is true: a packet answered ray by ray.
#[inline]
pub(super) fn ray_by_ray<P: HitPolicy>(active: u8, mut answer: impl FnMut(usize) -> bool) -> u8 {
    bits(active).fold(0, |m, k| {
        counters::at::<P>(k);
        if answer(k) { m | 1 << k } else { m }
    })
}
