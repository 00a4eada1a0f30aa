//! Fullsphere irradiance vectors (Michael & Chrysanthou, "Fullsphere Irradiance
//! Factorization", 003): the environment's DifMap and FIV(Env), a table per occluder type,
//! and at run time the occluder sums per pixel, with occluders that translate every frame.
//! The one method lit by a distant environment: it needs a scene that declares one and names
//! its occluders.

use super::params::{Default, Param, Values};
use super::{Loaded, Method, Models};
use anyhow::Result;
use glam::Vec3;
use relume_bake::artifact::Artifact;
use relume_bake::contract::Baker;
use relume_bake::fiv::{
    self as bake_fiv, Beyond, FivBake, FivBakeSettings, FivBaker, FivSceneSettings, Grid, Occluder, OccluderType, Radial, SelfShadow,
    SumOptions,
};
use relume_bake::scene::Scene;
use relume_renderer::techniques::fiv::FivData;
use relume_renderer::MakeTechnique;

/// The paper's Table 1 grids, azimuths x polar angles x distances.
const GRIDS: [&str; 5] = ["32x17x15", "64x33x15", "64x33x30", "128x65x30", "256x129x30"];

const GRID: Param = Param::choice(
    "grid",
    "the occluder tables' sample grid, azimuths x polar angles x distances (003 Table 1)",
    &GRIDS,
    Default::Value("64x33x30"),
);
const DISTANCE_MIN: Param =
    Param::within("distance-min", "the tables' nearest distance, in bounding radii", FivBakeSettings::DISTANCE_MIN, Default::Value("0.1"));
const DISTANCE_MAX: Param =
    Param::within("distance-max", "the tables' farthest distance, in bounding radii", FivBakeSettings::DISTANCE_MAX, Default::Value("16"));
const MASK_SUPERSAMPLE: Param = Param::within(
    "mask-supersample",
    "k: k x k rays per environment texel for an occluder's mask (the paper: 1)",
    FivBakeSettings::MASK_SUPERSAMPLE,
    Default::Value("1"),
);
const DIFMAP_WIDTH: Param = Param::within(
    "difmap-width",
    "DifMap's width in texels (a lat-long grid of normals, half as high)",
    FivBakeSettings::DIFMAP_WIDTH,
    Default::Value("128"),
);
const PARTIAL: Param = Param::choice(
    "partial",
    "case B (an occluder across the tangent plane): scaled by (d + R) / 2R, or whole",
    &["paper", "off"],
    Default::Value("paper"),
)
.at_render();
const OVERLAP: Param =
    Param::choice("overlap", "the pairwise overlap correction of eq. (13)-(14)", &["on", "off"], Default::Value("on")).at_render();
const BEYOND: Param = Param::choice(
    "beyond",
    "an occluder beyond the farthest distance: the outer shell scaled by (max / d)^2, or nothing",
    &["scale", "drop"],
    Default::Value("scale"),
)
.at_render();

const RADIAL: Param = Param::choice(
    "radial",
    "between distance shells: distance^2 x FIV blended, then / distance^2 (inverse-square), or the paper's linear blend",
    &["inverse-square", "linear"],
    Default::Value("inverse-square"),
)
.at_render();

const SELF_SHADOW: Param = Param::choice(
    "self-shadow",
    "a receiver on an occluder shadowed by that occluder (003 §5): DifMap less what it hides above the tangent planes of the surface points nearest the samples, the paper's N . (FIV(Env) - FIV_self) from the table's samples, or not",
    &["surface", "paper", "off"],
    Default::Value("surface"),
)
.at_render();

const PARAMS: [&Param; 10] =
    [&GRID, &DISTANCE_MIN, &DISTANCE_MAX, &MASK_SUPERSAMPLE, &DIFMAP_WIDTH, &PARTIAL, &OVERLAP, &BEYOND, &RADIAL, &SELF_SHADOW];

pub(crate) struct Fiv;

fn bake_settings(values: &Values) -> Result<FivBakeSettings> {
    let settings = FivBakeSettings {
        grid: Grid::parse(values.choice(&GRID)).map_err(anyhow::Error::msg)?,
        distance_min: values.number(&DISTANCE_MIN) as f32,
        distance_max: values.number(&DISTANCE_MAX) as f32,
        mask_supersample: values.count(&MASK_SUPERSAMPLE) as u32,
        difmap_width: values.count(&DIFMAP_WIDTH) as u32,
    };
    settings.validate().map_err(|e| anyhow::anyhow!("{e} (--distance-min, --distance-max, --mask-supersample, --difmap-width)"))?;
    Ok(settings)
}

fn sum_options(values: &Values) -> SumOptions {
    SumOptions {
        partial: values.choice(&PARTIAL) == "paper",
        overlap: values.choice(&OVERLAP) == "on",
        beyond: if values.choice(&BEYOND) == "scale" { Beyond::Scale } else { Beyond::Drop },
        radial: if values.choice(&RADIAL) == "linear" { Radial::Linear } else { Radial::InverseSquare },
        self_shadow: match values.choice(&SELF_SHADOW) {
            "paper" => SelfShadow::Paper,
            "off" => SelfShadow::Off,
            _ => SelfShadow::Surface,
        },
    }
}

/// The scene's occluder types, refused by name.
fn types(scene: &Scene) -> Result<Vec<OccluderType>> {
    let settings = FivSceneSettings::of(scene).map_err(|e| anyhow::anyhow!("{}: {e}", scene.source.display()))?;
    bake_fiv::occluder_types(scene, &settings).map_err(|e| anyhow::anyhow!("{}: {e}", scene.source.display()))
}

fn representatives<'s>(scene: &'s Scene, types: &[OccluderType]) -> Vec<&'s str> {
    types.iter().map(|t| scene.meshes[t.meshes[0]].name.as_str()).collect()
}

/// A bake read for a scene, with the scene's occluders and the run-time choices.
struct Baked {
    scene: Scene,
    bake: FivBake,
    occluders: Vec<Occluder>,
    options: SumOptions,
}

impl Loaded for Baked {
    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>> {
        vec![Box::new(FivData { bake: &self.bake, occluders: &self.occluders, options: self.options })]
    }
}

impl Method for Fiv {
    fn name(&self) -> &'static str {
        "fiv"
    }

    fn description(&self) -> &'static str {
        "direct light of a distant environment with moving occluders, per pixel (Michael & Chrysanthou 2010)"
    }

    fn params(&self) -> Vec<&'static Param> {
        PARAMS.to_vec()
    }

    fn bakes(&self) -> bool {
        true
    }

    fn models(&self) -> Models {
        Models::Environment
    }

    /// A scene with an environment and occluders.
    fn suits(&self, scene: &Scene) -> bool {
        FivSceneSettings::of(scene).is_ok()
    }

    /// It models the environment's direct light and nothing else.
    fn ambient(&self, _: &Scene) -> Option<(Vec3, f32)> {
        None
    }

    fn baker(&self, _: &Scene, values: &Values) -> Result<Box<dyn Baker>> {
        Ok(Box::new(FivBaker { settings: bake_settings(values)? }))
    }

    fn load(&self, artifact: Option<&Artifact>, scene: &Scene, values: &Values) -> Result<Box<dyn Loaded>> {
        let artifact = artifact.ok_or_else(|| anyhow::anyhow!("fiv renders from a bake: give --bake"))?;
        let types = types(scene)?;
        let bake = bake_fiv::read(artifact, scene, &representatives(scene, &types))?;
        Ok(Box::new(Baked { occluders: bake_fiv::occluders(scene, &types), scene: scene.clone(), bake, options: sum_options(values) }))
    }
}
