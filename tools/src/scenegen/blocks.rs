//! Levels of blocks for modular radiance transfer (002): each `.` of a grid of rows (row r
//! along +z, character c along +x) a 2 m cube room whose sides open onto the blocks next to it;
//! the walls that remain, the floor and the ceiling facing inward, each block face a welded 4 x
//! 4 grid (so each lies on one face of one block), and `extras.relume.mrt.grid` declaring the
//! blocks (`mrt.blocks`, by their corners, for the warped cave); each level also declares a
//! light cloud and light path maps' region, for the other local-light methods. 002 Table 3's
//! levels: a single cube, a corridor, a small maze of 11 blocks with a cycle and a large one of
//! 41; Fig. 1's cave of 19 warped blocks; and the paper's failures: the corridor declared as
//! one long block (Fig. 12), the classroom with its furniture as one block (§8's Great Hall).

use super::geometry::{blob, lcg};
use super::gltf_writer::Builder;
use super::scenes::exposure_one_intensity;
use super::settings::{Settings, BLOCKS_SETTINGS};
use glam::DVec3;

/// A block's side, metres.
const CELL: f64 = 2.0;

/// The level of `rows`, lit by a point light at `light` (in cells), seen from `eye` towards
/// `target` (in cells), declared as a grid.
fn level(rows: &[&str], light: DVec3, eye: DVec3, target: DVec3) -> Builder {
    let mut b = surfaces(rows, &|p| p * CELL, &[light], eye, target);
    b.mrt_grid([0.0; 3], [CELL; 3], rows);
    b
}

/// Cells a block face's side is split into (a welded grid): vertices every 50 cm, for the
/// per-vertex light clouds beside MRT.
const SPLIT: usize = 4;

/// The surfaces of the level of `rows` with grid points (in cells) placed by `warp`, each block
/// face as `SPLIT` x `SPLIT` quads, lit by point lights at `lights` and seen from `eye`
/// towards `target` (grid points). The other local-light methods get the level too: a light
/// cloud of two cloud lights a block per axis, two high, and light path maps' region over the
/// level's whole floor plan between 1.2 and 1.6 m.
fn surfaces(rows: &[&str], warp: &dyn Fn(DVec3) -> DVec3, lights: &[DVec3], eye: DVec3, target: DVec3) -> Builder {
    let size = DVec3::new(rows.iter().map(|r| r.len()).max().unwrap_or(0) as f64, 1.0, rows.len() as f64);
    let columns = size.x as usize + 1;
    let layer = |y: f64| (0..columns * (size.z as usize + 1)).map(move |n| warp(DVec3::new((n % columns) as f64, y, (n / columns) as f64)));
    let (lo, hi) = layer(0.0).chain(layer(1.0)).fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let region = ([lo.x, 1.2, lo.z], [hi.x, 1.6, hi.z], 64);
    let mut b = Builder::new(Settings { light_region: Some(region), ..BLOCKS_SETTINGS });
    // The cloud between the highest floor point and the lowest ceiling point: inside the level.
    let (top_of_floor, foot_of_ceiling) =
        (layer(0.0).map(|p| p.y).fold(f64::MIN, f64::max), layer(1.0).map(|p| p.y).fold(f64::MAX, f64::min));
    let counts = (size * 2.0).as_uvec3();
    b.light_cloud_grid(lo.with_y(top_of_floor), hi.with_y(foot_of_ceiling), counts.to_array());
    let floor = b.material("floor", [0.55, 0.5, 0.45]);
    let wall = b.material("wall", [0.7, 0.7, 0.65]);
    let red = b.material("red-wall", [0.7, 0.15, 0.1]);
    let ceiling = b.material("ceiling", [0.75, 0.75, 0.75]);
    let open = |x: i64, z: i64| rows.get(z as usize).and_then(|r| r.as_bytes().get(x as usize)) == Some(&b'.') && x >= 0 && z >= 0;
    let mut surfaces: [Vec<[DVec3; 4]>; 4] = Default::default();
    // Each face quad's centre and the centre of the block it faces into.
    let mut facing: Vec<(DVec3, DVec3)> = Vec::new();
    for (z, row) in rows.iter().enumerate() {
        for (x, c) in row.bytes().enumerate() {
            if c != b'.' {
                continue;
            }
            let lo = DVec3::new(x as f64, 0.0, z as f64);
            let centre = warp(lo + DVec3::splat(0.5));
            let (x, z) = (x as i64, z as i64);
            for (axis, side, step) in
                [(0, 0.0, (-1, 0)), (0, 1.0, (1, 0)), (1, 0.0, (0, 0)), (1, 1.0, (0, 0)), (2, 0.0, (0, -1)), (2, 1.0, (0, 1))]
            {
                if axis != 1 && open(x + step.0, z + step.1) {
                    continue;
                }
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let corner = |i: f64, j: f64| {
                    let mut p = lo;
                    p[axis] += side;
                    p[u] += i;
                    p[v] += j;
                    warp(p)
                };
                // On a face the trilinear warp is the bilinear blend of its corners, as the grid
                // mesh splits it.
                let quad = [corner(0.0, 0.0), corner(1.0, 0.0), corner(1.0, 1.0), corner(0.0, 1.0)];
                facing.push((quad.iter().sum::<DVec3>() / 4.0, centre));
                // The wall at the +x end of the first row is red: colour bleeding to follow.
                let which = match (axis, side) {
                    (1, 0.0) => 0,
                    (1, _) => 3,
                    (0, 1.0) if z == 0 && !open(x + 1, z) && x > 0 => 2,
                    _ => 1,
                };
                surfaces[which].push(quad);
            }
        }
    }
    let inward = |c: DVec3| facing.iter().find(|(q, _)| q.distance(c) < 1e-9).map_or(DVec3::ZERO, |(_, centre)| *centre - c);
    for ((name, material), quads) in [("Floor", floor), ("Walls", wall), ("RedWall", red), ("Ceiling", ceiling)].into_iter().zip(&surfaces)
    {
        if !quads.is_empty() {
            let mesh = b.grid_mesh(name, quads, SPLIT as u32, inward, material);
            b.mesh_node(name, mesh, DVec3::ZERO, DVec3::ONE);
        }
    }
    for (i, light) in lights.iter().enumerate() {
        let name = if i == 0 { "BlockLight".to_string() } else { format!("BlockLight{i}") };
        // Pointed straight at the floor below, pi lux there (the floor is one plane).
        let floor = |dx: f64, dz: f64| warp(DVec3::new(light.x + dx, 0.0, light.z + dz));
        let up = (floor(0.0, 0.25) - floor(0.0, 0.0)).cross(floor(0.25, 0.0) - floor(0.0, 0.0)).normalize();
        let at = warp(*light);
        b.point_light(&name, at, -up, exposure_one_intensity((at - floor(0.0, 0.0)).dot(up)));
    }
    b.camera("BlockCamera", warp(eye), warp(target), 70f64.to_radians(), Some(1.5), 0.05, 100.0);
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

/// 002 Fig. 5: the maze with two figures (a lumpy blob 0.6 m wide and 1.2 m tall, an
/// untextured stand-in for a character) standing in its third row, where the light arrives
/// round the cycle, declared dynamic (`extras.relume.mrt.dynamic`): the light volume lights
/// them; they are not mapped onto the blocks.
pub(super) fn figures() -> Builder {
    let mut b = maze();
    let stone = b.material("figure", [0.6, 0.6, 0.6]);
    let figure = b.smooth_mesh("Figure", &blob(0.3, 3), stone);
    let tall = DVec3::new(1.0, 2.0, 1.0);
    b.mesh_node("Figure", figure, DVec3::new(5.0, 0.62, 4.7), tall);
    b.mesh_node("Figure.001", figure, DVec3::new(2.6, 0.62, 5.4), tall);
    b.mrt_dynamic(&["Figure", "Figure.001"]);
    b
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
        let (x, z) = frontier[(lcg(&mut state) >> 33) as usize % frontier.len()];
        open[z][x] = true;
    }
    let rows: Vec<String> = open.iter().map(|row| row.iter().map(|&o| if o { '.' } else { '#' }).collect()).collect();
    let rows: Vec<&str> = rows.iter().map(String::as_str).collect();
    level(&rows, DVec3::new(0.5, 0.7, 0.5), DVec3::new(4.8, 0.5, 0.5), DVec3::new(0.0, 0.45, 0.5))
}

/// 002 Fig. 1's cave: 19 blocks of a winding grid with two cycles, every lattice point moved
/// along x and z by up to ±15 % of a side (a fixed 64-bit LCG) and the floor and the ceiling
/// tilted two ways, so the blocks are warped cubes (trilinear from their 8 corners) whose faces
/// are flat (the scene's triangles lie on them); the faces 4 x 4 quads; four point lights; the
/// blocks declared by their corners (`extras.relume.mrt.blocks`).
pub(super) fn cave() -> Builder {
    const ROWS: [&str; 5] = ["...##", ".#...", "...#.", "#.#..", "....."];
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut jitter = || ((lcg(&mut state) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * 0.15;
    // Lattice point (i, j, k) of the 6 x 2 x 6 grid points, moved; a column's two points
    // share x and z, so the walls stand upright and are flat.
    let columns: Vec<(f64, f64)> = (0..36).map(|n| ((n % 6) as f64 + jitter(), (n / 6) as f64 + jitter())).collect();
    let lattice: Vec<DVec3> = (0..72)
        .map(|n| {
            let (x, z) = columns[(n / 12) * 6 + n % 6];
            let y = if (n / 6) % 2 == 0 { 0.06 * x - 0.04 * z } else { 1.0 - 0.04 * x + 0.05 * z };
            DVec3::new(x, y, z)
        })
        .collect();
    let point = |i: usize, j: usize, k: usize| lattice[k.min(5) * 12 + j.min(1) * 6 + i.min(5)] * CELL;
    let warp = move |p: DVec3| {
        let cell = p.floor().clamp(DVec3::ZERO, DVec3::new(4.0, 0.0, 4.0));
        let (f, [i, j, k]) = (p - cell, [cell.x as usize, cell.y as usize, cell.z as usize]);
        let corner = |n: usize| point(i + (n & 1), j + ((n >> 1) & 1), k + ((n >> 2) & 1));
        (0..8)
            .map(|n| {
                let w = |bit: usize, t: f64| if n & (1 << bit) != 0 { t } else { 1.0 - t };
                corner(n) * w(0, f.x) * w(1, f.y) * w(2, f.z)
            })
            .sum()
    };
    let lights = [DVec3::new(0.5, 0.7, 0.5), DVec3::new(3.5, 0.7, 1.5), DVec3::new(1.5, 0.7, 2.5), DVec3::new(4.5, 0.7, 4.5)];
    let mut b = surfaces(&ROWS, &warp, &lights, DVec3::new(1.5, 0.55, 4.7), DVec3::new(1.5, 0.45, 1.0));
    let cells = ROWS.iter().enumerate().flat_map(|(z, row)| row.bytes().enumerate().filter(|c| c.1 == b'.').map(move |(x, _)| (x, z)));
    let blocks = cells
        .map(|(x, z)| std::array::from_fn(|n| warp(DVec3::new((x + (n & 1)) as f64, ((n >> 1) & 1) as f64, (z + ((n >> 2) & 1)) as f64))));
    b.mrt_blocks(&blocks.collect::<Vec<[DVec3; 8]>>());
    b
}
