//! `relume render`: one scene through the Vulkan renderer, headless, to EXR and PNG, with the
//! techniques of the method that baked `--bake` (or none: constant ambient light).

use crate::args::{load_scene, refuse_exr_and_png_over, render_settings, GpuArgs, SceneArgs, FRAMES};
use crate::gpu::{print_timings, render_on_gpu, write_render_outputs, GpuJob};
use crate::methods;
use crate::methods::params::{RenderParams, Stage};
use anyhow::{bail, Result};
use clap::Args;
use relume_bake::artifact::Artifact;
use relume_bake::outputs::Outputs;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub(crate) struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    /// Output EXR; a tonemapped PNG is written beside it.
    #[arg(long, short, default_value = "render.exr")]
    out: PathBuf,
    /// Render this many frames and report the median GPU time of every pass.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(FRAMES))]
    frames: u32,
    /// A bake artifact folder (`relume bake --out`): the method that baked it renders, with
    /// its own ambient light unless --ambient or --beta say otherwise. Without one: direct light
    /// plus the scene's constant ambient light.
    #[arg(long)]
    bake: Option<PathBuf>,
    #[command(flatten)]
    params: RenderParams,
}

pub(crate) fn render_command(args: &RenderArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let frames = args.frames;
    let artifact = args.bake.as_deref().map(Artifact::read).transpose()?;
    refuse_exr_and_png_over(&args.out)?;
    let method = match &artifact {
        Some(artifact) => methods::of_bake(artifact, args.bake.as_deref().unwrap_or(Path::new("")))?,
        None => {
            if let Some((name, _)) = args.params.pairs.first() {
                bail!("--{name}: a run-time parameter of {}; render a bake of it (--bake)", methods::takers(name).join(", "));
            }
            methods::WITHOUT_BAKE
        }
    };
    let values = methods::parse_values(method, &args.params.pairs, Some(Stage::Render))?;
    let loaded = methods::load(method, artifact.as_ref(), &scene, &values)?;
    if let Some(missed) = methods::misses(method, &scene) {
        eprintln!("warning: {}: {missed}", scene.source.display());
    }
    let settings = render_settings(&args.scene, &args.gpu, method.ambient(&scene), method.environment_ambient())?;
    let (renders, device) = render_on_gpu(&[GpuJob { loaded: loaded.as_ref(), settings, frames }], &args.gpu)?;
    let mut outputs = Outputs::new();
    write_render_outputs(&mut outputs, &args.out, &renders[0])?;
    outputs.commit()?;
    println!("wrote {} and {}", args.out.display(), args.out.with_extension("png").display());
    println!("device: {device}");
    for (work, ms) in &renders[0].creation_ms {
        println!("{work} (once, at creation): {ms:.3} ms");
    }
    print_timings(&renders[0].frames);
    Ok(())
}
