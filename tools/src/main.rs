//! `relume`: the command-line program. Each subcommand is a thin user of the libraries:
//! `bake` (scenes, reference path tracer, metrics) and `renderer` (Vulkan).

use anyhow::{bail, Context as _, Result};
use clap::{Args, Parser, Subcommand};
use glam::{Vec3, Vec4};
use relume_bake::artifact::{Baked, PageLayout};
use relume_bake::bvh::SceneBvh;
use relume_bake::clustered_transfer::ClusteredTransfer;
use relume_bake::gltf_load::{load_with_camera, CameraOverride};
use relume_bake::image::{self, Image};
use relume_bake::metrics;
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::Scene;
use relume_bake::settings::LightingSettings;
use relume_renderer::techniques::light_path_maps::{Composition, LightPathMapsData};
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::vk::{Context, ContextOptions};
use relume_renderer::{AtlasImage, FrameTimings, Headless, MakeTechnique, RenderSettings, Renderer};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

mod bake;
mod bench;
mod report;

#[derive(Parser)]
#[command(name = "relume", version, about = "Precomputed lighting, measured against a path tracer")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Precompute a method's data for a scene into a bake artifact folder.
    Bake(bake::BakeArgs),
    /// Render a scene with the Vulkan renderer (headless) to EXR and PNG.
    Render(RenderArgs),
    /// Render the ground truth with the CPU path tracer to a layered EXR (direct, indirect, combined).
    Reference(ReferenceArgs),
    /// Compare two EXR images: RMSE, NRMSE and a false-colour error image.
    Compare(CompareArgs),
    /// The main job: render a scene with Vulkan and the reference, compare, write images and a report.
    Run(RunArgs),
    /// Run a sweep (scenes x methods x parameters x lights, from a TOML file): costs and
    /// errors of every point, CSV/JSON, charts with the Pareto front, report.md.
    Bench(bench::BenchArgs),
    /// Regenerate the shipped scenes (scenes/*.gltf) from their generator.
    Scenes {
        #[arg(long, default_value = "scenes")]
        out: PathBuf,
    },
}

#[derive(Args, Clone)]
struct SceneArgs {
    /// A glTF 2.0 scene (.gltf or .glb).
    scene: PathBuf,
    /// Camera instead of the scene's: "eye=x,y,z;target=x,y,z[;up=x,y,z][;yfov=degrees]".
    #[arg(long)]
    camera: Option<String>,
    #[arg(long, default_value_t = 512)]
    width: u32,
    #[arg(long, default_value_t = 512)]
    height: u32,
}

#[derive(Args, Clone)]
struct GpuArgs {
    /// Shadow-map size in texels per layer.
    #[arg(long, default_value_t = 1024)]
    shadow_map_size: u32,
    /// Gaussian blur radius of the shadow moments, texels (0: none).
    #[arg(long, default_value_t = 2)]
    blur_radius: u32,
    /// Floor on the variance in the Chebyshev bound (m^2).
    #[arg(long, default_value_t = 1e-5)]
    min_variance: f32,
    /// Light-bleeding reduction in [0, 1).
    #[arg(long, default_value_t = 0.2)]
    bleeding_reduction: f32,
    /// Turn shadows off (shading only).
    #[arg(long)]
    no_shadows: bool,
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Vulkan device: index or part of its name (default: a real GPU if any, else lavapipe;
    /// the RELUME_DEVICE variable does the same).
    #[arg(long)]
    device: Option<String>,
    /// Turn on the Vulkan validation layers; any message fails the command.
    #[arg(long)]
    validation: bool,
    /// Ambient irradiance I_A of the obscurance model, lux: "r,g,b" or one value
    /// (default: the scene's extras.relume.ambient).
    #[arg(long)]
    ambient: Option<String>,
    /// beta of the obscurance model's indirect term, in [0, 1) (default: the scene's).
    #[arg(long)]
    beta: Option<f32>,
    /// Direct light only: no ambient term (ambient and beta 0).
    #[arg(long, conflicts_with_all = ["ambient", "beta"])]
    direct_only: bool,
    /// How a light-path-maps bake's indirect irradiance I is added (000 §3.4): "plain"
    /// (albedo/pi I), "times-obscurance" (albedo/pi W I) or "times-obscurance-with-direct"
    /// (albedo/pi W (I + E_direct)). Only with a bake that has a transfer.
    #[arg(long, value_parser = parse_composition)]
    composition: Option<Composition>,
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    /// Output EXR; a tonemapped PNG is written beside it.
    #[arg(long, short, default_value = "render.exr")]
    out: PathBuf,
    /// Render this many frames and report the median GPU time of every pass.
    #[arg(long, default_value_t = 1)]
    frames: u32,
    /// A bake artifact folder (`relume bake --out`): W from its lightmap and, from a
    /// light-path-maps bake, the indirect irradiance of its transfer (then the ambient term
    /// is off unless --ambient or --beta asks for it). Without one, W = 1 (constant ambient).
    #[arg(long)]
    bake: Option<PathBuf>,
}

#[derive(Args, Clone)]
struct PathTracerArgs {
    /// Samples per pixel.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Stop after this many seconds (at whole passes over the image).
    #[arg(long)]
    time_limit: Option<f64>,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Sample pixel centres only (as a rasteriser does).
    #[arg(long)]
    pixel_centres: bool,
    #[arg(long, default_value_t = 64)]
    max_bounces: u32,
}

#[derive(Args)]
struct ReferenceArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    trace: PathTracerArgs,
    /// Ignore visibility of punctual lights (shading only, to compare with `render --no-shadows`).
    #[arg(long)]
    no_shadows: bool,
    #[arg(long, short, default_value = "reference.exr")]
    out: PathBuf,
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
}

#[derive(Args)]
struct CompareArgs {
    /// The image under test (EXR).
    image: PathBuf,
    /// The reference (EXR).
    reference: PathBuf,
    /// Layer of the image to compare (default: its first layer).
    #[arg(long)]
    layer: Option<String>,
    /// Layer of the reference (default: "combined" when it has one, else its first layer).
    #[arg(long)]
    reference_layer: Option<String>,
    /// Write a false-colour error image (PNG) here.
    #[arg(long)]
    error_image: Option<PathBuf>,
    /// Error that maps to red in the error image, relative to the reference RMS.
    #[arg(long, default_value_t = 0.5)]
    error_scale: f32,
}

#[derive(Args)]
struct RunArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(flatten)]
    trace: PathTracerArgs,
    /// Folder for the images and report.md.
    #[arg(long, short, default_value = "out")]
    out: PathBuf,
    /// Frames to time the Vulkan renderer over.
    #[arg(long, default_value_t = 100)]
    frames: u32,
    /// Obscurance rays per texel of the bake.
    #[arg(long, default_value_t = 256)]
    rays: u32,
}

fn main() -> ExitCode {
    end_quietly_when_stdout_closes();
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::FAILURE
        }
    }
}

/// Rust ignores SIGPIPE, so `relume compare a b | head -1` would panic in `println!` once
/// `head` exits; restoring the default action ends the program quietly, as Unix tools do.
fn end_quietly_when_stdout_closes() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is a valid action.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Bake(args) => bake::bake_command(&args),
        Command::Render(args) => render_command(&args),
        Command::Reference(args) => reference_command(&args),
        Command::Compare(args) => compare_command(&args),
        Command::Run(args) => report::run_main_job(&args),
        Command::Bench(args) => bench::bench_command(&args),
        Command::Scenes { out } => {
            for path in relume_tools::scenegen::write_all(&out)? {
                println!("wrote {}", path.display());
            }
            Ok(())
        }
    }
}

fn load_scene(args: &SceneArgs) -> Result<Scene> {
    if args.width == 0 || args.height == 0 || args.width > 16384 || args.height > 16384 {
        bail!("--width {} --height {}: use 1..=16384 pixels per side", args.width, args.height);
    }
    let camera = args.camera.as_deref().map(CameraOverride::parse).transpose()?;
    let loaded = load_with_camera(&args.scene, camera.as_ref())?;
    for warning in &loaded.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(loaded.scene)
}

/// `--ambient`: "r,g,b" or one value for all three channels.
fn parse_ambient(text: &str) -> Result<Vec3> {
    let values: Vec<f32> = text
        .split(',')
        .map(|v| v.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("--ambient {text}: give \"r,g,b\" or one number (lux)"))?;
    match values[..] {
        [v] => Ok(Vec3::splat(v)),
        [r, g, b] => Ok(Vec3::new(r, g, b)),
        _ => bail!("--ambient {text}: give \"r,g,b\" or one number (lux)"),
    }
}

/// `--composition`: the kebab-case name of a [`Composition`].
pub(crate) fn parse_composition(text: &str) -> Result<Composition> {
    Composition::parse(text)
        .ok_or_else(|| anyhow::anyhow!("--composition {text}: give one of {}", Composition::ALL.map(Composition::name).join(", ")))
}

/// The frame's settings from the flags. `lighting` gives the ambient term's defaults: the
/// scene's, or none when light path maps supply the indirect light (`lpm`).
fn render_settings(scene: &SceneArgs, gpu: &GpuArgs, lighting: &LightingSettings, lpm: bool) -> Result<RenderSettings> {
    let (default_ambient, default_beta) = if lpm { (Vec3::ZERO, 0.0) } else { (lighting.ambient, lighting.beta) };
    let (ambient, beta) = match gpu.direct_only {
        true => (Vec3::ZERO, 0.0),
        false => (gpu.ambient.as_deref().map(parse_ambient).transpose()?.unwrap_or(default_ambient), gpu.beta.unwrap_or(default_beta)),
    };
    if gpu.composition.is_some() && !lpm {
        bail!("--composition: only a bake with light path maps (`relume bake --method light-path-maps`) has indirect light to compose");
    }
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
    };
    settings.validate().map_err(|e| anyhow::anyhow!("render settings: {e}"))?;
    Ok(settings)
}

/// One Vulkan render to make: a scene (re-indexed by its bake's atlas when it has one), the
/// settings, the techniques, and how many frames to time.
struct GpuJob<'s> {
    scene: &'s Scene,
    settings: RenderSettings,
    techniques: Vec<Box<dyn MakeTechnique + 's>>,
    frames: u32,
}

/// What a Vulkan render produced: the HDR image, the display pixels, per-frame timings and
/// the GPU work timed once at creation.
struct GpuRender {
    radiance: Image,
    display_rgba: Vec<u8>,
    frames: Vec<FrameTimings>,
    creation_ms: Vec<(&'static str, f64)>,
}

/// Renders every job on one headless context; returns the renders and the device's name.
/// With `--validation`, any message (teardown included) fails the whole command.
fn render_on_gpu(jobs: &[GpuJob], gpu: &GpuArgs) -> Result<(Vec<GpuRender>, String)> {
    let options = ContextOptions { validation: gpu.validation, device: gpu.device.clone() };
    let ctx = Context::headless(&options).context("Vulkan")?;
    let log = ctx.message_log();
    let device = format!("{} ({})", ctx.info.name, ctx.info.driver);
    let result: Result<Vec<GpuRender>> = jobs.iter().map(|job| render_frames(&ctx, job)).collect();
    // Dropped first, so that messages about teardown (objects never destroyed) count too.
    drop(ctx);
    let messages = log.lock().map(|m| m.clone()).unwrap_or_default();
    if !messages.is_empty() {
        bail!("{} Vulkan validation message(s), first: {}", messages.len(), messages[0]);
    }
    Ok((result?, device))
}

fn render_frames(ctx: &Arc<Context>, job: &GpuJob) -> Result<GpuRender> {
    let techniques: Vec<&dyn MakeTechnique> = job.techniques.iter().map(|t| t.as_ref()).collect();
    let mut renderer = Headless::new(Renderer::new_blocking(ctx, job.scene, &job.settings, &techniques).context("Vulkan renderer")?)?;
    if job.frames > 1 {
        warm_up(&mut renderer, WARM_UP_SECONDS)?;
    } else {
        renderer.render()?;
    }
    let frames = (0..job.frames).map(|_| renderer.render()).collect::<Result<Vec<_>, _>>()?;
    let (radiance, display_rgba) = renderer.render_and_read()?;
    Ok(GpuRender { radiance, display_rgba, frames, creation_ms: renderer.creation_timings() })
}

/// The scene re-indexed by a bake artifact, the artifact's obscurance as the renderer takes
/// it, and its light path maps' transfer if it has one.
struct Lit {
    scene: Scene,
    layout: PageLayout,
    texels: Vec<Vec4>,
    transfer: Option<ClusteredTransfer>,
}

impl Lit {
    fn read(dir: &Path, scene: &Scene) -> Result<Lit> {
        let baked = Baked::read(dir, scene)?;
        let mut lit = scene.clone();
        baked.apply_to(&mut lit);
        let texels = baked.lightmap_rgba();
        Ok(Lit { scene: lit, layout: baked.layout, texels, transfer: baked.transfer })
    }

    fn job(&self, settings: RenderSettings, composition: Composition, frames: u32) -> GpuJob<'_> {
        GpuJob { scene: &self.scene, settings, techniques: self.techniques(composition), frames }
    }

    /// The obscurance technique, and the light path maps' after it when the bake has them.
    fn techniques(&self, composition: Composition) -> Vec<Box<dyn MakeTechnique + '_>> {
        let atlas = AtlasImage::new(self.layout, &self.texels);
        let mut techniques: Vec<Box<dyn MakeTechnique + '_>> = vec![Box::new(ObscuranceData { obscurance: atlas })];
        if let Some(transfer) = &self.transfer {
            techniques.push(Box::new(LightPathMapsData { transfer, atlas, composition }));
        }
        techniques
    }
}

fn rgba_to_rgb(rgba: &[u8]) -> Vec<u8> {
    rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect()
}

/// How long frames run before any is timed, unless a sweep says otherwise: long enough for
/// a real GPU's clocks to settle at the frame's load (docs/BENCHMARKS.md: on an H100 a point
/// timed after 3 frames alone ran at clocks its predecessor left, up to 4.1 times slower).
pub(crate) const WARM_UP_SECONDS: f64 = 0.5;

/// Renders untimed frames, at least three (caches, pipelines) and for at least `seconds`.
pub(crate) fn warm_up(renderer: &mut Headless, seconds: f64) -> Result<()> {
    let start = std::time::Instant::now();
    let mut frames = 0;
    while frames < 3 || start.elapsed().as_secs_f64() < seconds {
        renderer.render()?;
        frames += 1;
    }
    Ok(())
}

/// Timed frames: at least one, at most a number that cannot exhaust memory.
fn frame_count(frames: u32) -> Result<u32> {
    if !(1..=100_000).contains(&frames) {
        bail!("--frames {frames}: render 1..=100000 frames");
    }
    Ok(frames)
}

fn render_command(args: &RenderArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let frames = frame_count(args.frames)?;
    let lit = args.bake.as_deref().map(|dir| Lit::read(dir, &scene)).transpose()?;
    let lpm = lit.as_ref().is_some_and(|lit| lit.transfer.is_some());
    let settings = render_settings(&args.scene, &args.gpu, &scene.settings, lpm)?;
    if args.gpu.composition.is_some() && !lpm {
        bail!("--composition: only a bake with light path maps (`relume bake --method light-path-maps`) has indirect light to compose");
    }
    let job = match &lit {
        Some(lit) => lit.job(settings, args.gpu.composition.unwrap_or_default(), frames),
        None => GpuJob { scene: &scene, settings, techniques: Vec::new(), frames },
    };
    let (renders, device) = render_on_gpu(&[job], &args.gpu)?;
    write_render_outputs(&args.out, &renders[0])?;
    println!("device: {device}");
    for (work, ms) in &renders[0].creation_ms {
        println!("{work} (once, at creation): {ms:.3} ms");
    }
    print_timings(&renders[0].frames);
    Ok(())
}

fn write_render_outputs(exr_path: &Path, out: &GpuRender) -> Result<()> {
    image::write_exr_layers(exr_path, &[("radiance", &out.radiance)])?;
    let png = exr_path.with_extension("png");
    let (w, h) = (out.radiance.width, out.radiance.height);
    image::write_png_rgb8(&png, w, h, &rgba_to_rgb(&out.display_rgba))?;
    println!("wrote {} and {}", exr_path.display(), png.display());
    Ok(())
}

/// Median GPU time of each pass over the timed frames, then the frame total (empty when
/// the device has no timestamps).
pub(crate) fn median_timings(frames: &[FrameTimings]) -> Vec<(String, f64)> {
    let Some(first) = frames.first().filter(|f| !f.passes().is_empty()) else { return Vec::new() };
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    // Every frame of one renderer runs the same passes.
    let mut rows: Vec<_> = first
        .passes()
        .iter()
        .enumerate()
        .map(|(i, (name, _))| (name.to_string(), median(frames.iter().map(|f| f.passes()[i].1).collect())))
        .collect();
    rows.push(("frame".into(), median(frames.iter().map(FrameTimings::total_ms).collect())));
    rows
}

fn print_timings(frames: &[FrameTimings]) {
    let rows = median_timings(frames);
    if rows.is_empty() {
        println!("the device reports no timestamps");
        return;
    }
    println!("GPU time, median of {} frame(s):", frames.len());
    for (name, ms) in rows {
        println!("  {name:<34} {ms:>9.3} ms");
    }
}

fn positive(flag: &str, value: f32) -> Result<f32> {
    if !(value.is_finite() && value > 0.0) {
        bail!("{flag} {value}: give a finite number above 0");
    }
    Ok(value)
}

fn reference_settings(scene: &SceneArgs, trace: &PathTracerArgs, shadows: bool) -> Result<ReferenceSettings> {
    if trace.spp == 0 {
        bail!("--spp 0: take at least one sample per pixel");
    }
    let max_time = match trace.time_limit {
        Some(s) if !(s.is_finite() && s > 0.0) => bail!("--time-limit {s}: give a positive number of seconds"),
        Some(s) => Some(Duration::from_secs_f64(s)),
        None => None,
    };
    if trace.threads == Some(0) {
        bail!("--threads 0: use at least one thread");
    }
    Ok(ReferenceSettings {
        samples_per_pixel: trace.spp,
        max_time,
        seed: trace.seed,
        width: scene.width,
        height: scene.height,
        max_bounces: trace.max_bounces,
        pixel_centres: trace.pixel_centres,
        shadows,
        threads: trace.threads,
        progress: true,
    })
}

/// The reference's three layers and how they were made.
pub(crate) struct ReferenceRun {
    images: relume_bake::reference::ReferenceImages,
    seconds: f64,
}

fn trace_reference(scene: &Scene, settings: &ReferenceSettings) -> ReferenceRun {
    let start = Instant::now();
    let bvh = SceneBvh::new(scene);
    let images = render_reference(scene, &bvh, settings);
    ReferenceRun { images, seconds: start.elapsed().as_secs_f64() }
}

fn write_reference(path: &Path, run: &ReferenceRun, exposure: f32) -> Result<()> {
    let i = &run.images;
    image::write_exr_layers(path, &[("direct", &i.direct), ("indirect", &i.indirect), ("combined", &i.combined)])?;
    let png = path.with_extension("png");
    image::write_png_tonemapped(&png, &i.combined, exposure)?;
    println!("wrote {} and {}", path.display(), png.display());
    Ok(())
}

fn reference_command(args: &ReferenceArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let settings = reference_settings(&args.scene, &args.trace, !args.no_shadows)?;
    positive("--exposure", args.exposure)?;
    let run = trace_reference(&scene, &settings);
    write_reference(&args.out, &run, args.exposure)?;
    println!("{} samples per pixel in {:.2} s, {:.0} paths/s", run.images.samples_per_pixel, run.seconds, run.images.paths_per_second);
    if run.images.nonfinite_samples > 0 {
        bail!("{} samples were NaN or infinite; the scene holds degenerate data", run.images.nonfinite_samples);
    }
    Ok(())
}

fn compare_command(args: &CompareArgs) -> Result<()> {
    positive("--error-scale", args.error_scale)?;
    let image = image::read_exr_layer(&args.image, args.layer.as_deref())?;
    let reference = match &args.reference_layer {
        Some(layer) => image::read_exr_layer(&args.reference, Some(layer))?,
        None => image::read_exr_layer(&args.reference, Some("combined")).or_else(|_| image::read_exr_layer(&args.reference, None))?,
    };
    let stats =
        metrics::compare(&image, &reference).with_context(|| format!("{} against {}", args.image.display(), args.reference.display()))?;
    println!("RMSE  {:.6}\nNRMSE {:.6}", stats.rmse, stats.nrmse);
    if stats.dark_pixels > 0 {
        println!("light where the reference is black: {:.6} of its RMS over {} pixels", stats.dark_leak, stats.dark_pixels);
    }
    if let Some(path) = &args.error_image {
        let rgb = metrics::false_colour(&image, &reference, args.error_scale)?;
        image::write_png_rgb8(path, image.width, image.height, &rgb)?;
        println!("wrote {}", path.display());
    }
    if stats.non_finite_pixels > 0 {
        bail!("{}: {} pixel(s) are NaN or infinite", args.image.display(), stats.non_finite_pixels);
    }
    Ok(())
}
