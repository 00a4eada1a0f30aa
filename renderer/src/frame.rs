//! The frame, top to bottom: VSM moments -> moments blur -> forward lighting -> tonemap.
//! Forward lighting is the obscurance illumination model (001 eq. (5)-(7)): direct light with
//! variance shadow maps, plus the ambient term (I_A + I'_S) times the obscurance W, read from
//! the lightmap through each vertex's uv1 (see shaders/forward.frag). The lightmap is
//! uploaded and padded once, at creation ([`Renderer::with_lightmap`]); without one a single
//! texel of W = 1 stands in (constant ambient). Nothing is uploaded per frame but the lights.
//! `Renderer::record` writes a frame into any command buffer (the caller's, for integrators);
//! `Renderer::render` is the headless driver relume's own tools use.

use crate::gpu_scene::GpuScene;
use crate::lightmap::{check_uv1, GpuLightmap, LightmapData};
use crate::passes::forward::{ForwardParams, ForwardPass, DEPTH_FORMAT, RADIANCE_FORMAT};
use crate::passes::tonemap::{TonemapPass, DISPLAY_FORMAT};
use crate::passes::vsm::VsmPass;
use crate::passes::vsm_blur::VsmBlurPass;
use crate::vk::{vk, Access, Buffer, CommandBuffer, CommandRecorder, Context, Fence, Image, ImageDesc, TimestampQueries, Tracker, VkError, VkResult};
use glam::{Vec3, Vec4};
use gpu_allocator::MemoryLocation;
use relume_bake::image::Image as HdrImage;
use relume_bake::scene::{Camera, Light, Scene};

/// Everything that shapes a frame; validated by [`RenderSettings::validate`].
#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Shadow-map size in texels (square), per layer.
    pub shadow_map_size: u32,
    /// Gaussian blur radius of the moments in texels (0: no blur).
    pub blur_radius: u32,
    /// Floor on the variance in the Chebyshev bound, in square metres.
    pub min_variance: f32,
    /// Light-bleeding reduction: the part of the bound's tail cut off, in [0, 1).
    pub bleeding_reduction: f32,
    /// Off: every light is fully visible (shading only; for comparing shading alone).
    pub shadows: bool,
    /// Exposure multiplier of the display transform.
    pub exposure: f32,
    /// I_A of 001 eq. (5): the ambient irradiance (lux, rgb, each at least 0) an unoccluded
    /// surface receives. The forward pass outputs the radiance
    /// `L = emission + albedo / pi * ((I_A + I'_S) * W + E_direct)`: k_A = k_D = albedo,
    /// I_A and I'_S irradiances, W the obscurance from the lightmap (1 without one), E_direct
    /// the shadowed direct irradiance (eq. (6) with the receiver's cosine). Default 0.
    pub ambient: Vec3,
    /// beta of 001 eq. (7), in [0, 1): I'_S = beta * the sum over all lights of each light's
    /// unshadowed irradiance on a surface facing it (range window and spot cone included, no
    /// cosine, no visibility; a directional light's lux). Default 0. With ambient and beta
    /// both 0 the frame is direct light and emission alone, and the lightmap is not read.
    pub beta: f32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 512,
            height: 512,
            shadow_map_size: 1024,
            blur_radius: 2,
            min_variance: 1e-5,
            bleeding_reduction: 0.2,
            shadows: true,
            exposure: 1.0,
            ambient: Vec3::ZERO,
            beta: 0.0,
        }
    }
}

impl RenderSettings {
    /// Refuses settings no frame can be made with, saying which and what is allowed.
    pub fn validate(&self) -> Result<(), String> {
        let checks = [
            (self.width >= 1 && self.width <= 16384, "width must be 1..=16384 pixels"),
            (self.height >= 1 && self.height <= 16384, "height must be 1..=16384 pixels"),
            (self.shadow_map_size >= 16 && self.shadow_map_size <= 8192, "shadow map size must be 16..=8192 texels"),
            (self.blur_radius <= 64, "blur radius must be 0..=64 texels"),
            (self.min_variance.is_finite() && self.min_variance >= 0.0, "minimum variance must be finite and >= 0"),
            ((0.0..1.0).contains(&self.bleeding_reduction), "light-bleeding reduction must be in [0, 1)"),
            (self.exposure.is_finite() && self.exposure > 0.0, "exposure must be finite and > 0"),
            (self.ambient.is_finite() && self.ambient.min_element() >= 0.0, "ambient must be three finite values >= 0 (lux)"),
            (self.beta.is_finite() && (0.0..1.0).contains(&self.beta), "beta must be in [0, 1)"),
        ];
        match checks.iter().find(|(ok, _)| !ok) {
            Some((_, message)) => Err(message.to_string()),
            None => Ok(()),
        }
    }
}

/// The passes in frame order; timestamps are written before the first and after each.
pub const PASS_NAMES: [&str; 4] = ["vsm_moments", "vsm_blur", "forward", "tonemap"];

const STAMPS: usize = PASS_NAMES.len() + 1;

/// GPU time of each pass of one frame, in milliseconds (None when the device has no timestamps).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameTimings {
    pub passes_ms: Option<[f64; PASS_NAMES.len()]>,
}

/// The renderer borrows its context: the borrow checker keeps the context alive until every
/// resource made from it is dropped. Dropping a renderer releases everything it made; the
/// caller must first wait for any frame it recorded and submitted itself.
pub struct Renderer<'a> {
    ctx: &'a Context,
    settings: RenderSettings,
    camera: Camera,
    fence: Fence<'a>,
    cmd: CommandBuffer<'a>,
    queries: Option<TimestampQueries<'a>>,
    readback: (Buffer<'a>, Buffer<'a>),
    tonemap: TonemapPass<'a>,
    forward: ForwardPass<'a>,
    blur: VsmBlurPass<'a>,
    vsm: VsmPass<'a>,
    /// Linear radiance, the frame's HDR result.
    pub radiance: Image<'a>,
    depth: Image<'a>,
    /// Tonemapped sRGB, the frame's display result.
    pub display: Image<'a>,
    scene: GpuScene<'a>,
    /// The lightmap given at creation, or a single texel of W = 1.
    lightmap: GpuLightmap<'a>,
    /// Whether `lightmap` was given (and so was padded at creation).
    lightmap_given: bool,
    tracker: Tracker,
}

impl<'a> Renderer<'a> {
    /// Uploads the scene and creates every pass and target, without a lightmap: W = 1
    /// everywhere, so the ambient term (when `settings.ambient` or `beta` is > 0) is constant
    /// ambient. Nothing here runs per frame.
    pub fn new(ctx: &'a Context, scene: &Scene, settings: &RenderSettings) -> VkResult<Renderer<'a>> {
        Renderer::with_lightmap(ctx, scene, settings, None)
    }

    /// [`Renderer::new`] with the obscurance W read from `lightmap` through each vertex's uv1:
    /// uploaded and padded on the GPU once, here ([`Renderer::padding_ms`] says how long the
    /// padding took). With a lightmap every mesh of `scene` must have uv1 on one of its pages
    /// (a bake artifact's scene after `Baked::apply_to`); a mesh without is refused by name,
    /// as is a lightmap whose texel count is not width x height x pages.
    pub fn with_lightmap(
        ctx: &'a Context,
        scene: &Scene,
        settings: &RenderSettings,
        lightmap: Option<&LightmapData>,
    ) -> VkResult<Renderer<'a>> {
        settings.validate().map_err(VkError::Invalid)?;
        if let Some(data) = lightmap {
            check_uv1(scene, data.pages)?;
        }
        let lightmap_given = lightmap.is_some();
        let lightmap = match lightmap {
            Some(data) => GpuLightmap::upload(ctx, data.width, data.height, data.pages, data.texels)?,
            None => GpuLightmap::upload(ctx, 1, 1, 1, &[Vec4::ONE])?,
        };
        let (w, h) = (settings.width, settings.height);
        let target = |name, format, usage| {
            Image::new(ctx, name, ImageDesc { width: w, height: h, layers: 1, format, usage, view_type: vk::ImageViewType::TYPE_2D })
        };
        use vk::ImageUsageFlags as U;
        let gpu_scene = GpuScene::upload(ctx, scene)?;
        let vsm = VsmPass::new(ctx, &gpu_scene, settings.shadow_map_size)?;
        let blur = VsmBlurPass::new(ctx, &vsm.moments, settings.blur_radius)?;
        let forward = ForwardPass::new(ctx, &gpu_scene, &vsm.moments, &lightmap.image)?;
        let radiance = target("radiance", RADIANCE_FORMAT, U::COLOR_ATTACHMENT | U::STORAGE | U::TRANSFER_SRC)?;
        let depth = target("depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT)?;
        let display = target("display", DISPLAY_FORMAT, U::STORAGE | U::TRANSFER_SRC)?;
        let tonemap = TonemapPass::new(ctx, &radiance, &display)?;
        let pixels = w as u64 * h as u64;
        let readback = (
            Buffer::new(ctx, "radiance readback", pixels * 16, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?,
            Buffer::new(ctx, "display readback", pixels * 4, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?,
        );
        let mut tracker = Tracker::default();
        lightmap.register_state(&mut tracker);
        Ok(Renderer {
            ctx,
            settings: settings.clone(),
            camera: scene.camera,
            fence: Fence::new(ctx)?,
            cmd: CommandBuffer::new(ctx)?,
            queries: TimestampQueries::new(ctx)?,
            readback,
            tonemap,
            forward,
            blur,
            vsm,
            radiance,
            depth,
            display,
            scene: gpu_scene,
            lightmap,
            lightmap_given,
            tracker,
        })
    }

    /// GPU time of padding the lightmap at creation, in milliseconds; None without a lightmap
    /// or without timestamps.
    pub fn padding_ms(&self) -> Option<f64> {
        self.lightmap.padding_ms().filter(|_| self.lightmap_given)
    }

    /// Changes I_A (lux) and beta of the obscurance model (see [`RenderSettings::ambient`]) for
    /// the frames recorded from now on, without allocating; refused like invalid settings.
    pub fn set_ambient(&mut self, ambient: Vec3, beta: f32) -> VkResult<()> {
        let next = RenderSettings { ambient, beta, ..self.settings.clone() };
        next.validate().map_err(VkError::Invalid)?;
        self.settings = next;
        Ok(())
    }

    /// Moves the lights (same kinds and count as the scene had), without allocating. The
    /// next frame recorded carries the new data in its command buffer, so a frame still in
    /// flight is not disturbed.
    pub fn set_lights(&mut self, lights: &[Light]) -> VkResult<()> {
        self.scene.set_lights(lights)
    }

    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = camera;
    }

    fn forward_params(&self) -> ForwardParams {
        let s = &self.settings;
        ForwardParams {
            clip_from_world: self.camera.clip_from_world(s.width, s.height),
            camera_position: self.camera.position().extend(1.0),
            light_count: self.scene.light_count(),
            shadows: s.shadows as u32,
            min_variance: s.min_variance,
            bleeding_reduction: s.bleeding_reduction,
            material: 0,
            _pad: [0; 3],
            ambient_beta: s.ambient.extend(s.beta),
        }
    }

    /// Records one whole frame into `rec` (begun by the caller, ended and submitted by the
    /// caller, who must not submit two frames of one renderer at once). The renderer keeps
    /// the state of every image it owns across frames, whoever recorded them;
    /// [`Renderer::image_states`] tells what a frame left them in (`radiance` as compute
    /// storage read, `display` as compute storage write).
    pub fn record(&mut self, rec: &CommandRecorder) {
        let mut tracker = std::mem::take(&mut self.tracker);
        self.record_passes(rec, &mut tracker);
        self.tracker = tracker;
    }

    /// The last use of every image the renderer owns, as recorded so far.
    pub fn image_states(&self) -> &Tracker {
        &self.tracker
    }

    fn record_passes(&self, rec: &CommandRecorder, tracker: &mut Tracker) {
        let timestamp = |i: u32| {
            if let Some(q) = &self.queries {
                q.write(rec, i)
            }
        };
        if let Some(q) = &self.queries {
            q.reset(rec);
        }
        self.scene.record_light_update(rec);
        let shadows = self.settings.shadows && !self.scene.shadow_views.is_empty();
        timestamp(0);
        if shadows {
            self.vsm.record(rec, tracker, &self.scene);
        }
        timestamp(1);
        if shadows {
            self.blur.record(rec, tracker, &self.vsm.moments);
        }
        timestamp(2);
        let targets = (&self.radiance, &self.depth);
        let sampled = (&self.vsm.moments, &self.lightmap.image);
        self.forward.record(rec, tracker, &self.scene, sampled, targets, &self.forward_params());
        timestamp(3);
        self.tonemap.record(rec, tracker, &self.radiance, &self.display, self.settings.exposure);
        timestamp(4);
    }

    /// Renders one frame on the context's queue and waits for its fence (never the device).
    pub fn render(&mut self) -> VkResult<FrameTimings> {
        self.submit_frame(false)?;
        self.timings()
    }

    /// Renders one frame and reads back its linear radiance and its display image (RGBA8).
    pub fn render_and_read(&mut self) -> VkResult<(HdrImage, Vec<u8>)> {
        self.submit_frame(true)?;
        self.read_back()
    }

    /// Records copies of this frame's `radiance` and `display` into the renderer's readback
    /// buffers, after [`Renderer::record`] in the same command buffer; once the caller has
    /// waited for it, [`Renderer::read_back`] returns the pixels.
    pub fn record_readback(&mut self, rec: &CommandRecorder) {
        self.tracker.use_image(rec, &self.radiance, Access::TransferSource);
        self.tracker.use_image(rec, &self.display, Access::TransferSource);
        rec.copy_image_to_buffer(&self.radiance, self.readback.0.raw);
        rec.copy_image_to_buffer(&self.display, self.readback.1.raw);
        rec.transfer_to_host_barrier();
    }

    /// The linear radiance and display pixels of the last frame recorded with
    /// [`Renderer::record_readback`] (the caller has waited for its submission).
    pub fn read_back(&self) -> VkResult<(HdrImage, Vec<u8>)> {
        let pixels = self.settings.width as usize * self.settings.height as usize;
        let floats: &[f32] = bytemuck::try_cast_slice(self.readback.0.mapped_bytes(pixels * 16)?)
            .map_err(|e| VkError::Invalid(format!("readback is not f32 data: {e}")))?;
        let mut radiance = HdrImage::new(self.settings.width, self.settings.height);
        for (pixel, rgba) in radiance.pixels.iter_mut().zip(floats.chunks_exact(4)) {
            *pixel = glam::Vec3::new(rgba[0], rgba[1], rgba[2]);
        }
        Ok((radiance, self.readback.1.mapped_bytes(pixels * 4)?.to_vec()))
    }

    /// Forgets what the renderer's images were last used for, after a recorded frame was
    /// never submitted or its submission failed. Safe because every frame rewrites every
    /// image it uses; the next frame transitions them from UNDEFINED. The lightmap, which no
    /// frame writes, stays known as ready for sampling (the upload left it so).
    pub fn forget_image_states(&mut self) {
        self.tracker = Tracker::default();
        self.lightmap.register_state(&mut self.tracker);
    }

    fn submit_frame(&mut self, read_back: bool) -> VkResult<()> {
        let rec = self.ctx.begin(self.cmd.raw)?;
        self.record(&rec);
        if read_back {
            self.record_readback(&rec);
        }
        let submitted = self.ctx.submit_and_wait(rec, &self.fence);
        if submitted.is_err() {
            self.forget_image_states();
        }
        submitted
    }

    fn timings(&self) -> VkResult<FrameTimings> {
        let Some(queries) = &self.queries else { return Ok(FrameTimings::default()) };
        let stamps: [f64; STAMPS] = queries.read_ms()?;
        Ok(FrameTimings { passes_ms: Some(std::array::from_fn(|i| stamps[i + 1] - stamps[i])) })
    }
}
