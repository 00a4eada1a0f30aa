//! `relume rays`: how fast relume casts rays on a scene (BVH build, closest-hit and shadow
//! rays per second), on a path tracer's rays, optionally with every triangle subdivided, and
//! against Embree on the same rays where relume was built with it.

use crate::args::{load_scene, threads, SceneArgs};
use anyhow::{anyhow, Result};
use clap::Args;
use relume_bake::bvh::{RayBackend, SceneBvh};
use relume_bake::ray_bench::{ray_set, time_rays, RayCaster, RayRate, RaySet};
use relume_bake::scene::Scene;
use relume_bake::tessellation::Tessellation;
use std::time::Instant;

#[derive(Args)]
pub(crate) struct RaysArgs {
    /// The rays are those of a path tracer's image of this size (--width, --height), one path a
    /// pixel.
    #[command(flatten)]
    scene: SceneArgs,
    /// Split every triangle k x k first (the regular grid; for 2, 4, 8, ... the triangles of
    /// midpoint subdivision): the same surfaces in k^2 times the triangles.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=256))]
    subdivide: u32,
    /// Diffuse bounces of each path after its camera ray.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(0..=16))]
    bounces: u32,
    /// Times each caster traces the whole set (the rates are over all of them).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=1000))]
    repeats: u32,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads, 1..=1024 (default: all cores).
    #[arg(long, value_parser = threads)]
    threads: Option<usize>,
    /// The backend behind relume's ray calls to time: obvhs, or embree (builds with
    /// `--features embree`; Embree behind the same calls, against Embree called alone).
    #[arg(long, default_value = "obvhs", value_parser = RayBackend::parse)]
    ray_backend: RayBackend,
}

pub(crate) fn rays_command(args: &RaysArgs) -> Result<()> {
    let scene = subdivided(load_scene(&args.scene)?, args.subdivide)?;
    println!("{}: {} triangles (every triangle split {k} x {k})", args.scene.scene.display(), scene.triangle_count(), k = args.subdivide);
    let start = Instant::now();
    let bvh = SceneBvh::build(&scene, args.ray_backend).map_err(|e| anyhow!("--ray-backend: {e}"))?;
    println!("relume BVH ({}) built in {:.3} s", args.ray_backend.name(), start.elapsed().as_secs_f64());
    let set = ray_set(&scene, &bvh, args.scene.width, args.scene.height, args.bounces, args.seed);
    println!("{} closest-hit rays, {} shadow rays, each traced {} times", set.closest.len(), set.shadow.len(), args.repeats);
    let (closest, shadow) = report("relume", &bvh, &set, args);
    compare_with_embree(&scene, &bvh, &set, args, (closest, shadow))
}

#[cfg(not(feature = "embree"))]
fn compare_with_embree(_: &Scene, _: &SceneBvh, _: &RaySet, _: &RaysArgs, _: (RayRate, RayRate)) -> Result<()> {
    println!("(built without the embree feature: no comparison; docs/BENCHMARKS.md, \"Ray casting\")");
    Ok(())
}

/// Embree's rates on the same rays, relume's as a share of them, and how many rays the two
/// answer alike (the same geometry, so all but rays along shared edges).
#[cfg(feature = "embree")]
fn compare_with_embree(scene: &Scene, bvh: &SceneBvh, set: &RaySet, args: &RaysArgs, ours: (RayRate, RayRate)) -> Result<()> {
    let start = Instant::now();
    let embree = relume_bake::embree::EmbreeScene::new(scene, args.threads, false).map_err(|e| anyhow!("{e}"))?;
    println!("Embree BVH built in {:.3} s", start.elapsed().as_secs_f64());
    let theirs = report("Embree", &embree, set, args);
    let ratio = |a: RayRate, b: RayRate| a.rays_per_second() / b.rays_per_second();
    println!("relume / Embree: closest hit {:.2}x, shadow {:.2}x", ratio(ours.0, theirs.0), ratio(ours.1, theirs.1));
    let (closest, shadow) = relume_bake::ray_bench::agreement(bvh, &embree, set, 1e-4);
    println!("answered alike: {closest} of {} closest-hit rays, {shadow} of {} shadow rays", set.closest.len(), set.shadow.len());
    Ok(())
}

fn subdivided(scene: Scene, k: u32) -> Result<Scene> {
    if k == 1 {
        return Ok(scene);
    }
    let tessellation = Tessellation::uniform(&scene, k).map_err(|e| anyhow!("--subdivide: {e}"))?;
    Ok(tessellation.apply(&scene))
}

fn report(name: &str, caster: &impl RayCaster, set: &RaySet, args: &RaysArgs) -> (RayRate, RayRate) {
    let (closest, shadow) = time_rays(caster, set, args.threads, args.repeats);
    println!(
        "{name}: closest hit {:.2} M rays/s ({} of {} hit), shadow {:.2} M rays/s ({} of {} blocked)",
        closest.rays_per_second() * 1e-6,
        closest.hits,
        set.closest.len(),
        shadow.rays_per_second() * 1e-6,
        shadow.hits,
        set.shadow.len()
    );
    (closest, shadow)
}
