//! `relume`: the command-line program. Each subcommand is a thin user of the libraries:
//! `bake` (scenes, reference path tracer, metrics, bakers) and `renderer` (Vulkan), and of
//! the method registry (`methods`), which is the only place that knows any method.

use anyhow::Result;
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Counts each thread's heap allocations (one increment each), so that `relume view` can show
/// its idle window allocates nothing.
#[global_allocator]
static ALLOCATOR: relume_viewer::CountingAllocator = relume_viewer::CountingAllocator;

mod args;
mod bake;
mod bench;
mod gpu;
mod lights;
mod methods;
mod rays;
mod reference;
mod render;
mod report;
mod shards;
mod slurm;
mod view;

#[derive(Parser)]
#[command(name = "relume", version, about = "Precomputed lighting, measured against a path tracer")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Precompute a method's data for a scene into a bake artifact folder.
    Bake(bake::BakeCommand),
    /// Render a scene with the Vulkan renderer (headless) to EXR and PNG.
    Render(render::RenderArgs),
    /// Render the ground truth with the CPU path tracer to a layered EXR (direct, indirect, combined).
    Reference(reference::ReferenceArgs),
    /// Compare two EXR images: RMSE, NRMSE and a false-colour error image.
    Compare(reference::CompareArgs),
    /// The main job: every method that suits the scene, baked, rendered with Vulkan and
    /// compared with the reference; images and a report.
    Run(report::RunArgs),
    /// Run a sweep (scenes x methods x parameters x lights, from a TOML file): costs and
    /// errors of every point, CSV/JSON, charts with the Pareto front, report.md.
    Bench(bench::BenchArgs),
    /// Chart bakes' time and peak memory against their scenes' triangles, log-log, with each
    /// series' fitted exponent (the scale sweep's chart).
    Scaling(bench::scaling::ScalingArgs),
    /// Time ray casting on a scene: BVH build, closest-hit and shadow rays per second on a
    /// path tracer's rays (and Embree's on the same rays where relume was built with it).
    Rays(rays::RaysArgs),
    /// Write the lights a scene is lit by (its punctual lights, those of --lights, or the
    /// default rig of a scene without light) as a lights file to edit and give back with
    /// --lights.
    Lights(lights::LightsArgs),
    /// Open a window on a scene: move the camera and the lights, switch between the methods
    /// of the bakes given (and those without a bake), see each pass's GPU time, and trace the
    /// reference of the view on demand (keys and overlay: relume-viewer; F1 shows the keys).
    View(view::ViewArgs),
    /// List the methods and their parameters (bake and run time, with ranges and defaults).
    Methods {
        /// One method's name (default: every method).
        #[arg(value_parser = methods::method_name)]
        name: Option<String>,
    },
    /// Regenerate the shipped scenes (scenes/*.gltf) from their generator.
    Scenes {
        #[arg(long, default_value = "scenes")]
        out: PathBuf,
        /// Write only the scale scene of K x K bays, `scale-K` (1..=32: 10,368 furniture
        /// triangles and about 15,000 covered lightmap texels a bay), instead of the committed scenes.
        #[arg(long, value_name = "K")]
        scale: Option<u32>,
        /// With --scale: the hall without its ceiling under the sky (`scale-K-sky`, and
        /// envs/sky.exr), for the methods of environment light.
        #[arg(long, requires = "scale")]
        sky: bool,
    },
}

fn main() -> ExitCode {
    end_quietly_when_stdout_closes();
    remove_unfinished_outputs_when_interrupted();
    // Every file the command reads is refused as one of its outputs.
    let _inputs = relume_bake::inputs::track();
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::FAILURE
        }
    }
}

/// Rust ignores SIGPIPE, so `relume compare a b | head -1` would panic in `println!` once
/// `head` exits; restoring the default action ends the program quietly, as Unix tools do.
fn end_quietly_when_stdout_closes() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is a valid action.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Ctrl-C, SIGTERM or SIGHUP: every output not yet committed is removed (what was there
/// before stays), then relume exits with 130, as a shell reports an interrupted command.
fn remove_unfinished_outputs_when_interrupted() {
    let handler = || {
        relume_bake::outputs::remove_unfinished();
        eprintln!("relume: interrupted; outputs not yet moved in place were removed (none is left half-written)");
        // _exit, not exit: the main thread may be inside Vulkan or a worker pool, and exit's
        // destructors must not run under it.
        // SAFETY: ends the process; nothing after it runs.
        unsafe { libc::_exit(130) };
    };
    if let Err(e) = ctrlc::set_handler(handler) {
        eprintln!("relume: warning: cannot handle interrupts ({e}); an interrupted run may leave hidden temporary files");
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Bake(args) => bake::bake_command(&args),
        Command::Render(args) => render::render_command(&args),
        Command::Reference(args) => reference::reference_command(&args),
        Command::Compare(args) => reference::compare_command(&args),
        Command::Run(args) => report::run_main_job(&args),
        Command::Bench(args) => bench::bench_command(&args),
        Command::Scaling(args) => bench::scaling::scaling_command(&args),
        Command::Rays(args) => rays::rays_command(&args),
        Command::Lights(args) => lights::lights_command(&args),
        Command::View(args) => view::view_command(&args),
        Command::Methods { name } => {
            let listed = match name {
                Some(name) => vec![methods::find(&name)?],
                None => methods::METHODS.to_vec(),
            };
            for method in listed {
                print!("{}", methods::params::describe(method));
            }
            Ok(())
        }
        Command::Scenes { out, scale, sky } => {
            let written = match scale {
                Some(bays) => relume_tools::scenegen::write_scale(&out, bays, sky)?,
                None => relume_tools::scenegen::write_all(&out)?,
            };
            for path in written {
                println!("wrote {}", path.display());
            }
            Ok(())
        }
    }
}
