//! `relume run`, the main job: render a scene with the Vulkan renderer and with the reference
//! path tracer, compare them, and write the images and `report.md` into one folder.

use super::*;
use std::fmt::Write as _;

pub(crate) fn run_main_job(args: &RunArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let settings = render_settings(&args.scene, &args.gpu)?;
    let reference_settings = reference_settings(&args.scene, &args.trace, true)?;
    let frames = frame_count(args.frames)?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}: cannot create the folder", args.out.display()))?;

    println!("rendering {} with Vulkan ({} timed frames)", args.scene.scene.display(), args.frames);
    let gpu = render_on_gpu(&scene, &settings, &args.gpu, frames)?;
    write_render_outputs(&args.out.join("vulkan.exr"), &gpu)?;

    println!("rendering the reference ({} spp)", args.trace.spp);
    let reference = trace_reference(&scene, &reference_settings);
    write_reference(&args.out.join("reference.exr"), &reference, settings.exposure)?;

    let refs = &reference.images;
    let direct = metrics::compare(&gpu.radiance, &refs.direct)?;
    let combined = metrics::compare(&gpu.radiance, &refs.combined)?;
    let error_png = args.out.join("error_direct.png");
    let rgb = metrics::false_colour(&gpu.radiance, &refs.direct, 0.5)?;
    image::write_png_rgb8(&error_png, gpu.radiance.width, gpu.radiance.height, &rgb)?;

    let report = report_text(args, &gpu, &reference, (direct, combined));
    let report_path = args.out.join("report.md");
    image::write_atomically(&report_path, |tmp| std::fs::write(tmp, &report).map_err(|e| e.to_string()))?;
    print!("{report}");
    println!("wrote {}", report_path.display());
    if direct.non_finite_pixels > 0 {
        bail!("the Vulkan image has {} NaN or infinite pixel(s)", direct.non_finite_pixels);
    }
    Ok(())
}

fn report_text(
    args: &RunArgs,
    gpu: &GpuRender,
    reference: &ReferenceRun,
    (direct, combined): (metrics::ErrorStats, metrics::ErrorStats),
) -> String {
    let mut r = String::new();
    let (w, h) = (gpu.radiance.width, gpu.radiance.height);
    let _ = writeln!(r, "# relume report: {}\n", args.scene.scene.display());
    let _ = writeln!(r, "Image {w}x{h}. Vulkan device: {}.\n", gpu.device);
    let _ = writeln!(r, "| image | file |\n|---|---|");
    let _ = writeln!(r, "| Vulkan, direct light with variance shadow maps | ![](vulkan.png) |");
    let _ = writeln!(r, "| reference path tracer, combined | ![](reference.png) |");
    let _ = writeln!(r, "| error of Vulkan against reference direct (false colour) | ![](error_direct.png) |\n");
    let _ = writeln!(r, "## Error (NRMSE = RMSE / RMS of the reference, over all channels)\n");
    let _ = writeln!(r, "| Vulkan direct against | RMSE | NRMSE |\n|---|---|---|");
    let _ = writeln!(r, "| reference direct | {:.5} | {:.4} |", direct.rmse, direct.nrmse);
    let _ = writeln!(r, "| reference combined (no indirect method yet) | {:.5} | {:.4} |\n", combined.rmse, combined.nrmse);
    let _ = writeln!(r, "## Vulkan GPU time, median of {} frames\n", gpu.frames.len());
    let _ = writeln!(r, "| pass | ms |\n|---|---|");
    for (name, ms) in median_timings(&gpu.frames) {
        let _ = writeln!(r, "| {name} | {ms:.3} |");
    }
    let i = &reference.images;
    let _ = writeln!(
        r,
        "\n## Reference\n\n{} samples per pixel, seed {}, {:.1} s, {:.0} paths/s.",
        i.samples_per_pixel, args.trace.seed, reference.seconds, i.paths_per_second
    );
    r
}
