//! `relume bench`: runs a sweep (scenes x methods x parameter sets x light configurations,
//! from a TOML file: docs/BENCH.md) and records, for every point, what the bake cost, what a
//! frame costs on the GPU, and how far the image is from the reference path tracer; then
//! writes results.csv, results.json, the charts and report.md into one folder.

mod budget;
mod charts;
pub(crate) mod config;
mod configuration;
mod figures;
mod methods_table;
mod noise;
mod overview;
mod pareto;
mod perceptual;
mod reference_cache;
mod report;
mod results;
pub(crate) mod scaling;
mod sweep;
mod timing;

use crate::args::{load_scene, positive, threads, SceneArgs};
use crate::gpu;
use crate::methods;
use anyhow::{bail, Context as _, Result};
use clap::Args;
use config::Config;
use configuration::{configurations, Configuration};
use glam::Vec3;
pub(crate) use noise::Resolution;
use noise::{measured_noise, ReferenceNoise};
use reference_cache::{Reference, ReferenceCache};
use relume_bake::artifact::Artifact;
use relume_bake::bvh::SceneBvh;
use relume_bake::image::{self, Image};
use relume_bake::metrics;
use relume_bake::outputs::Outputs;
use relume_bake::reference::ReferenceSettings;
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use relume_renderer::vk::{Context, ContextOptions};
use relume_renderer::{Headless, RenderSettings, Renderer};
use results::{Accuracy, BakeCost, FrameCost, Row};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use sweep::{Sweep, SweepScene};

#[derive(Args)]
pub(crate) struct BenchArgs {
    /// The sweep file (TOML; docs/BENCH.md).
    #[arg(default_value = "tools/sweeps/default.toml")]
    sweep: PathBuf,
    /// Report folder: results.csv, results.json, charts, images, report.md.
    #[arg(long, short, default_value = "out/bench")]
    out: PathBuf,
    /// Reference images are cached here, by a hash of scene, camera, lights, samples and version.
    #[arg(long, default_value = "out/reference-cache")]
    cache: PathBuf,
    /// Pick, per scene, the method and parameter set that is cheapest of those whose mean NRMSE
    /// over the light configurations is within this; written to recommended.toml and the report.
    #[arg(long, value_parser = positive::<f64>)]
    budget: Option<f64>,
    /// Leave out of the budget's choice what takes longer than this per frame (median GPU time,
    /// ms); without --budget, the most accurate within the bounds is chosen.
    #[arg(long, value_parser = positive::<f64>)]
    budget_ms: Option<f64>,
    /// Leave out of the budget's choice what has a larger bake artifact than this (MiB, what a
    /// renderer uploads); without --budget, the most accurate within the bounds is chosen.
    #[arg(long, value_parser = positive::<f64>)]
    budget_mib: Option<f64>,
    /// Also write this page: the budget's answer, the charts and the table across methods, and
    /// links to --link's reports (the main job's out/report.md).
    #[arg(long)]
    overview: Option<PathBuf>,
    /// A report the overview links to (repeatable): a `relume run` report, say.
    #[arg(long, requires = "overview")]
    link: Vec<PathBuf>,
    /// Bake no new method configuration after this many seconds (the report says which were
    /// skipped); the ones baked by then are still measured, one scene's light configurations at most.
    #[arg(long, value_parser = positive::<f64>)]
    time_limit: Option<f64>,
    /// Vulkan device: index or part of its name (default: a real GPU if any, else lavapipe).
    #[arg(long)]
    device: Option<String>,
    /// Turn on the Vulkan validation layers; any message fails the bench.
    #[arg(long)]
    validation: bool,
    /// Worker threads of the reference path tracer and the bakes (default: all cores).
    #[arg(long, value_parser = threads)]
    threads: Option<usize>,
}

/// What a sweep run leaves for the outputs.
pub(crate) struct Outcome {
    sweep: Sweep,
    device: String,
    rows: Vec<Row>,
    skipped: Vec<String>,
    /// "scene method: why" of each method of the sweep that does not suit a scene (not run there).
    not_applicable: Vec<String>,
    /// Per scene that measured it: the references' own noise.
    noise: Vec<(String, ReferenceNoise)>,
    references_traced: usize,
    references_found: usize,
    seconds: f64,
    /// Vulkan validation messages (with --validation): any fails the bench, after the outputs.
    validation_messages: Vec<String>,
}

pub(crate) fn bench_command(args: &BenchArgs) -> Result<()> {
    let sweep = Sweep::read(&args.sweep)?;
    let configs = configs(&sweep).with_context(|| format!("{}", args.sweep.display()))?;
    check_scenes(&sweep).with_context(|| format!("{}", args.sweep.display()))?;
    let outputs: Vec<PathBuf> = report::FILES.iter().map(|f| args.out.join(f)).chain(args.overview.clone()).collect();
    crate::args::refuse_writing_over(&outputs)?;
    std::fs::create_dir_all(args.out.join("images")).with_context(|| format!("{}: cannot create the report folder", args.out.display()))?;
    let outcome = run_sweep(sweep, &configs, args)?;
    let failed: Vec<&Row> = outcome.rows.iter().filter(|r| r.accuracy.is_none()).collect();
    let budget = budget::Budget { nrmse: args.budget, frame_ms: args.budget_ms, artifact_mib: args.budget_mib };
    let overview = args.overview.as_ref().map(|path| overview::Overview { path: path.clone(), links: args.link.clone() });
    report::write_all(&args.out, &outcome, budget.given(), overview.as_ref())?;
    if let Some(first) = outcome.validation_messages.first() {
        bail!("{} Vulkan validation message(s), first: {first}", outcome.validation_messages.len());
    }
    let skipped = match outcome.skipped.len() {
        0 => String::new(),
        n => format!("; {n} configuration(s) skipped by --time-limit"),
    };
    println!(
        "{} points in {:.1} s; references: {} traced, {} from the cache{skipped}; wrote {}",
        outcome.rows.len(),
        outcome.seconds,
        outcome.references_traced,
        outcome.references_found,
        args.out.join("report.md").display()
    );
    if let Some(row) = failed.first() {
        bail!("{} point(s) failed, first: {} {} [{}] light {}: {}", failed.len(), row.scene, row.method, row.params, row.light, row.status);
    }
    Ok(())
}

/// Every method configuration of the sweep, checked before any work starts: the method
/// exists and takes every key.
fn configs(sweep: &Sweep) -> Result<Vec<Config>> {
    let mut configs = Vec::new();
    for entry in &sweep.methods {
        let method = methods::find(&entry.method)?;
        let tables = if entry.params.is_empty() { vec![toml::Table::new()] } else { entry.params.clone() };
        for table in tables {
            configs.push(config::config(method, table)?);
        }
    }
    for (i, chart) in sweep.charts.iter().enumerate() {
        let Some(x) = &chart.x else { continue };
        let method = methods::find(&chart.method)?;
        let known = method.params().iter().any(|p| p.name == x)
            || config::FRAME_KEYS.contains(&x.as_str())
            || figures::CONFIGURATION_VARIABLES.contains(&x.as_str());
        if !known {
            let names: Vec<&str> = method.params().iter().map(|p| p.name).chain(figures::CONFIGURATION_VARIABLES).collect();
            bail!(
                "charts[{i}].x \"{x}\": not a parameter of {} nor what a spot sweep varies; use one of {}",
                chart.method,
                names.join(", ")
            );
        }
    }
    Ok(configs)
}

/// Loads every scene of the sweep and lays out its light configurations, so that a bad scene
/// or path is refused before any work starts.
fn check_scenes(sweep: &Sweep) -> Result<()> {
    for entry in &sweep.scenes {
        configurations(&sweep_scene(sweep, entry)?, entry)?;
    }
    Ok(())
}

fn scene_args(sweep: &Sweep, entry: &SweepScene) -> SceneArgs {
    SceneArgs {
        scene: entry.path.clone(),
        camera: entry.camera.clone(),
        width: sweep.width,
        height: sweep.height,
        environment: entry.environment.clone(),
        allow_outside_files: false,
        max_texture_pixels: relume_bake::gltf_load::DEFAULT_MAX_TEXTURE_PIXELS,
        lights: entry.lights.clone(),
    }
}

/// A sweep's scene loaded, less the method settings it leaves out (`without`: what the methods
/// then derive from the scene); refused when the scene has no such settings.
fn sweep_scene(sweep: &Sweep, entry: &SweepScene) -> Result<Scene> {
    let mut scene = load_scene(&scene_args(sweep, entry))?;
    for key in &entry.without {
        if scene.settings.blocks.remove(key).is_none() {
            let held: Vec<&String> = scene.settings.blocks.keys().collect();
            bail!("{}: without \"{key}\": the scene has no extras.relume.{key} (it has {held:?})", entry.path.display());
        }
    }
    Ok(scene)
}

fn run_sweep(sweep: Sweep, configs: &[Config], args: &BenchArgs) -> Result<Outcome> {
    let start = Instant::now();
    let ctx = Context::headless(&ContextOptions { validation: args.validation, device: args.device.clone() }).context("Vulkan")?;
    let log = ctx.message_log();
    let device = format!("{} ({})", ctx.info.name, ctx.info.driver);
    let mut cache = ReferenceCache::new(&args.cache)?;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let mut not_applicable = Vec::new();
    let mut noise = Vec::new();
    let out_of_time = || args.time_limit.is_some_and(|limit| start.elapsed().as_secs_f64() > limit);
    for entry in &sweep.scenes {
        if out_of_time() {
            skipped.extend(configs.iter().map(|config| format!("{} {} [{}]", entry.name(), config.method.name(), config.label)));
            continue;
        }
        let mut bench = SceneBench::new(&sweep, entry, &ctx, &mut cache, args)?;
        noise.extend(bench.noise.map(|n| (bench.name.clone(), n)));
        let mut bakes = Vec::new();
        let mut scene_rows = Vec::new();
        for (order, config) in configs.iter().enumerate() {
            if let Some(why) = methods::unsuited(config.method, &bench.scene) {
                let line = format!("{} {}: {why}", bench.name, config.method.name());
                if !not_applicable.contains(&line) {
                    println!("{line}");
                    not_applicable.push(line);
                }
                continue;
            }
            if out_of_time() {
                skipped.push(format!("{} {} [{}]", bench.name, config.method.name(), config.label));
                continue;
            }
            // A configuration that cannot be baked or rendered fails its points; the sweep goes on.
            match bench.bake_for(config) {
                Ok(baked) => bakes.push((order, config, baked)),
                Err(why) => scene_rows.push(bench.fail(order, config, &why)),
            }
        }
        // Every bake of the scene first: a bake's peak memory holds no renderer.
        let mut prepared = Vec::new();
        for (order, config, (bake, dir)) in bakes {
            match bench.prepare(order, config, bake, dir.as_deref()) {
                Ok(p) => prepared.push(p),
                Err(why) => scene_rows.push(bench.fail(order, config, &why)),
            }
        }
        scene_rows.extend(bench.measure(prepared, &device));
        scene_rows.sort_by_key(|(order, _)| *order);
        rows.extend(scene_rows.into_iter().flat_map(|(_, r)| r));
    }
    drop(ctx);
    let validation_messages = log.lock().map(|m| m.clone()).unwrap_or_default();
    for row in &mut rows {
        row.device = device.clone();
    }
    results::mark_front(&mut rows, &Resolution::of_noise(&noise));
    let (references_traced, references_found) = (cache.traced, cache.found);
    Ok(Outcome {
        sweep,
        device,
        rows,
        skipped,
        not_applicable,
        noise,
        references_traced,
        references_found,
        seconds: start.elapsed().as_secs_f64(),
        validation_messages,
    })
}

/// One scene of the sweep: its light configurations, their references and direct-only frames.
struct SceneBench<'s> {
    sweep: &'s Sweep,
    ctx: &'s Arc<Context>,
    out: &'s Path,
    threads: Option<usize>,
    name: String,
    scene: Scene,
    configurations: Vec<Configuration>,
    /// Seconds between consecutive configurations when the light moves continuously.
    continuous: Option<f32>,
    references: Vec<Reference>,
    /// The references' own noise (with the sweep's reference_noise or reference_noise_target).
    noise: Option<ReferenceNoise>,
    /// Bakes made so far, by method and flags: configurations that differ only at run time
    /// (composition, shadow maps) share one.
    bakes: Vec<(String, PathBuf, BakeCost)>,
}

impl<'s> SceneBench<'s> {
    fn new(
        sweep: &'s Sweep,
        entry: &'s SweepScene,
        ctx: &'s Arc<Context>,
        cache: &mut ReferenceCache,
        args: &'s BenchArgs,
    ) -> Result<SceneBench<'s>> {
        let scene = sweep_scene(sweep, entry)?;
        let name = entry.name();
        let configurations = configurations(&scene, entry)?;
        let bvh = SceneBvh::new(&scene);
        let mut settings = ReferenceSettings {
            samples_per_pixel: sweep.reference_spp,
            width: sweep.width,
            height: sweep.height,
            pixel_centres: true,
            work: WorkOptions { threads: args.threads, progress: true, ..WorkOptions::default() },
            ..ReferenceSettings::default()
        };
        // The noise first: its target sets the samples of every reference.
        let noise = match sweep.measures_noise() {
            true => {
                let first = configurations[0].apply_to(&scene);
                let noise = measured_noise(&name, &first, cache, &settings, sweep)?;
                settings.samples_per_pixel = noise.spp;
                Some(noise)
            }
            false => None,
        };
        let mut references = Vec::new();
        for (k, config) in configurations.iter().enumerate() {
            println!("{name}: reference {}/{} ({} spp)", k + 1, configurations.len(), settings.samples_per_pixel);
            let moved = config.apply_to(&scene);
            let reference = match config.occluder {
                Some(_) => cache.get(&moved, &SceneBvh::new(&moved), &settings)?,
                None => cache.get(&moved, &bvh, &settings)?,
            };
            let exposure = perceptual::exposure_for(&reference.combined);
            let mut outputs = Outputs::new();
            let path = args.out.join("images").join(format!("{name}_light{k}_reference.png"));
            image::write_png_tonemapped(&mut outputs, &path, &reference.combined, exposure)?;
            outputs.commit()?;
            references.push(reference);
        }
        let continuous = entry.light_path.as_ref().and_then(|p| p.seconds);
        Ok(SceneBench {
            sweep,
            ctx,
            out: &args.out,
            threads: args.threads,
            name,
            scene,
            configurations,
            continuous,
            references,
            noise,
            bakes: Vec::new(),
        })
    }

    /// `config` baked if its method bakes: the cost and the bake's folder.
    fn bake_for(&mut self, config: &Config) -> Result<(BakeCost, Option<PathBuf>)> {
        println!("{}: {} [{}]", self.name, config.method.name(), config.label);
        if !config.method.bakes() {
            return Ok((BakeCost::default(), None));
        }
        let (dir, cost) = self.bake(config, &self.config_id(config))?;
        Ok((cost, Some(dir)))
    }

    /// `config`'s renderer made from its bake (in `dir`): ready to be measured with the
    /// scene's other configurations.
    fn prepare<'c>(&self, order: usize, config: &'c Config, bake: BakeCost, dir: Option<&Path>) -> Result<Prepared<'c>> {
        let method = config.method;
        let artifact = dir.map(Artifact::read).transpose()?;
        let loaded = methods::load(method, artifact.as_ref(), &self.scene, &config.values)?;
        let base = RenderSettings { width: self.sweep.width, height: self.sweep.height, ..RenderSettings::default() };
        let settings = config.frame.settings(method, &self.scene, base);
        settings.validate().map_err(|e| anyhow::anyhow!("{} [{}]: render settings: {e}", method.name(), config.label))?;
        let renderer = gpu::renderer(self.ctx, loaded.as_ref(), &settings)?;
        // Direct light alone with the same shadow maps: what the indirect part is measured
        // against. Under an environment it lacks the environment's direct light, so no
        // indirect part can be told apart (its columns stay empty).
        let direct = (!methods::environment_lit(&self.scene)).then(|| RenderSettings { ambient: Vec3::ZERO, beta: 0.0, ..settings });
        Ok(Prepared { order, config, bake, renderer, direct, rows: Vec::new(), previous: None })
    }

    /// Every prepared configuration at every light configuration: set to it, timed in turn
    /// with the others (timing::time_interleaved), then its image scored. The rows of each,
    /// by its order in the sweep; a configuration that fails at any light fails all its points.
    fn measure(&self, prepared: Vec<Prepared>, device: &str) -> Vec<(usize, Vec<Row>)> {
        let mut done = Vec::new();
        let mut live = prepared;
        let mut direct = DirectFrames::default();
        for k in 0..self.configurations.len() {
            let mut set = Vec::new();
            for mut p in live {
                match self.set(k, &mut p.renderer) {
                    Ok(()) => set.push(p),
                    Err(why) => done.push(self.fail(p.order, p.config, &why)),
                }
            }
            println!(
                "{}: light configuration {}/{}: {} configuration(s) timed in turn",
                self.name,
                k + 1,
                self.configurations.len(),
                set.len()
            );
            let mut renderers: Vec<&mut Headless> = set.iter_mut().map(|p| &mut p.renderer).collect();
            let costs = timing::time_interleaved(&mut renderers, self.sweep.frames, self.sweep.warmup_seconds);
            direct.clear();
            live = Vec::new();
            for (mut p, cost) in set.into_iter().zip(costs) {
                match cost.and_then(|frame| self.record(k, &mut p, frame, &mut direct, device)) {
                    Ok(()) => live.push(p),
                    Err(why) => done.push(self.fail(p.order, p.config, &why)),
                }
            }
        }
        done.extend(live.into_iter().map(|p| (p.order, p.rows)));
        done
    }

    /// A renderer set to light configuration `k`: moved there from `k - 1` when the light
    /// moves continuously.
    fn set(&self, k: usize, renderer: &mut Renderer) -> Result<()> {
        match (self.continuous, k.checked_sub(1)) {
            (Some(seconds), Some(before)) => self.configurations[before].move_to(&self.configurations[k], seconds, renderer),
            _ => self.configurations[k].apply(renderer),
        }
    }

    /// The point of `p` at light configuration `k`, its frames timed: its image scored
    /// against the reference (and against the direct-only frame of its settings).
    fn record(&self, k: usize, p: &mut Prepared, frame: FrameCost, direct: &mut DirectFrames, device: &str) -> Result<()> {
        let image = frame_image(&mut p.renderer)?;
        let direct = match &p.direct {
            Some(settings) => Some(direct.image(self, k, settings)?),
            None => None,
        };
        let scored = self.score(k, &image, direct, &self.point_id(p.config, k))?;
        let accuracy = scored.as_ref().ok().copied();
        let flicker = match (&p.previous, &accuracy) {
            (Some(before), Some(_)) => {
                Some(metrics::flicker(before, &image, &self.references[k - 1].combined, &self.references[k].combined))
            }
            _ => None,
        };
        p.rows.push(Row {
            status: match scored {
                Ok(_) => "ok".into(),
                Err(why) => format!("failed: {why}"),
            },
            bake: p.bake.clone(),
            frame,
            accuracy,
            flicker,
            non_finite_pixels: count_non_finite(&image),
            device: device.to_string(),
            ..self.row(p.config, k)
        });
        // Flicker compares scored images only: after a failed point the next has none.
        p.previous = accuracy.is_some().then_some(image);
        Ok(())
    }

    /// Every point of `config` failed, saying why (the sweep goes on).
    fn fail(&self, order: usize, config: &Config, why: &anyhow::Error) -> (usize, Vec<Row>) {
        eprintln!("{}: {} [{}] failed: {why:#}", self.name, config.method.name(), config.label);
        (order, self.failed(config, &format!("{why:#}")))
    }

    /// The stem of the configuration's files: its bake folder, its points' pictures.
    fn config_id(&self, config: &Config) -> String {
        format!("{}_{}_{}", self.name, config.method.name(), sanitize(&config.label))
    }

    /// The stem of a point's pictures.
    fn point_id(&self, config: &Config, k: usize) -> String {
        format!("{}_light{k}", self.config_id(config))
    }

    /// A row of `config` at light configuration `k` with nothing measured: failed, costs unknown.
    fn row(&self, config: &Config, k: usize) -> Row {
        let configuration = &self.configurations[k];
        Row {
            scene: self.name.clone(),
            light: k,
            light_position: configuration.light_position.map(|p| p.to_array()),
            occluder_translation: configuration.occluder.as_ref().map(|o| o.translation.to_array()),
            occluder_turn_degrees: configuration.occluder.as_ref().map(|o| o.turn_degrees),
            spot_outer_degrees: configuration.spot.map(|s| s.0),
            spot_turn_degrees: configuration.spot.map(|s| s.1),
            method: config.method.name().to_string(),
            params: config.label.clone(),
            params_table: config.table.clone(),
            status: "failed".into(),
            bake: BakeCost::default(),
            frame: FrameCost::unknown(),
            accuracy: None,
            flicker: None,
            non_finite_pixels: 0,
            on_front: false,
            device: String::new(),
            image_id: self.point_id(config, k),
        }
    }

    /// The rows of a configuration that could not be baked or rendered: every point failed, `why`.
    fn failed(&self, config: &Config, why: &str) -> Vec<Row> {
        (0..self.configurations.len()).map(|k| Row { status: format!("failed: {why}"), ..self.row(config, k) }).collect()
    }

    /// The folder and cost of the bake of `config` on this scene: made now into bakes/`id`,
    /// or the one made earlier in this run with the same method and bake values.
    fn bake(&mut self, config: &Config, id: &str) -> Result<(PathBuf, BakeCost)> {
        let key = config.bake_key();
        if let Some((_, dir, cost)) = self.bakes.iter().find(|b| b.0 == key) {
            return Ok((dir.clone(), cost.clone()));
        }
        let dir = self.out.join("bakes").join(id);
        let work = WorkOptions { threads: self.threads, progress: true, ..WorkOptions::default() };
        crate::bake::bake_scene(&self.scene, config.method, &config.values, work, &dir)?;
        let cost = BakeCost::read(&dir)?;
        self.bakes.push((key, dir.clone(), cost.clone()));
        Ok((dir, cost))
    }

    /// Writes the point's pictures (image, false-colour error) and scores it.
    fn score(&self, k: usize, image: &Image, direct: Option<&Image>, point_id: &str) -> Result<Result<Accuracy, String>> {
        let reference = &self.references[k];
        let exposure = perceptual::exposure_for(&reference.combined);
        let images = self.out.join("images");
        let mut outputs = Outputs::new();
        image::write_png_tonemapped(&mut outputs, &images.join(format!("{point_id}.png")), image, exposure)?;
        let rgb = metrics::false_colour(image, &reference.combined, 0.5)?;
        image::write_png_rgb8(&mut outputs, &images.join(format!("{point_id}_error.png")), image.width, image.height, &rgb)?;
        outputs.commit()?;
        accuracy(image, reference, direct)
    }
}

/// A configuration of a scene baked and loaded: its renderer stays alive while the scene's
/// configurations are measured together, and gathers its points.
struct Prepared<'c> {
    order: usize,
    config: &'c Config,
    bake: BakeCost,
    renderer: Headless,
    /// The settings of its direct-only frame (None under an environment).
    direct: Option<RenderSettings>,
    rows: Vec<Row>,
    /// Its last scored image, for flicker.
    previous: Option<Image>,
}

/// Direct-only frames of a scene: one renderer per settings (configurations that differ only
/// in what they add share one), each with its image at the light configuration being measured.
#[derive(Default)]
struct DirectFrames(Vec<DirectFrame>);

struct DirectFrame {
    settings: RenderSettings,
    renderer: Headless,
    /// Made at the first call for the light configuration being measured.
    image: Option<Image>,
}

impl DirectFrames {
    /// The direct-only image of `settings` at light configuration `k`, made once per configuration.
    fn image(&mut self, bench: &SceneBench, k: usize, settings: &RenderSettings) -> Result<&Image> {
        let i = match self.0.iter().position(|f| f.settings == *settings) {
            Some(i) => i,
            None => {
                let renderer = gpu::renderer(bench.ctx, &methods::Plain(bench.scene.clone()), settings)?;
                self.0.push(DirectFrame { settings: settings.clone(), renderer, image: None });
                self.0.len() - 1
            }
        };
        let frame = &mut self.0[i];
        if frame.image.is_none() {
            bench.configurations[k].apply(&mut frame.renderer)?;
            frame.image = Some(frame_image(&mut frame.renderer)?);
        }
        Ok(frame.image.as_ref().expect("made above"))
    }

    /// Forget the images: the light configuration changes.
    fn clear(&mut self) {
        self.0.iter_mut().for_each(|f| f.image = None);
    }
}

/// The errors of a method's image against the reference, over the whole image and over its
/// indirect part (the image minus the direct-only frame `direct`; NaN without one). The point fails (inner
/// Err, saying why; nothing is averaged over it) when the image holds a NaN or an infinity,
/// or when the reference is black, where NRMSE has no meaning.
fn accuracy(image: &Image, reference: &Reference, direct: Option<&Image>) -> Result<Result<Accuracy, String>> {
    let non_finite = count_non_finite(image);
    if non_finite > 0 {
        return Ok(Err(format!("{non_finite} NaN or infinite pixel(s)")));
    }
    let exposure = perceptual::exposure_for(&reference.combined);
    let combined = metrics::compare(image, &reference.combined)?;
    if !combined.nrmse.is_finite() {
        return Ok(Err("the reference is black (the camera sees nothing the lights reach): NRMSE has no meaning".into()));
    }
    let (indirect_rmse, indirect_nrmse, indirect_flip) = match direct {
        Some(direct) => {
            let part = metrics::difference(image, direct)?;
            let indirect = metrics::compare(&part, &reference.indirect)?;
            (indirect.rmse, indirect.nrmse, perceptual::mean_flip(&part, &reference.indirect, exposure))
        }
        None => (f64::NAN, f64::NAN, f64::NAN),
    };
    Ok(Ok(Accuracy {
        rmse: combined.rmse,
        nrmse: combined.nrmse,
        flip: perceptual::mean_flip(image, &reference.combined, exposure),
        indirect_rmse,
        indirect_nrmse,
        indirect_flip,
    }))
}

fn frame_image(renderer: &mut Headless) -> Result<Image> {
    Ok(renderer.render_and_read()?.0)
}

fn count_non_finite(image: &Image) -> usize {
    image.pixels.iter().filter(|p| !p.is_finite()).count()
}

/// A label as part of a file name: letters, digits, '-', '.', the rest '_'.
fn sanitize(label: &str) -> String {
    label.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '.' { c } else { '_' }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_nan_pixel_fails_the_point_and_is_counted() {
        let grey = Image { width: 4, height: 4, pixels: vec![Vec3::splat(0.5); 16] };
        let reference = Reference { indirect: grey.clone(), combined: grey.clone() };
        let black = Image::new(4, 4);
        assert!(accuracy(&grey, &reference, Some(&black)).unwrap().is_ok());
        let environment_lit = accuracy(&grey, &reference, None).unwrap().unwrap();
        assert!(environment_lit.nrmse == 0.0 && environment_lit.indirect_nrmse.is_nan(), "no direct-only frame, no indirect part");
        let mut image = grey.clone();
        image.pixels[5] = Vec3::new(f32::NAN, 0.0, 0.0);
        image.pixels[6] = Vec3::splat(f32::INFINITY);
        assert_eq!(count_non_finite(&image), 2);
        let failure = accuracy(&image, &reference, Some(&black)).unwrap().unwrap_err();
        assert!(failure.contains("2 NaN"), "a NaN image must not be scored: {failure}");
        let black = Reference { indirect: Image::new(4, 4), combined: Image::new(4, 4) };
        assert!(accuracy(&grey, &black, Some(&Image::new(4, 4))).unwrap().unwrap_err().contains("black"));
    }
}
