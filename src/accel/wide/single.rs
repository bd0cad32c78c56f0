//! The single-ray kernel of the wide BVHs, written once for closest and any hit, both widths and every
//! instruction set ([`super::lanes`]), and the leaf test that the packet kernel shares.
//!
//! Per node: one `W`-lane slab test of the children. The near and far planes of each axis are chosen
//! once per ray by the sign of its direction (not a min/max per node), which keeps the empty slots'
//! inverted boxes empty. Closest-hit visits the hit children nearest first and skips stack entries whose entry
//! distance lies beyond the closest hit so far; any-hit visits them in any order and returns at the first
//! hit.

use std::marker::PhantomData;

use wide::{f32x4, f32x8};

use super::lanes::{Lanes, Lanes8, OnLanes8};
use super::order::Visit;
use super::slab::{SlabRays, slab};
use super::tri4::Tri4;
use super::{Bvh4, Bvh8, ChildRef, EMPTY, LEAF, STACK, TRIANGLES, WideBvh, leaf_parts};
use crate::accel::counters;
use crate::accel::policy::HitPolicy;
use crate::accel::prims::Hit;
use crate::accel::stack::Stack;
use crate::geometry::ray::{CULL_MARGIN, Ray, ahead};

impl Bvh4<'_> {
    /// The closest (or, with [`crate::accel::policy::AnyHit`], any) hit with `t` in `(t_min, hit.t)`.
    /// Four lanes are one SSE register on every x86-64 CPU: no dispatch.
    #[inline]
    pub fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        self.single::<P, f32x4, f32x8>(ray, t_min, hit)
    }
}

impl Bvh8<'_> {
    /// The closest (or any) hit with `t` in `(t_min, hit.t)`, on the instruction set chosen at build
    /// time ([`WideBvh::simd`]).
    #[inline]
    pub fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        self.simd.run8(Single::<P> {
            bvh: self,
            ray,
            t_min,
            hit,
            policy: PhantomData,
        })
    }
}

/// The BVH8's single-ray kernel as a computation over eight lanes, for [`super::isa::Simd::run8`].
struct Single<'r, 'b, P> {
    bvh: &'r Bvh8<'b>,
    ray: &'r Ray,
    t_min: f32,
    hit: &'r mut Hit,
    policy: PhantomData<P>,
}

impl<P: HitPolicy> OnLanes8 for Single<'_, '_, P> {
    type Output = bool;

    #[inline(always)]
    fn run<L: Lanes8>(self) -> bool {
        self.bvh.single::<P, L, L>(self.ray, self.t_min, self.hit)
    }
}

impl<const W: usize> WideBvh<'_, W> {
    /// Tests the primitives of leaf `r` against one ray; sets `found` on a hit and returns true if the
    /// search is over (any-hit found one). Triangles go eight at a time where `T` is one register (two
    /// of their four-triangle SIMD blocks side by side, [`Tri4::intersect_pair`]), else (and a last odd
    /// block) four at a time, a hit kept only when strictly nearer: the block order's first among equal
    /// `t`. Other kinds go one by one. The packet kernel calls this for each of its rays, so both
    /// kernels find the same hits, ties included.
    #[inline(always)]
    pub(super) fn leaf<P: HitPolicy, T: Lanes8>(
        &self,
        r: ChildRef,
        ray: &Ray,
        t_min: f32,
        hit: &mut Hit,
        found: &mut bool,
    ) -> bool {
        let (start, count) = leaf_parts(r);
        if r & TRIANGLES != 0 {
            // The leaf's triangles are counted as tested together (an any-hit ray that stops early
            // is charged the whole leaf); other kinds count one by one.
            counters::prims::<P>(count);
            let blocks = &self.tris[start..start + count.div_ceil(4)];
            for group in blocks.chunks(if T::ONE_REGISTER { 2 } else { 1 }) {
                let lane = match group {
                    [lo, hi] => Tri4::intersect_pair::<T>(lo, hi, ray.origin, ray.dir, t_min, hit.t)
                        .map(|(k, t, u, v)| (group[k / 4].id[k % 4], t, u, v)),
                    _ => group[0]
                        .intersect(ray.origin, ray.dir, t_min, hit.t)
                        .map(|(k, t, u, v)| (group[0].id[k], t, u, v)),
                };
                if let Some((prim, t, u, v)) = lane {
                    *hit = Hit { t, prim, u, v };
                    *found = true;
                    if P::ANY {
                        return true;
                    }
                }
            }
            return false;
        }
        let hit_one =
            self.prims
                .intersect_each::<P>(self.ids[start..start + count].iter().copied(), ray, t_min, hit);
        *found |= hit_one;
        P::ANY && hit_one
    }

    /// The one single-ray traversal, for both policies, every width and every lane type.
    #[inline(always)]
    fn single<P: HitPolicy, L: Lanes<W>, T: Lanes8>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        let t_min = ahead(t_min);
        let mut found = self.prims.intersect_planes::<P>(ray, t_min, hit);
        if (P::ANY && found) || self.root == EMPTY {
            return found;
        }
        self.descend::<P, L, T>(self.root, ray, &SlabRays::splat(ray), t_min, hit, &mut found) || found
    }

    /// The single-ray traversal of the subtree under `start` (not [`EMPTY`]) for `ray`, prepared as
    /// `r`, with `t_min` already [`ahead`]: sets `found` on a hit and returns true if the search is over
    /// (any-hit found one). [`WideBvh::single`] starts it at the root.
    #[inline(always)]
    fn descend<P: HitPolicy, L: Lanes<W>, T: Lanes8>(
        &self,
        start: ChildRef,
        ray: &Ray,
        r: &SlabRays<L>,
        t_min: f32,
        hit: &mut Hit,
        found: &mut bool,
    ) -> bool {
        let mut stack = Stack::<Visit, STACK>::new();
        let mut current = start;
        loop {
            if current & LEAF != 0 {
                if self.leaf::<P, T>(current, ray, t_min, hit, found) {
                    return true;
                }
            } else {
                counters::node::<P>();
                let node = &self.nodes[current as usize];
                let plane =
                    |axis: usize, max: bool| L::load(if max { &node.max[axis] } else { &node.min[axis] });
                let (lanes, mut mask) = slab(r, plane, L::splat(t_min), L::splat(hit.t * CULL_MARGIN));
                let t = lanes.to_array();
                let entered = mask;
                // Child `k` kept for later, its lines already on their way (a macro, not a closure,
                // so that it compiles inside the kernel's instruction set).
                macro_rules! keep {
                    ($k:expr) => {{
                        self.prefetch(node.child[$k]);
                        stack.push(Visit {
                            child: node.child[$k],
                            t: t[$k],
                        });
                    }};
                }
                if mask != 0 {
                    if (P::ANY || P::COHERENT || W == 4) && mask.is_power_of_two() {
                        // One child: picked by branches on the mask, not by its bit's index, so
                        // that the CPU predicts the way and loads the child (and the next node)
                        // before the slab test is through (tinybvh's "branchy" step). It loses on
                        // the BVH8's incoherent bounces, and as a function (profiles/tried.md).
                        // `% W`: lanes the BVH4 never reaches, their indices kept in range.
                        let c = &node.child;
                        current = if mask & 0x0f != 0 {
                            if mask & 0x03 != 0 {
                                if mask & 1 != 0 { c[0] } else { c[1] }
                            } else if mask & 4 != 0 {
                                c[2]
                            } else {
                                c[3 % W]
                            }
                        } else if mask & 0x30 != 0 {
                            if mask & 0x10 != 0 { c[4 % W] } else { c[5 % W] }
                        } else if mask & 0x40 != 0 {
                            c[6 % W]
                        } else {
                            c[7 % W]
                        };
                        continue;
                    }
                    let first = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        current = node.child[first];
                        continue;
                    }
                    if P::ANY {
                        // Any order will do: descend into the first, keep the others for later.
                        while mask != 0 {
                            let k = mask.trailing_zeros() as usize;
                            mask &= mask - 1;
                            keep!(k);
                        }
                        current = node.child[first];
                        continue;
                    }
                    let second = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        // Two children, the commonest case: keep the farther, descend into the nearer
                        // (on a tie the second, as the sort below would), with no sort and no pop.
                        let (near, far) = if t[first] < t[second] {
                            (first, second)
                        } else {
                            (second, first)
                        };
                        keep!(far);
                        current = node.child[near];
                        continue;
                    }
                    // Three or more: all but the nearest go on the stack far to near, the nearest is
                    // next (its entry was just tested against the hit so far).
                    let mut rest = entered;
                    while rest != 0 {
                        self.prefetch(node.child[rest.trailing_zeros() as usize]);
                        rest &= rest - 1;
                    }
                    current = lanes.order_entered(entered, &node.child, &mut stack);
                    continue;
                }
            }
            // Pop the next subtree that may still hold a closer hit.
            loop {
                let Some(Visit { child, t }) = stack.pop() else {
                    return false;
                };
                if P::ANY || t <= hit.t * CULL_MARGIN {
                    current = child;
                    break;
                }
            }
        }
    }
}
