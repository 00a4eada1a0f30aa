//! One window frame, recorded into the viewer's own command buffer: relume's frame copied into
//! the viewer's image (`Renderer::record_to`, from the state the viewer says it is in), blitted
//! onto the swapchain image (RGBA to the window's BGRA), the overlay drawn on top, optionally
//! copied out for a screenshot, and handed to presentation. The viewer submits it itself,
//! waiting on the acquire semaphore and signalling the image's render-finished semaphore and
//! its one fence; the next frame waits for that fence (never the device) before recording.

use crate::device::Device;
use crate::swapchain::Swapchain;
use anyhow::Result;
use ash::vk;
use relume_renderer::vk::{
    barrier_between, Buffer, CommandBuffer, CommandRecorder, Context, Fence, Image, ImageDesc, ImageRef, ImageState, Readback,
};
use relume_renderer::{CallerImage, Renderer};
use std::sync::Arc;

/// What the overlay records onto the swapchain image, inside dynamic rendering.
pub type DrawOverlay<'a> = &'a mut dyn FnMut(vk::CommandBuffer, vk::Extent2D) -> Result<()>;

pub struct Presenter {
    ctx: Arc<Context>,
    device: ash::Device,
    queue: vk::Queue,
    cmd: CommandBuffer,
    fence: Fence,
    in_flight: bool,
    /// The viewer's copy of relume's display, the source of the blit.
    target: Image,
    target_state: ImageState,
    /// Host memory a screenshot is copied into (made when one is first asked for).
    screenshot: Option<Buffer>,
}

const COLOR: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

impl Presenter {
    pub fn new(ctx: &Arc<Context>, device: &Device, extent: vk::Extent2D) -> Result<Presenter> {
        Ok(Presenter {
            ctx: Arc::clone(ctx),
            device: device.device.clone(),
            queue: device.queue,
            cmd: CommandBuffer::new(ctx)?,
            fence: Fence::new(ctx)?,
            in_flight: false,
            target: target_image(ctx, extent)?,
            target_state: undefined(),
            screenshot: None,
        })
    }

    /// Waits for the frame in flight, if any (its fence, not the device).
    pub fn wait(&mut self) -> Result<()> {
        if self.in_flight {
            // SAFETY: the fence belongs to the submission below.
            unsafe {
                self.device.wait_for_fences(&[self.fence.raw], true, u64::MAX)?;
                self.device.reset_fences(&[self.fence.raw])?;
            }
            self.in_flight = false;
        }
        Ok(())
    }

    /// A new size: the viewer's image follows the swapchain (the queue is idle).
    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.target = target_image(&self.ctx, extent)?;
        self.target_state = undefined();
        self.screenshot = None;
        Ok(())
    }

    /// Records, submits and presents one frame into swapchain image `index`. With `capture`,
    /// the finished swapchain image is also copied to host memory ([`Presenter::screenshot`]
    /// reads it once the frame's fence has signalled).
    pub fn frame(
        &mut self,
        renderer: &mut Renderer,
        swapchain: &Swapchain,
        index: u32,
        overlay: Option<DrawOverlay<'_>>,
        capture: bool,
        radiance: Option<&Readback>,
    ) -> Result<()> {
        let (image, extent) = (swapchain.images[index as usize], swapchain.extent);
        if capture && self.screenshot.is_none() {
            let bytes = extent.width as u64 * extent.height as u64 * 4;
            let location = gpu_allocator::MemoryLocation::GpuToCpu;
            self.screenshot = Some(Buffer::new(&self.ctx, "screenshot", bytes, vk::BufferUsageFlags::TRANSFER_DST, location)?);
        }
        let ctx = Arc::clone(&self.ctx);
        let rec = ctx.begin(self.cmd.raw)?;
        let caller = CallerImage { image: self.target.raw, format: self.target.desc.format, extent, state: self.target_state };
        let copied = renderer.record_to(&rec, &caller).and_then(|state| {
            radiance.map(|r| renderer.record_readback(&rec, "radiance", r)).transpose()?;
            Ok(state)
        });
        let copied = match copied {
            Ok(state) => state,
            Err(e) => {
                // SAFETY: end the begun buffer so it can be reset next frame.
                unsafe { self.device.end_command_buffer(self.cmd.raw) }?;
                return Err(e.into());
            }
        };
        let blit_read = state(vk::PipelineStageFlags2::BLIT, vk::AccessFlags2::TRANSFER_READ, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
        let blit_write = state(vk::PipelineStageFlags2::BLIT, vk::AccessFlags2::TRANSFER_WRITE, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        // The acquire semaphore is waited for at the blit stage (see the submission).
        let acquired = state(vk::PipelineStageFlags2::BLIT, vk::AccessFlags2::NONE, vk::ImageLayout::UNDEFINED);
        barrier(&rec, self.target.raw, copied, blit_read);
        barrier(&rec, image, acquired, blit_write);
        self.blit(extent, image);
        self.target_state = blit_read;
        let mut last = blit_write;
        if let Some(draw) = overlay {
            let attachment = state(
                vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags2::COLOR_ATTACHMENT_READ | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            );
            barrier(&rec, image, last, attachment);
            self.draw_overlay(swapchain.views[index as usize], extent, draw)?;
            last = attachment;
        }
        if let (true, Some(buffer)) = (capture, &self.screenshot) {
            let read = state(vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
            barrier(&rec, image, last, read);
            self.copy_out(image, extent, buffer.raw);
            rec.transfer_to_host_barrier();
            last = read;
        }
        let present = state(vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE, vk::ImageLayout::PRESENT_SRC_KHR);
        barrier(&rec, image, last, present);
        self.submit(rec, swapchain, index)
    }

    /// The last frame's screenshot, RGBA8 rows top to bottom, once its fence has signalled.
    pub fn screenshot(&self, swapchain: &Swapchain) -> Result<Vec<u8>> {
        let extent = swapchain.extent;
        let buffer = self.screenshot.as_ref().ok_or_else(|| anyhow::anyhow!("no screenshot was taken"))?;
        let bytes = buffer.mapped_bytes(extent.width as usize * extent.height as usize * 4)?;
        let bgra = swapchain.format == vk::Format::B8G8R8A8_UNORM;
        Ok(bytes.chunks_exact(4).flat_map(|p| if bgra { [p[2], p[1], p[0], p[3]] } else { [p[0], p[1], p[2], p[3]] }).collect())
    }

    fn blit(&self, extent: vk::Extent2D, image: vk::Image) {
        let layers = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
        let corner = vk::Offset3D { x: extent.width as i32, y: extent.height as i32, z: 1 };
        let region = vk::ImageBlit::default()
            .src_subresource(layers)
            .src_offsets([vk::Offset3D::default(), corner])
            .dst_subresource(layers)
            .dst_offsets([vk::Offset3D::default(), corner]);
        // SAFETY: both images are in the layouts the barriers above left them in.
        unsafe {
            self.device.cmd_blit_image(
                self.cmd.raw,
                self.target.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
                vk::Filter::NEAREST,
            )
        };
    }

    fn draw_overlay(&self, view: vk::ImageView, extent: vk::Extent2D, draw: DrawOverlay) -> Result<()> {
        let attachments = [vk::RenderingAttachmentInfo::default()
            .image_view(view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .color_attachments(&attachments);
        // SAFETY: the image is a color attachment (the barrier above); rendering ends below.
        unsafe { self.device.cmd_begin_rendering(self.cmd.raw, &info) };
        let drawn = draw(self.cmd.raw, extent);
        // SAFETY: ends the rendering begun above.
        unsafe { self.device.cmd_end_rendering(self.cmd.raw) };
        drawn
    }

    fn copy_out(&self, image: vk::Image, extent: vk::Extent2D, buffer: vk::Buffer) {
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1))
            .image_extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 });
        // SAFETY: the image is a transfer source and the buffer holds every texel.
        unsafe { self.device.cmd_copy_image_to_buffer(self.cmd.raw, image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buffer, &[region]) };
    }

    fn submit(&mut self, rec: CommandRecorder, swapchain: &Swapchain, index: u32) -> Result<()> {
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(rec.cmd)];
        let waits = [vk::SemaphoreSubmitInfo::default().semaphore(swapchain.acquired).stage_mask(vk::PipelineStageFlags2::BLIT)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(swapchain.finished[index as usize])
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds).wait_semaphore_infos(&waits).signal_semaphore_infos(&signals)];
        // SAFETY: the buffer is fully recorded; the fence is unsignalled (waited and reset).
        unsafe {
            self.device.end_command_buffer(rec.cmd)?;
            self.device.queue_submit2(self.queue, &submit, self.fence.raw)?;
        }
        self.in_flight = true;
        Ok(())
    }
}

fn target_image(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Image> {
    use vk::ImageUsageFlags as U;
    let desc = ImageDesc {
        width: extent.width,
        height: extent.height,
        layers: 1,
        format: vk::Format::R8G8B8A8_UNORM,
        // Colour attachment only so that relume's image view of it is valid.
        usage: U::TRANSFER_DST | U::TRANSFER_SRC | U::COLOR_ATTACHMENT,
        view_type: vk::ImageViewType::TYPE_2D,
    };
    Ok(Image::new(ctx, "view target", desc)?)
}

fn state(stage: vk::PipelineStageFlags2, access: vk::AccessFlags2, layout: vk::ImageLayout) -> ImageState {
    ImageState { stage, access, layout }
}

fn undefined() -> ImageState {
    state(vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE, vk::ImageLayout::UNDEFINED)
}

fn barrier(rec: &CommandRecorder, image: vk::Image, from: ImageState, to: ImageState) {
    barrier_between(rec, ImageRef { raw: image, range: COLOR }, from, to);
}
