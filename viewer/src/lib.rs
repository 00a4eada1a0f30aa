//! `relume view`: an interactive lighting-design window, and relume's first real integrator.
//! The viewer owns everything an engine owns (the window, its own Vulkan instance, device and
//! queue, the swapchain, the frame loop, its command buffer and fence, the overlay) and uses
//! relume only through the library's public API: `Context::from_existing` on its device,
//! `Renderer::new_blocking`, `set_lights` / `move_lights`, `set_camera`, `record_to` into its
//! own image, `timings`. docs/ARCHITECTURE.md points here as the integrator example.
//!
//! Layers: `device` and `swapchain` hold the viewer's own unsafe Vulkan (as an engine's
//! backend would); `presenter` records and submits a window frame; `overlay` is egui;
//! `camera`, `script` and `truth` are plain Rust; `app` is the event loop that ties them (its
//! input and its script's steps in files of their own).

mod alloc;
mod app;
mod camera;
mod device;
mod overlay;
mod presenter;
pub mod script;
mod swapchain;
mod truth;
mod ui;

pub use alloc::{allocations_on_this_thread, CountingAllocator};
pub use app::{run, Outcome};

use glam::Vec3;
use relume_bake::scene::Scene;
use relume_renderer::{MakeTechnique, RenderSettings};
use std::path::PathBuf;

/// A method the viewer can switch to: its scene as its techniques need it, and its techniques
/// (made again whenever the window's size or the number of lights changes).
pub trait MethodSource {
    fn scene(&self) -> &Scene;
    fn techniques(&self) -> Vec<Box<dyn MakeTechnique + '_>>;
}

pub struct ViewMethod {
    pub name: String,
    pub source: Box<dyn MethodSource>,
    /// The frame's ambient light with this method: I_A (lux) and beta.
    pub ambient: (Vec3, f32),
    /// Whether I_A adds the scene's environment (`RenderSettings::environment_ambient`).
    pub environment_ambient: bool,
}

pub struct ViewOptions {
    /// The frame's settings; width and height are the window's first inner size.
    pub settings: RenderSettings,
    pub validation: bool,
    /// A device index or part of its name.
    pub device: Option<String>,
    /// Steps to replay, one a frame; the window closes after the last unless it says so.
    pub script: Option<Vec<script::Step>>,
    /// Where the save key writes the lights (a lights file every command reads with --lights).
    pub lights_file: PathBuf,
    /// Lines to show on screen from the start (how the scene was lit, what was refused).
    pub notes: Vec<String>,
}
