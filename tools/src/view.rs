//! `relume view`: the interactive window (relume-viewer). Here the registry turns the scene and
//! the bakes given into the methods the window switches between: every method that needs no
//! bake and suits the scene, then each bake's method; the viewer itself knows no method.

use crate::args::{load_scene_noting, refuse_writing_over, render_settings, GpuArgs, SceneArgs};
use crate::methods::{self, Loaded, Method};
use anyhow::{bail, Context as _, Result};
use clap::Args;
use relume_bake::artifact::Artifact;
use relume_bake::scene::Scene;
use relume_renderer::MakeTechnique;
use relume_viewer::{MethodSource, ViewMethod, ViewOptions};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub(crate) struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    /// A bake artifact folder (`relume bake --out`); give it again for more methods. Methods
    /// without a bake (direct, constant) are always there.
    #[arg(long)]
    bake: Vec<PathBuf>,
    /// Replay the steps of this file, one a frame, then close (relume-viewer's script: method,
    /// light, size, overlay, orbit, reference, frames, screenshot, save-lights, quit).
    #[arg(long)]
    script: Option<PathBuf>,
    /// Where Ctrl+S (and the overlay's button) saves the lights, as a lights file for --lights.
    #[arg(long, default_value = "lights.json")]
    save_lights: PathBuf,
}

/// A loaded method as the viewer takes it.
struct Source(Box<dyn Loaded>);

impl MethodSource for Source {
    fn scene(&self) -> &Scene {
        self.0.scene()
    }

    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>> {
        self.0.techniques()
    }
}

pub(crate) fn view_command(args: &ViewArgs) -> Result<()> {
    let script = args.script.as_deref().map(relume_viewer::script::read).transpose()?;
    let (scene, notes) = load_scene_noting(&args.scene)?;
    let mut methods = Vec::new();
    let none = methods::params::Values::default();
    for method in methods::METHODS.iter().filter(|m| !m.bakes() && methods::suits(**m, &scene)) {
        methods.push(view_method(*method, methods::load(*method, None, &scene, &none)?, &scene, args)?);
    }
    for bake in &args.bake {
        let artifact = Artifact::read(bake)?;
        let method = methods::of_bake(&artifact, bake)?;
        let values = methods::parse_values(method, &[], Some(methods::params::Stage::Render))?;
        let loaded = methods::load(method, Some(&artifact), &scene, &values).with_context(|| format!("--bake {}", bake.display()))?;
        methods.push(view_method(method, loaded, &scene, args)?);
    }
    if methods.is_empty() {
        bail!("{}: no method renders this scene without a bake; give one with --bake", args.scene.scene.display());
    }
    // Script steps that would write over an input are refused before any window opens.
    let script_outputs: Vec<PathBuf> = script.iter().flatten().filter_map(|s| s.output()).map(Path::to_path_buf).collect();
    refuse_writing_over(&script_outputs).with_context(|| format!("{}", args.script.as_deref().unwrap_or(Path::new("")).display()))?;
    let settings = render_settings(&args.scene, &args.gpu, None, false)?;
    let options = ViewOptions {
        settings,
        validation: args.gpu.validation,
        device: args.gpu.device.clone().or_else(|| std::env::var("RELUME_DEVICE").ok()),
        script,
        lights_file: args.save_lights.clone(),
        notes,
    };
    let outcome = relume_viewer::run(methods, options)?;
    if args.gpu.validation {
        if let Some(first) = outcome.validation_messages.first() {
            bail!("{} Vulkan validation message(s), first: {first}", outcome.validation_messages.len());
        }
        println!("{} frames, 0 validation messages", outcome.frames);
    }
    Ok(())
}

fn view_method(method: &dyn Method, loaded: Box<dyn Loaded>, scene: &Scene, args: &ViewArgs) -> Result<ViewMethod> {
    let settings = render_settings(&args.scene, &args.gpu, method.ambient(scene), method.environment_ambient())?;
    Ok(ViewMethod {
        name: method.name().to_string(),
        source: Box::new(Source(loaded)),
        ambient: (settings.ambient, settings.beta),
        environment_ambient: settings.environment_ambient,
    })
}
