//! A scene's light configurations in a sweep: its lights moved along a path, an occluder
//! moved and turned, or a spot's cone and aim swept; each applied to the reference's scene
//! and to a renderer alike.

use super::sweep::{self, SweepScene};
use anyhow::{bail, Result};
use glam::Vec3;
use relume_bake::scene::{Light, LightKind, Scene};
use relume_renderer::Renderer;

/// One configuration of a scene: its lights, and where the moving light or occluder is, or
/// the swept spot's outer cone and turn (degrees).
pub(super) struct Configuration {
    pub lights: Vec<Light>,
    pub light_position: Option<Vec3>,
    pub occluder: Option<MovedMesh>,
    pub spot: Option<(f32, f32)>,
}

/// A mesh moved by an occluder path: turned about the vertical axis through its bounds'
/// centre, then translated from where the scene has it.
pub(super) struct MovedMesh {
    mesh: usize,
    pub translation: Vec3,
    pub turn_degrees: f32,
    /// Its vertices turned (None without a turn).
    turned: Option<(Vec<Vec3>, Vec<Vec3>)>,
}

impl MovedMesh {
    fn new(scene: &Scene, mesh: usize, translation: Vec3, turn_degrees: f32) -> Self {
        let m = &scene.meshes[mesh];
        let turned = (turn_degrees != 0.0).then(|| {
            let (lo, hi) = m.bounds();
            let (centre, turn) = ((lo + hi) * 0.5, glam::Quat::from_rotation_y(turn_degrees.to_radians()));
            (m.positions.iter().map(|p| centre + turn * (*p - centre)).collect(), m.normals.iter().map(|n| turn * *n).collect())
        });
        MovedMesh { mesh, translation, turn_degrees, turned }
    }
}

impl Configuration {
    /// The scene as this configuration has it, for the reference.
    pub(super) fn apply_to(&self, scene: &Scene) -> Scene {
        let mut moved = Scene { lights: self.lights.clone(), ..scene.clone() };
        if let Some(o) = &self.occluder {
            let mesh = &mut moved.meshes[o.mesh];
            if let Some((positions, normals)) = &o.turned {
                (mesh.positions, mesh.normals) = (positions.clone(), normals.clone());
            }
            mesh.positions.iter_mut().for_each(|p| *p += o.translation);
        }
        moved
    }

    /// The renderer set to this configuration (the occluder first: set_lights refits the
    /// shadow maps to it).
    pub(super) fn apply(&self, renderer: &mut Renderer) -> Result<()> {
        if let Some(o) = &self.occluder {
            if let Some((positions, normals)) = &o.turned {
                renderer.set_mesh_vertices(o.mesh, positions, normals)?;
            }
            renderer.set_mesh_translation(o.mesh, o.translation)?;
        }
        renderer.set_lights(&self.lights)?;
        Ok(())
    }

    /// The lights moved from this configuration to `next` over `seconds`, in steps of 1/60 s
    /// along the straight line between (light paths only).
    pub(super) fn move_to(&self, next: &Configuration, seconds: f32, renderer: &mut Renderer) -> Result<()> {
        let steps = (seconds * 60.0).round().max(1.0) as usize;
        let mut lights = self.lights.clone();
        for step in 1..=steps {
            let t = step as f32 / steps as f32;
            for ((light, from), to) in lights.iter_mut().zip(&self.lights).zip(&next.lights) {
                light.position = from.position.lerp(to.position, t);
            }
            renderer.move_lights(&lights, seconds / steps as f32)?;
        }
        Ok(())
    }
}

/// The scene as it is, or one light or one mesh moved along the sweep's path.
pub(super) fn configurations(scene: &Scene, entry: &SweepScene) -> Result<Vec<Configuration>> {
    let at_rest = || Configuration { lights: scene.lights.clone(), light_position: None, occluder: None, spot: None };
    if let Some(path) = &entry.light_path {
        if path.light >= scene.lights.len() {
            bail!("{}: light_path.light {}: the scene has {} light(s)", entry.path.display(), path.light, scene.lights.len());
        }
        return Ok(sweep::spread(&path.points, path.frames)
            .into_iter()
            .map(|p| {
                let mut configuration = at_rest();
                configuration.lights[path.light].position = p;
                configuration.light_position = Some(p);
                configuration
            })
            .collect());
    }
    if let Some(path) = &entry.occluder_path {
        let Some(mesh) = scene.meshes.iter().position(|m| m.name == path.mesh) else {
            let names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
            bail!("{}: occluder_path.mesh \"{}\": no such mesh; the scene has {}", entry.path.display(), path.mesh, names.join(", "));
        };
        let turns = sweep::spread(&[[0.0; 3], [path.turn_degrees, 0.0, 0.0]], path.frames);
        return Ok(sweep::spread(&path.points, path.frames)
            .into_iter()
            .zip(turns)
            .map(|(t, turn)| Configuration { occluder: Some(MovedMesh::new(scene, mesh, t, turn.x)), ..at_rest() })
            .collect());
    }
    if let Some(sweep) = &entry.spot_sweep {
        return spot_configurations(scene, entry, sweep, &at_rest);
    }
    Ok(vec![at_rest()])
}

/// A spot sweep's configurations: the spot with each cone, or aimed at each target (a
/// directional light too: from where its node stands).
fn spot_configurations(
    scene: &Scene,
    entry: &SweepScene,
    sweep: &sweep::SpotSweep,
    at_rest: &dyn Fn() -> Configuration,
) -> Result<Vec<Configuration>> {
    let aimed = sweep.outer_degrees.is_empty();
    let sweepable = |l: &&Light| matches!(l.kind, LightKind::Spot { .. }) || (aimed && l.kind == LightKind::Directional);
    let Some(spot) = scene.lights.get(sweep.light).filter(sweepable) else {
        bail!(
            "{}: spot_sweep.light {}: not a spot light (nor, for targets, a directional light) of the scene's {}",
            entry.path.display(),
            sweep.light,
            scene.lights.len()
        );
    };
    let with = |kind: LightKind, direction: Vec3| {
        let mut configuration = at_rest();
        configuration.lights[sweep.light] = Light { kind, direction, ..spot.clone() };
        let turn = direction.angle_between(spot.direction).to_degrees();
        let outer = match kind {
            LightKind::Spot { outer_cone, .. } => outer_cone.to_degrees(),
            _ => 0.0,
        };
        configuration.spot = Some((outer, turn));
        configuration
    };
    let cones = sweep.outer_degrees.iter().map(|&outer| {
        let inner = (outer - sweep.softness_degrees).max(0.0);
        with(LightKind::Spot { inner_cone: inner.to_radians(), outer_cone: outer.to_radians() }, spot.direction)
    });
    let aims = sweep.targets.iter().map(|t| {
        let direction = (Vec3::from_array(*t) - spot.position).normalize_or(spot.direction);
        with(spot.kind, direction)
    });
    Ok(cones.chain(aims).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spot_sweep_narrows_its_cone_or_turns_its_aim_where_it_stands() {
        use relume_bake::testing::{look_at, point_light, scene, spot_light};
        let spot = spot_light(Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, Vec3::ONE, 0.5, 0.7);
        let s =
            scene("spot", vec![], vec![], vec![point_light(Vec3::ONE, Vec3::ONE), spot], look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 0.8));
        let entry = |text: &str| -> SweepScene { toml::from_str(&format!("path = 'a.gltf'\nspot_sweep = {text}")).unwrap() };
        let cones = configurations(&s, &entry("{ light = 1, outer_degrees = [60, 5], softness_degrees = 10 }")).unwrap();
        let kinds: Vec<LightKind> = cones.iter().map(|c| c.lights[1].kind).collect();
        assert_eq!(
            kinds,
            [
                LightKind::Spot { inner_cone: 50f32.to_radians(), outer_cone: 60f32.to_radians() },
                LightKind::Spot { inner_cone: 0.0, outer_cone: 5f32.to_radians() }
            ]
        );
        assert_eq!(cones.iter().map(|c| c.spot.unwrap().0.round()).collect::<Vec<_>>(), [60.0, 5.0]);
        let aims = configurations(&s, &entry("{ light = 1, targets = [[0, 0, 0], [2, 2, 0]] }")).unwrap();
        assert!(aims.iter().all(|c| c.lights[1].position == Vec3::new(0.0, 2.0, 0.0) && c.lights[0].position == Vec3::ONE));
        assert_eq!(aims.iter().map(|c| c.spot.unwrap().1.round()).collect::<Vec<_>>(), [0.0, 90.0]);
        assert!(aims[1].lights[1].direction.distance(Vec3::X) < 1e-6);
        let refused =
            configurations(&s, &entry("{ light = 0, outer_degrees = [30] }")).err().expect("a point light is no spot").to_string();
        assert!(refused.contains("spot_sweep.light 0: not a spot light"), "{refused}");
    }

    #[test]
    fn an_occluder_path_turns_its_mesh_about_its_bounds_centre_then_moves_it() {
        use relume_bake::testing::{closed_box, look_at, scene, Facing};
        let block = closed_box(Vec3::new(1.0, 0.0, 1.0), Vec3::new(3.0, 1.0, 2.0), 1, Facing::Outward, 0);
        let s = scene("block", vec![block], vec![], vec![], look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 0.8));
        let turned = MovedMesh::new(&s, 0, Vec3::new(0.0, 2.0, 0.0), 90.0);
        let configuration = Configuration { lights: vec![], light_position: None, occluder: Some(turned), spot: None };
        let moved = configuration.apply_to(&s).meshes.remove(0);
        let (lo, hi) = moved.bounds();
        // 2 x 1 x 1 about (2, 0.5, 1.5): turned a quarter, 1 x 1 x 2 about the same centre, 2 m up.
        assert!(
            (lo - Vec3::new(1.5, 2.0, 0.5)).abs().max_element() < 1e-5 && (hi - Vec3::new(2.5, 3.0, 2.5)).abs().max_element() < 1e-5,
            "{lo} {hi}"
        );
        let x_face = s.meshes[0].normals.iter().position(|n| *n == Vec3::X).unwrap();
        assert!((moved.normals[x_face] - Vec3::NEG_Z).length() < 1e-6, "{}", moved.normals[x_face]);
        assert!(MovedMesh::new(&s, 0, Vec3::ZERO, 0.0).turned.is_none());
    }
}
