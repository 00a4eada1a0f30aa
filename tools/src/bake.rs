//! `relume bake`: precompute a method's data for a scene into a bake artifact folder (format:
//! docs/FORMATS.md). The method comes from the registry (`methods`); this command only times,
//! writes and reports.

use crate::args::{load, replace_environment, WorkArgs};
use crate::methods::params::{BakeParams, Stage};
use crate::methods::{self, Method};
use anyhow::{bail, Context, Result};
use clap::Args;
use relume_bake::artifact::BakeOutput;
use relume_bake::contract::Stages;
use relume_bake::gltf_load::{LoadOptions, DEFAULT_MAX_TEXTURE_PIXELS};
use relume_bake::outputs::Outputs;
use relume_bake::scene::Scene;
use relume_bake::work::{with_threads, WorkOptions};
use serde_json::json;
use std::path::{Path, PathBuf};

/// `relume bake`: a whole bake, or (`plan`, `shard`, `merge`, `status`) one split into shards.
#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub(crate) struct BakeCommand {
    #[command(subcommand)]
    sharded: Option<crate::shards::Sharded>,
    #[command(flatten)]
    bake: BakeArgs,
}

#[derive(Args, Clone)]
pub(crate) struct BakeArgs {
    /// A glTF 2.0 scene (.gltf or .glb).
    #[arg(required = true)]
    pub scene: Option<PathBuf>,
    /// The method to bake: one of the registry's with a bake (`relume methods` lists them).
    #[arg(long, required_unless_present = "recommended", value_parser = |name: &str| baking_method(name).map(|m| m.name().to_string()).map_err(|e| e.to_string()))]
    method: Option<String>,
    /// Instead of --method: bake the method and parameters a `relume bench --budget` chose for
    /// this scene (its recommended.toml; the scene by its file name, as the sweep names it).
    /// Flags given beside it override its parameters.
    #[arg(long, conflicts_with = "method")]
    recommended: Option<PathBuf>,
    #[command(flatten)]
    pub work: WorkArgs,
    /// The artifact folder (default: out/<scene>/<method>); for `bake plan`, the plan's folder.
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Bake for the scene lit by this lat-long EXR instead of its own environment (as
    /// `render --environment`; a bake keyed to the environment is read only with the same).
    #[arg(long)]
    environment: Option<PathBuf>,
    /// As `render --allow-outside-files`.
    #[arg(long)]
    allow_outside_files: bool,
    /// As `render --lights`.
    #[arg(long)]
    lights: Option<PathBuf>,
    /// As `render --max-texture-pixels`.
    #[arg(long, default_value_t = DEFAULT_MAX_TEXTURE_PIXELS)]
    max_texture_pixels: u64,
    #[command(flatten)]
    params: BakeParams,
}

/// The artifact folder `relume bake` writes for a scene and method when no --out is given.
pub(crate) fn default_bake_dir(scene: &Path, method: &str) -> PathBuf {
    PathBuf::from("out").join(scene_name(scene)).join(method)
}

/// A method that bakes, or a refusal that names those that do.
pub(crate) fn baking_method(name: &str) -> Result<&'static dyn Method> {
    let method = methods::find(name)?;
    if !method.bakes() {
        let baking: Vec<&str> = methods::METHODS.iter().filter(|m| m.bakes()).map(|m| m.name()).collect();
        bail!("--method {name}: {name} has no bake; bake one of {}", baking.join(", "));
    }
    Ok(method)
}

/// The scene's name as a sweep names it: its file name without the extension.
pub(crate) fn scene_name(scene: &Path) -> String {
    scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into())
}

/// The method a bench's recommended.toml chose for the scene `name` and its bake parameters
/// as flag pairs (its run-time and frame keys left to `render`).
fn recommended(file: &Path, name: &str) -> Result<(&'static dyn Method, Vec<(String, String)>)> {
    let (method, table) = crate::bench::config::recommended(file, name)?;
    let method = baking_method(method.name()).map_err(|e| {
        anyhow::anyhow!(
            "{}: scene \"{name}\": {e:#} (the budget chose a method that needs no bake: `relume run --recommended` renders it)",
            file.display()
        )
    })?;
    let (_, pairs) = crate::bench::config::split(&table).map_err(|e| anyhow::anyhow!("{}: scene \"{name}\": {e:#}", file.display()))?;
    let baked: Vec<&str> = method.params().iter().filter(|p| p.stage == Stage::Bake).map(|p| p.name).collect();
    Ok((method, pairs.into_iter().filter(|(key, _)| baked.contains(&key.as_str())).collect()))
}

pub(crate) fn bake_command(command: &BakeCommand) -> Result<()> {
    if let Some(sharded) = &command.sharded {
        return crate::shards::command(sharded);
    }
    let bake = Prepared::new(&command.bake)?;
    print!("{}", bake_scene(&bake.scene, bake.method, &bake.values, bake.work, &bake.out)?);
    Ok(())
}

/// A bake's command line resolved: its scene loaded, its method and values, its work options
/// and its artifact folder.
pub(crate) struct Prepared {
    pub scene: Scene,
    pub method: &'static dyn Method,
    pub values: methods::params::Values,
    pub work: WorkOptions,
    pub out: PathBuf,
}

impl Prepared {
    pub(crate) fn new(args: &BakeArgs) -> Result<Prepared> {
        let scene_path = args.scene.as_deref().ok_or_else(|| anyhow::anyhow!("give the scene to bake"))?;
        let (method, pairs) = match (&args.recommended, &args.method) {
            (Some(file), _) => {
                let (method, mut pairs) = recommended(file, &scene_name(scene_path))?;
                pairs.retain(|(key, _)| !args.params.pairs.iter().any(|(given, _)| given == key));
                pairs.extend(args.params.pairs.iter().cloned());
                (method, pairs)
            }
            (None, Some(name)) => (baking_method(name)?, args.params.pairs.clone()),
            (None, None) => bail!("give --method or --recommended"),
        };
        let values = methods::parse_values(method, &pairs, Some(Stage::Bake))?;
        let work = args.work.options()?;
        let options = LoadOptions {
            outside_files: args.allow_outside_files,
            max_texture_pixels: Some(args.max_texture_pixels),
            ..Default::default()
        };
        let mut scene = load(scene_path, args.lights.as_deref(), options)?;
        replace_environment(&mut scene, args.environment.as_deref())?;
        let out = args.out.clone().unwrap_or_else(|| default_bake_dir(scene_path, method.name()));
        Ok(Prepared { scene, method, values, work, out })
    }
}

impl BakeArgs {
    /// The files besides the scene that these arguments have the bake read, by flag.
    pub(crate) fn files(&self) -> Vec<(&'static str, &Path)> {
        let given = [("recommended", &self.recommended), ("environment", &self.environment), ("lights", &self.lights)];
        given.into_iter().filter_map(|(name, path)| Some((name, path.as_deref()?))).collect()
    }

    /// The command line that gives these arguments (without --out), its paths absolute: what
    /// a plan keeps for its shards and merge to bake the same.
    pub(crate) fn argv(&self) -> Result<Vec<String>> {
        let absolute = |p: &Path| std::path::absolute(p).map(|p| p.display().to_string()).with_context(|| format!("{}", p.display()));
        let mut argv = Vec::new();
        let mut push = |name: &str, value: Option<String>| {
            argv.push(format!("--{name}"));
            argv.extend(value);
        };
        if let Some(method) = &self.method {
            push("method", Some(method.clone()));
        }
        for (name, path) in self.files() {
            push(name, Some(absolute(path)?));
        }
        if self.allow_outside_files {
            push("allow-outside-files", None);
        }
        push("max-texture-pixels", Some(self.max_texture_pixels.to_string()));
        argv.extend(self.work.argv());
        argv.extend(self.params.argv());
        argv.push(absolute(self.scene.as_deref().ok_or_else(|| anyhow::anyhow!("give the scene to bake"))?)?);
        Ok(argv)
    }
}

/// Bakes `scene` with `method` and `values` into the artifact folder `out`; returns a summary
/// to print.
pub(crate) fn bake_scene(
    scene: &Scene,
    method: &dyn Method,
    values: &methods::params::Values,
    work: WorkOptions,
    out: &Path,
) -> Result<String> {
    let mut outputs = Outputs::new();
    let (summary, _) = stage_bake(scene, method, values, work, out, &mut outputs)?;
    outputs.commit()?;
    Ok(summary)
}

/// As [`bake_scene`], the artifact staged among `outputs` (moved in place by their commit,
/// with the command's other outputs); returns the summary and the staging folder, which reads
/// as the artifact until then.
pub(crate) fn stage_bake(
    scene: &Scene,
    method: &dyn Method,
    values: &methods::params::Values,
    work: WorkOptions,
    out: &Path,
    outputs: &mut Outputs,
) -> Result<(String, PathBuf)> {
    // Refused before the work, not after it (the write checks again).
    relume_bake::artifact::refuse_foreign_folder(out)?;
    methods::refuse(method, scene)?;
    if let Some(missed) = methods::misses(method, scene) {
        eprintln!("warning: {}: {missed}", scene.source.display());
    }
    let baker = method.baker(scene, values)?;
    let mut stages = Stages::default();
    // Every stage on the worker threads --threads asks for, those without a pool of their own
    // (clustered PCA, light clustering) too.
    let bake = with_threads(work.threads, || baker.bake(scene, &work.begun(), &mut stages)).map_err(|e| naming(scene, e))?;
    let mut stats = bake.stats;
    stats["stages"] = stages.json();
    stats["peak_memory_bytes"] = json!(stages.peak_memory_bytes());
    stats["triangles"] = json!(scene.triangle_count());
    stats["threads"] = json!(work.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())));
    let mut parameters = bake.parameters;
    parameters["given"] = values.json(&method.params(), Stage::Bake);
    // The two backends give equivalent bakes, not the same bytes.
    parameters["ray_backend"] = json!(work.ray_backend.name());
    let output = BakeOutput { method: method.name(), scene: Some(scene), parameters, sections: bake.sections, stats };
    let staging = output.stage(outputs, out)?;
    Ok((format!("{}{}wrote {}\n", bake.summary, stages.summary(), out.display()), staging))
}

/// A bake's error naming the scene, once (an atlas's error names it already).
pub(crate) fn naming(scene: &Scene, error: String) -> anyhow::Error {
    let path = scene.source.display().to_string();
    match error.starts_with(&path) {
        true => anyhow::anyhow!(error),
        false => anyhow::anyhow!("{path}: {error}"),
    }
}
