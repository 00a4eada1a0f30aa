//! Effect mode: techniques without relume's frame, recorded into an engine's command buffer
//! (docs/ARCHITECTURE.md, "The integrator's contract"). An [`Effect`] is the scene uploaded,
//! the variance shadow maps its techniques read, and the techniques; per frame it takes the
//! engine's lights and camera, records the techniques' passes and hands back their terms
//! (`Terms`: the padded light map of a texel term, the per-vertex buffer of a vertex term, the
//! image of a pixel term, the spherical-harmonic buffer of a radiance term) as resources the
//! engine borrows, left in the state the engine asked for. The engine samples them with
//! `shaders/include/relume.glsl`, as relume's own lighting pass does. relume's frame
//! (`crate::Renderer`) is one user of an effect: its lighting pass reads the same terms.

use crate::atlas_image::check_uv1;
use crate::gpu_scene::{FrameUniforms, GpuScene, ShadowMapView};
use crate::passes::vsm::VsmPass;
use crate::passes::vsm_blur::VsmBlurPass;
use crate::technique::{MakeTechnique, Resource, Shared, Surfaces, Technique, Terms};
use crate::vk::{vk, Access, CommandRecorder, Context, Image, ImageRef, ImageState, Tracker, Use, VkError, VkResult};
use crate::RenderSettings;
use glam::{Vec3, Vec4};
use relume_bake::scene::{Camera, Light, Scene};
use std::any::Any;
use std::sync::Arc;

/// What the engine hands an effect at creation besides the scene: its own images, which a
/// technique that can reads instead of drawing its own.
#[derive(Clone, Copy, Default)]
pub struct EngineInputs<'i> {
    /// Its view's surfaces, for a pixel term (read instead of the technique's surfaces pass):
    /// the engine draws them each frame before the effect, writing into each normal's w the id
    /// `Effect::surface_ids` gives the mesh.
    pub surfaces: Option<Surfaces<'i>>,
    /// Its variance shadow maps, for the techniques that shadow their direct light
    /// (`Technique::reads_shadows`), which then read them instead of relume's: an RG32F 2D-array
    /// image with sampled usage, layer l holding the first two moments (d, d^2) of the light depth d that
    /// `Effect::shadow_map_views()[l]` sees (cleared to (far, far^2)), drawn each frame before
    /// the effect. The effect then renders no shadow maps of its own.
    pub shadows: Option<&'i Image>,
}

/// How the engine uses what an effect reads and writes in a frame: it will read the terms'
/// `images` as FragmentSampled or ComputeSampled and their `buffers` as GraphicsStorageRead or
/// ComputeStorageRead; the images it handed over (`EngineInputs`) were last used as `surfaces`
/// and `shadows` (by its own passes that drew them: never Undefined, which would discard them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TermReads {
    pub images: Access,
    pub buffers: Access,
    pub surfaces: Access,
    pub shadows: Access,
}

impl Default for TermReads {
    /// Read in the engine's own graphics pass; its surfaces and shadow maps drawn by its own
    /// graphics passes.
    fn default() -> Self {
        let drawn = Access::ColorAttachmentWrite;
        TermReads { images: Access::FragmentSampled, buffers: Access::GraphicsStorageRead, surfaces: drawn, shadows: drawn }
    }
}

/// The engine's images the techniques read (`EngineInputs`, those no technique reads left
/// out): their states come with each frame.
#[derive(Clone, Copy, Default)]
struct EngineImages {
    positions: Option<ImageRef>,
    normals: Option<ImageRef>,
    shadows: Option<ImageRef>,
}

/// What one frame of an effect hands the engine: its terms, borrowed until the next frame is
/// recorded, and the state each kind of resource is left in.
pub struct EffectOutput<'e> {
    pub terms: Terms<'e>,
    /// The state of every image of `terms` (the engine's next barrier starts from it).
    pub images: ImageState,
    /// The access every buffer of `terms` was made ready for.
    pub buffers: Access,
    /// The state the engine's surfaces and shadow maps (`EngineInputs`) are left in: as it
    /// gave it when no technique read them.
    pub surfaces: ImageState,
    pub shadows: ImageState,
}

/// The scene uploaded, the shadow maps and the techniques, with what a frame needs of them.
pub struct Effect {
    ctx: Arc<Context>,
    settings: RenderSettings,
    camera: Camera,
    pub(crate) scene: GpuScene,
    /// relume's shadow maps (moments, blur), unless the engine hands over its own.
    shadow_maps: Option<(VsmPass, VsmBlurPass)>,
    techniques: Vec<Box<dyn Technique>>,
    inputs: EngineImages,
    tracker: Tracker,
    /// The scene's environment's radiance in spherical harmonics (zero without one).
    environment_sh: [Vec4; 9],
}

impl Effect {
    /// Uploads the scene, creates the shadow maps and each technique from its data, in the
    /// given order (the order of their passes), handing them the engine's `inputs`. Blocking:
    /// uploads go through one-time submissions, each waited for by its own fence; nothing here
    /// runs per frame. Refused, by name: invalid settings, what a technique refuses (engine
    /// inputs of another size or format among it), two techniques handing over a term of the
    /// same role, and a texel term on a scene without uv1 on the atlas's pages. `settings`'
    /// size is a pixel term's; its shadow settings are the shadow maps'.
    pub fn new_blocking(
        ctx: &Arc<Context>,
        scene: &Scene,
        settings: &RenderSettings,
        techniques: &[&dyn MakeTechnique],
        inputs: &EngineInputs,
    ) -> VkResult<Effect> {
        settings.validate().map_err(VkError::Invalid)?;
        let gpu_scene = GpuScene::upload_blocking(ctx, scene)?;
        let shadow_maps = match inputs.shadows {
            Some(moments) => {
                check_shadow_maps(moments, gpu_scene.shadow_views.len().max(1) as u32)?;
                None
            }
            None => {
                let vsm = VsmPass::new(ctx, &gpu_scene, settings.shadow_map_size)?;
                let blur = VsmBlurPass::new(ctx, &vsm.moments, settings.blur_radius)?;
                Some((vsm, blur))
            }
        };
        let moments = inputs.shadows.or(shadow_maps.as_ref().map(|(vsm, _)| &vsm.moments)).expect("one or the other");
        let shared = Shared { ctx, scene, gpu_scene: &gpu_scene, moments, settings, surfaces: inputs.surfaces };
        let techniques = techniques.iter().map(|t| t.make_blocking(&shared)).collect::<VkResult<Vec<_>>>()?;
        let read_surfaces = techniques.iter().any(|t| t.surface_ids().is_some());
        let read_shadows = techniques.iter().any(|t| t.reads_shadows());
        let surfaces = inputs.surfaces.filter(|_| read_surfaces);
        let inputs = EngineImages {
            positions: surfaces.map(|s| ImageRef::from(s.positions)),
            normals: surfaces.map(|s| ImageRef::from(s.normals)),
            shadows: inputs.shadows.filter(|_| read_shadows).map(ImageRef::from),
        };
        let mut effect = Effect {
            ctx: Arc::clone(ctx),
            settings: settings.clone(),
            camera: scene.camera,
            scene: gpu_scene,
            shadow_maps,
            techniques,
            inputs,
            tracker: Tracker::default(),
            environment_sh: scene.environment.as_ref().map_or([Vec4::ZERO; 9], |e| e.radiance_sh().map(|c| c.extend(0.0))),
        };
        for atlas in effect.terms()?.atlas_images() {
            check_uv1(scene, atlas.desc.layers)?;
        }
        effect.forget_states();
        Ok(effect)
    }

    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }

    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The terms the techniques hand over (checked at creation: at most one of each role).
    pub fn terms(&self) -> VkResult<Terms<'_>> {
        gather_terms(&self.techniques)
    }

    /// Per mesh of the scene, the id the engine writes into the w of its surfaces' normals,
    /// when a technique reads the surfaces it handed over; None when none does (the engine
    /// then need not draw them).
    pub fn surface_ids(&self) -> Option<&[u32]> {
        self.techniques.iter().find_map(|t| t.surface_ids())
    }

    /// relume's blurred variance shadow maps (one layer per shadow view of every light); None
    /// when the engine hands over its own.
    pub(crate) fn moments(&self) -> Option<&Image> {
        self.shadow_maps.as_ref().map(|(vsm, _)| &vsm.moments)
    }

    /// Whether a technique reads shadow maps: the engine's when it handed them over.
    pub fn reads_shadow_maps(&self) -> bool {
        self.techniques.iter().any(|t| t.reads_shadows())
    }

    /// Every layer of the shadow maps an engine that hands over its own draws
    /// (`EngineInputs::shadows`), as the lights stand now: ask again after `set_lights` (the
    /// views follow the lights; reading them allocates nothing).
    pub fn shadow_map_views(&self) -> impl Iterator<Item = ShadowMapView> + '_ {
        self.scene.shadow_map_views()
    }

    /// Passes the techniques record per frame.
    pub(crate) fn technique_passes(&self) -> usize {
        self.techniques.iter().map(|t| t.passes().len()).sum()
    }

    /// The technique of type `T`, if the effect has one (to change its own settings).
    pub fn technique_mut<T: Technique>(&mut self) -> Option<&mut T> {
        self.techniques.iter_mut().find_map(|t| (t.as_mut() as &mut dyn Any).downcast_mut::<T>())
    }

    /// GPU work the techniques timed at creation (`<technique>.<work>`, milliseconds).
    pub fn creation_timings(&self) -> Vec<(&'static str, f64)> {
        self.techniques.iter().flat_map(|t| t.creation_timings()).collect()
    }

    /// Changes I_A (lux) and beta (see [`RenderSettings::ambient`]) for the frames recorded
    /// from now on, without allocating; refused like invalid settings.
    pub fn set_ambient(&mut self, ambient: Vec3, beta: f32) -> VkResult<()> {
        let next = RenderSettings { ambient, beta, ..self.settings.clone() };
        next.validate().map_err(VkError::Invalid)?;
        self.settings = next;
        Ok(())
    }

    /// Moves the lights (same kinds and count as the scene had), without allocating, and tells
    /// every technique (`Technique::lights_set`). The next frame recorded carries the new data
    /// in its command buffer, so a frame still in flight is not disturbed.
    pub fn set_lights(&mut self, lights: &[Light]) -> VkResult<()> {
        self.place_lights(lights, None)
    }

    /// As [`Effect::set_lights`] for lights that moved continuously over `seconds` (a frame's
    /// time): techniques that ease changes over time (a fade as visibility changes) advance by
    /// it instead of settling at once.
    pub fn move_lights(&mut self, lights: &[Light], seconds: f32) -> VkResult<()> {
        self.place_lights(lights, Some(seconds))
    }

    fn place_lights(&mut self, lights: &[Light], elapsed: Option<f32>) -> VkResult<()> {
        self.scene.set_lights(lights)?;
        self.techniques.iter_mut().for_each(|t| t.lights_set(lights, elapsed));
        Ok(())
    }

    /// Moves mesh `mesh` (an index into the scene's meshes) by `translation` from where the
    /// scene had it, for the frames recorded from now on, without allocating; the shadow
    /// maps refit to the moved scene at the next [`Effect::set_lights`], and every technique
    /// hears of it (`Technique::mesh_translated`: one that models moving geometry follows).
    /// Baked data stays as baked: that is what a moving-occluder sweep measures. The vertex
    /// buffer is written at once, so no frame this effect recorded may be in flight.
    pub fn set_mesh_translation(&mut self, mesh: usize, translation: Vec3) -> VkResult<()> {
        self.scene.translate_mesh(mesh, translation)?;
        self.techniques.iter_mut().for_each(|t| t.mesh_translated(mesh, translation));
        Ok(())
    }

    /// Gives mesh `mesh` new vertex positions and normals (one each per vertex of the mesh as
    /// the effect was made with it, in that order; its triangles stay), for the frames
    /// recorded from now on, without allocating: a deforming receiver (003 §5: receivers need
    /// no precomputation). Its translation, if any, still applies. Baked data stays as baked.
    /// The vertex buffer is written at once, so no frame this effect recorded may be in flight.
    pub fn set_mesh_vertices(&mut self, mesh: usize, positions: &[Vec3], normals: &[Vec3]) -> VkResult<()> {
        self.scene.reshape_mesh(mesh, positions, normals)
    }

    /// The viewer: a pixel term's (and a radiance term's relume frame's) camera.
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = camera;
    }

    /// Records one frame of the techniques into the engine's command buffer (begun, ended and
    /// submitted by the engine, which must not submit two frames of one effect at once): the
    /// frame's uniforms and lights, the shadow maps when a technique reads them, every
    /// technique's passes, which read the engine's images from the states `reads.surfaces` and
    /// `reads.shadows`; then the barriers that make every term's image ready for `reads.images`
    /// and every buffer for `reads.buffers`. Nothing is allocated, submitted or waited on.
    /// Refused before anything is recorded: a read that is not a sampled image read or a storage
    /// buffer read, and engine images said to be Undefined.
    pub fn record(&mut self, rec: &CommandRecorder, reads: TermReads) -> VkResult<EffectOutput<'_>> {
        let image_reads = [Access::FragmentSampled, Access::ComputeSampled];
        let buffer_reads = [Access::GraphicsStorageRead, Access::ComputeStorageRead];
        if !image_reads.contains(&reads.images) || !buffer_reads.contains(&reads.buffers) {
            return Err(VkError::Invalid(format!(
                "an effect's terms are read as images {image_reads:?} and buffers {buffer_reads:?}; asked for {:?} and {:?}",
                reads.images, reads.buffers
            )));
        }
        if reads.surfaces == Access::Undefined || reads.shadows == Access::Undefined {
            return Err(VkError::Invalid(
                "the engine's surfaces and shadow maps are read as its passes left them; Undefined would discard them: give the access of the pass that drew them".into(),
            ));
        }
        let mut tracker = std::mem::take(&mut self.tracker);
        let given = [(self.inputs.positions, reads.surfaces), (self.inputs.normals, reads.surfaces), (self.inputs.shadows, reads.shadows)];
        given.iter().for_each(|(image, access)| image.iter().for_each(|image| tracker.assume(*image, *access)));
        self.record_passes(rec, &mut tracker, self.reads_shadow_maps(), &mut |_, _| {});
        let left = |image: Option<ImageRef>, given: Access| image.map_or(given, |image| tracker.state(image)).state();
        let (surfaces, shadows) = (left(self.inputs.positions, reads.surfaces), left(self.inputs.shadows, reads.shadows));
        self.tracker = tracker;
        let terms = gather_terms(&self.techniques)?;
        // The engine's read is a pass of its own: what it uses is declared here, for it.
        let images = terms.images().map(|image| Use::image(image, reads.images));
        let buffers = terms.vertex_values().into_iter().map(|buffer| Use::buffer(buffer, reads.buffers));
        self.tracker.pass(rec, images.chain(buffers), |_| {});
        Ok(EffectOutput { terms, images: reads.images.state(), buffers: reads.buffers, surfaces, shadows })
    }

    /// The frame's uniforms, lights and shadow layers, the shadow maps when `shadows` (and a
    /// light casts them), and every technique's passes, calling `stamp` after each pass.
    pub(crate) fn record_passes(
        &self,
        rec: &CommandRecorder,
        tracker: &mut Tracker,
        shadows: bool,
        stamp: &mut dyn FnMut(&CommandRecorder, &'static str),
    ) {
        self.scene.record_updates(rec, &self.frame_uniforms());
        let drawn = self.shadow_maps.as_ref().filter(|_| shadows && self.settings.shadows && !self.scene.shadow_views.is_empty());
        if let Some((vsm, blur)) = drawn {
            vsm.record(rec, tracker, &self.scene);
            stamp(rec, "vsm_moments");
            if self.settings.blur_radius > 0 {
                blur.record(rec, tracker);
                stamp(rec, "vsm_blur");
            }
        }
        for technique in &self.techniques {
            for (pass, name) in technique.passes().iter().enumerate() {
                technique.record(pass, rec, tracker);
                stamp(rec, name);
            }
        }
    }

    /// A technique's resource by its full name, `<technique>.<resource>`.
    pub fn resource(&self, name: &str) -> Option<Resource<'_>> {
        let (technique, resource) = name.split_once('.')?;
        let technique = self.techniques.iter().find(|t| t.name() == technique)?;
        technique.resources().into_iter().find(|(n, _)| *n == resource).map(|(_, r)| r)
    }

    /// Every technique resource's full name.
    pub fn resource_names(&self) -> Vec<String> {
        self.techniques.iter().flat_map(|t| t.resources().into_iter().map(|(n, _)| format!("{}.{n}", t.name()))).collect()
    }

    /// Forgets what the effect's images were last used for, after a recorded frame was never
    /// submitted or its submission failed. Safe because every frame rewrites every image and
    /// buffer it uses; the next frame transitions them from UNDEFINED. Uploaded images, which
    /// no frame writes, stay known as ready for sampling.
    pub fn forget_states(&mut self) {
        self.tracker = Tracker::default();
        self.scene.register_states(&mut self.tracker);
        for technique in &self.techniques {
            technique.register_states(&mut self.tracker);
        }
    }

    /// The tracker, taken for a frame that records more than the effect's passes (relume's
    /// own: its lighting pass and tonemap); handed back with [`Effect::put_tracker`].
    pub(crate) fn take_tracker(&mut self) -> Tracker {
        std::mem::take(&mut self.tracker)
    }

    pub(crate) fn put_tracker(&mut self, tracker: Tracker) {
        self.tracker = tracker;
    }

    pub(crate) fn tracker(&self) -> &Tracker {
        &self.tracker
    }

    fn frame_uniforms(&self) -> FrameUniforms {
        let s = &self.settings;
        let (times_occlusion, occluded_direct) = self.terms().map_or((false, false), |t| (t.times_occlusion, t.occluded_direct));
        FrameUniforms {
            clip_from_world: self.camera.clip_from_world(s.width, s.height),
            camera_position: self.camera.position().extend(1.0),
            ambient_beta: s.ambient.extend(s.beta),
            light_count: self.scene.light_count(),
            shadows: s.shadows as u32,
            min_variance: s.min_variance,
            bleeding_reduction: s.bleeding_reduction,
            irradiance_times_occlusion: times_occlusion as u32,
            occluded_direct: occluded_direct as u32,
            environment_ambient: (s.environment_ambient && self.environment_sh != [Vec4::ZERO; 9]) as u32,
            _pad: 0,
            environment_sh: self.environment_sh,
        }
    }
}

/// The terms `techniques` hand over (a borrow of them alone, so the tracker stays free).
fn gather_terms(techniques: &[Box<dyn Technique>]) -> VkResult<Terms<'_>> {
    Terms::gather(techniques.iter().map(|t| (t.name(), t.term())))
}

/// Refuses, naming what it must be, an engine's shadow maps the techniques cannot read.
fn check_shadow_maps(moments: &Image, layers: u32) -> VkResult<()> {
    let d = &moments.desc;
    let fits = d.format == vk::Format::R32G32_SFLOAT
        && d.usage.contains(vk::ImageUsageFlags::SAMPLED)
        && d.view_type == vk::ImageViewType::TYPE_2D_ARRAY
        && d.layers == layers;
    match fits {
        true => Ok(()),
        false => Err(VkError::Invalid(format!(
            "the engine's shadow maps are a {}-layer {:?} {:?} image with usage {:?}; the techniques read an RG32F 2D array with sampled usage of {layers} layers, one per Effect::shadow_map_views()",
            d.layers, d.format, d.view_type, d.usage
        ))),
    }
}
