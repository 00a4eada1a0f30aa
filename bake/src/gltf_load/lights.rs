//! KHR_lights_punctual lights in world space: point, spot (with its cone) and directional.

use super::{quoted_name, ErrorKind, Loader, SceneError};
use crate::scene::{Light, LightKind, MAX_COORDINATE, MAX_LIGHT};
use glam::{Mat4, Vec3};

impl Loader<'_> {
    pub(super) fn convert_light(
        &self,
        light: &gltf::khr_lights_punctual::Light,
        node: &gltf::Node,
        world: Mat4,
    ) -> Result<Light, SceneError> {
        use gltf::khr_lights_punctual::Kind;
        let ctx = self.ctx;
        let item = format!("{} light {}", quoted_name("node", node.name(), node.index()), light.index());
        let color = Vec3::from(light.color());
        let intensity = light.intensity();
        if !color.is_finite() || color.min_element() < 0.0 || !intensity.is_finite() || intensity < 0.0 {
            return Err(ctx.fail(
                ErrorKind::Invalid,
                item,
                format!("color {color} or intensity {intensity} is negative or not finite"),
                "use a finite, non-negative color and intensity",
            ));
        }
        if (color * intensity).max_element() > MAX_LIGHT {
            return Err(ctx.fail(
                ErrorKind::Invalid,
                item,
                format!("color {color} times intensity {intensity} exceeds {MAX_LIGHT:e}"),
                "give a light at most 1e9 (candela, or lux for a directional light)",
            ));
        }
        let kind = match light.kind() {
            Kind::Directional => LightKind::Directional,
            Kind::Point => LightKind::Point,
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                // Allow for outerConeAngle written as a rounded pi/2.
                let outer = if outer_cone_angle > std::f32::consts::FRAC_PI_2 && outer_cone_angle < std::f32::consts::FRAC_PI_2 + 1e-5 {
                    std::f32::consts::FRAC_PI_2
                } else {
                    outer_cone_angle
                };
                if !(inner_cone_angle >= 0.0 && inner_cone_angle < outer && outer <= std::f32::consts::FRAC_PI_2) {
                    return Err(ctx.fail(
                        ErrorKind::Invalid,
                        item,
                        format!("spot cone angles inner {inner_cone_angle} outer {outer_cone_angle} rad"),
                        "KHR_lights_punctual needs 0 <= innerConeAngle < outerConeAngle <= pi/2",
                    ));
                }
                LightKind::Spot { inner_cone: inner_cone_angle, outer_cone: outer }
            }
        };
        let range = light.range();
        if let Some(r) = range {
            if !(r.is_finite() && r > 0.0) {
                return Err(ctx.fail(
                    ErrorKind::Invalid,
                    item,
                    format!("range {r}"),
                    "range must be a positive number (or absent for no limit)",
                ));
            }
        }
        let position = world.w_axis.truncate();
        if !(position.is_finite() && position.abs().max_element() <= MAX_COORDINATE) {
            return Err(ctx.fail(
                ErrorKind::Invalid,
                item,
                format!("stands at {position}, past 1e7 m from the origin"),
                "fix the light's node transform",
            ));
        }
        let direction = (-world.z_axis.truncate()).normalize_or_zero();
        if direction == Vec3::ZERO && kind != LightKind::Point {
            return Err(ctx.fail(
                ErrorKind::Invalid,
                item,
                "the node transform collapses the light's -Z axis (zero scale)",
                "give the light's node a non-zero scale",
            ));
        }
        let name = light.name().or(node.name()).map(str::to_string).unwrap_or_else(|| format!("light {}", light.index()));
        Ok(Light {
            name,
            kind,
            intensity: color * intensity,
            range,
            position,
            direction: if direction == Vec3::ZERO { Vec3::NEG_Z } else { direction },
        })
    }
}
