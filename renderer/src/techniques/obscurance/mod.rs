//! The obscurances of Iones et al., "Fast realistic lighting for video games" (001), at run
//! time: the baked obscurance W (any variant: obscurance, ambient occlusion, the spectral
//! obscurance of 000 §3.3) uploaded and padded once, and handed to the lighting pass as the
//! occlusion term that scales its ambient light, 001 eq. (5). No pass runs per frame.

use crate::atlas_image::{AtlasImage, GpuAtlasImage};
use crate::technique::{MakeTechnique, Resource, Shared, Technique, Term};
use crate::vk::{CommandRecorder, Tracker, VkResult};

/// What the technique is made from: W in rgb and the coverage in alpha, on the atlas whose
/// uv1 the scene carries.
pub struct ObscuranceData<'d> {
    pub obscurance: AtlasImage<'d>,
}

pub struct Obscurance {
    image: GpuAtlasImage,
}

impl Technique for Obscurance {
    fn name(&self) -> &'static str {
        "obscurance"
    }

    fn passes(&self) -> &'static [&'static str] {
        &[]
    }

    fn record(&self, _pass: usize, _rec: &CommandRecorder, _tracker: &mut Tracker) {}

    fn term(&self) -> Option<Term<'_>> {
        Some(Term::Occlusion(&self.image.image))
    }

    fn register_states(&self, tracker: &mut Tracker) {
        self.image.register_state(tracker);
    }

    /// `obscurance`: W (rgb), padded (alpha < 0 in padded texels).
    fn resources(&self) -> Vec<(&'static str, Resource<'_>)> {
        vec![("obscurance", Resource::Image(&self.image.image))]
    }

    fn creation_timings(&self) -> Vec<(&'static str, f64)> {
        self.image.padding_ms().map(|ms| ("obscurance.padding", ms)).into_iter().collect()
    }
}

impl MakeTechnique for ObscuranceData<'_> {
    /// Uploads and pads W in one submission that is waited for. Refused, by name: an image
    /// whose texel count is not width x height x pages.
    fn make_blocking(&self, shared: &Shared) -> VkResult<Box<dyn Technique>> {
        let image = GpuAtlasImage::upload_blocking(shared.ctx, "obscurance", &self.obscurance)?;
        Ok(Box::new(Obscurance { image }))
    }
}
