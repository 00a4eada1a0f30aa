//! A sweep file (TOML, documented in docs/BENCH.md): scenes, each with the light
//! configurations to measure (the scene's own lights, or one light moved along a path of K
//! frames), times methods, each with its parameter sets.

use anyhow::{bail, Result};
use glam::Vec3;
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct Sweep {
    pub name: String,
    #[serde(default = "default_size")]
    pub width: u32,
    #[serde(default = "default_size")]
    pub height: u32,
    /// Samples per pixel of the reference path tracer.
    #[serde(default = "default_spp")]
    pub reference_spp: u32,
    /// Trace each scene's first light configuration again with the next seed, and report the
    /// references' own noise (docs/BENCH.md, the sweep keys).
    #[serde(default)]
    pub reference_noise: bool,
    /// The references' noise (an image NRMSE) to reach: a scene's references get the samples,
    /// from reference_spp by doublings up to reference_max_spp (required with it), that should
    /// bring its measured noise under this. Measures the noise (as reference_noise).
    pub reference_noise_target: Option<f64>,
    /// The most samples per pixel reference_noise_target may give a reference.
    pub reference_max_spp: Option<u32>,
    /// Timed frames per point.
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// Untimed frames run for at least this long before a point's timed ones (at least 3).
    #[serde(default = "default_warmup")]
    pub warmup_seconds: f64,
    pub scenes: Vec<SweepScene>,
    pub methods: Vec<SweepMethod>,
    /// Charts of one method beyond the standard ones, per scene.
    #[serde(default)]
    pub charts: Vec<SweepChart>,
}

/// One method's configurations drawn on their own: mean indirect NRMSE against one of its
/// parameters (`x`; those configurations that give it, a line per set of their other
/// parameters), or a bake statistic (`statistic`: an object of number arrays in the bake's
/// stats.json, each array a line against its index from 1).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct SweepChart {
    pub method: String,
    pub x: Option<String>,
    pub statistic: Option<String>,
}

fn default_size() -> u32 {
    128
}

fn default_spp() -> u32 {
    256
}

fn default_frames() -> u32 {
    20
}

fn default_warmup() -> f64 {
    crate::gpu::WARM_UP_SECONDS
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct SweepScene {
    /// glTF file, relative to the sweep file's folder.
    pub path: PathBuf,
    /// The scene's name in the outputs; default the file's stem. Each must be unique.
    pub name: Option<String>,
    /// `--camera` syntax; default the scene's camera.
    pub camera: Option<String>,
    /// A lat-long EXR lighting the scene instead of its own environment (`--environment`),
    /// relative to the sweep file's folder.
    pub environment: Option<PathBuf>,
    /// A lights file lighting the scene instead of its own lights (`--lights`), relative to
    /// the sweep file's folder.
    pub lights: Option<PathBuf>,
    /// Move one light along a path; without it the scene's lights as they are.
    pub light_path: Option<LightPath>,
    /// Or move one mesh (an occluder) along a path of translations; the bakes stay as made.
    pub occluder_path: Option<OccluderPath>,
    /// Or change one spot light's cone or aim, one configuration a value.
    pub spot_sweep: Option<SpotSweep>,
    /// Method settings (keys) of the scene's `extras.relume` to leave out: the methods derive
    /// them from the scene instead, as on a scene without them.
    #[serde(default)]
    pub without: Vec<String>,
}

/// One spot light's cone or aim changed from configuration to configuration, where it stands.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct SpotSweep {
    /// Index of the scene's spot light (default 0), or for `targets` its directional light.
    #[serde(default)]
    pub light: usize,
    /// Outer cone angles, degrees (0, 90]: one configuration each, the inner angle
    /// `softness_degrees` less (at least 0).
    #[serde(default)]
    pub outer_degrees: Vec<f32>,
    #[serde(default = "default_softness")]
    pub softness_degrees: f32,
    /// Or points to aim the spot at, one configuration each, its cone as it is.
    #[serde(default)]
    pub targets: Vec<[f32; 3]>,
}

fn default_softness() -> f32 {
    10.0
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct LightPath {
    /// Index of the scene's light that moves (default 0).
    #[serde(default)]
    pub light: usize,
    /// The path's corners in metres; the light visits `frames` positions spread evenly by
    /// length along it, both ends included.
    pub points: Vec<[f32; 3]>,
    pub frames: u32,
    /// Seconds the light takes from one position to the next, moved in steps of 1/60 s
    /// (`Renderer::move_lights`: what eases over time, a fade, sees the motion); without, each
    /// position is a cut.
    #[serde(default)]
    pub seconds: Option<f32>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct OccluderPath {
    /// The mesh's name, as the scene names it.
    pub mesh: String,
    /// Translations from where the scene has the mesh, metres; `frames` of them are spread
    /// evenly by length along the polyline, both ends included.
    pub points: Vec<[f32; 3]>,
    pub frames: u32,
    /// Degrees the mesh turns about the vertical axis through its bounds' centre over the
    /// frames, spread evenly (0: it only translates).
    #[serde(default)]
    pub turn_degrees: f32,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct SweepMethod {
    pub method: String,
    /// One table per parameter set (an empty list means one set of defaults).
    #[serde(default)]
    pub params: Vec<toml::Table>,
}

impl SweepScene {
    /// The name rows, pictures and charts carry: `name`, else the file's stem.
    pub fn name(&self) -> String {
        self.name.clone().unwrap_or_else(|| crate::bake::scene_name(&self.path))
    }
}

impl Sweep {
    /// Reads and checks `path`; scene paths become relative to the current folder.
    pub fn read(path: &Path) -> Result<Sweep> {
        let text = relume_bake::inputs::read_text(path).map_err(|e| anyhow::anyhow!("{}: {e}; give a sweep file", path.display()))?;
        let mut sweep: Sweep = toml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.to_string().trim()))?;
        let folder = path.parent().unwrap_or(Path::new("."));
        for scene in &mut sweep.scenes {
            scene.path = folder.join(&scene.path);
            scene.environment = scene.environment.as_ref().map(|e| folder.join(e));
            scene.lights = scene.lights.as_ref().map(|l| folder.join(l));
        }
        sweep.validate().map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        Ok(sweep)
    }

    /// Whether the references' own noise is measured (reference_noise, or a target for it).
    pub fn measures_noise(&self) -> bool {
        self.reference_noise || self.reference_noise_target.is_some()
    }

    fn validate(&self) -> Result<()> {
        if !(1..=4096).contains(&self.width) || !(1..=4096).contains(&self.height) {
            bail!("width {} height {}: use 1..=4096 pixels per side", self.width, self.height);
        }
        if !(1..=65536).contains(&self.reference_spp) {
            bail!("reference_spp {}: use 1..=65536 samples per pixel", self.reference_spp);
        }
        if let Some(target) = self.reference_noise_target {
            if !(target > 0.0 && target <= 1.0) {
                bail!("reference_noise_target {target}: give an image NRMSE in (0, 1], e.g. 0.03");
            }
            if self.reference_max_spp.is_none() {
                bail!("reference_noise_target {target}: give reference_max_spp too, the most samples per pixel it may ask for (e.g. 2048)");
            }
        }
        if let Some(max) = self.reference_max_spp {
            if self.reference_noise_target.is_none() {
                bail!("reference_max_spp {max}: it caps the samples reference_noise_target asks for; give reference_noise_target too");
            }
            if !(self.reference_spp..=65536).contains(&max) {
                bail!("reference_max_spp {max}: use reference_spp ({}) up to 65536 samples per pixel", self.reference_spp);
            }
        }
        if !(1..=10_000).contains(&self.frames) {
            bail!("frames {}: time 1..=10000 frames per point", self.frames);
        }
        if !(0.0..=600.0).contains(&self.warmup_seconds) {
            bail!("warmup_seconds {}: warm up for 0 to 600 seconds", self.warmup_seconds);
        }
        if self.scenes.is_empty() || self.methods.is_empty() {
            bail!("a sweep needs at least one [[scenes]] and one [[methods]] entry");
        }
        for (i, chart) in self.charts.iter().enumerate() {
            if chart.x.is_some() == chart.statistic.is_some() {
                bail!("charts[{i}]: give `x` (a parameter) or `statistic` (a bake statistic), one of them");
            }
            let named = |s: &Option<String>| {
                s.as_deref().is_none_or(|s| !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_".contains(c)))
            };
            if !named(&chart.x) || !named(&chart.statistic) {
                bail!("charts[{i}]: `x` and `statistic` are names of letters, digits, '-' and '_' (they name files)");
            }
            if !self.methods.iter().any(|m| m.method == chart.method) {
                bail!("charts[{i}].method \"{}\": no [[methods]] entry measures it", chart.method);
            }
        }
        for (i, scene) in self.scenes.iter().enumerate() {
            let name = scene.name();
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c)) {
                bail!("scenes[{i}].name \"{name}\": use letters, digits, '-', '_' and '.' (it names files)");
            }
            if let Some(j) = self.scenes[..i].iter().position(|other| other.name() == name) {
                bail!("scenes[{j}] and scenes[{i}] are both named \"{name}\": give each its own `name`");
            }
            if scene.light_path.as_ref().and_then(|p| p.seconds).is_some_and(|s| !(s > 0.0 && s <= 60.0)) {
                bail!("scenes[{i}].light_path.seconds must be a number of seconds in (0, 60]");
            }
            if scene.occluder_path.as_ref().is_some_and(|p| !p.turn_degrees.is_finite()) {
                bail!("scenes[{i}].occluder_path.turn_degrees must be a finite number of degrees");
            }
            let paths = [
                ("light_path", scene.light_path.as_ref().map(|p| (&p.points, p.frames))),
                ("occluder_path", scene.occluder_path.as_ref().map(|p| (&p.points, p.frames))),
            ];
            if paths.iter().filter(|(_, p)| p.is_some()).count() + usize::from(scene.spot_sweep.is_some()) > 1 {
                bail!("scenes[{i}]: give one of light_path, occluder_path and spot_sweep, not both of any two");
            }
            if let Some(spot) = &scene.spot_sweep {
                check_spot_sweep(spot).map_err(|e| anyhow::anyhow!("scenes[{i}].spot_sweep: {e}"))?;
            }
            for (key, path) in paths {
                let Some((points, frames)) = path else { continue };
                if points.is_empty() || !(1..=1000).contains(&frames) {
                    bail!("scenes[{i}].{key}: give at least one point and 1..=1000 frames");
                }
                if points.iter().flatten().any(|v| !v.is_finite()) {
                    bail!("scenes[{i}].{key}.points: every coordinate must be a finite number (metres)");
                }
            }
        }
        Ok(())
    }
}

fn check_spot_sweep(spot: &SpotSweep) -> Result<()> {
    if spot.outer_degrees.is_empty() == spot.targets.is_empty() {
        bail!("give outer_degrees (cone angles) or targets (points to aim at), one of them");
    }
    if spot.outer_degrees.len() + spot.targets.len() > 1000 {
        bail!("at most 1000 configurations");
    }
    if spot.outer_degrees.iter().any(|d| !(d.is_finite() && *d > 0.0 && *d <= 90.0)) {
        bail!("outer_degrees: each a finite angle in (0, 90] degrees");
    }
    if !(spot.softness_degrees.is_finite() && spot.softness_degrees >= 0.0) {
        bail!("softness_degrees: a finite angle >= 0");
    }
    if spot.targets.iter().flatten().any(|v| !v.is_finite()) {
        bail!("targets: every coordinate must be a finite number (metres)");
    }
    Ok(())
}

/// `frames` points evenly spread by length along the polyline through `points`, both ends
/// included.
pub(crate) fn spread(points: &[[f32; 3]], frames: u32) -> Vec<Vec3> {
    let corners: Vec<Vec3> = points.iter().map(|p| Vec3::from_array(*p)).collect();
    let lengths: Vec<f32> = corners.windows(2).map(|w| w[0].distance(w[1])).collect();
    let total: f32 = lengths.iter().sum();
    (0..frames)
        .map(|k| {
            let mut along = if frames > 1 { total * k as f32 / (frames - 1) as f32 } else { 0.0 };
            for (i, &length) in lengths.iter().enumerate() {
                if along <= length && length > 0.0 {
                    return corners[i].lerp(corners[i + 1], along / length);
                }
                along -= length;
            }
            *corners.last().unwrap()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_is_spread_evenly_by_length_with_both_ends() {
        let p = spread(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 3.0, 0.0]], 5);
        assert_eq!(p.len(), 5);
        for (got, want) in p.iter().zip([Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, 2.0, 0.0), Vec3::new(1.0, 3.0, 0.0)])
        {
            assert!(got.distance(want) < 1e-5, "{got} != {want}");
        }
    }

    #[test]
    fn files_are_relative_to_the_sweep_file() {
        let dir = std::env::temp_dir().join(format!("relume-sweep-files-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text =
            "name = 'x'\n[[scenes]]\npath = 'm/a.gltf'\nenvironment = 'e.exr'\nlights = 'l/rig.json'\n[[methods]]\nmethod = 'direct'";
        std::fs::write(dir.join("sweep.toml"), text).unwrap();
        let sweep = Sweep::read(&dir.join("sweep.toml")).unwrap();
        let scene = &sweep.scenes[0];
        assert_eq!(
            (&scene.path, scene.environment.as_ref(), scene.lights.as_ref()),
            (&dir.join("m/a.gltf"), Some(&dir.join("e.exr")), Some(&dir.join("l/rig.json")))
        );
    }

    #[test]
    fn bad_sweeps_are_refused_by_key() {
        let dir = std::env::temp_dir().join(format!("relume-sweep-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (text, expected) in [
            ("name = 'x'\nscenes = []\nmethods = []", "at least one"),
            ("name = 'x'\nwidth = 0\n[[scenes]]\npath = 'a.gltf'\n[[methods]]\nmethod = 'direct'", "width"),
            ("name = 'x'\nreference_noise_target = 0.1\n[[scenes]]\npath = 'a.gltf'\n[[methods]]\nmethod = 'direct'", "give reference_max_spp too"),
            ("name = 'x'\nreference_noise_target = 0\nreference_max_spp = 512\n[[scenes]]\npath = 'a.gltf'\n[[methods]]\nmethod = 'direct'", "reference_noise_target 0"),
            ("name = 'x'\nreference_max_spp = 512\n[[scenes]]\npath = 'a.gltf'\n[[methods]]\nmethod = 'direct'", "give reference_noise_target too"),
            ("name = 'x'\nreference_noise_target = 0.1\nreference_max_spp = 16\n[[scenes]]\npath = 'a.gltf'\n[[methods]]\nmethod = 'direct'", "use reference_spp (256)"),
            ("name = 'x'\nwarmup_seconds = -1\n[[scenes]]\npath = 'a.gltf'\n[[methods]]\nmethod = 'direct'", "warmup_seconds"),
            ("name = 'x'\n[[scenes]]\npath = 'a.gltf'\n[[scenes]]\npath = 'b/a.gltf'\ncamera = 'eye=0,1,2;target=0,0,0'\n[[methods]]\nmethod = 'direct'", "both named \"a\""),
            ("name = 'x'\n[[scenes]]\npath = 'a.gltf'\nname = 'a b'\n[[methods]]\nmethod = 'direct'", "names files"),
            ("name = 'x'\ncolour = 1\n[[scenes]]\npath = 'a.gltf'\n[[methods]]\nmethod = 'direct'", "colour"),
            ("name = 'x'\n[[scenes]]\npath = 'a.gltf'\nlight_path = { points = [], frames = 3 }\n[[methods]]\nmethod = 'direct'", "light_path"),
            ("name = 'x'\n[[scenes]]\npath = 'a.gltf'\nlight_path = { points = [[0, 1, 0]], frames = 1 }\noccluder_path = { mesh = 'Cube', points = [[0, 1, 0]], frames = 1 }\n[[methods]]\nmethod = 'direct'", "not both"),
            ("name = 'x'\n[[scenes]]\npath = 'a.gltf'\nspot_sweep = { outer_degrees = [95] }\n[[methods]]\nmethod = 'direct'", "spot_sweep: outer_degrees"),
            ("name = 'x'\n[[scenes]]\npath = 'a.gltf'\nspot_sweep = { outer_degrees = [45], targets = [[0, 0, 0]] }\n[[methods]]\nmethod = 'direct'", "one of them"),
            ("name = 'x'\n[[scenes]]\npath = 'a.gltf'\noccluder_path = { mesh = 'Cube', points = [[0, 1, 0]], frames = 2, turn_degrees = nan }\n[[methods]]\nmethod = 'direct'", "turn_degrees must be a finite"),
            ("name = 'x'\n[[scenes]]\npath = 'a.gltf'\nlight_path = { points = [[0, 1, 0]], frames = 2, seconds = 0 }\n[[methods]]\nmethod = 'direct'", "light_path.seconds must be"),
        ] {
            let path = dir.join("sweep.toml");
            std::fs::write(&path, text).unwrap();
            let error = Sweep::read(&path).unwrap_err().to_string();
            assert!(error.contains("sweep.toml") && error.contains(expected), "{expected}: {error}");
        }
    }
}
