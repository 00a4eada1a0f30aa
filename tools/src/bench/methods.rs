//! The lighting methods a sweep can name. A method plugs into the bench by implementing
//! [`Method`] and being listed in [`METHODS`]; the harness knows nothing else about it.

use crate::Lit;
use anyhow::{bail, Context as _, Result};
use glam::Vec3;
use relume_bake::scene::Scene;
use relume_renderer::techniques::light_path_maps::Composition;
use relume_renderer::vk::Context;
use relume_renderer::{Headless, MakeTechnique, RenderSettings, Renderer};
use std::sync::Arc;

/// A parameter set's run-time part: the keys the renderer reads. Every other key of a
/// sweep's parameter table is a `relume bake` flag of the method's bake.
#[derive(Clone, Debug, Default)]
pub(crate) struct RenderParams {
    pub ambient: Option<Vec3>,
    pub beta: Option<f32>,
    pub composition: Option<Composition>,
    /// The variance shadow maps' settings, for every method (render's flags of the same names).
    pub shadow_map_size: Option<u32>,
    pub blur_radius: Option<u32>,
    pub min_variance: Option<f32>,
    pub bleeding_reduction: Option<f32>,
}

impl RenderParams {
    /// `settings` with the shadow-map keys this parameter set gives.
    pub fn apply_shadows(&self, settings: RenderSettings) -> RenderSettings {
        RenderSettings {
            shadow_map_size: self.shadow_map_size.unwrap_or(settings.shadow_map_size),
            blur_radius: self.blur_radius.unwrap_or(settings.blur_radius),
            min_variance: self.min_variance.unwrap_or(settings.min_variance),
            bleeding_reduction: self.bleeding_reduction.unwrap_or(settings.bleeding_reduction),
            ..settings
        }
    }
}

pub(crate) trait Method: Sync {
    /// The name a sweep's `method` gives.
    fn name(&self) -> &'static str;

    /// The `relume bake --method` this method renders from, if it needs a bake.
    fn bake_method(&self) -> Option<&'static str>;

    /// The frame settings for one parameter set. `base` holds the sweep's image size and the
    /// scene's ambient term (I_A, beta).
    fn settings(&self, base: &RenderSettings, params: &RenderParams) -> RenderSettings;

    /// The renderer of one parameter set; `lit` is its bake, read back (None without one).
    fn renderer(
        &self,
        ctx: &Arc<Context>,
        scene: &Scene,
        lit: Option<&Lit>,
        settings: &RenderSettings,
        params: &RenderParams,
    ) -> Result<Headless> {
        let techniques = lit.map(|lit| lit.techniques(params.composition.unwrap_or_default())).unwrap_or_default();
        let techniques: Vec<&dyn MakeTechnique> = techniques.iter().map(|t| t.as_ref()).collect();
        let scene = lit.map_or(scene, |lit| &lit.scene);
        let renderer = Renderer::new_blocking(ctx, scene, settings, &techniques).and_then(Headless::new);
        renderer.with_context(|| format!("{}: Vulkan renderer", self.name()))
    }
}

/// Direct light only (variance shadow maps), no ambient term.
struct Direct;

/// Direct light plus a constant ambient term (W = 1): Iones et al. eq. (5) without obscurance.
struct ConstantAmbient;

/// Direct light plus the obscurance ambient of Iones et al. 2003 (eq. 5-7).
struct Obscurance;

/// Umenhoffer et al. 2008: light path maps and the spectral obscurance.
struct LightPathMaps;

fn no_ambient(base: &RenderSettings) -> RenderSettings {
    RenderSettings { ambient: Vec3::ZERO, beta: 0.0, ..base.clone() }
}

fn with_ambient(base: &RenderSettings, params: &RenderParams) -> RenderSettings {
    RenderSettings { ambient: params.ambient.unwrap_or(base.ambient), beta: params.beta.unwrap_or(base.beta), ..base.clone() }
}

impl Method for Direct {
    fn name(&self) -> &'static str {
        "direct"
    }
    fn bake_method(&self) -> Option<&'static str> {
        None
    }
    fn settings(&self, base: &RenderSettings, _: &RenderParams) -> RenderSettings {
        no_ambient(base)
    }
}

impl Method for ConstantAmbient {
    fn name(&self) -> &'static str {
        "constant"
    }
    fn bake_method(&self) -> Option<&'static str> {
        None
    }
    fn settings(&self, base: &RenderSettings, params: &RenderParams) -> RenderSettings {
        with_ambient(base, params)
    }
}

impl Method for Obscurance {
    fn name(&self) -> &'static str {
        "obscurance"
    }
    fn bake_method(&self) -> Option<&'static str> {
        Some("obscurance")
    }
    fn settings(&self, base: &RenderSettings, params: &RenderParams) -> RenderSettings {
        with_ambient(base, params)
    }
}

impl Method for LightPathMaps {
    fn name(&self) -> &'static str {
        "light-path-maps"
    }
    fn bake_method(&self) -> Option<&'static str> {
        Some("light-path-maps")
    }
    fn settings(&self, base: &RenderSettings, params: &RenderParams) -> RenderSettings {
        let ambient = params.ambient.unwrap_or(Vec3::ZERO);
        RenderSettings { ambient, beta: params.beta.unwrap_or(0.0), ..base.clone() }
    }
}

/// Every method, in the order reports list them.
pub(crate) const METHODS: [&dyn Method; 4] = [&Direct, &ConstantAmbient, &Obscurance, &LightPathMaps];

pub(crate) fn find(name: &str) -> Result<&'static dyn Method> {
    METHODS.iter().copied().find(|m| m.name() == name).with_context(|| {
        format!("method \"{name}\": not a relume method; use one of {}", METHODS.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "))
    })
}

/// The parameter keys every method takes at run time.
pub(crate) const RENDER_KEYS: [&str; 7] =
    ["ambient", "beta", "composition", "shadow_map_size", "blur_radius", "min_variance", "bleeding_reduction"];

/// Splits a sweep's parameter table into the run-time keys and the bake's flags
/// (`key = value` becomes `--key value`, `key = true` becomes `--key`).
pub(crate) fn split_params(method: &dyn Method, table: &toml::Table) -> Result<(RenderParams, Vec<String>)> {
    let mut render = RenderParams::default();
    let mut flags = Vec::new();
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
            "ambient" => render.ambient = Some(Vec3::splat(number()?)),
            "beta" => render.beta = Some(number()?),
            "composition" => render.composition = Some(crate::parse_composition(value.as_str().unwrap_or_default())?),
            "shadow_map_size" => render.shadow_map_size = Some(count()?),
            "blur_radius" => render.blur_radius = Some(count()?),
            "min_variance" => render.min_variance = Some(number()?),
            "bleeding_reduction" => render.bleeding_reduction = Some(number()?),
            _ if method.bake_method().is_none() => {
                bail!("{key}: method {} has no bake; its keys are {}", method.name(), RENDER_KEYS.join(", "))
            }
            _ => match value {
                toml::Value::Boolean(true) => flags.push(format!("--{key}")),
                toml::Value::Boolean(false) => {}
                toml::Value::String(s) => flags.extend([format!("--{key}"), s.clone()]),
                other => flags.extend([format!("--{key}"), other.to_string()]),
            },
        }
    }
    Ok((render, flags))
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
    fn parameters_split_into_render_keys_and_bake_flags() {
        let table: toml::Table =
            toml::from_str("rays = 64\nuncompressed = true\nvariant = 'ao'\nbeta = 0.5\ncomposition = 'plain'").unwrap();
        let (render, flags) = split_params(find("light-path-maps").unwrap(), &table).unwrap();
        assert_eq!(render.beta, Some(0.5));
        assert_eq!(render.composition, Some(Composition::Plain));
        assert_eq!(flags, ["--rays", "64", "--uncompressed", "--variant", "ao"]);
        assert!(split_params(find("direct").unwrap(), &table).unwrap_err().to_string().contains("has no bake"));
        assert!(find("photon-mapping").err().expect("refused").to_string().contains("light-path-maps"));
    }
}
