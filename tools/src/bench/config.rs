//! A sweep's method configurations: a method of the registry with one parameter table, split
//! into the frame's keys (every method takes them: the ambient light and the shadow maps) and
//! the method's own parameters (checked by the registry's declarations).

use crate::methods::params::{Stage, Values};
use crate::methods::{self, Method};
use anyhow::{Context as _, Result};
use glam::Vec3;
use relume_bake::scene::Scene;
use relume_renderer::RenderSettings;
use std::path::Path;

/// The keys every method takes at run time: `relume render`'s flags of the same names.
pub(crate) const FRAME_KEYS: [&str; 6] = ["ambient", "beta", "shadow_map_size", "blur_radius", "min_variance", "bleeding_reduction"];

/// A parameter table's frame keys.
#[derive(Clone, Debug, Default)]
pub(crate) struct FrameParams {
    pub ambient: Option<Vec3>,
    pub beta: Option<f32>,
    pub shadow_map_size: Option<u32>,
    pub blur_radius: Option<u32>,
    pub min_variance: Option<f32>,
    pub bleeding_reduction: Option<f32>,
}

impl FrameParams {
    /// `base` (the sweep's size) with the method's ambient light for `scene` and these keys.
    pub fn settings(&self, method: &dyn Method, scene: &Scene, base: RenderSettings) -> RenderSettings {
        let (ambient, beta) = methods::frame_ambient(method.ambient(scene), self.ambient, self.beta);
        RenderSettings {
            ambient,
            beta,
            shadow_map_size: self.shadow_map_size.unwrap_or(base.shadow_map_size),
            blur_radius: self.blur_radius.unwrap_or(base.blur_radius),
            min_variance: self.min_variance.unwrap_or(base.min_variance),
            bleeding_reduction: self.bleeding_reduction.unwrap_or(base.bleeding_reduction),
            environment_ambient: method.environment_ambient(),
            ..base
        }
    }
}

/// One method with one parameter set, as the sweep gives it, checked.
pub(crate) struct Config {
    pub method: &'static dyn Method,
    pub table: toml::Table,
    pub label: String,
    pub frame: FrameParams,
    pub values: Values,
}

impl Config {
    /// What tells this configuration's bake apart from another's of the same method.
    pub fn bake_key(&self) -> String {
        format!("{} {}", self.method.name(), self.values.of_stage(&self.method.params(), Stage::Bake).join(" "))
    }
}

/// `table` for `method`: its frame keys, and every other key a parameter of the method
/// (`key = value` as `--key value`, `key = true` as `--key`), refused by name otherwise.
pub(crate) fn config(method: &'static dyn Method, table: toml::Table) -> Result<Config> {
    let label = label(&table);
    let context = || format!("method {} [{label}]", method.name());
    let (frame, pairs) = split(&table).with_context(context)?;
    let values = methods::parse_values(method, &pairs, None)
        .with_context(|| format!("{} (or one of the frame keys: {})", context(), FRAME_KEYS.join(", ")))?;
    Ok(Config { method, table, label, frame, values })
}

/// A parameter table's frame keys, and its other keys as flag pairs (`key = value` as
/// `("key", "value")`, `key = true` as `("key", "true")`, `key = false` left out).
pub(crate) fn split(table: &toml::Table) -> Result<(FrameParams, Vec<(String, String)>)> {
    let mut frame = FrameParams::default();
    let mut pairs = Vec::new();
    for (key, value) in table {
        let number = || {
            value
                .as_float()
                .or_else(|| value.as_integer().map(|i| i as f64))
                .map(|v| v as f32)
                .with_context(|| format!("{key}: give a number"))
        };
        let count = || value.as_integer().and_then(|i| u32::try_from(i).ok()).with_context(|| format!("{key}: give a whole number >= 0"));
        match key.as_str() {
            "ambient" => frame.ambient = Some(Vec3::splat(number()?)),
            "beta" => frame.beta = Some(number()?),
            "shadow_map_size" => frame.shadow_map_size = Some(count()?),
            "blur_radius" => frame.blur_radius = Some(count()?),
            "min_variance" => frame.min_variance = Some(number()?),
            "bleeding_reduction" => frame.bleeding_reduction = Some(number()?),
            _ => match value {
                toml::Value::Boolean(true) => pairs.push((key.clone(), "true".to_string())),
                toml::Value::Boolean(false) => {}
                toml::Value::String(s) => pairs.push((key.clone(), s.clone())),
                other => pairs.push((key.clone(), other.to_string())),
            },
        }
    }
    Ok((frame, pairs))
}

/// The method a bench's recommended.toml chose for the scene `name` and its parameter table,
/// refused naming the file, the scene and the fix.
pub(crate) fn recommended(file: &Path, name: &str) -> Result<(&'static dyn Method, toml::Table)> {
    let at = |what: String| anyhow::anyhow!("{}: {what}", file.display());
    let text =
        relume_bake::inputs::read_text(file).map_err(|e| at(format!("{e}; give the recommended.toml `relume bench --budget` wrote")))?;
    let table: toml::Table =
        toml::from_str(&text).map_err(|e| at(format!("not a recommended.toml ({e}); `relume bench --budget` writes one")))?;
    let Some(entry) = table.get(name).and_then(|v| v.as_table()) else {
        let scenes: Vec<&String> = table.keys().collect();
        return Err(at(format!(
            "no scene \"{name}\" (it has {scenes:?}); bench this scene with --budget, or give the scene under the name the sweep gave it"
        )));
    };
    let Some(method) = entry.get("method").and_then(|m| m.as_str()) else {
        return Err(at(format!("scene \"{name}\": no method was within the budget; bench again with a looser budget")));
    };
    let method = methods::find(method).map_err(|e| at(format!("scene \"{name}\": {e:#}")))?;
    let params = entry.get(method.name()).and_then(|e| e.get("params")).and_then(|p| p.as_table()).cloned().unwrap_or_default();
    Ok((method, params))
}

/// A parameter table as one short label: `key=value` pairs joined by spaces ("defaults" when empty).
pub(crate) fn label(table: &toml::Table) -> String {
    let pairs: Vec<String> = table.iter().map(|(k, v)| format!("{k}={}", v.to_string().trim_matches('"'))).collect();
    if pairs.is_empty() {
        "defaults".into()
    } else {
        pairs.join(" ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_split_into_frame_keys_and_the_methods_own() {
        let table: toml::Table =
            toml::from_str("rays = 64\nuncompressed = true\nvariant = 'ao'\nbeta = 0.5\ncomposition = 'plain'").unwrap();
        let method = methods::find("light-path-maps").unwrap();
        let config = config(method, table.clone()).unwrap();
        assert_eq!(config.frame.beta, Some(0.5));
        assert_eq!(config.values.of_stage(&method.params(), Stage::Render), ["composition=plain"]);
        assert_eq!(config.values.of_stage(&method.params(), Stage::Bake), ["rays=64", "uncompressed=true", "variant=ao"]);
        let refused = super::config(methods::find("direct").unwrap(), table).err().expect("direct takes no rays");
        assert!(format!("{refused:#}").contains("not a parameter of direct"), "{refused:#}");
        assert!(methods::find("photon-mapping").err().expect("refused").to_string().contains("light-path-maps"));
    }
}
