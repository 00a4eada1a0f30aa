//! A scene's lights as a file of their own (docs/FORMATS.md, "Lights file"), so a model that
//! carries no light, or a lighting a designer placed, can be rendered, baked and benched
//! without editing the scene; and the default rig a scene without any light is given.

use crate::scene::{Camera, Light, LightKind};
use glam::Vec3;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

pub const FORMAT: &str = "relume-lights";
pub const VERSION: u32 = 1;

/// Why a lights file could not be read: the file, the item, the problem.
#[derive(Debug, thiserror::Error)]
#[error("{}: {item}: {problem}; {FIX}", path.display())]
pub struct LightsFileError {
    pub path: PathBuf,
    pub item: String,
    pub problem: String,
}

const FIX: &str = "fix the lights file (docs/FORMATS.md, \"Lights file\")";

/// The lights of the file at `path`, each checked as a glTF light is.
pub fn read(path: &Path) -> Result<Vec<Light>, LightsFileError> {
    let fail = |item: &str, problem: String| LightsFileError { path: path.to_path_buf(), item: item.to_string(), problem };
    crate::inputs::admit(path).map_err(|e| fail("the file", e))?;
    let text = std::fs::read_to_string(path).map_err(|e| fail("the file", format!("cannot be read ({e})")))?;
    let file: Value = serde_json::from_str(&text).map_err(|e| fail("the file", format!("is not valid JSON ({e})")))?;
    if file["format"] != FORMAT || file["version"] != VERSION {
        return Err(fail("the file", format!("is not a \"{FORMAT}\" file of version {VERSION}")));
    }
    let listed = file["lights"].as_array().ok_or_else(|| fail("the file", "has no list \"lights\"".into()))?;
    if listed.is_empty() {
        return Err(fail("lights", "is empty: a scene needs at least one light".into()));
    }
    listed.iter().enumerate().map(|(k, entry)| light(entry, k).map_err(|problem| fail(&format!("lights[{k}]"), problem))).collect()
}

fn light(entry: &Value, k: usize) -> Result<Light, String> {
    let vector = |key: &str| -> Result<Vec3, String> {
        let values: Option<Vec<f32>> = entry[key].as_array().map(|a| a.iter().filter_map(|v| v.as_f64().map(|v| v as f32)).collect());
        match values.as_deref() {
            Some([x, y, z]) if [x, y, z].iter().all(|v| v.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(format!("\"{key}\" must be three finite numbers")),
        }
    };
    let intensity = vector("intensity")?;
    if intensity.min_element() < 0.0 || intensity.max_element() > crate::scene::MAX_LIGHT {
        return Err(format!("intensity {intensity} is negative or exceeds 1e9 (candela, or lux for a directional light)"));
    }
    let position = || {
        let p = vector("position")?;
        (p.abs().max_element() <= crate::scene::MAX_COORDINATE)
            .then_some(p)
            .ok_or_else(|| format!("\"position\" {p} lies past 1e7 m from the origin"))
    };
    let direction = || {
        let d = vector("direction")?;
        (d.length() > 1e-6).then(|| d.normalize()).ok_or_else(|| "\"direction\" must not be zero".to_string())
    };
    let (kind, position, direction) = match entry["type"].as_str() {
        Some("point") => (LightKind::Point, position()?, Vec3::NEG_Z),
        Some("spot") => {
            let degrees = |key: &str| entry[key].as_f64().map(|d| (d as f32).to_radians()).ok_or_else(|| format!("\"{key}\" is missing"));
            let (inner_cone, outer_cone) = (degrees("inner_cone_degrees")?, degrees("outer_cone_degrees")?);
            if !(0.0 <= inner_cone && inner_cone < outer_cone && outer_cone <= std::f32::consts::FRAC_PI_2) {
                return Err("cones must satisfy 0 <= inner_cone_degrees < outer_cone_degrees <= 90".into());
            }
            (LightKind::Spot { inner_cone, outer_cone }, position()?, direction()?)
        }
        Some("directional") => (LightKind::Directional, Vec3::ZERO, direction()?),
        _ => return Err("\"type\" must be \"point\", \"spot\" or \"directional\"".into()),
    };
    let name = entry["name"].as_str().map_or_else(|| format!("light {k}"), str::to_string);
    Ok(Light { name, kind, intensity, range: None, position, direction })
}

/// The lights file of `lights` (what [`read`] reads back).
pub fn to_json(lights: &[Light]) -> String {
    let entries: Vec<Value> = lights
        .iter()
        .map(|l| {
            let mut entry = json!({ "name": l.name, "intensity": numbers(l.intensity) });
            match l.kind {
                LightKind::Point => {
                    entry["type"] = json!("point");
                    entry["position"] = numbers(l.position);
                }
                LightKind::Spot { inner_cone, outer_cone } => {
                    entry["type"] = json!("spot");
                    entry["position"] = numbers(l.position);
                    entry["direction"] = numbers(l.direction);
                    entry["inner_cone_degrees"] = number(inner_cone.to_degrees());
                    entry["outer_cone_degrees"] = number(outer_cone.to_degrees());
                }
                LightKind::Directional => {
                    entry["type"] = json!("directional");
                    entry["direction"] = numbers(l.direction);
                }
            }
            entry
        })
        .collect();
    let mut text = serde_json::to_string_pretty(&json!({ "format": FORMAT, "version": VERSION, "lights": entries })).expect("JSON");
    text.push('\n');
    text
}

/// `v` as the shortest decimal that reads back as the same f32 (not its f64 expansion).
fn number(v: f32) -> Value {
    json!(v.to_string().parse::<f64>().unwrap_or(0.0))
}

fn numbers(v: Vec3) -> Value {
    json!(v.to_array().map(number))
}

/// The rig a scene without any light is given: one white point light at the camera, a
/// headlight, of the intensity that gives a surface facing it at the scene's centre an
/// irradiance of pi lux (a white Lambertian surface there has radiance about 1). At the
/// camera, not inside the bounds: a light inside a closed model's bounding box can sit inside
/// the model, while the camera always stands where it sees what it renders.
pub fn default_rig((min, max): (Vec3, Vec3), camera: &Camera) -> Vec<Light> {
    let eye = camera.world_from_camera.w_axis.truncate();
    let distance = eye.distance((min + max) / 2.0).max((max - min).length() / 2.0).max(1e-3);
    let intensity = Vec3::splat(std::f32::consts::PI * distance * distance);
    vec![Light {
        name: "default rig: headlight".into(),
        kind: LightKind::Point,
        intensity,
        range: None,
        position: eye,
        direction: Vec3::NEG_Z,
    }]
}
