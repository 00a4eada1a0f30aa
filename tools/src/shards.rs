//! `relume bake plan | shard | merge | status`: one bake split into shards that processes or
//! machines bake apart and a merge puts together, the same bytes as the whole bake
//! (docs/CLUSTER.md; the splitting itself is `relume_bake::shards`).

use crate::bake::{bake_scene, default_bake_dir, naming, BakeArgs, Prepared};
use crate::methods;
use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use relume_bake::artifact::{file_checksum, scene_checksum};
use relume_bake::contract::Stages;
use relume_bake::outputs::Outputs;
use relume_bake::shards::{self, Plan, Planned, Role};
use relume_bake::work::{with_threads, WorkOptions};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

#[derive(Subcommand)]
pub(crate) enum Sharded {
    /// Plan a bake in shards: bake's own arguments, with --out the plan's folder; writes the
    /// plan (the scene's and settings' checksums, the work items and each shard's range) and,
    /// with --slurm, the scripts that run it on a Slurm cluster.
    Plan(PlanArgs),
    /// Bake one shard of a plan into its part (kept when already complete).
    Shard(ShardArgs),
    /// Check every part of a plan and bake the artifact from them: the whole bake's bytes.
    Merge(MergeArgs),
    /// Which shards of a plan are done, and why the others are not.
    Status(StatusArgs),
}

#[derive(Args)]
pub(crate) struct PlanArgs {
    #[command(flatten)]
    bake: BakeArgs,
    /// How many shards, each about the same share of the sampled cost.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    shards: u64,
    /// Also write slurm/shards.sbatch, slurm/merge.sbatch and slurm/submit.sh in the plan.
    #[arg(long)]
    slurm: bool,
    /// Where the Slurm merge writes the artifact (default: out/<scene>/<method>, from here).
    #[arg(long, requires = "slurm")]
    artifact: Option<PathBuf>,
    /// Run at most this many shards at once on Slurm (the array's %K).
    #[arg(long, requires = "slurm", value_parser = clap::value_parser!(u32).range(1..))]
    max_parallel: Option<u32>,
    /// CPUs each Slurm task asks for; a shard runs as many threads.
    #[arg(long, requires = "slurm", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024))]
    cpus_per_task: u32,
}

#[derive(Args)]
pub(crate) struct ShardArgs {
    /// The plan's folder.
    plan: PathBuf,
    /// The shard to bake, from 0.
    #[arg(long)]
    index: usize,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = crate::args::threads)]
    threads: Option<usize>,
}

#[derive(Args)]
pub(crate) struct MergeArgs {
    /// The plan's folder.
    plan: PathBuf,
    /// The artifact folder.
    #[arg(long, short)]
    out: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = crate::args::threads)]
    threads: Option<usize>,
}

#[derive(Args)]
pub(crate) struct StatusArgs {
    /// The plan's folder.
    plan: PathBuf,
    /// Print only the shards not done, as Slurm's --array takes them (0,3,5), or nothing.
    #[arg(long)]
    missing: bool,
}

/// The samples of a plan: enough stretches that shards of a few of them still balance.
const STRATA: u64 = 256;

pub(crate) fn command(sharded: &Sharded) -> Result<()> {
    match sharded {
        Sharded::Plan(args) => plan(args),
        Sharded::Shard(args) => shard(args),
        Sharded::Merge(args) => merge(args),
        Sharded::Status(args) => status(args),
    }
}

fn plan(args: &PlanArgs) -> Result<()> {
    let folder = args.bake.out.clone().ok_or_else(|| anyhow!("give the plan's folder with --out"))?;
    if args.bake.work.time_limit.is_some() {
        bail!("--time-limit: a sharded bake makes all its work, the same whoever makes it; limit each shard's time through the scheduler (Slurm's --time) instead");
    }
    refuse_foreign(&folder)?;
    let bake = Prepared::new(&args.bake)?;
    let role = leak(Role::Plan { strata: STRATA, found: Mutex::new(Planned::default()) });
    eprintln!("plan: preparing the bake, then timing a sample of its work items ...");
    // The gathers get no pool of their own: the plan times items on one thread.
    run_to_gather(&bake, bake.work.threads, WorkOptions { role: Some(role), threads: None, ..bake.work })?;
    let planned = role.planned();
    let ranges = shards::balanced(&planned, args.shards).map_err(|e| anyhow!("--shards: {e}"))?;
    let scene_file = args.bake.scene.as_deref().unwrap_or(Path::new(""));
    let artifact = args.artifact.clone().unwrap_or_else(|| default_bake_dir(scene_file, bake.method.name()));
    let mut argv = args.bake.argv()?;
    // The limit the plan's machine gave: the light path maps' search chooses within it, so
    // every shard and the merge bake within the same.
    if let (None, Some(limit)) = (args.bake.work.memory_limit, bake.work.memory_limit) {
        argv.extend(["--memory-limit".to_string(), limit.to_string()]);
    }
    let facts = json!({
        "method": bake.method.name(),
        "settings_checksum": relume_bake::artifact::checksum(argv.join("\n").as_bytes()),
        "args": argv,
        "inputs": inputs(&bake, &args.bake)?,
    });
    let contents = Plan::contents(facts, &planned, &ranges).map_err(|e| anyhow!(e))?;
    let mut outputs = Outputs::new();
    let staged = outputs.folder(&folder)?;
    std::fs::create_dir(staged.join("parts")).with_context(|| format!("{}: cannot create the parts' folder", folder.display()))?;
    relume_bake::outputs::write_staged(&staged.join(shards::PLAN_FILE), serde_json::to_string_pretty(&contents)?.as_bytes())
        .with_context(|| format!("{}: cannot write the plan", folder.display()))?;
    if args.slurm {
        let settings = crate::slurm::Settings {
            plan: std::path::absolute(&folder)?,
            folder: std::env::current_dir().context("cannot read the current folder")?,
            artifact: std::path::absolute(&artifact)?,
            shards: ranges.len(),
            max_parallel: args.max_parallel,
            cpus_per_task: args.cpus_per_task,
        };
        crate::slurm::write_scripts(&staged, &settings)?;
    }
    outputs.commit()?;
    println!(
        "planned {} shards of {} work items (about {:.0} s of work on one thread, sampled) in {}{}",
        ranges.len(),
        planned.count(),
        contents["estimated_seconds"].as_f64().unwrap_or(0.0),
        folder.display(),
        if args.slurm { format!("; submit with: bash {}", folder.join("slurm/submit.sh").display()) } else { String::new() }
    );
    Ok(())
}

/// A plan replaces only a plan folder, a new one or an empty one.
fn refuse_foreign(folder: &Path) -> Result<()> {
    let Ok(mut entries) = std::fs::read_dir(folder) else { return Ok(()) };
    match entries.next().is_none() || folder.join(shards::PLAN_FILE).is_file() {
        true => Ok(()),
        false => bail!("{}: exists, is not empty and holds no plan: choose an empty or new --out folder", folder.display()),
    }
}

/// What a plan records of the files the bake reads, and what each shard and the merge check:
/// the scene file's checksum and that of its surfaces as loaded, and those of the environment,
/// lights and recommended files given.
fn inputs(bake: &Prepared, args: &BakeArgs) -> Result<Value> {
    let sum = |file: &Path| -> Result<Value> {
        let checksum = file_checksum(file).with_context(|| file.display().to_string())?;
        Ok(json!({ "file": std::path::absolute(file)?, "checksum": checksum }))
    };
    let scene = args.scene.as_deref().ok_or_else(|| anyhow!("give the scene to bake"))?;
    let mut inputs = json!({ "scene": sum(scene)?, "surfaces": scene_checksum(&bake.scene) });
    for (name, file) in args.files() {
        inputs[name] = sum(file)?;
    }
    Ok(inputs)
}

fn leak(role: Role) -> &'static Role {
    Box::leak(Box::new(role))
}

/// Runs the bake on a pool of `threads` until its gathers have done what `work`'s role asks,
/// then stops.
fn run_to_gather(bake: &Prepared, threads: Option<usize>, work: WorkOptions) -> Result<()> {
    methods::refuse(bake.method, &bake.scene)?;
    let baker = bake.method.baker(&bake.scene, &bake.values)?;
    let mut stages = Stages::default();
    match with_threads(threads, || baker.bake(&bake.scene, &work.begun(), &mut stages)) {
        Err(e) if shards::stopped(&e) => Ok(()),
        Err(e) => Err(naming(&bake.scene, e)),
        Ok(_) => bail!(
            "--method {}: this bake has no long work to split (all its work is what a merge would do); bake it whole with `relume bake`",
            bake.method.name()
        ),
    }
}

/// The plan in `folder` and its bake, resolved again from the arguments it keeps, with the
/// scene checked against the one planned.
fn planned_bake(folder: &Path, threads: Option<usize>) -> Result<(Plan, Prepared)> {
    let plan = Plan::read(folder).map_err(|e| anyhow!(e))?;
    #[derive(Parser)]
    struct Kept {
        #[command(flatten)]
        bake: BakeArgs,
    }
    let argv: Vec<String> =
        plan.json["bake"]["args"].as_array().into_iter().flatten().filter_map(|a| a.as_str().map(String::from)).collect();
    let kept = Kept::try_parse_from(std::iter::once("relume-bake".to_string()).chain(argv))
        .map_err(|e| anyhow!("{}: its bake's arguments do not parse ({e}): plan again", folder.join(shards::PLAN_FILE).display()))?;
    let mut bake = Prepared::new(&kept.bake)?;
    let now = inputs(&bake, &kept.bake)?;
    if now != plan.json["bake"]["inputs"] {
        let changed = now.as_object().into_iter().flatten().filter(|(k, v)| plan.json["bake"]["inputs"][k.as_str()] != **v);
        let names: Vec<&str> = changed.map(|(k, _)| k.as_str()).collect();
        bail!("{}: the bake's {} changed since the plan was made: plan again", folder.display(), names.join(", "));
    }
    bake.work.threads = threads.or(bake.work.threads);
    Ok((plan, bake))
}

fn shard(args: &ShardArgs) -> Result<()> {
    let (plan, bake) = planned_bake(&args.plan, args.threads)?;
    let range = plan.range(args.index).map_err(|e| anyhow!(e))?;
    if plan.check_part(args.index, true).is_ok() {
        println!("shard {}: its part is complete, kept", args.index);
        return Ok(());
    }
    let role = leak(plan.shard_role(args.index));
    run_to_gather(&bake, bake.work.threads, WorkOptions { role: Some(role), ..bake.work })?;
    let made = role.made();
    let manifest = plan.part_manifest_path(args.index);
    let contents = plan.part_manifest(args.index, &made).map_err(|e| anyhow!(e))?;
    let mut outputs = Outputs::new();
    outputs.bytes(&manifest, serde_json::to_string_pretty(&contents)?.as_bytes())?;
    outputs.commit()?;
    println!("shard {}: items {range:?} written to {}", args.index, manifest.display());
    Ok(())
}

fn merge(args: &MergeArgs) -> Result<()> {
    let (plan, bake) = planned_bake(&args.plan, args.threads)?;
    let unfinished = plan.unfinished(true);
    if !unfinished.is_empty() {
        let why: Vec<String> = unfinished.iter().map(|(_, e)| e.clone()).collect();
        bail!("{} of {} parts are not complete:\n{}", unfinished.len(), plan.ranges.len(), why.join("\n"));
    }
    let role = leak(plan.merge_role());
    print!("{}", bake_scene(&bake.scene, bake.method, &bake.values, WorkOptions { role: Some(role), ..bake.work }, &args.out)?);
    Ok(())
}

fn status(args: &StatusArgs) -> Result<()> {
    let plan = Plan::read(&args.plan).map_err(|e| anyhow!(e))?;
    // Sizes and manifests only: the merge reads every byte.
    let unfinished = plan.unfinished(false);
    if args.missing {
        println!("{}", unfinished.iter().map(|(i, _)| i.to_string()).collect::<Vec<_>>().join(","));
        return Ok(());
    }
    println!("{} of {} shards done", plan.ranges.len() - unfinished.len(), plan.ranges.len());
    unfinished.iter().for_each(|(_, why)| println!("  {why}"));
    Ok(())
}
