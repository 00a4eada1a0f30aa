//! `relume run`, the main job: bake the scene's obscurances (and its light path maps when it
//! declares a light region), render it with the Vulkan renderer (direct light only, constant
//! ambient, obscurance ambient: Iones et al. 2003, eq. 5-7; light path maps: Umenhoffer et
//! al. 2008) and with the reference path tracer, compare each against the reference, and
//! write the images and `report.md` into one folder.

use super::*;
use std::fmt::Write as _;

/// The models the main job compares, in the order of the report; the last only on a scene
/// with a light region.
const MODELS: [&str; 4] = ["direct", "constant", "obscurance", "light_path_maps"];

/// Bakes `args` into `dir` and reads it back; returns the bake's summary too.
fn bake_and_read(scene: &Scene, args: &bake::BakeArgs, dir: &Path) -> Result<(Lit, String)> {
    let summary = bake::bake_scene(scene, args, dir)?;
    print!("{summary}");
    Ok((Lit::read(dir, scene)?, summary))
}

pub(crate) fn run_main_job(args: &RunArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let settings = render_settings(&args.scene, &args.gpu, &scene.settings, false)?;
    let reference_settings = reference_settings(&args.scene, &args.trace, true)?;
    let frames = frame_count(args.frames)?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}: cannot create the folder", args.out.display()))?;

    println!("baking obscurances of {} ({} rays per texel)", args.scene.scene.display(), args.rays);
    let (lit, mut bake_summary) = bake_and_read(&scene, &bake::BakeArgs::obscurance(&args.scene.scene, args.rays), &args.out.join("bake"))?;
    let lpm = match scene.settings.light_region {
        Some(_) => {
            println!("baking light path maps of {}", args.scene.scene.display());
            let (lpm, summary) = bake_and_read(
                &scene,
                &bake::BakeArgs::light_path_maps(&args.scene.scene, args.rays),
                &args.out.join("bake_light_path_maps"),
            )?;
            bake_summary.push_str(&summary);
            Some(lpm)
        }
        None => None,
    };
    let models = &MODELS[..3 + lpm.is_some() as usize];

    println!("rendering with Vulkan: {} ({} timed frames each)", models.join(", "), frames);
    let direct_only = RenderSettings { ambient: Vec3::ZERO, beta: 0.0, ..settings.clone() };
    let mut jobs = vec![
        GpuJob { scene: &scene, settings: direct_only.clone(), techniques: Vec::new(), frames },
        GpuJob { scene: &scene, settings: settings.clone(), techniques: Vec::new(), frames },
        lit.job(settings.clone(), Composition::default(), frames),
    ];
    jobs.extend(lpm.as_ref().map(|lpm| lpm.job(direct_only, Composition::default(), frames)));
    let (renders, device) = render_on_gpu(&jobs, &args.gpu)?;
    for (model, render) in models.iter().zip(&renders) {
        write_render_outputs(&args.out.join(format!("{model}.exr")), render)?;
    }

    println!("rendering the reference ({} spp)", args.trace.spp);
    let reference = trace_reference(&scene, &reference_settings);
    write_reference(&args.out.join("reference.exr"), &reference, settings.exposure)?;

    let rows =
        models.iter().zip(&renders).map(|(model, render)| score(model, render, &renders[0], &reference)).collect::<Result<Vec<_>>>()?;
    for (model, render) in models.iter().zip(&renders).skip(1) {
        let rgb = metrics::false_colour(&render.radiance, &reference.images.combined, 0.5)?;
        image::write_png_rgb8(&args.out.join(format!("error_{model}.png")), settings.width, settings.height, &rgb)?;
    }
    let report = report_text(args, &settings, &device, &renders, &rows, &reference, &bake_summary);
    let report_path = args.out.join("report.md");
    image::write_atomically(&report_path, |tmp| std::fs::write(tmp, &report).map_err(|e| e.to_string()))?;
    print!("{report}");
    println!("wrote {}", report_path.display());
    if let Some(row) = rows.iter().find(|r| r.combined.non_finite_pixels > 0) {
        bail!("the {} image has {} NaN or infinite pixel(s)", row.model, row.combined.non_finite_pixels);
    }
    Ok(())
}

/// One model's error against the reference.
struct Score {
    model: &'static str,
    combined: metrics::ErrorStats,
    /// The model's indirect part (its image minus the direct-only image) against the
    /// reference's indirect layer.
    indirect: metrics::ErrorStats,
    /// The factor on the ambient term (I_A and beta together) that fits the reference's
    /// indirect layer best in the least-squares sense, and the NRMSE of the indirect part
    /// and of the image at that factor: how much of the error is the model's shape rather
    /// than its parameters.
    best_scale: f64,
    best_indirect_nrmse: f64,
    best_nrmse: f64,
}

fn score(model: &'static str, render: &GpuRender, direct: &GpuRender, reference: &ReferenceRun) -> Result<Score> {
    let refs = &reference.images;
    let ambient = subtract(&render.radiance, &direct.radiance);
    let black = Image::new(ambient.width, ambient.height);
    let best_scale = metrics::best_scale(&black, &ambient, &refs.indirect)?;
    let best_ambient = metrics::add_scaled(&black, &ambient, best_scale as f32)?;
    let best = metrics::add_scaled(&direct.radiance, &ambient, best_scale as f32)?;
    Ok(Score {
        model,
        combined: metrics::compare(&render.radiance, &refs.combined)?,
        indirect: metrics::compare(&ambient, &refs.indirect)?,
        best_scale,
        best_indirect_nrmse: metrics::compare(&best_ambient, &refs.indirect)?.nrmse,
        best_nrmse: metrics::compare(&best, &refs.combined)?.nrmse,
    })
}

fn subtract(a: &Image, b: &Image) -> Image {
    Image { width: a.width, height: a.height, pixels: a.pixels.iter().zip(&b.pixels).map(|(x, y)| *x - *y).collect() }
}

fn report_text(
    args: &RunArgs,
    settings: &RenderSettings,
    device: &str,
    renders: &[GpuRender],
    rows: &[Score],
    reference: &ReferenceRun,
    bake_summary: &str,
) -> String {
    let mut r = String::new();
    let _ = writeln!(r, "# relume report: {}\n", args.scene.scene.display());
    let _ = writeln!(r, "Image {}x{}. Vulkan device: {device}.", settings.width, settings.height);
    let _ = writeln!(
        r,
        "Obscurance illumination model (Iones et al. 2003, eq. 5-7): ambient I_A = {:?} lux, beta = {}.\n",
        settings.ambient.to_array(),
        settings.beta
    );
    if rows.iter().any(|row| row.model == "light_path_maps") {
        let _ = writeln!(
            r,
            "Light path maps (Umenhoffer et al. 2008): direct light plus their indirect irradiance composed as `{}`, no ambient term.\n",
            Composition::default().name()
        );
    }
    let models: Vec<&str> = rows.iter().map(|row| row.model).collect();
    let _ = writeln!(r, "| {} | reference |\n|{}---|", models.join(" | "), "---|".repeat(models.len()));
    let _ = writeln!(r, "| {} ![](reference.png) |", models.iter().map(|m| format!("![]({m}.png) |")).collect::<String>());
    let errors: String = models.iter().map(|m| if *m == "direct" { " |".to_string() } else { format!(" ![](error_{m}.png) |") }).collect();
    let _ = writeln!(r, "|{errors} false-colour error against the reference |\n");
    let _ = writeln!(r, "## Error against the reference (NRMSE = RMSE / RMS of the reference, all channels)\n");
    let _ = writeln!(r, "The indirect part of a model is its image minus the direct-only image. The best factor scales that part (for the ambient models: I_A and beta together) to fit the reference's indirect layer in the least-squares sense.\n");
    let _ = writeln!(r, "| model | image vs combined | indirect part vs reference indirect | best factor | indirect at best factor | image at best factor |");
    let _ = writeln!(r, "|---|---|---|---|---|---|");
    for row in rows {
        let _ = writeln!(
            r,
            "| {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} |",
            row.model, row.combined.nrmse, row.indirect.nrmse, row.best_scale, row.best_indirect_nrmse, row.best_nrmse
        );
    }
    let _ = writeln!(r, "\n## Bake\n\n```\n{}```", bake_summary);
    for (model, render) in models.iter().zip(renders).skip(2) {
        let _ = writeln!(r, "\n## Vulkan GPU time, {model}, median of {} frames\n", render.frames.len());
        let _ = writeln!(r, "| pass | ms |\n|---|---|");
        for (name, ms) in median_timings(&render.frames) {
            let _ = writeln!(r, "| {name} | {ms:.3} |");
        }
        for (work, ms) in &render.creation_ms {
            let _ = writeln!(r, "| {work} (once, at creation) | {ms:.3} |");
        }
    }
    let i = &reference.images;
    let _ = writeln!(
        r,
        "\n## Reference\n\n{} samples per pixel, seed {}, {:.1} s, {:.0} paths/s.",
        i.samples_per_pixel, args.trace.seed, reference.seconds, i.paths_per_second
    );
    r
}
