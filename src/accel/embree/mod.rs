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
//! Coordinates: Embree takes them below [`FLT_LARGE`]. Its builders leave out any primitive that
//! reaches past it, so [`Embree::new`] refuses such a scene; and its traversal asserts that every ray's
//! origin lies within it, an assertion that aborts the process in Debian's build, so a ray from
//! farther (a camera far out, a shadow ray from a far point of a plane) goes to Embree from where it
//! enters the cube of half-side `FLT_LARGE`, which holds all of Embree's scene (`verbs.rs`).
//!
//! Single rays go through `rtcIntersect1`/`rtcOccluded1`, packets through `rtcIntersect8`/
//! `rtcOccluded8` with the packet's active mask as Embree's `valid` lanes. The device and scene are
//! released when the last clone of the accelerator is dropped; Embree's errors (`rtcGetDeviceError`,
//! with the message of its error callback) become our [`Error`]. A committed Embree scene may be traced
//! from any number of threads at once, which makes the accelerator `Send + Sync`.
//!
//! Embree's triangle test is its own: where a ray crosses within f32 rounding of an edge shared by
//! two triangles the two tests may disagree on which one (or, through a crack of ours, whether any) is
//! hit; `tests/embree/main.rs` bounds how often.

mod callbacks;
pub mod ffi;
#[cfg(test)]
mod tests;
mod verbs;

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::fmt;
use std::sync::{Arc, Mutex};

use super::Isa;
use super::prims::{PrimKind, Prims};
use crate::error::{Error, Result};
use callbacks::{Others, bounds, intersect, occluded};

/// Embree's largest coordinate, `FLT_LARGE` (1.844e18, Embree's `common/math/constants.h`): a
/// primitive must lie strictly within it, a ray's origin and direction within it
/// (`Ray::valid`).
pub const FLT_LARGE: f32 = 1.844e18;

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
    /// The instruction set asked for (`None`: Embree's choice, the best the CPU has).
    isa: Option<Isa>,
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
    /// thread pool; the tracing calls run on the caller's threads), its kernels on `isa` (`None`: the
    /// best the CPU has, Embree's own choice), so that both sides of a race can run one instruction set.
    pub fn new(prims: Prims<'a>, quality: Quality, threads: usize, isa: Option<Isa>) -> Result<Self> {
        let scene = prims.scene;
        let reach = (0..prims.bounded())
            .map(|id| {
                let b = prims.bounds(id);
                b.min.abs().max(b.max.abs()).max_element()
            })
            .fold(0.0, f32::max);
        if reach >= FLT_LARGE {
            return Err(Error::msg(format!(
                "Embree takes coordinates below {FLT_LARGE:e} (its FLT_LARGE), and the scene's \
                 primitives reach {reach:e}: another --accel renders it"
            )));
        }
        let others: Vec<u32> = (0..prims.bounded())
            .filter(|&id| !matches!(prims.kind(id), PrimKind::Triangle(_)))
            .collect();
        let mut config = format!("threads={}", threads.max(1));
        if let Some(isa) = isa {
            if !isa.available() {
                return Err(Error::msg(format!(
                    "Embree cannot run {isa:?} kernels on this CPU, which lacks the instructions"
                )));
            }
            // Embree 3's names (rtcNewDevice(3)); its AVX-512 kernels are the Skylake-X set.
            let name = match isa {
                Isa::Portable => "sse2",
                Isa::Avx2 => "avx2",
                Isa::Avx512 => "avx512",
            };
            config += &format!(",isa={name}");
        }
        let config = CString::new(config).expect("no NUL");
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
            isa,
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
            "embree {} ({} tasking, {} kernels): {} quality BVH, built on {} threads, over {t} \
             triangles and {o} other primitives (user geometry); {} planes beside it",
            self.version(),
            self.tasking(),
            self.inner.isa.map_or("its best".into(), |isa| format!("{isa:?}")),
            self.inner.quality.name(),
            self.inner.threads,
            self.inner.prims.planes().len()
        )
    }

    /// The error Embree reported since the device was created, if any.
    pub fn error(&self) -> Result<()> {
        check(&self.inner, "tracing")
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
