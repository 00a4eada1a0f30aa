//! The frame, top to bottom: VSM moments -> moments blur -> entry irradiance -> cluster sums
//! -> light-path-map reconstruction -> its padding -> forward lighting -> tonemap.
//! Forward lighting is the obscurance illumination model (001 eq. (5)-(7)): direct light with
//! variance shadow maps, plus the ambient term (I_A + I'_S) times the obscurance W, read from
//! the lightmap through each vertex's uv1 (see shaders/forward.frag). The lightmap is
//! uploaded and padded once, at creation ([`Renderer::with_lightmap`]); without one a single
//! texel of W = 1 stands in (constant ambient). With light path maps
//! ([`Renderer::with_transfer`], 000 §3.4), the four passes after the blur compute the
//! large-scale indirect irradiance I of the frame's lights into an image laid out as the
//! lightmap, which the forward pass adds as [`Composition`] says; without them those passes
//! record nothing and a single texel of I = 0 stands in. Nothing is uploaded per frame but the
//! lights. `Renderer::record` writes a frame into any command buffer (the caller's, for
//! integrators); `Renderer::render` is the headless driver relume's own tools use.

use crate::gpu_scene::GpuScene;
use crate::light_path_maps::GpuLightPathMaps;
use crate::lightmap::{check_uv1, GpuLightmap, LightmapData};
use crate::passes::cluster_sums::ClusterSumsPass;
use crate::passes::entry_irradiance::{EntryIrradianceParams, EntryIrradiancePass};
use crate::passes::forward::{ForwardParams, ForwardPass, DEPTH_FORMAT, RADIANCE_FORMAT};
use crate::passes::lpm_reconstruct::LpmReconstructPass;
use crate::passes::tonemap::{TonemapPass, DISPLAY_FORMAT};
use crate::passes::vsm::VsmPass;
use crate::passes::vsm_blur::VsmBlurPass;
use crate::vk::{
    vk, Access, Buffer, CommandBuffer, CommandRecorder, Context, Fence, Image, ImageDesc, TimestampQueries, Tracker, VkError, VkResult,
};
use glam::{Vec3, Vec4};
use gpu_allocator::MemoryLocation;
use relume_bake::clustered_transfer::ClusteredTransfer;
use relume_bake::image::Image as HdrImage;
use relume_bake::scene::{Camera, Light, Scene};
use relume_bake::settings::first_failed_check;

/// How the forward pass adds the light path maps' large-scale indirect irradiance I (000
/// §3.4) to a surface of albedo a, with W the obscurance and E_d the shadowed direct
/// irradiance (every light's, times the receiver's cosine). §3.4 can be read three ways;
/// relume renders each, to measure them. The ambient term (I_A + I'_S) W is added apart, the
/// same in every mode; without light path maps no mode adds anything.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Composition {
    /// L += a / pi * I: the large scale alone, no small-scale term.
    Plain,
    /// L += a / pi * W * I: "the two texture values are multiplied".
    #[default]
    TimesObscurance,
    /// L += a / pi * W * (I + E_d): the literal reading, which also multiplies "the
    /// obscuration value by the direct illumination" (paths of length 2 whose last ray is
    /// small-scale).
    TimesObscuranceWithDirect,
}

impl Composition {
    pub const ALL: [Composition; 3] = [Composition::Plain, Composition::TimesObscurance, Composition::TimesObscuranceWithDirect];

    /// forward.frag's LPM_* constant (0, LPM_NONE, is for a renderer without light path maps).
    fn shader_mode(self) -> u32 {
        match self {
            Composition::Plain => 1,
            Composition::TimesObscurance => 2,
            Composition::TimesObscuranceWithDirect => 3,
        }
    }
}

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
    /// How the light path maps' indirect irradiance is added (a renderer made
    /// [`Renderer::with_transfer`]; without one nothing is added). Default
    /// [`Composition::TimesObscurance`].
    pub composition: Composition,
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
            composition: Composition::default(),
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
        first_failed_check(&checks)
    }
}

/// The passes in frame order; timestamps are written before the first and after each. A pass
/// a frame does not need (the four light-path-map passes without light path maps, the VSM
/// passes without shadows) records nothing between its timestamps and takes about 0 ms.
pub const PASS_NAMES: [&str; 8] =
    ["vsm_moments", "vsm_blur", "entry_irradiance", "cluster_sums", "lpm_reconstruct", "lpm_padding", "forward", "tonemap"];

const STAMPS: usize = PASS_NAMES.len() + 1;

/// GPU time of each pass of one frame, in milliseconds (None when the device has no timestamps).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameTimings {
    pub passes_ms: Option<[f64; PASS_NAMES.len()]>,
}

/// The light path maps and the passes that turn them into the indirect image each frame.
struct LightPathMaps<'a> {
    entry_irradiance: EntryIrradiancePass<'a>,
    cluster_sums: ClusterSumsPass<'a>,
    reconstruct: LpmReconstructPass<'a>,
    maps: GpuLightPathMaps<'a>,
}

/// What the forward pass reads as the indirect irradiance I.
enum Indirect<'a> {
    Maps(Box<LightPathMaps<'a>>),
    /// A single texel of 0, uploaded once: no light path maps.
    StandIn(Box<GpuLightmap<'a>>),
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
    indirect: Indirect<'a>,
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
        Renderer::build(ctx, scene, settings, lightmap, None)
    }

    /// [`Renderer::with_lightmap`] with the light path maps of 000 (§3.4): `transfer` (entry
    /// points, clustered textures, weights) is uploaded once, here, and every frame computes
    /// the entry points' irradiance from the frame's lights and shadow maps, the cluster sums
    /// and the indirect irradiance per texel, which the forward pass adds as
    /// `settings.composition` says. `lightmap` holds the obscurance W (rgb) and the coverage
    /// (alpha) of the atlas the transfer was baked on. Refused, by name: a transfer that fails
    /// its `validate`, an empty one, one whose texel count is not the lightmap's, and what
    /// `with_lightmap` refuses.
    pub fn with_transfer(
        ctx: &'a Context,
        scene: &Scene,
        settings: &RenderSettings,
        lightmap: &LightmapData,
        transfer: &ClusteredTransfer,
    ) -> VkResult<Renderer<'a>> {
        Renderer::build(ctx, scene, settings, Some(lightmap), Some(transfer))
    }

    fn build(
        ctx: &'a Context,
        scene: &Scene,
        settings: &RenderSettings,
        lightmap: Option<&LightmapData>,
        transfer: Option<&ClusteredTransfer>,
    ) -> VkResult<Renderer<'a>> {
        settings.validate().map_err(VkError::Invalid)?;
        if let Some(data) = lightmap {
            check_uv1(scene, data.pages)?;
        }
        let maps = match (transfer, lightmap) {
            (Some(transfer), Some(data)) => Some(GpuLightPathMaps::upload(ctx, transfer, data)?),
            _ => None,
        };
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
        let indirect = match maps {
            Some(maps) => Indirect::Maps(Box::new(LightPathMaps {
                entry_irradiance: EntryIrradiancePass::new(ctx, &gpu_scene, &vsm.moments, &maps)?,
                cluster_sums: ClusterSumsPass::new(ctx, &maps)?,
                reconstruct: LpmReconstructPass::new(ctx, &maps)?,
                maps,
            })),
            None => Indirect::StandIn(Box::new(GpuLightmap::upload(ctx, 1, 1, 1, &[Vec4::ZERO])?)),
        };
        let indirect_image = match &indirect {
            Indirect::Maps(lpm) => &lpm.maps.indirect,
            Indirect::StandIn(stand_in) => &stand_in.image,
        };
        let forward = ForwardPass::new(ctx, &gpu_scene, &vsm.moments, &lightmap.image, indirect_image)?;
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
        if let Indirect::StandIn(stand_in) = &indirect {
            stand_in.register_state(&mut tracker);
        }
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
            indirect,
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

    /// Changes how the light path maps' indirect irradiance is added (see [`Composition`]) for
    /// the frames recorded from now on, without allocating; no effect without light path maps.
    pub fn set_composition(&mut self, composition: Composition) {
        self.settings.composition = composition;
    }

    /// Moves the lights (same kinds and count as the scene had), without allocating. The
    /// next frame recorded carries the new data in its command buffer, so a frame still in
    /// flight is not disturbed.
    pub fn set_lights(&mut self, lights: &[Light]) -> VkResult<()> {
        self.scene.set_lights(lights)
    }

    /// Moves mesh `mesh` (an index into the scene's meshes) by `translation` from where the
    /// scene had it, for the frames recorded from now on, without allocating; the shadow
    /// maps refit to the moved scene at the next [`Renderer::set_lights`]. Baked data (the
    /// lightmap, light path maps) stays as baked: that is what a moving-occluder sweep
    /// measures. The vertex buffer is written at once, so no frame this renderer recorded
    /// may be in flight ([`Renderer::render`] waits for its own).
    pub fn set_mesh_translation(&mut self, mesh: usize, translation: Vec3) -> VkResult<()> {
        self.scene.translate_mesh(mesh, translation)
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
            lpm_mode: match self.indirect {
                Indirect::Maps(_) => s.composition.shader_mode(),
                Indirect::StandIn(_) => 0,
            },
            _pad: [0; 2],
            ambient_beta: s.ambient.extend(s.beta),
        }
    }

    fn entry_irradiance_params(&self, maps: &GpuLightPathMaps) -> EntryIrradianceParams {
        let s = &self.settings;
        EntryIrradianceParams {
            light_count: self.scene.light_count(),
            shadows: s.shadows as u32,
            min_variance: s.min_variance,
            bleeding_reduction: s.bleeding_reduction,
            entry_count: maps.entry_count,
            light_area: maps.light_area,
        }
    }

    fn light_path_maps(&self) -> Option<&LightPathMaps<'a>> {
        match &self.indirect {
            Indirect::Maps(lpm) => Some(lpm),
            Indirect::StandIn(_) => None,
        }
    }

    fn indirect_image(&self) -> &Image<'a> {
        match &self.indirect {
            Indirect::Maps(lpm) => &lpm.maps.indirect,
            Indirect::StandIn(stand_in) => &stand_in.image,
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
        let lpm = self.light_path_maps();
        if let Some(lpm) = lpm {
            let params = self.entry_irradiance_params(&lpm.maps);
            lpm.entry_irradiance.record(rec, tracker, &self.vsm.moments, &lpm.maps, &params);
        }
        timestamp(3);
        if let Some(lpm) = lpm {
            lpm.cluster_sums.record(rec, tracker, &lpm.maps);
        }
        timestamp(4);
        if let Some(lpm) = lpm {
            lpm.reconstruct.record(rec, tracker, &lpm.maps);
        }
        timestamp(5);
        if let Some(lpm) = lpm {
            lpm.maps.record_padding(rec, tracker);
        }
        timestamp(6);
        let targets = (&self.radiance, &self.depth);
        let sampled = (&self.vsm.moments, &self.lightmap.image, self.indirect_image());
        self.forward.record(rec, tracker, &self.scene, sampled, targets, &self.forward_params());
        timestamp(7);
        self.tonemap.record(rec, tracker, &self.radiance, &self.display, self.settings.exposure);
        timestamp(8);
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
    /// image and buffer it uses; the next frame transitions them from UNDEFINED. The lightmap
    /// (and the stand-in for the indirect image), which no frame writes, stay known as ready
    /// for sampling (the upload left them so).
    pub fn forget_image_states(&mut self) {
        self.tracker = Tracker::default();
        self.lightmap.register_state(&mut self.tracker);
        if let Indirect::StandIn(stand_in) = &self.indirect {
            stand_in.register_state(&mut self.tracker);
        }
    }

    /// I_e of every entry point (rgb, lux) as the last frame rendered computed it, through a
    /// one-time submission on the renderer's command buffer that is waited for (for tests and
    /// tools: no frame of this renderer may be pending). Refused without light path maps.
    pub fn read_entry_irradiance(&mut self) -> VkResult<Vec<Vec3>> {
        let count = self.maps()?.entry_count as usize;
        let buffer = Buffer::new(
            self.ctx,
            "entry irradiance readback",
            count as u64 * 16,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        self.submit_read(|rec, tracker, maps| {
            tracker.use_buffer(rec, &maps.entry_irradiance, Access::TransferSource);
            rec.copy_buffer(maps.entry_irradiance.raw, 0, buffer.raw, count as u64 * 16);
        })?;
        let floats: &[f32] = bytemuck::try_cast_slice(buffer.mapped_bytes(count * 16)?)
            .map_err(|e| VkError::Invalid(format!("entry irradiance readback is not f32 data: {e}")))?;
        Ok(floats.chunks_exact(4).map(|v| Vec3::new(v[0], v[1], v[2])).collect())
    }

    /// Every texel of the indirect image (rgb I in lux, alpha the coverage: > 0 covered, < 0
    /// padded, from the nearest covered texel) as the last frame rendered left it, in
    /// lightmap order, through a one-time submission as [`Renderer::read_entry_irradiance`].
    pub fn read_indirect(&mut self) -> VkResult<Vec<Vec4>> {
        let count = self.maps()?.texel_count();
        let buffer =
            Buffer::new(self.ctx, "indirect readback", count as u64 * 16, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?;
        self.submit_read(|rec, tracker, maps| {
            tracker.use_image(rec, &maps.indirect, Access::TransferSource);
            rec.copy_image_to_buffer(&maps.indirect, buffer.raw);
        })?;
        let floats: &[f32] = bytemuck::try_cast_slice(buffer.mapped_bytes(count * 16)?)
            .map_err(|e| VkError::Invalid(format!("indirect readback is not f32 data: {e}")))?;
        Ok(floats.chunks_exact(4).map(Vec4::from_slice).collect())
    }

    fn maps(&self) -> VkResult<&GpuLightPathMaps<'a>> {
        self.light_path_maps()
            .map(|lpm| &lpm.maps)
            .ok_or_else(|| VkError::Invalid("this renderer has no light path maps; create it with Renderer::with_transfer".into()))
    }

    /// Records `copy` (transfers out of the light path maps, declared to the renderer's
    /// tracker) on the renderer's command buffer, then makes them visible to the host, submits
    /// and waits.
    fn submit_read(&mut self, copy: impl FnOnce(&CommandRecorder, &mut Tracker, &GpuLightPathMaps)) -> VkResult<()> {
        let mut tracker = std::mem::take(&mut self.tracker);
        let rec = self.ctx.begin(self.cmd.raw);
        let submitted = rec.and_then(|rec| {
            copy(&rec, &mut tracker, self.maps()?);
            rec.transfer_to_host_barrier();
            self.ctx.submit_and_wait(rec, &self.fence)
        });
        self.tracker = tracker;
        if submitted.is_err() {
            self.forget_image_states();
        }
        submitted
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
