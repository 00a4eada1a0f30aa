//! Direct light alone: every punctual light with its variance shadow maps, no ambient light,
//! no bake. The floor every other method adds to.

use super::params::Param;
use super::{Method, Models};
use glam::Vec3;
use relume_bake::scene::Scene;

pub(crate) struct Direct;

impl Method for Direct {
    fn name(&self) -> &'static str {
        "direct"
    }

    fn description(&self) -> &'static str {
        "direct light with variance shadow maps (000 §3.4), no ambient light"
    }

    fn params(&self) -> Vec<&'static Param> {
        Vec::new()
    }

    fn models(&self) -> Models {
        Models::LocalLights
    }

    fn ambient(&self, _: &Scene) -> Option<(Vec3, f32)> {
        None
    }
}
