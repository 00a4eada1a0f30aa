//! Direct light plus a constant ambient term: the illumination model of Iones et al., "Fast
//! realistic lighting for video games" (001), eq. (5)-(7), with W = 1 everywhere; on a scene
//! lit by an environment, I_A adds its unoccluded irradiance at each normal. No bake.

use super::params::Param;
use super::{scene_ambient, Method, Models};
use glam::Vec3;
use relume_bake::scene::Scene;

pub(crate) struct Constant;

impl Method for Constant {
    fn name(&self) -> &'static str {
        "constant"
    }

    fn description(&self) -> &'static str {
        "direct light plus constant ambient light (001 eq. 5-7 with W = 1)"
    }

    fn params(&self) -> Vec<&'static Param> {
        Vec::new()
    }

    fn models(&self) -> Models {
        Models::Ambient
    }

    fn ambient(&self, scene: &Scene) -> Option<(Vec3, f32)> {
        scene_ambient(scene)
    }

    fn environment_ambient(&self) -> bool {
        true
    }
}
