//! `relume lights`: the lights a scene is lit by, as a lights file to edit and give back with
//! `--lights` (the format: docs/FORMATS.md, "Lights file").

use crate::args::{load_scene, refuse_writing_over, SceneArgs};
use anyhow::{bail, Result};
use clap::Args;
use relume_bake::lights_file;
use relume_bake::outputs::Outputs;
use std::path::PathBuf;

#[derive(Args)]
pub(crate) struct LightsArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Write the lights file here (default: print it).
    #[arg(long, short)]
    out: Option<PathBuf>,
}

pub(crate) fn lights_command(args: &LightsArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    refuse_writing_over(args.out.as_slice())?;
    if scene.lights.is_empty() {
        bail!("{}: has no punctual light (it is lit by emission or its environment alone); nothing to write", args.scene.scene.display());
    }
    let text = lights_file::to_json(&scene.lights);
    match &args.out {
        None => print!("{text}"),
        Some(path) => {
            let mut outputs = Outputs::new();
            outputs.bytes(path, text.as_bytes())?;
            outputs.commit()?;
            eprintln!("wrote {} ({} lights)", path.display(), scene.lights.len());
        }
    }
    Ok(())
}
