//! A block proxy derived from a scene that declares none (002 §6.2's proxy; at least §8's
//! Great Hall, the scene's bounds as one block): a floor plan of columns on a cell about a
//! room's height (the dictionary's blocks are cubes, and stretched ones fail: 002 Fig. 12),
//! each column a block where its middle is inside the rooms, neighbouring blocks joined where
//! no wall stands between them, and the lattice moved onto the walls it nearly meets, so a
//! maze-like model gets a maze and a cave of tilted, bent walls its warped blocks.
//!
//! 1. The room height h: the median, over a 16 x 16 grid of points, of the distance from the
//!    lowest surface to the highest where that faces down (a ceiling), both found from outside
//!    the bounds; the bounds' height without ceilings (a maze open to the sky).
//! 2. The lattice: along x and z, round(extent / h) cells (at least 1) over the bounds.
//! 3. A cell is free where, at most of 5 points at its middle height, at least 9 of 14 rays
//!    (the axes and the cube's diagonals) first meet a surface facing them: inside a room, not
//!    inside a wall's or a solid cell's back faces, not outside the model. Without any room (a
//!    model on open ground), the bounds are one block.
//! 4. Two free cells are joined unless most of 3 x 3 segments across their shared face are
//!    blocked (a wall between them).
//! 5. Each lattice point that a wall nearly meets moves onto it: every closed face of a free
//!    cell whose wall triangles near it cover at least half of it (a wall, not furniture)
//!    takes their line in plan, and a point goes to the least-squares meeting of its faces'
//!    lines (at most 0.45 of a cell).
//! 6. Each free cell's floor and ceiling are planes through vertical ray hits at 3 x 3 points;
//!    a lattice point's heights are the mean of its free cells' planes there.
//!
//! Triangles that cross a block boundary are split there (`split`: a floor under several
//! blocks, a desk across a boundary), and the meshes with a triangle still on no block face
//! (within `REACH` of one) go to the light volume, as declared dynamic meshes do. What was derived is returned as a scene would declare it
//! (`extras.relume.mrt`: a grid when the lattice is a plain grid with every neighbour joined,
//! else warped blocks by their corners with their walls between touching blocks `closed`).

use super::level::Level;
use super::map::unplaced;
use super::proxy::{check_shape, Proxy};
use super::split::{split, Side};
use super::Face;
use crate::bvh::SceneBvh;
use crate::scene::Scene;
use crate::tessellation::Tessellation;
use glam::{DVec2, DVec3, Vec3};
use serde_json::{json, Value};

/// A proxy derived from a scene, the meshes left to the light volume, and the proxy as a scene
/// would declare it.
pub struct Derived {
    pub proxy: Proxy,
    /// The scene's triangles split at the blocks' boundaries (None: none crossed one); the
    /// proxy and `dynamic` are for the scene with it applied.
    pub split: Option<Tessellation>,
    /// The meshes (ascending) no block face holds: lit by the light volume, as `mrt.dynamic`.
    pub dynamic: Vec<usize>,
    /// The proxy as `extras.relume.mrt` would declare it.
    pub declared: Value,
    /// Blocks of cells in x and z.
    pub cells: [usize; 2],
}

/// How far past a derived block's face a triangle may reach, in face widths: derived faces
/// stand in walls' middles and at rooms' bounds, so a wall's thickness, its top, or a
/// cornice reaches a little past them.
const REACH: f32 = 0.15;

/// Rays from a cell's middle that must meet a surface facing them for the cell to be free.
const FRONT_RAYS: usize = 9;

/// The most cells the lattice has (the feedback of 512 blocks of 32 modes is the solver's
/// 16,384 coefficients).
const MAX_CELLS: usize = 512;

/// How far a lattice point may move onto the walls, in cells.
const MOST_SNAP: f64 = 0.45;

pub fn derive(scene: &Scene, bvh: &SceneBvh) -> Result<Derived, String> {
    let (lo, hi) = (scene.settings.bounds.0.as_dvec3(), scene.settings.bounds.1.as_dvec3());
    let h = room_height(bvh, lo, hi);
    let mut cells = [axis_cells(hi.x - lo.x, h), axis_cells(hi.z - lo.z, h)];
    while cells[0] * cells[1] > MAX_CELLS {
        cells = cells.map(|n| (n * 3 / 4).max(1));
    }
    let mut lattice = Lattice::new(lo, hi, cells);
    let mut free: Vec<bool> = (0..cells[0] * cells[1]).map(|c| lattice.is_free(bvh, c)).collect();
    if !free.contains(&true) {
        // No room anywhere (a model on open ground): the bounds as one block, 002 §8's Great Hall.
        cells = [1, 1];
        lattice = Lattice::new(lo, hi, cells);
        free = vec![true];
    }
    let blocks: Vec<usize> = (0..free.len()).filter(|&c| free[c]).collect();
    // Each pair of neighbouring free cells tested once, lower cell first.
    let lattice = &lattice;
    let joins: std::collections::HashSet<(usize, usize)> = blocks
        .iter()
        .flat_map(|&a| [Face::ALL[1], Face::ALL[5]].into_iter().filter_map(move |f| lattice.neighbour(a, f).map(|b| (a, b))))
        .filter(|&(a, b)| free[b] && lattice.open_between(bvh, a, b))
        .collect();
    let joined = |a: usize, b: usize| joins.contains(&(a.min(b), a.max(b)));
    let columns = lattice.snapped_columns(scene, &free, &joined, h);
    let heights = lattice.column_heights(bvh, &columns, &free);
    let corners: Vec<[DVec3; 8]> = blocks.iter().map(|&c| lattice.corners(c, &columns, &heights)).collect();
    for (b, c) in corners.iter().enumerate() {
        check_shape(c).map_err(|e| format!("the derived block at cell {:?} {e}; declare extras.relume.mrt", lattice.cell_of(blocks[b])))?;
    }
    let index = |cell: usize| blocks.binary_search(&cell).ok();
    let level = Level::joined(blocks.len(), |b, face| {
        let next = lattice.neighbour(blocks[b], face)?;
        joined(blocks[b], next).then(|| index(next)).flatten()
    })?;
    let proxy = Proxy::from_parts(corners, level, REACH);
    // A corner within a hundredth of a cell of a boundary is on it (a wall's lean, a crease).
    let split = split(scene, &|p| lattice.sides(p, &columns), 1e-2 * lattice.size.min_element());
    let dynamic = match &split {
        Some(s) => unplaced(&s.apply(scene), &proxy, &proxy.level()),
        None => unplaced(scene, &proxy, &proxy.level()),
    };
    let plain = columns == lattice.plain && heights.iter().all(|y| *y == (lo.y, hi.y));
    let every_neighbour =
        blocks.iter().all(|&c| Face::ALL.iter().filter_map(|f| lattice.neighbour(c, *f)).all(|n| !free[n] || joined(c, n)));
    let declared = if plain && every_neighbour { lattice.grid(&free) } else { warped(&proxy, &blocks, lattice, &free, &joined) };
    Ok(Derived { proxy, split, dynamic, declared, cells })
}

/// Cells along an axis of `extent` metres for rooms `h` high: round(extent / h), at least 1.
fn axis_cells(extent: f64, h: f64) -> usize {
    // A flat scene (a height of 0) has no rooms to count along an axis: one cell.
    let n = (extent / h).round();
    if n.is_finite() {
        (n as usize).clamp(1, MAX_CELLS)
    } else {
        1
    }
}

/// The bounds' height, or the median floor-to-ceiling height over a 16 x 16 grid of points.
fn room_height(bvh: &SceneBvh, lo: DVec3, hi: DVec3) -> f64 {
    let mut heights: Vec<f64> = (0..256)
        .filter_map(|k| {
            let (u, v) = (((k % 16) as f64 + 0.5) / 16.0, ((k / 16) as f64 + 0.5) / 16.0);
            let (floor, ceiling) = vertical(bvh, lo, hi, DVec2::new(lo.x + u * (hi.x - lo.x), lo.z + v * (hi.z - lo.z)));
            Some(ceiling? - floor?)
        })
        .collect();
    heights.sort_by(f64::total_cmp);
    heights.get(heights.len() / 2).copied().filter(|h| *h > 0.0).unwrap_or(hi.y - lo.y)
}

/// At plan point `p`: the lowest surface's height (a ray up from below the bounds), and the
/// highest's if it faces down (a ceiling, seen from above from behind), or the one under it
/// within a tenth of the bounds' height if that faces down (a roof slab's top, then its
/// underside); a surface facing up with nothing so close under it is a floor open to the sky.
/// From outside, so furniture is never taken for either.
fn vertical(bvh: &SceneBvh, lo: DVec3, hi: DVec3, p: DVec2) -> (Option<f64>, Option<f64>) {
    let margin = 0.01 * (hi.y - lo.y) + 1e-3;
    let at = |y: f64| Vec3::new(p.x as f32, y as f32, p.y as f32);
    let floor = bvh.closest_hit(at(lo.y - margin), Vec3::Y, f32::INFINITY);
    let facing_down = |h: &crate::bvh::Hit| h.geometric_normal.y < 0.0;
    let top = bvh.closest_hit(at(hi.y + margin), Vec3::NEG_Y, f32::INFINITY);
    let ceiling = top.and_then(|t| match facing_down(&t) {
        true => Some(t),
        false => {
            let start = bvh.offset_origin(t.position, t.geometric_normal, Vec3::NEG_Y);
            bvh.closest_hit(start, Vec3::NEG_Y, (0.1 * (hi.y - lo.y)) as f32).filter(facing_down)
        }
    });
    (floor.map(|f| f.position.y as f64), ceiling.map(|c| c.position.y as f64))
}

/// The plan's lattice: `cells` cells of `size` over the bounds, x then z; column (i, j) is
/// lattice point i + (cells x + 1) j.
struct Lattice {
    lo: DVec3,
    hi: DVec3,
    cells: [usize; 2],
    size: DVec2,
    /// The lattice points where the plain grid has them.
    plain: Vec<DVec2>,
}

impl Lattice {
    fn new(lo: DVec3, hi: DVec3, cells: [usize; 2]) -> Lattice {
        let size = DVec2::new((hi.x - lo.x) / cells[0] as f64, (hi.z - lo.z) / cells[1] as f64);
        let (nx, nz) = (cells[0] + 1, cells[1] + 1);
        let plain = (0..nx * nz).map(|n| DVec2::new(lo.x, lo.z) + DVec2::new((n % nx) as f64, (n / nx) as f64) * size).collect();
        Lattice { lo, hi, cells, size, plain }
    }

    fn cell_of(&self, c: usize) -> (usize, usize) {
        (c % self.cells[0], c / self.cells[0])
    }

    fn column(&self, i: usize, j: usize) -> usize {
        i + (self.cells[0] + 1) * j
    }

    /// The cell beyond `c`'s side face `face`, if the lattice has one.
    fn neighbour(&self, c: usize, face: Face) -> Option<usize> {
        let (i, j) = self.cell_of(c);
        let step = if face.positive { 1 } else { -1 };
        let (i, j) = match face.axis {
            0 => (i as i64 + step, j as i64),
            2 => (i as i64, j as i64 + step),
            _ => return None,
        };
        (i >= 0 && j >= 0 && (i as usize) < self.cells[0] && (j as usize) < self.cells[1]).then(|| i as usize + self.cells[0] * j as usize)
    }

    /// The plan point at (u, v) in [0, 1]^2 of cell `c` with its columns where `columns` has them.
    fn at(&self, c: usize, columns: &[DVec2], (u, v): (f64, f64)) -> DVec2 {
        let (i, j) = self.cell_of(c);
        let p = |a: usize, b: usize| columns[self.column(i + a, j + b)];
        (p(0, 0) * (1.0 - u) + p(1, 0) * u) * (1.0 - v) + (p(0, 1) * (1.0 - u) + p(1, 1) * u) * v
    }

    /// Whether most of 5 points at cell `c`'s middle height (its middle and the middles of its
    /// quarters' diagonals) are inside a room: something standing in the middle of a room is
    /// not a solid cell.
    fn is_free(&self, bvh: &SceneBvh, c: usize) -> bool {
        let points = [(0.5, 0.5), (0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];
        points.iter().filter(|&&uv| self.inside_a_room(bvh, self.at(c, &self.plain, uv))).count() >= 3
    }

    /// Whether the point over plan point `p` halfway between floor and ceiling is inside a room:
    /// at least `FRONT_RAYS` of 14 rays first meet a surface facing them.
    fn inside_a_room(&self, bvh: &SceneBvh, p: DVec2) -> bool {
        let (floor, ceiling) = vertical(bvh, self.lo, self.hi, p);
        let y = (floor.unwrap_or(self.lo.y) + ceiling.unwrap_or(self.hi.y)) * 0.5;
        let middle = Vec3::new(p.x as f32, y as f32, p.y as f32);
        let axes = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
        let diagonals = (0..8).map(|k| Vec3::new([1.0, -1.0][k & 1], [1.0, -1.0][(k >> 1) & 1], [1.0, -1.0][k >> 2]).normalize());
        let facing = |d: Vec3| bvh.closest_hit(middle, d, f32::INFINITY).is_some_and(|h| h.geometric_normal.dot(d) < 0.0);
        axes.into_iter().chain(diagonals).filter(|&d| facing(d)).count() >= FRONT_RAYS
    }

    /// Whether most of 3 x 3 segments across the face between neighbouring cells `a` and `b`
    /// (a quarter cell into each) are unblocked.
    fn open_between(&self, bvh: &SceneBvh, a: usize, b: usize) -> bool {
        let (pa, pb) = (self.at(a, &self.plain, (0.5, 0.5)), self.at(b, &self.plain, (0.5, 0.5)));
        let across = pb - pa;
        let along = DVec2::new(-across.y, across.x);
        let mut blocked = 0;
        for k in 0..9 {
            let (s, t) = ([0.25, 0.5, 0.75][k % 3], [0.25, 0.5, 0.75][k / 3]);
            let mid = (pa + pb) * 0.5 + along * (s - 0.5);
            let (floor, ceiling) = vertical(bvh, self.lo, self.hi, mid);
            let (floor, ceiling) = (floor.unwrap_or(self.lo.y), ceiling.unwrap_or(self.hi.y));
            let y = floor + (ceiling - floor) * t;
            let point = |q: DVec2| Vec3::new(q.x as f32, y as f32, q.y as f32);
            blocked += usize::from(!bvh.visible(point(mid - across * 0.25), point(mid + across * 0.25)));
        }
        blocked < 5
    }

    /// The lattice points moved onto the walls they nearly meet (`free`: which cells are
    /// blocks; `joined`: which neighbouring cells are joined). A plain grid stays exact.
    fn snapped_columns(&self, scene: &Scene, free: &[bool], joined: &dyn Fn(usize, usize) -> bool, height: f64) -> Vec<DVec2> {
        let plain = &self.plain;
        let lines = self.wall_lines(scene, free, joined, height);
        let mut moved = plain.clone();
        for (n, p) in moved.iter_mut().enumerate() {
            let at: Vec<(DVec2, f64)> = lines.iter().filter(|(ends, _)| ends.contains(&n)).map(|(_, line)| *line).collect();
            if let Some(q) = meet(&at, *p).filter(|q| q.distance(*p) <= MOST_SNAP * self.size.min_element()) {
                *p = q;
            }
        }
        // Within a thousandth of a cell of the plain grid: the plain grid (a model on a lattice).
        let tiny = moved.iter().zip(plain).all(|(a, b)| a.distance(*b) <= 1e-3 * self.size.min_element());
        if tiny {
            plain.clone()
        } else {
            moved
        }
    }

    /// Per lattice edge that is a closed face of a free cell and has wall triangles along it:
    /// its two lattice points and the wall's line in plan, n . p = d (n unit).
    fn wall_lines(
        &self,
        scene: &Scene,
        free: &[bool],
        joined: &dyn Fn(usize, usize) -> bool,
        height: f64,
    ) -> Vec<([usize; 2], (DVec2, f64))> {
        let (nx, nz) = (self.cells[0], self.cells[1]);
        // Edges: along x at z-line j (between cells (i, j - 1) and (i, j)), then along z at
        // x-line i; each gathers its wall triangles: area, plan normal, plan centroid.
        let along_x = nx * (nz + 1);
        let mut near: Vec<Vec<(f64, DVec2, DVec2)>> = vec![Vec::new(); along_x + (nx + 1) * nz];
        for mesh in &scene.meshes {
            for t in mesh.indices.chunks_exact(3) {
                let p = [0, 1, 2].map(|k| mesh.positions[t[k] as usize].as_dvec3());
                let cross = (p[1] - p[0]).cross(p[2] - p[0]);
                let (area, n) = (0.5 * cross.length(), cross.normalize_or_zero());
                let c = (p[0] + p[1] + p[2]) / 3.0;
                let plan = DVec2::new(n.x, n.z);
                if n.y.abs() > 0.5 || area == 0.0 {
                    continue;
                }
                let local = (DVec2::new(c.x, c.z) - DVec2::new(self.lo.x, self.lo.z)) / self.size;
                let edge = if plan.y.abs() > 0.7 {
                    // A wall along x: its z-line is the nearest, its cell along x the one it is in.
                    let (i, j) = (local.x.floor(), local.y.round());
                    let inside = (local.x - i) > 0.1 && (local.x - i) < 0.9 && (local.y - j).abs() < 0.4;
                    (inside && i >= 0.0 && (i as usize) < nx && j >= 0.0 && (j as usize) <= nz).then(|| j as usize * nx + i as usize)
                } else if plan.x.abs() > 0.7 {
                    let (i, j) = (local.x.round(), local.y.floor());
                    let inside = (local.y - j) > 0.1 && (local.y - j) < 0.9 && (local.x - i).abs() < 0.4;
                    (inside && i >= 0.0 && (i as usize) <= nx && j >= 0.0 && (j as usize) < nz)
                        .then(|| along_x + j as usize * (nx + 1) + i as usize)
                } else {
                    None
                };
                let Some(e) = edge else { continue };
                // Both sides of a thick wall count with one orientation: +x or +z.
                let plan = plan.normalize_or_zero();
                near[e].push((area, if plan.x + plan.y < 0.0 { -plan } else { plan }, DVec2::new(c.x, c.z)));
            }
        }
        let cell = |i: i64, j: i64| (i >= 0 && j >= 0 && (i as usize) < nx && (j as usize) < nz).then(|| i as usize + nx * j as usize);
        // A closed face of a free cell: a free cell on one side that the other side does not join.
        let closed = |a: Option<usize>, b: Option<usize>| match (a, b) {
            (Some(a), Some(b)) => (free[a] || free[b]) && !joined(a, b),
            (Some(c), None) | (None, Some(c)) => free[c],
            (None, None) => false,
        };
        let mut lines = Vec::new();
        for (e, triangles) in near.iter().enumerate() {
            // A wall covers most of the face (a thick one twice); a desk's side or a block in a
            // room does not, and stays furniture.
            let face = if e < along_x { self.size.x } else { self.size.y } * height;
            let Some((area, normal, d)) = dominant_plane(triangles, 0.15 * self.size.min_element()) else { continue };
            if area < 0.5 * face {
                continue;
            }
            let (ends, sides) = if e < along_x {
                let (i, j) = (e % nx, e / nx);
                ([self.column(i, j), self.column(i + 1, j)], (cell(i as i64, j as i64 - 1), cell(i as i64, j as i64)))
            } else {
                let (i, j) = ((e - along_x) % (nx + 1), (e - along_x) / (nx + 1));
                ([self.column(i, j), self.column(i, j + 1)], (cell(i as i64 - 1, j as i64), cell(i as i64, j as i64)))
            };
            if closed(sides.0, sides.1) {
                lines.push((ends, (normal, d)));
            }
        }
        lines
    }

    /// Per lattice point, the heights of its floor and ceiling: the mean of its free cells'
    /// planes there (the bounds' without free cells, or without a ceiling).
    fn column_heights(&self, bvh: &SceneBvh, columns: &[DVec2], free: &[bool]) -> Vec<(f64, f64)> {
        let mut sums = vec![(0.0, 0.0, 0usize); columns.len()];
        for c in (0..free.len()).filter(|&c| free[c]) {
            let samples: Vec<(DVec2, Option<f64>, Option<f64>)> = (0..9)
                .map(|k| {
                    let p = self.at(c, columns, ([0.25, 0.5, 0.75][k % 3], [0.25, 0.5, 0.75][k / 3]));
                    let (floor, ceiling) = vertical(bvh, self.lo, self.hi, p);
                    (p, floor, ceiling)
                })
                .collect();
            let floor = plane(&samples.iter().filter_map(|(p, f, _)| Some((*p, (*f)?))).collect::<Vec<_>>());
            let ceiling = plane(&samples.iter().filter_map(|(p, _, c)| Some((*p, (*c)?))).collect::<Vec<_>>());
            let (i, j) = self.cell_of(c);
            for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let n = self.column(i + a, j + b);
                let q = columns[n];
                let s = &mut sums[n];
                *s = (s.0 + floor.as_ref().map_or(self.lo.y, |f| f(q)), s.1 + ceiling.as_ref().map_or(self.hi.y, |f| f(q)), s.2 + 1);
            }
        }
        sums.iter().map(|&(f, c, n)| if n == 0 { (self.lo.y, self.hi.y) } else { (f / n as f64, c / n as f64) }).collect()
    }

    /// Cell `c`'s block: corner i at its columns' (i & 1, i >> 2 & 1), floor or ceiling by
    /// i >> 1 & 1.
    fn corners(&self, c: usize, columns: &[DVec2], heights: &[(f64, f64)]) -> [DVec3; 8] {
        let (i, j) = self.cell_of(c);
        std::array::from_fn(|k| {
            let n = self.column(i + (k & 1), j + ((k >> 2) & 1));
            let y = if (k >> 1) & 1 == 1 { heights[n].1 } else { heights[n].0 };
            DVec3::new(columns[n].x, y, columns[n].y)
        })
    }

    /// The sides of the cell whose plan quad (its columns where `columns` has them) holds `p`,
    /// each named by its lattice edge; outside every cell, the nearest plain cell's (so what
    /// lies beyond the lattice, a wall's outer face, is cut at its lines too).
    fn sides(&self, p: DVec2, columns: &[DVec2]) -> Option<[Side; 4]> {
        let guess = ((p - DVec2::new(self.lo.x, self.lo.z)) / self.size).floor();
        let (nx, nz) = (self.cells[0] as i64, self.cells[1] as i64);
        let near = (-1..=1).flat_map(|dj| (-1..=1).map(move |di| (guess.x as i64 + di, guess.y as i64 + dj)));
        let nearest = (guess.x.clamp(0.0, (nx - 1) as f64) as i64, guess.y.clamp(0.0, (nz - 1) as f64) as i64);
        let along_x = self.cells[0] * (self.cells[1] + 1);
        for (i, j) in near.filter(|&(i, j)| i >= 0 && j >= 0 && i < nx && j < nz).chain([nearest]) {
            let (i, j) = (i as usize, j as usize);
            let q = |a: usize, b: usize| columns[self.column(i + a, j + b)];
            let centre = (q(0, 0) + q(1, 0) + q(0, 1) + q(1, 1)) * 0.25;
            let side = |a: DVec2, b: DVec2, id: usize| {
                let along = (b - a).normalize_or_zero();
                let n = DVec2::new(-along.y, along.x);
                let n = if n.dot(centre - a) < 0.0 { -n } else { n };
                Side { normal: n, d: n.dot(a), id }
            };
            let sides = [
                side(q(0, 0), q(0, 1), along_x + j * (self.cells[0] + 1) + i),
                side(q(1, 0), q(1, 1), along_x + j * (self.cells[0] + 1) + i + 1),
                side(q(0, 0), q(1, 0), j * self.cells[0] + i),
                side(q(0, 1), q(1, 1), (j + 1) * self.cells[0] + i),
            ];
            if (i, j) == (nearest.0 as usize, nearest.1 as usize)
                || sides.iter().all(|s| s.normal.dot(p) - s.d >= -1e-9 * self.size.min_element())
            {
                return Some(sides);
            }
        }
        None
    }

    /// The plain grid as `extras.relume.mrt.grid` declares it.
    fn grid(&self, free: &[bool]) -> Value {
        let rows: Vec<String> =
            (0..self.cells[1]).map(|j| (0..self.cells[0]).map(|i| if free[i + self.cells[0] * j] { '.' } else { '#' }).collect()).collect();
        json!({ "grid": { "origin": self.lo.to_array(), "cell": [self.size.x, self.hi.y - self.lo.y, self.size.y], "rows": rows } })
    }
}

/// The plane in plan most of `triangles`' area lies in (area, plan normal, centroid): the
/// normal with the most area within 5 degrees of it, and those triangles' offsets within
/// `spread` of their area-weighted median (a wall's two sides, not a block leaning on it);
/// returns their area, the normal and their mean offset, n . p = d.
fn dominant_plane(triangles: &[(f64, DVec2, DVec2)], spread: f64) -> Option<(f64, DVec2, f64)> {
    let close = |a: DVec2, b: DVec2| a.dot(b) >= 5f64.to_radians().cos();
    let aligned = |n: DVec2| triangles.iter().filter(|t| close(t.1, n)).map(|t| t.0).sum::<f64>();
    let normal = triangles.iter().map(|t| t.1).max_by(|a, b| aligned(*a).total_cmp(&aligned(*b)))?;
    let mut offsets: Vec<(f64, f64)> = triangles.iter().filter(|t| close(t.1, normal)).map(|t| (normal.dot(t.2), t.0)).collect();
    offsets.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half: f64 = offsets.iter().map(|o| o.1).sum::<f64>() / 2.0;
    let mut running = 0.0;
    let median = offsets.iter().find(|o| {
        running += o.1;
        running >= half
    })?;
    let kept: Vec<&(f64, f64)> = offsets.iter().filter(|o| (o.0 - median.0).abs() <= spread).collect();
    let area: f64 = kept.iter().map(|o| o.1).sum();
    (area > 0.0).then(|| (area, normal, kept.iter().map(|o| o.0 * o.1).sum::<f64>() / area))
}

/// The point where the lines n . p = d meet in the least-squares sense, or on the one line
/// they make (parallel lines: the point nearest `p` on their mean); None without lines.
fn meet(lines: &[(DVec2, f64)], p: DVec2) -> Option<DVec2> {
    let (mut a, mut b) = (glam::DMat2::ZERO, DVec2::ZERO);
    for (n, d) in lines {
        a += glam::DMat2::from_cols(*n * n.x, *n * n.y);
        b += *n * *d;
    }
    if lines.is_empty() {
        return None;
    }
    if a.determinant().abs() > 1e-3 * lines.len() as f64 {
        return Some(a.inverse() * b);
    }
    let (n, d) = lines.iter().fold((DVec2::ZERO, 0.0), |(n, d), (m, e)| if n.dot(*m) >= 0.0 { (n + *m, d + e) } else { (n - *m, d - e) });
    let length = n.length();
    (length > 0.0).then(|| p - n / length * (n.dot(p) / length - d / length))
}

/// The plane y = a x + b z + c through `points` (plan point, height) in the least-squares
/// sense; a level plane at their mean when they cannot fix its tilt; None without points.
fn plane(points: &[(DVec2, f64)]) -> Option<Box<dyn Fn(DVec2) -> f64>> {
    let n = points.len() as f64;
    let mean = points.iter().map(|(_, y)| y).sum::<f64>() / n;
    if points.is_empty() {
        return None;
    }
    let centre = points.iter().map(|(p, _)| *p).sum::<DVec2>() / n;
    let mut m = glam::DMat2::ZERO;
    let mut r = DVec2::ZERO;
    for (p, y) in points {
        let q = *p - centre;
        m += glam::DMat2::from_cols(q * q.x, q * q.y);
        r += q * (y - mean);
    }
    if m.determinant().abs() <= 1e-12 * (m.x_axis.x + m.y_axis.y).powi(2) {
        return Some(Box::new(move |_| mean));
    }
    let slope = m.inverse() * r;
    Some(Box::new(move |p| mean + slope.dot(p - centre)))
}

/// The derived proxy as warped blocks by their corners, each with the side faces it shares with
/// a block it is not joined to listed as `closed`.
fn warped(proxy: &Proxy, blocks: &[usize], lattice: &Lattice, free: &[bool], joined: &dyn Fn(usize, usize) -> bool) -> Value {
    let described: Vec<Value> = blocks
        .iter()
        .zip(&proxy.corners)
        .map(|(&c, corners)| {
            let walls: Vec<&str> = Face::ALL
                .iter()
                .filter(|f| lattice.neighbour(c, **f).is_some_and(|n| free[n] && !joined(c, n)))
                .map(|f| f.name())
                .collect();
            let corners: Vec<[f64; 3]> = corners.iter().map(|p| p.to_array()).collect();
            if walls.is_empty() {
                json!({ "corners": corners })
            } else {
                json!({ "corners": corners, "closed": walls })
            }
        })
        .collect();
    json!({ "blocks": described })
}
