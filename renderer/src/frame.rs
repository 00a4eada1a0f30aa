//! The frame, top to bottom: the effect's passes (the frame's uniforms and lights, the variance
//! shadow maps, each technique's passes in the order the techniques were given: `crate::effect`),
//! the lighting pass (direct light plus the techniques' terms), the tonemap, and, when the caller
//! hands relume its own image, the copy of the display image into it. [`Renderer::record`]
//! writes a frame into any command buffer (the caller's: an integrator's); nothing in a frame
//! allocates, submits or waits. The headless driver relume's own tools use (command buffer,
//! fence, read-back) is `crate::headless`, apart from this library type.

use crate::effect::{Effect, EngineInputs};
use crate::passes::lighting::{LightingPass, DEPTH_FORMAT, RADIANCE_FORMAT};
use crate::passes::tonemap::{TonemapPass, DISPLAY_FORMAT};
use crate::technique::{MakeTechnique, Resource, Technique};
use crate::vk::{transition, vk, Access, CommandRecorder, Context, Image, ImageDesc, ImageRef, ImageState, Readback, TimestampQueries};
use crate::vk::{Tracker, Use};
use crate::vk::{VkError, VkResult};
use glam::Vec3;
use relume_bake::scene::{Camera, Light, Scene};
use relume_bake::settings::first_failed_check;
use std::sync::Arc;

/// Everything that shapes a frame; validated by [`RenderSettings::validate`].
#[derive(Clone, Debug, PartialEq)]
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
    /// surface receives; scaled by the frame's occlusion term where a technique hands one
    /// over (shaders/lighting_fragment.glsl). Default 0.
    pub ambient: Vec3,
    /// beta of 001 eq. (7), in [0, 1): I'_S = beta * the sum over all lights of each light's
    /// unshadowed irradiance on a surface facing it (range window and spot cone included, no
    /// cosine, no visibility; a directional light's lux), added to I_A. Default 0. With
    /// ambient and beta both 0 the ambient term is skipped.
    pub beta: f32,
    /// I_A gains the scene's environment's unoccluded irradiance at each surface's normal
    /// (`extras.relume.environment`: nine spherical harmonics of its working cube,
    /// `Environment::radiance_sh`), scaled by the occlusion term as I_A is: the ambient light of
    /// the ambient methods on a scene lit by an environment. Nothing on a scene without one.
    /// Default off.
    pub environment_ambient: bool,
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
            environment_ambient: false,
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

/// The most passes a frame can time (one timestamp before the first and one after each).
pub const MAX_PASSES: usize = TimestampQueries::CAPACITY - 1;

/// The frame's own passes at most: vsm_moments, vsm_blur, lighting, tonemap, output_copy.
const FRAME_PASSES: usize = 5;

/// The passes a frame recorded, in order, with their GPU times in milliseconds once read
/// ([`Renderer::timings`]). A fixed-size list: reading it allocates nothing.
#[derive(Clone, Copy, Debug)]
pub struct FrameTimings {
    passes: [(&'static str, f64); MAX_PASSES],
    len: usize,
}

impl Default for FrameTimings {
    fn default() -> Self {
        FrameTimings { passes: [("", 0.0); MAX_PASSES], len: 0 }
    }
}

impl FrameTimings {
    /// Every pass that ran, in frame order, with its time (empty when the device writes no
    /// timestamps).
    pub fn passes(&self) -> &[(&'static str, f64)] {
        &self.passes[..self.len]
    }

    /// The frame's GPU time: the sum of its passes.
    pub fn total_ms(&self) -> f64 {
        self.passes().iter().map(|(_, ms)| ms).sum()
    }
}

/// An image the caller owns and hands relume for one frame ([`Renderer::record_to`]): the
/// frame's display pixels (sRGB-encoded RGBA8, as `display`) are copied into it. It must have
/// the frame's size, TRANSFER_DST usage and the format R8G8B8A8_UNORM or R8G8B8A8_SRGB, and
/// `state` must be what it is in when the frame's commands run.
#[derive(Clone, Copy, Debug)]
pub struct CallerImage {
    pub image: vk::Image,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub state: ImageState,
}

/// The renderer: an effect (the scene uploaded, the shadow maps, the techniques) and the
/// frame around it: the lighting pass that reads the effect's terms, the tonemap and the
/// frame's images. It holds its context (`Arc`), so a caller can own both side by side.
/// Dropping it releases everything it made; the caller must first wait for any frame it
/// submitted.
pub struct Renderer {
    effect: Effect,
    lighting: LightingPass,
    tonemap: TonemapPass,
    radiance: Image,
    /// Held while the lighting pass draws into it.
    _depth: Image,
    display: Image,
    queries: Option<TimestampQueries>,
    /// The passes the last frame recorded (its timestamps' names).
    recorded: FrameTimings,
}

impl Renderer {
    /// Makes the effect of the techniques (`Effect::new_blocking`: the scene uploaded, every
    /// technique made in the given order, which is the order of their passes in a frame), then
    /// the lighting pass for the terms they hand over, the tonemap and the frame's images.
    /// Blocking: uploads go through one-time submissions on the context's queue, each waited
    /// for by its own fence (never the device); nothing here runs per frame. Refused, by name:
    /// what the effect refuses, and more technique passes than a frame times.
    pub fn new_blocking(
        ctx: &Arc<Context>,
        scene: &Scene,
        settings: &RenderSettings,
        techniques: &[&dyn MakeTechnique],
    ) -> VkResult<Renderer> {
        let effect = Effect::new_blocking(ctx, scene, settings, techniques, &EngineInputs::default())?;
        let technique_passes = effect.technique_passes();
        if technique_passes > MAX_PASSES - FRAME_PASSES {
            return Err(VkError::Invalid(format!(
                "the techniques record {technique_passes} passes a frame; at most {} fit beside the frame's own",
                MAX_PASSES - FRAME_PASSES
            )));
        }
        let (w, h) = (settings.width, settings.height);
        let target = |name, format, usage| {
            Image::new(ctx, name, ImageDesc { width: w, height: h, layers: 1, format, usage, view_type: vk::ImageViewType::TYPE_2D })
        };
        use vk::ImageUsageFlags as U;
        let radiance = target("radiance", RADIANCE_FORMAT, U::COLOR_ATTACHMENT | U::STORAGE | U::TRANSFER_SRC)?;
        let depth = target("depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT)?;
        let moments = effect.moments().ok_or_else(|| VkError::Invalid("relume's frame renders its own shadow maps".into()))?;
        let lighting = LightingPass::new(ctx, &effect.scene, moments, &effect.terms()?, (&radiance, &depth))?;
        let display = target("display", DISPLAY_FORMAT, U::STORAGE | U::TRANSFER_SRC)?;
        let tonemap = TonemapPass::new(ctx, &radiance, &display)?;
        Ok(Renderer {
            queries: TimestampQueries::new(ctx)?,
            effect,
            lighting,
            tonemap,
            radiance,
            _depth: depth,
            display,
            recorded: FrameTimings::default(),
        })
    }

    pub fn context(&self) -> &Arc<Context> {
        self.effect.context()
    }

    pub fn settings(&self) -> &RenderSettings {
        self.effect.settings()
    }

    /// The technique of type `T`, if the renderer has one (to change its own settings).
    pub fn technique_mut<T: Technique>(&mut self) -> Option<&mut T> {
        self.effect.technique_mut()
    }

    /// GPU work the techniques timed at creation (`<technique>.<work>`, milliseconds).
    pub fn creation_timings(&self) -> Vec<(&'static str, f64)> {
        self.effect.creation_timings()
    }

    /// [`Effect::set_ambient`].
    pub fn set_ambient(&mut self, ambient: Vec3, beta: f32) -> VkResult<()> {
        self.effect.set_ambient(ambient, beta)
    }

    /// [`Effect::set_lights`].
    pub fn set_lights(&mut self, lights: &[Light]) -> VkResult<()> {
        self.effect.set_lights(lights)
    }

    /// [`Effect::move_lights`].
    pub fn move_lights(&mut self, lights: &[Light], seconds: f32) -> VkResult<()> {
        self.effect.move_lights(lights, seconds)
    }

    /// [`Effect::set_mesh_translation`].
    pub fn set_mesh_translation(&mut self, mesh: usize, translation: Vec3) -> VkResult<()> {
        self.effect.set_mesh_translation(mesh, translation)
    }

    /// [`Effect::set_mesh_vertices`].
    pub fn set_mesh_vertices(&mut self, mesh: usize, positions: &[Vec3], normals: &[Vec3]) -> VkResult<()> {
        self.effect.set_mesh_vertices(mesh, positions, normals)
    }

    pub fn set_camera(&mut self, camera: Camera) {
        self.effect.set_camera(camera);
    }

    /// Records one whole frame into `rec` (begun, ended and submitted by the caller, who
    /// must not submit two frames of one renderer at once). It renders into relume's own
    /// images; the renderer keeps their states across frames, whoever recorded them:
    /// afterwards `radiance` is left as compute storage read ([`Renderer::radiance_state`])
    /// and `display` as compute storage write ([`Renderer::display_state`]).
    pub fn record(&mut self, rec: &CommandRecorder) {
        let mut tracker = self.effect.take_tracker();
        self.recorded = self.record_frame(rec, &mut tracker);
        self.effect.put_tracker(tracker);
    }

    /// [`Renderer::record`], then the copy of the display image into the caller's `target`
    /// (from the state it says it is in). Returns the state the copy leaves `target` in, for
    /// the caller's next barrier. Refused before anything is recorded: a target of another
    /// size or format.
    pub fn record_to(&mut self, rec: &CommandRecorder, target: &CallerImage) -> VkResult<ImageState> {
        let formats = [vk::Format::R8G8B8A8_UNORM, vk::Format::R8G8B8A8_SRGB];
        if target.extent != self.display.desc.extent() || !formats.contains(&target.format) {
            return Err(VkError::Invalid(format!(
                "the caller's image is {}x{} {:?}; relume copies its {}x{} display (sRGB-encoded RGBA8) into an image of that size in R8G8B8A8_UNORM or R8G8B8A8_SRGB",
                target.extent.width, target.extent.height, target.format, self.settings().width, self.settings().height
            )));
        }
        let mut tracker = self.effect.take_tracker();
        let mut timer = PassTimer::resume(self.queries.as_ref(), self.record_frame(rec, &mut tracker));
        let target_ref = ImageRef { raw: target.image, range: self.display.desc.all_layers() };
        let mut state = target.state;
        // The caller's image is no tracker's: its barrier comes from the state the caller gave.
        tracker.pass(rec, [Use::image(&self.display, Access::TransferSource)], |rec| {
            state = transition(rec, target_ref, target.state, Access::TransferDestination);
            rec.copy_image(&self.display, target.image);
        });
        timer.stamp(rec, "output_copy");
        self.recorded = timer.recorded;
        self.effect.put_tracker(tracker);
        Ok(state)
    }

    /// How the last frame recorded left `radiance` (linear radiance, RGBA32F).
    pub fn radiance_state(&self) -> ImageState {
        self.effect.tracker().state(&self.radiance).state()
    }

    /// How the last frame recorded left `display` (tonemapped, sRGB-encoded RGBA8).
    pub fn display_state(&self) -> ImageState {
        self.effect.tracker().state(&self.display).state()
    }

    pub fn radiance(&self) -> &Image {
        &self.radiance
    }

    pub fn display(&self) -> &Image {
        &self.display
    }

    /// A resource by name: `radiance`, `display`, or a technique's `<technique>.<resource>`.
    pub fn resource(&self, name: &str) -> VkResult<Resource<'_>> {
        match name {
            "radiance" => return Ok(Resource::Image(&self.radiance)),
            "display" => return Ok(Resource::Image(&self.display)),
            _ => {}
        }
        self.effect.resource(name).ok_or_else(|| {
            VkError::Invalid(format!(
                "this renderer has no resource \"{name}\"; it has radiance, display{}",
                self.effect.resource_names().iter().map(|k| format!(", {k}")).collect::<String>()
            ))
        })
    }

    /// Records the copy of resource `name` into `readback` (sized for it) after its last use
    /// in the frames recorded so far; the bytes are there once that submission completed.
    pub fn record_readback(&mut self, rec: &CommandRecorder, name: &str, readback: &Readback) -> VkResult<()> {
        let mut tracker = self.effect.take_tracker();
        let recorded = self.resource(name).map(|resource| match resource {
            Resource::Image(image) => readback.record_image(rec, &mut tracker, image),
            Resource::Buffer(buffer) => readback.record_buffer(rec, &mut tracker, buffer),
        });
        self.effect.put_tracker(tracker);
        recorded
    }

    /// The GPU time of each pass of the last frame recorded, once its submission has
    /// completed (the caller knows: it waited for its own fence); never waits. Empty when the
    /// device writes no timestamps.
    pub fn timings(&self) -> VkResult<FrameTimings> {
        let Some(queries) = &self.queries else { return Ok(FrameTimings::default()) };
        let mut stamps = [0.0; TimestampQueries::CAPACITY];
        let recorded = self.recorded;
        queries.read_ms(&mut stamps[..recorded.len + 1])?;
        let mut timings = recorded;
        for (i, pass) in timings.passes[..recorded.len].iter_mut().enumerate() {
            pass.1 = stamps[i + 1] - stamps[i];
        }
        Ok(timings)
    }

    /// [`Effect::forget_states`]: the frame's images too are transitioned from UNDEFINED by
    /// the next frame.
    pub fn forget_states(&mut self) {
        self.effect.forget_states();
    }

    /// The frame itself; returns the passes it recorded (whose timestamps it wrote).
    fn record_frame(&self, rec: &CommandRecorder, tracker: &mut Tracker) -> FrameTimings {
        let mut timer = PassTimer::start(self.queries.as_ref(), rec);
        // The lighting pass reads the shadow maps whatever the techniques read.
        self.effect.record_passes(rec, tracker, true, &mut |rec, name| timer.stamp(rec, name));
        self.lighting.record(rec, tracker, &self.effect.scene);
        timer.stamp(rec, "lighting");
        self.tonemap.record(rec, tracker, self.settings().exposure);
        timer.stamp(rec, "tonemap");
        timer.recorded
    }
}

/// Writes a timestamp before the first pass and after each, and lists the passes' names.
struct PassTimer<'q> {
    queries: Option<&'q TimestampQueries>,
    recorded: FrameTimings,
}

impl<'q> PassTimer<'q> {
    fn start(queries: Option<&'q TimestampQueries>, rec: &CommandRecorder) -> Self {
        if let Some(q) = queries {
            q.reset(rec);
            q.write(rec, 0);
        }
        PassTimer { queries, recorded: FrameTimings::default() }
    }

    /// Resumes timing after the passes `recorded` lists.
    fn resume(queries: Option<&'q TimestampQueries>, recorded: FrameTimings) -> Self {
        PassTimer { queries, recorded }
    }

    fn stamp(&mut self, rec: &CommandRecorder, pass: &'static str) {
        let n = self.recorded.len;
        debug_assert!(n < MAX_PASSES, "refused at creation: a frame times at most {MAX_PASSES} passes");
        if let Some(q) = self.queries {
            q.write(rec, n as u32 + 1);
        }
        self.recorded.passes[n] = (pass, 0.0);
        self.recorded.len = n + 1;
    }
}
