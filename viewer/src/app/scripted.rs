//! A script's steps (crate::script), one a frame: what a user does, replayed, and the waits
//! between steps (frames, a size, a reference, a screenshot, an idle spell).

use super::input::set_cone;
use super::{App, Wait};
use crate::script::Step;
use crate::truth::Truth;
use anyhow::{anyhow, bail, Result};
use relume_bake::scene::Light;
use std::collections::VecDeque;
use std::time::{Duration, Instant};
use winit::dpi::PhysicalSize;
use winit::event_loop::ActiveEventLoop;

impl App {
    /// The next script step, when the one before is done.
    pub(super) fn step_script(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let done = match &self.waiting {
            None => true,
            Some(Wait::Frames(until, times)) => {
                let done = self.frames >= *until;
                if done && times.len() > 1 {
                    report_frame_times(times);
                }
                done
            }
            Some(Wait::Size(w, h, asked)) => {
                let size = self.gpu.as_ref().map(|g| (g.swapchain.extent.width, g.swapchain.extent.height));
                if size != Some((*w, *h)) && asked.elapsed() > Duration::from_secs(10) {
                    bail!("script: size {w} {h}: the window system kept the window at {size:?} for 10 s");
                }
                size == Some((*w, *h))
            }
            Some(Wait::Reference) if self.truth.is_none() => {
                bail!("script: reference: the reference was dropped (the view changed) before it finished")
            }
            Some(Wait::Reference) => self.reference_compared(),
            Some(Wait::Screenshot) => false,
            Some(Wait::Idle(until, frames, allocations)) => {
                if Instant::now() < *until {
                    return Ok(());
                }
                let allocations = crate::alloc::allocations_on_this_thread() - allocations;
                eprintln!("relume view: idle: {} frame(s), {allocations} heap allocation(s) on the window's thread", self.frames - frames);
                true
            }
        };
        if !done {
            self.dirty = true;
            return Ok(());
        }
        self.waiting = None;
        let Some(step) = self.script.as_mut().and_then(VecDeque::pop_front) else {
            if self.script.is_some() {
                event_loop.exit();
            }
            return Ok(());
        };
        self.dirty = true;
        self.run_step(event_loop, step)
    }

    /// Whether the reference asked for is finished and the live frame compared with it (said
    /// on stderr once).
    fn reference_compared(&self) -> bool {
        let finished = self.truth.as_ref().is_some_and(Truth::finished);
        match self.shown_truth.as_ref().and_then(|t| t.live_nrmse.map(|e| (t.samples, e))) {
            Some((samples, nrmse)) if finished => {
                eprintln!("relume view: reference of the view: {samples} spp, live NRMSE {nrmse:.4}");
                true
            }
            _ => false,
        }
    }

    fn run_step(&mut self, event_loop: &ActiveEventLoop, step: Step) -> Result<()> {
        fn light(lights: &mut [Light], i: usize) -> Result<&mut Light> {
            let count = lights.len();
            lights.get_mut(i).ok_or_else(|| anyhow!("script: light {i}: the scene has {count} light(s), numbered from 0"))
        }
        match step {
            Step::Method(name) => {
                let index = self.methods.iter().position(|m| m.name == name).ok_or_else(|| {
                    let names: Vec<&str> = self.methods.iter().map(|m| m.name.as_str()).collect();
                    anyhow!("script: method {name}: not open in this window (open: {})", names.join(", "))
                })?;
                self.switch_method(index);
            }
            Step::LightPosition(i, at) => {
                light(&mut self.lights, i)?.position = at;
                self.lights_changed();
            }
            Step::LightIntensity(i, intensity) => {
                light(&mut self.lights, i)?.intensity = intensity;
                self.lights_changed();
            }
            Step::LightCone(i, inner, outer) => {
                let l = light(&mut self.lights, i)?;
                set_cone(l, inner.to_radians(), outer.to_radians()).map_err(|e| anyhow!("script: light {i}: {e}"))?;
                self.lights_changed();
            }
            Step::Size(w, h) => {
                if let Some(window) = &self.window {
                    let _ = window.request_inner_size(PhysicalSize::new(w, h));
                }
                self.waiting = Some(Wait::Size(w, h, Instant::now()));
            }
            Step::Overlay(on) => self.overlay_visible = on,
            Step::Orbit(yaw, pitch) => {
                self.camera.orbit(yaw.to_radians(), pitch.to_radians());
                self.view_changed();
            }
            Step::Reference(samples) => {
                self.start_truth(samples);
                self.waiting = Some(Wait::Reference);
            }
            Step::Frames(n) => self.waiting = Some(Wait::Frames(self.frames + n as u64, Vec::with_capacity(n.min(10_000) as usize))),
            Step::Idle(ms) => {
                let until = Instant::now() + Duration::from_millis(ms as u64);
                self.waiting = Some(Wait::Idle(until, self.frames, crate::alloc::allocations_on_this_thread()));
                self.dirty = false;
            }
            Step::Screenshot(path) => {
                self.capture = Some(path);
                self.waiting = Some(Wait::Screenshot);
            }
            Step::SaveLights(path) => self.save_lights(&path)?,
            Step::Quit => event_loop.exit(),
        }
        Ok(())
    }
}

/// The median interval between frames (the window's frame time) and the median GPU time of
/// the frames a `frames` step drew (the first interval, from before the step, left out).
fn report_frame_times(times: &[(f64, f64)]) {
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let interval = median(times[1..].iter().map(|t| t.0).collect());
    let gpu = median(times[1..].iter().map(|t| t.1).collect());
    eprintln!("relume view: {} frames: median frame time {interval:.2} ms, GPU {gpu:.2} ms", times.len() - 1);
}
