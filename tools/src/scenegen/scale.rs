//! `scale-K`: the scale scene, a hall of K x K bays for measuring how bakes grow with the work
//! (docs/BENCHMARKS.md, "Scale sweep"). A bay is 8 x 8 m under a 3 m ceiling with sixteen
//! desk and chair pairs (the classroom's, 1.6 m apart) and a light at its ceiling's centre (a
//! spot straight down where the bay's row and column sum to an even number, a point light
//! elsewhere); the hall's shell and every box face are welded grids. Every pair is one node
//! instancing one mesh (6 boxes, each face a 3 x 3 grid: 648 triangles), so the file stays small
//! while the scene grows: 10,368 furniture triangles a bay, 1.04 M at K = 10. At the texel
//! density of 8 texels a metre the atlas covers about 15,000 texels a bay (1.48 M at K = 10). It
//! declares no method's block: the light cloud's region, MRT's blocks and the light path maps'
//! test points (the lights where they stand) are derived, as a user's scene's would be.
//!
//! `scale-K-sky` is the same hall without its ceiling, under the `sky` environment: FIV models
//! an environment's light, which the closed hall has none of, and its occluders are then the
//! desk and chair pairs (derived: closed meshes apart from the shell).
//!
//! Not one of the committed scenes (its bakes take minutes to hours); `relume scenes --scale K`
//! (with `--sky`, the open hall) writes it.

use super::gltf_writer::Builder;
use super::scenes::{exposure_one_intensity, panel_chair, panel_desk, Part};
use super::settings::SCALE_SETTINGS;
use glam::DVec3;

/// A bay's side and the hall's height, metres.
const BAY: f64 = 8.0;
const HEIGHT: f64 = 3.0;
/// Grid cells a side of every furniture box face; of the shell, a metre.
const FURNITURE_CELLS: u32 = 3;
const SHELL_CELLS_A_METRE: f64 = 1.0;
/// The bays a side of the largest scale scene `relume scenes --scale` writes.
pub const MAX_BAYS: u32 = 32;

/// The hall of `bays` x `bays` bays; with `sky`, without its ceiling and under the sky.
pub(super) fn scale(bays: u32, sky: bool) -> Builder {
    let mut b = Builder::new(SCALE_SETTINGS);
    let floor = b.material("floor", [0.45, 0.42, 0.38]);
    let wall = b.material("wall", [0.75, 0.73, 0.68]);
    let ceiling = b.material("ceiling", [0.8, 0.8, 0.8]);
    let furniture = b.material("furniture", [0.6, 0.45, 0.3]);
    let side = BAY * bays as f64;
    let (lo, hi) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(side, HEIGHT, side));
    shell(&mut b, lo, hi, [floor, wall, ceiling], sky);
    if sky {
        b.environment("envs/sky.exr", 1.0);
    }
    let pair = pair_mesh(&mut b, furniture);
    for (row, column) in (0..bays).flat_map(|r| (0..bays).map(move |c| (r, c))) {
        let centre = DVec3::new((column as f64 + 0.5) * BAY, 0.0, (row as f64 + 0.5) * BAY);
        for (k, (dx, dz)) in [-2.4, -0.8, 0.8, 2.4].into_iter().flat_map(|z| [-2.4, -0.8, 0.8, 2.4].map(|x| (x, z - 0.2))).enumerate() {
            b.mesh_node(&format!("Pair{row}-{column}-{k}"), pair, centre + DVec3::new(dx, 0.0, dz), DVec3::ONE);
        }
        let light = centre + DVec3::new(0.0, HEIGHT - 0.05, 0.0);
        let intensity = exposure_one_intensity(light.y);
        match (row + column) % 2 {
            0 => b.spot_light(&format!("Spot{row}-{column}"), light, DVec3::NEG_Y, intensity, 45.0, 60.0),
            _ => b.point_light(&format!("Point{row}-{column}"), light, DVec3::NEG_Y, intensity),
        }
    }
    let eye = DVec3::new(0.6, 1.7, 0.6);
    b.camera(
        "Camera",
        eye,
        DVec3::new(side * 0.5, 0.8, side * 0.5).max(eye + DVec3::new(4.0, -0.9, 4.0)),
        60f64.to_radians(),
        None,
        0.05,
        side * 2.0,
    );
    b
}

/// The floor, ceiling (not when `open`) and four walls, each a welded grid of about a metre a
/// cell, facing in.
fn shell(b: &mut Builder, lo: DVec3, hi: DVec3, [floor, wall, ceiling]: [usize; 3], open: bool) {
    let centre = (lo + hi) * 0.5;
    let names = ["Floor", "Ceiling", "BackWall", "FrontWall", "LeftWall", "RightWall"];
    let materials = [floor, ceiling, wall, wall, wall, wall];
    let faces = box_faces(lo, hi).into_iter().zip(names.into_iter().zip(materials));
    for ((quad, _), (name, material)) in faces.filter(|(_, (name, _))| !(open && *name == "Ceiling")) {
        let length = quad[0].distance(quad[1]);
        let cells = (length * SHELL_CELLS_A_METRE).round().max(1.0) as u32;
        let mesh = b.grid_mesh(name, &[quad], cells, |p| centre - p, material);
        b.mesh_node(name, mesh, DVec3::ZERO, DVec3::ONE);
    }
}

/// A desk and its chair (the classroom's panel desk, the chair 36 cm behind it) as one mesh
/// about its footprint's middle: every box face a welded grid, facing out.
fn pair_mesh(b: &mut Builder, material: usize) -> usize {
    let mut parts: Vec<Part> = panel_desk(DVec3::ZERO);
    parts.extend(panel_chair(DVec3::new(0.0, 0.0, 0.36)));
    let faces: Vec<([DVec3; 4], DVec3)> = parts.iter().flat_map(|(_, lo, hi)| box_faces(*lo, *hi)).collect();
    let quads: Vec<[DVec3; 4]> = faces.iter().map(|f| f.0).collect();
    // A face's outward normal, found by its centre (boxes that touch share no face centre).
    let outward = move |centre: DVec3| {
        let nearest = faces.iter().min_by(|a, b| quad_centre(&a.0).distance(centre).total_cmp(&quad_centre(&b.0).distance(centre)));
        nearest.map_or(DVec3::Y, |f| f.1)
    };
    b.grid_mesh("DeskChair", &quads, FURNITURE_CELLS, outward, material)
}

fn quad_centre(q: &[DVec3; 4]) -> DVec3 {
    (q[0] + q[1] + q[2] + q[3]) / 4.0
}

/// The six faces of the box `lo`..`hi`, as quads with their outward normals.
fn box_faces(lo: DVec3, hi: DVec3) -> Vec<([DVec3; 4], DVec3)> {
    let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    vec![
        ([c(lo.x, lo.y, lo.z), c(hi.x, lo.y, lo.z), c(hi.x, lo.y, hi.z), c(lo.x, lo.y, hi.z)], DVec3::NEG_Y),
        ([c(lo.x, hi.y, lo.z), c(hi.x, hi.y, lo.z), c(hi.x, hi.y, hi.z), c(lo.x, hi.y, hi.z)], DVec3::Y),
        ([c(lo.x, lo.y, lo.z), c(hi.x, lo.y, lo.z), c(hi.x, hi.y, lo.z), c(lo.x, hi.y, lo.z)], DVec3::NEG_Z),
        ([c(lo.x, lo.y, hi.z), c(hi.x, lo.y, hi.z), c(hi.x, hi.y, hi.z), c(lo.x, hi.y, hi.z)], DVec3::Z),
        ([c(lo.x, lo.y, lo.z), c(lo.x, lo.y, hi.z), c(lo.x, hi.y, hi.z), c(lo.x, hi.y, lo.z)], DVec3::NEG_X),
        ([c(hi.x, lo.y, lo.z), c(hi.x, lo.y, hi.z), c(hi.x, hi.y, hi.z), c(hi.x, hi.y, lo.z)], DVec3::X),
    ]
}
