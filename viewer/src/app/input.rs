//! The window's input: keys and the pointer move the camera, pick and drag lights, change
//! their intensity and cone, add and delete them, switch methods, save the lights.

use super::{App, Drag};
use anyhow::Result;
use glam::Vec3;
use relume_bake::scene::{Light, LightKind};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{Key, NamedKey};

impl App {
    pub(super) fn key(&mut self, key: &Key) -> Result<()> {
        let step = match key {
            Key::Named(NamedKey::Tab) => {
                let n = self.methods.len();
                let next = if self.modifiers.shift_key() { self.active + n - 1 } else { self.active + 1 };
                self.switch_method(next % n);
                return Ok(());
            }
            Key::Named(NamedKey::Home) => {
                self.camera.reset();
                self.view_changed();
                return Ok(());
            }
            Key::Named(NamedKey::F1) => {
                self.overlay_visible = !self.overlay_visible;
                self.dirty = true;
                return Ok(());
            }
            Key::Named(NamedKey::Delete) => return self.delete_light(),
            Key::Named(NamedKey::Escape) => {
                self.selected = None;
                self.dirty = true;
                return Ok(());
            }
            Key::Character(c) => c.to_lowercase(),
            _ => return Ok(()),
        };
        let fly = match step.as_str() {
            "w" => Vec3::Z,
            "s" => Vec3::NEG_Z,
            "a" => Vec3::NEG_X,
            "d" => Vec3::X,
            "e" => Vec3::Y,
            "q" => Vec3::NEG_Y,
            _ => Vec3::ZERO,
        };
        if fly != Vec3::ZERO && !self.modifiers.control_key() {
            self.camera.fly(fly);
            self.view_changed();
            return Ok(());
        }
        match step.as_str() {
            "s" if self.modifiers.control_key() => self.save_lights_noting(),
            "r" => {
                self.camera.reset();
                self.view_changed();
            }
            "t" if self.truth.is_some() => self.truth = None,
            "t" => self.start_truth(256),
            "n" => self.add_light(),
            "+" | "=" => self.scale_selected(1.25),
            "-" => self.scale_selected(0.8),
            "[" => self.widen_selected(-2f32.to_radians()),
            "]" => self.widen_selected(2f32.to_radians()),
            digit if digit.len() == 1 && digit.as_bytes()[0].is_ascii_digit() && digit != "0" => {
                self.switch_method(digit.parse::<usize>().unwrap_or(1) - 1);
            }
            _ => {}
        }
        self.dirty = true;
        Ok(())
    }

    fn scale_selected(&mut self, factor: f32) {
        if let Some(i) = self.selected {
            self.lights[i].intensity *= factor;
            self.lights_changed();
        }
    }

    fn widen_selected(&mut self, by: f32) {
        if let Some(light) = self.selected.map(|i| &mut self.lights[i]) {
            if let LightKind::Spot { inner_cone, outer_cone } = light.kind {
                let outer = (outer_cone + by).clamp(1f32.to_radians(), std::f32::consts::FRAC_PI_2);
                let _ = set_cone(light, inner_cone.min(outer * 0.9), outer);
                self.lights_changed();
            }
        }
    }

    /// A new point light at the orbit's pivot (the scene's centre, as flown), as bright as the first light (1 cd without
    /// any); the renderer is made again for the new count.
    fn add_light(&mut self) {
        let intensity = self.lights.first().map_or(Vec3::ONE, |l| l.intensity);
        let position = self.camera.pivot();
        let name = format!("light {}", self.lights.len());
        self.lights.push(Light { name, kind: LightKind::Point, intensity, range: None, position, direction: Vec3::NEG_Y });
        self.selected = Some(self.lights.len() - 1);
        self.remake = true;
        self.view_changed();
    }

    fn delete_light(&mut self) -> Result<()> {
        let Some(i) = self.selected else { return Ok(()) };
        if self.lights.len() == 1 {
            self.notes.push("the last light stays: relume renders a scene with at least one light".into());
        } else {
            self.lights.remove(i);
            (self.selected, self.drag) = (None, None);
            self.remake = true;
            self.view_changed();
        }
        self.dirty = true;
        Ok(())
    }

    /// The light whose window position is within 24 pixels of the cursor, nearest first.
    fn light_under_cursor(&self) -> Option<usize> {
        let size = self.window.as_ref()?.inner_size();
        let (cx, cy) = (self.cursor.x as f32, self.cursor.y as f32);
        let distances = self.lights.iter().enumerate().filter_map(|(i, l)| {
            let (x, y) = self.camera.project(l.position, size.width, size.height)?;
            Some((i, ((x - cx).powi(2) + (y - cy).powi(2)).sqrt()))
        });
        distances.filter(|(_, d)| *d < 24.0).min_by(|a, b| a.1.total_cmp(&b.1)).map(|(i, _)| i)
    }

    pub(super) fn pointer(&mut self, event: &WindowEvent) {
        match event {
            WindowEvent::MouseInput { state: ElementState::Pressed, button, .. } => {
                self.drag = match button {
                    MouseButton::Left => match self.light_under_cursor() {
                        Some(i) => {
                            self.selected = Some(i);
                            Some(Drag::Light(i, self.modifiers.shift_key()))
                        }
                        None => Some(Drag::Orbit),
                    },
                    MouseButton::Right | MouseButton::Middle => Some(Drag::Pan),
                    _ => None,
                };
                self.dirty = true;
            }
            WindowEvent::MouseInput { state: ElementState::Released, .. } => self.drag = None,
            WindowEvent::CursorMoved { position, .. } => {
                let (dx, dy) = ((position.x - self.cursor.x) as f32, (position.y - self.cursor.y) as f32);
                self.cursor = *position;
                self.dragged(dx, dy);
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => *y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.camera.dolly(notches);
                self.view_changed();
            }
            _ => {}
        }
    }

    fn dragged(&mut self, dx: f32, dy: f32) {
        let Some(drag) = self.drag else { return };
        let height = self.window.as_ref().map_or(1, |w| w.inner_size().height);
        let (right, up, forward) = self.camera.axes();
        match drag {
            Drag::Orbit => self.camera.orbit(-dx * 0.01, -dy * 0.01),
            Drag::Pan => self.camera.fly(Vec3::new(-dx, dy, 0.0) * 0.05),
            Drag::Light(i, along_view) => {
                let Some(light) = self.lights.get_mut(i) else { return };
                let scale = self.camera.metres_per_pixel(light.position, height);
                // In the view plane, or (with Shift) towards and away from the camera.
                light.position += match along_view {
                    false => (right * dx - up * dy) * scale,
                    true => forward * (-dy * scale),
                };
                self.lights_moved = true;
            }
        }
        self.view_changed();
    }
}

/// A spot light's cone; refused for other kinds and for angles out of 0 <= inner < outer <= 90°.
pub(super) fn set_cone(light: &mut Light, inner: f32, outer: f32) -> Result<(), String> {
    if !matches!(light.kind, LightKind::Spot { .. }) {
        return Err("not a spot light".into());
    }
    if !(0.0 <= inner && inner < outer && outer <= std::f32::consts::FRAC_PI_2) {
        return Err("a cone needs 0 <= inner < outer <= 90 degrees".into());
    }
    light.kind = LightKind::Spot { inner_cone: inner, outer_cone: outer };
    Ok(())
}
