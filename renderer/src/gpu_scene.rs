//! The scene as the GPU reads it: one vertex and index buffer for every mesh, the materials,
//! the lights and the shadow-map layers each light renders. Layouts match `shaders/*.glsl`.

use crate::upload::upload_array_layers_blocking;
use crate::vk::{vk, Access, Buffer, CommandRecorder, Context, Image, ImageDesc, Tracker, VkError, VkResult};
use glam::{Mat4, Vec3, Vec4};
use gpu_allocator::MemoryLocation;
use relume_bake::scene::{Light, LightKind, Scene, Texture};
use std::sync::Arc;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct GpuVertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv0: [f32; 2],
    /// Atlas coordinate (relume_bake::atlas): the page in the integer part of u; zero for
    /// meshes without one (the renderer then reads no texel term).
    uv1: [f32; 2],
}

pub(crate) const VERTEX_STRIDE: u32 = std::mem::size_of::<GpuVertex>() as u32;

/// Vertex attributes: position, normal, uv0, uv1 (locations 0-3).
pub(crate) fn vertex_attributes() -> [vk::VertexInputAttributeDescription; 4] {
    let attribute = |location, format, offset| vk::VertexInputAttributeDescription { location, binding: 0, format, offset };
    [
        attribute(0, vk::Format::R32G32B32_SFLOAT, 0),
        attribute(1, vk::Format::R32G32B32_SFLOAT, 12),
        attribute(2, vk::Format::R32G32_SFLOAT, 24),
        attribute(3, vk::Format::R32G32_SFLOAT, 32),
    ]
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuMaterial {
    base_color: Vec4,
    emission: Vec4,
    /// Base-colour texture: width, height, layer of the texture array (-1: none).
    texture: Vec4,
    /// The glossy lobe: rho_s rgb, exponent (all 0: Lambertian).
    phong: Vec4,
}

/// One mesh's index range and material: a draw of the lighting pass.
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    pub first_index: u32,
    pub index_count: u32,
    pub material: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuLight {
    position_kind: Vec4,
    direction_range: Vec4,
    intensity_layer: Vec4,
    cone_depth: Vec4,
}

/// The frame's uniform buffer (shaders/frame.glsl, std140): what every pass of a frame may
/// read besides the lights, rewritten in the command stream at the start of each frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    pub clip_from_world: Mat4,
    pub camera_position: Vec4,
    /// rgb: I_A, the ambient irradiance (lux); w: beta (001 eq. (5), (7)).
    pub ambient_beta: Vec4,
    pub light_count: u32,
    /// 0: every light fully visible (shading only).
    pub shadows: u32,
    pub min_variance: f32,
    pub bleeding_reduction: f32,
    /// 1: the irradiance term is scaled by the occlusion term (`Term::Irradiance`).
    pub irradiance_times_occlusion: u32,
    /// 1: the occlusion term also scales the direct irradiance, added again.
    pub occluded_direct: u32,
    /// 1: the ambient light adds the environment's unoccluded irradiance at the normal,
    /// `environment_sh` (`RenderSettings::environment_ambient`).
    pub environment_ambient: u32,
    pub _pad: u32,
    /// The environment's radiance in spherical harmonics of bands l <= 2, rgb per coefficient
    /// (`Environment::radiance_sh`; zero without one).
    pub environment_sh: [Vec4; 9],
}

const _: () = assert!(std::mem::size_of::<FrameUniforms>() == 272);

/// vkCmdUpdateBuffer writes at most 64 KiB: 1024 lights or shadow layers of 64 bytes.
const MAX_LIGHTS: usize = 1024;

/// The shadow-map layers a light owns: six cube faces for a point light, one otherwise.
pub fn shadow_layer_count(kind: LightKind) -> u32 {
    match kind {
        LightKind::Point => 6,
        _ => 1,
    }
}

/// One shadow-map layer to render: which light, which layer, and the depth that means
/// "nothing here" (the layer's far distance), which the moments are cleared to.
#[derive(Clone, Copy, Debug)]
pub struct ShadowView {
    pub light: u32,
    pub layer: u32,
    pub far: f32,
}

/// One layer of the variance shadow maps as an engine that draws them renders it (000 §3.4):
/// the layer's clip-from-world, the light it belongs to (an index into the lights), the depth
/// the layer is cleared to (nothing there), and the light depth whose first two moments it
/// stores. A point light owns six layers, the cube's faces +X, -X, +Y, -Y, +Z, -Z in that order;
/// a point is read from the face of its offset's major axis.
#[derive(Clone, Copy, Debug)]
pub struct ShadowMapView {
    pub clip_from_world: Mat4,
    pub light: usize,
    pub far: f32,
    pub depth: LightDepth,
}

/// How a light's depth is measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightDepth {
    /// A point or spot light: the distance from it.
    Distance { from: Vec3 },
    /// A directional light: the distance along its direction, from `origin` (dot(p, direction)
    /// - origin).
    Along { direction: Vec3, origin: f32 },
}

pub struct GpuScene {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
    pub materials: Buffer,
    /// Device-local; every frame records its update from `light_data` (see `record_updates`).
    pub lights: Buffer,
    pub layers: Buffer,
    /// Device-local, [`FrameUniforms`]; every frame records its update.
    pub frame: Buffer,
    pub draws: Vec<Draw>,
    /// Every base-colour texture, one layer each of an RGBA32F array as large as the largest
    /// (top-left aligned; a white texel when the scene has none). One binding serves every
    /// material without needing descriptor indexing, which lavapipe lacks.
    pub textures: Image,
    pub shadow_views: Vec<ShadowView>,
    light_kinds: Vec<LightKind>,
    light_data: Vec<GpuLight>,
    layer_data: Vec<Mat4>,
    bounds: (Vec3, Vec3),
    /// The vertices as uploaded (or as `reshape_mesh` last gave them), each mesh's range of
    /// them, and room for one moved mesh: what `translate_mesh` and `reshape_mesh` rewrite
    /// without allocating.
    uploaded: Vec<GpuVertex>,
    mesh_ranges: Vec<std::ops::Range<usize>>,
    moved: Vec<GpuVertex>,
    translations: Vec<Vec3>,
}

impl GpuScene {
    /// Uploads the scene (textures through one submission that is waited for: blocking).
    pub fn upload_blocking(ctx: &Arc<Context>, scene: &Scene) -> VkResult<GpuScene> {
        let light_kinds: Vec<_> = scene.lights.iter().map(|l| l.kind).collect();
        let layer_count: u32 = light_kinds.iter().map(|k| shadow_layer_count(*k)).sum();
        if scene.lights.len() > MAX_LIGHTS || layer_count as usize > MAX_LIGHTS {
            return Err(VkError::Invalid(format!(
                "{}: {} lights ({layer_count} shadow layers); the renderer takes at most {MAX_LIGHTS} of each",
                scene.source.display(),
                scene.lights.len()
            )));
        }
        let (vertices, indices, draws) = flatten_meshes(scene);
        let mut mesh_ranges = Vec::with_capacity(scene.meshes.len());
        for mesh in &scene.meshes {
            let start = mesh_ranges.last().map_or(0, |r: &std::ops::Range<usize>| r.end);
            mesh_ranges.push(start..start + mesh.positions.len());
        }
        let largest_mesh = mesh_ranges.iter().map(|r| r.len()).max().unwrap_or(0);
        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .map(|m| GpuMaterial {
                base_color: m.base_color,
                emission: m.emission.extend(0.0),
                texture: match m.base_color_texture.and_then(|i| scene.textures.get(i).map(|t| (i, t))) {
                    Some((layer, t)) => Vec4::new(t.width as f32, t.height as f32, layer as f32, 0.0),
                    None => Vec4::new(0.0, 0.0, -1.0, 0.0),
                },
                phong: m.phong.map_or(Vec4::ZERO, |p| p.specular.extend(p.exponent)),
            })
            .collect();
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let per_frame = storage | vk::BufferUsageFlags::TRANSFER_DST;
        let device_buffer = |name, count: usize| Buffer::new(ctx, name, 64 * count.max(1) as u64, per_frame, MemoryLocation::GpuOnly);
        let mut gpu = GpuScene {
            // Storage too: a technique may read where moving meshes stand now in compute.
            vertices: Buffer::with_data(ctx, "vertices", vk::BufferUsageFlags::VERTEX_BUFFER | storage, &vertices)?,
            indices: Buffer::with_data(ctx, "indices", vk::BufferUsageFlags::INDEX_BUFFER, &indices)?,
            index_count: indices.len() as u32,
            materials: Buffer::with_data(ctx, "materials", storage, &materials)?,
            lights: device_buffer("lights", scene.lights.len())?,
            layers: device_buffer("shadow layers", layer_count as usize)?,
            frame: Buffer::new(
                ctx,
                "frame uniforms",
                std::mem::size_of::<FrameUniforms>() as u64,
                vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            )?,
            draws,
            textures: upload_textures(ctx, &scene.textures)?,
            shadow_views: Vec::with_capacity(layer_count as usize),
            light_kinds,
            light_data: vec![GpuLight::default(); scene.lights.len()],
            layer_data: vec![Mat4::ZERO; layer_count as usize],
            bounds: scene.bounds(),
            translations: vec![Vec3::ZERO; mesh_ranges.len()],
            mesh_ranges,
            moved: Vec::with_capacity(largest_mesh),
            uploaded: vertices,
        };
        gpu.set_lights(&scene.lights)?;
        Ok(gpu)
    }

    /// Recomputes the lights and their shadow layers, without allocating; the GPU buffers
    /// change when the next recorded frame runs. The lights' kinds and count must be those
    /// the scene was uploaded with.
    pub fn set_lights(&mut self, lights: &[Light]) -> VkResult<()> {
        let same_kinds = lights.len() == self.light_kinds.len()
            && lights.iter().zip(&self.light_kinds).all(|(l, k)| std::mem::discriminant(&l.kind) == std::mem::discriminant(k));
        if !same_kinds {
            return Err(VkError::Invalid(
                "lights changed kind or count since upload; create the renderer again for a new light set".into(),
            ));
        }
        self.shadow_views.clear();
        let mut first_layer = 0;
        for (index, light) in lights.iter().enumerate() {
            let count = shadow_layer_count(light.kind) as usize;
            let layers = &mut self.layer_data[first_layer..first_layer + count];
            let (depth_origin, far) = fill_shadow_layers(light, self.bounds, layers);
            self.light_data[index] = gpu_light(light, first_layer as f32, depth_origin);
            self.shadow_views.extend((first_layer..first_layer + count).map(|layer| ShadowView {
                light: index as u32,
                layer: layer as u32,
                far,
            }));
            first_layer += count;
        }
        Ok(())
    }

    /// Moves mesh `mesh` by `translation` from where it was uploaded: rewrites its vertices
    /// in the (host-visible) vertex buffer now, without allocating, and widens the bounds the
    /// shadow layers are fitted to, which takes effect at the next `set_lights`. No frame
    /// that reads the vertices may be in flight.
    pub fn translate_mesh(&mut self, mesh: usize, translation: Vec3) -> VkResult<()> {
        self.range_of(mesh)?;
        if !translation.is_finite() {
            return Err(VkError::Invalid(format!("mesh {mesh}: translation {translation} is not finite")));
        }
        self.translations[mesh] = translation;
        self.write_mesh(mesh)
    }

    /// Gives mesh `mesh` new vertex positions and normals (as many as it has, in its vertex
    /// order; its triangles stay), kept under its translation: a deforming receiver. Rewrites
    /// the vertex buffer now, without allocating; no frame that reads it may be in flight.
    pub fn reshape_mesh(&mut self, mesh: usize, positions: &[Vec3], normals: &[Vec3]) -> VkResult<()> {
        let range = self.range_of(mesh)?;
        if positions.len() != range.len() || normals.len() != range.len() {
            return Err(VkError::Invalid(format!(
                "mesh {mesh}: {} positions and {} normals for its {} vertices",
                positions.len(),
                normals.len(),
                range.len()
            )));
        }
        if let Some(i) = positions.iter().zip(normals).position(|(p, n)| !p.is_finite() || !n.is_finite()) {
            return Err(VkError::Invalid(format!("mesh {mesh}: vertex {i} is not finite")));
        }
        for ((vertex, p), n) in self.uploaded[range].iter_mut().zip(positions).zip(normals) {
            vertex.position = p.to_array();
            vertex.normal = n.to_array();
        }
        self.write_mesh(mesh)
    }

    /// Mesh `mesh`'s vertices in the vertex buffer; refused for a mesh the scene lacks.
    pub fn range_of(&self, mesh: usize) -> VkResult<std::ops::Range<usize>> {
        self.mesh_ranges
            .get(mesh)
            .cloned()
            .ok_or_else(|| VkError::Invalid(format!("mesh {mesh}: the scene has {} meshes", self.mesh_ranges.len())))
    }

    /// Writes mesh `mesh` (its uploaded vertices moved by its translation) into the vertex
    /// buffer and refits the bounds.
    fn write_mesh(&mut self, mesh: usize) -> VkResult<()> {
        let range = self.mesh_ranges[mesh].clone();
        let translation = self.translations[mesh];
        self.moved.clear();
        self.moved.extend(
            self.uploaded[range.clone()]
                .iter()
                .map(|v| GpuVertex { position: (Vec3::from_array(v.position) + translation).to_array(), ..*v }),
        );
        self.vertices.write_at(range.start * std::mem::size_of::<GpuVertex>(), &self.moved)?;
        self.bounds = self.mesh_ranges.iter().zip(&self.translations).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (r, t)| {
            self.uploaded[r.clone()]
                .iter()
                .fold((lo, hi), |(lo, hi), v| (lo.min(Vec3::from_array(v.position) + *t), hi.max(Vec3::from_array(v.position) + *t)))
        });
        Ok(())
    }

    /// Records this frame's uniforms and its light and shadow-layer data into the device-local
    /// buffers, with the barriers that order them against the previous frame's reads and
    /// this frame's passes.
    pub fn record_updates(&self, rec: &CommandRecorder, frame: &FrameUniforms) {
        let frame = (self.frame.raw, bytemuck::bytes_of(frame));
        match self.light_data.is_empty() {
            true => rec.update_buffers([frame]),
            false => rec.update_buffers([
                frame,
                (self.lights.raw, bytemuck::cast_slice(&self.light_data)),
                (self.layers.raw, bytemuck::cast_slice(&self.layer_data)),
            ]),
        }
    }

    /// Every layer of the shadow maps as the lights stand now (they refit at `set_lights`).
    pub fn shadow_map_views(&self) -> impl Iterator<Item = ShadowMapView> + '_ {
        self.shadow_views.iter().map(|view| {
            let light = &self.light_data[view.light as usize];
            let depth = match self.light_kinds[view.light as usize] {
                LightKind::Directional => LightDepth::Along { direction: light.direction_range.truncate(), origin: light.cone_depth.z },
                _ => LightDepth::Distance { from: light.position_kind.truncate() },
            };
            ShadowMapView { clip_from_world: self.layer_data[view.layer as usize], light: view.light as usize, far: view.far, depth }
        })
    }

    /// Tells a frame's tracker that the texture array is ready for FragmentSampled reads, as
    /// its upload left it.
    pub fn register_states(&self, tracker: &mut Tracker) {
        tracker.assume(&self.textures, Access::FragmentSampled);
    }

    /// Vertices of the vertex buffer (every mesh's, in order): what a vertex term holds one
    /// value for.
    pub fn vertex_count(&self) -> usize {
        self.uploaded.len()
    }

    pub fn light_count(&self) -> u32 {
        self.light_kinds.len() as u32
    }
}

fn flatten_meshes(scene: &Scene) -> (Vec<GpuVertex>, Vec<u32>, Vec<Draw>) {
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    let mut draws = Vec::with_capacity(scene.meshes.len());
    for mesh in &scene.meshes {
        let base = vertices.len() as u32;
        for (i, (p, n)) in mesh.positions.iter().zip(&mesh.normals).enumerate() {
            let uv0 = mesh.uv0.as_ref().map_or(glam::Vec2::ZERO, |uv| uv[i]);
            let uv1 = mesh.uv1.as_ref().map_or(glam::Vec2::ZERO, |uv| uv[i]);
            vertices.push(GpuVertex { position: p.to_array(), normal: n.to_array(), uv0: uv0.to_array(), uv1: uv1.to_array() });
        }
        draws.push(Draw { first_index: indices.len() as u32, index_count: mesh.indices.len() as u32, material: mesh.material as u32 });
        indices.extend(mesh.indices.iter().map(|i| i + base));
    }
    (vertices, indices, draws)
}

/// Uploads every texture into its layer of one array image, through one staging buffer and
/// one submission, at creation.
fn upload_textures(ctx: &Arc<Context>, textures: &[Texture]) -> VkResult<Image> {
    let white = Texture { name: "white".into(), width: 1, height: 1, texels: vec![Vec4::ONE] };
    let textures = if textures.is_empty() { std::slice::from_ref(&white) } else { textures };
    let layers: Vec<_> = textures.iter().map(|t| (&t.texels[..], vk::Extent2D { width: t.width, height: t.height })).collect();
    let array = Image::new(
        ctx,
        "base colour textures",
        ImageDesc {
            width: textures.iter().map(|t| t.width).max().unwrap_or(1),
            height: textures.iter().map(|t| t.height).max().unwrap_or(1),
            layers: textures.len() as u32,
            format: vk::Format::R32G32B32A32_SFLOAT,
            usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            view_type: vk::ImageViewType::TYPE_2D_ARRAY,
        },
    )?;
    upload_array_layers_blocking(ctx, &array, &layers, |_, _| {})?;
    Ok(array)
}

fn gpu_light(light: &Light, first_layer: f32, depth_origin: f32) -> GpuLight {
    let kind = match light.kind {
        LightKind::Point => 0.0,
        LightKind::Spot { .. } => 1.0,
        LightKind::Directional => 2.0,
    };
    let (cos_outer, cone_scale) = match light.kind {
        // The same terms as relume_bake::scene::Light::cone_attenuation.
        LightKind::Spot { inner_cone, outer_cone } => (outer_cone.cos(), 1.0 / (inner_cone.cos() - outer_cone.cos()).max(1e-3)),
        _ => (-1.0, 1.0),
    };
    GpuLight {
        position_kind: light.position.extend(kind),
        direction_range: light.direction.extend(light.range.unwrap_or(0.0)),
        intensity_layer: light.intensity.extend(first_layer),
        cone_depth: Vec4::new(cos_outer, cone_scale, depth_origin, 0.0),
    }
}

/// Writes the clip-from-world matrices of a light's shadow layers into `layers`; returns the
/// depth origin along the light direction (directional lights) and the far depth. Point-light
/// faces follow `shadow_layer` in lights.glsl.
fn fill_shadow_layers(light: &Light, (lo, hi): (Vec3, Vec3), layers: &mut [Mat4]) -> (f32, f32) {
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
            for (layer, face) in layers.iter_mut().zip(faces) {
                *layer = proj * look(face);
            }
            (0.0, far)
        }
        LightKind::Spot { outer_cone, .. } => {
            let fov = (2.0 * outer_cone).min(170f32.to_radians());
            layers[0] = vulkan::perspective(fov, 1.0, near, far) * look(light.direction);
            (0.0, far)
        }
        LightKind::Directional => {
            let eye = centre - light.direction * radius;
            let view = view::look_to_mat4(eye, light.direction, any_perpendicular_up(light.direction));
            layers[0] = vulkan::orthographic(-radius, radius, -radius, radius, 0.0, 2.0 * radius) * view;
            (eye.dot(light.direction), 2.0 * radius)
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
