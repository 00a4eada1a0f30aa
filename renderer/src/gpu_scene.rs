//! The scene as the GPU reads it: one vertex and index buffer for every mesh, the materials,
//! the lights and the shadow-map layers each light renders. Layouts match `shaders/*.glsl`.

use crate::vk::{vk, Access, Buffer, Context, Image, ImageDesc, Tracker, VkError, VkResult};
use glam::{Mat4, Vec3, Vec4};
use gpu_allocator::MemoryLocation;
use relume_bake::scene::{Light, LightKind, Scene, Texture};

#[repr(C)]
#[derive(Clone, Copy)]
pub(crate) struct GpuVertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv0: [f32; 2],
}

pub(crate) const VERTEX_STRIDE: u32 = std::mem::size_of::<GpuVertex>() as u32;

/// Vertex attributes: position, normal, uv0 (locations 0-2).
pub(crate) fn vertex_attributes() -> [vk::VertexInputAttributeDescription; 3] {
    let attribute = |location, format, offset| vk::VertexInputAttributeDescription { location, binding: 0, format, offset };
    [
        attribute(0, vk::Format::R32G32B32_SFLOAT, 0),
        attribute(1, vk::Format::R32G32B32_SFLOAT, 12),
        attribute(2, vk::Format::R32G32_SFLOAT, 24),
    ]
}

#[repr(C)]
#[derive(Clone, Copy)]
struct GpuMaterial {
    base_color: Vec4,
    /// rgb emission, w the base-colour texture index (-1: none).
    emission_texture: Vec4,
}

/// One mesh's index range and material: a draw of the forward pass.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Draw {
    pub first_index: u32,
    pub index_count: u32,
    pub material: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Default)]
struct GpuLight {
    position_kind: Vec4,
    direction_range: Vec4,
    intensity_layer: Vec4,
    cone_depth: Vec4,
}

/// The shadow-map layers a light owns: six cube faces for a point light, one otherwise.
pub fn shadow_layer_count(kind: LightKind) -> u32 {
    match kind {
        LightKind::Point => 6,
        _ => 1,
    }
}

/// One shadow-map layer to render: which light, which layer.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShadowView {
    pub light: u32,
    pub layer: u32,
}

pub(crate) struct GpuScene {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
    pub materials: Buffer,
    pub lights: Buffer,
    pub layers: Buffer,
    pub draws: Vec<Draw>,
    /// Base-colour textures in linear RGBA32F, sampled with repeat; one white texel when
    /// the scene has none, so the shader's texture array is never empty.
    pub textures: Vec<Image>,
    pub light_kinds: Vec<LightKind>,
    pub shadow_views: Vec<ShadowView>,
    bounds: (Vec3, Vec3),
}

impl GpuScene {
    pub fn upload(ctx: &Context, scene: &Scene) -> VkResult<GpuScene> {
        let (vertices, indices, draws) = flatten_meshes(scene);
        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .map(|m| GpuMaterial {
                base_color: m.base_color,
                emission_texture: m.emission.extend(m.base_color_texture.map_or(-1.0, |t| t as f32)),
            })
            .collect();
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let light_kinds: Vec<_> = scene.lights.iter().map(|l| l.kind).collect();
        let shadow_views: Vec<_> = light_kinds
            .iter()
            .enumerate()
            .flat_map(|(i, kind)| (0..shadow_layer_count(*kind)).map(move |face| (i as u32, face)))
            .enumerate()
            .map(|(layer, (light, _))| ShadowView { light, layer: layer as u32 })
            .collect();
        let mut gpu = GpuScene {
            vertices: Buffer::with_data(ctx, "vertices", vk::BufferUsageFlags::VERTEX_BUFFER, &vertices)?,
            indices: Buffer::with_data(ctx, "indices", vk::BufferUsageFlags::INDEX_BUFFER, &indices)?,
            index_count: indices.len() as u32,
            materials: Buffer::with_data(ctx, "materials", storage, &materials)?,
            lights: Buffer::with_data(ctx, "lights", storage, &vec![GpuLight::default(); scene.lights.len().max(1)])?,
            layers: Buffer::with_data(ctx, "shadow layers", storage, &vec![Mat4::ZERO; shadow_views.len().max(1)])?,
            draws,
            textures: upload_textures(ctx, &scene.textures)?,
            light_kinds,
            shadow_views,
            bounds: scene.bounds(),
        };
        gpu.set_lights(&scene.lights)?;
        Ok(gpu)
    }

    /// Rewrites the light and shadow-layer buffers; the caller makes sure no frame that reads
    /// them is in flight. The lights' kinds must be those the scene was uploaded with.
    pub fn set_lights(&mut self, lights: &[Light]) -> VkResult<()> {
        let kinds: Vec<_> = lights.iter().map(|l| l.kind).collect();
        let same_kinds = kinds.len() == self.light_kinds.len()
            && kinds.iter().zip(&self.light_kinds).all(|(a, b)| std::mem::discriminant(a) == std::mem::discriminant(b));
        if !same_kinds {
            return Err(VkError::Invalid(
                "lights changed kind or count since upload; create the renderer again for a new light set".into(),
            ));
        }
        let mut gpu_lights = Vec::with_capacity(lights.len());
        let mut layers = Vec::with_capacity(self.shadow_views.len());
        for light in lights {
            let first_layer = layers.len() as f32;
            let (matrices, depth_origin) = shadow_matrices(light, self.bounds);
            layers.extend(matrices);
            gpu_lights.push(gpu_light(light, first_layer, depth_origin));
        }
        self.lights.write(&gpu_lights)?;
        self.layers.write(&layers)
    }

    pub fn light_count(&self) -> u32 {
        self.light_kinds.len() as u32
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for buffer in [&mut self.vertices, &mut self.indices, &mut self.materials, &mut self.lights, &mut self.layers] {
            buffer.destroy(ctx);
        }
        for texture in &mut self.textures {
            texture.destroy(ctx);
        }
    }
}

fn flatten_meshes(scene: &Scene) -> (Vec<GpuVertex>, Vec<u32>, Vec<Draw>) {
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    let mut draws = Vec::with_capacity(scene.meshes.len());
    for mesh in &scene.meshes {
        let base = vertices.len() as u32;
        for (i, (p, n)) in mesh.positions.iter().zip(&mesh.normals).enumerate() {
            let uv = mesh.uv0.as_ref().map_or(glam::Vec2::ZERO, |uv| uv[i]);
            vertices.push(GpuVertex { position: p.to_array(), normal: n.to_array(), uv0: uv.to_array() });
        }
        draws.push(Draw {
            first_index: indices.len() as u32,
            index_count: mesh.indices.len() as u32,
            material: mesh.material as u32,
        });
        indices.extend(mesh.indices.iter().map(|i| i + base));
    }
    (vertices, indices, draws)
}

/// Uploads every texture through one staging buffer and one submission, at creation.
fn upload_textures(ctx: &Context, textures: &[Texture]) -> VkResult<Vec<Image>> {
    let white = Texture { name: "white".into(), width: 1, height: 1, texels: vec![Vec4::ONE] };
    let textures = if textures.is_empty() { std::slice::from_ref(&white) } else { textures };
    let texel_count: usize = textures.iter().map(|t| t.texels.len()).sum();
    let staging = Buffer::new(ctx, "texture staging", (texel_count * 16) as u64, vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu)?;
    let mut images = Vec::with_capacity(textures.len());
    let result = (|| {
        let all_texels: Vec<Vec4> = textures.iter().flat_map(|t| t.texels.iter().copied()).collect();
        staging.write(&all_texels)?;
        let cmd = ctx.allocate_command_buffer()?;
        let fence = ctx.create_fence()?;
        let rec = ctx.begin(cmd)?;
        let mut tracker = Tracker::default();
        let mut offset = 0u64;
        for texture in textures {
            let image = Image::new(ctx, &texture.name, ImageDesc {
                width: texture.width,
                height: texture.height,
                layers: 1,
                format: vk::Format::R32G32B32A32_SFLOAT,
                usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
                view_type: vk::ImageViewType::TYPE_2D,
            })?;
            tracker.use_image(&rec, &image, Access::TransferDestination);
            rec.copy_buffer_to_image_at(staging.raw, offset, &image);
            tracker.use_image(&rec, &image, Access::FragmentSampled);
            offset += texture.texels.len() as u64 * 16;
            images.push(image);
        }
        let submitted = ctx.submit_and_wait(rec, fence);
        ctx.destroy_fence(fence);
        ctx.free_command_buffer(cmd);
        submitted
    })();
    let mut staging = staging;
    staging.destroy(ctx);
    match result {
        Ok(()) => Ok(images),
        Err(e) => {
            images.iter_mut().for_each(|i| i.destroy(ctx));
            Err(e)
        }
    }
}

fn gpu_light(light: &Light, first_layer: f32, depth_origin: f32) -> GpuLight {
    let kind = match light.kind {
        LightKind::Point => 0.0,
        LightKind::Spot { .. } => 1.0,
        LightKind::Directional => 2.0,
    };
    let (cos_outer, cone_scale) = match light.kind {
        // The same terms as relume_bake::scene::Light::cone_attenuation.
        LightKind::Spot { inner_cone, outer_cone } => {
            (outer_cone.cos(), 1.0 / (inner_cone.cos() - outer_cone.cos()).max(1e-3))
        }
        _ => (-1.0, 1.0),
    };
    GpuLight {
        position_kind: light.position.extend(kind),
        direction_range: light.direction.extend(light.range.unwrap_or(0.0)),
        intensity_layer: light.intensity.extend(first_layer),
        cone_depth: Vec4::new(cos_outer, cone_scale, depth_origin, 0.0),
    }
}

/// Clip-from-world matrices of a light's shadow layers, and (directional lights) the depth
/// origin along the light direction. Point-light faces follow `shadow_layer` in lights.glsl.
fn shadow_matrices(light: &Light, (lo, hi): (Vec3, Vec3)) -> (Vec<Mat4>, f32) {
    use glam::camera::rh::{proj::vulkan, view};
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let far = (light.position - centre).length() + radius * 1.01;
    let near = (radius * 1e-3).max(1e-3);
    let look = |dir: Vec3| view::look_to_mat4(light.position, dir, any_perpendicular_up(dir));
    match light.kind {
        LightKind::Point => {
            let faces = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
            let proj = vulkan::perspective(std::f32::consts::FRAC_PI_2, 1.0, near, far);
            (faces.iter().map(|d| proj * look(*d)).collect(), 0.0)
        }
        LightKind::Spot { outer_cone, .. } => {
            let fov = (2.0 * outer_cone).min(170f32.to_radians());
            (vec![vulkan::perspective(fov, 1.0, near, far) * look(light.direction)], 0.0)
        }
        LightKind::Directional => {
            let eye = centre - light.direction * radius;
            let view = view::look_to_mat4(eye, light.direction, any_perpendicular_up(light.direction));
            let proj = vulkan::orthographic(-radius, radius, -radius, radius, 0.0, 2.0 * radius);
            (vec![proj * view], eye.dot(light.direction))
        }
    }
}

fn any_perpendicular_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}
