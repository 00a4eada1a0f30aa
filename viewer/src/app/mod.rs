//! The event loop: winit's events drive the camera, the lights and the method; a frame is
//! drawn only when something changed (the loop sleeps in `ControlFlow::Wait` otherwise), and
//! a script, when given, replays one step a frame.

use crate::camera::CameraControl;
use crate::device::{Device, Messages};
use crate::overlay::Overlay;
use crate::presenter::Presenter;
use crate::script::Step;
use crate::swapchain::{Fit, Swapchain};
use crate::truth::Truth;
use crate::ui::{self, Action, Panel};
use crate::{ViewMethod, ViewOptions};
use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use glam::Vec3;
use relume_bake::image::Image as HdrImage;
use relume_bake::scene::{Light, Scene};
use relume_renderer::vk::{Context, Readback};
use relume_renderer::{FrameTimings, RenderSettings, Renderer};
use std::collections::VecDeque;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::ModifiersState;
use winit::window::{Window, WindowId};

mod input;
mod scripted;

/// How a session ended.
pub struct Outcome {
    pub frames: u64,
    /// The validation layer's messages over the whole session, teardown included.
    pub validation_messages: Vec<String>,
}

/// Opens the window and runs until it is closed (or the script ends). Without a display: one
/// error saying so.
pub fn run(methods: Vec<ViewMethod>, options: ViewOptions) -> Result<Outcome> {
    if methods.is_empty() {
        bail!("no method to view");
    }
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!(
            "cannot open a window: no display ({e}); run it in a desktop session, or set DISPLAY (X11, e.g. under Xvfb) or WAYLAND_DISPLAY"
        )
    })?;
    let mut app = App::new(methods, options);
    event_loop.run_app(&mut app).context("the window's event loop")?;
    app.gpu = None;
    if let Some(error) = app.error.take() {
        return Err(error);
    }
    let validation_messages = app.messages.as_ref().map(|m| m.lock().map(|m| m.clone()).unwrap_or_default()).unwrap_or_default();
    Ok(Outcome { frames: app.frames, validation_messages })
}

/// Everything on the device, dropped top to bottom after the queue is idle.
struct Gpu {
    renderer: Renderer,
    /// The live frame's radiance, read back while a reference is shown (for its NRMSE).
    radiance: Readback,
    presenter: Presenter,
    overlay: Overlay,
    swapchain: Swapchain,
    ctx: Arc<Context>,
    device: Device,
}

impl Drop for Gpu {
    fn drop(&mut self) {
        let _ = self.device.wait_queue_idle();
    }
}

enum Wait {
    /// Until this many frames are drawn; each frame's interval and GPU time (ms) meanwhile.
    Frames(u64, Vec<(f64, f64)>),
    /// Until this instant, from this many frames and allocations.
    Idle(Instant, u64, u64),
    /// Until the swapchain has this size, asked for at that instant.
    Size(u32, u32, Instant),
    Reference,
    Screenshot,
}

#[derive(Clone, Copy)]
enum Drag {
    Orbit,
    Pan,
    Light(usize, bool),
}

struct App {
    methods: Vec<ViewMethod>,
    options: ViewOptions,
    active: usize,
    lights: Vec<Light>,
    camera: CameraControl,
    selected: Option<usize>,
    gpu: Option<Gpu>,
    window: Option<Window>,
    messages: Option<Messages>,
    /// What the next frame must do first: make the renderer again (method, size or light
    /// count changed), move the lights.
    remake: bool,
    /// The swapchain is out of date or suboptimal: make it again before the next frame.
    stale: bool,
    /// The window size the swapchain was last made for.
    built_for: vk::Extent2D,
    lights_moved: bool,
    dirty: bool,
    overlay_visible: bool,
    cursor: PhysicalPosition<f64>,
    drag: Option<Drag>,
    modifiers: ModifiersState,
    script: Option<VecDeque<Step>>,
    waiting: Option<Wait>,
    capture: Option<std::path::PathBuf>,
    truth: Option<Truth>,
    truth_samples: u32,
    /// The reference shown, its texture, and the live frame's NRMSE against it.
    shown_truth: Option<ui::Truth>,
    /// The live frame's radiance as last read, kept to be refilled (made again only for a new
    /// size), so that comparing with a reference allocates nothing per frame.
    live: HdrImage,
    frames: u64,
    /// When a scripted light change happened, until the frame that shows it has finished.
    latency_from: Option<Instant>,
    /// Whether the renderer has drawn a frame whose timings are still to read.
    drawn: bool,
    timings: FrameTimings,
    last_frame: Option<Instant>,
    frame_ms: f64,
    device_name: String,
    notes: Vec<String>,
    error: Option<anyhow::Error>,
}

impl App {
    fn new(methods: Vec<ViewMethod>, options: ViewOptions) -> App {
        let scene = methods[0].source.scene();
        let camera = CameraControl::new(scene.camera, scene.bounds());
        let lights = scene.lights.clone();
        let script = options.script.clone().map(VecDeque::from);
        let notes = options.notes.clone();
        App {
            methods,
            options,
            active: 0,
            lights,
            camera,
            selected: None,
            gpu: None,
            window: None,
            messages: None,
            remake: false,
            stale: false,
            built_for: vk::Extent2D::default(),
            lights_moved: false,
            dirty: true,
            overlay_visible: true,
            cursor: PhysicalPosition::default(),
            drag: None,
            modifiers: ModifiersState::empty(),
            script,
            waiting: None,
            capture: None,
            truth: None,
            truth_samples: 0,
            shown_truth: None,
            live: HdrImage::new(0, 0),
            frames: 0,
            drawn: false,
            latency_from: None,
            timings: FrameTimings::default(),
            last_frame: None,
            frame_ms: 0.0,
            device_name: String::new(),
            notes,
            error: None,
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: anyhow::Error) {
        self.error.get_or_insert(error);
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let s = &self.options.settings;
        let title = format!("relume view: {}", self.methods[0].source.scene().source.display());
        let attributes = Window::default_attributes().with_title(title).with_inner_size(PhysicalSize::new(s.width, s.height));
        let window = event_loop.create_window(attributes).context("cannot create the window")?;
        let device = Device::new(&window, self.options.validation, self.options.device.as_deref())?;
        self.messages = Some(device.message_log());
        let ctx = device.relume_context()?;
        let size = window.inner_size();
        let swapchain = Swapchain::new(&device, vk::Extent2D { width: size.width.max(1), height: size.height.max(1) }, None)?;
        let overlay = Overlay::new(&window, &device, swapchain.format)?;
        let presenter = Presenter::new(&ctx, &device, swapchain.extent)?;
        let renderer = self.make_renderer(&ctx, swapchain.extent)?;
        let radiance = Readback::for_image(&ctx, "live radiance", renderer.radiance())?;
        eprintln!("relume view: {} on {}", self.methods[self.active].name, device.name);
        self.device_name = device.name.clone();
        self.built_for = vk::Extent2D { width: size.width, height: size.height };
        self.gpu = Some(Gpu { renderer, radiance, presenter, overlay, swapchain, ctx, device });
        self.window = Some(window);
        Ok(())
    }

    /// The active method's renderer at `extent`, with the lights and camera as they are now.
    fn make_renderer(&self, ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Renderer> {
        let method = &self.methods[self.active];
        let mut scene: Scene = method.source.scene().clone();
        scene.lights = self.lights.clone();
        let settings = RenderSettings {
            width: extent.width,
            height: extent.height,
            ambient: method.ambient.0,
            beta: method.ambient.1,
            environment_ambient: method.environment_ambient,
            ..self.options.settings.clone()
        };
        let techniques = method.source.techniques();
        let techniques: Vec<&dyn relume_renderer::MakeTechnique> = techniques.iter().map(|t| t.as_ref()).collect();
        let mut renderer =
            Renderer::new_blocking(ctx, &scene, &settings, &techniques).with_context(|| format!("method {}", method.name))?;
        renderer.set_camera(self.camera.camera);
        Ok(renderer)
    }

    /// One window frame, if the window has an area.
    fn draw(&mut self) -> Result<()> {
        let Some(size) = self.window.as_ref().map(Window::inner_size) else { return Ok(()) };
        if size.width == 0 || size.height == 0 || self.gpu.is_none() {
            return Ok(());
        }
        self.finish_last_frame()?;
        let wanted = vk::Extent2D { width: size.width, height: size.height };
        if self.stale || wanted != self.built_for {
            self.rebuild_swapchain(wanted)?;
        }
        if self.remake {
            self.remake_renderer()?;
        }
        let gpu = self.gpu.as_mut().expect("checked above");
        let (fit, index) = gpu.swapchain.acquire()?;
        if fit == Fit::OutOfDate {
            (self.stale, self.dirty) = (true, true);
            return Ok(());
        }
        let now = Instant::now();
        let seconds = self.last_frame.map_or(0.0, |t| (now - t).as_secs_f32());
        self.frame_ms = seconds as f64 * 1e3;
        self.last_frame = Some(now);
        gpu.renderer.set_camera(self.camera.camera);
        if std::mem::take(&mut self.lights_moved) {
            gpu.renderer.move_lights(&self.lights, seconds.min(0.1))?;
        }
        let actions = self.prepare_overlay()?;
        let gpu = self.gpu.as_mut().expect("checked above");
        let read_live = self.shown_truth.is_some();
        let (visible, overlay) = (self.overlay_visible, &mut gpu.overlay);
        let mut draw = |cmd, extent| overlay.draw(cmd, extent);
        let draw_overlay: Option<crate::presenter::DrawOverlay> = if visible { Some(&mut draw) } else { None };
        let radiance = read_live.then_some(&gpu.radiance);
        gpu.presenter.frame(&mut gpu.renderer, &gpu.swapchain, index, draw_overlay, self.capture.is_some(), radiance)?;
        if gpu.swapchain.present(gpu.device.queue, index)? == Fit::OutOfDate {
            (self.stale, self.dirty) = (true, true);
        }
        self.frames += 1;
        self.drawn = true;
        if self.latency_from.is_some() || self.capture.is_some() || read_live {
            self.after_frame(read_live)?;
        }
        for action in actions {
            self.apply(action)?;
        }
        Ok(())
    }

    /// Waits for the frame in flight and reads its timings (a new renderer has none to read).
    fn finish_last_frame(&mut self) -> Result<()> {
        let gpu = self.gpu.as_mut().expect("drawn with a device");
        gpu.presenter.wait()?;
        if std::mem::take(&mut self.drawn) {
            self.timings = gpu.renderer.timings()?;
            if let Some(Wait::Frames(_, times)) = &mut self.waiting {
                times.push((self.frame_ms, self.timings.total_ms()));
            }
        }
        Ok(())
    }

    /// What needs the frame just submitted finished: the latency of a scripted light change,
    /// a screenshot, the live NRMSE against the reference shown.
    fn after_frame(&mut self, read_live: bool) -> Result<()> {
        let gpu = self.gpu.as_mut().expect("drawn with a device");
        gpu.presenter.wait()?;
        if let Some(changed) = self.latency_from.take() {
            eprintln!("relume view: light change to finished frame: {:.1} ms", changed.elapsed().as_secs_f64() * 1e3);
        }
        if let Some(path) = self.capture.take() {
            let rgba = gpu.presenter.screenshot(&gpu.swapchain)?;
            write_png(&path, gpu.swapchain.extent, &rgba)?;
            eprintln!("relume view: wrote {}", path.display());
            if matches!(self.waiting, Some(Wait::Screenshot)) {
                self.waiting = None;
            }
        }
        if read_live {
            self.read_live()?;
        }
        Ok(())
    }

    /// A swapchain for the window's size (or because the old one is out of date); the
    /// renderer follows when the size changed. Waits for the queue: only on a resize.
    fn rebuild_swapchain(&mut self, wanted: vk::Extent2D) -> Result<()> {
        let gpu = self.gpu.as_mut().expect("drawn with a device");
        gpu.device.wait_queue_idle()?;
        let swapchain = Swapchain::new(&gpu.device, wanted, Some(&gpu.swapchain))?;
        gpu.swapchain = swapchain;
        let extent = gpu.swapchain.extent;
        let settings = gpu.renderer.settings();
        if (settings.width, settings.height) != (extent.width, extent.height) {
            gpu.presenter.resize(extent)?;
            self.remake = true;
            self.view_changed();
        }
        (self.built_for, self.stale) = (wanted, false);
        Ok(())
    }

    /// The renderer again, for another method, size or number of lights; waits for the queue.
    fn remake_renderer(&mut self) -> Result<()> {
        let gpu = self.gpu.as_mut().expect("drawn with a device");
        gpu.device.wait_queue_idle()?;
        let (ctx, extent) = (Arc::clone(&gpu.ctx), gpu.swapchain.extent);
        let renderer = self.make_renderer(&ctx, extent)?;
        let gpu = self.gpu.as_mut().expect("drawn with a device");
        gpu.radiance = Readback::for_image(&ctx, "live radiance", renderer.radiance())?;
        gpu.renderer = renderer;
        (self.drawn, self.remake, self.lights_moved) = (false, false, false);
        Ok(())
    }

    /// The frame's radiance (its fence has signalled), and its NRMSE against the reference
    /// shown; a new value is drawn once more, so the panel never shows an older frame's.
    fn read_live(&mut self) -> Result<()> {
        let gpu = self.gpu.as_ref().expect("drawn with a device");
        let floats = gpu.radiance.floats()?;
        let (w, h) = (gpu.swapchain.extent.width, gpu.swapchain.extent.height);
        if (self.live.width, self.live.height) != (w, h) {
            self.live = HdrImage::new(w, h);
        }
        for (p, rgba) in self.live.pixels.iter_mut().zip(floats.chunks_exact(4)) {
            *p = Vec3::new(rgba[0], rgba[1], rgba[2]);
        }
        if let Some(shown) = self.shown_truth.as_mut() {
            let nrmse = relume_bake::metrics::compare(&self.live, &shown.image).ok().map(|e| e.nrmse);
            self.dirty |= nrmse != shown.live_nrmse;
            shown.live_nrmse = nrmse;
        }
        Ok(())
    }

    fn prepare_overlay(&mut self) -> Result<Vec<Action>> {
        if !self.overlay_visible {
            return Ok(Vec::new());
        }
        let panel = Panel {
            methods: self.methods.iter().map(|m| m.name.as_str()).collect(),
            active: self.active,
            device: &self.device_name,
            timings: &self.timings,
            frame_ms: self.frame_ms,
            lights: &self.lights,
            selected: self.selected,
            notes: &self.notes,
            truth: self.shown_truth.as_ref(),
            tracing: self.truth.as_ref().map(|t| (self.truth_samples, t.target())),
        };
        let mut actions = Vec::new();
        let (gpu, window) = (self.gpu.as_mut().expect("drawn with a device"), self.window.as_ref().expect("open"));
        let again = gpu.overlay.prepare(window, |ctx| actions = ui::panel(ctx, &panel))?;
        self.dirty |= again;
        Ok(actions)
    }

    fn apply(&mut self, action: Action) -> Result<()> {
        match action {
            Action::Method(index) => self.switch_method(index),
            Action::Select(index) => self.selected = index,
            Action::Light(index, light) => {
                self.lights[index] = light;
                self.lights_changed();
            }
            Action::StartTruth => self.start_truth(256),
            Action::StopTruth => self.truth = None,
            Action::SaveLights => self.save_lights_noting(),
        }
        self.dirty = true;
        Ok(())
    }

    fn switch_method(&mut self, index: usize) {
        if index < self.methods.len() && index != self.active {
            self.active = index;
            self.remake = true;
            self.dirty = true;
            eprintln!("relume view: {}", self.methods[index].name);
        }
    }

    /// The reference of the view stays valid across a method switch (that is the point) and
    /// is dropped when what it shows changes.
    fn view_changed(&mut self) {
        self.truth = None;
        self.shown_truth = None;
        self.dirty = true;
    }

    fn lights_changed(&mut self) {
        if self.script.is_some() {
            self.latency_from = Some(Instant::now());
        }
        self.lights_moved = true;
        self.view_changed();
    }

    fn start_truth(&mut self, samples: u32) {
        let Some(gpu) = self.gpu.as_ref() else { return };
        let mut scene = self.methods[self.active].source.scene().clone();
        scene.lights = self.lights.clone();
        scene.camera = self.camera.camera;
        let extent = gpu.swapchain.extent;
        self.truth = Some(Truth::start(scene, extent.width, extent.height, samples));
        self.truth_samples = 0;
        self.dirty = true;
    }

    /// Takes the reference's newest pass when there is one.
    fn poll_truth(&mut self) {
        let Some(progress) = self.truth.as_ref().and_then(Truth::latest) else { return };
        if progress.samples != self.truth_samples {
            self.truth_samples = progress.samples;
            self.shown_truth = Some(ui::Truth::new(progress.image, progress.samples, self.options.settings.exposure));
            self.dirty = true;
        }
    }

    fn save_lights(&mut self, path: &Path) -> Result<()> {
        let mut outputs = relume_bake::outputs::Outputs::new();
        outputs.bytes(path, relume_bake::lights_file::to_json(&self.lights).as_bytes())?;
        outputs.commit()?;
        let note = format!("saved the lights to {} (give it to any command with --lights)", path.display());
        eprintln!("relume view: {note}");
        self.notes.push(note);
        Ok(())
    }

    /// Saves the lights to `--save-lights`; a failure is a note on screen, not the end of the
    /// session (its edits would be lost).
    fn save_lights_noting(&mut self) {
        if let Err(e) = self.save_lights(&self.options.lights_file.clone()) {
            let note = format!("could not save the lights: {e:#}");
            eprintln!("relume view: {note}");
            self.notes.push(note);
        }
    }
}

fn write_png(path: &Path, extent: vk::Extent2D, rgba: &[u8]) -> Result<()> {
    let rgb: Vec<u8> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    let mut outputs = relume_bake::outputs::Outputs::new();
    relume_bake::image::write_png_rgb8(&mut outputs, path, extent.width, extent.height, &rgb)?;
    outputs.commit()?;
    Ok(())
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            if let Err(e) = self.open(event_loop) {
                self.fail(event_loop, e);
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let (Some(window), Some(gpu)) = (self.window.as_ref(), self.gpu.as_mut()) else { return };
        let taken = self.overlay_visible && gpu.overlay.on_event(window, &event);
        if taken {
            self.dirty = true;
        }
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::RedrawRequested => self.draw(),
            WindowEvent::Resized(_) | WindowEvent::ScaleFactorChanged { .. } => {
                self.dirty = true;
                Ok(())
            }
            WindowEvent::ModifiersChanged(m) => {
                self.modifiers = m.state();
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } if !taken && event.state == ElementState::Pressed => self.key(&event.logical_key),
            WindowEvent::MouseInput { .. } | WindowEvent::CursorMoved { .. } | WindowEvent::MouseWheel { .. }
                if !taken || self.drag.is_some() =>
            {
                self.pointer(&event);
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_none() || self.error.is_some() {
            return;
        }
        self.poll_truth();
        if let Err(e) = self.step_script(event_loop) {
            self.fail(event_loop, e);
            return;
        }
        if std::mem::take(&mut self.dirty) {
            if let Some(window) = &self.window {
                window.request_redraw();
            }
        }
        // Asleep until an event, or polling a reference under way a few times a second.
        let tracing = self.truth.as_ref().is_some_and(|t| !t.finished());
        event_loop.set_control_flow(match (&self.waiting, tracing) {
            (Some(Wait::Idle(until, ..)), _) => ControlFlow::WaitUntil(*until),
            (_, true) => ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(100)),
            _ => ControlFlow::Wait,
        });
    }
}
