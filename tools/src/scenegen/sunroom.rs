//! `sunroom`: a room lit by the sun alone, through a skylight. A 5 x 4 m room 2.6 m high
//! (every face a welded grid, so per-vertex methods have vertices across it), its ceiling cut
//! by a 1.2 x 1.2 m skylight; a directional light straight down through it (π lux on the
//! floor below), a table half in the sun patch and a cabinet against the back wall. The light
//! that fills the room is the sun patch's bounce: what a directional light's indirect light
//! looks like indoors. It declares no method's settings.

use super::geometry::unit_cube;
use super::gltf_writer::Builder;
use super::scenes::{add_boxes, Part};
use super::settings::SUNROOM_SETTINGS;
use glam::DVec3;

/// The room's corners and the skylight's extent in x and z, metres.
const LO: DVec3 = DVec3::new(-2.5, 0.0, -2.0);
const HI: DVec3 = DVec3::new(2.5, 2.6, 2.0);
const SKYLIGHT: ([f64; 2], [f64; 2]) = ([-1.4, -0.2], [-1.2, 0.0]);
/// Grid cells a metre on every face.
const CELLS_A_METRE: f64 = 3.0;

pub(super) fn sunroom() -> Builder {
    let mut b = Builder::new(SUNROOM_SETTINGS);
    let floor = b.material("floor", [0.5, 0.42, 0.34]);
    let wall = b.material("wall", [0.75, 0.73, 0.68]);
    let ceiling = b.material("ceiling", [0.8, 0.8, 0.8]);
    let wood = b.material("table", [0.55, 0.4, 0.28]);
    let cabinet = b.material("cabinet", [0.35, 0.45, 0.55]);
    let centre = (LO + HI) * 0.5;
    let inward = |c: DVec3| centre - c;
    let ([x0, x1], [z0, z1]) = SKYLIGHT;
    let (lo, hi) = (LO, HI);
    let at = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let surfaces: [(&str, Vec<[DVec3; 4]>, usize); 6] = [
        ("Floor", vec![[at(lo.x, 0.0, lo.z), at(hi.x, 0.0, lo.z), at(hi.x, 0.0, hi.z), at(lo.x, 0.0, hi.z)]], floor),
        (
            "Ceiling",
            // The ceiling less the skylight: the strips in front of and behind it, and either side.
            [(lo.x, hi.x, lo.z, z0), (lo.x, hi.x, z1, hi.z), (lo.x, x0, z0, z1), (x1, hi.x, z0, z1)]
                .map(|(a, b, c, d)| [at(a, hi.y, c), at(b, hi.y, c), at(b, hi.y, d), at(a, hi.y, d)])
                .to_vec(),
            ceiling,
        ),
        ("BackWall", vec![[at(lo.x, 0.0, lo.z), at(hi.x, 0.0, lo.z), at(hi.x, hi.y, lo.z), at(lo.x, hi.y, lo.z)]], wall),
        ("FrontWall", vec![[at(lo.x, 0.0, hi.z), at(hi.x, 0.0, hi.z), at(hi.x, hi.y, hi.z), at(lo.x, hi.y, hi.z)]], wall),
        ("LeftWall", vec![[at(lo.x, 0.0, lo.z), at(lo.x, 0.0, hi.z), at(lo.x, hi.y, hi.z), at(lo.x, hi.y, lo.z)]], wall),
        ("RightWall", vec![[at(hi.x, 0.0, lo.z), at(hi.x, 0.0, hi.z), at(hi.x, hi.y, hi.z), at(hi.x, hi.y, lo.z)]], wall),
    ];
    for (name, quads, material) in surfaces {
        // Each quad's grid about CELLS_A_METRE cells a metre along its longer side.
        let longest = quads.iter().map(|q| (q[1] - q[0]).length().max((q[3] - q[0]).length())).fold(0.0, f64::max);
        let mesh = b.grid_mesh(name, &quads, (longest * CELLS_A_METRE).round() as u32, inward, material);
        b.mesh_node(name, mesh, DVec3::ZERO, DVec3::ONE);
    }
    let table_cube = b.mesh("TableCube", &unit_cube(), wood);
    let (t0, t1) = (DVec3::new(-0.6, 0.0, -0.7), DVec3::new(0.6, 0.0, 0.1));
    let mut table: Vec<Part> = vec![("Top".into(), DVec3::new(t0.x, 0.7, t0.z), DVec3::new(t1.x, 0.75, t1.z))];
    for (i, (x, z)) in [(t0.x, t0.z), (t1.x - 0.06, t0.z), (t0.x, t1.z - 0.06), (t1.x - 0.06, t1.z - 0.06)].into_iter().enumerate() {
        table.push((format!("Leg{i}"), DVec3::new(x, 0.0, z), DVec3::new(x + 0.06, 0.7, z + 0.06)));
    }
    add_boxes(&mut b, "Table", table_cube, &table);
    let cabinet_cube = b.mesh("CabinetCube", &unit_cube(), cabinet);
    add_boxes(&mut b, "", cabinet_cube, &[("Cabinet".into(), DVec3::new(1.2, 0.0, lo.z), DVec3::new(2.2, 1.8, lo.z + 0.5))]);
    // Straight down through the skylight: π lux on the floor below it.
    let sun = DVec3::new((x0 + x1) * 0.5, hi.y + 1.0, (z0 + z1) * 0.5);
    b.directional_light("Sun", sun, DVec3::NEG_Y, std::f64::consts::PI);
    b.camera("Camera", DVec3::new(2.1, 1.6, 1.7), DVec3::new(-0.8, 0.4, -0.8), 60f64.to_radians(), None, 0.05, 20.0);
    b
}
