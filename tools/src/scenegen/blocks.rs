//! Levels of blocks for modular radiance transfer (002): each `.` of a grid of rows (row r
//! along +z, character c along +x) a 2 m cube room whose sides open onto the blocks next to it;
//! the walls that remain, the floor and the ceiling as inward-facing quads, one per block face
//! (so each lies on one face of one block), and `extras.relume.mrt.grid` declaring the blocks.
//! 002 Table 3's levels: a single cube, a corridor, a small maze of 11 blocks with a cycle and
//! a large one of 41; and the paper's failures: the corridor declared as one long block (Fig.
//! 12), the classroom with its furniture as one block (§8's Great Hall).

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
    b.mrt_grid([0.0; 3], [CELL; 3], rows);
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

/// The corridor's geometry declared as one block 10 x 2 x 2 m (002 Fig. 12: one block for a
/// long hall, the dictionary's cube stretched).
pub(super) fn hall_one_block() -> Builder {
    let mut b = corridor();
    b.mrt_grid([0.0; 3], [5.0 * CELL, CELL, CELL], &["."]);
    b
}

/// The classroom declared as one block, 8 x 3 x 7 m (002 §8's Great Hall: a room with
/// furniture as one block; the desks' and chairs' faces project onto the room's faces).
pub(super) fn classroom_one_block() -> Builder {
    let mut b = super::scenes::classroom();
    b.mrt_grid([-4.0, 0.0, -3.5], [8.0, 3.0, 7.0], &["."]);
    b
}

/// 41 blocks grown from one corner of a 9 x 9 grid by a fixed random walk over the frontier
/// (a 64-bit LCG: the same level everywhere), mostly corridors; the light in the first block,
/// the camera down a corridor.
pub(super) fn maze_large() -> Builder {
    const SIDE: usize = 9;
    let mut open = [[false; SIDE]; SIDE];
    open[0][0] = true;
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    for _ in 1..41 {
        let neighbours = |x: usize, z: usize| {
            [(x.wrapping_sub(1), z), (x + 1, z), (x, z.wrapping_sub(1)), (x, z + 1)]
                .iter()
                .filter(|&&(a, c)| a < SIDE && c < SIDE && open[c][a])
                .count()
        };
        // Cells next to exactly one open cell (corridors), every eighth step any frontier cell
        // (where corridors meet: loops and small halls).
        let any = state >> 61 == 0;
        let pick = |wanted: &dyn Fn(usize) -> bool| -> Vec<(usize, usize)> {
            (0..SIDE * SIDE).map(|i| (i % SIDE, i / SIDE)).filter(|&(x, z)| !open[z][x] && wanted(neighbours(x, z))).collect()
        };
        let mut frontier = pick(&|n| n == 1 || (any && n > 1));
        if frontier.is_empty() {
            frontier = pick(&|n| n > 0);
        }
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let (x, z) = frontier[(state >> 33) as usize % frontier.len()];
        open[z][x] = true;
    }
    let rows: Vec<String> = open.iter().map(|row| row.iter().map(|&o| if o { '.' } else { '#' }).collect()).collect();
    let rows: Vec<&str> = rows.iter().map(String::as_str).collect();
    level(&rows, DVec3::new(0.5, 0.7, 0.5), DVec3::new(4.8, 0.5, 0.5), DVec3::new(0.0, 0.45, 0.5))
}
