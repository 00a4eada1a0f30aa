//! What the overlay shows and what its controls ask for: the method (switched from a list),
//! the device, the frame time and every pass's GPU time, the lights (select, intensity, spot
//! cone), the reference under way and the live frame's NRMSE against it, shown beside the
//! live image, and the keys.

use egui::{Color32, ColorImage, TextureHandle, TextureOptions};
use relume_bake::image::{tonemap_to_srgb8, Image};
use relume_bake::scene::{Light, LightKind};
use relume_renderer::FrameTimings;
use std::cell::OnceCell;
use std::sync::Arc;

/// What the panel reads, gathered before it is laid out.
pub struct Panel<'a> {
    pub methods: Vec<&'a str>,
    pub active: usize,
    pub device: &'a str,
    pub timings: &'a FrameTimings,
    pub frame_ms: f64,
    pub lights: &'a [Light],
    pub selected: Option<usize>,
    pub notes: &'a [String],
    pub truth: Option<&'a Truth>,
    /// Samples taken and asked for, while a reference is under way.
    pub tracing: Option<(u32, u32)>,
}

/// What a control asked for; the viewer applies it after the frame.
pub enum Action {
    Method(usize),
    Select(Option<usize>),
    Light(usize, Light),
    StartTruth,
    StopTruth,
    SaveLights,
}

/// The reference shown: its image, its texture (uploaded once, when first drawn) and the live
/// frame's NRMSE against it.
pub struct Truth {
    pub image: Arc<Image>,
    pub samples: u32,
    pub live_nrmse: Option<f64>,
    exposure: f32,
    texture: OnceCell<TextureHandle>,
}

impl Truth {
    pub fn new(image: Arc<Image>, samples: u32, exposure: f32) -> Truth {
        Truth { image, samples, live_nrmse: None, exposure, texture: OnceCell::new() }
    }

    fn texture(&self, ctx: &egui::Context) -> &TextureHandle {
        self.texture.get_or_init(|| {
            let pixels = self.image.pixels.iter().map(|p| {
                let [r, g, b] = tonemap_to_srgb8(*p, self.exposure);
                Color32::from_rgb(r, g, b)
            });
            // Every step-th pixel: shown at a third of the window, within egui's texture limit.
            let step = (self.image.width.max(self.image.height) as usize).div_ceil(1024);
            let (w, h) = (self.image.width as usize, self.image.height as usize);
            let pixels: Vec<Color32> = pixels.collect();
            let kept = (0..h).step_by(step).flat_map(|y| (0..w).step_by(step).map(move |x| y * w + x));
            let image = ColorImage::new([w.div_ceil(step), h.div_ceil(step)], kept.map(|i| pixels[i]).collect());
            ctx.load_texture("reference", image, TextureOptions::LINEAR)
        })
    }
}

pub fn panel(ctx: &egui::Context, p: &Panel) -> Vec<Action> {
    let mut actions = Vec::new();
    egui::Window::new("relume").default_pos([8.0, 8.0]).default_width(280.0).show(ctx, |ui| {
        method_list(ui, p, &mut actions);
        ui.label(format!("device: {}", p.device));
        times(ui, p);
        ui.separator();
        lights(ui, p, &mut actions);
        ui.separator();
        truth(ui, p, &mut actions);
        for note in p.notes {
            ui.colored_label(Color32::YELLOW, note);
        }
        ui.collapsing("keys", |ui| {
            ui.label("Tab / 1-9: method   drag: orbit   right drag: pan   wheel: dolly\nW A S D Q E: fly   R / Home: reset camera   F1: overlay\nclick a light: select   drag it: move (Shift: towards you)\n+ / -: intensity   [ ]: spot cone   N: add   Delete: remove\nCtrl+S: save lights   T: reference on / off");
        });
    });
    if let Some(truth) = p.truth {
        let texture = truth.texture(ctx);
        egui::Window::new(format!("reference, {} spp", truth.samples)).default_pos([300.0, 8.0]).show(ctx, |ui| {
            let width = (ctx.content_rect().width() / 3.0).max(64.0);
            let size = texture.size_vec2();
            ui.image((texture.id(), egui::vec2(width, width * size.y / size.x)));
        });
    }
    actions
}

fn method_list(ui: &mut egui::Ui, p: &Panel, actions: &mut Vec<Action>) {
    egui::ComboBox::from_label("method").selected_text(p.methods[p.active]).show_ui(ui, |ui| {
        for (i, name) in p.methods.iter().enumerate() {
            if ui.selectable_label(i == p.active, *name).clicked() && i != p.active {
                actions.push(Action::Method(i));
            }
        }
    });
}

fn times(ui: &mut egui::Ui, p: &Panel) {
    ui.label(format!("frame {:.1} ms between frames, GPU {:.2} ms", p.frame_ms, p.timings.total_ms()));
    ui.collapsing("passes (GPU ms)", |ui| {
        for (name, ms) in p.timings.passes() {
            ui.label(format!("{name:<28} {ms:>8.3}"));
        }
    });
}

fn lights(ui: &mut egui::Ui, p: &Panel, actions: &mut Vec<Action>) {
    ui.label(format!("{} light(s)", p.lights.len()));
    for (i, light) in p.lights.iter().enumerate() {
        if ui.selectable_label(p.selected == Some(i), format!("{i}: {}", light.name)).clicked() {
            actions.push(Action::Select(Some(i)));
        }
    }
    let Some(i) = p.selected.filter(|&i| i < p.lights.len()) else { return };
    let mut light = p.lights[i].clone();
    let mut changed = false;
    let mut strength = light.intensity.max_element();
    let colour = if strength > 0.0 { light.intensity / strength } else { glam::Vec3::ONE };
    let most = (strength * 4.0).max(1.0);
    changed |= ui.add(egui::Slider::new(&mut strength, 0.0..=most).text("intensity")).changed();
    light.intensity = colour * strength;
    if let LightKind::Spot { mut inner_cone, mut outer_cone } = light.kind {
        changed |= ui.add(egui::Slider::new(&mut outer_cone, 0.02..=std::f32::consts::FRAC_PI_2).text("outer cone (rad)")).changed();
        changed |= ui.add(egui::Slider::new(&mut inner_cone, 0.0..=outer_cone * 0.99).text("inner cone (rad)")).changed();
        light.kind = LightKind::Spot { inner_cone: inner_cone.min(outer_cone * 0.99), outer_cone };
    }
    let at = light.position;
    ui.label(format!("at ({:.3}, {:.3}, {:.3})", at.x, at.y, at.z));
    if changed {
        actions.push(Action::Light(i, light));
    }
    if ui.button("save lights (Ctrl+S)").clicked() {
        actions.push(Action::SaveLights);
    }
}

fn truth(ui: &mut egui::Ui, p: &Panel, actions: &mut Vec<Action>) {
    match p.tracing {
        Some((taken, target)) if taken < target => {
            ui.label(format!("reference: {taken} of {target} spp"));
            if ui.button("stop reference (T)").clicked() {
                actions.push(Action::StopTruth);
            }
        }
        _ => {
            if ui.button("trace a reference of this view (T)").clicked() {
                actions.push(Action::StartTruth);
            }
        }
    }
    if let Some(nrmse) = p.truth.and_then(|t| t.live_nrmse) {
        ui.label(format!("live NRMSE against the reference: {nrmse:.4}"));
    }
}
