//! The flags several subcommands share, and what they turn into: the scene (with a camera and
//! an image size), the frame's settings (shadow maps, the ambient light, the device), and the
//! reference path tracer's settings.

use anyhow::{Context as _, Result};
use clap::Args;
use glam::Vec3;
use relume_bake::bvh::RayBackend;
use relume_bake::environment::{Environment, EnvironmentSettings};
use relume_bake::gltf_load::{load_with_options, CameraOverride, LightChoice, LoadOptions, DEFAULT_MAX_TEXTURE_PIXELS};
use relume_bake::lights_file;
use relume_bake::reference::ReferenceSettings;
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use relume_renderer::RenderSettings;
use std::path::{Path, PathBuf};
use std::time::Duration;

#[derive(Args, Clone)]
pub(crate) struct SceneArgs {
    /// A glTF 2.0 scene (.gltf or .glb).
    pub scene: PathBuf,
    /// Camera instead of the scene's: "eye=x,y,z;target=x,y,z[;up=x,y,z][;yfov=degrees]".
    #[arg(long, value_parser = |text: &str| CameraOverride::parse(text).map(|_| text.to_string()).map_err(|e| e.to_string()))]
    pub camera: Option<String>,
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: u32,
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: u32,
    /// Light the scene by this lat-long EXR instead of the one its extras.relume.environment
    /// names (its intensity, rotation and cube face stay); a scene that declares none is lit
    /// by it at intensity 1, no rotation, cube faces of 32 texels.
    #[arg(long)]
    pub environment: Option<PathBuf>,
    /// Let the scene read buffers, images and its environment outside its own folder (an
    /// absolute path or one up through ..); without it such a scene is refused.
    #[arg(long)]
    pub allow_outside_files: bool,
    /// The most pixels a scene's texture may have (checked before decoding; 8192 x 8192,
    /// 1 GiB decoded, by default).
    #[arg(long, default_value_t = DEFAULT_MAX_TEXTURE_PIXELS, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_texture_pixels: u64,
    /// Light the scene by this lights file (docs/FORMATS.md) instead of its own punctual
    /// lights; a scene without any light and without this gets a default rig (a headlight).
    #[arg(long)]
    pub lights: Option<PathBuf>,
}

#[derive(Args, Clone)]
pub(crate) struct GpuArgs {
    /// Shadow-map size in texels per layer.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(16..=8192))]
    pub shadow_map_size: u32,
    /// Gaussian blur radius of the shadow moments, texels (0: none).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=64))]
    pub blur_radius: u32,
    /// Floor on the variance in the Chebyshev bound (m^2).
    #[arg(long, default_value_t = 1e-5, value_parser = at_least_zero)]
    pub min_variance: f32,
    /// Light-bleeding reduction in [0, 1).
    #[arg(long, default_value_t = 0.2, value_parser = fraction)]
    pub bleeding_reduction: f32,
    /// Turn shadows off (shading only).
    #[arg(long)]
    pub no_shadows: bool,
    #[arg(long, default_value_t = 1.0, value_parser = positive::<f32>)]
    pub exposure: f32,
    /// Vulkan device: index or part of its name (default: a real GPU if any, else lavapipe;
    /// the RELUME_DEVICE variable does the same).
    #[arg(long)]
    pub device: Option<String>,
    /// Turn on the Vulkan validation layers; any message fails the command.
    #[arg(long)]
    pub validation: bool,
    /// Ambient irradiance I_A of the frame's ambient light (001 eq. 5), lux: "r,g,b" or one
    /// value (default: the method's; the scene's extras.relume.ambient where the method
    /// models ambient light).
    #[arg(long, value_parser = ambient)]
    pub ambient: Option<Vec3>,
    /// beta of the ambient light's share of every light (001 eq. 7), in [0, 1) (default: as
    /// --ambient).
    #[arg(long, value_parser = fraction)]
    pub beta: Option<f32>,
    /// Direct light only: no ambient light (ambient and beta 0).
    #[arg(long, conflicts_with_all = ["ambient", "beta"])]
    pub direct_only: bool,
}

/// `--seed`, `--threads` and `--time-limit`: what every long job takes.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct WorkArgs {
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads, 1..=1024 (default: all cores).
    #[arg(long, value_parser = threads)]
    pub threads: Option<usize>,
    /// Stop after this many seconds, at a whole pass of the work (at least one is made); a
    /// stage that needs all its work (an occluder table, a dictionary) is refused instead.
    #[arg(long, value_parser = seconds)]
    pub time_limit: Option<Duration>,
    /// Refuse, before its long work, a bake whose peak memory is estimated above this: bytes,
    /// or a number with K, M, G or T (binary units). Default: the machine's memory.
    #[arg(long, value_parser = bytes)]
    pub memory_limit: Option<u64>,
    /// Which library casts the rays: obvhs (relume's BVH, every build) or embree (Embree 3, in
    /// builds with `--features embree`).
    #[arg(long, default_value = "obvhs", value_parser = RayBackend::parse)]
    pub ray_backend: RayBackend,
}

impl WorkArgs {
    /// The command line that gives what these arguments make of the bake's bytes: the seed,
    /// the ray backend and a memory limit given (not the threads, which change no byte; a
    /// time limit a sharded bake refuses).
    pub fn argv(&self) -> Vec<String> {
        let mut argv = vec!["--seed".to_string(), self.seed.to_string(), "--ray-backend".into(), self.ray_backend.name().into()];
        argv.extend(self.memory_limit.map(|b| ["--memory-limit".to_string(), b.to_string()]).into_iter().flatten());
        argv
    }

    /// The options, refused by name when impossible; a progress bar on a terminal.
    pub fn options(&self) -> Result<WorkOptions> {
        let options = WorkOptions {
            seed: self.seed,
            threads: self.threads,
            time_limit: self.time_limit,
            progress: true,
            memory_limit: self.memory_limit.or_else(relume_bake::work::machine_memory_bytes),
            started: None,
            ray_backend: self.ray_backend,
            role: None,
        };
        options.validate().map_err(|e| anyhow::anyhow!("--threads: {e}"))?;
        Ok(options)
    }
}

#[derive(Args, Clone)]
pub(crate) struct PathTracerArgs {
    /// Samples per pixel.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    #[command(flatten)]
    pub work: WorkArgs,
    /// Sample pixel centres only (as a rasteriser does).
    #[arg(long)]
    pub pixel_centres: bool,
    #[arg(long, default_value_t = 64)]
    pub max_bounces: u32,
}

pub(crate) fn load_scene(args: &SceneArgs) -> Result<Scene> {
    Ok(load_scene_noting(args)?.0)
}

/// [`load_scene`], and the load's warnings (also printed), for showing them elsewhere.
pub(crate) fn load_scene_noting(args: &SceneArgs) -> Result<(Scene, Vec<String>)> {
    let camera = args.camera.as_deref().map(CameraOverride::parse).transpose()?;
    let options = LoadOptions {
        camera: camera.as_ref(),
        outside_files: args.allow_outside_files,
        max_texture_pixels: Some(args.max_texture_pixels),
        ..Default::default()
    };
    let (mut scene, warnings) = load_noting(&args.scene, args.lights.as_deref(), options)?;
    replace_environment(&mut scene, args.environment.as_deref())?;
    Ok((scene, warnings))
}

/// Lights `scene` by `image` instead of its own environment, when one is given
/// (`--environment`).
pub(crate) fn replace_environment(scene: &mut Scene, image: Option<&Path>) -> Result<()> {
    if let Some(image) = image {
        scene.environment = Some(replaced_environment(scene, image)?);
    }
    Ok(())
}

/// The scene's environment read from `image` instead of its own file, keeping its intensity,
/// rotation and cube face; a scene that declares none gets the block's defaults.
fn replaced_environment(scene: &Scene, image: &Path) -> Result<Environment> {
    let image = std::path::absolute(image).with_context(|| format!("--environment {}: not a usable path", image.display()))?;
    let settings = match &scene.settings.environment {
        Some(declared) => EnvironmentSettings { image: image.clone(), ..declared.clone() },
        None => {
            EnvironmentSettings::from_json(&serde_json::json!({ "image": image })).map_err(|e| anyhow::anyhow!("--environment: {e}"))?
        }
    };
    let environment = Environment::load(&settings, &scene.source)
        .map_err(|e| anyhow::anyhow!("--environment: {e}; give a lat-long RGB EXR of finite radiance >= 0"))?;
    if environment.clamped_texels > 0 {
        eprintln!("warning: --environment {}: {} texels slightly below 0 read as 0", image.display(), environment.clamped_texels);
    }
    Ok(environment)
}

/// The scene at `path`, its load warnings printed; lit by `lights_file` when given, else by
/// its own lights or, having none, the default rig.
pub(crate) fn load(path: &Path, lights_file: Option<&Path>, options: LoadOptions) -> Result<Scene> {
    Ok(load_noting(path, lights_file, options)?.0)
}

fn load_noting(path: &Path, lights_file: Option<&Path>, options: LoadOptions) -> Result<(Scene, Vec<String>)> {
    let given = lights_file.map(lights_file::read).transpose()?;
    let lights = given.as_deref().map_or(LightChoice::SceneOrDefaultRig, LightChoice::Given);
    let loaded = load_with_options(path, &LoadOptions { lights, ..options })?;
    for warning in &loaded.warnings {
        eprintln!("warning: {warning}");
    }
    Ok((loaded.scene, loaded.warnings))
}

/// The frame's settings from the flags, with a method's ambient light: `defaults` its I_A and
/// beta (None: it models no ambient light), `environment` whether it adds the scene's
/// environment to them (`Method::environment_ambient`); `--direct-only` drops all three.
pub(crate) fn render_settings(
    scene: &SceneArgs,
    gpu: &GpuArgs,
    defaults: Option<(Vec3, f32)>,
    environment: bool,
) -> Result<RenderSettings> {
    let defaults = defaults.filter(|_| !gpu.direct_only);
    let (ambient, beta) = crate::methods::frame_ambient(defaults, gpu.ambient, gpu.beta);
    let settings = RenderSettings {
        width: scene.width,
        height: scene.height,
        shadow_map_size: gpu.shadow_map_size,
        blur_radius: gpu.blur_radius,
        min_variance: gpu.min_variance,
        bleeding_reduction: gpu.bleeding_reduction,
        shadows: !gpu.no_shadows,
        exposure: gpu.exposure,
        ambient,
        beta,
        environment_ambient: environment && !gpu.direct_only,
    };
    settings.validate().map_err(|e| anyhow::anyhow!("render settings: {e}"))?;
    Ok(settings)
}

pub(crate) fn reference_settings(scene: &SceneArgs, trace: &PathTracerArgs, shadows: bool) -> Result<ReferenceSettings> {
    Ok(ReferenceSettings {
        samples_per_pixel: trace.spp,
        width: scene.width,
        height: scene.height,
        max_bounces: trace.max_bounces,
        pixel_centres: trace.pixel_centres,
        shadows,
        work: trace.work.options()?,
    })
}

// Parsers of flags with a range: a value outside it is a usage error (exit 2), as one that
// is not a number is, whatever the flag.

/// A finite number above 0.
pub(crate) fn positive<T: std::str::FromStr + Into<f64> + Copy>(text: &str) -> Result<T, String> {
    number(text, |v| v > 0.0).ok_or_else(|| "give a finite number above 0".into())
}

/// Seconds above 0 that a clock can count (not 1e20).
fn seconds(text: &str) -> Result<Duration, String> {
    let seconds: f64 = positive(text)?;
    Duration::try_from_secs_f64(seconds).map_err(|_| format!("{seconds} s is more than a clock counts; give fewer seconds"))
}

/// A size in bytes: a whole number, or a number with K, M, G or T (binary units, an optional
/// "iB" or "B"), above 0.
pub(crate) fn bytes(text: &str) -> Result<u64, String> {
    let trimmed = text.trim().trim_end_matches("iB").trim_end_matches('B');
    let (number, scale) = match trimmed.char_indices().last() {
        Some((i, unit)) if unit.is_ascii_alphabetic() => {
            let power =
                "KMGT".find(unit.to_ascii_uppercase()).ok_or_else(|| format!("\"{text}\": give bytes, or a number with K, M, G or T"))?;
            (&trimmed[..i], 1u64 << (10 * (power + 1)))
        }
        _ => (trimmed, 1),
    };
    let value: f64 = number.trim().parse().map_err(|_| format!("\"{text}\": give bytes, or a number with K, M, G or T"))?;
    let total = value * scale as f64;
    match total.is_finite() && total >= 1.0 && total < u64::MAX as f64 {
        true => Ok(total as u64),
        false => Err(format!("\"{text}\": give a size of at least one byte that a 64-bit count holds")),
    }
}

/// `--ambient`: "r,g,b" or one value for all three channels, each in 0..=1e9 lux (a light's
/// bound, `scene::MAX_LIGHT`).
fn ambient(text: &str) -> Result<Vec3, String> {
    let admitted = |v: &f32| (0.0..=relume_bake::scene::MAX_LIGHT).contains(v);
    let values: Option<Vec<f32>> = text.split(',').map(|v| v.trim().parse::<f32>().ok().filter(admitted)).collect();
    match values.as_deref() {
        Some(&[v]) => Ok(Vec3::splat(v)),
        Some(&[r, g, b]) => Ok(Vec3::new(r, g, b)),
        _ => Err("give \"r,g,b\" or one number, each in 0..=1e9 (lux)".into()),
    }
}

/// A finite number >= 0.
fn at_least_zero(text: &str) -> Result<f32, String> {
    number(text, |v| v >= 0.0).ok_or_else(|| "give a finite number >= 0".into())
}

/// A number in [0, 1).
fn fraction(text: &str) -> Result<f32, String> {
    number(text, |v| (0.0..1.0).contains(&v)).ok_or_else(|| "give a number in [0, 1)".into())
}

fn number<T: std::str::FromStr + Into<f64> + Copy>(text: &str, allowed: impl Fn(f64) -> bool) -> Option<T> {
    text.parse::<T>().ok().filter(|v| (*v).into().is_finite() && allowed((*v).into()))
}

/// Worker threads: 1..=1024 (more only slows the work and can exhaust the machine).
pub(crate) fn threads(text: &str) -> Result<usize, String> {
    text.parse::<usize>().ok().filter(|n| (1..=1024).contains(n)).ok_or_else(|| "give 1..=1024 worker threads".into())
}

/// Timed frames: at least one, at most a number that cannot exhaust memory.
pub(crate) const FRAMES: std::ops::RangeInclusive<i64> = 1..=100_000;

/// Refuses, before the work starts, a command's output (or a companion such as the PNG
/// beside an EXR) that is a file the command has read: call it after the inputs are loaded.
pub(crate) fn refuse_writing_over(outputs: &[PathBuf]) -> Result<()> {
    relume_bake::inputs::refuse_outputs(outputs.iter().map(PathBuf::as_path)).map_err(|e| anyhow::anyhow!(e))
}

/// [`refuse_writing_over`] for an EXR output `out` and the tonemapped PNG written beside it.
pub(crate) fn refuse_exr_and_png_over(out: &Path) -> Result<()> {
    refuse_writing_over(&[out.to_path_buf(), out.with_extension("png")])
        .with_context(|| format!("--out {} (an EXR and the PNG beside it)", out.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped(name: &str) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(name);
        load(&path, None, LoadOptions::default()).expect("a shipped scene loads")
    }

    /// A scene that declares no environment is lit by `--environment` at the block's defaults;
    /// one that does has its image replaced; a missing image is refused by name.
    #[test]
    fn an_environment_lights_a_scene_with_or_without_its_own() {
        let sky = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/envs/uniform.exr");
        let mut cornell = shipped("cornell.gltf");
        assert!(cornell.environment.is_none());
        replace_environment(&mut cornell, Some(&sky)).unwrap();
        assert!(cornell.environment.as_ref().is_some_and(|e| e.is_lit()), "cornell is lit by the uniform environment");
        assert_eq!(cornell.environment.as_ref().unwrap().face, 32, "the block's default cube face");
        let mut blobs = shipped("fiv-blobs.gltf");
        let own = blobs.environment.as_ref().unwrap().source.clone();
        replace_environment(&mut blobs, Some(&sky)).unwrap();
        let replaced = blobs.environment.as_ref().unwrap();
        assert!(
            replaced.source != own && replaced.source.ends_with("uniform.exr"),
            "fiv-blobs' environment is replaced: {}",
            replaced.source.display()
        );
        let missing = sky.with_file_name("missing.exr");
        let e = replace_environment(&mut shipped("cornell.gltf"), Some(&missing)).unwrap_err();
        assert!(format!("{e:#}").contains("missing.exr"), "{e:#}");
    }
}
