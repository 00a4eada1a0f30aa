//! A level's blocks and T_b->r (§6.3): which block lies next to which, each block as a
//! dictionary shape turned about +y, and the traversal that carries every block's light from
//! its openings through the level. For each source block the traversal is a dynamic programme
//! over (directed crossing, depth) (spec B11): the light reaching a crossing at depth d + 1 is
//! the sum, over the crossings at depth d that lead to it, of R_turn times theirs. That is the
//! sum over every path of at most d_max crossings (cycles included, no U-turns), which the
//! explicit enumeration in the tests checks.

use super::{Face, Samples, Shape};
use glam::Vec3;
#[cfg(feature = "baking")]
use nalgebra::DMatrix;
use std::collections::HashMap;

/// Where light can go: from `block` out through `face` into `to` (entering it through the
/// opposite face).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Crossing {
    pub block: usize,
    pub face: Face,
    pub to: usize,
}

/// A level of blocks joined side to side: each block's side face is open to the block
/// beyond it, if any, which it enters through the opposite face (+x joins -x, +z joins -z);
/// all other faces are closed. Built from grid cells (the 2D maze shorthand, spec C) or from
/// joins found between warped blocks (`proxy`).
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    /// Per block, the block beyond each side face, in `SIDES` order.
    links: Vec<[Option<usize>; 4]>,
}

/// The farthest a cell may lie from the origin along x or z.
const MAX_CELL: i32 = 1 << 20;

/// The side faces, with the grid step they lead to.
const SIDES: [(Face, (i32, i32)); 4] = [
    (Face { axis: 0, positive: false }, (-1, 0)),
    (Face { axis: 0, positive: true }, (1, 0)),
    (Face { axis: 2, positive: false }, (0, -1)),
    (Face { axis: 2, positive: true }, (0, 1)),
];

impl Level {
    /// The level of unit blocks at these grid cells (x, z), neighbouring cells joined; refused
    /// when a cell repeats or lies past 2^20.
    pub fn new(cells: Vec<(i32, i32)>) -> Result<Level, String> {
        let mut at = HashMap::new();
        for (i, cell) in cells.iter().enumerate() {
            if cell.0.abs() > MAX_CELL || cell.1.abs() > MAX_CELL {
                return Err(format!("block {i} stands at cell {cell:?}, past {MAX_CELL} cells from the origin"));
            }
            if let Some(j) = at.insert(*cell, i) {
                return Err(format!("blocks {j} and {i} both stand at cell {cell:?}; give each cell one block"));
            }
        }
        let links = cells.iter().map(|&(x, z)| SIDES.map(|(_, (dx, dz))| at.get(&(x + dx, z + dz)).copied())).collect();
        Ok(Level { links })
    }

    /// The level of blocks joined as `join` says: `join(block, face)` is the block beyond
    /// `block`'s side face `face`, if any. Refused unless every join is mutual (the block
    /// beyond is entered through the opposite face and leads back) and between two blocks.
    pub fn joined(blocks: usize, join: impl Fn(usize, Face) -> Option<usize>) -> Result<Level, String> {
        let links: Vec<[Option<usize>; 4]> = (0..blocks).map(|b| SIDES.map(|(face, _)| join(b, face))).collect();
        let level = Level { links };
        for b in 0..blocks {
            for (face, _) in SIDES {
                let Some(n) = level.neighbour(b, face) else { continue };
                if n >= blocks || n == b || level.neighbour(n, opposite(face)) != Some(b) {
                    return Err(format!(
                        "block {b}'s {} face joins block {n}, which does not join it back through its {} face",
                        face.name(),
                        opposite(face).name()
                    ));
                }
            }
        }
        Ok(level)
    }

    /// The number of blocks.
    pub fn len(&self) -> usize {
        self.links.len()
    }

    pub fn is_empty(&self) -> bool {
        self.links.is_empty()
    }

    /// The block next to `block` through `face`, if any.
    pub fn neighbour(&self, block: usize, face: Face) -> Option<usize> {
        let side = SIDES.iter().position(|(f, _)| *f == face)?;
        self.links[block][side]
    }

    /// Block `block`'s shape: open where a neighbour is.
    pub fn shape(&self, block: usize) -> Shape {
        let open: Vec<Face> = SIDES.iter().map(|(f, _)| *f).filter(|f| self.neighbour(block, *f).is_some()).collect();
        Shape::with_open(&open).expect("side faces only")
    }

    /// The crossings out of `block`.
    pub fn crossings(&self, block: usize) -> Vec<Crossing> {
        SIDES.iter().filter_map(|(face, _)| self.neighbour(block, *face).map(|to| Crossing { block, face: *face, to })).collect()
    }

    /// Where light entering `crossing.to` goes on after `turn`, if that face is open.
    pub fn turn(&self, crossing: Crossing, turn: Turn) -> Option<Crossing> {
        let entry = opposite(crossing.face);
        let out = target(entry, turn);
        self.neighbour(crossing.to, out).map(|to| Crossing { block: crossing.to, face: out, to })
    }
}

impl Level {
    /// Block `block`'s face `face` as a face of its dictionary shape: (the shape's index in
    /// `Shape::dictionary`, the face before the block's turn).
    pub fn dictionary_face(&self, block: usize, face: Face) -> (usize, Face) {
        let (index, quarter_turns) = self.shape(block).canonical();
        (index, face.turned(undo(quarter_turns)))
    }

    /// For each sample of the canonical receiver (`receiver`: open at -z, entered there), the
    /// sample of block `block` entered through `entry` it lands on when turned to it (spec B9:
    /// rows on the block's other openings have none).
    pub fn receiver_rows(&self, receiver: &Samples, block: usize, entry: Face) -> Vec<Option<usize>> {
        let quarter_turns = (0..4).find(|&q| Face { axis: 2, positive: false }.turned(q) == entry).expect("a side face");
        turned_rows(receiver, quarter_turns, &Samples::new(self.shape(block), receiver.grid))
    }

    /// For each sample of block `block`'s dictionary shape (`dictionary`, its samples), the
    /// block's own sample it stands for.
    pub fn own_rows(&self, dictionary: &Samples, block: usize) -> Vec<usize> {
        let (_, quarter_turns) = self.shape(block).canonical();
        let rows = turned_rows(dictionary, quarter_turns, &Samples::new(self.shape(block), dictionary.grid));
        rows.into_iter().map(|r| r.expect("a turned dictionary shape has the block's faces")).collect()
    }
}

/// For each sample of `from`, the sample of `to` it lands on after `quarter_turns` about +y
/// (None on a face `to` lacks).
fn turned_rows(from: &Samples, quarter_turns: u32, to: &Samples) -> Vec<Option<usize>> {
    (0..from.len())
        .map(|i| {
            let (face, p, _) = from.sample(i);
            let (turned, at) = (face.turned(quarter_turns), turn_point(p, quarter_turns));
            let slot = to.faces.iter().position(|f| *f == turned)?;
            let uv = turned.uv(at) * to.grid as f32;
            let (x, y) = ((uv.x as usize).min(to.grid - 1), (uv.y as usize).min(to.grid - 1));
            Some(slot * to.grid * to.grid + y * to.grid + x)
        })
        .collect()
}

/// A point of the unit cube turned about its vertical axis as `Face::turned` turns faces.
pub fn turn_point(p: Vec3, quarter_turns: u32) -> Vec3 {
    turn_direction(p - Vec3::splat(0.5), quarter_turns) + Vec3::splat(0.5)
}

/// A direction turned `quarter_turns` about +y, as `Face::turned` turns faces.
pub fn turn_direction(mut d: Vec3, quarter_turns: u32) -> Vec3 {
    for _ in 0..quarter_turns % 4 {
        d = Vec3::new(d.z, d.y, -d.x);
    }
    d
}

/// The quarter turns that undo `quarter_turns`.
pub fn undo(quarter_turns: u32) -> u32 {
    (4 - quarter_turns % 4) % 4
}

/// The three ways on from an interface across an empty block. Left and right are spec B10's
/// frame's (right = up x the travel): in glTF's right-handed frame with +y up that is the
/// traveller's own left, so `Right` turns to the traveller's left. Both sides of every
/// operator use `target`, so only the names differ from the paper's R_left and R_right.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Turn {
    Ahead,
    Left,
    Right,
}

/// The face of a block entered through `entry` that light leaves through after `turn`.
pub fn target(entry: Face, turn: Turn) -> Face {
    let n = entry.inward();
    let right = Vec3::Y.cross(n);
    let out = match turn {
        Turn::Ahead => n,
        Turn::Right => right,
        Turn::Left => -right,
    };
    Face::ALL.into_iter().find(|f| (-f.inward()).abs_diff_eq(out, 1e-6)).expect("a side face")
}

/// The same face on the other side: the face of the next block that a face leads into.
pub fn opposite(face: Face) -> Face {
    Face { axis: face.axis, positive: !face.positive }
}

#[cfg(feature = "baking")]
/// The light of one source block at every crossing it reaches within `d_max` crossings: for
/// each crossing, the sum over paths of the product of R_b->rlf (`from`) and the turns' R
/// (k_rlf x k_self). `from(crossing)` gives R_b->rlf for the source's own openings. With
/// `d_max` 0 nothing is reached.
pub fn traverse(
    level: &Level,
    source: usize,
    d_max: usize,
    from: impl Fn(Crossing) -> DMatrix<f64>,
    turn: impl Fn(Turn) -> DMatrix<f64>,
) -> HashMap<Crossing, DMatrix<f64>> {
    let turns = [Turn::Ahead, Turn::Left, Turn::Right].map(|t| (t, turn(t)));
    if d_max == 0 {
        return HashMap::new();
    }
    let mut frontier: HashMap<Crossing, DMatrix<f64>> = level.crossings(source).into_iter().map(|c| (c, from(c))).collect();
    let mut reached = frontier.clone();
    for _ in 1..d_max {
        let mut next: HashMap<Crossing, DMatrix<f64>> = HashMap::new();
        // A fixed order of crossings, so the sums do not depend on the map's iteration order.
        let mut order: Vec<&Crossing> = frontier.keys().collect();
        order.sort_by_key(|c| (c.block, c.face.index(), c.to));
        for crossing in order {
            for (t, r) in &turns {
                if let Some(on) = level.turn(*crossing, *t) {
                    let carried = r * &frontier[crossing];
                    next.entry(on).and_modify(|m| *m += &carried).or_insert(carried);
                }
            }
        }
        let mut order: Vec<(&Crossing, &DMatrix<f64>)> = next.iter().collect();
        order.sort_by_key(|(c, _)| (c.block, c.face.index(), c.to));
        for (crossing, light) in order {
            reached.entry(*crossing).and_modify(|m| *m += light).or_insert_with(|| light.clone());
        }
        frontier = next;
    }
    reached
}
