//! The on-screen overlay: egui (an immediate-mode UI) for text and controls, fed by winit's
//! events through egui-winit and recorded into the viewer's command buffer by
//! egui-ash-renderer with dynamic rendering, onto the swapchain image after relume's frame.
//! Its vertex buffers grow only when the UI does; a texture is uploaded when egui changes it
//! (the font atlas at the first frame and when new glyphs appear, the reference as it refines:
//! that upload waits for the queue, never in steady state). Each texture is uploaded whole
//! from a copy kept here: egui-ash-renderer 0.11 updates a part of a texture after moving the
//! whole of it from an undefined layout, which may lose the rest on drivers that re-tile.

use crate::device::Device;
use anyhow::Result;
use ash::vk;
use egui::epaint::{ImageData, ImageDelta};
use egui::{ClippedPrimitive, ColorImage, TextureId};
use egui_ash_renderer::{DynamicRendering, Options, Renderer};
use std::collections::HashMap;
use std::sync::Arc;
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
    /// Every live texture as uploaded last, to apply egui's partial updates to.
    textures: HashMap<TextureId, Arc<ColorImage>>,
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
            textures: HashMap::new(),
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
        let freed = std::mem::take(&mut self.to_free);
        self.renderer.free_textures(&freed)?;
        freed.iter().for_each(|id| _ = self.textures.remove(id));
        if !output.textures_delta.set.is_empty() {
            let whole: Vec<(TextureId, ImageDelta)> =
                output.textures_delta.set.iter().map(|(id, delta)| (*id, self.whole(*id, delta))).collect();
            self.renderer.set_textures(self.queue, self.pool, &whole)?;
        }
        self.to_free = output.textures_delta.free;
        self.pixels_per_point = output.pixels_per_point;
        self.primitives = self.ctx.tessellate(output.shapes, output.pixels_per_point);
        let again = output.viewport_output.get(&egui::ViewportId::ROOT).is_some_and(|v| v.repaint_delay.is_zero());
        Ok(again)
    }

    /// The whole texture `id` after `delta`.
    fn whole(&mut self, id: TextureId, delta: &ImageDelta) -> ImageDelta {
        let ImageData::Color(patch) = &delta.image;
        let image = match (delta.pos, self.textures.get(&id)) {
            (Some([x0, y0]), Some(old)) => {
                let mut image = ColorImage::clone(old);
                let width = image.size[0];
                for (row, pixels) in patch.pixels.chunks_exact(patch.size[0].max(1)).enumerate() {
                    let at = (y0 + row) * width + x0;
                    image.pixels[at..at + pixels.len()].copy_from_slice(pixels);
                }
                Arc::new(image)
            }
            _ => Arc::clone(patch),
        };
        self.textures.insert(id, Arc::clone(&image));
        ImageDelta::full(ImageData::Color(image), delta.options)
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
