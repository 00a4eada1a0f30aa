//! The lighting settings a scene carries, in one place: the glTF scene's
//! `extras.relume` block (documented in docs/FORMATS.md). Every key is optional; a scene
//! without the block gets [`LightingSettings::defaults_for`], sized from its bounds.
//! The command line overrides any of them.
//!
//! ```json
//! "scenes": [{ "nodes": [0, 1], "extras": { "relume": {
//!     "ambient": [0.0, 0.0, 0.0], "beta": 0.3, "texel_density": 64.0,
//!     "obscurance": { "tau": 0.1, "l_max": 0.3 } } } }]
//! ```

use glam::Vec3;
use serde_json::{Map, Value};

/// The parameters of the obscurance illumination model (Iones et al., "Fast realistic
/// lighting for video games", eq. (2), (5)-(8)) and of the lightmap atlas they are stored in.
#[derive(Clone, Copy, Debug, PartialEq)]
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
    /// L_max of §4.4, metres: rho is 1 from this distance on.
    pub l_max: f32,
}

impl LightingSettings {
    /// Settings for a scene that states none: no ambient, beta 0.3, L_max a tenth of the
    /// bounding-box diagonal, tau a third of L_max (so rho(L_max) = 0.95 and the cut at L_max
    /// is small), and 256 texels along the diagonal.
    pub fn defaults_for(bounds: (Vec3, Vec3)) -> Self {
        let diagonal = (bounds.1 - bounds.0).length().max(1e-3);
        let l_max = 0.1 * diagonal;
        LightingSettings { ambient: Vec3::ZERO, beta: 0.3, texel_density: 256.0 / diagonal, tau: l_max / 3.0, l_max }
    }

    /// Refuses values the model has no meaning for, naming the setting and what is allowed.
    pub fn validate(&self) -> Result<(), String> {
        let checks = [
            (self.ambient.is_finite() && self.ambient.min_element() >= 0.0, "ambient must be three finite values >= 0 (lux)"),
            (self.beta.is_finite() && (0.0..1.0).contains(&self.beta), "beta must be in [0, 1)"),
            (self.texel_density.is_finite() && self.texel_density > 0.0, "texel_density must be finite and > 0 (texels per metre)"),
            (self.tau.is_finite() && self.tau > 0.0, "obscurance tau must be finite and > 0 (metres)"),
            (self.l_max.is_finite() && self.l_max > 0.0, "obscurance l_max must be finite and > 0 (metres)"),
        ];
        match checks.iter().find(|(ok, _)| !ok) {
            Some((_, message)) => Err(message.to_string()),
            None => Ok(()),
        }
    }

    /// Reads a scene's `extras` value over `defaults`; `Ok(defaults)` when it has no `relume`
    /// key. The error names the key and what it should be.
    pub fn from_extras(extras: &Value, defaults: LightingSettings) -> Result<Self, String> {
        let Some(block) = extras.get("relume") else { return Ok(defaults) };
        let block = as_object(block, "extras.relume")?;
        known_keys(block, "extras.relume", &["ambient", "beta", "texel_density", "obscurance"])?;
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
        s.validate().map_err(|e| format!("extras.relume: {e}"))?;
        Ok(s)
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
        let s = LightingSettings::from_extras(
            &json!({"relume": {"beta": 0.5, "obscurance": {"l_max": 2.0}}}),
            defaults(),
        )
        .unwrap();
        assert_eq!((s.beta, s.l_max, s.tau), (0.5, 2.0, defaults().tau));
    }

    #[test]
    fn refuses_unknown_keys_wrong_types_and_impossible_values() {
        let cases = [
            (json!({"relume": {"betta": 0.5}}), "betta"),
            (json!({"relume": {"ambient": [1, 2]}}), "ambient"),
            (json!({"relume": {"beta": 1.5}}), "beta"),
            (json!({"relume": {"obscurance": {"tau": -1}}}), "tau"),
            (json!({"relume": 3}), "object"),
        ];
        for (extras, expected) in cases {
            let error = LightingSettings::from_extras(&extras, defaults()).unwrap_err();
            assert!(error.contains(expected), "{extras}: {error}");
        }
    }
}
