//! The settings a scene carries, in one place: the glTF scene's `extras.relume` block
//! (documented in docs/FORMATS.md). Its top-level keys are what every method may read (the
//! ambient light and the atlas's texel density); each method reads its own block under its
//! key, checked when the scene loads by the [`SceneBlock`] the method registers in `crate::methods`.
//! Every key is optional; a scene without the block gets [`SceneSettings::defaults_for`],
//! sized from its bounds. The command line overrides any of them.
//!
//! ```json
//! "scenes": [{ "nodes": [0, 1], "extras": { "relume": {
//!     "ambient": [0.0, 0.0, 0.0], "beta": 0.3, "texel_density": 64.0,
//!     "environment": { "image": "envs/sky.exr", "intensity": 1.0, "cube_face": 32 },
//!     "<a method's key>": { ... } } } }]
//! ```

use crate::environment::EnvironmentSettings;
use glam::Vec3;
use serde_json::{Map, Value};

/// The top-level settings (the ambient light of Iones et al., "Fast realistic lighting for
/// video games" (001), eq. (5)-(7), which the lighting pass adds for every method; and the
/// lightmap atlas's density), and every method's block as given.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSettings {
    /// I_A of eq. (5): the ambient irradiance (lux) an unoccluded surface receives.
    pub ambient: Vec3,
    /// beta of eq. (7): the share of every light's unshadowed, cosine-free irradiance that
    /// comes back as indirect light, 0 <= beta < 1.
    pub beta: f32,
    /// Lightmap texels per metre in the chart's mapping space (001 §3's patch grid).
    pub texel_density: f32,
    /// The methods' blocks by key, checked at load; each method parses its own.
    pub blocks: Map<String, Value>,
    /// The scene's bounds, which size the defaults of the methods' settings.
    pub bounds: (Vec3, Vec3),
    /// The distant environment light, if the scene declares one.
    pub environment: Option<EnvironmentSettings>,
}

const SHARED_KEYS: [&str; 4] = ["ambient", "beta", "texel_density", "environment"];

/// A method's block of scene settings.
#[derive(Clone, Copy)]
pub struct SceneBlock {
    /// The key under `extras.relume`.
    pub key: &'static str,
    /// Checks the block of a scene with the given bounds, naming what is wrong.
    pub check: fn(&Value, (Vec3, Vec3)) -> Result<(), String>,
}

impl SceneSettings {
    /// Settings for a scene that states none: no ambient, beta 0.3, 256 texels along the
    /// bounding-box diagonal, and no method block (each method's defaults).
    pub fn defaults_for(bounds: (Vec3, Vec3)) -> Self {
        SceneSettings {
            ambient: Vec3::ZERO,
            beta: 0.3,
            texel_density: 256.0 / diagonal(bounds),
            blocks: Map::new(),
            bounds,
            environment: None,
        }
    }

    /// Refuses values the model has no meaning for, naming the setting and what is allowed.
    pub fn validate(&self) -> Result<(), String> {
        let checks = [
            (
                self.ambient.is_finite() && self.ambient.min_element() >= 0.0 && self.ambient.max_element() <= crate::scene::MAX_LIGHT,
                "ambient must be three values in 0..=1e9 (lux)",
            ),
            (self.beta.is_finite() && (0.0..1.0).contains(&self.beta), "beta must be in [0, 1)"),
            (self.texel_density.is_finite() && self.texel_density > 0.0, "texel_density must be finite and > 0 (texels per metre)"),
        ];
        first_failed_check(&checks)
    }

    /// Reads a scene's `extras` value over `defaults`; `Ok(defaults)` when it has no `relume`
    /// key. Every method block present is checked by its method's reader. The error names the
    /// key and what it should be. `methods` are the blocks a scene may carry (the registry's
    /// `crate::methods::SCENE_BLOCKS`).
    pub fn from_extras(extras: &Value, defaults: SceneSettings, methods: &[SceneBlock]) -> Result<Self, String> {
        let Some(block) = extras.get("relume") else { return Ok(defaults) };
        let block = as_object(block, "extras.relume")?;
        let method_keys: Vec<&str> = methods.iter().map(|b| b.key).collect();
        known_keys(block, "extras.relume", &[&SHARED_KEYS[..], &method_keys[..]].concat())?;
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
        if let Some(v) = block.get("environment") {
            s.environment = Some(EnvironmentSettings::from_json(v)?);
        }
        s.validate().map_err(|e| format!("extras.relume: {e}"))?;
        for method in methods {
            if let Some(v) = block.get(method.key) {
                (method.check)(v, s.bounds)?;
                s.blocks.insert(method.key.to_string(), v.clone());
            }
        }
        Ok(s)
    }

    /// The block a method reads, if the scene gives one.
    pub fn block(&self, key: &str) -> Option<&Value> {
        self.blocks.get(key)
    }
}

/// The length of the bounds' diagonal, at least a millimetre.
pub fn diagonal(bounds: (Vec3, Vec3)) -> f32 {
    (bounds.1 - bounds.0).length().max(1e-3)
}

/// The values a setting accepts: the one definition its `validate` checks and the command
/// line's parameter registry shows and enforces, so that the two never disagree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ValueRange {
    /// Whole numbers in `min..=max` that are multiples of `step`.
    Count { min: u64, max: u64, step: u64 },
    /// Finite numbers from `min` to `max`, each end left out when open.
    Number { min: f64, max: f64, min_open: bool, max_open: bool },
}

impl ValueRange {
    /// Whole numbers in `min..=max`.
    pub const fn count(min: u64, max: u64) -> ValueRange {
        ValueRange::Count { min, max, step: 1 }
    }

    /// Even numbers in `min..=max`.
    pub const fn even(min: u64, max: u64) -> ValueRange {
        ValueRange::Count { min, max, step: 2 }
    }

    /// Finite numbers in `min..=max`, above `min` when `min_open`.
    pub const fn number(min: f64, max: f64, min_open: bool) -> ValueRange {
        ValueRange::Number { min, max, min_open, max_open: false }
    }

    /// Finite numbers strictly between `min` and `max`.
    pub const fn between(min: f64, max: f64) -> ValueRange {
        ValueRange::Number { min, max, min_open: true, max_open: true }
    }

    pub fn admits_count(&self, v: u64) -> bool {
        match *self {
            ValueRange::Count { min, max, step } => (min..=max).contains(&v) && v.is_multiple_of(step),
            ValueRange::Number { .. } => self.admits(v as f64),
        }
    }

    pub fn admits(&self, v: f64) -> bool {
        match *self {
            ValueRange::Count { .. } => v.fract() == 0.0 && v >= 0.0 && self.admits_count(v as u64),
            ValueRange::Number { min, max, min_open, max_open } => {
                v.is_finite() && if min_open { v > min } else { v >= min } && if max_open { v < max } else { v <= max }
            }
        }
    }

    /// As `--help`, `relume methods` and the refusals show it: `1..=64`, `8..=1024, even`,
    /// `>0..=1000`, `>0..<90`.
    pub fn text(&self) -> String {
        match *self {
            ValueRange::Count { min, max, step: 1 } => format!("{min}..={max}"),
            ValueRange::Count { min, max, step: 2 } => format!("{min}..={max}, even"),
            ValueRange::Count { min, max, step } => format!("{min}..={max}, a multiple of {step}"),
            ValueRange::Number { min, max, min_open, max_open } => {
                let upper = if max.is_finite() { format!("{max}") } else { "inf".into() };
                format!("{}{min}..{}{upper}", if min_open { ">" } else { "" }, if max_open { "<" } else { "=" })
            }
        }
    }
}

/// The message of the first check that fails, or Ok: every `validate` of relume's settings.
pub fn first_failed_check(checks: &[(bool, &str)]) -> Result<(), String> {
    match checks.iter().find(|(ok, _)| !ok) {
        Some((_, message)) => Err(message.to_string()),
        None => Ok(()),
    }
}

pub fn as_object<'v>(value: &'v Value, key: &str) -> Result<&'v Map<String, Value>, String> {
    value.as_object().ok_or_else(|| format!("{key} must be a JSON object"))
}

/// Refuses a key of `object` (at `key`) that is not one of `known`.
pub fn known_keys(object: &Map<String, Value>, key: &str, known: &[&str]) -> Result<(), String> {
    match object.keys().find(|k| !known.contains(&k.as_str())) {
        Some(unknown) => Err(format!("{key}.{unknown} is not a relume setting (known: {})", known.join(", "))),
        None => Ok(()),
    }
}

pub fn number(value: &Value, key: &str) -> Result<f32, String> {
    value.as_f64().map(|x| x as f32).ok_or_else(|| format!("{key} must be a number"))
}

pub fn vec3(value: &Value, key: &str) -> Result<Vec3, String> {
    match value.as_array().map(|a| a.as_slice()) {
        Some([x, y, z]) => Ok(Vec3::new(number(x, key)?, number(y, key)?, number(z, key)?)),
        _ => Err(format!("{key} must be an array of three numbers")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::SCENE_BLOCKS;
    use serde_json::json;

    fn defaults() -> SceneSettings {
        SceneSettings::defaults_for((Vec3::ZERO, Vec3::ONE))
    }

    #[test]
    fn missing_block_keeps_defaults_and_keys_override() {
        assert_eq!(SceneSettings::from_extras(&json!({}), defaults(), &SCENE_BLOCKS), Ok(defaults()));
        let s =
            SceneSettings::from_extras(&json!({"relume": {"beta": 0.5, "obscurance": {"l_max": 2.0}}}), defaults(), &SCENE_BLOCKS).unwrap();
        assert_eq!(s.beta, 0.5);
        assert_eq!(s.block("obscurance"), Some(&json!({"l_max": 2.0})));
    }

    /// What a range admits is what its text says, ends open or closed, steps kept.
    #[test]
    fn a_value_range_admits_what_its_text_says() {
        let angle = ValueRange::between(0.0, 90.0);
        assert_eq!(angle.text(), ">0..<90");
        assert!(angle.admits(89.9) && angle.admits(1e-6) && !angle.admits(90.0) && !angle.admits(0.0) && !angle.admits(f64::NAN));
        let width = ValueRange::even(8, 1024);
        assert_eq!(width.text(), "8..=1024, even");
        assert!(width.admits_count(8) && width.admits_count(1024) && !width.admits_count(9) && !width.admits_count(1026));
        assert!(width.admits(10.0) && !width.admits(10.5) && !width.admits(-2.0));
        let distance = ValueRange::number(0.0, 1e6, true);
        assert_eq!(distance.text(), ">0..=1000000");
        assert!(distance.admits(1e6) && !distance.admits(1e6 + 1.0) && !distance.admits(f64::INFINITY));
        assert_eq!(ValueRange::count(1, 64).text(), "1..=64");
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
            (json!({"relume": {"light_path_maps": {"region": {"points": [[0, 0, 0]], "test_points": 8}}}}), "goes with a"),
            (json!({"relume": {"environment": {}}}), "environment.image"),
            (json!({"relume": {"environment": {"image": "a.exr", "cube_face": 4}}}), "cube_face"),
            (json!({"relume": {"environment": {"image": "a.exr", "cube_face": 4096}}}), "cube_face"),
            (json!({"relume": {"environment": {"image": "a.exr", "intensity": -1}}}), "intensity"),
            (json!({"relume": {"environment": {"image": "a.exr", "layer": 3}}}), "layer"),
            (json!({"relume": {"environment": {"image": "a.exr", "sun": 3}}}), "environment.sun"),
        ];
        for (extras, expected) in cases {
            let error = SceneSettings::from_extras(&extras, defaults(), &SCENE_BLOCKS).unwrap_err();
            assert!(error.contains(expected), "{extras}: {error}");
        }
    }
}
