//! The viewer's camera: the scene's camera to start, then orbit about a pivot, fly, and dolly.
//! Every move transforms the camera's own matrix, so an unmoved camera is bit for bit the
//! scene's (a screenshot then equals `relume render` of the same state).

use glam::{Mat4, Quat, Vec3};
use relume_bake::scene::Camera;

#[derive(Clone, Debug)]
pub struct CameraControl {
    pub camera: Camera,
    start: Camera,
    /// The point orbits turn about: the scene's centre, seen from the start.
    pivot: Vec3,
    start_pivot: Vec3,
    /// Metres a fly step or a dolly notch moves: a fiftieth of the scene's size.
    step: f32,
}

impl CameraControl {
    pub fn new(camera: Camera, bounds: (Vec3, Vec3)) -> CameraControl {
        let centre = (bounds.0 + bounds.1) * 0.5;
        let step = ((bounds.1 - bounds.0).length() / 50.0).max(1e-3);
        CameraControl { camera, start: camera, pivot: centre, start_pivot: centre, step }
    }

    pub fn reset(&mut self) {
        self.camera = self.start;
        self.pivot = self.start_pivot;
    }

    /// The point orbits turn about.
    pub fn pivot(&self) -> Vec3 {
        self.pivot
    }

    pub fn position(&self) -> Vec3 {
        self.camera.position()
    }

    /// Unit right, up and forward (looking direction) of the camera in world space.
    pub fn axes(&self) -> (Vec3, Vec3, Vec3) {
        let m = self.camera.world_from_camera;
        (m.x_axis.truncate().normalize(), m.y_axis.truncate().normalize(), -m.z_axis.truncate().normalize())
    }

    /// Turns about the pivot by `yaw` about world up and `pitch` about the camera's right
    /// (radians).
    pub fn orbit(&mut self, yaw: f32, pitch: f32) {
        let (right, _, _) = self.axes();
        let turn = Quat::from_axis_angle(Vec3::Y, yaw) * Quat::from_axis_angle(right, pitch);
        let about = Mat4::from_translation(self.pivot) * Mat4::from_quat(turn) * Mat4::from_translation(-self.pivot);
        self.camera.world_from_camera = about * self.camera.world_from_camera;
    }

    /// Moves camera and pivot by steps along the camera's right, up and forward.
    pub fn fly(&mut self, steps: Vec3) {
        let (right, up, forward) = self.axes();
        let by = (right * steps.x + up * steps.y + forward * steps.z) * self.step;
        self.camera.world_from_camera = Mat4::from_translation(by) * self.camera.world_from_camera;
        self.pivot += by;
    }

    /// Moves the camera towards the pivot (positive notches) without passing it.
    pub fn dolly(&mut self, notches: f32) {
        let (_, _, forward) = self.axes();
        let room = (self.pivot - self.position()).length() - self.step;
        let by = forward * (notches * self.step).min(room.max(0.0));
        self.camera.world_from_camera = Mat4::from_translation(by) * self.camera.world_from_camera;
    }

    /// World metres per pixel at `point`, for dragging things in the view plane.
    pub fn metres_per_pixel(&self, point: Vec3, height: u32) -> f32 {
        let (_, _, forward) = self.axes();
        let depth = (point - self.position()).dot(forward).max(1e-3);
        2.0 * depth * (self.camera.yfov * 0.5).tan() / height.max(1) as f32
    }

    /// Where `point` lands in the window, in pixels from the top left; None behind the camera.
    pub fn project(&self, point: Vec3, width: u32, height: u32) -> Option<(f32, f32)> {
        let clip = self.camera.clip_from_world(width, height) * point.extend(1.0);
        (clip.w > 0.0).then(|| {
            let ndc = clip.truncate() / clip.w;
            ((ndc.x * 0.5 + 0.5) * width as f32, (ndc.y * 0.5 + 0.5) * height as f32)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn control() -> CameraControl {
        let camera = relume_bake::testing::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 0.8);
        CameraControl::new(camera, (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0)))
    }

    #[test]
    fn an_orbit_keeps_the_distance_to_the_pivot_and_reset_restores_the_scene_camera_exactly() {
        let mut c = control();
        let before = (c.position() - Vec3::new(0.0, 1.0, 0.0)).length();
        c.orbit(0.7, -0.3);
        let after = (c.position() - Vec3::new(0.0, 1.0, 0.0)).length();
        assert!((before - after).abs() < 1e-5, "{before} vs {after}");
        assert!(c.position().distance(Vec3::new(0.0, 1.0, 5.0)) > 1.0, "the orbit moved the camera");
        c.fly(Vec3::new(1.0, 2.0, 3.0));
        c.reset();
        assert_eq!(c.camera.world_from_camera, control().camera.world_from_camera);
    }

    #[test]
    fn the_pivot_projects_to_the_window_centre_and_a_dolly_never_passes_it() {
        let mut c = control();
        let (x, y) = c.project(Vec3::new(0.0, 1.0, 0.0), 200, 100).expect("in front");
        assert!((x - 100.0).abs() < 1e-3 && (y - 50.0).abs() < 1e-3, "({x}, {y})");
        c.dolly(1e6);
        assert!(c.position().z > 0.0, "stopped short of the pivot: {}", c.position());
        assert!(c.project(Vec3::new(0.0, 1.0, 10.0), 200, 100).is_none(), "behind the camera");
    }
}
