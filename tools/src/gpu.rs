//! Rendering on the GPU for relume's own commands: jobs (a scene, its settings and a method's
//! techniques) rendered on one headless context, timed after a warm-up, read back, and their
//! pass timings summarised.

use crate::args::GpuArgs;
use crate::methods::Loaded;
use anyhow::{bail, Context as _, Result};
use relume_bake::image::{self, Image};
use relume_bake::outputs::Outputs;
use relume_renderer::vk::{Context, ContextOptions};
use relume_renderer::{FrameTimings, Headless, MakeTechnique, RenderSettings, Renderer};
use std::path::Path;
use std::sync::Arc;

/// One Vulkan render to make: a method's loaded data, the frame's settings, and how many
/// frames to time.
pub(crate) struct GpuJob<'l> {
    pub loaded: &'l dyn Loaded,
    pub settings: RenderSettings,
    pub frames: u32,
}

/// What a Vulkan render produced: the HDR image, the display pixels, per-frame timings and
/// the GPU work timed once at creation.
pub(crate) struct GpuRender {
    pub radiance: Image,
    pub display_rgba: Vec<u8>,
    pub frames: Vec<FrameTimings>,
    pub creation_ms: Vec<(&'static str, f64)>,
}

/// A headless renderer of a method's loaded data.
pub(crate) fn renderer(ctx: &Arc<Context>, loaded: &dyn Loaded, settings: &RenderSettings) -> Result<Headless> {
    let techniques = loaded.techniques();
    let techniques: Vec<&dyn MakeTechnique> = techniques.iter().map(|t| t.as_ref()).collect();
    Ok(Headless::new(Renderer::new_blocking(ctx, loaded.scene(), settings, &techniques).context("Vulkan renderer")?)?)
}

/// Renders every job on one headless context; returns the renders and the device's name.
/// With `--validation`, any message (teardown included) fails the whole command.
pub(crate) fn render_on_gpu(jobs: &[GpuJob], gpu: &GpuArgs) -> Result<(Vec<GpuRender>, String)> {
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
    let mut renderer = renderer(ctx, job.loaded, &job.settings)?;
    if job.frames > 1 {
        warm_up(&mut renderer, WARM_UP_SECONDS)?;
    } else {
        renderer.render()?;
    }
    let frames = (0..job.frames).map(|_| renderer.render()).collect::<Result<Vec<_>, _>>()?;
    let (radiance, display_rgba) = renderer.render_and_read()?;
    Ok(GpuRender { radiance, display_rgba, frames, creation_ms: renderer.creation_timings() })
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

/// Stages a render's EXR at `exr_path` and its displayed PNG beside it.
pub(crate) fn write_render_outputs(outputs: &mut Outputs, exr_path: &Path, out: &GpuRender) -> Result<()> {
    image::write_exr_layers(outputs, exr_path, &[("radiance", &out.radiance)])?;
    let (w, h) = (out.radiance.width, out.radiance.height);
    let rgb: Vec<u8> = out.display_rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    image::write_png_rgb8(outputs, &exr_path.with_extension("png"), w, h, &rgb)?;
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

pub(crate) fn print_timings(frames: &[FrameTimings]) {
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
