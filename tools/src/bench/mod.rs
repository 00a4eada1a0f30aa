//! `relume bench`: runs a sweep (scenes x methods x parameter sets x light configurations,
//! from a TOML file: docs/BENCH.md) and records, for every point, what the bake cost, what a
//! frame costs on the GPU, and how far the image is from the reference path tracer; then
//! writes results.csv, results.json, the charts and report.md into one folder.

mod budget;
mod charts;
pub(crate) mod config;
mod figures;
mod methods_table;
mod overview;
mod pareto;
mod perceptual;
mod reference_cache;
mod report;
mod results;
mod sweep;

use crate::args::{load_scene, positive, threads, SceneArgs};
use crate::gpu::{self, median_timings, warm_up};
use crate::methods;
use anyhow::{bail, Context as _, Result};
use clap::Args;
use config::Config;
use glam::Vec3;
use reference_cache::{Reference, ReferenceCache};
use relume_bake::artifact::Artifact;
use relume_bake::bvh::SceneBvh;
use relume_bake::image::{self, Image};
use relume_bake::metrics;
use relume_bake::outputs::Outputs;
use relume_bake::reference::ReferenceSettings;
use relume_bake::scene::{Light, LightKind, Scene};
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
    /// Start no new method configuration after this many seconds (the report says which were skipped).
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
        for config in configs {
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
            match bench.run(config, &device) {
                Ok(scored) => rows.extend(scored),
                Err(why) => {
                    eprintln!("{}: {} [{}] failed: {why:#}", bench.name, config.method.name(), config.label);
                    rows.extend(bench.failed(config, &format!("{why:#}")));
                }
            }
        }
    }
    drop(ctx);
    let validation_messages = log.lock().map(|m| m.clone()).unwrap_or_default();
    for row in &mut rows {
        row.device = device.clone();
    }
    results::mark_front(&mut rows);
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
    /// The references' own noise (with the sweep's reference_noise).
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
        let settings = ReferenceSettings {
            samples_per_pixel: sweep.reference_spp,
            width: sweep.width,
            height: sweep.height,
            pixel_centres: true,
            work: WorkOptions { threads: args.threads, progress: true, ..WorkOptions::default() },
            ..ReferenceSettings::default()
        };
        let mut references = Vec::new();
        for (k, config) in configurations.iter().enumerate() {
            println!("{name}: reference {}/{} ({} spp)", k + 1, configurations.len(), sweep.reference_spp);
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
        let noise = match sweep.reference_noise {
            true => {
                println!("{name}: reference 1 again with the next seed (its noise)");
                let seeded = ReferenceSettings { work: WorkOptions { seed: settings.work.seed + 1, ..settings.work }, ..settings.clone() };
                let moved = configurations[0].apply_to(&scene);
                let again = cache.get(&moved, &SceneBvh::new(&moved), &seeded)?;
                Some(reference_noise(&references[0], &again)?)
            }
            false => None,
        };
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

    /// Bakes `config` if it needs a bake, then renders and scores every light configuration.
    fn run(&mut self, config: &Config, device: &str) -> Result<Vec<Row>> {
        let method = config.method;
        println!("{}: {} [{}]", self.name, method.name(), config.label);
        let id = self.config_id(config);
        let (bake, artifact) = match method.bakes() {
            true => {
                let (dir, cost) = self.bake(config, &id)?;
                (cost, Some(Artifact::read(&dir)?))
            }
            false => (BakeCost::default(), None),
        };
        let loaded = methods::load(method, artifact.as_ref(), &self.scene, &config.values)?;
        let base = RenderSettings { width: self.sweep.width, height: self.sweep.height, ..RenderSettings::default() };
        let settings = config.frame.settings(method, &self.scene, base);
        settings.validate().map_err(|e| anyhow::anyhow!("{} [{}]: render settings: {e}", method.name(), config.label))?;
        let mut renderer = gpu::renderer(self.ctx, loaded.as_ref(), &settings)?;
        // Direct light alone with the same shadow maps: what the indirect part is measured
        // against. Under an environment it lacks the environment's direct light, so no
        // indirect part can be told apart (its columns stay empty).
        let direct_settings = RenderSettings { ambient: Vec3::ZERO, beta: 0.0, ..settings.clone() };
        let mut direct_renderer = match methods::environment_lit(&self.scene) {
            false => Some(gpu::renderer(self.ctx, &methods::Plain(self.scene.clone()), &direct_settings)?),
            true => None,
        };
        let mut rows: Vec<Row> = Vec::new();
        let mut previous: Option<Image> = None;
        for (k, configuration) in self.configurations.iter().enumerate() {
            match (self.continuous, k.checked_sub(1)) {
                (Some(seconds), Some(before)) => self.configurations[before].move_to(configuration, seconds, &mut renderer)?,
                _ => configuration.apply(&mut renderer)?,
            }
            let frames = time_frames(&mut renderer, self.sweep.frames, self.sweep.warmup_seconds)?;
            let image = frame_image(&mut renderer)?;
            let direct = match &mut direct_renderer {
                Some(renderer) => {
                    configuration.apply(renderer)?;
                    Some(frame_image(renderer)?)
                }
                None => None,
            };
            let scored = self.score(k, &image, direct.as_ref(), &self.point_id(config, k))?;
            let accuracy = scored.as_ref().ok().copied();
            let flicker = match (&previous, &accuracy) {
                (Some(before), Some(_)) => {
                    Some(metrics::flicker(before, &image, &self.references[k - 1].combined, &self.references[k].combined))
                }
                _ => None,
            };
            rows.push(Row {
                status: match scored {
                    Ok(_) => "ok".into(),
                    Err(why) => format!("failed: {why}"),
                },
                bake: bake.clone(),
                frame: frames,
                accuracy,
                flicker,
                non_finite_pixels: count_non_finite(&image),
                device: device.to_string(),
                ..self.row(config, k)
            });
            // Flicker compares scored images only: after a failed point the next has none.
            previous = accuracy.is_some().then_some(image);
        }
        Ok(rows)
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

/// A reference's own noise as an NRMSE against the truth, of the image and of its indirect
/// layer: two references of other seeds differ by sqrt(2) times it (their noise independent).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub(crate) struct ReferenceNoise {
    pub scene_nrmse: f64,
    pub indirect_nrmse: f64,
}

/// The noise of `a`, from `b` traced with another seed: NRMSE(a, b) / sqrt(2), measured
/// against `a` (the scale NRMSE of a method is measured at).
fn reference_noise(a: &Reference, b: &Reference) -> Result<ReferenceNoise> {
    let noise = |of: &Image, again: &Image| -> Result<f64> {
        let e = metrics::compare(again, of)?;
        Ok(e.nrmse / std::f64::consts::SQRT_2)
    };
    Ok(ReferenceNoise { scene_nrmse: noise(&a.combined, &b.combined)?, indirect_nrmse: noise(&a.indirect, &b.indirect)? })
}

/// One configuration of a scene: its lights, and where the moving light or occluder is, or
/// the swept spot's outer cone and turn (degrees).
struct Configuration {
    lights: Vec<Light>,
    light_position: Option<Vec3>,
    occluder: Option<MovedMesh>,
    spot: Option<(f32, f32)>,
}

/// A mesh moved by an occluder path: turned about the vertical axis through its bounds'
/// centre, then translated from where the scene has it.
struct MovedMesh {
    mesh: usize,
    translation: Vec3,
    turn_degrees: f32,
    /// Its vertices turned (None without a turn).
    turned: Option<(Vec<Vec3>, Vec<Vec3>)>,
}

impl MovedMesh {
    fn new(scene: &Scene, mesh: usize, translation: Vec3, turn_degrees: f32) -> Self {
        let m = &scene.meshes[mesh];
        let turned = (turn_degrees != 0.0).then(|| {
            let (lo, hi) = m.bounds();
            let (centre, turn) = ((lo + hi) * 0.5, glam::Quat::from_rotation_y(turn_degrees.to_radians()));
            (m.positions.iter().map(|p| centre + turn * (*p - centre)).collect(), m.normals.iter().map(|n| turn * *n).collect())
        });
        MovedMesh { mesh, translation, turn_degrees, turned }
    }
}

impl Configuration {
    /// The scene as this configuration has it, for the reference.
    fn apply_to(&self, scene: &Scene) -> Scene {
        let mut moved = Scene { lights: self.lights.clone(), ..scene.clone() };
        if let Some(o) = &self.occluder {
            let mesh = &mut moved.meshes[o.mesh];
            if let Some((positions, normals)) = &o.turned {
                (mesh.positions, mesh.normals) = (positions.clone(), normals.clone());
            }
            mesh.positions.iter_mut().for_each(|p| *p += o.translation);
        }
        moved
    }

    /// The renderer set to this configuration (the occluder first: set_lights refits the
    /// shadow maps to it).
    fn apply(&self, renderer: &mut Renderer) -> Result<()> {
        if let Some(o) = &self.occluder {
            if let Some((positions, normals)) = &o.turned {
                renderer.set_mesh_vertices(o.mesh, positions, normals)?;
            }
            renderer.set_mesh_translation(o.mesh, o.translation)?;
        }
        renderer.set_lights(&self.lights)?;
        Ok(())
    }

    /// The lights moved from this configuration to `next` over `seconds`, in steps of 1/60 s
    /// along the straight line between (light paths only).
    fn move_to(&self, next: &Configuration, seconds: f32, renderer: &mut Renderer) -> Result<()> {
        let steps = (seconds * 60.0).round().max(1.0) as usize;
        let mut lights = self.lights.clone();
        for step in 1..=steps {
            let t = step as f32 / steps as f32;
            for ((light, from), to) in lights.iter_mut().zip(&self.lights).zip(&next.lights) {
                light.position = from.position.lerp(to.position, t);
            }
            renderer.move_lights(&lights, seconds / steps as f32)?;
        }
        Ok(())
    }
}

/// The scene as it is, or one light or one mesh moved along the sweep's path.
fn configurations(scene: &Scene, entry: &SweepScene) -> Result<Vec<Configuration>> {
    let at_rest = || Configuration { lights: scene.lights.clone(), light_position: None, occluder: None, spot: None };
    if let Some(path) = &entry.light_path {
        if path.light >= scene.lights.len() {
            bail!("{}: light_path.light {}: the scene has {} light(s)", entry.path.display(), path.light, scene.lights.len());
        }
        return Ok(sweep::spread(&path.points, path.frames)
            .into_iter()
            .map(|p| {
                let mut configuration = at_rest();
                configuration.lights[path.light].position = p;
                configuration.light_position = Some(p);
                configuration
            })
            .collect());
    }
    if let Some(path) = &entry.occluder_path {
        let Some(mesh) = scene.meshes.iter().position(|m| m.name == path.mesh) else {
            let names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
            bail!("{}: occluder_path.mesh \"{}\": no such mesh; the scene has {}", entry.path.display(), path.mesh, names.join(", "));
        };
        let turns = sweep::spread(&[[0.0; 3], [path.turn_degrees, 0.0, 0.0]], path.frames);
        return Ok(sweep::spread(&path.points, path.frames)
            .into_iter()
            .zip(turns)
            .map(|(t, turn)| Configuration { occluder: Some(MovedMesh::new(scene, mesh, t, turn.x)), ..at_rest() })
            .collect());
    }
    if let Some(sweep) = &entry.spot_sweep {
        return spot_configurations(scene, entry, sweep, &at_rest);
    }
    Ok(vec![at_rest()])
}

/// A spot sweep's configurations: the spot with each cone, or aimed at each target (a
/// directional light too: from where its node stands).
fn spot_configurations(
    scene: &Scene,
    entry: &SweepScene,
    sweep: &sweep::SpotSweep,
    at_rest: &dyn Fn() -> Configuration,
) -> Result<Vec<Configuration>> {
    let aimed = sweep.outer_degrees.is_empty();
    let sweepable = |l: &&Light| matches!(l.kind, LightKind::Spot { .. }) || (aimed && l.kind == LightKind::Directional);
    let Some(spot) = scene.lights.get(sweep.light).filter(sweepable) else {
        bail!(
            "{}: spot_sweep.light {}: not a spot light (nor, for targets, a directional light) of the scene's {}",
            entry.path.display(),
            sweep.light,
            scene.lights.len()
        );
    };
    let with = |kind: LightKind, direction: Vec3| {
        let mut configuration = at_rest();
        configuration.lights[sweep.light] = Light { kind, direction, ..spot.clone() };
        let turn = direction.angle_between(spot.direction).to_degrees();
        let outer = match kind {
            LightKind::Spot { outer_cone, .. } => outer_cone.to_degrees(),
            _ => 0.0,
        };
        configuration.spot = Some((outer, turn));
        configuration
    };
    let cones = sweep.outer_degrees.iter().map(|&outer| {
        let inner = (outer - sweep.softness_degrees).max(0.0);
        with(LightKind::Spot { inner_cone: inner.to_radians(), outer_cone: outer.to_radians() }, spot.direction)
    });
    let aims = sweep.targets.iter().map(|t| {
        let direction = (Vec3::from_array(*t) - spot.position).normalize_or(spot.direction);
        with(spot.kind, direction)
    });
    Ok(cones.chain(aims).collect())
}

fn frame_image(renderer: &mut Headless) -> Result<Image> {
    Ok(renderer.render_and_read()?.0)
}

/// Warm-up frames (crate::warm_up), then `frames` timed ones: GPU time per pass from
/// timestamps and the CPU's wall time of each `render` call (record, submit, wait for its fence).
fn time_frames(renderer: &mut Headless, frames: u32, warm_up_seconds: f64) -> Result<FrameCost> {
    warm_up(renderer, warm_up_seconds)?;
    let mut timings = Vec::new();
    let mut cpu_ms = Vec::new();
    for _ in 0..frames {
        let start = Instant::now();
        timings.push(renderer.render()?);
        cpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let totals: Vec<f64> = timings.iter().filter(|t| !t.passes().is_empty()).map(|t| t.total_ms()).collect();
    Ok(FrameCost {
        passes_ms: median_timings(&timings).into_iter().filter(|(name, _)| name != "frame").collect(),
        gpu_ms: results::percentile(&totals, 0.5),
        gpu_p10_ms: results::percentile(&totals, 0.1),
        gpu_p90_ms: results::percentile(&totals, 0.9),
        cpu_ms: results::percentile(&cpu_ms, 0.5),
    })
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

    #[test]
    fn a_spot_sweep_narrows_its_cone_or_turns_its_aim_where_it_stands() {
        use relume_bake::testing::{look_at, point_light, scene, spot_light};
        let spot = spot_light(Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, Vec3::ONE, 0.5, 0.7);
        let s =
            scene("spot", vec![], vec![], vec![point_light(Vec3::ONE, Vec3::ONE), spot], look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 0.8));
        let entry = |text: &str| -> SweepScene { toml::from_str(&format!("path = 'a.gltf'\nspot_sweep = {text}")).unwrap() };
        let cones = configurations(&s, &entry("{ light = 1, outer_degrees = [60, 5], softness_degrees = 10 }")).unwrap();
        let kinds: Vec<LightKind> = cones.iter().map(|c| c.lights[1].kind).collect();
        assert_eq!(
            kinds,
            [
                LightKind::Spot { inner_cone: 50f32.to_radians(), outer_cone: 60f32.to_radians() },
                LightKind::Spot { inner_cone: 0.0, outer_cone: 5f32.to_radians() }
            ]
        );
        assert_eq!(cones.iter().map(|c| c.spot.unwrap().0.round()).collect::<Vec<_>>(), [60.0, 5.0]);
        let aims = configurations(&s, &entry("{ light = 1, targets = [[0, 0, 0], [2, 2, 0]] }")).unwrap();
        assert!(aims.iter().all(|c| c.lights[1].position == Vec3::new(0.0, 2.0, 0.0) && c.lights[0].position == Vec3::ONE));
        assert_eq!(aims.iter().map(|c| c.spot.unwrap().1.round()).collect::<Vec<_>>(), [0.0, 90.0]);
        assert!(aims[1].lights[1].direction.distance(Vec3::X) < 1e-6);
        let refused =
            configurations(&s, &entry("{ light = 0, outer_degrees = [30] }")).err().expect("a point light is no spot").to_string();
        assert!(refused.contains("spot_sweep.light 0: not a spot light"), "{refused}");
    }

    #[test]
    fn an_occluder_path_turns_its_mesh_about_its_bounds_centre_then_moves_it() {
        use relume_bake::testing::{closed_box, look_at, scene, Facing};
        let block = closed_box(Vec3::new(1.0, 0.0, 1.0), Vec3::new(3.0, 1.0, 2.0), 1, Facing::Outward, 0);
        let s = scene("block", vec![block], vec![], vec![], look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 0.8));
        let turned = MovedMesh::new(&s, 0, Vec3::new(0.0, 2.0, 0.0), 90.0);
        let configuration = Configuration { lights: vec![], light_position: None, occluder: Some(turned), spot: None };
        let moved = configuration.apply_to(&s).meshes.remove(0);
        let (lo, hi) = moved.bounds();
        // 2 x 1 x 1 about (2, 0.5, 1.5): turned a quarter, 1 x 1 x 2 about the same centre, 2 m up.
        assert!(
            (lo - Vec3::new(1.5, 2.0, 0.5)).abs().max_element() < 1e-5 && (hi - Vec3::new(2.5, 3.0, 2.5)).abs().max_element() < 1e-5,
            "{lo} {hi}"
        );
        let x_face = s.meshes[0].normals.iter().position(|n| *n == Vec3::X).unwrap();
        assert!((moved.normals[x_face] - Vec3::NEG_Z).length() < 1e-6, "{}", moved.normals[x_face]);
        assert!(MovedMesh::new(&s, 0, Vec3::ZERO, 0.0).turned.is_none());
    }
}
