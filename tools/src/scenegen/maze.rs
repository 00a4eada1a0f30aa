//! 004's Maze scene (Table 1: 42,450 triangles, 1,024 cloud lights, half of them above the
//! maze, its Fig. 4): a maze of 8 x 8 corridors half a metre wide, cut by a recursive
//! backtracker with a fixed seed, walls half a metre tall and 5 cm thick standing open to the
//! sky on a 4 x 4 m floor. Every face is a welded grid (per-vertex transfer needs vertices).

use super::gltf_writer::Builder;
use super::scenes::exposure_one_intensity;
use super::settings::MAZE_SETTINGS;
use glam::DVec3;

/// Cells a side, the cell's and the walls' size (metres).
const CELLS: usize = 8;
const CELL: f64 = 0.5;
const HEIGHT: f64 = 0.5;
const THICKNESS: f64 = 0.05;

/// The maze's wall segments, each from one grid corner `(i, j)` to the next along x or z: the
/// border, and between every two cells the backtracker did not join.
fn wall_segments() -> Vec<([usize; 2], [usize; 2])> {
    // joined[cell][k]: the wall on side k (0 +x, 1 +z) of the cell is open.
    let mut joined = [[false; 2]; CELLS * CELLS];
    let mut visited = [false; CELLS * CELLS];
    let mut stack = vec![0usize];
    visited[0] = true;
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    while let Some(&cell) = stack.last() {
        let (x, z) = (cell % CELLS, cell / CELLS);
        let neighbours: Vec<usize> =
            [(x + 1 < CELLS, cell + 1), (z + 1 < CELLS, cell + CELLS), (x > 0, cell.wrapping_sub(1)), (z > 0, cell.wrapping_sub(CELLS))]
                .into_iter()
                .filter(|&(inside, next)| inside && !visited[next])
                .map(|(_, next)| next)
                .collect();
        if neighbours.is_empty() {
            stack.pop();
            continue;
        }
        let next = neighbours[(super::geometry::lcg(&mut state) >> 33) as usize % neighbours.len()];
        let (low, high) = (cell.min(next), cell.max(next));
        joined[low][usize::from(high - low == CELLS)] = true;
        visited[next] = true;
        stack.push(next);
    }
    let mut segments = Vec::new();
    for j in 0..CELLS {
        for i in 0..CELLS {
            let cell = j * CELLS + i;
            // The wall on the cell's +x side, then on its +z side (the border's included).
            if i + 1 == CELLS || !joined[cell][0] {
                segments.push(([i + 1, j], [i + 1, j + 1]));
            }
            if j + 1 == CELLS || !joined[cell][1] {
                segments.push(([i, j + 1], [i + 1, j + 1]));
            }
        }
        segments.push(([0, j], [0, j + 1]));
    }
    segments.extend((0..CELLS).map(|i| ([i, 0], [i + 1, 0])));
    segments
}

/// A grid corner in metres: the maze centred on the origin.
fn corner([i, j]: [usize; 2]) -> DVec3 {
    let half = CELLS as f64 * CELL / 2.0;
    DVec3::new(i as f64 * CELL - half, 0.0, j as f64 * CELL - half)
}

/// The five faces (all but the bottom) of the box from `lo` to `hi`, each corner order as
/// `Builder::grid_mesh` takes it.
fn box_faces(lo: DVec3, hi: DVec3) -> [[DVec3; 4]; 5] {
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    [
        [p(lo.x, hi.y, lo.z), p(hi.x, hi.y, lo.z), p(hi.x, hi.y, hi.z), p(lo.x, hi.y, hi.z)],
        [p(lo.x, lo.y, lo.z), p(hi.x, lo.y, lo.z), p(hi.x, hi.y, lo.z), p(lo.x, hi.y, lo.z)],
        [p(lo.x, lo.y, hi.z), p(hi.x, lo.y, hi.z), p(hi.x, hi.y, hi.z), p(lo.x, hi.y, hi.z)],
        [p(lo.x, lo.y, lo.z), p(lo.x, lo.y, hi.z), p(lo.x, hi.y, hi.z), p(lo.x, hi.y, lo.z)],
        [p(hi.x, lo.y, lo.z), p(hi.x, lo.y, hi.z), p(hi.x, hi.y, hi.z), p(hi.x, hi.y, lo.z)],
    ]
}

pub(super) fn maze() -> Builder {
    let mut b = Builder::new(MAZE_SETTINGS);
    let floor = b.material("floor", [0.6, 0.58, 0.55]);
    let wall = b.material("wall", [0.7, 0.45, 0.3]);
    let half = CELLS as f64 * CELL / 2.0;
    let ground = [DVec3::new(-half, 0.0, -half), DVec3::new(half, 0.0, -half), DVec3::new(half, 0.0, half), DVec3::new(-half, 0.0, half)];
    let mesh = b.grid_mesh("Floor", &[ground], 80, |_| DVec3::Y, floor);
    b.mesh_node("Floor", mesh, DVec3::ZERO, DVec3::ONE);
    let boxes: Vec<(DVec3, DVec3)> = wall_segments()
        .into_iter()
        .map(|(a, c)| {
            let (a, c) = (corner(a), corner(c));
            let pad = DVec3::splat(THICKNESS / 2.0).with_y(0.0);
            (a.min(c) - pad, a.max(c) + pad + DVec3::Y * HEIGHT)
        })
        .collect();
    let faces: Vec<[DVec3; 4]> = boxes.iter().flat_map(|&(lo, hi)| box_faces(lo, hi)).collect();
    // A face faces away from the box it bounds: the first whose bounds hold its centre.
    let outward = |c: DVec3| {
        let (lo, hi) = boxes.iter().find(|(lo, hi)| c.cmpge(*lo - 1e-9).all() && c.cmple(*hi + 1e-9).all()).expect("a face of a box");
        c - (*lo + *hi) / 2.0
    };
    let mesh = b.grid_mesh("Walls", &faces, 6, outward, wall);
    b.mesh_node("Walls", mesh, DVec3::ZERO, DVec3::ONE);
    // In the corridor of the maze's middle cell, at two thirds of the walls' height.
    let light_position = DVec3::new(0.25, 0.35, 0.25);
    b.point_light("MazePoint", light_position, DVec3::NEG_Y, exposure_one_intensity(light_position.y));
    // 16 x 16 x 4: cell centres 12.5 cm from the walls' centrelines, two layers in the maze and
    // two above it.
    b.light_cloud_grid(DVec3::new(-half, 0.0, -half), DVec3::new(half, 2.0 * HEIGHT, half), [16, 4, 16]);
    b.camera("MazeCamera", DVec3::new(0.0, 3.2, 3.4), DVec3::new(0.0, 0.0, 0.2), 55f64.to_radians(), Some(1.0), 0.05, 20.0);
    b
}
