//! The accelerator's verbs on Embree: single rays through `rtcIntersect1`/`rtcOccluded1`, packets
//! through `rtcIntersect8`/`rtcOccluded8` with the packet's active mask as Embree's `valid` lanes, the
//! planes tested beside the hierarchy first, as every accelerator of ours tests them.

use glam::Vec3;

use super::{Embree, FLT_LARGE, TRIANGLES, ffi};
use crate::accel::packet::{HitPacket, PACKET, RayPacket, bits};
use crate::accel::policy::{AnyHit, Closest, HitPolicy};
use crate::accel::prims::{Hit, Prims};
use crate::accel::structure::Structure;
use crate::geometry::ray::{Ray, ahead, safe_inverse};

impl Embree<'_> {
    /// True when nothing but planes is there to trace (Embree's scene is empty).
    #[inline]
    fn empty(&self) -> bool {
        self.inner.prims.bounded() == 0
    }

    /// Our hit of Embree's (geometry, primitive) at `t` with barycentrics `u, v`.
    #[inline]
    fn hit(&self, t: f32, geom_id: u32, prim_id: u32, u: f32, v: f32) -> Hit {
        let prim = if geom_id == TRIANGLES {
            self.inner.prims.triangle_id(prim_id as usize)
        } else {
            self.inner.others.ids[prim_id as usize]
        };
        Hit { t, prim, u, v }
    }

    /// The closest hit with `t` in `(t_min, hit.t)`: the planes, then Embree (`rtcIntersect1`) on what
    /// is left of the interval. Updates `hit` and returns true if there is one.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        let found = self.inner.prims.intersect_planes::<Closest>(ray, t_min, hit);
        if self.empty() || !holds_any(t_min, hit.t) {
            return found;
        }
        let Some((r, shift)) = ray1(ray, t_min, hit.t) else {
            return found;
        };
        let mut rh = ffi::RayHit1 {
            ray: r,
            hit: ffi::Hit1 {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: ffi::INVALID_GEOMETRY_ID,
                geom_id: ffi::INVALID_GEOMETRY_ID,
                inst_id: [ffi::INVALID_GEOMETRY_ID],
            },
        };
        // SAFETY: a committed scene, an initialised context and an aligned ray and hit.
        unsafe { ffi::rtcIntersect1(self.inner.scene, &mut ffi::Context::new(), &mut rh) };
        if rh.hit.geom_id == ffi::INVALID_GEOMETRY_ID {
            return found;
        }
        let t = ours(rh.ray.tfar, shift, hit.t);
        *hit = self.hit(t, rh.hit.geom_id, rh.hit.prim_id, rh.hit.u, rh.hit.v);
        true
    }

    /// True if anything is hit with `t` in `(t_min, t_max)`: the planes, then `rtcOccluded1`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        if self
            .inner
            .prims
            .intersect_planes::<AnyHit>(ray, t_min, &mut Hit::miss(t_max))
        {
            return true;
        }
        if self.empty() || !holds_any(t_min, t_max) {
            return false;
        }
        let Some((mut r, _)) = ray1(ray, t_min, t_max) else {
            return false;
        };
        // SAFETY: as in `intersect`.
        unsafe { ffi::rtcOccluded1(self.inner.scene, &mut ffi::Context::new(), &mut r) };
        r.tfar == f32::NEG_INFINITY
    }

    /// [`Embree::intersect`] for the rays of `active` (`hits[k].t` each ray's limit): the planes ray by
    /// ray, then one `rtcIntersect8` with those rays as its valid lanes. Returns the mask of the rays
    /// that hit; the other rays' hits are left as they are.
    #[inline]
    pub fn intersect_packet(&self, rays: &RayPacket, active: u8, t_min: f32, hits: &mut HitPacket) -> u8 {
        let prims = self.inner.prims;
        let mut found = 0u8;
        for k in bits(active) {
            if prims.intersect_planes::<Closest>(&rays[k], t_min, &mut hits[k]) {
                found |= 1 << k;
            }
        }
        if self.empty() {
            return found;
        }
        let mut rh = ffi::RayHit8::default();
        let mut valid = ffi::Valid8::default();
        let (mut live, mut shifts) = (0u8, [0.0; PACKET]);
        for k in bits(active).filter(|&k| holds_any(t_min, hits[k].t)) {
            if let Some(shift) = lane(&mut rh.ray, k, &rays[k], t_min, hits[k].t) {
                shifts[k] = shift;
                valid.0[k] = -1;
                live |= 1 << k;
            }
        }
        if live == 0 {
            return found;
        }
        rh.hit.geom_id = [ffi::INVALID_GEOMETRY_ID; PACKET];
        // SAFETY: as in `intersect`, with a 32-byte aligned packet and its valid lanes.
        unsafe { ffi::rtcIntersect8(&valid, self.inner.scene, &mut ffi::Context::new(), &mut rh) };
        for k in bits(live) {
            let g = rh.hit.geom_id[k];
            if g != ffi::INVALID_GEOMETRY_ID {
                let (h, t) = (&rh.hit, ours(rh.ray.tfar[k], shifts[k], hits[k].t));
                hits[k] = self.hit(t, g, h.prim_id[k], h.u[k], h.v[k]);
                found |= 1 << k;
            }
        }
        found
    }

    /// [`Embree::occluded`] for the rays of `active`: the planes ray by ray, then one `rtcOccluded8`
    /// for the rays they do not block. Returns the mask of the blocked rays.
    #[inline]
    pub fn occluded_packet(&self, rays: &RayPacket, active: u8, t_min: f32, t_max: &[f32; PACKET]) -> u8 {
        let prims = self.inner.prims;
        let mut blocked = 0u8;
        for k in bits(active) {
            if prims.intersect_planes::<AnyHit>(&rays[k], t_min, &mut Hit::miss(t_max[k])) {
                blocked |= 1 << k;
            }
        }
        if self.empty() {
            return blocked;
        }
        let mut r = ffi::Ray8::default();
        let mut valid = ffi::Valid8::default();
        let mut live = 0u8;
        for k in bits(active & !blocked).filter(|&k| holds_any(t_min, t_max[k])) {
            if lane(&mut r, k, &rays[k], t_min, t_max[k]).is_some() {
                valid.0[k] = -1;
                live |= 1 << k;
            }
        }
        if live == 0 {
            return blocked;
        }
        // SAFETY: as in `intersect_packet`.
        unsafe { ffi::rtcOccluded8(&valid, self.inner.scene, &mut ffi::Context::new(), &mut r) };
        for k in bits(live) {
            if r.tfar[k] == f32::NEG_INFINITY {
                blocked |= 1 << k;
            }
        }
        blocked
    }
}

impl<'a> Structure<'a> for Embree<'a> {
    fn prims(&self) -> Prims<'a> {
        Embree::prims(self)
    }

    fn describe(&self) -> String {
        Embree::describe(self)
    }

    fn has_packet_kernel(&self) -> bool {
        true
    }

    /// Embree's traversal is its own: nothing of it is counted.
    fn counts_steps(&self) -> bool {
        false
    }

    #[inline]
    fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        if P::ANY {
            self.occluded(ray, t_min, hit.t)
        } else {
            self.intersect(ray, t_min, hit)
        }
    }

    #[inline]
    fn traverse_packet<P: HitPolicy>(
        &self,
        rays: &RayPacket,
        active: u8,
        t_min: f32,
        hits: &mut HitPacket,
    ) -> u8 {
        if P::ANY {
            self.occluded_packet(rays, active, t_min, &hits.map(|h| h.t))
        } else {
            self.intersect_packet(rays, active, t_min, hits)
        }
    }
}

/// True when the open interval `(t_min, t_max)` holds a number (false for NaN limits too).
#[inline]
fn holds_any(t_min: f32, t_max: f32) -> bool {
    t_max > t_min
}

/// `ray` over `(t_min, t_max)` as Embree takes it: the ray, its interval and the `t` on `ray` of its
/// origin (the shift to add back to the `t` Embree finds). A ray from within [`FLT_LARGE`] is itself,
/// shifted by 0. One from farther starts where it enters the cube of half-side `FLT_LARGE`, which
/// holds all of Embree's scene: `None` where its interval holds no point of that cube, as for a NaN
/// origin or a direction out of range (nothing of ours makes them), where Embree can hit nothing.
#[inline]
fn within_range(ray: &Ray, t_min: f32, t_max: f32) -> Option<(Ray, f32, f32, f32)> {
    // False for NaN too.
    let fits = |v: Vec3| v.abs().cmple(Vec3::splat(FLT_LARGE)).all();
    let t_min = ahead(t_min);
    if fits(ray.origin) && fits(ray.dir) {
        return Some((*ray, t_min, t_max, 0.0));
    }
    if ray.origin.is_nan() || !fits(ray.dir) {
        return None;
    }
    let inv = safe_inverse(ray.dir);
    let a = (Vec3::splat(-FLT_LARGE) - ray.origin) * inv;
    let b = (Vec3::splat(FLT_LARGE) - ray.origin) * inv;
    let near = a.min(b).max_element().max(t_min);
    let far = a.max(b).min_element().min(t_max);
    if near >= far {
        return None;
    }
    // Rounding may leave the entry point just outside.
    let origin = ray
        .at(near)
        .clamp(Vec3::splat(-FLT_LARGE), Vec3::splat(FLT_LARGE));
    Some((Ray::new(origin, ray.dir), 0.0, t_max - near, near))
}

/// Our `t` of the `t` Embree found on a ray shifted by `shift` ([`within_range`]), below our `t_max`
/// where their sum rounds up to it.
#[inline]
fn ours(t: f32, shift: f32, t_max: f32) -> f32 {
    (t + shift).min(t_max.next_down())
}

/// An Embree ray for our open interval `(t_min, t_max)` ([`within_range`]): Embree searches
/// `(tnear, tfar]`. Returns it and its shift.
#[inline]
fn ray1(ray: &Ray, t_min: f32, t_max: f32) -> Option<(ffi::Ray1, f32)> {
    let (ray, t_min, t_max, shift) = within_range(ray, t_min, t_max)?;
    let r = ffi::Ray1 {
        org: ray.origin.to_array(),
        tnear: t_min,
        dir: ray.dir.to_array(),
        time: 0.0,
        tfar: t_max.next_down(),
        mask: u32::MAX,
        id: 0,
        flags: 0,
    };
    Some((r, shift))
}

/// Lane `k` of a packet: `ray` over `(t_min, t_max)`, as [`ray1`]. Returns its shift, or `None` (the
/// lane left as it is) where Embree can hit nothing.
#[inline]
fn lane(r: &mut ffi::Ray8, k: usize, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
    let (ray, t_min, t_max, shift) = within_range(ray, t_min, t_max)?;
    for a in 0..3 {
        r.org[a][k] = ray.origin[a];
        r.dir[a][k] = ray.dir[a];
    }
    (r.tnear[k], r.tfar[k], r.mask[k]) = (t_min, t_max.next_down(), u32::MAX);
    Some(shift)
}
