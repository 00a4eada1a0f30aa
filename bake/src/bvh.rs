//! Ray casting against a whole [`Scene`]: every mesh's triangles in one compressed wide BVH
//! (obvhs' CWBVH), with a watertight triangle test; or, chosen by [`RayBackend`], in Embree 3's
//! BVH (builds with the `embree` feature).
//!
//! The path tracer and the bakers reach the geometry only through [`SceneBvh::closest_hit`] and
//! [`SceneBvh::occluded`] (plus [`SceneBvh::offset_origin`] for leaving a surface), so the
//! backend is replaced behind those three calls and nothing else sees it.
//!
//! Two facts about obvhs shape this file:
//! - The primitive ids its traversal hands to the intersection closure are positions in the
//!   BVH's leaf order, not input order. The triangles are therefore copied into leaf order
//!   once at build time (`leaf_triangles`), and `leaf_primitive` maps a leaf slot back to the
//!   scene's triangle.
//! - Its box test never reports boxes closer than a fixed 1e-4 along the ray, so each ray is
//!   traced from 1e-4 behind its origin and only hits past the origin count (`behind`); else
//!   geometry nearer than that to the origin, such as the other wall of a corner, is missed.
//!   Rays that leave a surface start [`SceneBvh::epsilon`] off it (at least 1e-4, more in
//!   large scenes, where f32 positions are coarser), along the geometric normal, on the side
//!   the ray leaves to, so the shifted start stays on that side too.

use crate::scene::Scene;
use glam::{Mat3A, Vec2, Vec3, Vec3A};
use obvhs::{
    cwbvh::{builder::build_cwbvh_from_tris, CwBvh},
    ray::{Ray, RayHit},
    triangle::Triangle,
    BvhBuildParams,
};
use std::time::Duration;

/// A ray's closest intersection, with what shading needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// The hit point, interpolated from the triangle's vertices (more precise than o + t d).
    pub position: Vec3,
    /// Unit normal of the triangle's plane on its front side: counter-clockwise winding, as
    /// glTF defines front faces. Not flipped towards the ray.
    pub geometric_normal: Vec3,
    /// The mesh's vertex normals interpolated and renormalised (the geometric normal where
    /// they cancel out). Not flipped towards the ray.
    pub shading_normal: Vec3,
    /// Barycentric weights of the triangle's second and third vertices (the first has
    /// 1 - x - y).
    pub barycentrics: Vec2,
    /// Interpolated first texture coordinate (zero when the mesh has none).
    pub uv0: Vec2,
    /// Index into [`Scene::meshes`].
    pub mesh: u32,
    /// Triangle index within that mesh (its indices are `3 * triangle ..`).
    pub triangle: u32,
    /// Index of the triangle in the scene's flattened triangle list (meshes in order); see
    /// [`SceneBvh::primitive_index`].
    pub primitive: u32,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

/// Per-triangle shading data in the scene's flattened order.
#[derive(Clone, Copy, Debug)]
struct Primitive {
    positions: [Vec3; 3],
    normals: [Vec3; 3],
    uvs: [Vec2; 3],
    mesh: u32,
    triangle: u32,
    material: u32,
}

/// Which library casts the rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RayBackend {
    /// obvhs' CWBVH and relume's watertight test: in every build, the default.
    #[default]
    Obvhs,
    /// Embree 3 in its robust (watertight) mode, Debian's `libembree-dev`: only in builds with
    /// the `embree` feature. Its kernels are chosen for the CPU at run time, so its bytes may
    /// differ between CPUs (never between thread counts).
    Embree,
}

impl RayBackend {
    pub const NAMES: [&'static str; 2] = ["obvhs", "embree"];

    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// The backend named `name`; refuses Embree in a build without it, saying how to get it.
    pub fn parse(name: &str) -> Result<RayBackend, String> {
        match name {
            "obvhs" => Ok(RayBackend::Obvhs),
            "embree" if cfg!(feature = "embree") => Ok(RayBackend::Embree),
            "embree" => Err("this relume was built without Embree: build it with `cargo build --release -p relume-tools --features embree` (needs Debian's libembree-dev), or use obvhs".into()),
            _ => Err(format!("unknown ray backend {name:?}: one of {}", Self::NAMES.join(", "))),
        }
    }
}

/// obvhs' BVH over the triangles, in the order its leaves list them.
struct Obvhs {
    bvh: CwBvh,
    /// Triangle vertices in the BVH's leaf order, for the intersection test.
    leaf_triangles: Vec<[Vec3A; 3]>,
    /// Flattened scene triangle of each leaf slot.
    leaf_primitive: Vec<u32>,
}

enum Caster {
    /// None for a scene without triangles (obvhs builds no empty BVH).
    Obvhs(Option<Obvhs>),
    #[cfg(feature = "embree")]
    Embree(crate::embree::EmbreeScene),
}

/// The scene's triangles in a BVH, owning copies of the data a hit reports (no borrow of the
/// scene, so it can be built once and shared between threads).
pub struct SceneBvh {
    caster: Caster,
    primitives: Vec<Primitive>,
    /// First flattened index of each mesh.
    mesh_offsets: Vec<u32>,
    epsilon: f32,
}

impl SceneBvh {
    /// Builds obvhs' BVH over every triangle of every mesh.
    pub fn new(scene: &Scene) -> Self {
        let primitives = primitives(scene);
        let caster = Caster::Obvhs(Obvhs::build(&primitives));
        Self::with_caster(scene, caster, primitives)
    }

    /// Builds `backend`'s BVH over every triangle of every mesh.
    pub fn build(scene: &Scene, backend: RayBackend) -> Result<Self, String> {
        match backend {
            RayBackend::Obvhs => Ok(Self::new(scene)),
            #[cfg(feature = "embree")]
            // One build thread: Embree's tree, and so which of two triangles meeting at an
            // edge a ray reports, must not depend on the thread count.
            RayBackend::Embree => {
                let caster = Caster::Embree(crate::embree::EmbreeScene::new(scene, Some(1), true)?);
                Ok(Self::with_caster(scene, caster, primitives(scene)))
            }
            #[cfg(not(feature = "embree"))]
            RayBackend::Embree => Err(RayBackend::parse("embree").unwrap_err()),
        }
    }

    fn with_caster(scene: &Scene, caster: Caster, primitives: Vec<Primitive>) -> Self {
        let (lo, hi) = scene.bounds();
        let magnitude = if primitives.is_empty() { 0.0 } else { lo.abs().max(hi.abs()).max_element() };
        let mesh_offsets = scene
            .meshes
            .iter()
            .scan(0, |first, mesh| {
                let at = *first;
                *first += (mesh.indices.len() / 3) as u32;
                Some(at)
            })
            .collect();
        SceneBvh { caster, primitives, mesh_offsets, epsilon: 1e-4 + 1e-5 * magnitude }
    }

    pub fn triangle_count(&self) -> usize {
        self.primitives.len()
    }

    /// The flattened index of a mesh's triangle, as [`Hit::primitive`] reports it.
    pub fn primitive_index(&self, mesh: usize, triangle: usize) -> u32 {
        self.mesh_offsets[mesh] + triangle as u32
    }

    /// The three world-space vertices of a flattened triangle.
    pub fn primitive_positions(&self, primitive: u32) -> [Vec3; 3] {
        self.primitives[primitive as usize].positions
    }

    /// The material of a flattened triangle.
    pub fn primitive_material(&self, primitive: u32) -> u32 {
        self.primitives[primitive as usize].material
    }

    /// How far rays start off a surface: 1e-4 (obvhs' minimum box distance, which the traced
    /// ray's start is moved back by, so it stays off the surface it leaves) plus 1e-5 of the
    /// largest coordinate magnitude in the scene (about 170 f32 ulps there), which covers
    /// the rounding of hit positions.
    pub fn epsilon(&self) -> f32 {
        self.epsilon
    }

    /// A ray origin for leaving the surface at `point` in direction `dir`: moved
    /// [`Self::epsilon`] along the geometric normal, to the side `dir` points to, so the ray
    /// cannot hit the surface it starts on.
    #[inline]
    pub fn offset_origin(&self, point: Vec3, geometric_normal: Vec3, dir: Vec3) -> Vec3 {
        let side = if geometric_normal.dot(dir) >= 0.0 { 1.0 } else { -1.0 };
        point + geometric_normal * (side * self.epsilon)
    }

    /// The closest triangle the ray `origin + t dir`, 0 < t < `t_max`, hits. `dir` should be
    /// unit length so that `t` is a distance.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        let (primitive, t, barycentrics) = self.closest(origin, dir, t_max)?;
        Some(self.make_hit(primitive, t, barycentrics))
    }

    /// The distance to [`Self::closest_hit`]'s triangle, without the hit's data (what `relume
    /// rays` times, as Embree alone returns only the distance).
    pub fn closest_distance(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<f32> {
        self.closest(origin, dir, t_max).map(|(_, t, _)| t)
    }

    fn closest(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(u32, f32, Vec2)> {
        match &self.caster {
            Caster::Obvhs(bvh) => bvh.as_ref()?.closest(origin, dir, t_max),
            #[cfg(feature = "embree")]
            Caster::Embree(embree) => embree.closest(origin, dir, t_max),
        }
    }

    /// Whether anything blocks the ray `origin + t dir` for 0 < t < `t_max` (a shadow ray;
    /// stops at the first blocker found, not the closest).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        match &self.caster {
            Caster::Obvhs(bvh) => bvh.as_ref().is_some_and(|bvh| bvh.occluded(origin, dir, t_max)),
            #[cfg(feature = "embree")]
            Caster::Embree(embree) => embree.occluded(origin, dir, t_max),
        }
    }

    /// Whether nothing blocks the segment between two points in free space (no offsets: for
    /// points off every surface, such as lights).
    pub fn visible(&self, a: Vec3, b: Vec3) -> bool {
        let length = a.distance(b);
        length == 0.0 || !self.occluded(a, (b - a) / length, length)
    }

    fn make_hit(&self, primitive: u32, t: f32, bary: Vec2) -> Hit {
        let p = &self.primitives[primitive as usize];
        let w = Vec3::new(1.0 - bary.x - bary.y, bary.x, bary.y);
        let [p0, p1, p2] = p.positions;
        let geometric_normal = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        let shading = p.normals[0] * w.x + p.normals[1] * w.y + p.normals[2] * w.z;
        let shading_normal = shading.try_normalize().unwrap_or(geometric_normal);
        Hit {
            t,
            position: p0 * w.x + p1 * w.y + p2 * w.z,
            geometric_normal,
            shading_normal,
            barycentrics: bary,
            uv0: p.uvs[0] * w.x + p.uvs[1] * w.y + p.uvs[2] * w.z,
            mesh: p.mesh,
            triangle: p.triangle,
            primitive,
            material: p.material,
        }
    }
}

/// Every triangle of every mesh, meshes in order: the flattened order hits report.
fn primitives(scene: &Scene) -> Vec<Primitive> {
    let mut primitives = Vec::with_capacity(scene.triangle_count());
    for (mesh_index, mesh) in scene.meshes.iter().enumerate() {
        for (triangle, idx) in mesh.indices.chunks_exact(3).enumerate() {
            let i = [idx[0] as usize, idx[1] as usize, idx[2] as usize];
            let uv = |k: usize| mesh.uv0.as_ref().map_or(Vec2::ZERO, |uv| uv[i[k]]);
            primitives.push(Primitive {
                positions: i.map(|k| mesh.positions[k]),
                normals: i.map(|k| mesh.normals[k]),
                uvs: [uv(0), uv(1), uv(2)],
                mesh: mesh_index as u32,
                triangle: triangle as u32,
                material: mesh.material as u32,
            });
        }
    }
    primitives
}

impl Obvhs {
    /// None for no triangles.
    fn build(primitives: &[Primitive]) -> Option<Obvhs> {
        let triangles: Vec<Triangle> = primitives
            .iter()
            .map(|p| Triangle { v0: p.positions[0].into(), v1: p.positions[1].into(), v2: p.positions[2].into() })
            .collect();
        if triangles.is_empty() {
            return None;
        }
        // The slowest preset: its full reinsertion and wide search from the first merge keep
        // finely triangulated scenes traversable (medium_build's BVH cast 5x fewer rays on
        // classroom split 32 x 32, 2.6x fewer on glossy-enclosure: docs/BENCHMARKS.md,
        // "Ray casting"). Its pre-split may list a triangle in several leaves.
        let bvh = build_cwbvh_from_tris(&triangles, BvhBuildParams::very_slow_build(), &mut Duration::default());
        let leaf_triangles = bvh
            .primitive_indices
            .iter()
            .map(|&i| {
                let t = &triangles[i as usize];
                [t.v0, t.v1, t.v2]
            })
            .collect();
        let leaf_primitive = bvh.primitive_indices.clone();
        Some(Obvhs { bvh, leaf_triangles, leaf_primitive })
    }

    /// (flattened triangle, t, barycentrics) of the closest hit.
    fn closest(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(u32, f32, Vec2)> {
        let (ray, wt) = behind(origin, dir, t_max);
        let mut hit = RayHit::none();
        let mut best = Vec2::ZERO;
        let found = self.bvh.ray_traverse(ray, &mut hit, |r, leaf| match wt.intersect(&self.leaf_triangles[leaf], OBVHS_NEAREST, r.tmax) {
            Some((t, b1, b2)) => {
                best = Vec2::new(b1, b2);
                t
            }
            None => f32::INFINITY,
        });
        found.then(|| (self.leaf_primitive[hit.primitive_id as usize], hit.t - OBVHS_NEAREST, best))
    }

    fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        let (ray, wt) = behind(origin, dir, t_max);
        let blocker = |r: &Ray, leaf: usize| wt.intersect(&self.leaf_triangles[leaf], OBVHS_NEAREST, r.tmax).map_or(f32::INFINITY, |h| h.0);
        !self.bvh.ray_traverse_miss(ray, blocker)
    }
}

/// How near a ray's origin obvhs' box test stops seeing boxes (its `cwbvh::node::EPSILON`).
const OBVHS_NEAREST: f32 = 1e-4;

/// The ray `origin + t dir` started `OBVHS_NEAREST` behind its origin, for obvhs and for the
/// triangle test, which then takes only hits past the origin. Started at the origin, a ray
/// within 1e-4 of the other wall of a corner went through it (7 of about 262,000 paths left
/// glossy-enclosure's closed room so: docs/BENCHMARKS.md, "Ray casting"). Beyond t_max of
/// about 2,000 the added 1e-4 rounds away and the ray ends that much short: below rounding.
fn behind(origin: Vec3, dir: Vec3, t_max: f32) -> (Ray, WatertightRay) {
    let dir = positive_zeros(dir);
    let start = origin - dir * OBVHS_NEAREST;
    (Ray::new(start.into(), dir.into(), 0.0, t_max + OBVHS_NEAREST), WatertightRay::new(start, dir))
}

/// Per-ray constants of the watertight ray/triangle test of Woop, Benthin and Wald,
/// "Watertight Ray/Triangle Intersection" (JCGT 2(1), 2013): vertices are moved to the ray's
/// origin and sheared so the ray becomes the +z axis; the three 2D edge functions are then
/// evaluated identically for the two triangles that share an edge, so no ray slips between
/// neighbours. That matters for the analytic tests: a ray leaking out of a closed furnace
/// would read black.
struct WatertightRay {
    origin: Vec3A,
    /// Rows (Sx, Sy, Sz) of the shear as a matrix, so one vertex is transformed with three
    /// SIMD multiply-adds. Each row has one exact zero, so every component is rounded exactly
    /// as the paper's scalar code rounds it and watertightness is kept.
    shear: Mat3A,
}

/// Rows of the shear for dominant axis `kz` (direction component, unit axis) and the other
/// two axes `kx`, `ky` in cyclic order, swapped when the dominant component is negative so
/// the winding is kept. Written without indexed stores.
#[inline(always)]
fn axis_shear((dz, ez): (f32, Vec3A), kx: (f32, Vec3A), ky: (f32, Vec3A)) -> [Vec3A; 3] {
    let ((dx, ex), (dy, ey)) = if dz < 0.0 { (ky, kx) } else { (kx, ky) };
    [ex - ez * (dx / dz), ey - ez * (dy / dz), ez / dz]
}

impl WatertightRay {
    #[inline]
    fn new(origin: Vec3, dir: Vec3) -> Self {
        // kz: the dominant axis; kx, ky the other two in cyclic order.
        let a = dir.abs();
        let (x, y, z) = (dir.x, dir.y, dir.z);
        let shear = if a.z >= a.x && a.z >= a.y {
            axis_shear((z, Vec3A::Z), (x, Vec3A::X), (y, Vec3A::Y))
        } else if a.x >= a.y {
            axis_shear((x, Vec3A::X), (y, Vec3A::Y), (z, Vec3A::Z))
        } else {
            axis_shear((y, Vec3A::Y), (z, Vec3A::Z), (x, Vec3A::X))
        };
        WatertightRay { origin: origin.into(), shear: Mat3A::from_cols(shear[0], shear[1], shear[2]).transpose() }
    }

    /// (t, b1, b2) of a hit with t_min < t < t_max, or None.
    #[inline(always)]
    fn intersect(&self, tri: &[Vec3A; 3], t_min: f32, t_max: f32) -> Option<(f32, f32, f32)> {
        let a = self.shear * (tri[0] - self.origin);
        let b = self.shear * (tri[1] - self.origin);
        let c = self.shear * (tri[2] - self.origin);
        let mut u = c.x * b.y - c.y * b.x;
        let mut v = a.x * c.y - a.y * c.x;
        let mut w = b.x * a.y - b.y * a.x;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // On an edge in single precision: decide it in double, as the paper does, so the
            // two triangles sharing the edge still agree.
            let e = |px: f32, py: f32, qx: f32, qy: f32| (px as f64 * qy as f64 - py as f64 * qx as f64) as f32;
            u = e(c.x, c.y, b.x, b.y);
            v = e(a.x, a.y, c.x, c.y);
            w = e(b.x, b.y, a.x, a.y);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * a.z + v * b.z + w * c.z;
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        if !(t > t_min && t < t_max) {
            return None;
        }
        Some((t, v * inv, w * inv))
    }
}

/// `dir` with any -0.0 component made +0.0: a ray along an axis whose other components are
/// -0.0 (the negation of a light pointing straight down, (0, -1, 0)) passed through every
/// triangle in the traversal (a sunroom's ceiling let a vertical sun through).
fn positive_zeros(dir: Vec3) -> Vec3 {
    Vec3::select(dir.cmpeq(Vec3::ZERO), Vec3::ZERO, dir)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{look_at, material, scene, square};

    fn single(tri: [Vec3; 3]) -> [Vec3A; 3] {
        tri.map(Vec3A::from)
    }

    #[test]
    fn watertight_test_reports_distance_and_barycentrics() {
        let tri = single([Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)]);
        let ray = WatertightRay::new(Vec3::new(0.25, 0.5, 2.0), Vec3::NEG_Z);
        let (t, b1, b2) = ray.intersect(&tri, 0.0, f32::INFINITY).unwrap();
        assert!((t - 2.0).abs() < 1e-6 && (b1 - 0.25).abs() < 1e-6 && (b2 - 0.5).abs() < 1e-6);
        // From behind too (surfaces are two-sided for intersection).
        let ray = WatertightRay::new(Vec3::new(0.25, 0.5, -3.0), Vec3::Z);
        let (t, b1, b2) = ray.intersect(&tri, 0.0, f32::INFINITY).unwrap();
        assert!((t - 3.0).abs() < 1e-6 && (b1 - 0.25).abs() < 1e-6 && (b2 - 0.5).abs() < 1e-6);
        assert!(ray.intersect(&tri, 0.0, 2.5).is_none());
        let miss = WatertightRay::new(Vec3::new(0.75, 0.5, 2.0), Vec3::NEG_Z);
        assert!(miss.intersect(&tri, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn shared_edge_is_hit_by_exactly_one_or_both_never_neither() {
        // Two triangles of a quad, rays aimed along the shared diagonal in many directions.
        let q = [Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(-1.0, 1.0, 0.0)];
        let t0 = single([q[0], q[1], q[2]]);
        let t1 = single([q[0], q[2], q[3]]);
        for i in 0..2000 {
            let s = i as f32 / 2000.0;
            let target = Vec3::new(-0.9 + 1.8 * s, -0.9 + 1.8 * s, 0.0);
            let origin = Vec3::new(0.3 * (i as f32).sin(), 0.7 * (i as f32 * 1.3).cos(), 1.0 + s);
            let dir = (target - origin).normalize();
            let ray = WatertightRay::new(origin, dir);
            let hits = ray.intersect(&t0, 0.0, f32::INFINITY).is_some() as u32 + ray.intersect(&t1, 0.0, f32::INFINITY).is_some() as u32;
            assert!(hits >= 1, "ray {i} slipped through the shared edge");
        }
    }

    /// The BVH of `meshes` in one white material.
    fn bvh_of(meshes: Vec<crate::scene::Mesh>) -> SceneBvh {
        let m = vec![material("m", Vec3::ONE, Vec3::ZERO)];
        SceneBvh::new(&scene("surfaces", meshes, m, vec![], look_at(Vec3::Y, Vec3::ZERO, Vec3::Z, 1.0)))
    }

    /// A ray leaving a floor within 1e-4 of the wall it meets (a corner) hits that wall; traced
    /// from its origin, obvhs' box test skipped the wall.
    #[test]
    fn a_ray_from_a_corner_meets_the_wall_beside_it() {
        let wall = square(Vec3::new(0.6, 0.5, 0.0), Vec3::Y * 0.5, Vec3::Z * 0.5, 2, 0);
        let floor = square(Vec3::ZERO, Vec3::X * 0.6, Vec3::NEG_Z * 0.5, 2, 0);
        let bvh = bvh_of(vec![wall, floor]);
        let origin = bvh.offset_origin(Vec3::new(0.59995, 0.0, 0.1), Vec3::Y, Vec3::Y);
        let dir = Vec3::new(1.0, 1.0, 0.0).normalize();
        let hit = bvh.closest_hit(origin, dir, f32::INFINITY).expect("the wall 5e-5 away");
        assert!((hit.position.x - 0.6).abs() < 1e-6 && (hit.t - 5e-5 * 2f32.sqrt()).abs() < 1e-6, "{hit:?}");
        assert!(bvh.occluded(origin, dir, 1.0));
        assert!(!bvh.occluded(origin, dir, 5e-5), "the wall lies beyond a shorter ray");
    }

    /// A ray straight up from a floor meets the ceiling whether its other components are +0.0
    /// or -0.0 (the second once missed), and so does one a hair off the axis.
    #[test]
    fn a_ray_along_an_axis_meets_the_ceiling_whatever_the_sign_of_its_zeros() {
        let ceiling = square(Vec3::new(0.0, 2.6, 0.0), Vec3::X * 2.0, Vec3::Z * 2.0, 4, 0);
        let floor = square(Vec3::ZERO, Vec3::X * 2.0, Vec3::NEG_Z * 2.0, 4, 0);
        let bvh = bvh_of(vec![ceiling, floor]);
        for dir in [Vec3::Y, -Vec3::NEG_Y, Vec3::new(1e-6, 1.0, 0.0).normalize()] {
            for origin in [Vec3::new(0.3, 0.001, 0.2), Vec3::new(-0.7, 0.001, 0.45)] {
                assert!(bvh.occluded(origin, dir, f32::INFINITY), "{dir:?} from {origin}");
                let hit = bvh.closest_hit(origin, dir, f32::INFINITY).map(|h| h.position.y);
                assert!(hit.is_some_and(|y| (y - 2.6).abs() < 1e-5), "{dir:?} from {origin}: {hit:?}");
            }
        }
    }
}
