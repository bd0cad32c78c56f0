//! The slab test (Kay and Kajiya 1986), written once over [`Lanes`]: a single ray against a node's `W`
//! children, or a packet's rays against one or two children. Its distances' maximum, minimum and
//! compare work on the integers of their bits, exact on any instruction set; the distances themselves
//! are one fused multiply-subtract where the lanes have FMA, a subtract and a multiply where not, both
//! rounded so that no box holding a hit is missed. So every path enters every box that holds a hit and
//! the images do not depend on the CPU (the tests compare them byte for byte across the paths).

use glam::Vec3;

use super::lanes::{Lanes, Lanes8, Twice};
use crate::geometry::ray::{Ray, SLAB_ROBUST, safe_inverse};

/// Relative outward move of a per-ray `origin · inv` for the fused slab test: 2⁻²², four times the
/// largest relative error of a product rounded to nearest (2⁻²⁴), so that after the nudge's own rounding
/// it still lies beyond the exact product.
const NUDGE: f32 = 1.0 / (1 << 22) as f32;

/// Rays prepared for slab tests (Kay and Kajiya 1986): per axis their origins and (Embree's
/// [`safe_inverse`]) inverse directions in lanes, splatted for one ray or side by side for a packet, the
/// inverse directions again scaled by [`SLAB_ROBUST`] for the exit planes, what each distance
/// subtracts ([`shifts`]: the origin, or for [`slab`]'s fused form the origin times each inverse), and
/// per axis whether the max
/// plane is the near one (Embree's near/far plane selection, once per ray or packet rather than a min/max
/// per box). When a packet's rays disagree in a sign (`mixed`), each lane picks its own planes by its
/// own sign (`negative`: all ones in the lanes whose inverse direction is negative), so that every lane
/// computes what the single-ray test computes for its ray.
pub(super) struct SlabRays<V> {
    inv: [V; 3],
    inv_far: [V; 3],
    shift: [V; 3],
    shift_far: [V; 3],
    negative: [V; 3],
    flip: [bool; 3],
    mixed: bool,
}

impl<V> SlabRays<V> {
    /// One ray in every lane.
    #[inline(always)]
    pub fn splat<const N: usize>(ray: &Ray) -> Self
    where
        V: Lanes<N>,
    {
        Self::one(&SlabRay::new::<N, V>(ray))
    }

    /// One ray prepared beforehand ([`SlabRay`]) in every lane.
    #[inline(always)]
    pub fn one<const N: usize>(r: &SlabRay) -> Self
    where
        V: Lanes<N>,
    {
        let lanes = |v: Vec3| [V::splat(v.x), V::splat(v.y), V::splat(v.z)];
        SlabRays {
            inv: lanes(r.inv),
            inv_far: lanes(r.inv_far),
            shift: lanes(r.shift),
            shift_far: lanes(r.shift_far),
            negative: [V::splat(0.0); 3],
            flip: [r.inv.x < 0.0, r.inv.y < 0.0, r.inv.z < 0.0],
            mixed: false,
        }
    }

    /// Eight rays, one per lane; the signs of the rays in `live` choose the planes.
    #[inline(always)]
    pub fn packet(rays: &[Ray; 8], live: u32) -> Self
    where
        V: Lanes<8>,
    {
        // Plain loops and explicit arrays: `map` and `from_fn` closures over arrays were left out of
        // line here, outside the AVX2 compile (callgrind).
        let (mut shift, mut shift_far) = ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3]);
        let (mut inv, mut inv_far, mut sign_mask, mut negative) =
            ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3], [[0.0f32; 8]; 3], [0u32; 3]);
        for (k, r) in rays.iter().enumerate() {
            let i = safe_inverse(r.dir);
            for a in 0..3 {
                inv[a][k] = i[a];
                inv_far[a][k] = i[a] * SLAB_ROBUST;
                (shift[a][k], shift_far[a][k]) = shifts::<8, V>(r.origin[a], i[a], inv_far[a][k]);
                sign_mask[a][k] = f32::from_bits(if i[a] < 0.0 { u32::MAX } else { 0 });
                negative[a] |= u32::from(i[a] < 0.0) << k;
            }
        }
        let negative = [negative[0] & live, negative[1] & live, negative[2] & live];
        SlabRays {
            inv: [V::load(&inv[0]), V::load(&inv[1]), V::load(&inv[2])],
            inv_far: [V::load(&inv_far[0]), V::load(&inv_far[1]), V::load(&inv_far[2])],
            shift: [V::load(&shift[0]), V::load(&shift[1]), V::load(&shift[2])],
            shift_far: [
                V::load(&shift_far[0]),
                V::load(&shift_far[1]),
                V::load(&shift_far[2]),
            ],
            negative: [
                V::load(&sign_mask[0]),
                V::load(&sign_mask[1]),
                V::load(&sign_mask[2]),
            ],
            flip: [negative[0] != 0, negative[1] != 0, negative[2] != 0],
            mixed: negative.iter().any(|&m| m != 0 && m != live),
        }
    }
}

/// One ray's slab-test values as plain numbers ([`SlabRays`] before they are splatted): 48 bytes a ray,
/// where the splatted lanes take 480, for the stream kernel to keep one per ray of its stream and splat
/// at each node test (the division of the inverse is then once per ray, not once per node).
#[derive(Clone, Copy, Debug)]
pub(super) struct SlabRay {
    inv: Vec3,
    inv_far: Vec3,
    shift: Vec3,
    shift_far: Vec3,
}

impl SlabRay {
    /// `ray` prepared for the slab tests of lanes `V`.
    #[inline(always)]
    pub fn new<const N: usize, V: Lanes<N>>(ray: &Ray) -> Self {
        let inv = safe_inverse(ray.dir);
        let inv_far = inv * SLAB_ROBUST;
        let (mut shift, mut shift_far) = (Vec3::ZERO, Vec3::ZERO);
        for a in 0..3 {
            (shift[a], shift_far[a]) = shifts::<N, V>(ray.origin[a], inv[a], inv_far[a]);
        }
        SlabRay {
            inv,
            inv_far,
            shift,
            shift_far,
        }
    }
}

impl<L: Lanes8> SlabRays<L> {
    /// The same rays twice, in lanes 0-7 and 8-15: for testing two boxes against them at once.
    #[inline(always)]
    pub fn doubled(&self) -> SlabRays<Twice<L>> {
        SlabRays {
            inv: two(&self.inv),
            inv_far: two(&self.inv_far),
            shift: two(&self.shift),
            shift_far: two(&self.shift_far),
            negative: two(&self.negative),
            flip: self.flip,
            mixed: self.mixed,
        }
    }
}

/// Each of three lanes twice.
#[inline(always)]
fn two<L: Lanes8>(v: &[L; 3]) -> [Twice<L>; 3] {
    [Twice(v[0], v[0]), Twice(v[1], v[1]), Twice(v[2], v[2])]
}

/// What one ray's entry and exit distances subtract on one axis, given its origin, inverse direction
/// and exit inverse on that axis: the origin itself where `V` subtracts before multiplying; where it
/// fuses, `origin · inv` rounded up and `origin · inv_far` rounded down by [`NUDGE`] ([`slab`]).
#[inline(always)]
fn shifts<const N: usize, V: Lanes<N>>(origin: f32, inv: f32, inv_far: f32) -> (f32, f32) {
    if V::FUSED {
        let (near, far) = (origin * inv, origin * inv_far);
        (near + near.abs() * NUDGE, far - far.abs() * NUDGE)
    } else {
        (origin, origin)
    }
}

/// The slab test: each lane's entry distance into its box and the mask of lanes whose ray enters it
/// within `[t_min, t_max]`, for `t_min >= +0`. `plane(axis, max)` gives the boxes' min or max planes on
/// `axis` in lanes (a node's children side by side, or one child splatted).
///
/// The exit planes' distances are taken with the inverse direction scaled by [`SLAB_ROBUST`] (Ize 2013,
/// "Robust BVH Ray Traversal", rounds the reciprocal up in the same way), so that rounding never rejects
/// a primitive touching the box; the scale is then off the path from a node's load to its mask. The
/// distances are compared as the integers of their bits (Embree's `maxi`/`mini`): with the `t_min` lane
/// at least +0, the entry is the float maximum and a negative exit (the box behind the ray) stays below
/// it, while each step is a one-cycle integer instruction where `maxps` and `cmpps` take four (a single
/// ray's traversal is a chain of such steps, node to child). The one difference from float compares is
/// −0, which counts as negative: a box left exactly at the origin is not entered; it holds no point at
/// `t > t_min`. An empty slot's inverted box gives an entry of +∞ above any exit.
///
/// Where the lanes have FMA ([`Lanes::FUSED`]) a distance is one fused `plane · inv − origin · inv`
/// (Embree's `msub` with its `org_rdir`) instead of a subtract and a multiply: one step fewer on the
/// chain from a node's load to its mask. `origin · inv` is rounded once per ray, so it is moved outward
/// by [`NUDGE`] of itself (more than its rounding error), up for the entries and down for the exits
/// (the box grows by about 2⁻²¹ of the origin's coordinates): what is left is each distance's own final
/// rounding, relative to the distance, which the exits' [`SLAB_ROBUST`] covers as it covers the
/// unfused form's. Lanes without FMA would round `plane · inv` too, an error relative to the plane,
/// not to the distance, so they subtract first. The two forms can differ in the last bits of an entry
/// distance, and so in the order of two children entered at the same distance; not in whether a box
/// that holds a hit is entered.
#[inline(always)]
pub(super) fn slab<const N: usize, V: Lanes<N>>(
    rays: &SlabRays<V>,
    plane: impl Fn(usize, bool) -> V,
    t_min: V,
    t_max: V,
) -> (V, u32) {
    let (mut near, mut far) = ([t_min; 3], [t_max; 3]);
    for axis in 0..3 {
        let flip = rays.flip[axis];
        let (entry, exit) = if rays.mixed {
            let (lo, hi, neg) = (plane(axis, false), plane(axis, true), rays.negative[axis]);
            (neg.select(hi, lo), neg.select(lo, hi))
        } else {
            (plane(axis, flip), plane(axis, !flip))
        };
        if V::FUSED {
            near[axis] = entry.mul_sub(rays.inv[axis], rays.shift[axis]);
            far[axis] = exit.mul_sub(rays.inv_far[axis], rays.shift_far[axis]);
        } else {
            near[axis] = entry.sub(rays.shift[axis]).mul(rays.inv[axis]);
            far[axis] = exit.sub(rays.shift[axis]).mul(rays.inv_far[axis]);
        }
    }
    // Two levels of pairs rather than a chain of four: the chain's latency is the traversal's.
    let near = near[0].max_bits(near[1]).max_bits(near[2].max_bits(t_min));
    let far = far[0].min_bits(far[1]).min_bits(far[2].min_bits(t_max));
    (near, near.le_bits(far))
}
