//! The single-ray BVH4 kernel, written once for closest and any hit.
//!
//! Per node: one 4-lane slab test of the four children. The near and far planes of each axis are chosen
//! once per ray by the sign of its direction (not a min/max per node), which keeps the empty slots'
//! inverted boxes empty. Closest-hit visits the hit children nearest first and skips stack entries whose entry
//! distance lies beyond the closest hit so far; any-hit visits them in any order and returns at the first
//! hit.

use wide::f32x4;

use super::{Bvh4, ChildRef, EMPTY, LEAF, STACK, TRIANGLES, leaf_parts};
use crate::accel::policy::HitPolicy;
use crate::accel::prims::Hit;
use crate::accel::stack::Stack;
use crate::geometry::ray::{CULL_MARGIN, Ray, SLAB_ROBUST, safe_inverse};

/// A ray prepared for 4-wide slab tests: origin and inverse direction splatted, and per axis whether
/// the direction is negative, which makes the max plane the near one (Embree's near/far plane offsets):
/// the planes are picked once per ray, not blended per node.
struct Prepared {
    origin: [f32x4; 3],
    inv: [f32x4; 3],
    flip: [bool; 3],
}

impl Prepared {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let inv = safe_inverse(ray.dir);
        Prepared {
            origin: [
                f32x4::splat(ray.origin.x),
                f32x4::splat(ray.origin.y),
                f32x4::splat(ray.origin.z),
            ],
            inv: [f32x4::splat(inv.x), f32x4::splat(inv.y), f32x4::splat(inv.z)],
            flip: [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0],
        }
    }
}

impl Bvh4<'_> {
    /// The four children's entry distances and the mask of those the ray enters within `[t_min, t_max]`.
    /// An empty slot's inverted box gives near = +∞ > far = −∞ whichever plane is near.
    #[inline(always)]
    fn slab4(&self, node: u32, r: &Prepared, t_min: f32, t_max: f32) -> (f32x4, u32) {
        let n = &self.nodes[node as usize];
        let mut near = f32x4::splat(t_min);
        let mut far = f32x4::splat(f32::INFINITY);
        for axis in 0..3 {
            let (a, b) = (&n.min[axis], &n.max[axis]);
            let (a, b) = if r.flip[axis] { (b, a) } else { (a, b) };
            near = near.fast_max((f32x4::new(*a) - r.origin[axis]) * r.inv[axis]);
            far = far.fast_min((f32x4::new(*b) - r.origin[axis]) * r.inv[axis]);
        }
        let far = (far * f32x4::splat(SLAB_ROBUST)).fast_min(f32x4::splat(t_max));
        (near, near.simd_le(far).to_bitmask())
    }

    /// Tests the primitives of a leaf; true if the search is over (any-hit found one). Triangles go four
    /// at a time through their SIMD blocks, other kinds one by one.
    #[inline(always)]
    fn leaf<P: HitPolicy>(
        &self,
        r: ChildRef,
        ray: &Ray,
        t_min: f32,
        hit: &mut Hit,
        found: &mut bool,
    ) -> bool {
        let (start, count) = leaf_parts(r);
        if r & TRIANGLES != 0 {
            for block in &self.tris[start..start + count.div_ceil(4)] {
                if let Some((k, t, u, v)) = block.intersect(ray.origin, ray.dir, t_min, hit.t) {
                    *hit = Hit {
                        t,
                        prim: block.id[k],
                        u,
                        v,
                    };
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

    /// The one single-ray traversal for both policies.
    #[inline]
    pub fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        let mut found = self.prims.intersect_planes::<P>(ray, t_min, hit);
        if (P::ANY && found) || self.root == EMPTY {
            return found;
        }
        let r = Prepared::new(ray);
        let mut stack = Stack::<(ChildRef, f32), STACK>::new();
        let mut current = self.root;
        loop {
            if current & LEAF != 0 {
                if self.leaf::<P>(current, ray, t_min, hit, &mut found) {
                    return true;
                }
            } else {
                let (near, mut mask) = self.slab4(current, &r, t_min, hit.t * CULL_MARGIN);
                if mask != 0 {
                    let node = &self.nodes[current as usize];
                    let t = near.to_array();
                    if mask.count_ones() == 1 {
                        current = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    // Push the hit children, then order the pushed run far-to-near so the nearest is popped
                    // first (any-hit keeps the order it found).
                    let start = stack.len();
                    while mask != 0 {
                        let k = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        stack.push((node.child[k], t[k]));
                    }
                    if !P::ANY {
                        sort_far_to_near(stack.above_mut(start));
                    }
                }
            }
            // Pop the next subtree that may still hold a closer hit.
            loop {
                let Some((c, t_enter)) = stack.pop() else {
                    return found;
                };
                if P::ANY || t_enter <= hit.t * CULL_MARGIN {
                    current = c;
                    break;
                }
            }
        }
    }
}

/// Sorts 2 to 4 entries by decreasing entry distance (insertion sort: at most six compares).
#[inline(always)]
fn sort_far_to_near(run: &mut [(ChildRef, f32)]) {
    for i in 1..run.len() {
        let mut j = i;
        while j > 0 && run[j - 1].1 < run[j].1 {
            run.swap(j - 1, j);
            j -= 1;
        }
    }
}
