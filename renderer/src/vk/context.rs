//! The Vulkan context: instance, device, queue and allocator. relume makes its own headless
//! context, or wraps a device the caller already has. A context is shared (`Arc<Context>`):
//! every object made from it holds a reference, so a caller can own the context beside the
//! renderer and other state, and it lives until the last object made from it is dropped.

use super::device::{self, DeviceInfo};
use super::instance::{self, MessageLog};
use super::sync::Fence;
use super::VkResult;
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Turns on VK_LAYER_KHRONOS_validation with synchronization validation.
    pub validation: bool,
    /// A device index or part of its name (e.g. "llvmpipe"); None picks a real GPU if any.
    pub device: Option<String>,
}

/// Send and Sync: the allocator is behind a mutex, submissions to the queue take a lock, and
/// the context owns no command pool (each [`super::CommandBuffer`] owns its own).
pub struct Context {
    pub device: ash::Device,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub queue_family: u32,
    pub info: DeviceInfo,
    queue: Mutex<vk::Queue>,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    _entry: ash::Entry,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    messages: MessageLog,
    owns_device: bool,
}

impl Context {
    /// A headless context on a device chosen by `options` (or the RELUME_DEVICE variable).
    pub fn headless(options: &ContextOptions) -> VkResult<Arc<Context>> {
        let messages: MessageLog = Arc::new(Mutex::new(Vec::new()));
        let parts = instance::create(options.validation, &messages)?;
        let selector = options.device.clone().or_else(|| std::env::var("RELUME_DEVICE").ok());
        let created = device::create(&parts.instance, selector.as_deref());
        let dev = match created {
            Ok(d) => d,
            Err(e) => {
                destroy_instance(&parts.instance, parts.debug.as_ref());
                return Err(e);
            }
        };
        let kept = Kept { entry: parts.entry, debug: parts.debug, messages, owns_device: true };
        Self::assemble(parts.instance, dev.physical, dev.device, dev.queue_family, dev.queue, dev.info, kept)
    }

    /// Wraps a device the caller created and keeps owning. The physical device must offer
    /// what relume needs (checked here: Vulkan 1.3, dynamicRendering, synchronization2,
    /// shaderStorageImageExtendedFormats) and the caller must have enabled those features.
    /// relume never waits on, nor destroys, the caller's device or instance. It submits to
    /// `queue` only in functions that say so (their names end in `_blocking`, and the headless
    /// driver), never while recording a frame; the caller must not
    /// use the queue from another thread during those calls.
    pub fn from_existing(
        entry: ash::Entry,
        instance: ash::Instance,
        physical: vk::PhysicalDevice,
        device: ash::Device,
        queue_family: u32,
        queue: vk::Queue,
    ) -> VkResult<Arc<Context>> {
        let info = device::check_and_describe(&instance, physical, queue_family)?;
        let kept = Kept { entry, debug: None, messages: Arc::new(Mutex::new(Vec::new())), owns_device: false };
        Self::assemble(instance, physical, device, queue_family, queue, info, kept)
    }

    fn assemble(
        instance: ash::Instance,
        physical: vk::PhysicalDevice,
        device: ash::Device,
        queue_family: u32,
        queue: vk::Queue,
        info: DeviceInfo,
        kept: Kept,
    ) -> VkResult<Arc<Context>> {
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(e) => {
                if kept.owns_device {
                    // SAFETY: nothing was created on the device yet.
                    unsafe { device.destroy_device(None) };
                    destroy_instance(&instance, kept.debug.as_ref());
                }
                return Err(e.into());
            }
        };
        let Kept { entry, debug, messages, owns_device } = kept;
        Ok(Arc::new(Context {
            device,
            instance,
            physical,
            queue_family,
            info,
            queue: Mutex::new(queue),
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            _entry: entry,
            debug,
            messages,
            owns_device,
        }))
    }

    pub fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The shared log of validation messages; it outlives the context, so teardown messages
    /// (objects never destroyed) can be read after the context is dropped.
    pub fn message_log(&self) -> Arc<Mutex<Vec<String>>> {
        Arc::clone(&self.messages)
    }

    /// Validation warnings and errors reported so far (empty without validation).
    pub fn validation_messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }

    /// Begins recording `cmd` for one submission.
    pub fn begin(&self, cmd: vk::CommandBuffer) -> VkResult<CommandRecorder<'_>> {
        let info = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the caller guarantees `cmd` is not pending (its fence was waited on) and that
        // no other thread records into a buffer of its pool.
        unsafe {
            self.device.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())?;
            self.device.begin_command_buffer(cmd, &info)?;
        }
        Ok(CommandRecorder { device: &self.device, cmd })
    }

    /// Ends `rec`, submits it signalling `fence`, and waits for that fence (not the device):
    /// the one way relume submits (uploads at creation, read-backs, the headless driver).
    pub fn submit_and_wait(&self, rec: CommandRecorder, fence: &Fence) -> VkResult<()> {
        let fence = fence.raw;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(rec.cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
        let queue = self.queue.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        // SAFETY: the buffer was fully recorded; the fence is unsignalled and reset after use;
        // the lock gives the queue the external synchronization it needs.
        unsafe {
            self.device.end_command_buffer(rec.cmd)?;
            self.device.queue_submit2(*queue, &submit, fence)?;
            self.device.wait_for_fences(&[fence], true, u64::MAX)?;
            self.device.reset_fences(&[fence])?;
        }
        Ok(())
    }
}

/// What the context keeps beside the device: the loader, relume's own validation messenger
/// and log, and whether relume made (and so destroys) the device and instance.
struct Kept {
    entry: ash::Entry,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    messages: MessageLog,
    owns_device: bool,
}

fn destroy_instance(instance: &ash::Instance, debug: Option<&(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>) {
    // SAFETY: nothing created from the instance is alive any more.
    unsafe {
        if let Some((loader, messenger)) = debug {
            loader.destroy_debug_utils_messenger(*messenger, None);
        }
        instance.destroy_instance(None);
    }
}

impl Drop for Context {
    /// Teardown in reverse order of creation: allocator, then (when relume made them) device,
    /// messenger and instance. Every object made from this context holds an `Arc` of it, so
    /// all of them are gone by now.
    fn drop(&mut self) {
        // SAFETY: no object made from this context is alive; the wait covers submissions a
        // caller made on relume's own device.
        unsafe {
            if self.owns_device {
                let _ = self.device.device_wait_idle();
            }
            ManuallyDrop::drop(&mut self.allocator);
            if self.owns_device {
                self.device.destroy_device(None);
                destroy_instance(&self.instance, self.debug.as_ref());
            }
        }
    }
}

/// A command buffer being recorded; the safe face of every vkCmd* call passes make.
pub struct CommandRecorder<'a> {
    pub(super) device: &'a ash::Device,
    pub cmd: vk::CommandBuffer,
}

impl<'a> CommandRecorder<'a> {
    /// Records into a command buffer the caller began and will end and submit.
    pub fn wrap(ctx: &'a Context, cmd: vk::CommandBuffer) -> Self {
        CommandRecorder { device: &ctx.device, cmd }
    }

    pub fn image_barrier(&self, barrier: vk::ImageMemoryBarrier2) {
        let barriers = [barrier];
        // SAFETY: recording state; the barrier names a live image.
        unsafe { self.device.cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers)) };
    }

    pub fn buffer_barrier(&self, barrier: vk::BufferMemoryBarrier2) {
        let barriers = [barrier];
        // SAFETY: recording state; the barrier names a live buffer.
        unsafe { self.device.cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().buffer_memory_barriers(&barriers)) };
    }

    pub fn bind_compute(&self, pipeline: vk::Pipeline, layout: vk::PipelineLayout, set: vk::DescriptorSet) {
        self.bind(vk::PipelineBindPoint::COMPUTE, pipeline, layout, set);
    }

    pub fn bind_graphics(&self, pipeline: vk::Pipeline, layout: vk::PipelineLayout, set: vk::DescriptorSet) {
        self.bind(vk::PipelineBindPoint::GRAPHICS, pipeline, layout, set);
    }

    fn bind(&self, point: vk::PipelineBindPoint, pipeline: vk::Pipeline, layout: vk::PipelineLayout, set: vk::DescriptorSet) {
        // SAFETY: recording state; the set matches the layout it was made for.
        unsafe {
            self.device.cmd_bind_pipeline(self.cmd, point, pipeline);
            self.device.cmd_bind_descriptor_sets(self.cmd, point, layout, 0, &[set], &[]);
        }
    }

    pub fn push_constants<T: bytemuck::NoUninit>(&self, layout: vk::PipelineLayout, value: &T) {
        let bytes = bytemuck::bytes_of(value);
        // SAFETY: recording state; the layout's range covers ALL stages from offset 0.
        unsafe { self.device.cmd_push_constants(self.cmd, layout, vk::ShaderStageFlags::ALL, 0, bytes) };
    }

    pub fn dispatch(&self, x: u32, y: u32, z: u32) {
        // SAFETY: recording state with a compute pipeline bound.
        unsafe { self.device.cmd_dispatch(self.cmd, x, y, z) };
    }

    /// Begins dynamic rendering into the colour attachments `colors` (each cleared to `clear`)
    /// and `depth` (cleared to far), with viewport and scissor covering `extent`.
    pub fn begin_rendering<const N: usize>(&self, extent: vk::Extent2D, colors: [vk::ImageView; N], clear: [f32; 4], depth: vk::ImageView) {
        let colors = colors.map(|color| {
            vk::RenderingAttachmentInfo::default()
                .image_view(color)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: clear } })
        });
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(depth)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
        let info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&colors).depth_attachment(&depth);
        let viewport =
            vk::Viewport { x: 0.0, y: 0.0, width: extent.width as f32, height: extent.height as f32, min_depth: 0.0, max_depth: 1.0 };
        // SAFETY: recording state; the views are live and in the stated layouts (the tracker saw to it).
        unsafe {
            self.device.cmd_begin_rendering(self.cmd, &info);
            self.device.cmd_set_viewport(self.cmd, 0, &[viewport]);
            self.device.cmd_set_scissor(self.cmd, 0, &[area]);
        }
    }

    pub fn end_rendering(&self) {
        // SAFETY: paired with begin_rendering.
        unsafe { self.device.cmd_end_rendering(self.cmd) };
    }

    pub fn bind_geometry(&self, vertices: vk::Buffer, indices: vk::Buffer) {
        // SAFETY: recording state; the buffers hold vertices and u32 indices.
        unsafe {
            self.device.cmd_bind_vertex_buffers(self.cmd, 0, &[vertices], &[0]);
            self.device.cmd_bind_index_buffer(self.cmd, indices, 0, vk::IndexType::UINT32);
        }
    }

    /// Draws `count` indices from `first` of the bound geometry.
    pub fn draw_indexed(&self, first: u32, count: u32) {
        // SAFETY: recording state inside rendering; the range lies in the bound index buffer.
        unsafe { self.device.cmd_draw_indexed(self.cmd, count, 1, first, 0, 0) };
    }

    /// Copies an image into a buffer, tightly packed, layer after layer.
    pub fn copy_image_to_buffer(&self, image: &super::Image, buffer: vk::Buffer) {
        let layers = vk::ImageSubresourceLayers::default().aspect_mask(image.desc.aspect()).layer_count(image.desc.layers);
        let region = vk::BufferImageCopy::default().image_subresource(layers).image_extent(vk::Extent3D {
            width: image.desc.width,
            height: image.desc.height,
            depth: 1,
        });
        // SAFETY: the image is in TRANSFER_SRC_OPTIMAL (tracker) and the buffer is large enough.
        unsafe { self.device.cmd_copy_image_to_buffer(self.cmd, image.raw, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buffer, &[region]) };
    }

    /// Copies `size` bytes of `source` from `source_offset` to the start of `destination`.
    pub fn copy_buffer(&self, source: vk::Buffer, source_offset: u64, destination: vk::Buffer, size: u64) {
        let region = vk::BufferCopy { src_offset: source_offset, dst_offset: 0, size };
        // SAFETY: recording state; both ranges lie in their buffers (the callers' check).
        unsafe { self.device.cmd_copy_buffer(self.cmd, source, destination, &[region]) };
    }

    /// Fills the top-left `extent` of one layer of an image (in TRANSFER_DST_OPTIMAL) from
    /// tightly packed buffer data starting at `offset` bytes.
    pub fn copy_buffer_to_image_layer(&self, buffer: vk::Buffer, offset: u64, image: &super::Image, layer: u32, extent: vk::Extent2D) {
        let region = vk::BufferImageCopy::default()
            .buffer_offset(offset)
            .image_subresource(
                vk::ImageSubresourceLayers::default().aspect_mask(image.desc.aspect()).base_array_layer(layer).layer_count(1),
            )
            .image_extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 });
        // SAFETY: the image is in TRANSFER_DST_OPTIMAL (tracker) and the buffer holds its texels.
        unsafe { self.device.cmd_copy_buffer_to_image(self.cmd, buffer, image.raw, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &[region]) };
    }

    /// Writes each update's data into its device-local buffer inside the command stream, between
    /// two barriers for all of them: earlier shader reads of the buffers finish first, and the
    /// vertex, fragment and compute stages that follow see the new data. Data longer than one
    /// vkCmdUpdateBuffer carries (65536 bytes) goes in pieces of that size; each is a multiple
    /// of 4 bytes where the data is.
    pub fn update_buffers<const N: usize>(&self, updates: [(vk::Buffer, &[u8]); N]) {
        let shader_stages =
            vk::PipelineStageFlags2::VERTEX_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER | vk::PipelineStageFlags2::COMPUTE_SHADER;
        let barrier = |buffer, src_stage, src_access, dst_stage, dst_access| {
            vk::BufferMemoryBarrier2::default()
                .src_stage_mask(src_stage)
                .src_access_mask(src_access)
                .dst_stage_mask(dst_stage)
                .dst_access_mask(dst_access)
                .buffer(buffer)
                .size(vk::WHOLE_SIZE)
        };
        // vkCmdUpdateBuffer is a clear command: ALL_TRANSFER covers its stage under every
        // reading of synchronization2 (older validation layers call it COPY, newer CLEAR).
        let transfer = vk::PipelineStageFlags2::ALL_TRANSFER;
        let reads = vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::UNIFORM_READ;
        let before = updates.map(|(buffer, _)| barrier(buffer, shader_stages, reads, transfer, vk::AccessFlags2::TRANSFER_WRITE));
        let after = updates.map(|(buffer, _)| barrier(buffer, transfer, vk::AccessFlags2::TRANSFER_WRITE, shader_stages, reads));
        // SAFETY: recording state outside rendering; the caller keeps `data` within the limits.
        unsafe {
            self.device.cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().buffer_memory_barriers(&before));
            for (buffer, data) in updates {
                for (k, piece) in data.chunks(UPDATE_BYTES).enumerate() {
                    self.device.cmd_update_buffer(self.cmd, buffer, (k * UPDATE_BYTES) as vk::DeviceSize, piece);
                }
            }
            self.device.cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().buffer_memory_barriers(&after));
        }
    }

    /// Copies all of `source` (in TRANSFER_SRC_OPTIMAL) into `destination`, an image of the same
    /// size and texel size in TRANSFER_DST_OPTIMAL, layer 0.
    pub fn copy_image(&self, source: &super::Image, destination: vk::Image) {
        let layer = vk::ImageSubresourceLayers::default().aspect_mask(source.desc.aspect()).layer_count(1);
        let region = vk::ImageCopy::default().src_subresource(layer).dst_subresource(layer).extent(vk::Extent3D {
            width: source.desc.width,
            height: source.desc.height,
            depth: 1,
        });
        // SAFETY: recording state; both images are in the stated layouts (the caller's barrier)
        // and the caller checked that the destination is large enough and format-compatible.
        unsafe {
            self.device.cmd_copy_image(
                self.cmd,
                source.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                destination,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Makes the transfer writes of this submission visible to the host after its fence.
    pub fn transfer_to_host_barrier(&self) {
        let barrier = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        // SAFETY: recording state.
        unsafe { self.device.cmd_pipeline_barrier2(self.cmd, &vk::DependencyInfo::default().memory_barriers(&barrier)) };
    }
}

/// The most bytes one vkCmdUpdateBuffer writes.
const UPDATE_BYTES: usize = 65536;
