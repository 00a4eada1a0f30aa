//! The on-screen overlay: egui (an immediate-mode UI) for text and controls, fed by winit's
//! events through egui-winit and recorded into the viewer's command buffer by
//! egui-ash-renderer with dynamic rendering, onto the swapchain image after relume's frame.
//! Its vertex buffers grow only when the UI does; its font atlas is uploaded once (that
//! upload waits for the queue: at the first frame, never in steady state).

use crate::device::Device;
use anyhow::Result;
use ash::vk;
use egui::{ClippedPrimitive, TextureId};
use egui_ash_renderer::{DynamicRendering, Options, Renderer};
use winit::event::WindowEvent;
use winit::window::Window;

pub struct Overlay {
    pub ctx: egui::Context,
    state: egui_winit::State,
    renderer: Renderer,
    device: ash::Device,
    queue: vk::Queue,
    /// For the renderer's texture uploads only.
    pool: vk::CommandPool,
    primitives: Vec<ClippedPrimitive>,
    pixels_per_point: f32,
    to_free: Vec<TextureId>,
}

impl Overlay {
    pub fn new(window: &Window, device: &Device, format: vk::Format) -> Result<Overlay> {
        let ctx = egui::Context::default();
        let state = egui_winit::State::new(ctx.clone(), egui::ViewportId::ROOT, window, Some(window.scale_factor() as f32), None, None);
        let rendering = DynamicRendering { color_attachment_format: format, depth_attachment_format: None };
        let options = Options { in_flight_frames: 1, srgb_framebuffer: false, ..Options::default() };
        let renderer = Renderer::with_default_allocator(&device.base.instance, device.physical, device.device.clone(), rendering, options)?;
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(device.family);
        // SAFETY: a valid create info on a live device; destroyed in Drop.
        let pool = unsafe { device.device.create_command_pool(&info, None) }?;
        Ok(Overlay {
            ctx,
            state,
            renderer,
            device: device.device.clone(),
            queue: device.queue,
            pool,
            primitives: Vec::new(),
            pixels_per_point: 1.0,
            to_free: Vec::new(),
        })
    }

    /// Hands egui a window event; true when egui took it (a click on the overlay).
    pub fn on_event(&mut self, window: &Window, event: &WindowEvent) -> bool {
        self.state.on_window_event(window, event).consumed
    }

    /// Lays the UI out for the next frame and uploads what it changed; the previous frame
    /// must have completed. Returns whether egui asks to be drawn again at once (an animation).
    pub fn prepare(&mut self, window: &Window, ui: impl FnMut(&egui::Context)) -> Result<bool> {
        let input = self.state.take_egui_input(window);
        let output = self.ctx.run(input, ui);
        self.state.handle_platform_output(window, output.platform_output);
        self.renderer.free_textures(&std::mem::take(&mut self.to_free))?;
        if !output.textures_delta.set.is_empty() {
            self.renderer.set_textures(self.queue, self.pool, &output.textures_delta.set)?;
        }
        self.to_free = output.textures_delta.free;
        self.pixels_per_point = output.pixels_per_point;
        self.primitives = self.ctx.tessellate(output.shapes, output.pixels_per_point);
        let again = output.viewport_output.get(&egui::ViewportId::ROOT).is_some_and(|v| v.repaint_delay.is_zero());
        Ok(again)
    }

    /// Records the prepared UI inside the caller's dynamic rendering.
    pub fn draw(&mut self, cmd: vk::CommandBuffer, extent: vk::Extent2D) -> Result<()> {
        self.renderer.cmd_draw(cmd, extent, self.pixels_per_point, &self.primitives)?;
        Ok(())
    }
}

impl Drop for Overlay {
    /// The queue is idle (the viewer waits for it at teardown).
    fn drop(&mut self) {
        // SAFETY: no submission uses the pool any more.
        unsafe { self.device.destroy_command_pool(self.pool, None) };
    }
}
