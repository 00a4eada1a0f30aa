//! An engine that is not relume, using relume's techniques as effects. The engine owns its
//! instance, device, queue and submissions (common/engine_device.rs), its geometry, its
//! lights, its passes (shadow maps, surfaces, forward) and its shaders (engine_shaders/,
//! compiled by the engine at start with shaderc); relume's `Effect` records the technique's
//! passes into the engine's command buffer, reading the engine's shadow maps and surfaces, and
//! hands back the term, which the engine's fragment shader samples with
//! `shaders/include/relume.glsl`. relume's lighting pass, shadow maps and tonemap take no part.
//! The engine records two frames into one command buffer, each pass's barriers starting from
//! where the frame before (or relume) left its images.
//!
//!     cargo run -p relume-renderer --example engine -- SCENE.gltf OBSCURANCE_BAKE [--validation]
//!
//! renders SCENE with an obscurance bake of it (`relume bake --method obscurance`) as the
//! engine's ambient occlusion and prints the radiance's range. The test every technique runs it
//! with (tools/src/methods/effects.rs) compares its image with relume's own frame.

#[path = "common/engine_device.rs"]
mod engine_device;

use ash::vk;
use bytemuck::Zeroable;
use engine_device::Engine;
use relume_bake::scene::{LightKind, Scene};
use relume_renderer::gpu_scene::shadow_layer_count;
use relume_renderer::technique::{MakeTechnique, Surfaces, Terms};
use relume_renderer::vk::{transition, Access, Binding, Buffer, CommandBuffer, CommandRecorder, Context, DescriptorSet, Fence};
use relume_renderer::vk::{GraphicsPipelineDesc, Image, ImageDesc, ImageState, ImageView, Pipeline, Sampler};
use relume_renderer::{Effect, EngineInputs, LightDepth, RenderSettings, ShadowMapView, TermReads};
use std::error::Error;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What the engine got out of one frame.
pub struct Outcome {
    /// The device the engine created.
    pub device: String,
    /// The engine's linear radiance, RGBA32F, row by row.
    pub radiance: Vec<f32>,
    /// The shader variant the effect's terms chose (its macro definitions).
    pub variant: String,
    /// Whether the effect read the engine's surfaces pass (a pixel term does).
    pub drew_surfaces: bool,
    /// The validation layer's warnings and errors over the whole run (empty without it).
    pub validation_messages: Vec<String>,
}

#[allow(dead_code)]
fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let validation = args.iter().any(|a| a == "--validation");
    let paths: Vec<PathBuf> = args.iter().filter(|a| !a.starts_with("--")).map(PathBuf::from).collect();
    let [scene_path, bake] = &paths[..] else {
        return Err("usage: engine SCENE.gltf OBSCURANCE_BAKE [--validation]".into());
    };
    let (scene, obscurance) = obscurance_bake(scene_path, bake)?;
    let layout = relume_renderer::AtlasImage::new(obscurance.0, &obscurance.1);
    let data = relume_renderer::techniques::obscurance::ObscuranceData { obscurance: layout };
    let settings = RenderSettings { width: 256, height: 256, ambient: glam::Vec3::splat(1.0), ..RenderSettings::default() };
    let outcome = run(&scene, &[&data], &settings, validation)?;
    let largest = outcome.radiance.chunks_exact(4).flat_map(|p| &p[..3]).fold(0.0f32, |a, &b| a.max(b));
    println!("device: {}; the engine's radiance reaches {largest}", outcome.device);
    println!("{} validation message(s)", outcome.validation_messages.len());
    outcome.validation_messages.iter().for_each(|m| println!("  {m}"));
    Ok(())
}

type Obscurance = (relume_bake::artifact::PageLayout, Vec<glam::Vec4>);

/// The scene with the bake's uv1, and its obscurance on the atlas (coverage in alpha).
fn obscurance_bake(scene: &Path, bake: &Path) -> Result<(Scene, Obscurance), Box<dyn Error>> {
    let loaded = relume_bake::gltf_load::load(scene)?.scene;
    let artifact = relume_bake::artifact::Artifact::read(bake)?;
    let atlas = relume_bake::atlas::AtlasSection::read_for(&artifact, &loaded, &loaded)?;
    let mut applied = loaded.clone();
    atlas.apply_to(&mut applied);
    let values = relume_bake::obscurance::read(&artifact, &loaded, atlas.layout)?;
    Ok((applied, (atlas.layout, atlas.with_coverage(&values))))
}

/// Renders one frame of `scene` at `settings`' size with the effect of `techniques`, as
/// described above, on the engine's own device.
pub fn run(
    scene: &Scene,
    techniques: &[&dyn MakeTechnique],
    settings: &RenderSettings,
    validation: bool,
) -> Result<Outcome, Box<dyn Error>> {
    let engine = Engine::new(validation)?;
    let ctx = engine.context()?;
    let drawn = frame(&engine, &ctx, scene, techniques, settings);
    drop(ctx);
    let outcome = drawn.map(|(radiance, variant, drew_surfaces)| Outcome {
        device: engine.name.clone(),
        radiance,
        variant,
        drew_surfaces,
        validation_messages: engine.validation_messages(),
    });
    engine.destroy();
    outcome
}

/// The engine's surfaces pass (when the effect reads it), the effect, then the engine's forward
/// pass and its read-back, in one command buffer the engine submits and waits for. Returns
/// the radiance, the shader variant and whether the surfaces pass ran.
fn frame(
    engine: &Engine,
    ctx: &Arc<Context>,
    scene: &Scene,
    techniques: &[&dyn MakeTechnique],
    settings: &RenderSettings,
) -> Result<(Vec<f32>, String, bool), Box<dyn Error>> {
    if scene.materials.iter().any(|m| m.base_color_texture.is_some()) || (settings.environment_ambient && scene.environment.is_some()) {
        return Err("the engine example draws untextured materials and no environment light".into());
    }
    use vk::ImageUsageFlags as U;
    let image = |name, (width, height, layers), format, usage, view_type| {
        Image::new(ctx, name, ImageDesc { width, height, layers, format, usage, view_type })
    };
    let frame_size = (settings.width, settings.height, 1);
    let target = |name, format, usage| image(name, frame_size, format, usage, vk::ImageViewType::TYPE_2D);
    let surfaces = [
        target("engine positions", RGBA32F, U::COLOR_ATTACHMENT | U::STORAGE)?,
        target("engine normals", RGBA32F, U::COLOR_ATTACHMENT | U::STORAGE)?,
    ];
    // Its shadow maps: one layer per shadow view relume names, six for a point light.
    let layers = scene.lights.iter().map(|l| shadow_layer_count(l.kind)).sum::<u32>().max(1);
    let size = settings.shadow_map_size;
    let moments = image(
        "engine moments",
        (size, size, layers),
        vk::Format::R32G32_SFLOAT,
        U::COLOR_ATTACHMENT | U::SAMPLED,
        vk::ImageViewType::TYPE_2D_ARRAY,
    )?;
    let inputs = EngineInputs { surfaces: Some(Surfaces { positions: &surfaces[0], normals: &surfaces[1] }), shadows: Some(&moments) };
    let mut effect = Effect::new_blocking(ctx, scene, settings, techniques, &inputs)?;
    let views: Vec<ShadowMapView> = effect.shadow_map_views().collect();
    let terms = effect.terms()?;
    let geometry = Geometry::new(ctx, scene, settings, &terms, &views)?;
    // A depth buffer for each pass: each clears its own.
    let depths = [
        target("engine surfaces depth", vk::Format::D32_SFLOAT, U::DEPTH_STENCIL_ATTACHMENT)?,
        target("engine depth", vk::Format::D32_SFLOAT, U::DEPTH_STENCIL_ATTACHMENT)?,
        image("engine shadow depth", (size, size, 1), vk::Format::D32_SFLOAT, U::DEPTH_STENCIL_ATTACHMENT, vk::ImageViewType::TYPE_2D)?,
    ];
    let surfaces_pass = match effect.surface_ids() {
        Some(ids) => Some(SurfacesPass::new(ctx, &geometry, ids)?),
        None => None,
    };
    let shadow_pass = ShadowPass::new(ctx, &moments, &views)?;
    let forward = Forward::new(ctx, &geometry, &terms, settings, &moments)?;
    drop(terms);
    let (cmd, fence) = (CommandBuffer::new(ctx)?, Fence::new(ctx)?);
    let rec = ctx.begin(cmd.raw)?;
    let mut states = States::default();
    for frame in 0..FRAMES {
        shadow_pass.record(&rec, &geometry, (&moments, &depths[2]), &mut states);
        if let Some(pass) = &surfaces_pass {
            pass.record(&rec, &geometry, (&surfaces, &depths[0]), &mut states);
        }
        // The default: terms read by its fragment shaders, its surfaces and shadow maps last
        // drawn by its own passes.
        let output = effect.record(&rec, TermReads::default())?;
        (states.surfaces, states.moments) = (output.surfaces, output.shadows);
        forward.record(&rec, &geometry, (&moments, &depths[1]), output.images, &mut states, frame + 1 == FRAMES);
    }
    engine.end_submit_and_wait(cmd.raw, fence.raw)?;
    let bytes = forward.readback.mapped_bytes(forward.color.desc.texel_count() as usize * 16)?;
    Ok((bytemuck::pod_collect_to_vec(bytes), forward.variant, surfaces_pass.is_some()))
}

/// Frames the engine records, one after the other in one command buffer: the second starts
/// from where the first left every image and buffer.
const FRAMES: usize = 2;

/// The engine's lights as its shader reads them (engine_shaders/engine.glsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EngineLight {
    position_kind: [f32; 4],
    direction_range: [f32; 4],
    intensity: [f32; 4],
    cone: [f32; 4],
    /// Its first shadow-map layer, a directional light's depth origin.
    shadow: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EngineFrame {
    clip_from_world: [f32; 16],
    camera_position: [f32; 4],
    ambient_beta: [f32; 4],
    counts: [u32; 4],
    shadow: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EngineMaterial {
    base_color: [f32; 4],
    emission: [f32; 4],
    phong: [f32; 4],
}

/// The engine's scene: its vertex and index buffers (position, normal, uv1 per vertex, every
/// mesh's vertices in the scene's order, so that gl_VertexIndex is the index relume's
/// per-vertex terms use), per mesh its index range and material, its lights, its frame
/// uniforms and its shadow maps' layers.
struct Geometry {
    vertices: Buffer,
    indices: Buffer,
    draws: Vec<(u32, u32, EngineMaterial)>,
    lights: Buffer,
    uniforms: Buffer,
    layers: Buffer,
}

/// Where a pass draws: its extent, a view of each colour attachment, their clear value and
/// the depth attachment's view.
type Target<const N: usize> = (vk::Extent2D, [vk::ImageView; N], [f32; 4], vk::ImageView);

impl Geometry {
    fn new(
        ctx: &Arc<Context>,
        scene: &Scene,
        settings: &RenderSettings,
        terms: &Terms,
        views: &[ShadowMapView],
    ) -> Result<Geometry, Box<dyn Error>> {
        let (vertices, indices, draws) = geometry(scene);
        let uniforms = EngineFrame {
            clip_from_world: scene.camera.clip_from_world(settings.width, settings.height).to_cols_array(),
            camera_position: scene.camera.position().extend(1.0).to_array(),
            ambient_beta: settings.ambient.extend(settings.beta).to_array(),
            counts: [scene.lights.len() as u32, terms.times_occlusion as u32, terms.occluded_direct as u32, settings.shadows as u32],
            shadow: [settings.min_variance, settings.bleeding_reduction, 0.0, 0.0],
        };
        // A storage buffer is never empty.
        let layers: Vec<[f32; 16]> = views.iter().map(|v| v.clip_from_world.to_cols_array()).chain([[0.0; 16]]).collect();
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Geometry {
            vertices: Buffer::with_data(ctx, "engine vertices", vk::BufferUsageFlags::VERTEX_BUFFER, &vertices)?,
            indices: Buffer::with_data(ctx, "engine indices", vk::BufferUsageFlags::INDEX_BUFFER, &indices)?,
            draws,
            lights: Buffer::with_data(ctx, "engine lights", storage, &engine_lights(scene, views))?,
            uniforms: Buffer::with_data(ctx, "engine frame", vk::BufferUsageFlags::UNIFORM_BUFFER, &[uniforms])?,
            layers: Buffer::with_data(ctx, "engine shadow layers", storage, &layers)?,
        })
    }

    /// Renders every mesh into `target` (its attachments already in their attachment states)
    /// with `pipeline`, pushing each mesh's `push`.
    fn draw<P: bytemuck::NoUninit, const N: usize>(
        &self,
        rec: &CommandRecorder,
        (pipeline, set): (&Pipeline, &DescriptorSet),
        (extent, colors, clear, depth): Target<N>,
        push: impl Fn(usize) -> P,
    ) {
        rec.bind_graphics(pipeline.raw, pipeline.layout, set.set);
        rec.begin_rendering(extent, colors, clear, depth);
        rec.bind_geometry(self.vertices.raw, self.indices.raw);
        for (mesh, (first_index, index_count, _)) in self.draws.iter().enumerate() {
            rec.push_constants(pipeline.layout, &push(mesh));
            rec.draw_indexed(*first_index, *index_count);
        }
        rec.end_rendering();
    }
}

/// Brings `image` from where it stands (`state`) into `access`, and remembers it there.
fn bring(rec: &CommandRecorder, image: &Image, state: &mut ImageState, access: Access) {
    *state = transition(rec, image.into(), *state, access);
}

/// Where each of the engine's images stands between its passes and frames.
struct States {
    moments: ImageState,
    surfaces: ImageState,
    /// The surfaces, forward and shadow passes' depth buffers.
    depths: [ImageState; 3],
    color: ImageState,
    stand_in: ImageState,
}

impl Default for States {
    fn default() -> Self {
        let undefined = Access::Undefined.state();
        States { moments: undefined, surfaces: undefined, depths: [undefined; 3], color: undefined, stand_in: undefined }
    }
}

/// The engine's pipeline of `shaders` (vertex, fragment) over its geometry into colours of
/// `formats`.
fn pipeline(
    ctx: &Arc<Context>,
    name: &str,
    shaders: [&[u8]; 2],
    set: &DescriptorSet,
    formats: &[vk::Format],
    push_bytes: usize,
) -> Result<Pipeline, Box<dyn Error>> {
    let attribute = |location, format, offset| vk::VertexInputAttributeDescription { location, binding: 0, format, offset };
    Ok(Pipeline::graphics(
        ctx,
        &GraphicsPipelineDesc {
            name,
            vertex: shaders[0],
            fragment: shaders[1],
            specialization: &[],
            vertex_stride: 32,
            attributes: &[
                attribute(0, vk::Format::R32G32B32_SFLOAT, 0),
                attribute(1, vk::Format::R32G32B32_SFLOAT, 12),
                attribute(2, vk::Format::R32G32_SFLOAT, 24),
            ],
            color_formats: formats,
            depth_format: vk::Format::D32_SFLOAT,
            cull_mode: vk::CullModeFlags::NONE,
            set,
            push_bytes: push_bytes as u32,
        },
    )?)
}

/// The engine's surfaces pass (its G-buffer): every pixel's position and normal, with the id
/// relume gave the pixel's mesh, for the effect's pixel term.
struct SurfacesPass {
    pipeline: Pipeline,
    descriptors: DescriptorSet,
    ids: Vec<u32>,
}

impl SurfacesPass {
    fn new(ctx: &Arc<Context>, geometry: &Geometry, ids: &[u32]) -> Result<SurfacesPass, Box<dyn Error>> {
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let descriptors = DescriptorSet::new(ctx, stages, &[Binding::UniformBuffer(geometry.uniforms.raw)])?;
        let shaders = [
            compile(include_str!("engine_shaders/surfaces.vert"), shaderc::ShaderKind::Vertex, &[])?,
            compile(include_str!("engine_shaders/surfaces.frag"), shaderc::ShaderKind::Fragment, &[])?,
        ];
        let pipeline = pipeline(ctx, "engine.surfaces", [&shaders[0], &shaders[1]], &descriptors, &[RGBA32F; 2], 4)?;
        Ok(SurfacesPass { pipeline, descriptors, ids: ids.to_vec() })
    }

    fn record(&self, rec: &CommandRecorder, geometry: &Geometry, (surfaces, depth): (&[Image; 2], &Image), states: &mut States) {
        let mut normals = states.surfaces;
        bring(rec, &surfaces[0], &mut states.surfaces, Access::ColorAttachmentWrite);
        bring(rec, &surfaces[1], &mut normals, Access::ColorAttachmentWrite);
        bring(rec, depth, &mut states.depths[0], Access::DepthAttachmentWrite);
        let target = (depth.desc.extent(), [surfaces[0].view, surfaces[1].view], [0.0; 4], depth.view);
        geometry.draw(rec, (&self.pipeline, &self.descriptors), target, |mesh| self.ids[mesh]);
    }
}

/// The engine's forward pass: its pipeline for the effect's terms, its colour target, and its
/// read-back buffer.
struct Forward {
    pipeline: Pipeline,
    descriptors: DescriptorSet,
    color: Image,
    stand_in: Image,
    readback: Buffer,
    variant: String,
    // Named by the descriptor set, so kept as long as it.
    _held: (Buffer, Sampler, Sampler),
}

impl Forward {
    fn new(
        ctx: &Arc<Context>,
        geometry: &Geometry,
        terms: &Terms,
        settings: &RenderSettings,
        moments: &Image,
    ) -> Result<Forward, Box<dyn Error>> {
        let (w, h) = (settings.width, settings.height);
        let stand_in_values = Buffer::with_data(ctx, "engine stand-in", vk::BufferUsageFlags::STORAGE_BUFFER, &[0.0f32; 4])?;
        use vk::ImageUsageFlags as U;
        let desc = |width, height, usage, view_type| ImageDesc {
            width,
            height,
            layers: 1,
            format: vk::Format::R32G32B32A32_SFLOAT,
            usage,
            view_type,
        };
        let color = Image::new(ctx, "engine color", desc(w, h, U::COLOR_ATTACHMENT | U::TRANSFER_SRC, vk::ImageViewType::TYPE_2D))?;
        let stand_in = Image::new(ctx, "engine stand-in", desc(1, 1, U::SAMPLED, vk::ImageViewType::TYPE_2D_ARRAY))?;
        let readback = Buffer::with_data(ctx, "engine readback", vk::BufferUsageFlags::TRANSFER_DST, &vec![0.0f32; (w * h * 4) as usize])?;
        let sampler = Sampler::new(ctx, false, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        // Moments are filtered as relume filters them where the device can.
        let moments_sampler = Sampler::new(ctx, ctx.info.linear_moments, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        let sampled = |image: Option<&Image>| Binding::SampledImage { view: image.unwrap_or(&stand_in).view, sampler: sampler.raw };
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            &[
                Binding::StorageBuffer(geometry.lights.raw),
                Binding::UniformBuffer(geometry.uniforms.raw),
                sampled(terms.occlusion),
                sampled(terms.texels()),
                sampled(terms.pixels()),
                Binding::StorageBuffer(terms.vertex_values().unwrap_or(&stand_in_values).raw),
                Binding::StorageBuffer(geometry.layers.raw),
                Binding::SampledImage { view: moments.view, sampler: moments_sampler.raw },
            ],
        )?;
        let defines = variant(terms);
        let shaders = [
            compile(include_str!("engine_shaders/forward.vert"), shaderc::ShaderKind::Vertex, &defines)?,
            compile(include_str!("engine_shaders/forward.frag"), shaderc::ShaderKind::Fragment, &defines)?,
        ];
        let push_bytes = std::mem::size_of::<EngineMaterial>();
        let pipeline = pipeline(ctx, "engine.forward", [&shaders[0], &shaders[1]], &descriptors, &[RGBA32F], push_bytes)?;
        let variant = defines.iter().map(|(name, value)| format!("{name}={value}")).collect::<Vec<_>>().join(" ");
        Ok(Forward { pipeline, descriptors, color, stand_in, readback, variant, _held: (stand_in_values, sampler, moments_sampler) })
    }

    /// Draws every mesh, reading the effect's terms from the state relume left its images in
    /// (`images`) and the shadow maps from theirs (`states.moments`, as relume handed them
    /// back); with `read_back`, then copies the colour to the read-back buffer.
    fn record(
        &self,
        rec: &CommandRecorder,
        geometry: &Geometry,
        (moments, depth): (&Image, &Image),
        images: ImageState,
        states: &mut States,
        read_back: bool,
    ) {
        debug_assert_eq!(images, Access::FragmentSampled.state(), "the engine asked relume for fragment-shader reads");
        bring(rec, moments, &mut states.moments, Access::FragmentSampled);
        bring(rec, &self.stand_in, &mut states.stand_in, Access::FragmentSampled);
        bring(rec, &self.color, &mut states.color, Access::ColorAttachmentWrite);
        bring(rec, depth, &mut states.depths[1], Access::DepthAttachmentWrite);
        let target = (depth.desc.extent(), [self.color.view], [0.0; 4], depth.view);
        geometry.draw(rec, (&self.pipeline, &self.descriptors), target, |mesh| geometry.draws[mesh].2);
        if read_back {
            bring(rec, &self.color, &mut states.color, Access::TransferSource);
            rec.copy_image_to_buffer(&self.color, self.readback.raw);
            rec.transfer_to_host_barrier();
        }
    }
}

/// The engine's shadow maps: the moments of the light depth of every layer of relume's shadow
/// views, which it shades its direct light with and hands the effect.
struct ShadowPass {
    pipeline: Pipeline,
    descriptors: DescriptorSet,
    layer_views: Vec<ImageView>,
    pushes: Vec<EngineShadowView>,
}

/// One shadow view as the engine's shadow-map shaders take it (engine_shaders/moments.*).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EngineShadowView {
    clip_from_world: [f32; 16],
    depth: [f32; 4],
    origin: [f32; 4],
}

impl ShadowPass {
    fn new(ctx: &Arc<Context>, moments: &Image, views: &[ShadowMapView]) -> Result<ShadowPass, Box<dyn Error>> {
        let descriptors = DescriptorSet::new(ctx, vk::ShaderStageFlags::VERTEX, &[])?;
        let shaders = [
            compile(include_str!("engine_shaders/moments.vert"), shaderc::ShaderKind::Vertex, &[])?,
            compile(include_str!("engine_shaders/moments.frag"), shaderc::ShaderKind::Fragment, &[])?,
        ];
        let push_bytes = std::mem::size_of::<EngineShadowView>();
        let pipeline = pipeline(ctx, "engine.shadows", [&shaders[0], &shaders[1]], &descriptors, &[moments.desc.format], push_bytes)?;
        let layer_views = (0..views.len() as u32).map(|layer| moments.layer_view(layer)).collect::<Result<Vec<_>, _>>()?;
        let pushes = views
            .iter()
            .map(|v| {
                let (depth, origin) = match v.depth {
                    LightDepth::Distance { from } => (from.extend(0.0), 0.0),
                    LightDepth::Along { direction, origin } => (direction.extend(1.0), origin),
                };
                EngineShadowView {
                    clip_from_world: v.clip_from_world.to_cols_array(),
                    depth: depth.to_array(),
                    origin: [origin, 0.0, 0.0, v.far],
                }
            })
            .collect();
        Ok(ShadowPass { pipeline, descriptors, layer_views, pushes })
    }

    /// Every layer cleared to its far depth and drawn; `moments` left as colour attachment
    /// written.
    fn record(&self, rec: &CommandRecorder, geometry: &Geometry, (moments, depth): (&Image, &Image), states: &mut States) {
        bring(rec, moments, &mut states.moments, Access::ColorAttachmentWrite);
        for (view, push) in self.layer_views.iter().zip(&self.pushes) {
            // One depth buffer serves every layer: each clear waits for the layer before.
            bring(rec, depth, &mut states.depths[2], Access::DepthAttachmentWrite);
            let far = push.origin[3];
            let target = (moments.desc.extent(), [view.raw], [far, far * far, 0.0, 0.0], depth.view);
            geometry.draw(rec, (&self.pipeline, &self.descriptors), target, |_| *push);
        }
    }
}

/// Every mesh's vertices (position, normal, uv1) in the scene's order, the indices made global,
/// and per mesh its index range and material.
fn geometry(scene: &Scene) -> (Vec<[f32; 8]>, Vec<u32>, Vec<(u32, u32, EngineMaterial)>) {
    let (mut vertices, mut indices, mut draws) = (Vec::new(), Vec::new(), Vec::new());
    for mesh in &scene.meshes {
        let base = vertices.len() as u32;
        for (i, (p, n)) in mesh.positions.iter().zip(&mesh.normals).enumerate() {
            let uv1 = mesh.uv1.as_ref().map_or(glam::Vec2::ZERO, |uv| uv[i]);
            vertices.push([p.x, p.y, p.z, n.x, n.y, n.z, uv1.x, uv1.y]);
        }
        let m = &scene.materials[mesh.material];
        let phong = m.phong.map_or([0.0; 4], |p| p.specular.extend(p.exponent).to_array());
        let material = EngineMaterial { base_color: m.base_color.to_array(), emission: m.emission.extend(0.0).to_array(), phong };
        draws.push((indices.len() as u32, mesh.indices.len() as u32, material));
        indices.extend(mesh.indices.iter().map(|i| i + base));
    }
    (vertices, indices, draws)
}

/// The engine's lights, each with its first layer of `views` and a directional light's depth
/// origin.
fn engine_lights(scene: &Scene, views: &[ShadowMapView]) -> Vec<EngineLight> {
    let lights = scene.lights.iter().enumerate().map(|(index, l)| {
        let first = views.iter().position(|v| v.light == index).unwrap_or(0);
        let origin = match views.get(first).map(|v| v.depth) {
            Some(LightDepth::Along { origin, .. }) => origin,
            _ => 0.0,
        };
        let (kind, cone) = match l.kind {
            LightKind::Point => (0.0, [0.0; 4]),
            LightKind::Spot { inner_cone, outer_cone } => {
                (1.0, [outer_cone.cos(), 1.0 / (inner_cone.cos() - outer_cone.cos()).max(1e-4), 0.0, 0.0])
            }
            LightKind::Directional => (2.0, [0.0; 4]),
        };
        EngineLight {
            position_kind: l.position.extend(kind).to_array(),
            direction_range: l.direction.extend(l.range.unwrap_or(0.0)).to_array(),
            intensity: l.intensity.extend(0.0).to_array(),
            cone,
            shadow: [first as f32, origin, 0.0, 0.0],
        }
    });
    // A storage buffer is never empty.
    lights.chain(std::iter::once(EngineLight::zeroed())).collect()
}

const RGBA32F: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// The shader variant of the effect's terms (engine_shaders/engine.glsl).
fn variant(terms: &Terms) -> Vec<(&'static str, String)> {
    let mut defines = vec![("RELUME_TERM", terms.irradiance_kind().to_string())];
    defines.extend(terms.occlusion.map(|_| ("OCCLUSION", String::new())));
    defines.extend(terms.radiance.map(|_| ("RADIANCE", String::new())));
    defines
}

/// The engine's shader compiler: its own sources, and relume's `shaders/` on the include path.
fn compile(source: &str, kind: shaderc::ShaderKind, defines: &[(&str, String)]) -> Result<Vec<u8>, Box<dyn Error>> {
    let compiler = shaderc::Compiler::new()?;
    let mut options = shaderc::CompileOptions::new()?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    defines.iter().for_each(|(name, value)| options.add_macro_definition(name, Some(value.as_str())));
    let relume_shaders = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    options.set_include_callback(move |name, _, _, _| {
        let content = match name {
            "engine.glsl" => include_str!("engine_shaders/engine.glsl").to_string(),
            "engine_frame.glsl" => include_str!("engine_shaders/engine_frame.glsl").to_string(),
            _ => std::fs::read_to_string(relume_shaders.join(name)).map_err(|e| format!("{name}: {e}"))?,
        };
        Ok(shaderc::ResolvedInclude { resolved_name: name.to_string(), content })
    });
    Ok(compiler.compile_into_spirv(source, kind, "engine", "main", Some(&options))?.as_binary_u8().to_vec())
}
