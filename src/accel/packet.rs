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

/// Rays with fewer live lanes than this go ray by ray: a packet's node tests cost about as much for
/// one ray as for eight.
const MIN_LANES: u32 = 2;

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

/// Whether `rays` (up to a packet's worth) are worth tracing as one packet: at least `MIN_LANES` of
/// them, their directions all in one octant. Rays that point apart (diffuse bounces, rays off a curved
/// mirror) share few nodes, and the single-ray kernel traces them faster one by one (`profiles/README.md`,
/// tuned constants): the renderer's rule for its secondary rays, and the kernels bench's `hybrid` rows.
pub fn coherent_rays<'r>(mut rays: impl Iterator<Item = &'r Ray>) -> bool {
    let octant = |r: &Ray| r.dir.cmplt(glam::Vec3::ZERO).bitmask();
    let Some(first) = rays.next().map(octant) else {
        return false;
    };
    let mut n = 1;
    for r in rays {
        if octant(r) != first {
            return false;
        }
        n += 1;
    }
    n >= MIN_LANES
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

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::coherent_rays;
    use crate::geometry::ray::Ray;

    fn rays(dirs: &[[f32; 3]]) -> Vec<Ray> {
        dirs.iter()
            .map(|&d| Ray::new(Vec3::ZERO, Vec3::from(d).normalize()))
            .collect()
    }

    #[test]
    fn a_packet_is_worth_its_rays_when_two_or_more_point_into_one_octant() {
        let same = rays(&[[1.0, 2.0, -3.0], [0.1, 0.1, -1.0], [5.0, 0.5, -0.2]]);
        assert!(coherent_rays(same.iter()));
        // One component's sign apart is another octant, however close the directions.
        let apart = rays(&[[1.0, 1.0, -1.0], [1.0, -0.001, -1.0]]);
        assert!(!coherent_rays(apart.iter()));
        // One ray, or none, goes alone.
        assert!(!coherent_rays(same[..1].iter()));
        assert!(!coherent_rays(same[..0].iter()));
    }
}
