//! The C declarations of Embree 3 that the accelerator uses, mirroring the headers of Embree 3.13
//! (`embree3/rtcore_*.h`, Debian's `libembree-dev` 3.13.5), which this binding was checked against:
//! one instance level (`RTC_MAX_INSTANCE_LEVEL_COUNT` 1) and no curve minimum width (`RTC_MIN_WIDTH`
//! 0), as Embree's default build. The repository's one Embree binding: the accelerator
//! ([`super::Embree`]) and the benches both go through it.
//!
//! Handles are opaque pointers; enums are C `int`s, passed as their numeric values below.

use std::ffi::{c_char, c_int, c_uint, c_void};

/// `RTCDevice`.
pub type Device = *mut c_void;
/// `RTCScene`.
pub type Scene = *mut c_void;
/// `RTCGeometry`.
pub type Geometry = *mut c_void;

/// `RTC_INVALID_GEOMETRY_ID`: no geometry hit.
pub const INVALID_GEOMETRY_ID: u32 = u32::MAX;

/// `enum RTCError`.
pub const ERROR_NONE: c_int = 0;

/// `enum RTCGeometryType`: a triangle mesh.
pub const GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
/// `enum RTCGeometryType`: primitives with the user's bounds, intersect and occluded callbacks.
pub const GEOMETRY_TYPE_USER: c_uint = 120;

/// `enum RTCBufferType`: the index buffer.
pub const BUFFER_TYPE_INDEX: c_uint = 0;
/// `enum RTCBufferType`: the vertex buffer.
pub const BUFFER_TYPE_VERTEX: c_uint = 1;

/// `enum RTCFormat`: three `unsigned int`s (a triangle's vertex indices).
pub const FORMAT_UINT3: c_uint = 0x5003;
/// `enum RTCFormat`: three `float`s (a vertex).
pub const FORMAT_FLOAT3: c_uint = 0x9003;

/// `enum RTCBuildQuality`: Embree's default, a binned SAH build.
pub const BUILD_QUALITY_MEDIUM: c_uint = 1;
/// `enum RTCBuildQuality`: with spatial splits.
pub const BUILD_QUALITY_HIGH: c_uint = 2;

/// `enum RTCDeviceProperty`: the version, `10000 * major + 100 * minor + patch`.
pub const DEVICE_PROPERTY_VERSION: c_int = 0;
/// `enum RTCDeviceProperty`: 0 Embree's internal tasking system, 1 TBB, 2 PPL.
pub const DEVICE_PROPERTY_TASKING_SYSTEM: c_int = 128;

/// `RTCErrorFunction`.
pub type ErrorFunction = unsafe extern "C" fn(user: *mut c_void, code: c_int, message: *const c_char);

/// `struct RTCIntersectContext` (one instance level, no minimum width).
#[repr(C)]
pub struct Context {
    /// `enum RTCIntersectContextFlags`: 0 incoherent rays, 1 coherent.
    pub flags: c_uint,
    /// `RTCFilterFunctionN`: none.
    pub filter: Option<unsafe extern "C" fn(*const c_void)>,
    /// The instance stack: empty.
    pub inst_id: [u32; 1],
}

impl Context {
    /// `rtcInitIntersectContext`, an inline function of the header: incoherent rays, no filter, no
    /// instance.
    pub fn new() -> Self {
        Context {
            flags: 0,
            filter: None,
            inst_id: [INVALID_GEOMETRY_ID],
        }
    }
}

impl Default for Context {
    fn default() -> Self {
        Self::new()
    }
}

/// `struct RTCRay`.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct Ray1 {
    pub org: [f32; 3],
    pub tnear: f32,
    pub dir: [f32; 3],
    pub time: f32,
    pub tfar: f32,
    pub mask: u32,
    pub id: u32,
    pub flags: u32,
}

/// `struct RTCHit`.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct Hit1 {
    pub ng: [f32; 3],
    pub u: f32,
    pub v: f32,
    pub prim_id: u32,
    pub geom_id: u32,
    pub inst_id: [u32; 1],
}

/// `struct RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RayHit1 {
    pub ray: Ray1,
    pub hit: Hit1,
}

/// `struct RTCRay8`: eight rays, structure of arrays.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, Default)]
pub struct Ray8 {
    pub org: [[f32; 8]; 3],
    pub tnear: [f32; 8],
    pub dir: [[f32; 8]; 3],
    pub time: [f32; 8],
    pub tfar: [f32; 8],
    pub mask: [u32; 8],
    pub id: [u32; 8],
    pub flags: [u32; 8],
}

/// `struct RTCHit8`.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, Default)]
pub struct Hit8 {
    pub ng: [[f32; 8]; 3],
    pub u: [f32; 8],
    pub v: [f32; 8],
    pub prim_id: [u32; 8],
    pub geom_id: [u32; 8],
    pub inst_id: [[u32; 8]; 1],
}

/// `struct RTCRayHit8`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct RayHit8 {
    pub ray: Ray8,
    pub hit: Hit8,
}

/// A packet's `valid` argument: -1 for an active lane, 0 for one left out; Embree loads it as one
/// aligned vector.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, Default)]
pub struct Valid8(pub [i32; 8]);

/// `struct RTCBounds`.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct Bounds {
    pub lower: [f32; 3],
    pub align0: f32,
    pub upper: [f32; 3],
    pub align1: f32,
}

/// `struct RTCBoundsFunctionArguments`.
#[repr(C)]
pub struct BoundsArguments {
    pub geometry_user_ptr: *mut c_void,
    pub prim_id: c_uint,
    pub time_step: c_uint,
    pub bounds_o: *mut Bounds,
}

/// `struct RTCIntersectFunctionNArguments`. `rayhit` points to an `RTCRayHitN` of `n` lanes: the ray's
/// twelve fields, then the hit's, each an array of `n` ([`ray_n`], [`hit_n`]).
#[repr(C)]
pub struct IntersectArguments {
    pub valid: *mut c_int,
    pub geometry_user_ptr: *mut c_void,
    pub prim_id: c_uint,
    pub context: *mut Context,
    pub rayhit: *mut c_void,
    pub n: c_uint,
    pub geom_id: c_uint,
}

/// `struct RTCOccludedFunctionNArguments`; `ray` points to an `RTCRayN` of `n` lanes.
#[repr(C)]
pub struct OccludedArguments {
    pub valid: *mut c_int,
    pub geometry_user_ptr: *mut c_void,
    pub prim_id: c_uint,
    pub context: *mut Context,
    pub ray: *mut c_void,
    pub n: c_uint,
    pub geom_id: c_uint,
}

/// The `RTCRayN_*` accessors: the 32-bit word of field `field` (0 `org_x` ... 3 `tnear`, 4 `dir_x` ...
/// 8 `tfar`, 9 `mask`, 10 `id`, 11 `flags`) of lane `i` of an `n`-lane `RTCRayN`.
pub const fn ray_n(field: usize, n: usize, i: usize) -> usize {
    field * n + i
}

/// The `RTCRayHitN_HitN` and `RTCHitN_*` accessors: the word of hit field `field` (0 `Ng_x` ... 3 `u`,
/// 4 `v`, 5 `primID`, 6 `geomID`, 7 `instID[0]`) of lane `i` of an `n`-lane `RTCRayHitN`.
pub const fn hit_n(field: usize, n: usize, i: usize) -> usize {
    12 * n + field * n + i
}

/// Field numbers of [`ray_n`].
pub mod ray_field {
    pub const ORG: usize = 0;
    pub const TNEAR: usize = 3;
    pub const DIR: usize = 4;
    pub const TFAR: usize = 8;
}

/// Field numbers of [`hit_n`].
pub mod hit_field {
    pub const NG: usize = 0;
    pub const U: usize = 3;
    pub const V: usize = 4;
    pub const PRIM_ID: usize = 5;
    pub const GEOM_ID: usize = 6;
    pub const INST_ID: usize = 7;
}

/// `RTCBoundsFunction`.
pub type BoundsFunction = unsafe extern "C" fn(args: *const BoundsArguments);
/// `RTCIntersectFunctionN`.
pub type IntersectFunction = unsafe extern "C" fn(args: *const IntersectArguments);
/// `RTCOccludedFunctionN`.
pub type OccludedFunction = unsafe extern "C" fn(args: *const OccludedArguments);

#[link(name = "embree3")]
unsafe extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> Device;
    pub fn rtcReleaseDevice(device: Device);
    pub fn rtcGetDeviceError(device: Device) -> c_int;
    pub fn rtcGetDeviceProperty(device: Device, property: c_int) -> isize;
    pub fn rtcSetDeviceErrorFunction(device: Device, function: Option<ErrorFunction>, user: *mut c_void);

    pub fn rtcNewScene(device: Device) -> Scene;
    pub fn rtcReleaseScene(scene: Scene);
    pub fn rtcSetSceneBuildQuality(scene: Scene, quality: c_uint);
    pub fn rtcAttachGeometryByID(scene: Scene, geometry: Geometry, geom_id: c_uint);
    pub fn rtcCommitScene(scene: Scene);

    pub fn rtcNewGeometry(device: Device, kind: c_uint) -> Geometry;
    pub fn rtcReleaseGeometry(geometry: Geometry);
    pub fn rtcCommitGeometry(geometry: Geometry);
    pub fn rtcSetNewGeometryBuffer(
        geometry: Geometry,
        kind: c_uint,
        slot: c_uint,
        format: c_uint,
        stride: usize,
        count: usize,
    ) -> *mut c_void;
    pub fn rtcSetGeometryUserPrimitiveCount(geometry: Geometry, count: c_uint);
    pub fn rtcSetGeometryUserData(geometry: Geometry, user: *mut c_void);
    pub fn rtcSetGeometryBoundsFunction(
        geometry: Geometry,
        bounds: Option<BoundsFunction>,
        user: *mut c_void,
    );
    pub fn rtcSetGeometryIntersectFunction(geometry: Geometry, intersect: Option<IntersectFunction>);
    pub fn rtcSetGeometryOccludedFunction(geometry: Geometry, occluded: Option<OccludedFunction>);

    pub fn rtcIntersect1(scene: Scene, context: *mut Context, rayhit: *mut RayHit1);
    pub fn rtcOccluded1(scene: Scene, context: *mut Context, ray: *mut Ray1);
    pub fn rtcIntersect8(valid: *const Valid8, scene: Scene, context: *mut Context, rayhit: *mut RayHit8);
    pub fn rtcOccluded8(valid: *const Valid8, scene: Scene, context: *mut Context, ray: *mut Ray8);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sizes and alignments of the header's structs (for one instance level).
    #[test]
    fn layouts_match_the_headers() {
        use std::mem::{align_of, size_of};
        assert_eq!((size_of::<Ray1>(), align_of::<Ray1>()), (48, 16));
        assert_eq!((size_of::<Hit1>(), align_of::<Hit1>()), (32, 16));
        assert_eq!(size_of::<RayHit1>(), 80);
        assert_eq!((size_of::<Ray8>(), align_of::<Ray8>()), (12 * 32, 32));
        assert_eq!((size_of::<Hit8>(), align_of::<Hit8>()), (8 * 32, 32));
        assert_eq!(size_of::<RayHit8>(), 20 * 32);
        assert_eq!((size_of::<Bounds>(), align_of::<Bounds>()), (32, 16));
        assert_eq!(size_of::<Context>(), 24);
        assert_eq!(std::mem::offset_of!(RayHit8, hit), hit_n(0, 8, 0) * 4);
        assert_eq!(std::mem::offset_of!(Ray8, tfar), ray_n(ray_field::TFAR, 8, 0) * 4);
        assert_eq!(
            std::mem::offset_of!(Hit8, geom_id),
            (hit_n(hit_field::GEOM_ID, 8, 0) - 96) * 4
        );
        assert_eq!(std::mem::offset_of!(RayHit1, hit), 48);
    }
}
