//! A method's run-time part is a technique: created once from the frame's shared state and
//! its own data (uploads, pipelines, descriptor sets), it records its passes into the frame in
//! order and hands the lighting pass one term (docs/ARCHITECTURE.md). The frame knows
//! techniques only through this trait; each lives in a folder under `techniques/` with its
//! shaders in a folder of the same name under `shaders/`.

use crate::gpu_scene::GpuScene;
use crate::vk::{Buffer, CommandRecorder, Context, Image, Tracker, VkError, VkResult};
use crate::RenderSettings;
use glam::Vec3;
use relume_bake::scene::{Light, Scene};
use std::any::Any;
use std::sync::Arc;

/// What a technique is created from besides its own data: the device, the scene as loaded
/// (with the atlas's uv1 when a bake gave one) and as uploaded (its buffers, among them the
/// frame's uniforms), the shadow moments (relume's, blurred, or an engine's), the frame's settings, and the surfaces of
/// the view an engine draws itself, when it hands them over (`crate::effect::EngineInputs`).
pub struct Shared<'s> {
    pub ctx: &'s Arc<Context>,
    pub scene: &'s Scene,
    pub gpu_scene: &'s GpuScene,
    pub moments: &'s Image,
    pub settings: &'s RenderSettings,
    pub surfaces: Option<Surfaces<'s>>,
}

/// Every pixel's surface in a view, as a pixel term reads them: `positions` (world xyz; w 1
/// where a surface is, 0 elsewhere) and `normals` (unit, turned towards the viewer; w the id
/// `Technique::surface_ids` gives the surface's mesh), RGBA32F 2D images of the frame's size
/// with storage usage, written by the engine's own pass before the effect runs.
#[derive(Clone, Copy)]
pub struct Surfaces<'s> {
    pub positions: &'s Image,
    pub normals: &'s Image,
}

/// Where the lighting pass reads an irradiance term.
pub enum Source<'t> {
    /// An atlas image (RGBA32F 2D array, padded), read through each vertex's uv1.
    Texel(&'t Image),
    /// One rgb value (vec4) per vertex of the scene's vertex buffer, read in the vertex stage
    /// and interpolated.
    Vertex(&'t Buffer),
    /// One rgb value per pixel of the frame (RGBA32F, a 2D array of one layer), read at the
    /// fragment's pixel.
    Pixel(&'t Image),
    /// The atlas image, except at vertices whose vec4 in the buffer has alpha 1 (one per
    /// vertex of the scene's vertex buffer): meshes lit per vertex, off the atlas (moving
    /// meshes lit from a volume, say). Alpha is 0 or 1 across each mesh.
    TexelOrVertex(&'t Image, &'t Buffer),
}

/// What a technique hands the lighting pass (lighting_fragment.glsl states the formula).
pub enum Term<'t> {
    /// An atlas image whose rgb scales the ambient light (I_A + beta * every light's
    /// unshadowed irradiance): W of 001 eq. (5).
    Occlusion(&'t Image),
    /// Indirect irradiance (lux), added as albedo / pi * E.
    Irradiance {
        source: Source<'t>,
        /// Scaled by the frame's occlusion term, when there is one.
        times_occlusion: bool,
        /// With `times_occlusion`: the occlusion term also scales the direct irradiance, added
        /// again (000 §3.4's literal reading).
        occluded_direct: bool,
    },
    /// Indirect exitant radiance per vertex of the scene's vertex buffer as 16 real spherical
    /// harmonics (bands l <= 3, world space, `relume_bake::sh`): 16 vec4 (rgb) per vertex, read
    /// in the vertex stage, interpolated, evaluated towards the camera and added as is (glossy
    /// surfaces). It takes the irradiance term's place: a frame has one or the other.
    Radiance(&'t Buffer),
}

/// The terms a set of techniques hands over, at most one of each role: what the lighting pass
/// reads, and what an effect gives an engine (`crate::effect`).
#[derive(Default)]
pub struct Terms<'t> {
    /// `Term::Occlusion`'s atlas image.
    pub occlusion: Option<&'t Image>,
    pub irradiance: Option<Source<'t>>,
    /// Exitant radiance in spherical harmonics per vertex: in place of `irradiance`.
    pub radiance: Option<&'t Buffer>,
    /// The irradiance term's flags (`Term::Irradiance`); false without one.
    pub times_occlusion: bool,
    pub occluded_direct: bool,
}

/// shaders/include/relume.glsl's RELUME_TERM_* kinds of the irradiance term.
pub const TERM_NONE: u32 = 0;
pub const TERM_TEXEL: u32 = 1;
pub const TERM_VERTEX: u32 = 2;
pub const TERM_PIXEL: u32 = 3;
pub const TERM_TEXEL_OR_VERTEX: u32 = 4;

impl<'t> Terms<'t> {
    /// Gathers the terms of techniques named `names`; two of one role are refused.
    pub fn gather(terms: impl Iterator<Item = (&'static str, Option<Term<'t>>)>) -> VkResult<Terms<'t>> {
        let mut gathered = Terms::default();
        let mut givers: [Option<&str>; 2] = [None, None];
        for (name, term) in terms {
            let role = match term {
                None => continue,
                Some(Term::Occlusion(image)) => {
                    gathered.occlusion = Some(image);
                    0
                }
                Some(Term::Irradiance { source, times_occlusion, occluded_direct }) => {
                    gathered.irradiance = Some(source);
                    (gathered.times_occlusion, gathered.occluded_direct) = (times_occlusion, occluded_direct);
                    1
                }
                Some(Term::Radiance(buffer)) => {
                    gathered.radiance = Some(buffer);
                    1
                }
            };
            if let Some(first) = givers[role].replace(name) {
                let what = ["an occlusion", "an irradiance or radiance"][role];
                return Err(VkError::Invalid(format!(
                    "techniques {first} and {name} both hand the lighting pass {what} term; a frame takes one of each"
                )));
            }
        }
        Ok(gathered)
    }

    /// The atlas images the terms are read from through uv1.
    pub fn atlas_images(&self) -> impl Iterator<Item = &'t Image> {
        self.occlusion.into_iter().chain(self.texels())
    }

    /// The irradiance term's atlas image, when it reads one.
    pub fn texels(&self) -> Option<&'t Image> {
        match self.irradiance {
            Some(Source::Texel(image)) | Some(Source::TexelOrVertex(image, _)) => Some(image),
            _ => None,
        }
    }

    /// The irradiance term's image of one texel per pixel, when it is one.
    pub fn pixels(&self) -> Option<&'t Image> {
        match self.irradiance {
            Some(Source::Pixel(image)) => Some(image),
            _ => None,
        }
    }

    /// The buffer read per vertex: a vertex (or texel-or-vertex) irradiance term's, or the
    /// radiance term's.
    pub fn vertex_values(&self) -> Option<&'t Buffer> {
        match (&self.irradiance, self.radiance) {
            (Some(Source::Vertex(buffer)), _) | (Some(Source::TexelOrVertex(_, buffer)), _) => Some(buffer),
            (_, radiance) => radiance,
        }
    }

    /// Every image the terms are read from.
    pub fn images(&self) -> impl Iterator<Item = &'t Image> {
        self.atlas_images().chain(self.pixels())
    }

    /// The irradiance term's kind, as the shaders number it (`TERM_*`).
    pub fn irradiance_kind(&self) -> u32 {
        match self.irradiance {
            None => TERM_NONE,
            Some(Source::Texel(_)) => TERM_TEXEL,
            Some(Source::Vertex(_)) => TERM_VERTEX,
            Some(Source::Pixel(_)) => TERM_PIXEL,
            Some(Source::TexelOrVertex(..)) => TERM_TEXEL_OR_VERTEX,
        }
    }
}

/// A technique's image or buffer, named for read-back (tests and tools).
pub enum Resource<'r> {
    Image(&'r Image),
    Buffer(&'r Buffer),
}

/// A method's run-time part. Its passes record into the frame's command buffer in the order
/// `passes` names them, each declaring what it reads and writes to the tracker; nothing is
/// allocated, submitted or waited on while recording.
pub trait Technique: Any + Send {
    /// The technique's name: its folder's, and the prefix of its passes and resources.
    fn name(&self) -> &'static str;

    /// Its passes in frame order, each `<name>.<pass>`; every one is timed.
    fn passes(&self) -> &'static [&'static str];

    /// Records pass `pass` (an index into `passes`).
    fn record(&self, pass: usize, rec: &CommandRecorder, tracker: &mut Tracker);

    /// The term it hands the lighting pass this frame, or none. Its kind and images are fixed
    /// at creation (they pick the lighting pass's variant); its flags may change per frame.
    fn term(&self) -> Option<Term<'_>>;

    /// Whether its passes read the variance shadow maps (`Shared::moments`): an effect then
    /// renders them before its passes, unless the engine handed over its own (`crate::effect`).
    fn reads_shadows(&self) -> bool {
        false
    }

    /// When it reads the engine's surfaces (`Shared::surfaces`) instead of drawing its own: the
    /// id each of the scene's meshes carries in the w of the normals.
    fn surface_ids(&self) -> Option<&[u32]> {
        None
    }

    /// Tells a frame's tracker the state its uploads left its images in.
    fn register_states(&self, _tracker: &mut Tracker) {}

    /// Its resources by name (without the prefix), for read-back.
    fn resources(&self) -> Vec<(&'static str, Resource<'_>)> {
        Vec::new()
    }

    /// GPU work timed once at creation (`<name>.<work>`, milliseconds).
    fn creation_timings(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }

    /// The scene's mesh `mesh` now stands `translation` from where the scene had it (see
    /// `Renderer::set_mesh_translation`), for the frames recorded from now on; a technique
    /// that follows moving geometry updates its own data here, without allocating.
    fn mesh_translated(&mut self, _mesh: usize, _translation: Vec3) {}

    /// The lights now stand as `lights` (see `Renderer::set_lights`; at creation, the scene's),
    /// for the frames recorded from now on; a technique whose data follows the lights on the
    /// CPU updates it here, without allocating. `elapsed`: the seconds since they last stood
    /// somewhere when they moved continuously (`Renderer::move_lights`), None for a cut: a
    /// technique that eases changes over time settles at once.
    fn lights_set(&mut self, _lights: &[Light], _elapsed: Option<f32>) {}
}

/// A technique's data, ready to become a technique on the device.
pub trait MakeTechnique {
    /// Uploads the data and creates the passes; may submit and wait (once, at creation).
    fn make_blocking(&self, shared: &Shared) -> VkResult<Box<dyn Technique>>;
}
