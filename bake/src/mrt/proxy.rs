//! The block proxy a scene declares (`extras.relume.mrt`, §6.2): for now the grid shorthand of
//! 2D mazes (spec C): `{"grid": {"origin": [x, y, z], "cell": [sx, sy, sz], "rows": ["#..#",
//! ...]}}`, row r along +z, character c along +x, `.` a block and `#` solid. A block's faces
//! towards its neighbours are open, the others closed; nothing can dangle or overlap.

use super::level::Level;
use crate::scene::Scene;
use crate::settings::{as_object, known_keys, vec3, SceneBlock};
use glam::Vec3;
use serde_json::Value;

const KEY: &str = "mrt";

pub const SCENE_BLOCK: SceneBlock = SceneBlock { key: KEY, check: |block, _| from_block(block).map(|_| ()) };

/// The most blocks a proxy may have (the paper's largest maze has 41).
pub const MAX_BLOCKS: usize = 4096;

#[derive(Clone, Debug, PartialEq)]
pub struct Proxy {
    /// The world position of cell (0, 0)'s minimum corner.
    pub origin: Vec3,
    /// A cell's size along x, y and z, metres.
    pub cell: Vec3,
    /// Each block's cell (x, z), in reading order.
    pub cells: Vec<(i32, i32)>,
}

impl Proxy {
    /// The scene's proxy; refused when it declares none (the method needs its blocks).
    pub fn of(scene: &Scene) -> Result<Proxy, String> {
        match scene.settings.block(KEY) {
            Some(block) => from_block(block),
            None => Err("the scene declares no block proxy (extras.relume.mrt.grid: rows of '.' blocks and '#' solid cells)".into()),
        }
    }

    pub fn level(&self) -> Level {
        Level::new(self.cells.clone()).expect("a grid has one block a cell")
    }

    /// The world position of a point of block `block`'s unit cube.
    pub fn world(&self, block: usize, local: Vec3) -> Vec3 {
        let (x, z) = self.cells[block];
        self.origin + (Vec3::new(x as f32, 0.0, z as f32) + local) * self.cell
    }
}

fn from_block(block: &Value) -> Result<Proxy, String> {
    let key = "extras.relume.mrt";
    let block = as_object(block, key)?;
    known_keys(block, key, &["grid"])?;
    let grid = block.get("grid").ok_or_else(|| format!("{key} needs a grid (origin, cell, rows)"))?;
    let key = "extras.relume.mrt.grid";
    let grid = as_object(grid, key)?;
    known_keys(grid, key, &["origin", "cell", "rows"])?;
    let origin = grid.get("origin").map_or(Ok(Vec3::ZERO), |v| vec3(v, &format!("{key}.origin")))?;
    let cell = grid.get("cell").map_or(Ok(Vec3::splat(2.0)), |v| vec3(v, &format!("{key}.cell")))?;
    if !origin.is_finite() || !cell.is_finite() || cell.min_element() <= 0.0 {
        return Err(format!("{key}: origin must be finite and cell three sizes > 0 (metres)"));
    }
    let rows =
        grid.get("rows").and_then(Value::as_array).ok_or_else(|| format!("{key}.rows must be an array of strings of '.' and '#'"))?;
    let mut cells = Vec::new();
    for (z, row) in rows.iter().enumerate() {
        let row = row.as_str().ok_or_else(|| format!("{key}.rows[{z}] must be a string of '.' and '#'"))?;
        for (x, c) in row.chars().enumerate() {
            match c {
                '.' => cells.push((x as i32, z as i32)),
                '#' => {}
                other => return Err(format!("{key}.rows[{z}] holds '{other}' at {x}; use '.' for a block and '#' for a solid cell")),
            }
        }
    }
    if cells.is_empty() || cells.len() > MAX_BLOCKS {
        return Err(format!("{key}.rows declare {} blocks; give 1..={MAX_BLOCKS} ('.')", cells.len()));
    }
    Ok(Proxy { origin, cell, cells })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_grid_reads_into_blocks_with_their_openings_and_bad_grids_are_refused_by_key() {
        let proxy = from_block(&json!({"grid": {"origin": [1, 0, 0], "cell": [2, 3, 2], "rows": ["..#", "#.."]}})).unwrap();
        assert_eq!(proxy.cells, vec![(0, 0), (1, 0), (1, 1), (2, 1)]);
        assert_eq!(proxy.world(3, Vec3::ONE), Vec3::new(7.0, 3.0, 4.0));
        let level = proxy.level();
        assert_eq!(level.shape(1).open_faces().len(), 2, "a corner block opens to two neighbours");
        for (bad, named) in [
            (json!({"grid": {"rows": ["..x"]}}), "rows[0] holds 'x'"),
            (json!({"grid": {"rows": ["##"]}}), "0 blocks"),
            (json!({"grid": {"cell": [2, 0, 2], "rows": ["."]}}), "sizes > 0"),
            (json!({"grid": {"rows": "..."}}), "rows must be an array"),
            (json!({"blocks": []}), "mrt.blocks is not a relume setting"),
        ] {
            let error = from_block(&bad).unwrap_err();
            assert!(error.contains(named), "{bad}: {error}");
        }
    }
}
