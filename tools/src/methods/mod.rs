//! The one registry of relume's methods. A method is one type implementing [`Method`] and one
//! line in [`METHODS`]; `relume bake`, `render`, `run`, `bench` and `methods` read it and know
//! nothing else about any method (docs/ARCHITECTURE.md, "Adding a method").

mod atlas;
mod constant;
mod direct;
#[cfg(test)]
mod effects;
mod fiv;
mod light_cloud;
mod light_path_maps;
#[cfg(test)]
mod limits;
#[cfg(test)]
mod matrix;
mod mrt;
mod obscurance;
pub(crate) mod params;

use anyhow::{bail, Context as _, Result};
use glam::Vec3;
use params::{Param, Stage, Values};
use relume_bake::artifact::Artifact;
use relume_bake::contract::Baker;
use relume_bake::scene::Scene;
use relume_renderer::MakeTechnique;

/// Every method, in the order reports list them.
pub(crate) const METHODS: [&dyn Method; 7] = [
    &direct::Direct,
    &constant::Constant,
    &obscurance::Obscurance,
    &light_path_maps::LightPathMaps,
    &fiv::Fiv,
    &light_cloud::LightCloudMethod,
    &mrt::MrtMethod,
];

/// What `relume render` renders without a bake.
pub(crate) const WITHOUT_BAKE: &dyn Method = &constant::Constant;

pub(crate) trait Method: Sync {
    /// Its one name: the `--method` of `relume bake`, a sweep's `method`, an artifact's
    /// `method`, the main job's file names.
    fn name(&self) -> &'static str;

    /// One line: what it renders, after which paper.
    fn description(&self) -> &'static str;

    /// Its parameters, bake and run time (see `params`).
    fn params(&self) -> Vec<&'static Param>;

    /// Whether it renders from a bake artifact.
    fn bakes(&self) -> bool {
        false
    }

    /// The light it models beside every punctual light's direct light, which every frame
    /// renders: a scene without any of it is refused (`refusal`), and a scene with light it
    /// does not model renders with a warning that its image lacks that light (`misses`).
    fn models(&self) -> Models;

    /// Whether what it needs from `scene` is there or can be derived from it (the main job
    /// runs it where `suits` says so: see the function).
    fn suits(&self, _scene: &Scene) -> bool {
        true
    }

    /// Parameter values the main job gives it instead of the defaults.
    fn main_job_values(&self, _rays: u32) -> Vec<(String, String)> {
        Vec::new()
    }

    /// I_A and beta of the frame's ambient light when the user gives none: the scene's for
    /// the methods of the obscurance illumination model, zero for the others. None for a
    /// method that models no ambient light: then none is given to it either.
    fn ambient(&self, _scene: &Scene) -> Option<(Vec3, f32)> {
        Some((Vec3::ZERO, 0.0))
    }

    /// Whether its ambient light adds the scene's environment (`extras.relume.environment`):
    /// the environment's unoccluded irradiance at each normal, scaled as I_A is
    /// (`RenderSettings::environment_ambient`).
    fn environment_ambient(&self) -> bool {
        false
    }

    /// Its bake for `scene`, its settings mapped from `values` (the bake contract: the work
    /// itself is the bake crate's).
    fn baker(&self, _scene: &Scene, _values: &Values) -> Result<Box<dyn Baker>> {
        anyhow::bail!("{} has no bake", self.name())
    }

    /// What its techniques are made from: read from `artifact` (its bake; None for a method
    /// without one) for `scene`, with the run-time `values`. Without a bake: the scene as it
    /// is and no technique.
    fn load(&self, _artifact: Option<&Artifact>, scene: &Scene, _values: &Values) -> Result<Box<dyn Loaded>> {
        Ok(Box::new(Plain(scene.clone())))
    }
}

/// The light a method models beside the punctual lights' direct light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Models {
    /// Punctual (point, spot, directional) lights: their light alone, or their indirect light.
    LocalLights,
    /// A distant environment's light (`extras.relume.environment`).
    Environment,
    /// Ambient light: the scene's I_A and beta, and its environment where it has one.
    Ambient,
}

/// Whether the main job runs `method` on `scene`: the scene has light it models, and what it
/// needs from the scene is there or can be derived (relume models no more than a scene needs).
pub(crate) fn suits(method: &dyn Method, scene: &Scene) -> bool {
    unsuited(method, scene).is_none()
}

/// Why `method` does not suit `scene` (see `suits`), for a report's list of what did not run.
pub(crate) fn unsuited(method: &dyn Method, scene: &Scene) -> Option<String> {
    refusal(method, scene).or_else(|| {
        (!method.suits(scene))
            .then(|| format!("{} needs settings this scene neither declares nor lets it derive (its bake would refuse it)", method.name()))
    })
}

/// Whether a distant environment lights `scene` (one whose light is not all zero).
pub(crate) fn environment_lit(scene: &Scene) -> bool {
    scene.environment.as_ref().is_some_and(|e| e.is_lit())
}

/// Why `method` cannot render `scene`: the scene has none of the light it models.
pub(crate) fn refusal(method: &dyn Method, scene: &Scene) -> Option<String> {
    let lit = environment_lit(scene);
    match method.models() {
        Models::LocalLights if scene.lights.is_empty() => Some(format!(
            "{} models the light of point, spot and directional lights; this scene has none (give some with --lights FILE)",
            method.name()
        )),
        Models::Environment if !lit => Some(format!(
            "{} models a distant environment's light; this scene has none (declare extras.relume.environment or give --environment FILE)",
            method.name()
        )),
        _ => None,
    }
}

/// The light the scene has that `method` does not model (its image lacks it), for a warning.
pub(crate) fn misses(method: &dyn Method, scene: &Scene) -> Option<String> {
    let lit = environment_lit(scene);
    match method.models() {
        Models::LocalLights if lit => Some(format!("{} models no environment light: its image lacks the environment's", method.name())),
        Models::Environment if !scene.lights.is_empty() => {
            Some(format!("{} models no indirect light of the punctual lights: its image lacks it", method.name()))
        }
        _ => None,
    }
}

/// The scene's I_A and beta: the ambient light of the obscurance illumination model (001 eq. 5-7).
pub(crate) fn scene_ambient(scene: &Scene) -> Option<(Vec3, f32)> {
    Some((scene.settings.ambient, scene.settings.beta))
}

/// The frame's I_A and beta: the given ones over the method's `defaults`; none where the
/// method models no ambient light (`defaults` None).
pub(crate) fn frame_ambient(defaults: Option<(Vec3, f32)>, ambient: Option<Vec3>, beta: Option<f32>) -> (Vec3, f32) {
    match defaults {
        Some((default_ambient, default_beta)) => (ambient.unwrap_or(default_ambient), beta.unwrap_or(default_beta)),
        None => (Vec3::ZERO, 0.0),
    }
}

/// A method's data for one scene, read and ready to become the renderer's techniques.
pub(crate) trait Loaded {
    /// The scene as its techniques need it (re-indexed with the atlas's uv1, when it has one).
    fn scene(&self) -> &Scene;

    /// Its techniques, in frame order.
    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>>;
}

/// A method without a bake: the scene as it is and no technique.
pub(crate) struct Plain(pub Scene);

impl Loaded for Plain {
    fn scene(&self) -> &Scene {
        &self.0
    }

    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>> {
        Vec::new()
    }
}

/// The method of that name, or a refusal that lists them.
/// A method's name as a flag's value: checked by the flag's parser, so an unknown name is a
/// usage error (exit code 2) like any value that cannot be read.
pub(crate) fn method_name(name: &str) -> std::result::Result<String, String> {
    find(name).map(|m| m.name().to_string()).map_err(|e| e.to_string())
}

pub(crate) fn find(name: &str) -> Result<&'static dyn Method> {
    METHODS.iter().copied().find(|m| m.name() == name).with_context(|| {
        format!("method \"{name}\": not a relume method; use one of {}", METHODS.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "))
    })
}

/// What `method` renders from: its bake `artifact` read for `scene` with the run-time
/// `values`; refused when the scene has none of the light the method models.
pub(crate) fn load(method: &dyn Method, artifact: Option<&Artifact>, scene: &Scene, values: &Values) -> Result<Box<dyn Loaded>> {
    refuse(method, scene)?;
    method.load(artifact, scene, values)
}

/// Refuses, naming the scene, a method that models none of the scene's light.
pub(crate) fn refuse(method: &dyn Method, scene: &Scene) -> Result<()> {
    match refusal(method, scene) {
        Some(why) => anyhow::bail!("{}: {why}", scene.source.display()),
        None => Ok(()),
    }
}

/// The method whose bake `artifact` (read from `dir`) is: refused, naming its manifest, when
/// the manifest names a method this relume lacks or one that makes no bake.
pub(crate) fn of_bake(artifact: &Artifact, dir: &std::path::Path) -> Result<&'static dyn Method> {
    let manifest = dir.join("manifest.json");
    let method = find(artifact.method())
        .with_context(|| format!("{}: the bake names a method this relume lacks; bake it again with `relume bake`", manifest.display()))?;
    if !method.bakes() {
        bail!("{}: the bake names {}, a method that makes no bake; bake it again with `relume bake`", manifest.display(), method.name());
    }
    Ok(method)
}

/// The methods that take the parameter `name`.
pub(crate) fn takers(name: &str) -> Vec<&'static str> {
    METHODS.iter().filter(|m| m.params().iter().any(|p| p.name == name)).map(|m| m.name()).collect()
}

/// `values` parsed for `method`, keeping only the parameters of `stage` (None: every one).
pub(crate) fn parse_values(method: &dyn Method, pairs: &[(String, String)], stage: Option<Stage>) -> Result<Values> {
    let params: Vec<&'static Param> = method.params().into_iter().filter(|p| stage.is_none_or(|s| p.stage == s)).collect();
    Values::parse(method.name(), &params, pairs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use relume_bake::testing::{closed_box, look_at, scene, Facing};

    #[test]
    fn a_given_ambient_light_reaches_every_method_that_models_one_and_never_direct_or_fiv() {
        let mut room = scene(
            "room",
            vec![closed_box(Vec3::ZERO, Vec3::ONE, 1, Facing::Inward, 0)],
            vec![],
            vec![],
            look_at(Vec3::splat(0.5), Vec3::X, Vec3::Y, 1.0),
        );
        room.settings.ambient = Vec3::splat(0.25);
        let given = (Some(Vec3::splat(2.0)), Some(0.5));
        for method in METHODS {
            let (ambient, beta) = frame_ambient(method.ambient(&room), given.0, given.1);
            let (default_ambient, _) = frame_ambient(method.ambient(&room), None, None);
            match method.name() {
                // Models no ambient light: direct light alone, the environment's, or all indirect light.
                "direct" | "fiv" | "light-cloud" | "mrt" => assert_eq!((ambient, beta, default_ambient), (Vec3::ZERO, 0.0, Vec3::ZERO)),
                "constant" | "obscurance" => assert_eq!((ambient, beta, default_ambient), (Vec3::splat(2.0), 0.5, Vec3::splat(0.25))),
                _ => assert_eq!((ambient, beta, default_ambient), (Vec3::splat(2.0), 0.5, Vec3::ZERO)),
            }
        }
    }
}
