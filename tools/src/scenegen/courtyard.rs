//! `courtyard`: a scene where every method has work. A 6 x 4 m paved courtyard inside four
//! walls 2.5 m high, its south half under a roof: an interior lit by the sky through the open
//! half (`envs/sky.exr` at half its radiance, whose sun stands 50 degrees up over the south-east
//! corner, behind the camera) and by two spot lights, a downlight under the roof and a lamp on a
//! bracket off the west wall over the open half; a sculpture (a lumpy blob) and a crate stand on
//! the paving (the ground) (FIV's occluders, which a sweep may
//! move). The scene declares no method's settings: each method derives what it needs (the
//! light cloud's grid, modular radiance transfer's blocks, FIV's occluders, light path maps'
//! region), so the chart shows what each models and misses: the ambient methods the sky's
//! light (unshadowed or occluded), FIV the sky's direct light with the walls', roof's and
//! figures' shadows, the local-light methods the lamps' indirect light.

use super::geometry::{blob, quad_facing, unit_cube};
use super::gltf_writer::Builder;
use super::scenes::{add_boxes, exposure_one_intensity, Part};
use super::settings::COURTYARD_SETTINGS;
use glam::DVec3;

/// The paving's half extents (x, z), the walls' height and thickness, metres.
const HALF: (f64, f64) = (3.0, 2.0);
const HEIGHT: f64 = 2.5;
const THICK: f64 = 0.2;

pub(super) fn courtyard() -> Builder {
    let mut b = Builder::new(COURTYARD_SETTINGS);
    let paving = b.material("paving", [0.5, 0.48, 0.45]);
    let plaster = b.material("plaster", [0.75, 0.72, 0.66]);
    let roof = b.material("roof", [0.6, 0.6, 0.62]);
    let stone = b.material("stone", [0.6, 0.6, 0.6]);
    let crate_wood = b.material("crate", [0.65, 0.32, 0.18]);
    let (x, z) = HALF;
    let floor = [DVec3::new(-x, 0.0, -z), DVec3::new(x, 0.0, -z), DVec3::new(x, 0.0, z), DVec3::new(-x, 0.0, z)];
    let mesh = b.mesh("Ground", &quad_facing(floor, |_| DVec3::Y), paving);
    b.mesh_node("Ground", mesh, DVec3::ZERO, DVec3::ONE);
    // North and south walls run the whole width, corners included; east and west between.
    let walls: Vec<Part> = vec![
        ("North".into(), DVec3::new(-x - THICK, 0.0, -z - THICK), DVec3::new(x + THICK, HEIGHT, -z)),
        ("South".into(), DVec3::new(-x - THICK, 0.0, z), DVec3::new(x + THICK, HEIGHT, z + THICK)),
        ("West".into(), DVec3::new(-x - THICK, 0.0, -z), DVec3::new(-x, HEIGHT, z)),
        ("East".into(), DVec3::new(x, 0.0, -z), DVec3::new(x + THICK, HEIGHT, z)),
    ];
    let wall_cube = b.mesh("WallCube", &unit_cube(), plaster);
    add_boxes(&mut b, "Wall", wall_cube, &walls);
    // The roof over the south half, resting on the walls.
    let roof_cube = b.mesh("RoofCube", &unit_cube(), roof);
    add_boxes(
        &mut b,
        "",
        roof_cube,
        &[("Roof".into(), DVec3::new(-x - THICK, HEIGHT, 0.0), DVec3::new(x + THICK, HEIGHT + THICK, z + THICK))],
    );
    let sculpture = b.mesh("Sculpture", &blob(0.35, 3), stone);
    b.mesh_node("Sculpture", sculpture, DVec3::new(1.0, 0.4, -0.9), DVec3::ONE);
    let crate_cube = b.mesh("CrateCube", &unit_cube(), crate_wood);
    add_boxes(&mut b, "", crate_cube, &[("Crate".into(), DVec3::new(-1.5, 0.0, 0.5), DVec3::new(-0.9, 0.5, 1.1))]);
    // A downlight under the roof: pi lux on the paving below it.
    let lamp = DVec3::new(0.5, 2.4, 1.2);
    b.spot_light("Downlight", lamp, DVec3::NEG_Y, exposure_one_intensity(lamp.y), 45.0, 60.0);
    // A lamp on a bracket a metre off the west wall, over the open half: pi lux on the paving
    // below it, its cone's edge reaching up the wall.
    let spot = DVec3::new(-2.0, 2.2, -1.0);
    b.spot_light("WallSpot", spot, DVec3::NEG_Y, exposure_one_intensity(spot.y), 30.0, 45.0);
    // Half the sky's radiance: the open paving then takes about as much from the sky as the
    // paving under a lamp takes from the lamp (pi lux).
    b.environment("envs/sky.exr", 0.5);
    b.camera("Camera", DVec3::new(2.6, 1.6, 1.7), DVec3::new(-1.2, 0.7, -1.2), 60f64.to_radians(), None, 0.05, 30.0);
    b
}
