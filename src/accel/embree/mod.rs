//! Embree 3 as an accelerator (`--accel embree`, behind the cargo feature `embree`): the standard CPU
//! ray tracing kernels (I. Wald, S. Woop, C. Benthin, G. S. Johnson, M. Ernst, "Embree: A Kernel
//! Framework for Efficient CPU Ray Tracing", *ACM TOG* 33(4), 2014), linked from the system's
//! `libembree3.so`, to race our BVHs against on the same frames.
//!
//! The scene's triangles are one Embree triangle geometry (geometry id 0), its vertex buffer each
//! triangle's `v0, v0 + e1, v0 + e2` (the corners our own test sees) and its index buffer `3i, 3i + 1,
//! 3i + 2` (our store keeps triangles apart, so no vertex is shared). Every other bounded primitive
//! (spheres, boxes, cones) is one primitive of one Embree user geometry (geometry id 1), whose bounds,
//! intersect and occluded callbacks call our own routines ([`Prims::bounds`], [`Prims::intersect`]);
//! its primitive ids index the list of our ids it holds. Planes stay beside the hierarchy, tested
//! before it, as every accelerator of ours tests them.
//!
//! Embree's hit maps back to our [`Hit`]: `t` is the ray's `tfar`, the primitive is our id of
//! (geometry, primitive), and a triangle's `u, v` are Embree's, which are ours: the weights of the
//! second and third vertices (`hit = (1 - u - v) v0 + u v1 + v v2`, `rtcore_ray.h`; checked against our
//! Möller–Trumbore test in the tests below). Intervals: ours are open, `t` in `(t_min, t_max)`;
//! Embree's triangle test accepts `tnear < t <= tfar`, so a ray goes to Embree with `tfar` the largest
//! float below our `t_max`, and the user callbacks hand our routines `tfar`'s successor as their open
//! upper limit. Embree requires `tnear >= 0`: a negative `t_min` (which nothing of ours passes) is
//! searched from 0.
//!
//! Single rays go through `rtcIntersect1`/`rtcOccluded1`, packets through `rtcIntersect8`/
//! `rtcOccluded8` with the packet's active mask as Embree's `valid` lanes. The device and scene are
//! released when the last clone of the accelerator is dropped; Embree's errors (`rtcGetDeviceError`,
//! with the message of its error callback) become our [`Error`]. A committed Embree scene may be traced
//! from any number of threads at once, which makes the accelerator `Send + Sync`.
//!
//! Embree's triangle test is its own: where a ray crosses within f32 rounding of an edge shared by
//! two triangles the two tests may disagree on which one (or, through a crack of ours, whether any) is
//! hit; `tests/embree.rs` bounds how often.

pub mod ffi;

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::fmt;
use std::sync::{Arc, Mutex};

use glam::Vec3;

use super::packet::{HitPacket, PACKET, RayPacket, bits};
use super::policy::{AnyHit, Closest};
use super::prims::{Hit, PrimKind, Prims};
use crate::error::{Error, Result};
use crate::geometry::ray::{Ray, ahead};

/// Embree's geometry id of the triangles.
const TRIANGLES: u32 = 0;
/// Embree's geometry id of the other bounded primitives (the user geometry).
const OTHERS: u32 = 1;

/// Embree's BVH build quality (`RTCBuildQuality`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// Embree's default: a binned SAH build.
    Medium,
    /// With spatial splits (Embree's best trees, slower to build).
    High,
}

impl Quality {
    /// Its name: `medium` or `high`.
    pub fn name(self) -> &'static str {
        match self {
            Quality::Medium => "medium",
            Quality::High => "high",
        }
    }
}

/// The build quality `--accel embree` uses.
pub const DEFAULT_QUALITY: Quality = Quality::High;

/// The data the user geometry's callbacks read, at a fixed address (the geometry's user pointer).
struct Others<'a> {
    prims: Prims<'a>,
    /// Our id of each of the user geometry's primitives, by Embree's primitive id.
    ids: Vec<u32>,
}

/// The messages of Embree's error callback, at a fixed address (the callback's user pointer).
type Messages = Mutex<Vec<String>>;

/// The handles and what Embree's callbacks point to; shared by the accelerator's clones.
struct Inner<'a> {
    device: ffi::Device,
    scene: ffi::Scene,
    prims: Prims<'a>,
    others: Box<Others<'a>>,
    messages: Box<Messages>,
    quality: Quality,
    threads: usize,
    triangles: usize,
}

// SAFETY: the handles are Embree's reference-counted objects; a committed scene is documented as safe to
// trace from any number of threads at once (rtcIntersect*/rtcOccluded* take it by pointer and change
// nothing of it), nothing here modifies device or scene after `Embree::new`, and they are released
// once, in `Drop`. What the callbacks read (`others`) is immutable after the build; `messages` is a
// mutex.
unsafe impl Send for Inner<'_> {}
// SAFETY: as for Send.
unsafe impl Sync for Inner<'_> {}

impl Drop for Inner<'_> {
    fn drop(&mut self) {
        // SAFETY: each handle came from `Embree::new` and is released exactly once (null when that
        // step was never reached); the scene goes before its device, and `others`/`messages`, which
        // Embree's callbacks point to, outlive both (fields drop after this).
        unsafe {
            if !self.scene.is_null() {
                ffi::rtcReleaseScene(self.scene);
            }
            if !self.device.is_null() {
                ffi::rtcReleaseDevice(self.device);
            }
        }
    }
}

/// An Embree scene over a scene's bounded primitives, with the planes beside it. Clones share it.
#[derive(Clone)]
pub struct Embree<'a> {
    inner: Arc<Inner<'a>>,
}

impl fmt::Debug for Embree<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Embree")
            .field("triangles", &self.inner.triangles)
            .field("others", &self.inner.others.ids.len())
            .field("quality", &self.inner.quality)
            .field("threads", &self.inner.threads)
            .finish()
    }
}

/// The name of an `RTCError` code.
fn error_name(code: c_int) -> &'static str {
    match code {
        0 => "no error",
        1 => "unknown error",
        2 => "invalid argument",
        3 => "invalid operation",
        4 => "out of memory",
        5 => "unsupported CPU",
        6 => "cancelled",
        _ => "unrecognised error code",
    }
}

/// Embree's error callback: keeps the message for [`Embree::check`].
unsafe extern "C" fn on_error(user: *mut c_void, code: c_int, message: *const c_char) {
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated string, valid during the call.
        unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
    };
    // SAFETY: `user` is the `Messages` box of the device's `Inner`, which outlives the device.
    let messages = unsafe { &*(user as *const Messages) };
    if let Ok(mut m) = messages.lock() {
        m.push(format!("{}: {text}", error_name(code)));
    }
}

impl<'a> Embree<'a> {
    /// Builds the Embree scene of `prims` at `quality`, with `threads` build threads (Embree's own
    /// thread pool; the tracing calls run on the caller's threads).
    pub fn new(prims: Prims<'a>, quality: Quality, threads: usize) -> Result<Self> {
        let scene = prims.scene;
        let others: Vec<u32> = (0..prims.bounded())
            .filter(|&id| !matches!(prims.kind(id), PrimKind::Triangle(_)))
            .collect();
        let config = CString::new(format!("threads={}", threads.max(1))).expect("no NUL");
        // SAFETY: rtcNewDevice takes a NUL-terminated configuration string.
        let device = unsafe { ffi::rtcNewDevice(config.as_ptr()) };
        if device.is_null() {
            // SAFETY: the null device asks for the error of the failed device creation.
            let code = unsafe { ffi::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(Error::msg(format!(
                "Embree could not create a device: {}",
                error_name(code)
            )));
        }
        let mut inner = Inner {
            device,
            scene: std::ptr::null_mut(),
            prims,
            others: Box::new(Others { prims, ids: others }),
            messages: Box::new(Mutex::new(Vec::new())),
            quality,
            threads: threads.max(1),
            triangles: scene.triangles.len(),
        };
        // SAFETY: from here on every call gets the live device (released in Inner's Drop, also on the
        // error paths), handles it returned, and buffers filled within the item counts they were created
        // with; the callbacks' user pointers are boxes owned by `inner`, which outlive the device.
        unsafe {
            let messages = &*inner.messages as *const Messages as *mut c_void;
            ffi::rtcSetDeviceErrorFunction(device, Some(on_error), messages);
            inner.scene = ffi::rtcNewScene(device);
            check(&inner, "creating a scene")?;
            let quality = match quality {
                Quality::Medium => ffi::BUILD_QUALITY_MEDIUM,
                Quality::High => ffi::BUILD_QUALITY_HIGH,
            };
            ffi::rtcSetSceneBuildQuality(inner.scene, quality);
            if inner.triangles > 0 {
                let geometry = ffi::rtcNewGeometry(device, ffi::GEOMETRY_TYPE_TRIANGLE);
                check(&inner, "creating the triangle geometry")?;
                let result = fill_triangles(&inner, geometry);
                if result.is_ok() {
                    ffi::rtcCommitGeometry(geometry);
                    ffi::rtcAttachGeometryByID(inner.scene, geometry, TRIANGLES);
                }
                ffi::rtcReleaseGeometry(geometry);
                result?;
                check(&inner, "attaching the triangles")?;
            }
            if !inner.others.ids.is_empty() {
                let geometry = ffi::rtcNewGeometry(device, ffi::GEOMETRY_TYPE_USER);
                check(&inner, "creating the user geometry")?;
                let user = &*inner.others as *const Others as *mut c_void;
                ffi::rtcSetGeometryUserPrimitiveCount(geometry, inner.others.ids.len() as u32);
                ffi::rtcSetGeometryUserData(geometry, user);
                ffi::rtcSetGeometryBoundsFunction(geometry, Some(bounds), std::ptr::null_mut());
                ffi::rtcSetGeometryIntersectFunction(geometry, Some(intersect));
                ffi::rtcSetGeometryOccludedFunction(geometry, Some(occluded));
                ffi::rtcCommitGeometry(geometry);
                ffi::rtcAttachGeometryByID(inner.scene, geometry, OTHERS);
                ffi::rtcReleaseGeometry(geometry);
                check(&inner, "attaching the spheres, boxes and cones")?;
            }
            ffi::rtcCommitScene(inner.scene);
            check(&inner, "building the scene")?;
        }
        Ok(Embree {
            inner: Arc::new(inner),
        })
    }

    /// The scene's primitives.
    pub fn prims(&self) -> Prims<'a> {
        self.inner.prims
    }

    /// The build quality.
    pub fn quality(&self) -> Quality {
        self.inner.quality
    }

    /// The triangles (Embree's triangle geometry) and the other bounded primitives (its user
    /// geometry).
    pub fn counts(&self) -> (usize, usize) {
        (self.inner.triangles, self.inner.others.ids.len())
    }

    /// Embree's version, `major.minor.patch`.
    pub fn version(&self) -> String {
        // SAFETY: a live device.
        let v = unsafe { ffi::rtcGetDeviceProperty(self.inner.device, ffi::DEVICE_PROPERTY_VERSION) };
        format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100)
    }

    /// Embree's tasking system: `internal`, `tbb` or `ppl`.
    pub fn tasking(&self) -> &'static str {
        // SAFETY: a live device.
        match unsafe { ffi::rtcGetDeviceProperty(self.inner.device, ffi::DEVICE_PROPERTY_TASKING_SYSTEM) } {
            0 => "internal",
            1 => "tbb",
            2 => "ppl",
            _ => "unknown",
        }
    }

    /// One line: version, quality, build threads and what the geometries hold.
    pub fn describe(&self) -> String {
        let (t, o) = self.counts();
        format!(
            "embree {} ({} tasking): {} quality BVH, built on {} threads, over {t} triangles and {o} \
             other primitives (user geometry); {} planes beside it",
            self.version(),
            self.tasking(),
            self.inner.quality.name(),
            self.inner.threads,
            self.inner.prims.planes().len()
        )
    }

    /// The error Embree reported since the device was created, if any.
    pub fn error(&self) -> Result<()> {
        check(&self.inner, "tracing")
    }

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

/// The error Embree reported on `inner`'s device, as our error about `doing`.
fn check(inner: &Inner, doing: &str) -> Result<()> {
    // SAFETY: a live device.
    let code = unsafe { ffi::rtcGetDeviceError(inner.device) };
    let messages = inner.messages.lock().map(|m| m.join("; ")).unwrap_or_default();
    if code == ffi::ERROR_NONE && messages.is_empty() {
        return Ok(());
    }
    let what = if messages.is_empty() {
        error_name(code).to_string()
    } else {
        messages
    };
    Err(Error::msg(format!("Embree failed {doing}: {what}")))
}

/// Fills the triangle geometry's vertex and index buffers: each triangle's corners as our test sees
/// them, `v0, v0 + e1, v0 + e2`.
///
/// # Safety
///
/// `geometry` is a live triangle geometry of `inner.device`.
unsafe fn fill_triangles(inner: &Inner, geometry: ffi::Geometry) -> Result<()> {
    let t = &inner.prims.scene.triangles;
    let n = t.len();
    // SAFETY: per the contract; each buffer is written within the item count it was created with.
    unsafe {
        let v = ffi::rtcSetNewGeometryBuffer(
            geometry,
            ffi::BUFFER_TYPE_VERTEX,
            0,
            ffi::FORMAT_FLOAT3,
            12,
            3 * n,
        );
        let i = ffi::rtcSetNewGeometryBuffer(geometry, ffi::BUFFER_TYPE_INDEX, 0, ffi::FORMAT_UINT3, 12, n);
        check(inner, "allocating the triangle buffers")?;
        if v.is_null() || i.is_null() {
            return Err(Error::msg("Embree failed allocating the triangle buffers"));
        }
        let vertices = std::slice::from_raw_parts_mut(v.cast::<[f32; 3]>(), 3 * n);
        let indices = std::slice::from_raw_parts_mut(i.cast::<[u32; 3]>(), n);
        for k in 0..n {
            for (corner, v) in t.vertices(k).iter().enumerate() {
                vertices[3 * k + corner] = v.to_array();
            }
            let first = 3 * k as u32;
            indices[k] = [first, first + 1, first + 2];
        }
    }
    Ok(())
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

/// The user geometry's bounds callback: [`Prims::bounds`] of the primitive.
unsafe extern "C" fn bounds(args: *const ffi::BoundsArguments) {
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
unsafe extern "C" fn intersect(args: *const ffi::IntersectArguments) {
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
unsafe extern "C" fn occluded(args: *const ffi::OccludedArguments) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangle;
    use crate::kit::rays::TestRng;
    use crate::scene::{Camera, Material, Scene};

    fn scene() -> Scene {
        Scene::new(Camera::new(
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ZERO,
            Vec3::Y,
            45.0,
            32,
            32,
        ))
    }

    /// Embree's `u, v` on a triangle are ours: the weights of the second and third vertices, to
    /// rounding, and `t` too; and the primitive id maps back to ours.
    #[test]
    fn barycentrics_and_t_match_moller_trumbore() {
        let mut s = scene();
        let m = s.add_material(Material::default());
        s.add_sphere(Vec3::new(10.0, 10.0, 10.0), 0.5, m);
        let (a, b, c) = (
            Vec3::new(-1.0, -0.5, 0.0),
            Vec3::new(2.0, -1.0, 0.3),
            Vec3::new(0.2, 1.5, -0.4),
        );
        s.add_triangle(a, b, c, m);
        let prims = Prims::new(&s);
        let e = Embree::new(prims, Quality::High, 1).unwrap();
        let mut rng = TestRng::new(3);
        let mut compared = 0;
        for _ in 0..1000 {
            let target = a + (b - a) * rng.unit_f32() + (c - a) * rng.unit_f32() * 0.999;
            let origin = Vec3::new(rng.unit_f32() - 0.5, rng.unit_f32() - 0.5, 4.0 + rng.unit_f32());
            let ray = Ray::new(origin, target - origin);
            let t = &s.triangles;
            let ours = triangle::intersect(t.v0.get(0), t.e1.get(0), t.e2.get(0), &ray, 0.0, f32::INFINITY);
            let mut hit = Hit::miss(f32::INFINITY);
            let found = e.intersect(&ray, 0.0, &mut hit);
            let Some((t, u, v)) = ours else {
                continue;
            };
            // Well inside: Embree must agree on the hit.
            if u.min(v).min(1.0 - u - v) < 1e-4 {
                continue;
            }
            assert!(found, "{ray:?}");
            assert_eq!(hit.prim, prims.triangle_id(0));
            assert!((hit.t - t).abs() <= 1e-6 * t, "t {} vs {t}", hit.t);
            assert!(
                (hit.u - u).abs() < 1e-5 && (hit.v - v).abs() < 1e-5,
                "({}, {}) vs ({u}, {v})",
                hit.u,
                hit.v
            );
            compared += 1;
        }
        assert!(compared > 300, "{compared}");
    }

    /// Spheres, boxes and cones through the user geometry, planes beside: every kind answers as brute
    /// force, single rays and packets, closest and any hit, and the interval is open at both ends.
    #[test]
    fn user_geometry_and_planes() {
        let mut s = scene();
        let m = s.add_material(Material::default());
        s.add_sphere(Vec3::new(0.0, 0.0, 0.0), 1.0, m);
        s.add_box(Vec3::new(-3.0, -1.0, -1.0), Vec3::new(-2.0, 1.0, 1.0), m);
        let z = |x: f32, y: f32| Vec3::new(x, y, -3.0);
        assert!(s.add_plane(z(0.0, 0.0), z(1.0, 0.0), z(0.0, 1.0), m));
        let prims = Prims::new(&s);
        let e = Embree::new(prims, Quality::Medium, 2).unwrap();
        assert_eq!(e.counts(), (0, 2));
        let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let mut hit = Hit::miss(f32::INFINITY);
        assert!(e.intersect(&ray, 0.0, &mut hit));
        assert_eq!((hit.t, hit.prim), (4.0, 0));
        // Open at t_max: the sphere at exactly 4 is not before 4; the plane at 8 is beyond.
        assert!(!e.occluded(&ray, 0.0, 4.0));
        assert!(e.occluded(&ray, 0.0, 4.0f32.next_up()));
        // Open at t_min: from 4 on, the sphere's far side at 6.
        let mut hit = Hit::miss(f32::INFINITY);
        assert!(e.intersect(&ray, 4.0, &mut hit));
        assert_eq!((hit.t, hit.prim), (6.0, 0));
        let mut hit = Hit::miss(f32::INFINITY);
        assert!(e.intersect(&ray, 6.0, &mut hit));
        assert_eq!((hit.t, hit.prim), (8.0, prims.planes().start));
        // The box, and a packet of both.
        let to_box = Ray::new(Vec3::new(-2.5, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let mut rays = [ray; PACKET];
        rays[3] = to_box;
        let mut hits = [Hit::miss(f32::INFINITY); PACKET];
        hits[5].t = -1.0;
        let found = e.intersect_packet(&rays, 0b0010_1011, 0.0, &mut hits);
        assert_eq!(found, 0b0000_1011);
        assert_eq!((hits[3].t, hits[3].prim), (4.0, 1));
        assert_eq!((hits[0].t, hits[0].prim), (4.0, 0));
        assert_eq!(hits[2], Hit::miss(f32::INFINITY));
        let t_max = [4.0, 4.5, 9.0, 3.5, 1.0, 1.0, 1.0, 1.0];
        assert_eq!(e.occluded_packet(&rays, 0b0000_1111, 0.0, &t_max), 0b0000_0110);
        assert!(e.error().is_ok());
    }

    /// An empty scene and one of planes only answer without Embree's scene; clones share one.
    #[test]
    fn empty_and_planes_only() {
        let s = scene();
        let e = Embree::new(Prims::new(&s), Quality::High, 1).unwrap();
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!(!e.intersect(&ray, 0.0, &mut Hit::miss(f32::INFINITY)));
        let mut s = scene();
        let m = s.add_material(Material::default());
        let z = |x: f32, y: f32| Vec3::new(x, y, 2.0);
        assert!(s.add_plane(z(0.0, 0.0), z(1.0, 0.0), z(0.0, 1.0), m));
        let e = Embree::new(Prims::new(&s), Quality::High, 1).unwrap();
        let copy = e.clone();
        drop(e);
        let mut hit = Hit::miss(f32::INFINITY);
        assert!(copy.intersect(&ray, 0.0, &mut hit));
        assert_eq!(hit.t, 2.0);
    }

    #[test]
    fn send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<Embree<'static>>();
    }
}
