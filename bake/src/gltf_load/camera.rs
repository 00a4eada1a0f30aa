//! The camera: one given on the command line instead of the file's ([`CameraOverride`]), the
//! file's first perspective camera, or a default one that frames the scene.

use super::{Ctx, ErrorKind, SceneError};
use crate::scene::Camera;
use glam::{Mat4, Vec3};
use std::str::FromStr;

/// A camera given on the command line instead of the file's: eye, target, up and vertical
/// field of view. Constructed only through [`CameraOverride::new`] or the parser, which
/// check it, so that [`CameraOverride::camera`] cannot fail.
///
/// Syntax: `eye=x,y,z;target=x,y,z[;up=x,y,z][;yfov=degrees]`, spaces allowed around items;
/// `up` defaults to `0,1,0` (glTF's Y up) and `yfov` to 45 degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraOverride {
    eye: Vec3,
    target: Vec3,
    up: Vec3,
    yfov_degrees: f32,
}

/// Why a camera override was refused (one line, with the syntax as the fix).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("camera \"{input}\": {problem}; write it as eye=x,y,z;target=x,y,z[;up=x,y,z][;yfov=degrees]")]
pub struct CameraOverrideError {
    pub input: String,
    pub problem: String,
}

impl CameraOverride {
    pub const DEFAULT_YFOV_DEGREES: f32 = 45.0;

    pub fn new(eye: Vec3, target: Vec3, up: Vec3, yfov_degrees: f32) -> Result<Self, CameraOverrideError> {
        let fail = |problem: String| CameraOverrideError {
            input: format!(
                "eye={},{},{};target={},{},{};up={},{},{};yfov={}",
                eye.x, eye.y, eye.z, target.x, target.y, target.z, up.x, up.y, up.z, yfov_degrees
            ),
            problem,
        };
        let within = |p: Vec3| p.is_finite() && p.abs().max_element() <= crate::scene::MAX_COORDINATE;
        if !(within(eye) && within(target) && up.is_finite()) {
            return Err(fail("eye, target and up must be finite numbers, eye and target within 1e7 m of the origin".into()));
        }
        let forward = target - eye;
        if forward.length() <= 1e-6 * eye.length().max(1.0) {
            return Err(fail("eye and target are the same point, so there is no view direction".into()));
        }
        if forward.normalize().cross(up.normalize_or_zero()).length() < 1e-4 {
            return Err(fail("up is zero or parallel to the view direction (target - eye)".into()));
        }
        if !(yfov_degrees > 0.0 && yfov_degrees < 180.0) {
            return Err(fail(format!("yfov {yfov_degrees} is not between 0 and 180 degrees")));
        }
        Ok(CameraOverride { eye, target, up, yfov_degrees })
    }

    /// Parses `eye=x,y,z;target=x,y,z[;up=x,y,z][;yfov=degrees]` (see the type's docs).
    pub fn parse(text: &str) -> Result<Self, CameraOverrideError> {
        text.parse()
    }

    pub fn eye(&self) -> Vec3 {
        self.eye
    }
    pub fn target(&self) -> Vec3 {
        self.target
    }
    pub fn up(&self) -> Vec3 {
        self.up
    }
    pub fn yfov_degrees(&self) -> f32 {
        self.yfov_degrees
    }

    /// The camera, with clip planes chosen from the scene bounds so that the whole scene
    /// lies between them (the CLI has no way to know good planes; the bounds do).
    pub fn camera(&self, scene_bounds: (Vec3, Vec3)) -> Camera {
        let world_from_camera = look_at(self.eye, self.target, self.up);
        let (znear, zfar) = clip_planes(self.eye, scene_bounds);
        Camera { world_from_camera, yfov: self.yfov_degrees.to_radians(), znear, zfar }
    }
}

impl FromStr for CameraOverride {
    type Err = CameraOverrideError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let fail = |problem: String| CameraOverrideError { input: text.to_string(), problem };
        let vec3 = |key: &str, value: &str| -> Result<Vec3, CameraOverrideError> {
            let parts: Vec<&str> = value.split(',').map(str::trim).collect();
            let numbers: Vec<f32> = parts.iter().filter_map(|p| p.parse().ok()).collect();
            if parts.len() != 3 || numbers.len() != 3 {
                return Err(fail(format!("{key} needs three numbers x,y,z, got \"{value}\"")));
            }
            Ok(Vec3::new(numbers[0], numbers[1], numbers[2]))
        };
        let (mut eye, mut target, mut up, mut yfov) = (None, None, None, None);
        for item in text.split(';').map(str::trim).filter(|s| !s.is_empty()) {
            let Some((key, value)) = item.split_once('=') else {
                return Err(fail(format!("\"{item}\" is not key=value")));
            };
            let (key, value) = (key.trim(), value.trim());
            let slot_taken = match key {
                "eye" => eye.replace(vec3(key, value)?).is_some(),
                "target" => target.replace(vec3(key, value)?).is_some(),
                "up" => up.replace(vec3(key, value)?).is_some(),
                "yfov" => {
                    let degrees: f32 = value.parse().map_err(|_| fail(format!("yfov needs a number of degrees, got \"{value}\"")))?;
                    yfov.replace(degrees).is_some()
                }
                _ => return Err(fail(format!("unknown key \"{key}\" (keys: eye, target, up, yfov)"))),
            };
            if slot_taken {
                return Err(fail(format!("{key} is given twice")));
            }
        }
        let eye = eye.ok_or_else(|| fail("eye is missing".into()))?;
        let target = target.ok_or_else(|| fail("target is missing".into()))?;
        CameraOverride::new(eye, target, up.unwrap_or(Vec3::Y), yfov.unwrap_or(Self::DEFAULT_YFOV_DEGREES)).map_err(|e| fail(e.problem))
    }
}

/// A glTF perspective camera's parameters (zfar absent means infinite).
pub(super) struct Perspective {
    pub(super) yfov: f32,
    pub(super) znear: f32,
    pub(super) zfar: Option<f32>,
}

/// The file's camera, with any scale removed from its node matrix (Gram-Schmidt on the
/// -Z and +Y axes, so a scaled or slightly sheared node still gives a rigid view).
pub(super) fn perspective_camera(ctx: Ctx, item: &str, p: &Perspective, world: Mat4, bounds: (Vec3, Vec3)) -> Result<Camera, SceneError> {
    let back = world.z_axis.truncate().normalize_or_zero();
    let up = (world.y_axis.truncate() - back * back.dot(world.y_axis.truncate())).normalize_or_zero();
    if back == Vec3::ZERO || up == Vec3::ZERO {
        return Err(ctx.fail(
            ErrorKind::Invalid,
            item,
            "the node transform collapses the camera's axes (zero scale)",
            "give the camera's node a non-zero scale",
        ));
    }
    let right = up.cross(back);
    let eye = world.w_axis.truncate();
    let world_from_camera = Mat4::from_cols(right.extend(0.0), up.extend(0.0), back.extend(0.0), eye.extend(1.0));
    let (yfov, znear) = (p.yfov, p.znear);
    if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
        return Err(ctx.fail(ErrorKind::Invalid, item, format!("yfov {yfov} rad"), "yfov must be between 0 and pi radians"));
    }
    if !(znear > 0.0 && znear.is_finite()) {
        return Err(ctx.fail(ErrorKind::Invalid, item, format!("znear {znear}"), "znear must be a positive number"));
    }
    // An infinite far plane (zfar absent) becomes a finite one that holds the whole scene,
    // because the renderer's projection and depth buffer need one.
    let zfar = match p.zfar {
        Some(f) => f,
        None => clip_planes(eye, bounds).1.max(znear * 2.0),
    };
    if !(zfar > znear && zfar.is_finite()) {
        return Err(ctx.fail(ErrorKind::Invalid, item, format!("zfar {zfar} is not beyond znear {znear}"), "make zfar larger than znear"));
    }
    Ok(Camera { world_from_camera, yfov, znear, zfar })
}

/// A right-handed view from `eye` to `target`: the camera looks down its -Z, +Y up.
pub(super) fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let forward = (target - eye).normalize();
    let right = forward.cross(up).normalize();
    let true_up = right.cross(forward);
    Mat4::from_cols(right.extend(0.0), true_up.extend(0.0), (-forward).extend(0.0), eye.extend(1.0))
}

/// Near and far planes that hold the whole box as seen from `eye`: far beyond its farthest
/// corner, near at half the distance to the box (never below far / 10^4, which keeps depth
/// precision usable when the eye is inside the box).
pub(super) fn clip_planes(eye: Vec3, (lo, hi): (Vec3, Vec3)) -> (f32, f32) {
    let farthest = (0..8)
        .map(|i| {
            let corner =
                Vec3::new(if i & 1 == 0 { lo.x } else { hi.x }, if i & 2 == 0 { lo.y } else { hi.y }, if i & 4 == 0 { lo.z } else { hi.z });
            (corner - eye).length()
        })
        .fold(0.0f32, f32::max);
    let far = (farthest * 1.1).max(1e-3);
    let nearest = (eye.clamp(lo, hi) - eye).length();
    let near = (nearest * 0.5).max(far * 1e-4);
    (near, far)
}

/// A camera for files without one: 45 degrees vertical, looking at the bounds' centre from
/// the +Z side and 20 degrees above, far enough that the bounding sphere fits the height.
pub(super) fn framing_camera(bounds: (Vec3, Vec3)) -> Camera {
    let (lo, hi) = bounds;
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let yfov = 45f32.to_radians();
    let distance = radius / (yfov * 0.5).sin();
    let elevation = 20f32.to_radians();
    let eye = centre + Vec3::new(0.0, elevation.sin(), elevation.cos()) * distance;
    let (znear, zfar) = clip_planes(eye, bounds);
    Camera { world_from_camera: look_at(eye, centre, Vec3::Y), yfov, znear, zfar }
}
#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn camera_override_parses_and_rejects() {
        let c = CameraOverride::parse("eye=0,1,5; target=0,1,0; yfov=40").unwrap();
        assert_eq!(c.eye(), Vec3::new(0.0, 1.0, 5.0));
        assert_eq!(c.up(), Vec3::Y);
        assert_eq!(c.yfov_degrees(), 40.0);
        let cam = c.camera((Vec3::splat(-1.0), Vec3::splat(1.0)));
        assert!((cam.position() - Vec3::new(0.0, 1.0, 5.0)).length() < 1e-6);
        let forward = cam.world_from_camera.transform_vector3(Vec3::NEG_Z);
        assert!((forward - Vec3::NEG_Z).length() < 1e-6);
        assert!(cam.znear > 0.0 && cam.zfar > 6.0);
        for bad in [
            "eye=0,1;target=0,0,0",
            "target=0,0,0",
            "eye=0,0,0;target=0,0,0",
            "eye=0,0,0;target=0,1,0",
            "eye=1,2,3;target=0,0,0;yfov=200",
            "eye=1,2,3;target=0,0,0;fov=20",
            "eye=1,2,3;eye=1,2,3;target=0,0,0",
        ] {
            let e = CameraOverride::parse(bad).unwrap_err().to_string();
            assert!(e.contains("write it as eye="), "{e}");
            assert!(!e.contains('\n'));
        }
    }
}
