//! Embree 3 (Debian's `libembree-dev`), the standard CPU ray tracers are measured against, behind the
//! `bench-embree` feature: the few calls that build a scene of our triangles. The kernels bench adds the
//! tracing calls (`kernels/embree.rs`).

use std::ffi::{CString, c_char, c_void};

use whitted::scene::Scene;

/// Embree's opaque handles.
pub type Handle = *mut c_void;

const GEOMETRY_TYPE_TRIANGLE: u32 = 0;
const BUFFER_TYPE_INDEX: u32 = 0;
const BUFFER_TYPE_VERTEX: u32 = 1;
const FORMAT_UINT3: u32 = 0x5003;
const FORMAT_FLOAT3: u32 = 0x9003;

/// `RTCBuildQuality`: medium is Embree's default (binned SAH); high adds spatial splits.
const QUALITY_MEDIUM: u32 = 1;
const QUALITY_HIGH: u32 = 2;

#[link(name = "embree3")]
unsafe extern "C" {
    fn rtcNewDevice(config: *const c_char) -> Handle;
    fn rtcReleaseDevice(device: Handle);
    fn rtcNewScene(device: Handle) -> Handle;
    fn rtcReleaseScene(scene: Handle);
    fn rtcSetSceneBuildQuality(scene: Handle, quality: u32);
    fn rtcNewGeometry(device: Handle, kind: u32) -> Handle;
    fn rtcSetNewGeometryBuffer(
        geometry: Handle,
        kind: u32,
        slot: u32,
        format: u32,
        stride: usize,
        count: usize,
    ) -> *mut c_void;
    fn rtcCommitGeometry(geometry: Handle);
    fn rtcAttachGeometry(scene: Handle, geometry: Handle) -> u32;
    fn rtcReleaseGeometry(geometry: Handle);
    fn rtcCommitScene(scene: Handle);
}

/// A committed Embree scene of one triangle mesh, on its own device.
pub struct EmbreeScene {
    device: Handle,
    /// The committed scene, for the tracing calls.
    pub scene: Handle,
}

impl EmbreeScene {
    /// Builds the BVH of `scene`'s triangles with `threads` build threads, at Embree's high quality
    /// (spatial splits) or its default medium one.
    pub fn new(scene: &Scene, threads: usize, high_quality: bool) -> Self {
        let quality = if high_quality {
            QUALITY_HIGH
        } else {
            QUALITY_MEDIUM
        };
        let n = scene.triangles.len();
        let config = CString::new(format!("threads={threads}")).expect("no NUL");
        // SAFETY: the calls follow Embree 3's API: each buffer is filled within the item count it was
        // created with, and every handle is released once (geometry here, scene and device in Drop).
        unsafe {
            let device = rtcNewDevice(config.as_ptr());
            assert!(!device.is_null(), "Embree refused to create a device");
            let handle = rtcNewScene(device);
            rtcSetSceneBuildQuality(handle, quality);
            let geometry = rtcNewGeometry(device, GEOMETRY_TYPE_TRIANGLE);
            let v = rtcSetNewGeometryBuffer(geometry, BUFFER_TYPE_VERTEX, 0, FORMAT_FLOAT3, 12, 3 * n);
            let vertices = std::slice::from_raw_parts_mut(v.cast::<f32>(), 9 * n);
            let i = rtcSetNewGeometryBuffer(geometry, BUFFER_TYPE_INDEX, 0, FORMAT_UINT3, 12, n);
            let indices = std::slice::from_raw_parts_mut(i.cast::<u32>(), 3 * n);
            for t in 0..n {
                for (k, v) in scene.triangles.vertices(t).iter().enumerate() {
                    vertices[9 * t + 3 * k..9 * t + 3 * k + 3].copy_from_slice(&v.to_array());
                    indices[3 * t + k] = (3 * t + k) as u32;
                }
            }
            rtcCommitGeometry(geometry);
            rtcAttachGeometry(handle, geometry);
            rtcReleaseGeometry(geometry);
            rtcCommitScene(handle);
            EmbreeScene {
                device,
                scene: handle,
            }
        }
    }
}

// SAFETY: Embree documents a committed scene as safe to trace from any number of threads at once, and
// nothing here modifies it after `new`.
unsafe impl Sync for EmbreeScene {}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: both handles came from `new` and are released exactly once.
        unsafe {
            rtcReleaseScene(self.scene);
            rtcReleaseDevice(self.device);
        }
    }
}
