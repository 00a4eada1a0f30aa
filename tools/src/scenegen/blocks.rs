//! Levels of blocks for modular radiance transfer (002): each `.` of a grid of rows (row r
//! along +z, character c along +x) a 2 m cube room whose sides open onto the blocks next to it;
//! the walls that remain, the floor and the ceiling as inward-facing quads, one per block face
//! (so each lies on one face of one block), and `extras.relume.mrt.grid` declaring the blocks.
//! 002 Table 3's levels: a single cube, a corridor, a small maze of 11 blocks with a cycle.

use super::geometry::quad_facing;
use super::gltf_writer::Builder;
use super::scenes::exposure_one_intensity;
use super::settings::BLOCKS_SETTINGS;
use glam::DVec3;

/// A block's side, metres.
const CELL: f64 = 2.0;

/// The level of `rows`, lit by a point light at `light` (in cells), seen from `eye` towards
/// `target` (in cells).
fn level(rows: &[&str], light: DVec3, eye: DVec3, target: DVec3) -> Builder {
    let mut b = Builder::new(BLOCKS_SETTINGS);
    let floor = b.material("floor", [0.55, 0.5, 0.45]);
    let wall = b.material("wall", [0.7, 0.7, 0.65]);
    let red = b.material("red-wall", [0.7, 0.15, 0.1]);
    let ceiling = b.material("ceiling", [0.75, 0.75, 0.75]);
    let open = |x: i64, z: i64| rows.get(z as usize).and_then(|r| r.as_bytes().get(x as usize)) == Some(&b'.') && x >= 0 && z >= 0;
    let mut surfaces: [Vec<[DVec3; 3]>; 4] = Default::default();
    for (z, row) in rows.iter().enumerate() {
        for (x, c) in row.bytes().enumerate() {
            if c != b'.' {
                continue;
            }
            let lo = DVec3::new(x as f64, 0.0, z as f64) * CELL;
            let centre = lo + DVec3::splat(CELL / 2.0);
            let (x, z) = (x as i64, z as i64);
            for (axis, side, step) in
                [(0, 0.0, (-1, 0)), (0, 1.0, (1, 0)), (1, 0.0, (0, 0)), (1, 1.0, (0, 0)), (2, 0.0, (0, -1)), (2, 1.0, (0, 1))]
            {
                if axis != 1 && open(x + step.0, z + step.1) {
                    continue;
                }
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let corner = |s: f64, t: f64| {
                    let mut p = lo;
                    p[axis] += side * CELL;
                    p[u] += s * CELL;
                    p[v] += t * CELL;
                    p
                };
                let quad = quad_facing([corner(0.0, 0.0), corner(1.0, 0.0), corner(1.0, 1.0), corner(0.0, 1.0)], |c| centre - c);
                // The wall at the +x end of the first row is red: colour bleeding to follow.
                let which = match (axis, side) {
                    (1, 0.0) => 0,
                    (1, _) => 3,
                    (0, 1.0) if z == 0 && !open(x + 1, z) && x > 0 => 2,
                    _ => 1,
                };
                surfaces[which].extend(quad);
            }
        }
    }
    for ((name, material), tris) in [("Floor", floor), ("Walls", wall), ("RedWall", red), ("Ceiling", ceiling)].into_iter().zip(&surfaces) {
        if !tris.is_empty() {
            let mesh = b.mesh(name, tris, material);
            b.mesh_node(name, mesh, DVec3::ZERO, DVec3::ONE);
        }
    }
    let light = light * CELL;
    b.point_light("BlockLight", light, DVec3::NEG_Y, exposure_one_intensity(light.y));
    b.camera("BlockCamera", eye * CELL, target * CELL, 70f64.to_radians(), Some(1.5), 0.05, 100.0);
    b.mrt_grid(CELL, rows);
    b
}

/// One closed block.
pub(super) fn cube() -> Builder {
    level(&["."], DVec3::new(0.3, 0.7, 0.4), DVec3::new(0.85, 0.5, 0.9), DVec3::new(0.2, 0.4, 0.1))
}

/// Five blocks in a row along +x, the light in the first.
pub(super) fn corridor() -> Builder {
    level(&["....."], DVec3::new(0.5, 0.7, 0.5), DVec3::new(4.8, 0.5, 0.5), DVec3::new(0.0, 0.45, 0.5))
}

/// 11 blocks: two rows of four joined at both ends and in the middle (a cycle), the light in
/// one corner.
pub(super) fn maze() -> Builder {
    level(&["....", ".#..", "...."], DVec3::new(0.5, 0.7, 0.5), DVec3::new(3.8, 0.5, 2.5), DVec3::new(0.0, 0.45, 2.5))
}
