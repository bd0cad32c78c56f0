//! The user geometry's callbacks: Embree calls them for the bounded primitives that are not triangles
//! (spheres, boxes, cones), and they answer with our own routines ([`Prims::bounds`],
//! [`Prims::intersect`]).

use glam::Vec3;

use super::ffi;
use crate::accel::prims::Prims;
use crate::geometry::ray::Ray;

/// The data the user geometry's callbacks read, at a fixed address (the geometry's user pointer).
pub(super) struct Others<'a> {
    pub(super) prims: Prims<'a>,
    /// Our id of each of the user geometry's primitives, by Embree's primitive id.
    pub(super) ids: Vec<u32>,
}

/// The user geometry's bounds callback: [`Prims::bounds`] of the primitive.
pub(super) unsafe extern "C" fn bounds(args: *const ffi::BoundsArguments) {
    // SAFETY: Embree passes valid arguments; the user pointer is the geometry's `Others`, and its
    // primitive ids are below the count it was given.
    unsafe {
        let a = &*args;
        let others = &*(a.geometry_user_ptr as *const Others);
        let b = others.prims.bounds(others.ids[a.prim_id as usize]);
        *a.bounds_o = ffi::Bounds {
            lower: b.min.to_array(),
            align0: 0.0,
            upper: b.max.to_array(),
            align1: 0.0,
        };
    }
}

/// Lane `i` of an `n`-lane `RTCRayN` at `base`: the ray and its `(tnear, tfar)`.
///
/// # Safety
///
/// `base` points to an `RTCRayN` (or `RTCRayHitN`) of `n` lanes and `i < n`.
#[inline(always)]
unsafe fn read_ray(base: *const f32, n: usize, i: usize) -> (Ray, f32, f32) {
    use ffi::ray_field::*;
    // SAFETY: per the contract.
    let f = |field: usize| unsafe { *base.add(ffi::ray_n(field, n, i)) };
    let origin = Vec3::new(f(ORG), f(ORG + 1), f(ORG + 2));
    let dir = Vec3::new(f(DIR), f(DIR + 1), f(DIR + 2));
    (Ray::new(origin, dir), f(TNEAR), f(TFAR))
}

/// Our test of the primitive on ray lane `i`, with Embree's interval `(tnear, tfar]`.
///
/// # Safety
///
/// As [`read_ray`].
#[inline(always)]
unsafe fn test_lane(
    others: &Others,
    id: u32,
    base: *const f32,
    n: usize,
    i: usize,
) -> Option<(f32, f32, f32)> {
    // SAFETY: per the contract.
    let (ray, tnear, tfar) = unsafe { read_ray(base, n, i) };
    if tfar.partial_cmp(&tnear).is_none_or(|o| o.is_lt()) {
        return None;
    }
    others.prims.intersect(id, &ray, tnear, tfar.next_up())
}

/// The user geometry's intersect callback: for each valid lane, our test of the primitive; a hit
/// within the lane's interval becomes its `tfar` and hit record.
pub(super) unsafe extern "C" fn intersect(args: *const ffi::IntersectArguments) {
    use ffi::hit_field::*;
    // SAFETY: Embree passes valid arguments: `valid` and `rayhit` of `n` lanes, the geometry's user
    // pointer (its `Others`), one of its primitive ids and the query's context.
    unsafe {
        let a = &*args;
        let others = &*(a.geometry_user_ptr as *const Others);
        let id = others.ids[a.prim_id as usize];
        let n = a.n as usize;
        let words = a.rayhit.cast::<f32>();
        let ints = a.rayhit.cast::<u32>();
        for i in 0..n {
            if *a.valid.add(i) == 0 {
                continue;
            }
            let Some((t, u, v)) = test_lane(others, id, words, n, i) else {
                continue;
            };
            *words.add(ffi::ray_n(ffi::ray_field::TFAR, n, i)) = t;
            for axis in 0..3 {
                *words.add(ffi::hit_n(NG + axis, n, i)) = 0.0;
            }
            *words.add(ffi::hit_n(U, n, i)) = u;
            *words.add(ffi::hit_n(V, n, i)) = v;
            *ints.add(ffi::hit_n(PRIM_ID, n, i)) = a.prim_id;
            *ints.add(ffi::hit_n(GEOM_ID, n, i)) = a.geom_id;
            *ints.add(ffi::hit_n(INST_ID, n, i)) = (*a.context).inst_id[0];
        }
    }
}

/// The user geometry's occluded callback: a valid lane whose interval holds a hit of the primitive
/// gets `tfar = -inf`, Embree's "occluded".
pub(super) unsafe extern "C" fn occluded(args: *const ffi::OccludedArguments) {
    // SAFETY: as in `intersect`, with `ray` an `RTCRayN` of `n` lanes.
    unsafe {
        let a = &*args;
        let others = &*(a.geometry_user_ptr as *const Others);
        let id = others.ids[a.prim_id as usize];
        let n = a.n as usize;
        let words = a.ray.cast::<f32>();
        for i in 0..n {
            if *a.valid.add(i) != 0 && test_lane(others, id, words, n, i).is_some() {
                *words.add(ffi::ray_n(ffi::ray_field::TFAR, n, i)) = f32::NEG_INFINITY;
            }
        }
    }
}
