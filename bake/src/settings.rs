//! The lighting settings a scene carries, in one place: the glTF scene's
//! `extras.relume` block (documented in docs/FORMATS.md). Every key is optional; a scene
//! without the block gets [`LightingSettings::defaults_for`], sized from its bounds.
//! The command line overrides any of them.
//!
//! ```json
//! "scenes": [{ "nodes": [0, 1], "extras": { "relume": {
//!     "ambient": [0.0, 0.0, 0.0], "beta": 0.3, "texel_density": 64.0,
//!     "obscurance": { "tau": 0.1, "l_max": 0.3 },
//!     "light_path_maps": { "region": { "box": [[-1, 2, -1], [1, 2.5, 1]], "test_points": 64 },
//!                          "light_area": 0.01 } } } }]
//! ```

use glam::Vec3;
use serde_json::{Map, Value};

/// The parameters of the obscurance illumination model (Iones et al., "Fast realistic
/// lighting for video games", eq. (2), (5)-(8)) and of the lightmap atlas they are stored in.
#[derive(Clone, Debug, PartialEq)]
pub struct LightingSettings {
    /// I_A of eq. (5): the ambient irradiance (lux) an unoccluded surface receives.
    pub ambient: Vec3,
    /// beta of eq. (7): the share of every light's unshadowed, cosine-free irradiance that
    /// comes back as indirect light, 0 <= beta < 1.
    pub beta: f32,
    /// Lightmap texels per metre in the chart's mapping space (001 §3's patch grid).
    pub texel_density: f32,
    /// tau of eq. (2), metres: rho(L) = 1 - exp(-L / tau).
    pub tau: f32,
    /// L_max of §4.4, metres: rho is 1 from this distance on. Also the small-scale threshold
    /// of the light path maps (000 §3.2.2), so no path is counted twice.
    pub l_max: f32,
    /// Where lights may move (000 §3.2.1's test points); None: the scene's point and spot
    /// lights where they stand.
    pub light_region: Option<LightRegion>,
    /// Delta-l of 000 §3.4, square metres: the area of the lights moving in the region.
    pub light_area: f32,
}

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

impl LightingSettings {
    /// Settings for a scene that states none: no ambient, beta 0.3, L_max a tenth of the
    /// bounding-box diagonal, tau a third of L_max (so rho(L_max) = 0.95 and the cut at L_max
    /// is small), and 256 texels along the diagonal.
    pub fn defaults_for(bounds: (Vec3, Vec3)) -> Self {
        let diagonal = (bounds.1 - bounds.0).length().max(1e-3);
        let l_max = 0.1 * diagonal;
        LightingSettings {
            ambient: Vec3::ZERO,
            beta: 0.3,
            texel_density: 256.0 / diagonal,
            tau: l_max / 3.0,
            l_max,
            light_region: None,
            light_area: 0.0,
        }
    }

    /// Refuses values the model has no meaning for, naming the setting and what is allowed.
    pub fn validate(&self) -> Result<(), String> {
        let checks = [
            (self.ambient.is_finite() && self.ambient.min_element() >= 0.0, "ambient must be three finite values >= 0 (lux)"),
            (self.beta.is_finite() && (0.0..1.0).contains(&self.beta), "beta must be in [0, 1)"),
            (self.texel_density.is_finite() && self.texel_density > 0.0, "texel_density must be finite and > 0 (texels per metre)"),
            (self.tau.is_finite() && self.tau > 0.0, "obscurance tau must be finite and > 0 (metres)"),
            (self.l_max.is_finite() && self.l_max > 0.0, "obscurance l_max must be finite and > 0 (metres)"),
            (self.light_area.is_finite() && self.light_area >= 0.0, "light_path_maps.light_area must be finite and >= 0 (square metres)"),
        ];
        first_failed_check(&checks)?;
        self.light_region.as_ref().map_or(Ok(()), LightRegion::validate)
    }

    /// Reads a scene's `extras` value over `defaults`; `Ok(defaults)` when it has no `relume`
    /// key. The error names the key and what it should be.
    pub fn from_extras(extras: &Value, defaults: LightingSettings) -> Result<Self, String> {
        let Some(block) = extras.get("relume") else { return Ok(defaults) };
        let block = as_object(block, "extras.relume")?;
        known_keys(block, "extras.relume", &["ambient", "beta", "texel_density", "obscurance", "light_path_maps"])?;
        let mut s = defaults;
        if let Some(v) = block.get("ambient") {
            s.ambient = vec3(v, "extras.relume.ambient")?;
        }
        if let Some(v) = block.get("beta") {
            s.beta = number(v, "extras.relume.beta")?;
        }
        if let Some(v) = block.get("texel_density") {
            s.texel_density = number(v, "extras.relume.texel_density")?;
        }
        if let Some(o) = block.get("obscurance") {
            let o = as_object(o, "extras.relume.obscurance")?;
            known_keys(o, "extras.relume.obscurance", &["tau", "l_max"])?;
            if let Some(v) = o.get("tau") {
                s.tau = number(v, "extras.relume.obscurance.tau")?;
            }
            if let Some(v) = o.get("l_max") {
                s.l_max = number(v, "extras.relume.obscurance.l_max")?;
            }
        }
        if let Some(l) = block.get("light_path_maps") {
            read_light_path_maps(as_object(l, "extras.relume.light_path_maps")?, &mut s)?;
        }
        s.validate().map_err(|e| format!("extras.relume: {e}"))?;
        Ok(s)
    }
}

fn read_light_path_maps(block: &Map<String, Value>, s: &mut LightingSettings) -> Result<(), String> {
    let key = "extras.relume.light_path_maps";
    known_keys(block, key, &["region", "light_area"])?;
    if let Some(v) = block.get("light_area") {
        s.light_area = number(v, &format!("{key}.light_area"))?;
    }
    if let Some(r) = block.get("region") {
        let r = as_object(r, &format!("{key}.region"))?;
        known_keys(r, &format!("{key}.region"), &["box", "test_points", "points"])?;
        s.light_region = Some(match (r.get("box"), r.get("points")) {
            (Some(b), None) => {
                let corners = b
                    .as_array()
                    .filter(|a| a.len() == 2)
                    .ok_or_else(|| format!("{key}.region.box must be [[min x, y, z], [max x, y, z]]"))?;
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
            (None, Some(p)) => {
                let points = p.as_array().ok_or_else(|| format!("{key}.region.points must be an array of [x, y, z]"))?;
                LightRegion::Points(points.iter().map(|q| vec3(q, &format!("{key}.region.points[]"))).collect::<Result<_, _>>()?)
            }
            _ => return Err(format!("{key}.region needs exactly one of \"box\" (with \"test_points\") or \"points\"")),
        });
    }
    Ok(())
}

/// The message of the first check that fails, or Ok: every `validate` of relume's settings.
pub fn first_failed_check(checks: &[(bool, &str)]) -> Result<(), String> {
    match checks.iter().find(|(ok, _)| !ok) {
        Some((_, message)) => Err(message.to_string()),
        None => Ok(()),
    }
}

fn as_object<'v>(value: &'v Value, key: &str) -> Result<&'v Map<String, Value>, String> {
    value.as_object().ok_or_else(|| format!("{key} must be a JSON object"))
}

fn known_keys(object: &Map<String, Value>, key: &str, known: &[&str]) -> Result<(), String> {
    match object.keys().find(|k| !known.contains(&k.as_str())) {
        Some(unknown) => Err(format!("{key}.{unknown} is not a relume setting (known: {})", known.join(", "))),
        None => Ok(()),
    }
}

fn number(value: &Value, key: &str) -> Result<f32, String> {
    value.as_f64().map(|x| x as f32).ok_or_else(|| format!("{key} must be a number"))
}

fn vec3(value: &Value, key: &str) -> Result<Vec3, String> {
    match value.as_array().map(|a| a.as_slice()) {
        Some([x, y, z]) => Ok(Vec3::new(number(x, key)?, number(y, key)?, number(z, key)?)),
        _ => Err(format!("{key} must be an array of three numbers")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn defaults() -> LightingSettings {
        LightingSettings::defaults_for((Vec3::ZERO, Vec3::ONE))
    }

    #[test]
    fn missing_block_keeps_defaults_and_keys_override() {
        assert_eq!(LightingSettings::from_extras(&json!({}), defaults()), Ok(defaults()));
        let s = LightingSettings::from_extras(&json!({"relume": {"beta": 0.5, "obscurance": {"l_max": 2.0}}}), defaults()).unwrap();
        assert_eq!((s.beta, s.l_max, s.tau), (0.5, 2.0, defaults().tau));
        let s = LightingSettings::from_extras(
            &json!({"relume": {"light_path_maps": {"region": {"points": [[0, 1, 2]]}, "light_area": 0.5}}}),
            defaults(),
        )
        .unwrap();
        assert_eq!((s.light_region, s.light_area), (Some(LightRegion::Points(vec![Vec3::new(0.0, 1.0, 2.0)])), 0.5));
    }

    #[test]
    fn refuses_unknown_keys_wrong_types_and_impossible_values() {
        let cases = [
            (json!({"relume": {"betta": 0.5}}), "betta"),
            (json!({"relume": {"ambient": [1, 2]}}), "ambient"),
            (json!({"relume": {"beta": 1.5}}), "beta"),
            (json!({"relume": {"obscurance": {"tau": -1}}}), "tau"),
            (json!({"relume": 3}), "object"),
            (json!({"relume": {"light_path_maps": {"region": {"box": [[1, 0, 0], [0, 1, 1]]}}}}), "min <= max"),
            (json!({"relume": {"light_path_maps": {"region": {"box": [[0, 0, 0], [1, 1, 1]], "test_points": 0}}}}), "test_points"),
            (json!({"relume": {"light_path_maps": {"region": {}}}}), "exactly one"),
            (json!({"relume": {"light_path_maps": {"light_area": -1}}}), "light_area"),
        ];
        for (extras, expected) in cases {
            let error = LightingSettings::from_extras(&extras, defaults()).unwrap_err();
            assert!(error.contains(expected), "{extras}: {error}");
        }
    }
}
