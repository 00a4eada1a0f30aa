//! `relume run`, the main job: every method that suits the scene (or the one a bench's budget
//! chose for it), baked (those that bake) and rendered with the Vulkan renderer, and the reference path tracer; each compared with the
//! reference, over the whole image and over its indirect part (its image minus direct light
//! alone); the images and `report.md` written into one folder.

use crate::args::{load_scene, reference_settings, render_settings, GpuArgs, PathTracerArgs, SceneArgs, FRAMES};
use crate::bake::stage_bake;
use crate::bench::config::{self, FrameParams};
use crate::gpu::{median_timings, render_on_gpu, write_render_outputs, GpuJob, GpuRender};
use crate::methods::params::Values;
use crate::methods::{self, Loaded, Method, Plain};
use crate::reference::{trace_reference, write_reference, ReferenceRun};
use anyhow::{bail, Context as _, Result};
use clap::Args;
use relume_bake::artifact::Artifact;
use relume_bake::image::{self, Image};
use relume_bake::metrics;
use relume_bake::outputs::Outputs;
use relume_bake::scene::Scene;
use relume_renderer::RenderSettings;
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(Args)]
pub(crate) struct RunArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(flatten)]
    trace: PathTracerArgs,
    /// Folder for the images, the bakes (bake/<method>) and report.md.
    #[arg(long, short, default_value = "out")]
    out: PathBuf,
    /// Frames to time the Vulkan renderer over.
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(FRAMES))]
    frames: u32,
    /// Rays per texel of the bakes that trace them (obscurances).
    #[arg(long, default_value_t = 256)]
    rays: u32,
    /// Instead of every method that suits the scene: the method and configuration (bake, run
    /// time and frame keys) a `relume bench --budget` chose for this scene (its
    /// recommended.toml; the scene by its file name, as the sweep names it), as the bench
    /// rendered it.
    #[arg(long, conflicts_with_all = ["ambient", "beta", "direct_only", "rays"])]
    recommended: Option<PathBuf>,
}

/// One method of the main job: what it renders from, with which settings.
struct Model {
    method: &'static dyn Method,
    loaded: Box<dyn Loaded>,
    settings: RenderSettings,
}

pub(crate) fn run_main_job(args: &RunArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let reference_settings = reference_settings(&args.scene, &args.trace, true)?;
    let frames = args.frames;
    let work = relume_bake::work::WorkOptions {
        threads: reference_settings.work.threads,
        progress: true,
        ray_backend: reference_settings.work.ray_backend,
        ..Default::default()
    };
    // A bad recommended file is refused before anything is written.
    let mut skipped = Vec::new();
    let chosen = chosen_methods(args, &scene, &mut skipped)?;
    let files =
        chosen.iter().flat_map(|(m, ..)| [format!("{}.exr", m.name()), format!("{}.png", m.name()), format!("error_{}.png", m.name())]);
    let files: Vec<PathBuf> =
        files.chain(["reference.exr", "reference.png", "report.md"].map(String::from)).map(|f| args.out.join(f)).collect();
    crate::args::refuse_writing_over(&files)?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}: cannot create the folder", args.out.display()))?;

    // The bakes, images, reference and report move in together, or none does.
    let mut outputs = Outputs::new();
    let mut models = Vec::new();
    let mut bake_summary = String::new();
    for (method, values, frame) in chosen {
        let artifact = match method.bakes() {
            true => {
                println!("baking {} of {}", method.name(), args.scene.scene.display());
                let dir = args.out.join("bake").join(method.name());
                let (summary, staging) = stage_bake(&scene, method, &values, work, &dir, &mut outputs)?;
                print!("{summary}");
                let _ = write!(bake_summary, "{}:\n{summary}", method.name());
                Some(Artifact::read(&staging)?)
            }
            false => None,
        };
        let loaded = methods::load(method, artifact.as_ref(), &scene, &values)?;
        let settings = render_settings(&args.scene, &args.gpu, method.ambient(&scene), method.environment_ambient())?;
        let settings = match frame {
            Some(frame) => frame.settings(method, &scene, settings),
            None => settings,
        };
        settings.validate().map_err(|e| anyhow::anyhow!("{}: render settings: {e}", method.name()))?;
        models.push(Model { method, loaded, settings });
    }

    let names: Vec<&str> = models.iter().map(|m| m.method.name()).collect();
    println!("rendering with Vulkan: {} ({frames} timed frames each)", names.join(", "));
    // Direct light alone, with the same shadow maps (a recommended configuration's own):
    // what each method's indirect part is measured against.
    let direct_only = Plain(scene.clone());
    let direct_settings = match models.first() {
        Some(m) => RenderSettings { ambient: glam::Vec3::ZERO, beta: 0.0, environment_ambient: false, ..m.settings.clone() },
        None => render_settings(&args.scene, &args.gpu, None, false)?,
    };
    let mut jobs = vec![GpuJob { loaded: &direct_only, settings: direct_settings, frames: 1 }];
    jobs.extend(models.iter().map(|m| GpuJob { loaded: m.loaded.as_ref(), settings: m.settings.clone(), frames }));
    let (renders, device) = render_on_gpu(&jobs, &args.gpu)?;
    let (direct, renders) = renders.split_first().expect("the direct-only job");
    for (name, render) in names.iter().zip(renders) {
        write_render_outputs(&mut outputs, &args.out.join(format!("{name}.exr")), render)?;
    }

    println!("rendering the reference ({} spp)", args.trace.spp);
    let reference = trace_reference(&scene, &reference_settings)?;
    let exposure = args.gpu.exposure;
    write_reference(&mut outputs, &args.out.join("reference.exr"), &reference, exposure)?;

    // The direct-only image has no environment light, so an image's indirect part cannot be separated from it.
    let separable = !methods::environment_lit(&scene);
    let rows =
        names.iter().zip(renders).map(|(name, render)| score(name, render, direct, &reference, separable)).collect::<Result<Vec<_>>>()?;
    for (name, render) in names.iter().zip(renders) {
        let rgb = metrics::false_colour(&render.radiance, &reference.images.combined, 0.5)?;
        image::write_png_rgb8(&mut outputs, &args.out.join(format!("error_{name}.png")), args.scene.width, args.scene.height, &rgb)?;
    }
    let mut report = report_text(args, &device, &models, renders, &rows, &reference, &bake_summary);
    skipped.iter().for_each(|why| {
        let _ = writeln!(report, "\nNot run: {why}.");
    });
    if let Some(row) = rows.iter().find(|r| r.combined.non_finite_pixels > 0) {
        bail!(
            "the {} image has {} NaN or infinite pixel(s), so no image or report was written; render that method alone (`relume render`) to see where",
            row.method,
            row.combined.non_finite_pixels
        );
    }
    let report_path = args.out.join("report.md");
    outputs.bytes(&report_path, report.as_bytes())?;
    outputs.commit()?;
    print!("{report}");
    println!("wrote the images, the reference and {} in {}", report_path.display(), args.out.display());
    Ok(())
}

/// The methods `relume run` renders, with their values and (from a recommended.toml) the
/// frame's keys: the one the budget chose, or every method that suits the scene with the main
/// job's values.
/// The methods `run` runs with their values, and why each of the others does not suit the
/// scene (its bake would fail: a note, and a line of the report).
type Chosen = Vec<(&'static dyn Method, Values, Option<FrameParams>)>;

fn chosen_methods(args: &RunArgs, scene: &Scene, skipped: &mut Vec<String>) -> Result<Chosen> {
    if let Some(file) = &args.recommended {
        let (method, table) = config::recommended(file, &crate::bake::scene_name(&args.scene.scene))?;
        methods::refuse(method, scene).with_context(|| format!("{}: the method chosen for this scene", file.display()))?;
        let chosen = config::config(method, table).with_context(|| format!("{}", file.display()))?;
        return Ok(vec![(method, chosen.values, Some(chosen.frame))]);
    }
    let mut chosen = Vec::new();
    for method in methods::METHODS {
        match methods::unsuited(method, scene) {
            Some(why) => {
                eprintln!("note: not run: {why}");
                skipped.push(why);
            }
            None => chosen.push((method, methods::parse_values(method, &method.main_job_values(args.rays), None)?, None)),
        }
    }
    Ok(chosen)
}

/// One method's error against the reference.
struct Score {
    method: String,
    combined: metrics::ErrorStats,
    /// The image against the reference's direct layer: the score of a method that models
    /// direct light alone (punctual or an environment's).
    direct: metrics::ErrorStats,
    /// The indirect part's scores, where the scene's direct light is all punctual (none under
    /// an environment: the direct-only image lacks its light).
    indirect: Option<IndirectScore>,
}

/// A method's indirect part (its image minus the direct-only image) against the reference's
/// indirect layer.
struct IndirectScore {
    nrmse: f64,
    /// The factor on the indirect part that fits the reference's indirect layer best in the
    /// least-squares sense, and the NRMSE of the indirect part and of the image at that
    /// factor: how much of the error is the method's shape rather than its parameters.
    best_scale: f64,
    best_indirect_nrmse: f64,
    best_nrmse: f64,
}

fn score(method: &str, render: &GpuRender, direct: &GpuRender, reference: &ReferenceRun, separable: bool) -> Result<Score> {
    let refs = &reference.images;
    Ok(Score {
        method: method.to_string(),
        combined: metrics::compare(&render.radiance, &refs.combined)?,
        direct: metrics::compare(&render.radiance, &refs.direct)?,
        indirect: if separable { Some(score_indirect(render, direct, reference)?) } else { None },
    })
}

fn score_indirect(render: &GpuRender, direct: &GpuRender, reference: &ReferenceRun) -> Result<IndirectScore> {
    let refs = &reference.images;
    let indirect = metrics::difference(&render.radiance, &direct.radiance)?;
    let black = Image::new(indirect.width, indirect.height);
    let best_scale = metrics::best_scale(&black, &indirect, &refs.indirect)?;
    let best_indirect = metrics::add_scaled(&black, &indirect, best_scale as f32)?;
    let best = metrics::add_scaled(&direct.radiance, &indirect, best_scale as f32)?;
    Ok(IndirectScore {
        nrmse: metrics::compare(&indirect, &refs.indirect)?.nrmse,
        best_scale,
        best_indirect_nrmse: metrics::compare(&best_indirect, &refs.indirect)?.nrmse,
        best_nrmse: metrics::compare(&best, &refs.combined)?.nrmse,
    })
}

/// The methods from nearest the reference to farthest by their image's NRMSE, each with how
/// many times the nearest's error it has: which wins on this scene, and by how much.
fn ranking(rows: &[Score]) -> String {
    let mut order: Vec<&Score> = rows.iter().filter(|r| r.combined.nrmse.is_finite()).collect();
    order.sort_by(|a, b| a.combined.nrmse.total_cmp(&b.combined.nrmse));
    let Some(best) = order.first() else { return String::new() };
    let others: Vec<String> = order[1..]
        .iter()
        .map(|r| format!("{} {:.4} ({:.2}x)", r.method, r.combined.nrmse, r.combined.nrmse / best.combined.nrmse.max(f64::MIN_POSITIVE)))
        .collect();
    format!(
        "Nearest the reference (image against `combined`): **{}**, NRMSE {:.4}; then {}.",
        best.method,
        best.combined.nrmse,
        if others.is_empty() { "no other method".to_string() } else { others.join(", ") }
    )
}

fn report_text(
    args: &RunArgs,
    device: &str,
    models: &[Model],
    renders: &[GpuRender],
    rows: &[Score],
    reference: &ReferenceRun,
    bake_summary: &str,
) -> String {
    let mut r = String::new();
    let _ = writeln!(r, "# relume report: {}\n", args.scene.scene.display());
    let _ = writeln!(r, "Image {}x{}. Vulkan device: {device}.\n", args.scene.width, args.scene.height);
    let _ = writeln!(r, "| method | what it renders | what it lacks here | ambient I_A (lux), beta |\n|---|---|---|---|");
    for model in models {
        let s = &model.settings;
        let lacks = methods::misses(model.method, model.loaded.scene()).map_or("-".to_string(), |m| m.replace('|', "/"));
        let ambient =
            format!("{:?}, {}{}", s.ambient.to_array(), s.beta, if s.environment_ambient { ", and the environment's" } else { "" });
        let _ = writeln!(r, "| {} | {} | {lacks} | {ambient} |", model.method.name(), model.method.description());
    }
    let names: Vec<&str> = models.iter().map(|m| m.method.name()).collect();
    let _ = writeln!(r, "\n| {} | reference |\n|{}---|", names.join(" | "), "---|".repeat(names.len()));
    let _ = writeln!(r, "| {} ![](reference.png) |", names.iter().map(|m| format!("![]({m}.png) |")).collect::<String>());
    let errors: String = names.iter().map(|m| format!(" ![](error_{m}.png) |")).collect();
    let _ = writeln!(r, "|{errors} false-colour error against the reference |\n");
    let _ = writeln!(r, "## Error against the reference (NRMSE = RMSE / RMS of the reference, all channels)\n");
    let _ = writeln!(r, "A method that models direct light alone is scored against the reference's direct layer (emission and one bounce). The indirect part of a method is its image minus the direct-only image (punctual lights with shadow maps). The best factor scales that part to fit the reference's indirect layer in the least-squares sense. Under an environment light the direct-only image lacks the environment's direct light, so no indirect part is separated (-).\n");
    let _ = writeln!(
        r,
        "| method | image vs combined | image vs direct | indirect part vs reference indirect | best factor | indirect at best factor | image at best factor |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|---|");
    for row in rows {
        let indirect = match &row.indirect {
            Some(i) => format!("{:.4} | {:.4} | {:.4} | {:.4}", i.nrmse, i.best_scale, i.best_indirect_nrmse, i.best_nrmse),
            None => "- | - | - | -".to_string(),
        };
        let _ = writeln!(r, "| {} | {:.4} | {:.4} | {indirect} |", row.method, row.combined.nrmse, row.direct.nrmse);
    }
    let _ = writeln!(r, "\n{}", ranking(rows));
    let _ = writeln!(r, "\n## Bakes\n\n```\n{bake_summary}```");
    for (name, render) in names.iter().zip(renders) {
        let _ = writeln!(r, "\n## Vulkan GPU time, {name}, median of {} frames\n", render.frames.len());
        let _ = writeln!(r, "| pass | ms |\n|---|---|");
        for (pass, ms) in median_timings(&render.frames) {
            let _ = writeln!(r, "| {pass} | {ms:.3} |");
        }
        for (work, ms) in &render.creation_ms {
            let _ = writeln!(r, "| {work} (once, at creation) | {ms:.3} |");
        }
    }
    let i = &reference.images;
    let _ = writeln!(
        r,
        "\n## Reference\n\n{} samples per pixel, seed {}, {:.1} s, {:.0} paths/s.",
        i.samples_per_pixel, args.trace.work.seed, reference.seconds, i.paths_per_second
    );
    r
}
