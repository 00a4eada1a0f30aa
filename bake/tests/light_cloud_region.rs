//! The light cloud's grid derived from a scene that declares none: over the space the scene's
//! lights reach, and refused, naming the light, when one stands inside closed geometry.
#![cfg(feature = "baking")]

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::region::reachable;
use relume_bake::scene::Scene;
use relume_bake::testing::{closed_box, look_at, material, point_light, scene, square, Facing};

/// A closed 4 x 3 x 4 m room on a 40 x 40 m ground (its bounds ten times the room's width),
/// with a closed block in it and a light at `light`.
fn room_on_ground(light: Vec3) -> Scene {
    let meshes = vec![
        square(Vec3::new(0.0, -0.01, 0.0), Vec3::Z * 20.0, Vec3::X * 20.0, 4, 0),
        closed_box(Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 3.0, 2.0), 2, Facing::Inward, 0),
        closed_box(Vec3::new(0.5, 0.0, 0.5), Vec3::new(1.5, 1.0, 1.5), 1, Facing::Outward, 0),
    ];
    let mut light = point_light(light, Vec3::ONE);
    light.name = "Lamp".into();
    scene(
        "room on ground",
        meshes,
        vec![material("grey", Vec3::splat(0.5), Vec3::ZERO)],
        vec![light],
        look_at(Vec3::new(0.0, 1.5, 1.5), Vec3::ZERO, Vec3::Y, 1.0),
    )
}

#[test]
fn the_grid_spans_the_room_the_light_is_in_not_the_ground_outside() {
    let s = room_on_ground(Vec3::new(-1.0, 2.0, -1.0));
    let derived = reachable(&s, &SceneBvh::new(&s)).unwrap();
    println!("{derived:?}");
    let (min, max) = (derived.grid.min, derived.grid.max);
    // The room within a fine voxel (0.28 m: 24 over the coarse flood's reach), not the ground.
    let (room_lo, room_hi) = (Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 3.0, 2.0));
    assert!((min - room_lo).abs().max_element() < 0.3 && (max - room_hi).abs().max_element() < 0.3, "{min} .. {max}");
    let cells: u32 = derived.grid.counts.iter().product();
    assert!((100..=400).contains(&cells), "{:?}", derived.grid.counts);
}

#[test]
fn a_light_inside_closed_geometry_is_refused_by_name() {
    let s = room_on_ground(Vec3::new(1.0, 0.5, 1.0));
    let refused = reachable(&s, &SceneBvh::new(&s)).err().expect("inside the block");
    assert!(
        refused.contains("\"Lamp\"") && refused.contains("inside closed geometry") && refused.contains("extras.relume.light_cloud.grid"),
        "{refused}"
    );
}

#[test]
fn cornell_reaches_its_whole_box() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell.gltf");
    let s = relume_bake::gltf_load::load(&path).unwrap().scene;
    let derived = reachable(&s, &SceneBvh::new(&s)).unwrap();
    let (lo, hi) = s.settings.bounds;
    assert!(derived.grid.min.distance(lo) < 1e-4 && derived.grid.max.distance(hi) < 1e-4, "{derived:?}");
    assert_eq!(derived.grid.counts, [6, 6, 6]);
}
