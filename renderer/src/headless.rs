//! The headless driver relume's own tools and tests use, apart from the library type: one
//! command buffer and one fence, reused; each frame is recorded, submitted and waited for by
//! that fence (never the device), with no allocation; read-backs of the frame's images and of
//! techniques' resources. An integrator records [`Renderer::record`] into its own command
//! buffer instead and needs none of this.

use crate::frame::{FrameTimings, Renderer};
use crate::vk::{CommandBuffer, Fence, Readback, VkResult};
use glam::Vec3;
use relume_bake::image::Image as HdrImage;
use std::ops::{Deref, DerefMut};

pub struct Headless {
    renderer: Renderer,
    cmd: CommandBuffer,
    fence: Fence,
    radiance: Readback,
    display: Readback,
}

impl Headless {
    pub fn new(renderer: Renderer) -> VkResult<Headless> {
        let ctx = renderer.context();
        let radiance = Readback::for_image(ctx, "radiance readback", renderer.radiance())?;
        let display = Readback::for_image(ctx, "display readback", renderer.display())?;
        Ok(Headless { cmd: CommandBuffer::new(ctx)?, fence: Fence::new(ctx)?, radiance, display, renderer })
    }

    /// Renders one frame and waits for its fence; returns its GPU time per pass.
    pub fn render(&mut self) -> VkResult<FrameTimings> {
        self.submit(false)?;
        self.renderer.timings()
    }

    /// Renders one frame and reads back its linear radiance and its display image (RGBA8).
    pub fn render_and_read(&mut self) -> VkResult<(HdrImage, Vec<u8>)> {
        self.submit(true)?;
        let (width, height) = (self.renderer.settings().width, self.renderer.settings().height);
        let mut radiance = HdrImage::new(width, height);
        for (pixel, rgba) in radiance.pixels.iter_mut().zip(self.radiance.floats()?.chunks_exact(4)) {
            *pixel = Vec3::new(rgba[0], rgba[1], rgba[2]);
        }
        Ok((radiance, self.display.bytes()?.to_vec()))
    }

    /// A resource of f32 data (see [`Renderer::resource`]) as the last frame left it, through
    /// a one-time submission on the driver's command buffer that is waited for.
    pub fn read_floats_blocking(&mut self, name: &str) -> VkResult<Vec<f32>> {
        let ctx = std::sync::Arc::clone(self.renderer.context());
        let readback = match self.renderer.resource(name)? {
            crate::technique::Resource::Image(image) => Readback::for_image(&ctx, name, image)?,
            crate::technique::Resource::Buffer(buffer) => Readback::new(&ctx, name, buffer.size)?,
        };
        let rec = ctx.begin(self.cmd.raw)?;
        self.renderer.record_readback(&rec, name, &readback)?;
        let submitted = ctx.submit_and_wait(rec, &self.fence);
        if submitted.is_err() {
            self.renderer.forget_states();
        }
        submitted?;
        Ok(readback.floats()?.to_vec())
    }

    pub fn into_renderer(self) -> Renderer {
        self.renderer
    }

    fn submit(&mut self, read_back: bool) -> VkResult<()> {
        let ctx = std::sync::Arc::clone(self.renderer.context());
        let rec = ctx.begin(self.cmd.raw)?;
        self.renderer.record(&rec);
        if read_back {
            self.renderer.record_readback(&rec, "radiance", &self.radiance)?;
            self.renderer.record_readback(&rec, "display", &self.display)?;
        }
        let submitted = ctx.submit_and_wait(rec, &self.fence);
        if submitted.is_err() {
            self.renderer.forget_states();
        }
        submitted
    }
}

impl Deref for Headless {
    type Target = Renderer;

    fn deref(&self) -> &Renderer {
        &self.renderer
    }
}

impl DerefMut for Headless {
    fn deref_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }
}
