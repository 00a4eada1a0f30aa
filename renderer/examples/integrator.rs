//! An engine integrating relume. The engine owns the Vulkan instance, device, queue, command
//! buffer, fence and its output image; relume is a library inside it. In one command buffer
//! of the engine's, the engine clears its image (its own first pass), relume records its whole
//! frame and copies the display into that image (`Renderer::record_to`, told what state the
//! image is in, handing back the state it leaves it in), and the engine copies the image to
//! host memory (its own second pass, starting from the state relume handed back). The engine
//! submits and waits itself; relume never submits or waits during the frame.
//!
//!     cargo run -p relume-renderer --example integrator [SCENE.gltf] [--validation]
//!
//! With `--validation` the engine turns on the Khronos validation layer with synchronization
//! validation and counts its messages (a wrong handed-back layout would be one).

#[path = "common/engine_device.rs"]
mod engine_device;

use ash::vk;
use engine_device::Engine;
use relume_renderer::vk::{CommandRecorder, Context, ImageState};
use relume_renderer::{CallerImage, RenderSettings, Renderer};
use std::error::Error;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What the engine got out of one frame.
pub struct Outcome {
    /// The device the engine created (relume rendered on it).
    pub device: String,
    /// The engine's image after its second pass: relume's display pixels, RGBA8.
    pub pixels: Vec<u8>,
    /// The state relume handed back for the engine's image.
    pub handed_back: ImageState,
    /// The validation layer's warnings and errors over the whole run (empty without it).
    pub validation_messages: Vec<String>,
}

#[allow(dead_code)]
fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let validation = args.iter().any(|a| a == "--validation");
    let default_scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/occluder-plane.gltf");
    let scene = args.iter().find(|a| !a.starts_with("--")).map_or(default_scene, PathBuf::from);
    let outcome = run(&scene, 256, 256, validation)?;
    println!("device: {}", outcome.device);
    println!(
        "relume handed the image back in {:?} (stage {:?}, access {:?})",
        outcome.handed_back.layout, outcome.handed_back.stage, outcome.handed_back.access
    );
    let lit = outcome.pixels.chunks_exact(4).filter(|p| p[..3] != [255, 0, 255]).count();
    println!("{lit} of {} pixels hold relume's frame", outcome.pixels.len() / 4);
    if validation {
        println!("{} validation message(s)", outcome.validation_messages.len());
        for message in &outcome.validation_messages {
            println!("  {message}");
        }
    }
    Ok(())
}

/// Renders `scene` at `width` x `height` into the engine's own image, as described above.
pub fn run(scene: &Path, width: u32, height: u32, validation: bool) -> Result<Outcome, Box<dyn Error>> {
    let engine = Engine::new(validation)?;
    let loaded = relume_bake::gltf_load::load(scene)?;
    let ctx = engine.context()?;
    let settings = RenderSettings { width, height, ..RenderSettings::default() };
    let mut renderer = Renderer::new_blocking(&ctx, &loaded.scene, &settings, &[])?;
    let frame = engine.frame(&ctx, &mut renderer, width, height);
    drop(renderer);
    drop(ctx);
    let outcome = frame.map(|(pixels, handed_back)| Outcome {
        device: engine.name.clone(),
        pixels,
        handed_back,
        validation_messages: engine.validation_messages(),
    });
    engine.destroy();
    outcome
}

impl Engine {
    /// One frame: the engine's clear, relume's frame into the engine's image, the engine's
    /// copy to host memory; submitted and waited for by the engine. Returns the pixels and the
    /// state relume handed back.
    fn frame(&self, ctx: &Arc<Context>, renderer: &mut Renderer, width: u32, height: u32) -> Result<(Vec<u8>, ImageState), Box<dyn Error>> {
        let d = &self.device;
        let extent = vk::Extent2D { width, height };
        let bytes = width as u64 * height as u64 * 4;
        let range = vk::ImageSubresourceRange::default().aspect_mask(vk::ImageAspectFlags::COLOR).level_count(1).layer_count(1);
        // SAFETY: the engine's own objects, made from valid create infos, used while alive and
        // destroyed after the fence shows the GPU is done with them.
        unsafe {
            let image_info = vk::ImageCreateInfo::default()
                .image_type(vk::ImageType::TYPE_2D)
                .format(vk::Format::R8G8B8A8_UNORM)
                .extent(vk::Extent3D { width, height, depth: 1 })
                .mip_levels(1)
                .array_layers(1)
                .samples(vk::SampleCountFlags::TYPE_1)
                .usage(vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC);
            let image = d.create_image(&image_info, None)?;
            let image_memory = self.bind(d.get_image_memory_requirements(image), vk::MemoryPropertyFlags::DEVICE_LOCAL)?;
            d.bind_image_memory(image, image_memory, 0)?;
            let buffer = d.create_buffer(&vk::BufferCreateInfo::default().size(bytes).usage(vk::BufferUsageFlags::TRANSFER_DST), None)?;
            let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
            let buffer_memory = self.bind(d.get_buffer_memory_requirements(buffer), host)?;
            d.bind_buffer_memory(buffer, buffer_memory, 0)?;
            let pool = d.create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(self.family), None)?;
            let allocate =
                vk::CommandBufferAllocateInfo::default().command_pool(pool).level(vk::CommandBufferLevel::PRIMARY).command_buffer_count(1);
            let cmd = d.allocate_command_buffers(&allocate)?[0];
            let fence = d.create_fence(&vk::FenceCreateInfo::default(), None)?;

            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
            // The engine's first pass: its image cleared to magenta.
            let cleared = ImageState {
                stage: vk::PipelineStageFlags2::ALL_TRANSFER,
                access: vk::AccessFlags2::TRANSFER_WRITE,
                layout: vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            };
            let undefined =
                ImageState { stage: vk::PipelineStageFlags2::NONE, access: vk::AccessFlags2::NONE, layout: vk::ImageLayout::UNDEFINED };
            barrier(d, cmd, image, range, undefined, cleared);
            let magenta = vk::ClearColorValue { float32: [1.0, 0.0, 1.0, 1.0] };
            d.cmd_clear_color_image(cmd, image, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &magenta, &[range]);
            // relume's frame, into the engine's command buffer and image.
            let target = CallerImage { image, format: vk::Format::R8G8B8A8_UNORM, extent, state: cleared };
            let handed_back = renderer.record_to(&CommandRecorder::wrap(ctx, cmd), &target)?;
            // The engine's second pass, from the state relume handed back: a copy to the host.
            let source = ImageState {
                stage: vk::PipelineStageFlags2::COPY,
                access: vk::AccessFlags2::TRANSFER_READ,
                layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            };
            barrier(d, cmd, image, range, handed_back, source);
            let region = vk::BufferImageCopy::default()
                .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1))
                .image_extent(vk::Extent3D { width, height, depth: 1 });
            d.cmd_copy_image_to_buffer(cmd, image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buffer, &[region]);
            let to_host = [vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                .dst_access_mask(vk::AccessFlags2::HOST_READ)];
            d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&to_host));
            self.end_submit_and_wait(cmd, fence)?;

            let mapped = d.map_memory(buffer_memory, 0, bytes, vk::MemoryMapFlags::empty())? as *const u8;
            let pixels = std::slice::from_raw_parts(mapped, bytes as usize).to_vec();
            d.unmap_memory(buffer_memory);
            d.destroy_fence(fence, None);
            d.destroy_command_pool(pool, None);
            d.destroy_buffer(buffer, None);
            d.free_memory(buffer_memory, None);
            d.destroy_image(image, None);
            d.free_memory(image_memory, None);
            Ok((pixels, handed_back))
        }
    }

    /// Memory of a type with `flags` for `requirements`.
    fn bind(&self, requirements: vk::MemoryRequirements, flags: vk::MemoryPropertyFlags) -> Result<vk::DeviceMemory, Box<dyn Error>> {
        // SAFETY: plain queries and an allocation of a type the device offers.
        unsafe {
            let types = self.instance.get_physical_device_memory_properties(self.physical);
            let index = (0..types.memory_type_count)
                .find(|&i| requirements.memory_type_bits & (1 << i) != 0 && types.memory_types[i as usize].property_flags.contains(flags))
                .ok_or("no memory type fits")?;
            let info = vk::MemoryAllocateInfo::default().allocation_size(requirements.size).memory_type_index(index);
            Ok(self.device.allocate_memory(&info, None)?)
        }
    }
}

/// The engine's own barrier of `image` from one state to another.
fn barrier(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    from: ImageState,
    to: ImageState,
) {
    let barrier = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(from.stage)
        .src_access_mask(from.access)
        .dst_stage_mask(to.stage)
        .dst_access_mask(to.access)
        .old_layout(from.layout)
        .new_layout(to.layout)
        .image(image)
        .subresource_range(range)];
    // SAFETY: `cmd` is recording and `image` is the engine's live image.
    unsafe { device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barrier)) };
}
