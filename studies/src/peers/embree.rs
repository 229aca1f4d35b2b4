//! The Embree 3 peer, through the system library (`libembree3`, Debian's
//! `libembree-dev`) by hand-written FFI: one triangle geometry in one scene,
//! queried one ray at a time with `rtcIntersect1` (nearest hit) and
//! `rtcOccluded1` (any hit).
//!
//! The device is created with `threads=1`, so the build runs on one thread
//! like every other build here. Two modes: Embree's default, and
//! `RTC_SCENE_FLAG_ROBUST` (avoids optimisations that reduce the arithmetic
//! accuracy of traversal and intersection).
//!
//! Layouts and constants are those of `/usr/include/embree3` (3.13.5, with
//! `RTC_MAX_INSTANCE_LEVEL_COUNT = 1` and `RTC_MIN_WIDTH = 0`).

use super::{BuiltPeer, PeerHit, PeerMesh, Tracer};
use accel_core::Ray as OurRay;
use std::ffi::{CStr, c_char, c_uint, c_void};
use std::ptr::{self, NonNull};
use std::time::Instant;

/// The raw API: only what the peer calls.
mod ffi {
    use std::ffi::{c_char, c_uint, c_void};

    /// `RTCDevice`.
    pub type Device = *mut c_void;
    /// `RTCScene`.
    pub type Scene = *mut c_void;
    /// `RTCGeometry`.
    pub type Geometry = *mut c_void;

    /// `RTC_GEOMETRY_TYPE_TRIANGLE` (rtcore_geometry.h).
    pub const GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
    /// `RTC_BUFFER_TYPE_INDEX` (rtcore_buffer.h).
    pub const BUFFER_TYPE_INDEX: c_uint = 0;
    /// `RTC_BUFFER_TYPE_VERTEX` (rtcore_buffer.h).
    pub const BUFFER_TYPE_VERTEX: c_uint = 1;
    /// `RTC_FORMAT_UINT3` (rtcore_common.h).
    pub const FORMAT_UINT3: c_uint = 0x5003;
    /// `RTC_FORMAT_FLOAT3` (rtcore_common.h).
    pub const FORMAT_FLOAT3: c_uint = 0x9003;
    /// `RTC_SCENE_FLAG_ROBUST` (rtcore_scene.h).
    pub const SCENE_FLAG_ROBUST: c_uint = 1 << 2;
    /// `RTC_INVALID_GEOMETRY_ID` (rtcore_common.h).
    pub const INVALID_GEOMETRY_ID: c_uint = c_uint::MAX;
    /// `RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT` (rtcore_common.h).
    pub const INTERSECT_CONTEXT_FLAG_INCOHERENT: c_uint = 0;
    /// `RTC_ERROR_NONE` (rtcore_device.h).
    pub const ERROR_NONE: c_uint = 0;

    /// `struct RTCIntersectContext` with one instance level and no minimum
    /// width.
    #[repr(C)]
    pub struct IntersectContext {
        /// `enum RTCIntersectContextFlags flags`.
        pub flags: c_uint,
        /// `RTCFilterFunctionN filter` (a nullable function pointer).
        pub filter: Option<unsafe extern "C" fn(*const c_void)>,
        /// `unsigned int instID[1]`.
        pub inst_id: [c_uint; 1],
    }

    /// `struct RTC_ALIGN(16) RTCRay`.
    #[repr(C, align(16))]
    #[derive(Clone, Copy)]
    pub struct RtcRay {
        pub org_x: f32,
        pub org_y: f32,
        pub org_z: f32,
        pub tnear: f32,
        pub dir_x: f32,
        pub dir_y: f32,
        pub dir_z: f32,
        pub time: f32,
        pub tfar: f32,
        pub mask: c_uint,
        pub id: c_uint,
        pub flags: c_uint,
    }

    /// `struct RTC_ALIGN(16) RTCHit`.
    #[repr(C, align(16))]
    #[derive(Clone, Copy)]
    pub struct RtcHit {
        pub ng_x: f32,
        pub ng_y: f32,
        pub ng_z: f32,
        pub u: f32,
        pub v: f32,
        pub prim_id: c_uint,
        pub geom_id: c_uint,
        pub inst_id: [c_uint; 1],
    }

    /// `struct RTCRayHit`.
    #[repr(C)]
    #[derive(Clone, Copy)]
    pub struct RtcRayHit {
        pub ray: RtcRay,
        pub hit: RtcHit,
    }

    #[link(name = "embree3")]
    unsafe extern "C" {
        pub fn rtcNewDevice(config: *const c_char) -> Device;
        pub fn rtcReleaseDevice(device: Device);
        pub fn rtcGetDeviceError(device: Device) -> c_uint;
        pub fn rtcNewScene(device: Device) -> Scene;
        pub fn rtcSetSceneFlags(scene: Scene, flags: c_uint);
        pub fn rtcReleaseScene(scene: Scene);
        pub fn rtcAttachGeometry(scene: Scene, geometry: Geometry) -> c_uint;
        pub fn rtcCommitScene(scene: Scene);
        pub fn rtcNewGeometry(device: Device, kind: c_uint) -> Geometry;
        pub fn rtcSetNewGeometryBuffer(
            geometry: Geometry,
            kind: c_uint,
            slot: c_uint,
            format: c_uint,
            byte_stride: usize,
            item_count: usize,
        ) -> *mut c_void;
        pub fn rtcCommitGeometry(geometry: Geometry);
        pub fn rtcReleaseGeometry(geometry: Geometry);
        pub fn rtcIntersect1(scene: Scene, context: *mut IntersectContext, rayhit: *mut RtcRayHit);
        pub fn rtcOccluded1(scene: Scene, context: *mut IntersectContext, ray: *mut RtcRay);
    }

    // The layouts of rtcore_common.h and rtcore_ray.h on x86-64 (checked
    // against sizeof in C).
    const _: () = assert!(size_of::<IntersectContext>() == 24);
    const _: () = assert!(size_of::<RtcRay>() == 48 && align_of::<RtcRay>() == 16);
    const _: () = assert!(size_of::<RtcHit>() == 32 && align_of::<RtcHit>() == 16);
    const _: () = assert!(size_of::<RtcRayHit>() == 80);
}

/// An Embree device (one thread) with one committed triangle scene.
pub struct EmbreePeer {
    device: NonNull<c_void>,
    scene: NonNull<c_void>,
}

impl Drop for EmbreePeer {
    fn drop(&mut self) {
        // SAFETY: both handles were created by `build` and are released once,
        // here; the scene holds its own reference to the device, so the order
        // does not matter, but releasing the scene first is the documented one.
        unsafe {
            ffi::rtcReleaseScene(self.scene.as_ptr());
            ffi::rtcReleaseDevice(self.device.as_ptr());
        }
    }
}

/// The device's pending error, as text.
fn device_error(device: ffi::Device, what: &str) -> Result<(), String> {
    // SAFETY: `device` is a live device handle.
    let code = unsafe { ffi::rtcGetDeviceError(device) };
    if code == ffi::ERROR_NONE {
        Ok(())
    } else {
        Err(format!("Embree: {what} failed with RTCError {code}"))
    }
}

/// Builds the peer in Embree's default mode.
///
/// # Errors
/// Embree's refusal (device creation, buffer allocation, build).
pub fn build_default(mesh: &PeerMesh) -> Result<BuiltPeer, String> {
    build(mesh, false)
}

/// Builds the peer with `RTC_SCENE_FLAG_ROBUST`.
///
/// # Errors
/// Embree's refusal (device creation, buffer allocation, build).
pub fn build_robust(mesh: &PeerMesh) -> Result<BuiltPeer, String> {
    build(mesh, true)
}

fn build(mesh: &PeerMesh, robust: bool) -> Result<BuiltPeer, String> {
    let config: &CStr = c"threads=1";
    let config_ptr: *const c_char = config.as_ptr();
    // SAFETY: the configuration is a NUL-terminated string that outlives the call.
    let device = unsafe { ffi::rtcNewDevice(config_ptr) };
    let device = NonNull::new(device).ok_or(
        "Embree: rtcNewDevice returned NULL (is libembree3 installed and the CPU supported?)",
    )?;
    // From here on `peer` owns the device, and the scene once it exists.
    let start = Instant::now();
    // SAFETY: `device` is live.
    let scene = unsafe { ffi::rtcNewScene(device.as_ptr()) };
    let Some(scene) = NonNull::new(scene) else {
        let e = device_error(device.as_ptr(), "rtcNewScene");
        // SAFETY: the device was created above and is released once.
        unsafe { ffi::rtcReleaseDevice(device.as_ptr()) };
        return Err(e
            .err()
            .unwrap_or_else(|| "Embree: rtcNewScene returned NULL".into()));
    };
    let peer = EmbreePeer { device, scene };
    if robust {
        // SAFETY: `scene` is live and not yet committed.
        unsafe { ffi::rtcSetSceneFlags(scene.as_ptr(), ffi::SCENE_FLAG_ROBUST) };
    }
    // SAFETY: `device` is live; the geometry is released below after being
    // attached (the scene keeps its own reference).
    let geom = unsafe { ffi::rtcNewGeometry(device.as_ptr(), ffi::GEOMETRY_TYPE_TRIANGLE) };
    if geom.is_null() {
        device_error(device.as_ptr(), "rtcNewGeometry")?;
        return Err("Embree: rtcNewGeometry returned NULL".into());
    }
    let filled = fill_buffers(geom, mesh);
    // SAFETY: `geom` and `scene` are live; after attaching, the scene holds a
    // reference, so releasing ours leaves the geometry alive in the scene.
    // On a failed fill the geometry is released without being attached.
    unsafe {
        if filled.is_ok() {
            ffi::rtcCommitGeometry(geom);
            ffi::rtcAttachGeometry(scene.as_ptr(), geom);
        }
        ffi::rtcReleaseGeometry(geom);
    }
    filled?;
    // SAFETY: `scene` is live and holds one committed geometry.
    unsafe { ffi::rtcCommitScene(scene.as_ptr()) };
    device_error(device.as_ptr(), "building the scene")?;
    let build = start.elapsed();
    Ok(BuiltPeer {
        tracer: Box::new(peer),
        build,
    })
}

/// Allocates the vertex and index buffers of `geom` and copies `mesh` in.
fn fill_buffers(geom: ffi::Geometry, mesh: &PeerMesh) -> Result<(), String> {
    // SAFETY: `geom` is a live triangle geometry; Embree allocates
    // `count × stride` bytes (padded for its 16-byte loads) and returns the
    // pointer or NULL.
    let vertices = unsafe {
        ffi::rtcSetNewGeometryBuffer(
            geom,
            ffi::BUFFER_TYPE_VERTEX,
            0,
            ffi::FORMAT_FLOAT3,
            12,
            mesh.positions.len(),
        )
    };
    // SAFETY: as above, for the index buffer.
    let indices = unsafe {
        ffi::rtcSetNewGeometryBuffer(
            geom,
            ffi::BUFFER_TYPE_INDEX,
            0,
            ffi::FORMAT_UINT3,
            12,
            mesh.indices.len(),
        )
    };
    if vertices.is_null() || indices.is_null() {
        return Err("Embree: rtcSetNewGeometryBuffer returned NULL".into());
    }
    // SAFETY: Embree returned buffers of exactly these many 12-byte items,
    // suitably aligned for f32 and u32 (it aligns buffers to 16 bytes); the
    // sources are the same shapes (`[f32; 3]`, `[u32; 3]`, 12 bytes each) and
    // do not overlap Embree's memory.
    unsafe {
        ptr::copy_nonoverlapping(
            mesh.positions.as_ptr(),
            vertices.cast::<[f32; 3]>(),
            mesh.positions.len(),
        );
        ptr::copy_nonoverlapping(
            mesh.indices.as_ptr(),
            indices.cast::<[u32; 3]>(),
            mesh.indices.len(),
        );
    }
    Ok(())
}

/// `rtcInitIntersectContext`, an inline function of the header.
fn context() -> ffi::IntersectContext {
    ffi::IntersectContext {
        flags: ffi::INTERSECT_CONTEXT_FLAG_INCOHERENT,
        filter: None,
        inst_id: [ffi::INVALID_GEOMETRY_ID],
    }
}

fn rtc_ray(r: &OurRay<f32>) -> ffi::RtcRay {
    ffi::RtcRay {
        org_x: r.origin.x,
        org_y: r.origin.y,
        org_z: r.origin.z,
        tnear: r.t_min,
        dir_x: r.direction.x,
        dir_y: r.direction.y,
        dir_z: r.direction.z,
        time: 0.0,
        tfar: r.t_max,
        mask: c_uint::MAX,
        id: 0,
        flags: 0,
    }
}

impl Tracer for EmbreePeer {
    fn nearest(&self, ray: &OurRay<f32>) -> Option<PeerHit> {
        let mut ctx = context();
        let mut rh = ffi::RtcRayHit {
            ray: rtc_ray(ray),
            hit: ffi::RtcHit {
                ng_x: 0.0,
                ng_y: 0.0,
                ng_z: 0.0,
                u: 0.0,
                v: 0.0,
                prim_id: ffi::INVALID_GEOMETRY_ID,
                geom_id: ffi::INVALID_GEOMETRY_ID,
                inst_id: [ffi::INVALID_GEOMETRY_ID],
            },
        };
        // SAFETY: the scene is live and committed; `ctx` and `rh` are
        // initialised as the header's rtcInitIntersectContext and the API
        // require, properly aligned, and live for the call.
        unsafe { ffi::rtcIntersect1(self.scene.as_ptr(), &raw mut ctx, &raw mut rh) };
        (rh.hit.geom_id != ffi::INVALID_GEOMETRY_ID).then_some(PeerHit {
            t: rh.ray.tfar,
            prim: rh.hit.prim_id,
        })
    }

    fn occluded(&self, ray: &OurRay<f32>) -> bool {
        let mut ctx = context();
        let mut r = rtc_ray(ray);
        // SAFETY: as for rtcIntersect1; Embree sets `tfar` to -inf on a hit.
        unsafe { ffi::rtcOccluded1(self.scene.as_ptr(), &raw mut ctx, &raw mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}
