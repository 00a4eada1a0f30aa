//! Obscurances (Iones et al., "Fast realistic lighting for video games", 001): the atlas, W per
//! texel by Monte Carlo rays (any variant: obscurance, ambient occlusion, the spectral
//! obscurance of 000 §3.3), and at run time the obscurance technique scaling the ambient
//! light, eq. (5)-(7). Its parameters and stages serve the light path maps too, whose
//! small-scale term is the spectral obscurance.

use super::params::{Default, Param, Values};
use super::{atlas, Loaded, Method, Models};
use anyhow::Result;
use glam::{Vec3, Vec4};
use relume_bake::artifact::{Artifact, PageLayout};
use relume_bake::contract::Baker;
use relume_bake::obscurance::{self as bake_obscurance, ObscuranceBaker, ObscuranceSceneSettings, ObscuranceSettings, Variant};
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::{AtlasImage, MakeTechnique};

pub(crate) const VARIANT: Param = Param::choice(
    "variant",
    "obscurance (001 eq. 2-3), ao (rho a step at L_max) or spectral (000 §3.3's colour bleeding)",
    &["obscurance", "ao", "spectral"],
    Default::From("obscurance; spectral for light-path-maps"),
);
pub(crate) const TAU: Param = Param::within(
    "tau",
    "tau of rho(L) = 1 - exp(-L / tau), metres (001 eq. 2)",
    ObscuranceSettings::DISTANCE,
    Default::From("the scene's obscurance.tau"),
);
pub(crate) const L_MAX: Param = Param::within(
    "l-max",
    "L_max, metres: rho is 1 from here on (001 §4.4)",
    ObscuranceSettings::DISTANCE,
    Default::From("the scene's obscurance.l_max"),
);
pub(crate) const RAYS: Param =
    Param::within("rays", "rays per texel, spread over the texel's patch", ObscuranceSettings::RAYS_PER_TEXEL, Default::Value("256"));

pub(crate) const PARAMS: [&Param; 4] = [&VARIANT, &TAU, &L_MAX, &RAYS];

/// The obscurance bake's settings from `values` over the scene's, `variant` unless given, on
/// the atlas `values` ask for: the obscurance method's bake, and the small scale of the light
/// path maps'.
pub(crate) fn baker(scene: &Scene, values: &Values, variant: Variant) -> Result<ObscuranceBaker> {
    let scene_settings = ObscuranceSceneSettings::of(scene).map_err(anyhow::Error::msg)?;
    let variant = values.given_choice(&VARIANT).and_then(Variant::parse).unwrap_or(variant);
    let obscurance = ObscuranceSettings {
        variant,
        tau: values.given_number(&TAU).map_or(scene_settings.tau, |t| t as f32),
        l_max: values.given_number(&L_MAX).map_or(scene_settings.l_max, |l| l as f32),
        rays_per_texel: values.count(&RAYS) as u32,
        work: WorkOptions::default(),
    };
    obscurance.validate().map_err(|e| anyhow::anyhow!("{e} (--tau, --l-max, --rays)"))?;
    Ok(ObscuranceBaker { atlas: atlas::stage(scene, values)?, obscurance })
}

/// The scene re-indexed by an artifact's atlas and the obscurance on it (rgb W, alpha the
/// coverage), as the renderer takes them.
pub(crate) struct OnAtlas {
    pub scene: Scene,
    pub layout: PageLayout,
    pub texels: Vec<Vec4>,
}

impl OnAtlas {
    pub fn read(artifact: &Artifact, scene: &Scene) -> Result<OnAtlas> {
        let (atlas, applied) = atlas::read(artifact, scene)?;
        let values: Vec<Vec3> = bake_obscurance::read(artifact, scene, atlas.layout)?;
        Ok(OnAtlas { scene: applied, layout: atlas.layout, texels: atlas.with_coverage(&values) })
    }

    pub fn image(&self) -> AtlasImage<'_> {
        AtlasImage::new(self.layout, &self.texels)
    }
}

impl Loaded for OnAtlas {
    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>> {
        vec![Box::new(ObscuranceData { obscurance: self.image() })]
    }
}

pub(crate) struct Obscurance;

impl Method for Obscurance {
    fn name(&self) -> &'static str {
        "obscurance"
    }

    fn description(&self) -> &'static str {
        "direct light plus ambient light scaled by baked obscurances (Iones et al. 2003, eq. 5-7)"
    }

    fn params(&self) -> Vec<&'static Param> {
        [&atlas::PARAMS[..], &PARAMS[..]].concat()
    }

    fn bakes(&self) -> bool {
        true
    }

    fn main_job_values(&self, rays: u32) -> Vec<(String, String)> {
        vec![(RAYS.name.into(), rays.to_string())]
    }

    fn models(&self) -> Models {
        Models::Ambient
    }

    fn ambient(&self, scene: &Scene) -> Option<(Vec3, f32)> {
        super::scene_ambient(scene)
    }

    /// W times the environment's irradiance at the normal: the game baseline an environment's
    /// light is rendered by without a method of its own.
    fn environment_ambient(&self) -> bool {
        true
    }

    fn baker(&self, scene: &Scene, values: &Values) -> Result<Box<dyn Baker>> {
        Ok(Box::new(baker(scene, values, Variant::Obscurance)?))
    }

    fn load(&self, artifact: Option<&Artifact>, scene: &Scene, _: &Values) -> Result<Box<dyn Loaded>> {
        let artifact = artifact.ok_or_else(|| anyhow::anyhow!("obscurance renders from a bake: give --bake"))?;
        Ok(Box::new(OnAtlas::read(artifact, scene)?))
    }
}
