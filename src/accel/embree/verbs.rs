//! The accelerator's verbs on Embree: single rays through `rtcIntersect1`/`rtcOccluded1`, packets
//! through `rtcIntersect8`/`rtcOccluded8` with the packet's active mask as Embree's `valid` lanes, the
//! planes tested beside the hierarchy first, as every accelerator of ours tests them.

use super::{Embree, TRIANGLES, ffi};
use crate::accel::packet::{HitPacket, PACKET, RayPacket, bits};
use crate::accel::policy::{AnyHit, Closest, HitPolicy};
use crate::accel::prims::{Hit, Prims};
use crate::accel::structure::Structure;
use crate::geometry::ray::{Ray, ahead};

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
        let mut rh = ffi::RayHit1 {
            ray: ray1(ray, t_min, hit.t),
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
        *hit = self.hit(rh.ray.tfar, rh.hit.geom_id, rh.hit.prim_id, rh.hit.u, rh.hit.v);
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
        let mut r = ray1(ray, t_min, t_max);
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
        let mut live = 0u8;
        for k in bits(active).filter(|&k| holds_any(t_min, hits[k].t)) {
            lane(&mut rh.ray, k, &rays[k], t_min, hits[k].t);
            valid.0[k] = -1;
            live |= 1 << k;
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
                let h = &rh.hit;
                hits[k] = self.hit(rh.ray.tfar[k], g, h.prim_id[k], h.u[k], h.v[k]);
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
            lane(&mut r, k, &rays[k], t_min, t_max[k]);
            valid.0[k] = -1;
            live |= 1 << k;
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

/// An Embree ray for our open interval `(t_min, t_max)`: Embree searches `(tnear, tfar]`.
#[inline]
fn ray1(ray: &Ray, t_min: f32, t_max: f32) -> ffi::Ray1 {
    ffi::Ray1 {
        org: ray.origin.to_array(),
        tnear: ahead(t_min),
        dir: ray.dir.to_array(),
        time: 0.0,
        tfar: t_max.next_down(),
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// Lane `k` of a packet: `ray` over `(t_min, t_max)`, as [`ray1`].
#[inline]
fn lane(r: &mut ffi::Ray8, k: usize, ray: &Ray, t_min: f32, t_max: f32) {
    for a in 0..3 {
        r.org[a][k] = ray.origin[a];
        r.dir[a][k] = ray.dir[a];
    }
    (r.tnear[k], r.tfar[k], r.mask[k]) = (ahead(t_min), t_max.next_down(), u32::MAX);
}
