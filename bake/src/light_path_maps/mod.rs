//! The light path maps of Umenhoffer et al., "Partial, Multi-scale Precomputed Radiance
//! Transfer" (000): the scene's settings of them (`extras.relume.light_path_maps`: the region
//! lights may move in, the lights' area), the clustered transfer the renderer reads
//! (`transfer.rs`) and its artifact section `light-path-maps`, and, behind the `baking`
//! feature, the baker (`baker.rs`: entry points, transfers by virtual lights, clustered PCA).
//! The small-scale term, the spectral obscurance (§3.3), is the obscurance's own section.

#[cfg(feature = "baking")]
mod baker;
mod transfer;
#[cfg(feature = "baking")]
pub use baker::*;
#[cfg(feature = "baking")]
mod bake;
#[cfg(feature = "baking")]
pub use bake::*;
pub use transfer::*;

use crate::artifact::{fail, Artifact, ArtifactError, Key, PageLayout, Section, REBAKE};
use crate::binary::{Reader, Writer};
use crate::image::encode_exr_layer;
use crate::scene::Scene;
use crate::settings::{as_object, known_keys, number, vec3, SceneBlock};
use glam::Vec3;
use serde_json::{Map, Value};

/// The domain of light positions the light path maps are baked for (000 §3.2.1).
#[derive(Clone, Debug, PartialEq)]
pub enum LightRegion {
    /// An axis-aligned box sampled into `test_points` low-discrepancy points.
    Box { min: Vec3, max: Vec3, test_points: u32 },
    /// Test points placed by hand.
    Points(Vec<Vec3>),
}

impl LightRegion {
    pub fn validate(&self) -> Result<(), String> {
        match self {
            LightRegion::Box { min, max, test_points } => {
                if !(min.is_finite() && max.is_finite() && min.cmple(*max).all()) {
                    return Err(format!("light_path_maps.region.box {min} .. {max} must be finite with min <= max on every axis"));
                }
                if !(1..=65536).contains(test_points) {
                    return Err(format!("light_path_maps.region.test_points {test_points} must be 1..=65536"));
                }
            }
            LightRegion::Points(points) => {
                if points.is_empty() || points.len() > 65536 || points.iter().any(|p| !p.is_finite()) {
                    return Err("light_path_maps.region.points must hold 1..=65536 finite points".into());
                }
            }
        }
        Ok(())
    }

    /// Whether `p` lies in the region: inside the box, or within `tolerance` of a test point.
    pub fn contains(&self, p: Vec3, tolerance: f32) -> bool {
        match self {
            LightRegion::Box { min, max, .. } => p.cmpge(*min - tolerance).all() && p.cmple(*max + tolerance).all(),
            LightRegion::Points(points) => points.iter().any(|q| q.distance(p) <= tolerance),
        }
    }
}

/// The region and the lights' area, from the scene's `extras.relume.light_path_maps`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightPathMapsSceneSettings {
    /// Where lights may move (000 §3.2.1's test points); None: the scene's point and spot
    /// lights where they stand.
    pub region: Option<LightRegion>,
    /// Delta-l of 000 §3.4, square metres: the area of the lights moving in the region.
    pub light_area: f32,
}

impl LightPathMapsSceneSettings {
    /// The scene's settings (checked when it loaded); without a block, no region and 0.
    pub fn of(scene: &Scene) -> Result<Self, String> {
        from_block(scene.settings.block(KEY))
    }
}

const KEY: &str = "light_path_maps";

pub const SCENE_BLOCK: SceneBlock = SceneBlock { key: KEY, check: |block, _| from_block(Some(block)).map(|_| ()) };

fn from_block(block: Option<&Value>) -> Result<LightPathMapsSceneSettings, String> {
    let mut s = LightPathMapsSceneSettings::default();
    let Some(block) = block else { return Ok(s) };
    let key = "extras.relume.light_path_maps";
    let block = as_object(block, key)?;
    known_keys(block, key, &["region", "light_area"])?;
    if let Some(v) = block.get("light_area") {
        s.light_area = number(v, &format!("{key}.light_area"))?;
    }
    if !(s.light_area.is_finite() && s.light_area >= 0.0) {
        return Err(format!("{key}.light_area must be finite and >= 0 (square metres)"));
    }
    if let Some(r) = block.get("region") {
        let region = read_region(as_object(r, &format!("{key}.region"))?, key)?;
        region.validate().map_err(|e| format!("extras.relume.{e}"))?;
        s.region = Some(region);
    }
    Ok(s)
}

fn read_region(r: &Map<String, Value>, key: &str) -> Result<LightRegion, String> {
    known_keys(r, &format!("{key}.region"), &["box", "test_points", "points"])?;
    Ok(match (r.get("box"), r.get("points")) {
        (Some(b), None) => {
            let corners =
                b.as_array().filter(|a| a.len() == 2).ok_or_else(|| format!("{key}.region.box must be [[min x, y, z], [max x, y, z]]"))?;
            let test_points = r
                .get("test_points")
                .map_or(Some(64), Value::as_u64)
                .ok_or_else(|| format!("{key}.region.test_points must be a whole number"))?;
            LightRegion::Box {
                min: vec3(&corners[0], &format!("{key}.region.box[0]"))?,
                max: vec3(&corners[1], &format!("{key}.region.box[1]"))?,
                test_points: test_points.min(u32::MAX as u64) as u32,
            }
        }
        (None, Some(_)) if r.contains_key("test_points") => {
            return Err(format!("{key}.region.test_points goes with a \"box\"; \"points\" are the test points themselves"))
        }
        (None, Some(p)) => {
            let points = p.as_array().ok_or_else(|| format!("{key}.region.points must be an array of [x, y, z]"))?;
            LightRegion::Points(points.iter().map(|q| vec3(q, &format!("{key}.region.points[]"))).collect::<Result<_, _>>()?)
        }
        _ => return Err(format!("{key}.region needs exactly one of \"box\" (with \"test_points\") or \"points\"")),
    })
}

pub const SECTION: &str = "light-path-maps";
pub const SECTION_VERSION: u32 = 1;
const BIN: &str = "light-path-maps.bin";
const EXR: &str = "light-path-maps.exr";
const MAGIC: &[u8; 8] = b"RLTRANS\0";
const LAYER: &str = "T";

/// The section: `light-path-maps.bin` (entry points, clusters, weights) and
/// `light-path-maps.exr` (the clusters' mean and eigen-textures, each one atlas high).
pub fn section(transfer: &ClusteredTransfer, layout: PageLayout, summary: Value) -> Result<Section, String> {
    let mut w = Writer::new(MAGIC);
    w.u32s(&[transfer.entry_points.len() as u32, transfer.cluster_count() as u32, transfer.basis_count, transfer.texel_count as u32]);
    w.f32s(&[transfer.light_area]);
    w.u32s(&transfer.cluster_starts);
    for e in &transfer.entry_points {
        w.f32s(&[e.position.x, e.position.y, e.position.z, e.normal.x, e.normal.y, e.normal.z]);
    }
    w.f32s(&transfer.weights);
    let exr = encode_exr_layer(LAYER, layout.width, &transfer.textures)?;
    Ok(Section {
        name: SECTION.into(),
        version: SECTION_VERSION,
        key: Key::Scene,
        summary,
        files: vec![(BIN.into(), w.bytes), (EXR.into(), exr)],
    })
}

/// The transfer of `artifact`, read for `scene`, on the atlas of `layout`; refused when it
/// does not hang together ([`ClusteredTransfer::validate`]) or does not fit the atlas.
pub fn read(artifact: &Artifact, scene: &Scene, layout: PageLayout) -> Result<ClusteredTransfer, ArtifactError> {
    let data = artifact.section(SECTION, SECTION_VERSION, Some(scene))?;
    let (bin, path) = data.file(BIN)?;
    let mut r = Reader::new(&bin, &path, MAGIC, "light path maps")?;
    let [entries, clusters, basis_count, texel_count] =
        [r.u32("the entry-point count")?, r.u32("the cluster count")?, r.u32("D")?, r.u32("the texel count")?];
    if texel_count as usize != layout.texel_count() || entries > 1 << 24 || clusters > entries || basis_count > 1024 {
        let problem = format!(
            "{entries} entry points, {clusters} clusters, D = {basis_count}, {texel_count} texels do not fit an atlas of {} texels",
            layout.texel_count()
        );
        return Err(fail(&path, problem, REBAKE));
    }
    let light_area = r.f32s(1, "the light area")?[0];
    let cluster_starts = r.u32s(clusters as usize + 1, "the cluster starts")?;
    let entry_points = r
        .f32s(entries as usize * 6, "the entry points")?
        .chunks_exact(6)
        .map(|f| EntryPoint { position: Vec3::new(f[0], f[1], f[2]), normal: Vec3::new(f[3], f[4], f[5]) })
        .collect();
    let weights = r.f32s(entries as usize * basis_count as usize, "the weights")?;
    r.finish("the weights")?;
    let textures_per_page = clusters as u64 * (1 + basis_count as u64);
    let height = u32::try_from(layout.height as u64 * layout.pages as u64 * textures_per_page)
        .map_err(|_| fail(&path, format!("{clusters} clusters of D = {basis_count} make textures too tall for one image"), REBAKE))?;
    let (image, _) = data.exr_layer(EXR, LAYER, (layout.width, height))?;
    let transfer = ClusteredTransfer {
        entry_points,
        cluster_starts,
        basis_count,
        weights,
        texel_count: texel_count as usize,
        textures: image.pixels,
        light_area,
    };
    transfer.validate().map_err(|e| fail(&path, e, REBAKE))?;
    Ok(transfer)
}
