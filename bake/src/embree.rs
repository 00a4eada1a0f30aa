//! Embree 3 (Debian's `libembree-dev`) as a second ray caster, behind the `embree` feature:
//! the yardstick `relume rays` measures relume's own BVH against, on the same triangles and the
//! same rays, and the backend `--ray-backend embree` puts behind [`crate::bvh::SceneBvh`] for
//! the path tracer and the bakers.
//!
//! The few declarations below mirror Embree 3.13's headers (`embree3/rtcore_*.h`) for a build
//! with one instance level and no minimum width, which is how Debian builds it.

use crate::ray_bench::{RayCaster, TracedRay};
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use std::ffi::{c_char, c_void, CString};

type Device = *mut c_void;
type SceneHandle = *mut c_void;
type Geometry = *mut c_void;

const GEOMETRY_TYPE_TRIANGLE: u32 = 0;
const BUFFER_TYPE_INDEX: u32 = 0;
const BUFFER_TYPE_VERTEX: u32 = 1;
const FORMAT_UINT3: u32 = 0x5003;
const FORMAT_FLOAT3: u32 = 0x9003;
const INVALID_GEOMETRY_ID: u32 = u32::MAX;
/// RTC_SCENE_FLAG_ROBUST: "avoid optimizations that reduce arithmetic accuracy".
const SCENE_FLAG_ROBUST: u32 = 1 << 2;

#[repr(C)]
struct IntersectContext {
    flags: u32,
    filter: *const c_void,
    inst_id: [u32; 1],
}

#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Ray {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Hit {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
}

#[repr(C, align(16))]
struct RayHit {
    ray: Ray,
    hit: Hit,
}

#[link(name = "embree3")]
extern "C" {
    fn rtcNewDevice(config: *const c_char) -> Device;
    fn rtcReleaseDevice(device: Device);
    fn rtcGetDeviceError(device: Device) -> u32;
    fn rtcNewScene(device: Device) -> SceneHandle;
    fn rtcReleaseScene(scene: SceneHandle);
    fn rtcNewGeometry(device: Device, kind: u32) -> Geometry;
    fn rtcSetNewGeometryBuffer(geometry: Geometry, kind: u32, slot: u32, format: u32, stride: usize, count: usize) -> *mut c_void;
    fn rtcCommitGeometry(geometry: Geometry);
    fn rtcAttachGeometry(scene: SceneHandle, geometry: Geometry) -> u32;
    fn rtcReleaseGeometry(geometry: Geometry);
    fn rtcSetSceneFlags(scene: SceneHandle, flags: u32);
    fn rtcCommitScene(scene: SceneHandle);
    fn rtcIntersect1(scene: SceneHandle, context: *mut IntersectContext, rayhit: *mut RayHit);
    fn rtcOccluded1(scene: SceneHandle, context: *mut IntersectContext, ray: *mut Ray);
}

/// Every triangle of a scene in one Embree triangle mesh (flattened like [`crate::bvh::SceneBvh`]).
pub struct EmbreeScene {
    device: Device,
    scene: SceneHandle,
}

// Embree's committed scenes are safe to trace from any number of threads at once.
unsafe impl Send for EmbreeScene {}
unsafe impl Sync for EmbreeScene {}

impl EmbreeScene {
    /// Builds Embree's BVH with `threads` build threads (None: all cores); `watertight` asks
    /// for its robust mode, whose triangle test lets no ray slip between two triangles that
    /// share an edge (relume's own test does the same), else its fastest.
    pub fn new(scene: &Scene, threads: Option<usize>, watertight: bool) -> Result<EmbreeScene, String> {
        let positions: Vec<[f32; 3]> = scene.meshes.iter().flat_map(|m| m.positions.iter().map(|p| p.to_array())).collect();
        let mut indices = Vec::with_capacity(scene.triangle_count());
        let mut base = 0u32;
        for mesh in &scene.meshes {
            indices.extend(mesh.indices.chunks_exact(3).map(|t| [t[0] + base, t[1] + base, t[2] + base]));
            base += mesh.positions.len() as u32;
        }
        let config = CString::new(threads.map_or(String::new(), |n| format!("threads={n}"))).expect("no NUL in the config");
        // SAFETY: every call below follows Embree's API contract: buffers are written within the
        // sizes given, the geometry is committed before it is attached and released after.
        unsafe {
            let device = rtcNewDevice(config.as_ptr());
            if device.is_null() {
                return Err("Embree could not create a device".into());
            }
            let embree = EmbreeScene { device, scene: rtcNewScene(device) };
            if watertight {
                rtcSetSceneFlags(embree.scene, SCENE_FLAG_ROBUST);
            }
            if !indices.is_empty() {
                let geometry = rtcNewGeometry(device, GEOMETRY_TYPE_TRIANGLE);
                let v = rtcSetNewGeometryBuffer(geometry, BUFFER_TYPE_VERTEX, 0, FORMAT_FLOAT3, 12, positions.len()) as *mut [f32; 3];
                let i = rtcSetNewGeometryBuffer(geometry, BUFFER_TYPE_INDEX, 0, FORMAT_UINT3, 12, indices.len()) as *mut [u32; 3];
                if v.is_null() || i.is_null() {
                    rtcReleaseGeometry(geometry);
                    return Err(format!("Embree could not allocate its buffers (error {})", rtcGetDeviceError(device)));
                }
                std::ptr::copy_nonoverlapping(positions.as_ptr(), v, positions.len());
                std::ptr::copy_nonoverlapping(indices.as_ptr(), i, indices.len());
                rtcCommitGeometry(geometry);
                rtcAttachGeometry(embree.scene, geometry);
                rtcReleaseGeometry(geometry);
            }
            rtcCommitScene(embree.scene);
            match rtcGetDeviceError(device) {
                0 => Ok(embree),
                code => Err(format!("Embree could not build the scene (error {code})")),
            }
        }
    }

    fn ray(origin: Vec3, dir: Vec3, t_max: f32) -> Ray {
        // Embree takes hits up to tfar included; relume's calls end short of t_max.
        let tfar = t_max.next_down();
        Ray { org: origin.to_array(), tnear: 0.0, dir: dir.to_array(), time: 0.0, tfar, mask: u32::MAX, id: 0, flags: 0 }
    }

    /// The closest triangle hit by `origin + t dir`, 0 <= t < `t_max`: its index in the
    /// scene's flattened triangle list (meshes in order), t, and the barycentric weights of its
    /// second and third vertices.
    pub fn closest(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(u32, f32, Vec2)> {
        let hit = Hit {
            ng: [0.0; 3],
            u: 0.0,
            v: 0.0,
            prim_id: INVALID_GEOMETRY_ID,
            geom_id: INVALID_GEOMETRY_ID,
            inst_id: [INVALID_GEOMETRY_ID],
        };
        let mut rayhit = RayHit { ray: Self::ray(origin, dir, t_max), hit };
        // SAFETY: a committed scene, a context and a ray hit laid out as Embree's.
        unsafe { rtcIntersect1(self.scene, &mut context(), &mut rayhit) };
        let found = rayhit.hit.geom_id != INVALID_GEOMETRY_ID;
        found.then(|| (rayhit.hit.prim_id, rayhit.ray.tfar, Vec2::new(rayhit.hit.u, rayhit.hit.v)))
    }

    /// Whether anything blocks `origin + t dir` for 0 <= t < `t_max`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        let mut r = Self::ray(origin, dir, t_max);
        // SAFETY: as above; Embree sets tfar to -inf when the ray is blocked.
        unsafe { rtcOccluded1(self.scene, &mut context(), &mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}

fn context() -> IntersectContext {
    IntersectContext { flags: 0, filter: std::ptr::null(), inst_id: [INVALID_GEOMETRY_ID] }
}

impl RayCaster for EmbreeScene {
    fn closest_t(&self, ray: &TracedRay) -> Option<f32> {
        self.closest(ray.origin, ray.dir, ray.t_max).map(|(_, t, _)| t)
    }

    fn occluded(&self, ray: &TracedRay) -> bool {
        EmbreeScene::occluded(self, ray.origin, ray.dir, ray.t_max)
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: the scene and device were made by Embree and are released once.
        unsafe {
            rtcReleaseScene(self.scene);
            rtcReleaseDevice(self.device);
        }
    }
}
