//! An engine that is not relume, using relume's techniques as effects. The engine owns its
//! instance, device, queue and submissions (common/engine_device.rs), its geometry, its
//! lights, its forward pass and its shaders (engine_shaders/, compiled by the engine at start
//! with shaderc); relume's `Effect` records the technique's passes into the engine's command
//! buffer and hands back the term, which the engine's fragment shader samples with
//! `shaders/include/relume.glsl`. relume's lighting pass, shadow maps for the engine's direct
//! light and tonemap take no part: the engine shades, unshadowed, in its own pass.
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
use relume_renderer::technique::{MakeTechnique, Terms};
use relume_renderer::vk::{transition, Access, Binding, Buffer, CommandBuffer, CommandRecorder, Context, DescriptorSet, Fence};
use relume_renderer::vk::{GraphicsPipelineDesc, Image, ImageDesc, ImageState, Pipeline, Sampler};
use relume_renderer::{Effect, RenderSettings, TermReads};
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
    let outcome = drawn.map(|(radiance, variant)| Outcome {
        device: engine.name.clone(),
        radiance,
        variant,
        validation_messages: engine.validation_messages(),
    });
    engine.destroy();
    outcome
}

/// The effect, then the engine's forward pass and its read-back, in one command buffer the
/// engine submits and waits for. Returns the radiance and the shader variant.
fn frame(
    engine: &Engine,
    ctx: &Arc<Context>,
    scene: &Scene,
    techniques: &[&dyn MakeTechnique],
    settings: &RenderSettings,
) -> Result<(Vec<f32>, String), Box<dyn Error>> {
    let mut effect = Effect::new_blocking(ctx, scene, settings, techniques)?;
    let forward = Forward::new(ctx, scene, &effect.terms()?, settings)?;
    let (cmd, fence) = (CommandBuffer::new(ctx)?, Fence::new(ctx)?);
    let rec = ctx.begin(cmd.raw)?;
    let output = effect.record(&rec, TermReads::default())?;
    forward.record(&rec, output.images);
    engine.end_submit_and_wait(cmd.raw, fence.raw)?;
    let bytes = forward.readback.mapped_bytes(forward.color.desc.texel_count() as usize * 16)?;
    Ok((bytemuck::pod_collect_to_vec(bytes), forward.variant))
}

/// The engine's lights as its shader reads them (engine_shaders/engine.glsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EngineLight {
    position_kind: [f32; 4],
    direction_range: [f32; 4],
    intensity: [f32; 4],
    cone: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EngineFrame {
    clip_from_world: [f32; 16],
    camera_position: [f32; 4],
    ambient_beta: [f32; 4],
    counts: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EngineMaterial {
    base_color: [f32; 4],
    emission: [f32; 4],
    phong: [f32; 4],
}

/// The engine's forward pass: its geometry (position, normal, uv1 per vertex, every mesh's
/// vertices in the scene's order, so that gl_VertexIndex is the index relume's per-vertex
/// terms use), its pipeline for the effect's terms, its targets and its read-back buffer.
struct Forward {
    pipeline: Pipeline,
    descriptors: DescriptorSet,
    vertices: Buffer,
    indices: Buffer,
    draws: Vec<(u32, u32, EngineMaterial)>,
    color: Image,
    depth: Image,
    stand_in: Image,
    readback: Buffer,
    variant: String,
    // Named by the descriptor set, so kept as long as it.
    _held: (Buffer, Buffer, Buffer, Sampler),
}

impl Forward {
    fn new(ctx: &Arc<Context>, scene: &Scene, terms: &Terms, settings: &RenderSettings) -> Result<Forward, Box<dyn Error>> {
        if scene.materials.iter().any(|m| m.base_color_texture.is_some()) || (settings.environment_ambient && scene.environment.is_some()) {
            return Err("the engine example draws untextured materials and no environment light".into());
        }
        let (vertices, indices, draws) = geometry(scene);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let vertices = Buffer::with_data(ctx, "engine vertices", vk::BufferUsageFlags::VERTEX_BUFFER, &vertices)?;
        let indices = Buffer::with_data(ctx, "engine indices", vk::BufferUsageFlags::INDEX_BUFFER, &indices)?;
        let lights = Buffer::with_data(ctx, "engine lights", usage, &engine_lights(scene))?;
        let (w, h) = (settings.width, settings.height);
        let uniforms = EngineFrame {
            clip_from_world: scene.camera.clip_from_world(w, h).to_cols_array(),
            camera_position: scene.camera.position().extend(1.0).to_array(),
            ambient_beta: settings.ambient.extend(settings.beta).to_array(),
            counts: [scene.lights.len() as u32, terms.times_occlusion as u32, terms.occluded_direct as u32, 0],
        };
        let uniforms = Buffer::with_data(ctx, "engine frame", vk::BufferUsageFlags::UNIFORM_BUFFER, &[uniforms])?;
        let stand_in_values = Buffer::with_data(ctx, "engine stand-in", usage, &[0.0f32; 4])?;
        let image =
            |name, format, usage, view_type| Image::new(ctx, name, ImageDesc { width: w, height: h, layers: 1, format, usage, view_type });
        use vk::ImageUsageFlags as U;
        let color =
            image("engine color", vk::Format::R32G32B32A32_SFLOAT, U::COLOR_ATTACHMENT | U::TRANSFER_SRC, vk::ImageViewType::TYPE_2D)?;
        let depth = image("engine depth", vk::Format::D32_SFLOAT, U::DEPTH_STENCIL_ATTACHMENT, vk::ImageViewType::TYPE_2D)?;
        let stand_in = Image::new(
            ctx,
            "engine stand-in",
            ImageDesc {
                width: 1,
                height: 1,
                layers: 1,
                format: vk::Format::R32G32B32A32_SFLOAT,
                usage: U::SAMPLED,
                view_type: vk::ImageViewType::TYPE_2D_ARRAY,
            },
        )?;
        let readback = Buffer::with_data(ctx, "engine readback", vk::BufferUsageFlags::TRANSFER_DST, &vec![0.0f32; (w * h * 4) as usize])?;
        let sampler = Sampler::new(ctx, false, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        let sampled = |image: Option<&Image>| Binding::SampledImage { view: image.unwrap_or(&stand_in).view, sampler: sampler.raw };
        let descriptors = DescriptorSet::new(
            ctx,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            &[
                Binding::StorageBuffer(lights.raw),
                Binding::UniformBuffer(uniforms.raw),
                sampled(terms.occlusion),
                sampled(terms.texels()),
                sampled(terms.pixels()),
                Binding::StorageBuffer(terms.vertex_values().unwrap_or(&stand_in_values).raw),
            ],
        )?;
        let defines = variant(terms);
        let named: Vec<String> = defines.iter().map(|(name, value)| format!("{name}={value}")).collect();
        let attribute = |location, format, offset| vk::VertexInputAttributeDescription { location, binding: 0, format, offset };
        let pipeline = Pipeline::graphics(
            ctx,
            &GraphicsPipelineDesc {
                name: "engine.forward",
                vertex: &compile(include_str!("engine_shaders/forward.vert"), shaderc::ShaderKind::Vertex, &defines)?,
                fragment: &compile(include_str!("engine_shaders/forward.frag"), shaderc::ShaderKind::Fragment, &defines)?,
                specialization: &[],
                vertex_stride: 32,
                attributes: &[
                    attribute(0, vk::Format::R32G32B32_SFLOAT, 0),
                    attribute(1, vk::Format::R32G32B32_SFLOAT, 12),
                    attribute(2, vk::Format::R32G32_SFLOAT, 24),
                ],
                color_formats: &[vk::Format::R32G32B32A32_SFLOAT],
                depth_format: vk::Format::D32_SFLOAT,
                cull_mode: vk::CullModeFlags::NONE,
                set: &descriptors,
                push_bytes: std::mem::size_of::<EngineMaterial>() as u32,
            },
        )?;
        let variant = named.join(" ");
        let held = (lights, uniforms, stand_in_values, sampler);
        Ok(Forward { pipeline, descriptors, vertices, indices, draws, color, depth, stand_in, readback, variant, _held: held })
    }

    /// Draws every mesh, reading the effect's terms from the state relume left its images in
    /// (`images`), then copies the colour to the read-back buffer. The engine's barriers, by
    /// hand: its targets and stand-in are new each frame (from UNDEFINED).
    fn record(&self, rec: &CommandRecorder, images: ImageState) {
        debug_assert_eq!(images, Access::FragmentSampled.state(), "the engine asked relume for fragment-shader reads");
        let undefined = Access::Undefined.state();
        transition(rec, (&self.stand_in).into(), undefined, Access::FragmentSampled);
        let drawn = transition(rec, (&self.color).into(), undefined, Access::ColorAttachmentWrite);
        transition(rec, (&self.depth).into(), undefined, Access::DepthAttachmentWrite);
        rec.bind_graphics(self.pipeline.raw, self.pipeline.layout, self.descriptors.set);
        rec.begin_rendering(self.color.desc.extent(), [self.color.view], [0.0; 4], self.depth.view);
        rec.bind_geometry(self.vertices.raw, self.indices.raw);
        for (first_index, index_count, material) in &self.draws {
            rec.push_constants(self.pipeline.layout, material);
            rec.draw_indexed(*first_index, *index_count);
        }
        rec.end_rendering();
        transition(rec, (&self.color).into(), drawn, Access::TransferSource);
        rec.copy_image_to_buffer(&self.color, self.readback.raw);
        rec.transfer_to_host_barrier();
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

fn engine_lights(scene: &Scene) -> Vec<EngineLight> {
    let lights = scene.lights.iter().map(|l| {
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
        }
    });
    // A storage buffer is never empty.
    lights.chain(std::iter::once(EngineLight::zeroed())).collect()
}

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
            _ => std::fs::read_to_string(relume_shaders.join(name)).map_err(|e| format!("{name}: {e}"))?,
        };
        Ok(shaderc::ResolvedInclude { resolved_name: name.to_string(), content })
    });
    Ok(compiler.compile_into_spirv(source, kind, "engine", "main", Some(&options))?.as_binary_u8().to_vec())
}
