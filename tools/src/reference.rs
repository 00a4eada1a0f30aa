//! `relume reference` (the CPU path tracer's ground truth) and `relume compare` (RMSE and
//! NRMSE of one EXR against another, with a false-colour error image).

use crate::args::{load_scene, positive, reference_settings, refuse_exr_and_png_over, refuse_writing_over, PathTracerArgs, SceneArgs};
use anyhow::{anyhow, bail, Context as _, Result};
use clap::Args;
use relume_bake::bvh::SceneBvh;
use relume_bake::image;
use relume_bake::metrics;
use relume_bake::outputs::Outputs;
use relume_bake::reference::{render_reference, ReferenceImages, ReferenceSettings};
use relume_bake::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub(crate) struct ReferenceArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    trace: PathTracerArgs,
    /// Ignore visibility of punctual lights (shading only, to compare with `render --no-shadows`).
    #[arg(long)]
    no_shadows: bool,
    #[arg(long, short, default_value = "reference.exr")]
    out: PathBuf,
    #[arg(long, default_value_t = 1.0, value_parser = positive::<f32>)]
    exposure: f32,
}

#[derive(Args)]
pub(crate) struct CompareArgs {
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
    #[arg(long, default_value_t = 0.5, value_parser = positive::<f32>)]
    error_scale: f32,
}

/// The reference's three layers and how long they took.
pub(crate) struct ReferenceRun {
    pub images: ReferenceImages,
    pub seconds: f64,
}

pub(crate) fn trace_reference(scene: &Scene, settings: &ReferenceSettings) -> Result<ReferenceRun> {
    let start = Instant::now();
    let bvh = SceneBvh::build(scene, settings.work.ray_backend).map_err(|e| anyhow!("--ray-backend: {e}; or use obvhs"))?;
    let images = render_reference(scene, &bvh, settings);
    Ok(ReferenceRun { images, seconds: start.elapsed().as_secs_f64() })
}

/// Stages the reference's EXR at `path` and its tonemapped PNG beside it.
pub(crate) fn write_reference(outputs: &mut Outputs, path: &Path, run: &ReferenceRun, exposure: f32) -> Result<()> {
    let i = &run.images;
    image::write_exr_layers(outputs, path, &[("direct", &i.direct), ("indirect", &i.indirect), ("combined", &i.combined)])?;
    image::write_png_tonemapped(outputs, &path.with_extension("png"), &i.combined, exposure)?;
    Ok(())
}

pub(crate) fn reference_command(args: &ReferenceArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    refuse_exr_and_png_over(&args.out)?;
    let settings = reference_settings(&args.scene, &args.trace, !args.no_shadows)?;
    let run = trace_reference(&scene, &settings)?;
    if run.images.nonfinite_samples > 0 {
        bail!(
            "{}: {} samples were NaN or infinite, so nothing was written (under --out too); the scene holds degenerate data: check its lights' intensities, emission and environment for huge values",
            args.scene.scene.display(),
            run.images.nonfinite_samples
        );
    }
    let mut outputs = Outputs::new();
    write_reference(&mut outputs, &args.out, &run, args.exposure)?;
    outputs.commit()?;
    println!("wrote {} and {}", args.out.display(), args.out.with_extension("png").display());
    println!("{} samples per pixel in {:.2} s, {:.0} paths/s", run.images.samples_per_pixel, run.seconds, run.images.paths_per_second);
    Ok(())
}

pub(crate) fn compare_command(args: &CompareArgs) -> Result<()> {
    let image = image::read_exr_layer(&args.image, args.layer.as_deref())?;
    let reference = match &args.reference_layer {
        Some(layer) => image::read_exr_layer(&args.reference, Some(layer))?,
        None => image::read_exr_layer(&args.reference, Some("combined")).or_else(|_| image::read_exr_layer(&args.reference, None))?,
    };
    refuse_writing_over(args.error_image.as_slice())?;
    let stats =
        metrics::compare(&image, &reference).with_context(|| format!("{} against {}", args.image.display(), args.reference.display()))?;
    let unusable = reference.pixels.iter().filter(|p| !p.is_finite()).count();
    if unusable > 0 {
        bail!("{}: {unusable} pixel(s) of the reference are NaN or infinite; compare against a finite reference", args.reference.display());
    }
    if reference.pixels.iter().all(|p| *p == glam::Vec3::ZERO) {
        bail!(
            "{}: the reference is black everywhere, and an error relative to it has no meaning; compare against a lit reference",
            args.reference.display()
        );
    }
    println!("RMSE  {:.6}\nNRMSE {:.6}", stats.rmse, stats.nrmse);
    if stats.dark_pixels > 0 {
        println!("light where the reference is black: {:.6} of its RMS over {} pixels", stats.dark_leak, stats.dark_pixels);
    }
    if stats.non_finite_pixels > 0 {
        bail!("{}: {} pixel(s) are NaN or infinite", args.image.display(), stats.non_finite_pixels);
    }
    if let Some(path) = &args.error_image {
        let rgb = metrics::false_colour(&image, &reference, args.error_scale)?;
        let mut outputs = Outputs::new();
        image::write_png_rgb8(&mut outputs, path, image.width, image.height, &rgb)?;
        outputs.commit()?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
