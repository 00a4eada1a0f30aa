//! The plain scene every stage of relume works on: world-space triangle meshes, materials,
//! punctual lights and one camera. Loaded from glTF 2.0 by [`crate::gltf_load`]; the renderer
//! uploads it as it is, the path tracer and the bakers trace it.
//!
//! Units follow glTF: metres, point and spot intensity in candela, directional in lux.
//! relume treats photometric units as radiometric ones one to one (1 cd is 1 W/sr of
//! linear radiance units), so the path tracer and the renderer agree by construction.

/// The largest light value relume takes where it enters (a light's intensity, an emission, an
/// environment texel and its intensity, a baked light map's value): sums and squares of such
/// values over a bake stay finite in f32 (1e18 against 3.4e38), where 1e38 turned a bake's
/// tables into NaN; the brightest real lights (the sun, about 1e5 lux) are far below it.
pub const MAX_LIGHT: f32 = 1e9;

/// The farthest a vertex or a light may lie from the origin, metres: a city of ten kilometres
/// in millimetres; past it f32 keeps no centimetre, and at 1e30 the BVH's and the camera's
/// sums overflow.
pub const MAX_COORDINATE: f32 = 1e7;

use crate::environment::Environment;
use crate::settings::SceneSettings;
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::path::PathBuf;

#[derive(Clone, Debug)]
pub struct Scene {
    /// The file the scene was loaded from (named in every error about it).
    pub source: PathBuf,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    /// The distant environment light (`extras.relume.environment`), if declared.
    pub environment: Option<Environment>,
    pub camera: Camera,
    /// The scene's relume settings (glTF `extras.relume`), defaults where it states none.
    pub settings: SceneSettings,
}

/// One glTF primitive with its node transform applied: positions and normals are in world space.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Unit normals, one per vertex; computed (area-weighted) when the file has none.
    pub normals: Vec<Vec3>,
    pub uv0: Option<Vec<Vec2>>,
    pub uv1: Option<Vec<Vec2>>,
    /// Triangle list, three indices per triangle, all in range.
    pub indices: Vec<u32>,
    pub material: usize,
}

#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    /// Linear base colour factor (glTF baseColorFactor); its rgb is the Lambertian albedo.
    pub base_color: Vec4,
    /// Index into [`Scene::textures`], sampled with uv0 and multiplied by `base_color`.
    pub base_color_texture: Option<usize>,
    /// Emitted radiance: emissiveFactor times KHR_materials_emissive_strength.
    pub emission: Vec3,
    /// A glossy lobe added to the Lambertian one (`extras.relume.phong`); None: Lambertian.
    pub phong: Option<Phong>,
}

/// The normalised modified Phong lobe (light-clouds spec C, "Reference glossy"):
/// f = rho_d / pi + rho_s (e + 2) / (2 pi) max(0, wi . reflect(wo))^e, with rho_d the
/// base colour and rho_d + rho_s <= 1 per channel, so no light is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    /// rho_s, linear rgb.
    pub specular: Vec3,
    /// e, >= 0.
    pub exponent: f32,
}

/// An sRGB-encoded image decoded to linear RGBA, row 0 at the top (v = 0), as glTF lays it out.
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec4>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    Point,
    /// Cone angles in radians from the spot axis; 0 <= inner < outer <= pi/2.
    Spot {
        inner_cone: f32,
        outer_cone: f32,
    },
    Directional,
}

#[derive(Clone, Debug)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    /// Linear colour times intensity: candela for point and spot, lux for directional.
    pub intensity: Vec3,
    /// glTF `range`: the distance at which the light's influence reaches zero, if set.
    pub range: Option<f32>,
    pub position: Vec3,
    /// Unit direction the light points (the node's -Z); unused by point lights.
    pub direction: Vec3,
}

/// A perspective camera looking down its local -Z with +Y up, as glTF defines it.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub world_from_camera: Mat4,
    /// Vertical field of view in radians.
    pub yfov: f32,
    pub znear: f32,
    pub zfar: f32,
}

impl Scene {
    /// Its point and spot lights: those that stand somewhere (a directional light's light
    /// comes from afar).
    pub fn local_lights(&self) -> impl Iterator<Item = &Light> {
        self.lights.iter().filter(|l| l.kind != LightKind::Directional)
    }

    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len() / 3).sum()
    }

    /// Axis-aligned bounds of every vertex in the scene.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        bounds_of(self.meshes.iter().flat_map(|m| &m.positions))
    }
}

impl Mesh {
    /// Axis-aligned bounds of the mesh's vertices.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        bounds_of(&self.positions)
    }
}

/// Axis-aligned bounds of `positions`.
pub(crate) fn bounds_of<'p>(positions: impl IntoIterator<Item = &'p Vec3>) -> (Vec3, Vec3) {
    positions.into_iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

impl Material {
    /// Lambertian albedo at a texture coordinate (uv0), `base_color` times the texture.
    pub fn albedo(&self, textures: &[Texture], uv: Vec2) -> Vec3 {
        let factor = self.base_color.truncate();
        match self.base_color_texture {
            Some(t) => factor * textures[t].sample_bilinear(uv).truncate(),
            None => factor,
        }
    }
}

impl Texture {
    /// Bilinear sample with repeat wrapping, texel centres at (i + 0.5) / width, as GPUs sample.
    pub fn sample_bilinear(&self, uv: Vec2) -> Vec4 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * w as f32 - 0.5;
        let y = uv.y * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |i: i64, j: i64| self.texels[(j.rem_euclid(h) * w + i.rem_euclid(w)) as usize];
        let (i, j) = (x0 as i64, y0 as i64);
        let top = texel(i, j).lerp(texel(i + 1, j), fx);
        let bottom = texel(i, j + 1).lerp(texel(i + 1, j + 1), fx);
        top.lerp(bottom, fy)
    }
}

/// What a punctual light delivers at a point: the unit direction towards the light, the
/// distance to it (infinite for directional lights) and the irradiance on a surface facing it.
#[derive(Clone, Copy, Debug)]
pub struct Incident {
    pub to_light: Vec3,
    pub distance: f32,
    pub irradiance: Vec3,
}

impl Light {
    /// Incident light at `point`, before the cosine at the receiver and before visibility.
    /// Falloff is KHR_lights_punctual's: inverse square, the recommended smooth range window,
    /// and the smooth spot cone attenuation. The renderer's `lights.glsl` is the same formula.
    pub fn incident(&self, point: Vec3) -> Incident {
        if self.kind == LightKind::Directional {
            return Incident { to_light: -self.direction, distance: f32::INFINITY, irradiance: self.intensity };
        }
        let offset = self.position - point;
        let distance = offset.length();
        let to_light = offset / distance;
        let attenuation = range_window(distance, self.range) / (distance * distance) * self.cone_attenuation(-to_light);
        Incident { to_light, distance, irradiance: self.intensity * attenuation }
    }

    /// Spot cone factor for a direction leaving the light (1 for point lights).
    pub fn cone_attenuation(&self, from_light: Vec3) -> f32 {
        match self.kind {
            LightKind::Spot { inner_cone, outer_cone } => {
                let (cos_outer, cos_inner) = (outer_cone.cos(), inner_cone.cos());
                let scale = 1.0 / (cos_inner - cos_outer).max(1e-3);
                let t = ((self.direction.dot(from_light) - cos_outer) * scale).clamp(0.0, 1.0);
                t * t
            }
            _ => 1.0,
        }
    }
}

/// KHR_lights_punctual's recommended window: influence falls smoothly to zero at `range`.
fn range_window(distance: f32, range: Option<f32>) -> f32 {
    match range {
        Some(r) => (1.0 - (distance / r).powi(4)).clamp(0.0, 1.0).powi(2),
        None => 1.0,
    }
}

impl Camera {
    pub fn position(&self) -> Vec3 {
        self.world_from_camera.w_axis.truncate()
    }

    /// World-space unit direction through the image point (x, y) in pixels, (0, 0) the
    /// top-left corner; a pixel's centre is (i + 0.5, j + 0.5). The renderer's projection
    /// ([`Camera::clip_from_world`]) maps the same directions to the same pixels.
    pub fn ray_direction(&self, x: f32, y: f32, width: u32, height: u32) -> Vec3 {
        let tan_half = (self.yfov * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let ndc_x = 2.0 * x / width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * y / height as f32;
        let local = Vec3::new(ndc_x * tan_half * aspect, ndc_y * tan_half, -1.0);
        self.world_from_camera.transform_vector3(local).normalize()
    }

    /// Vulkan clip space (depth 0..1, +Y down in framebuffer) for an image of this aspect.
    pub fn clip_from_world(&self, width: u32, height: u32) -> Mat4 {
        let aspect = width as f32 / height as f32;
        let proj = glam::camera::rh::proj::vulkan::perspective(self.yfov, aspect, self.znear, self.zfar);
        proj * self.world_from_camera.inverse()
    }
}
