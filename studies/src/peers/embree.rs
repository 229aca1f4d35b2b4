//! The Embree 3 peer, through the system library (`libembree3`, Debian's
//! `libembree-dev`) by hand-written FFI: one triangle geometry in one scene,
//! queried one ray at a time with `rtcIntersect1` (nearest hit) and
//! `rtcOccluded1` (any hit), and in packets of 16 or 8 rays with
//! `rtcIntersect16`/`rtcIntersect8` and `rtcOccluded16`/`rtcOccluded8`
//! ([`Tracer::nearest_packet`], [`Tracer::occluded_packet`]).
//!
//! A packet is Embree's structure of arrays (`RTCRayHit16`, `RTCRay16`, …),
//! 64-byte aligned, with a valid mask of `-1` for each active lane; a short
//! packet (the last of a set) fills its other lanes with a copy of its first
//! ray and marks them invalid (`0`), so Embree neither reads garbage nor
//! answers them. A coherent packet (a tile of camera rays) goes with
//! `RTC_INTERSECT_CONTEXT_FLAG_COHERENT` in its context, which lets Embree
//! pick its coherent traversal; others go, as single rays do, with
//! `RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT`. The packet kernels are Embree's
//! own, not a loop of single rays (on the AVX-512 host measured,
//! `rtcGetDeviceProperty` reports native 8- and 16-wide packet support);
//! their answers agree with `rtcIntersect1`'s and `rtcOccluded1`'s within
//! [`super::T_TOLERANCE`] (tested below).
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
    use std::ffi::{c_char, c_int, c_uint, c_void};

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
    /// `RTC_INTERSECT_CONTEXT_FLAG_COHERENT` (rtcore_common.h).
    pub const INTERSECT_CONTEXT_FLAG_COHERENT: c_uint = 1;
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

    /// `struct RTCRay8` (N = 8) or `struct RTCRay16` (N = 16): the rays of
    /// a packet, structure of arrays. Embree asks 32-byte alignment for the
    /// 8-wide structures and 64 for the 16-wide ones; 64 serves both and,
    /// every size here being a multiple of 64, moves no field (checked
    /// below).
    #[repr(C, align(64))]
    #[derive(Clone, Copy)]
    pub struct RayN<const N: usize> {
        pub org_x: [f32; N],
        pub org_y: [f32; N],
        pub org_z: [f32; N],
        pub tnear: [f32; N],
        pub dir_x: [f32; N],
        pub dir_y: [f32; N],
        pub dir_z: [f32; N],
        pub time: [f32; N],
        pub tfar: [f32; N],
        pub mask: [c_uint; N],
        pub id: [c_uint; N],
        pub flags: [c_uint; N],
    }

    /// `struct RTCHit8` or `struct RTCHit16`, one instance level, aligned
    /// as [`RayN`].
    #[repr(C, align(64))]
    #[derive(Clone, Copy)]
    pub struct HitN<const N: usize> {
        pub ng_x: [f32; N],
        pub ng_y: [f32; N],
        pub ng_z: [f32; N],
        pub u: [f32; N],
        pub v: [f32; N],
        pub prim_id: [c_uint; N],
        pub geom_id: [c_uint; N],
        pub inst_id: [[c_uint; N]; 1],
    }

    /// `struct RTCRayHit8` or `struct RTCRayHit16`.
    #[repr(C)]
    #[derive(Clone, Copy)]
    pub struct RayHitN<const N: usize> {
        pub ray: RayN<N>,
        pub hit: HitN<N>,
    }

    /// The `const int* valid` mask of a packet query: `-1` for an active
    /// lane, `0` for an inactive one. Aligned as the packet: the manual
    /// states the packet's alignment only, but Embree may read the mask as
    /// one vector, so the mask gets the same.
    #[repr(C, align(64))]
    #[derive(Clone, Copy)]
    pub struct Valid<const N: usize>(pub [c_int; N]);

    /// `rtcIntersect8` or `rtcIntersect16` for packets of `N` rays.
    pub type IntersectN<const N: usize> =
        unsafe extern "C" fn(*const c_int, Scene, *mut IntersectContext, *mut RayHitN<N>);
    /// `rtcOccluded8` or `rtcOccluded16` for packets of `N` rays.
    pub type OccludedN<const N: usize> =
        unsafe extern "C" fn(*const c_int, Scene, *mut IntersectContext, *mut RayN<N>);

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
        pub fn rtcIntersect8(
            valid: *const c_int,
            scene: Scene,
            context: *mut IntersectContext,
            rayhit: *mut RayHitN<8>,
        );
        pub fn rtcIntersect16(
            valid: *const c_int,
            scene: Scene,
            context: *mut IntersectContext,
            rayhit: *mut RayHitN<16>,
        );
        pub fn rtcOccluded8(
            valid: *const c_int,
            scene: Scene,
            context: *mut IntersectContext,
            ray: *mut RayN<8>,
        );
        pub fn rtcOccluded16(
            valid: *const c_int,
            scene: Scene,
            context: *mut IntersectContext,
            ray: *mut RayN<16>,
        );
    }

    // The layouts of rtcore_common.h and rtcore_ray.h on x86-64 (checked
    // against sizeof in C).
    const _: () = assert!(size_of::<IntersectContext>() == 24);
    const _: () = assert!(size_of::<RtcRay>() == 48 && align_of::<RtcRay>() == 16);
    const _: () = assert!(size_of::<RtcHit>() == 32 && align_of::<RtcHit>() == 16);
    const _: () = assert!(size_of::<RtcRayHit>() == 80);
    // The packets of rtcore_ray.h: sizes and the offset of `hit` as sizeof
    // and offsetof give in C; alignment at least the header's (32 for 8
    // rays, 64 for 16).
    const _: () = assert!(size_of::<RayN<8>>() == 384 && align_of::<RayN<8>>() >= 32);
    const _: () = assert!(size_of::<HitN<8>>() == 256 && align_of::<HitN<8>>() >= 32);
    const _: () = assert!(size_of::<RayHitN<8>>() == 640);
    const _: () = assert!(std::mem::offset_of!(RayHitN<8>, hit) == 384);
    const _: () = assert!(size_of::<RayN<16>>() == 768 && align_of::<RayN<16>>() == 64);
    const _: () = assert!(size_of::<HitN<16>>() == 512 && align_of::<HitN<16>>() == 64);
    const _: () = assert!(size_of::<RayHitN<16>>() == 1280);
    const _: () = assert!(std::mem::offset_of!(RayHitN<16>, hit) == 768);
    const _: () = assert!(std::mem::offset_of!(RayN<16>, tfar) == 512);
    const _: () = assert!(std::mem::offset_of!(HitN<16>, prim_id) == 320);
    const _: () = assert!(size_of::<Valid<16>>() == 64 && align_of::<Valid<8>>() == 64);
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

/// `rtcInitIntersectContext`, an inline function of the header, with
/// `RTC_INTERSECT_CONTEXT_FLAG_COHERENT` for coherent rays.
fn context(coherent: bool) -> ffi::IntersectContext {
    ffi::IntersectContext {
        flags: if coherent {
            ffi::INTERSECT_CONTEXT_FLAG_COHERENT
        } else {
            ffi::INTERSECT_CONTEXT_FLAG_INCOHERENT
        },
        filter: None,
        inst_id: [ffi::INVALID_GEOMETRY_ID],
    }
}

/// The packet widths of [`EmbreePeer`], widest first.
pub const PACKET_WIDTHS: [usize; 2] = [16, 8];

/// A packet of `N` lanes holding `rays` and its valid mask: lanes past
/// `rays.len()` repeat the first ray and are inactive.
///
/// # Panics
/// If there are no rays or more than `N`.
fn packet<const N: usize>(rays: &[OurRay<f32>]) -> (ffi::Valid<N>, ffi::RayN<N>) {
    assert!(
        !rays.is_empty() && rays.len() <= N,
        "{} rays in a packet of {N}",
        rays.len()
    );
    let mut valid = ffi::Valid([0; N]);
    let mut p = ffi::RayN {
        org_x: [0.0; N],
        org_y: [0.0; N],
        org_z: [0.0; N],
        tnear: [0.0; N],
        dir_x: [0.0; N],
        dir_y: [0.0; N],
        dir_z: [0.0; N],
        time: [0.0; N],
        tfar: [0.0; N],
        mask: [c_uint::MAX; N],
        id: [0; N],
        flags: [0; N],
    };
    for lane in 0..N {
        let (r, active) = rays.get(lane).map_or((&rays[0], false), |r| (r, true));
        valid.0[lane] = if active { -1 } else { 0 };
        p.org_x[lane] = r.origin.x;
        p.org_y[lane] = r.origin.y;
        p.org_z[lane] = r.origin.z;
        p.tnear[lane] = r.t_min;
        p.dir_x[lane] = r.direction.x;
        p.dir_y[lane] = r.direction.y;
        p.dir_z[lane] = r.direction.z;
        p.tfar[lane] = r.t_max;
    }
    (valid, p)
}

impl EmbreePeer {
    /// [`Tracer::nearest_packet`] through `intersect`, Embree's query for
    /// packets of `N` rays.
    fn nearest_n<const N: usize>(
        &self,
        intersect: ffi::IntersectN<N>,
        coherent: bool,
        rays: &[OurRay<f32>],
        out: &mut [Option<PeerHit>],
    ) {
        assert_eq!(rays.len(), out.len(), "one answer per ray of the packet");
        if rays.is_empty() {
            return;
        }
        let (valid, ray) = packet::<N>(rays);
        let none = [ffi::INVALID_GEOMETRY_ID; N];
        let mut rh = ffi::RayHitN {
            ray,
            hit: ffi::HitN {
                ng_x: [0.0; N],
                ng_y: [0.0; N],
                ng_z: [0.0; N],
                u: [0.0; N],
                v: [0.0; N],
                prim_id: none,
                geom_id: none,
                inst_id: [none],
            },
        };
        let mut ctx = context(coherent);
        // SAFETY: the scene is live and committed; `valid` and `rh` are
        // Embree's layouts for packets of N rays (checked in `ffi`), 64-byte
        // aligned as rtcIntersect8/16 require, fully initialised, every
        // active lane a valid ray, and live for the call; `ctx` is
        // initialised as rtcInitIntersectContext would.
        unsafe {
            intersect(
                valid.0.as_ptr(),
                self.scene.as_ptr(),
                &raw mut ctx,
                &raw mut rh,
            );
        }
        for (lane, answer) in out.iter_mut().enumerate() {
            *answer = (rh.hit.geom_id[lane] != ffi::INVALID_GEOMETRY_ID).then_some(PeerHit {
                t: rh.ray.tfar[lane],
                prim: rh.hit.prim_id[lane],
            });
        }
    }

    /// [`Tracer::occluded_packet`] through `occluded`, Embree's query for
    /// packets of `N` rays.
    fn occluded_n<const N: usize>(
        &self,
        occluded: ffi::OccludedN<N>,
        coherent: bool,
        rays: &[OurRay<f32>],
        out: &mut [bool],
    ) {
        assert_eq!(rays.len(), out.len(), "one answer per ray of the packet");
        if rays.is_empty() {
            return;
        }
        let (valid, mut ray) = packet::<N>(rays);
        let mut ctx = context(coherent);
        // SAFETY: as for `nearest_n`; Embree sets `tfar` of each active
        // lane that hits to -inf and leaves the other lanes alone.
        unsafe {
            occluded(
                valid.0.as_ptr(),
                self.scene.as_ptr(),
                &raw mut ctx,
                &raw mut ray,
            );
        }
        for (lane, answer) in out.iter_mut().enumerate() {
            *answer = ray.tfar[lane] == f32::NEG_INFINITY;
        }
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
        let mut ctx = context(false);
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
        let mut ctx = context(false);
        let mut r = rtc_ray(ray);
        // SAFETY: as for rtcIntersect1; Embree sets `tfar` to -inf on a hit.
        unsafe { ffi::rtcOccluded1(self.scene.as_ptr(), &raw mut ctx, &raw mut r) };
        r.tfar == f32::NEG_INFINITY
    }

    fn packet_widths(&self) -> &'static [usize] {
        &PACKET_WIDTHS
    }

    fn nearest_packet(
        &self,
        width: usize,
        coherent: bool,
        rays: &[OurRay<f32>],
        out: &mut [Option<PeerHit>],
    ) {
        match width {
            16 => self.nearest_n::<16>(ffi::rtcIntersect16, coherent, rays, out),
            8 => self.nearest_n::<8>(ffi::rtcIntersect8, coherent, rays, out),
            _ => panic!("Embree has no packets of {width} rays here"),
        }
    }

    fn occluded_packet(
        &self,
        width: usize,
        coherent: bool,
        rays: &[OurRay<f32>],
        out: &mut [bool],
    ) {
        match width {
            16 => self.occluded_n::<16>(ffi::rtcOccluded16, coherent, rays, out),
            8 => self.occluded_n::<8>(ffi::rtcOccluded8, coherent, rays, out),
            _ => panic!("Embree has no packets of {width} rays here"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::peers::{PeerMesh, SetAnswers, compare, packet_answers};

    /// Embree's packets, 16 and 8 wide, coherent or not, with a short last
    /// packet, answer as `rtcIntersect1` and `rtcOccluded1` do (triangle,
    /// hit or miss, `t` within tolerance), in both modes: on random rays
    /// through the default scene, on its camera's rays by 8 × 8 tiles, and
    /// on both sets shortened to end halfway to their nearest hit. A
    /// nearest hit may name another triangle at the same `t` (a tie where
    /// an object touches the floor), on at most 2 of the rays.
    #[test]
    fn packets_agree_with_single_rays() {
        let scene = render::scene::default_scene().unwrap();
        let mesh = scene.mesh.cast::<f32>().unwrap();
        let peer_mesh = PeerMesh::new(&mesh);
        let random: Vec<OurRay<f32>> = accel_scenes::random_rays(&scene.mesh.bounds(), 2001, 0xB0B);
        let (w, h) = (37, 23);
        let camera = render::bench::by_tiles(&scene.view.camera.rays(w, h), w as usize, 8);
        assert_eq!(camera.len(), 851);
        for build in [build_default, build_robust] {
            let peer = build(&peer_mesh).unwrap().tracer;
            assert_eq!(peer.packet_widths(), PACKET_WIDTHS);
            for rays in [&random, &camera] {
                // Every width leaves a short last packet.
                assert!(PACKET_WIDTHS.iter().all(|&p| !rays.len().is_multiple_of(p)));
                let single: Vec<Option<PeerHit>> = rays.iter().map(|r| peer.nearest(r)).collect();
                let hits = single.iter().filter(|h| h.is_some()).count();
                assert!(hits > 100 && hits + 100 < rays.len(), "{hits} hits");
                let halfway: Vec<OurRay<f32>> = rays
                    .iter()
                    .zip(&single)
                    .map(|(r, h)| OurRay {
                        t_max: h.map_or(r.t_max, |h| r.t_min + (h.t - r.t_min) * 0.5),
                        ..*r
                    })
                    .collect();
                let nearest = SetAnswers::Nearest(single);
                for (set, any_reference) in [(rays, true), (&halfway, false)] {
                    let blocked: Vec<bool> = set.iter().map(|r| peer.occluded(r)).collect();
                    // Whole rays are blocked where they hit; halfway ones
                    // are clear.
                    assert_eq!(
                        blocked.iter().filter(|&&b| b).count(),
                        if any_reference { hits } else { 0 }
                    );
                    let blocked = SetAnswers::Occluded(blocked);
                    for width in PACKET_WIDTHS {
                        for coherent in [false, true] {
                            let what = format!("packets of {width}, coherent {coherent}");
                            let any = packet_answers(peer.as_ref(), width, coherent, true, set);
                            let a = compare(&blocked, "rtcOccluded1", &any, &what, set, 3);
                            assert!(a.agrees(), "{a:?}");
                            if any_reference {
                                let got =
                                    packet_answers(peer.as_ref(), width, coherent, false, set);
                                let a = compare(&nearest, "rtcIntersect1", &got, &what, set, 3);
                                // The same hit or miss and `t` everywhere;
                                // another triangle only at the same `t`,
                                // a tie the packet kernels round their
                                // own way (objects stand on the floor).
                                assert_eq!((a.hit_miss, a.t), (0, 0), "{a:?}");
                                assert!(a.prim <= 2, "{a:?}");
                            }
                        }
                    }
                }
            }
        }
    }

    /// A packet of one ray answers only that ray; a packet too wide for
    /// its width is refused.
    #[test]
    fn a_short_packet_answers_only_its_rays() {
        let tri = PeerMesh {
            positions: vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]],
            indices: vec![[0, 1, 2]],
        };
        let peer = build_default(&tri).unwrap().tracer;
        let up = OurRay {
            origin: accel_core::Vec3::new(0.25, 0.25, 0.0),
            direction: accel_core::Vec3::new(0.0, 0.0, 2.0),
            t_min: 0.0,
            t_max: f32::INFINITY,
        };
        for width in PACKET_WIDTHS {
            let mut out = [None; 1];
            peer.nearest_packet(width, false, &[up], &mut out);
            assert_eq!(out, [Some(PeerHit { t: 0.5, prim: 0 })]);
            let mut any = [false; 2];
            let down = OurRay {
                direction: -up.direction,
                ..up
            };
            peer.occluded_packet(width, true, &[down, up], &mut any);
            assert_eq!(any, [false, true]);
        }
        let too_many = vec![up; 9];
        let mut out = [None; 9];
        let refused = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            peer.nearest_packet(8, false, &too_many, &mut out);
        }));
        assert!(refused.is_err());
    }
}
