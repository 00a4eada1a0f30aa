//! The block proxy a scene declares (`extras.relume.mrt`, §6.2), in one of two forms:
//! - the grid shorthand of 2D mazes (spec C): `{"grid": {"origin": [x, y, z], "cell": [sx,
//!   sy, sz], "rows": ["#..#", ...]}}`, row r along +z, character c along +x, `.` a block and
//!   `#` solid; a block's faces towards its neighbours are open, the others closed;
//! - warped blocks (spec B12): `{"blocks": [{"corners": [[x, y, z] x 8]}, ...]}`, corner i at
//!   the unit cube's ((i & 1), (i >> 1) & 1, (i >> 2) & 1), +y up. A block is the trilinear
//!   map of its corners; two blocks are joined where a side face of one has the same four
//!   corners as the opposite face of the other. Refused: an inverted or flat block, two blocks
//!   that overlap, a face that touches another block without being joined to it (a dangling
//!   opening) unless both blocks list it under `closed` (a thin wall between them), and a
//!   joined top or bottom (the 2D dictionary has none).
//!
//! A scene that declares neither is given a proxy derived from its geometry (`derive`).
//!
//! The dictionary's operators are reused under the warp unchanged (spec B12).

use super::level::Level;
use super::Face;
use crate::scene::Scene;
use crate::settings::{as_object, known_keys, vec3, SceneBlock};
use glam::{DMat3, DVec3, Mat3, Vec3};
use serde_json::Value;
use std::collections::HashMap;

const KEY: &str = "mrt";

pub const SCENE_BLOCK: SceneBlock = SceneBlock { key: KEY, check: |block, _| from_block(block).map(|_| ()) };

/// The most blocks a proxy may have (the paper's largest maze has 41).
pub const MAX_BLOCKS: usize = 4096;

/// How near (in block sides) two corners must be to be the same corner; also how much a
/// block's bounds are widened, and how far outside its cube (in its local coordinates) a point
/// still counts as in it when locating.
const SAME: f64 = 1e-4;

/// The farthest a corner may lie from the origin along any axis, metres.
const MAX_COORDINATE: f32 = 1e6;

/// How far past its face a triangle of a declared proxy may reach, in face widths.
const DECLARED_REACH: f32 = 1e-3;

/// In a block's local coordinates: how far inside it a point must be to overlap it; how near
/// one of its faces a point must be to touch it (a dangling face); and how far outside its
/// cube Newton's root may fall and still be taken as the point's.
const INSIDE: f64 = 1e-3;

#[derive(Clone, Debug, PartialEq)]
pub struct Proxy {
    /// Each block's eight corners, corner i at local ((i & 1), (i >> 1) & 1, (i >> 2) & 1).
    pub corners: Vec<[DVec3; 8]>,
    level: Level,
    /// The shortest block edge, metres: the scale of the mapping's tolerances.
    side: f32,
    /// Each block's bounds, widened by the corner tolerance.
    boxes: Vec<Bounds>,
    /// The blocks whose bounds meet each cube of a uniform grid of side `bucket`.
    buckets: HashMap<[i64; 3], Vec<usize>>,
    bucket: f64,
    /// How far past the face it lies on a triangle may reach and still be placed (clamped to
    /// the face), in face widths: a hair for a declared proxy, more for a derived one, whose
    /// faces stand at walls' middles and rooms' bounds.
    reach: f32,
}

impl Proxy {
    /// Whether the scene declares a proxy (`extras.relume.mrt`).
    pub fn declared(scene: &Scene) -> bool {
        scene.settings.block(KEY).is_some()
    }

    /// A proxy of these blocks, joined as `level` says (a derived one: `derive`), whose faces
    /// take triangles reaching `reach` face widths past them.
    #[cfg(feature = "baking")]
    pub(super) fn from_parts(corners: Vec<[DVec3; 8]>, level: Level, reach: f32) -> Proxy {
        let mut proxy = Proxy { reach, ..Proxy::new(corners, level) };
        // Bounds (and the buckets over them) widened by the reach, for `locate`.
        proxy.boxes = proxy.corners.iter().map(|c| bounds(c, reach as f64 * mean_edge(c))).collect();
        proxy.buckets = buckets(&proxy.boxes, proxy.bucket);
        proxy
    }

    /// How far past its face a triangle may reach, in face widths.
    pub fn reach(&self) -> f32 {
        self.reach
    }

    /// Whether it was derived from the scene (its reach wider than a declared proxy's).
    pub fn derived(&self) -> bool {
        self.reach > DECLARED_REACH
    }

    /// The block whose bounds lie nearest `p`.
    pub fn nearest(&self, p: Vec3) -> usize {
        let p = p.as_dvec3();
        let distance = |b: &Bounds| (b.lo - p).max(p - b.hi).max(DVec3::ZERO).length();
        (0..self.boxes.len()).min_by(|&a, &b| distance(&self.boxes[a]).total_cmp(&distance(&self.boxes[b]))).unwrap_or(0)
    }

    /// The scene's proxy; refused when it declares none (the method needs its blocks).
    pub fn of(scene: &Scene) -> Result<Proxy, String> {
        match scene.settings.block(KEY) {
            Some(block) => from_block(block),
            None => Err("the scene declares no block proxy (extras.relume.mrt: a grid of rows of '.' blocks and '#' solid cells, or warped blocks by their corners)".into()),
        }
    }

    pub fn level(&self) -> Level {
        self.level.clone()
    }

    /// The world position of a point of block `block`'s unit cube (§6.2's warp: trilinear).
    pub fn world(&self, block: usize, local: Vec3) -> Vec3 {
        trilinear(&self.corners[block], local.as_dvec3()).as_vec3()
    }

    /// d(world)/d(local) at a point of block `block`: its columns follow local x, y and z.
    pub fn jacobian(&self, block: usize, local: Vec3) -> Mat3 {
        jacobian(&self.corners[block], local.as_dvec3()).as_mat3()
    }

    /// The world normal of block `block`'s face `face` at local point `local`, into the block.
    pub fn inward(&self, block: usize, face: Face, local: Vec3) -> Vec3 {
        (self.jacobian(block, local).inverse().transpose() * face.inward()).normalize()
    }

    /// The local point of block `block` at world point `p` (None where the warp cannot be
    /// undone there: far outside the block).
    pub fn local(&self, block: usize, p: Vec3) -> Option<Vec3> {
        local(&self.corners[block], p.as_dvec3()).map(|q| q.as_vec3())
    }

    /// The block `p` lies in (on a shared face: the one it lies deeper in) and its local
    /// point there.
    pub fn locate(&self, p: Vec3) -> Option<(usize, Vec3)> {
        self.locate_within(p, SAME)
    }

    /// As `locate`, or for a derived proxy the block `p` lies within its reach outside of (a
    /// wall's lean, a floor's edge past a block's).
    pub fn locate_near(&self, p: Vec3) -> Option<(usize, Vec3)> {
        self.derived().then(|| self.locate_within(p, self.reach as f64)).flatten()
    }

    fn locate_within(&self, p: Vec3, outside: f64) -> Option<(usize, Vec3)> {
        let p = p.as_dvec3();
        let near = self.buckets.get(&bucket_of(p, self.bucket))?;
        near.iter()
            .copied()
            .filter(|&b| self.boxes[b].contains(p))
            .filter_map(|b| local(&self.corners[b], p).map(|q| (b, q)))
            .filter(|(_, q)| depth(*q) >= -outside)
            .max_by(|a, b| depth(a.1).total_cmp(&depth(b.1)))
            .map(|(b, q)| (b, q.as_vec3()))
    }

    /// The shortest block edge, metres: the scale of the mapping's tolerances.
    pub fn side(&self) -> f32 {
        self.side
    }

    fn new(corners: Vec<[DVec3; 8]>, level: Level) -> Proxy {
        let edges = || corners.iter().flat_map(edges);
        let shortest = edges().fold(f64::INFINITY, f64::min);
        let longest = edges().fold(0.0, f64::max);
        let mean = edges().sum::<f64>() / (12 * corners.len()) as f64;
        // A bucket about a block wide; never so small that one block meets more than 9^3.
        let bucket = mean.max(longest / 8.0);
        let boxes: Vec<Bounds> = corners.iter().map(|c| bounds(c, SAME * mean_edge(c))).collect();
        let buckets = buckets(&boxes, bucket);
        Proxy { corners, level, side: shortest as f32, boxes, buckets, bucket, reach: DECLARED_REACH }
    }
}

/// The scene's meshes that the light volume lights (§6.5), by index, ascending:
/// `extras.relume.mrt.dynamic`, an array of mesh names (none when absent); refused by name when
/// one matches no mesh or is named twice.
pub fn dynamic_meshes(scene: &Scene) -> Result<Vec<usize>, String> {
    let key = "extras.relume.mrt.dynamic";
    let names = match scene.settings.block(KEY).and_then(|b| b.get("dynamic")) {
        None => return Ok(Vec::new()),
        Some(names) => dynamic_names(names)?,
    };
    let mut meshes = Vec::with_capacity(names.len());
    for (k, name) in names.iter().enumerate() {
        if names[..k].contains(name) {
            return Err(format!("{key} names \"{name}\" twice"));
        }
        let found: Vec<usize> = scene.meshes.iter().enumerate().filter(|(_, m)| &m.name == name).map(|(i, _)| i).collect();
        if found.is_empty() {
            let listed: Vec<&str> = scene.meshes.iter().take(12).map(|m| m.name.as_str()).collect();
            return Err(format!(
                "{key} names \"{name}\", which is no mesh of the scene (its meshes: {}); name a mesh or remove it",
                listed.join(", ")
            ));
        }
        meshes.extend(found);
    }
    meshes.sort_unstable();
    Ok(meshes)
}

fn dynamic_names(names: &Value) -> Result<Vec<String>, String> {
    let bad = || "extras.relume.mrt.dynamic must be an array of mesh names (strings)".to_string();
    let list = names.as_array().ok_or_else(bad)?;
    list.iter().map(|n| n.as_str().map(str::to_string).ok_or_else(bad)).collect()
}

fn from_block(block: &Value) -> Result<Proxy, String> {
    let key = "extras.relume.mrt";
    let block = as_object(block, key)?;
    known_keys(block, key, &["grid", "blocks", "dynamic"])?;
    if let Some(names) = block.get("dynamic") {
        dynamic_names(names)?;
    }
    match (block.get("grid"), block.get("blocks")) {
        (Some(grid), None) => from_grid(grid),
        (None, Some(blocks)) => from_blocks(blocks),
        _ => Err(format!("{key} needs either a grid (origin, cell, rows) or blocks (each with its 8 corners), not both")),
    }
}

fn from_grid(grid: &Value) -> Result<Proxy, String> {
    let key = "extras.relume.mrt.grid";
    let grid = as_object(grid, key)?;
    known_keys(grid, key, &["origin", "cell", "rows"])?;
    let origin = grid.get("origin").map_or(Ok(Vec3::ZERO), |v| vec3(v, &format!("{key}.origin")))?;
    let cell = grid.get("cell").map_or(Ok(Vec3::splat(2.0)), |v| vec3(v, &format!("{key}.cell")))?;
    let within = |v: Vec3| v.is_finite() && v.abs().max_element() <= MAX_COORDINATE;
    if !within(origin) || !within(cell) || cell.min_element() <= 0.0 {
        return Err(format!("{key}: origin must be finite and cell three sizes > 0 (metres), each within {MAX_COORDINATE} m"));
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
    let (origin, cell) = (origin.as_dvec3(), cell.as_dvec3());
    let corners = cells
        .iter()
        .map(|&(x, z)| std::array::from_fn(|i| origin + (DVec3::new(x as f64, 0.0, z as f64) + unit_corner(i)) * cell))
        .collect();
    Ok(Proxy::new(corners, Level::new(cells)?))
}

fn from_blocks(blocks: &Value) -> Result<Proxy, String> {
    let key = "extras.relume.mrt.blocks";
    let blocks = blocks.as_array().ok_or_else(|| format!("{key} must be an array of blocks, each {{\"corners\": [8 x [x, y, z]]}}"))?;
    if blocks.is_empty() || blocks.len() > MAX_BLOCKS {
        return Err(format!("{key} declares {} blocks; give 1..={MAX_BLOCKS}", blocks.len()));
    }
    let corners = blocks.iter().enumerate().map(|(i, block)| read_corners(block, &format!("{key}[{i}]"))).collect::<Result<Vec<_>, _>>()?;
    let closed = blocks.iter().enumerate().map(|(i, block)| read_closed(block, &format!("{key}[{i}]"))).collect::<Result<Vec<_>, _>>()?;
    for (i, c) in corners.iter().enumerate() {
        check_shape(c).map_err(|e| format!("{key}[{i}] {e}"))?;
    }
    // Each block's bounds, widened by twice the corner tolerance: the candidates for joins,
    // overlaps and touching faces.
    let boxes: Vec<Bounds> = corners.iter().map(|c| bounds(c, 2.0 * SAME * mean_edge(c))).collect();
    let near = nearby(&boxes);
    let mut around = vec![Vec::new(); corners.len()];
    for &(a, b) in &near {
        around[a].push(b);
        around[b].push(a);
    }
    for &(a, b) in &near {
        if let Some(why) = overlap(&corners[a], &corners[b]) {
            return Err(format!("{key}[{a}] and {key}[{b}] overlap ({why}); blocks may share faces but not volume"));
        }
    }
    let mut links = vec![[None::<usize>; 6]; corners.len()];
    for &(a, b) in &near {
        for face in Face::ALL {
            let other = Face { axis: face.axis, positive: !face.positive };
            if !same_face(&corners[a], face, &corners[b]) {
                continue;
            }
            if face.axis == 1 {
                return Err(format!("{key}[{a}]'s {} face is joined to {key}[{b}]: the 2D dictionary's blocks have a closed top and bottom; stack no blocks", face.name()));
            }
            match (closed[a].contains(&face), closed[b].contains(&other)) {
                (true, true) => continue,
                (false, false) => {}
                (a_closed, _) => {
                    let (listed, unlisted) = if a_closed { ((a, face), (b, other)) } else { ((b, other), (a, face)) };
                    return Err(format!(
                        "{key}[{}]'s {} face is listed under `closed` but {key}[{}]'s {} face, which it touches, is not: list a wall between two blocks on both",
                        listed.0,
                        listed.1.name(),
                        unlisted.0,
                        unlisted.1.name()
                    ));
                }
            }
            links[a][face.index()] = Some(b);
            links[b][other.index()] = Some(a);
        }
    }
    for (a, joins) in links.iter().enumerate() {
        for face in Face::ALL.into_iter().filter(|f| joins[f.index()].is_none() && !closed[a].contains(f)) {
            if let Some(b) = touched(&corners, &boxes, &around[a], a, face) {
                return Err(format!(
                    "{key}[{a}]'s {} face touches {key}[{b}] without being joined to it (a dangling opening): joined faces share all four corners, +x with -x and +z with -z; give the faces the same corners, move the blocks apart, or list the faces under `closed` on both blocks (a wall between them)",
                    face.name()
                ));
            }
        }
    }
    let level = Level::joined(corners.len(), |b, f| links[b][f.index()])?;
    Ok(Proxy::new(corners, level))
}

/// A block's `closed` faces: side faces that touch a neighbour but are walls.
fn read_closed(block: &Value, key: &str) -> Result<Vec<Face>, String> {
    let Some(list) = block.get("closed") else { return Ok(Vec::new()) };
    let bad = || format!("{key}.closed must be a list of side faces (\"-x\", \"+x\", \"-z\", \"+z\")");
    let names = list.as_array().ok_or_else(bad)?;
    names.iter().map(|n| Face::ALL.into_iter().find(|f| f.axis != 1 && Some(f.name()) == n.as_str()).ok_or_else(bad)).collect()
}

fn read_corners(block: &Value, key: &str) -> Result<[DVec3; 8], String> {
    let block = as_object(block, key)?;
    known_keys(block, key, &["corners", "closed"])?;
    let list = block.get("corners").and_then(Value::as_array).filter(|c| c.len() == 8);
    let list = list
        .ok_or_else(|| format!("{key}.corners must be 8 points [x, y, z], corner i at the unit cube's (i & 1, i >> 1 & 1, i >> 2 & 1)"))?;
    let mut corners = [DVec3::ZERO; 8];
    for (i, point) in list.iter().enumerate() {
        let p = vec3(point, &format!("{key}.corners[{i}]"))?;
        if !p.is_finite() || p.abs().max_element() > MAX_COORDINATE {
            return Err(format!("{key}.corners[{i}] must be finite and within {MAX_COORDINATE} m of the origin"));
        }
        corners[i] = p.as_dvec3();
    }
    Ok(corners)
}

/// Refuses a block inverted, flat or folded: at every point of a 5^3 lattice of its unit cube
/// (its corners among them) the warp's three derivatives must span a right-handed frame (x, y
/// up, z) at least 1 % of a box's volume.
pub(super) fn check_shape(corners: &[DVec3; 8]) -> Result<(), String> {
    for q in lattice(&[0.0, 0.25, 0.5, 0.75, 1.0]) {
        let j = jacobian(corners, q);
        if j.determinant() <= 0.01 * j.x_axis.length() * j.y_axis.length() * j.z_axis.length() {
            return Err(format!(
                "is inverted, flat or folded at its local point {q}: list the corners x fastest, then y (up), then z, so that corner 1 is corner 0's +x neighbour, 2 its +y and 4 its +z, and keep the block from folding"
            ));
        }
    }
    Ok(())
}

/// The points of the unit cube with every coordinate in `steps`.
fn lattice(steps: &[f64]) -> impl Iterator<Item = DVec3> + '_ {
    steps.iter().flat_map(move |&z| steps.iter().flat_map(move |&y| steps.iter().map(move |&x| DVec3::new(x, y, z))))
}

/// The pairs of blocks (a < b) whose bounds meet.
fn nearby(boxes: &[Bounds]) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    for a in 0..boxes.len() {
        for b in a + 1..boxes.len() {
            if boxes[a].meets(&boxes[b]) {
                pairs.push((a, b));
            }
        }
    }
    pairs
}

/// Why two blocks overlap, if they do: a point of a 5^3 lattice of one's unit cube, 1 % in
/// from its faces, lies inside the other.
fn overlap(a: &[DVec3; 8], b: &[DVec3; 8]) -> Option<String> {
    let probes = |c: &[DVec3; 8]| lattice(&[0.01, 0.25, 0.5, 0.75, 0.99]).map(|q| trilinear(c, q)).collect::<Vec<_>>();
    let (box_a, box_b) = (bounds(a, 0.0), bounds(b, 0.0));
    let inside = |c: &[DVec3; 8], outer: &Bounds, p: DVec3| outer.contains(p) && local(c, p).is_some_and(|q| depth(q) > INSIDE);
    let found = probes(a).into_iter().find(|&p| inside(b, &box_b, p)).or_else(|| probes(b).into_iter().find(|&p| inside(a, &box_a, p)));
    found.map(|p| format!("both hold {p}"))
}

/// Whether face `fa` of block `a` has the same four corners as the opposite face of block `b`,
/// corner for corner across the face.
fn same_face(a: &[DVec3; 8], fa: Face, b: &[DVec3; 8]) -> bool {
    let tolerance = SAME * mean_edge(a).min(mean_edge(b));
    (0..8).filter(|i| (i >> fa.axis) & 1 == fa.positive as usize).all(|i| a[i].distance(b[i ^ (1 << fa.axis)]) <= tolerance)
}

/// A block of `others` (near `a`) that a point of a 4 x 4 lattice on face `face` of `a` lies
/// on, away from its edges: a face that touches a block it is not joined to.
fn touched(corners: &[[DVec3; 8]], boxes: &[Bounds], others: &[usize], a: usize, face: Face) -> Option<usize> {
    let points: Vec<DVec3> = (0..16)
        .map(|k| trilinear(&corners[a], face.point(glam::Vec2::new((k % 4) as f32 + 0.5, (k / 4) as f32 + 0.5) / 4.0).as_dvec3()))
        .collect();
    others.iter().copied().find(|&b| {
        points.iter().any(|&p| boxes[b].contains(p) && local(&corners[b], p).is_some_and(|q| depth(q) > -INSIDE && on_a_face(q)))
    })
}

/// Whether a local point lies on a face of the unit cube away from its edges.
fn on_a_face(q: DVec3) -> bool {
    (0..3).any(|axis| {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let on = q[axis].abs() < INSIDE || (q[axis] - 1.0).abs() < INSIDE;
        on && [q[u], q[v]].iter().all(|t| (0.01..0.99).contains(t))
    })
}

/// The unit cube's corner i.
fn unit_corner(i: usize) -> DVec3 {
    DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)
}

fn trilinear(c: &[DVec3; 8], q: DVec3) -> DVec3 {
    (0..8).map(|i| c[i] * weight(i, q)).sum()
}

fn weight(i: usize, q: DVec3) -> f64 {
    (0..3).map(|a| factor(i, a, q[a])).product()
}

/// Corner i's trilinear factor along axis `a` at coordinate t: t on its high side, 1 - t on
/// its low side.
fn factor(i: usize, a: usize, t: f64) -> f64 {
    if (i >> a) & 1 == 1 {
        t
    } else {
        1.0 - t
    }
}

pub(super) fn jacobian(c: &[DVec3; 8], q: DVec3) -> DMat3 {
    // d/dq_axis of corner i's weight: its factor along `axis` becomes +1 or -1.
    let column = |axis: usize| -> DVec3 {
        (0..8)
            .map(|i| {
                let slope = if (i >> axis) & 1 == 1 { 1.0 } else { -1.0 };
                c[i] * (0..3).map(|a| if a == axis { slope } else { factor(i, a, q[a]) }).product::<f64>()
            })
            .sum()
    };
    DMat3::from_cols(column(0), column(1), column(2))
}

/// The trilinear map's inverse at `p` by Newton's method: from the block's centre, and where
/// that lands outside the cube (a warped block's map has other roots), from near each corner;
/// the first root inside, else the first found (None where none converges: far outside the
/// block, or where the map folds).
pub(super) fn local(c: &[DVec3; 8], p: DVec3) -> Option<DVec3> {
    let seeds = std::iter::once(DVec3::splat(0.5)).chain((0..8).map(|i| DVec3::splat(0.1) + unit_corner(i) * 0.8));
    let mut first = None;
    for seed in seeds {
        if let Some(q) = newton(c, p, seed) {
            if depth(q) >= -INSIDE {
                return Some(q);
            }
            first = first.or(Some(q));
        }
    }
    first
}

fn newton(c: &[DVec3; 8], p: DVec3, seed: DVec3) -> Option<DVec3> {
    let size = mean_edge(c);
    let mut q = seed;
    for _ in 0..32 {
        let miss = trilinear(c, q) - p;
        if miss.length() <= 1e-9 * size {
            return Some(q);
        }
        let j = jacobian(c, q);
        if j.determinant().abs() < 1e-12 * size.powi(3) {
            return None;
        }
        q = (q - j.inverse() * miss).clamp(DVec3::splat(-2.0), DVec3::splat(3.0));
    }
    (trilinear(c, q).distance(p) <= 1e-6 * size).then_some(q)
}

/// How deep inside the unit cube a local point lies (negative: outside).
pub(super) fn depth(q: DVec3) -> f64 {
    q.min_element().min((DVec3::ONE - q).min_element())
}

/// The mean length of a block's 12 edges.
pub fn mean_edge(c: &[DVec3; 8]) -> f64 {
    edges(c).sum::<f64>() / 12.0
}

/// The lengths of a block's 12 edges.
fn edges(c: &[DVec3; 8]) -> impl Iterator<Item = f64> + '_ {
    (0..8).flat_map(move |i| (0..3).filter(move |a| i & (1 << a) == 0).map(move |a| c[i].distance(c[i | (1 << a)])))
}

/// The blocks whose bounds meet each cube of a uniform grid of side `bucket`.
fn buckets(boxes: &[Bounds], bucket: f64) -> HashMap<[i64; 3], Vec<usize>> {
    let mut buckets: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (b, bounds) in boxes.iter().enumerate() {
        let (lo, hi) = (bucket_of(bounds.lo, bucket), bucket_of(bounds.hi, bucket));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    buckets.entry([x, y, z]).or_default().push(b);
                }
            }
        }
    }
    buckets
}

fn bucket_of(p: DVec3, size: f64) -> [i64; 3] {
    (p / size).floor().as_i64vec3().to_array()
}

#[derive(Clone, Debug, PartialEq)]
struct Bounds {
    lo: DVec3,
    hi: DVec3,
}

impl Bounds {
    fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.lo).all() && p.cmple(self.hi).all()
    }

    fn meets(&self, other: &Bounds) -> bool {
        self.lo.cmple(other.hi).all() && other.lo.cmple(self.hi).all()
    }
}

fn bounds(c: &[DVec3; 8], widen: f64) -> Bounds {
    let lo = c.iter().fold(DVec3::INFINITY, |m, p| m.min(*p)) - widen;
    let hi = c.iter().fold(DVec3::NEG_INFINITY, |m, p| m.max(*p)) + widen;
    Bounds { lo, hi }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_grid_reads_into_blocks_with_their_openings_and_bad_grids_are_refused_by_key() {
        let proxy = from_block(&json!({"grid": {"origin": [1, 0, 0], "cell": [2, 3, 2], "rows": ["..#", "#.."]}})).unwrap();
        assert_eq!(proxy.corners.len(), 4);
        assert_eq!(proxy.world(3, Vec3::ONE), Vec3::new(7.0, 3.0, 4.0));
        let level = proxy.level();
        assert_eq!(level.shape(1).open_faces().len(), 2, "a corner block opens to two neighbours");
        for (bad, named) in [
            (json!({"grid": {"rows": ["..x"]}}), "rows[0] holds 'x'"),
            (json!({"grid": {"rows": ["##"]}}), "0 blocks"),
            (json!({"grid": {"cell": [2, 0, 2], "rows": ["."]}}), "sizes > 0"),
            (json!({"grid": {"rows": "..."}}), "rows must be an array"),
            (json!({"cells": []}), "mrt.cells is not a relume setting"),
            (json!({"grid": {"rows": ["."]}, "blocks": []}), "not both"),
            (json!({"grid": {"rows": ["."]}, "dynamic": "Figure"}), "dynamic must be an array of mesh names"),
        ] {
            let error = from_block(&bad).unwrap_err();
            assert!(error.contains(named), "{bad}: {error}");
        }
    }

    /// The grid's blocks written as corners, moved by `warp`.
    fn as_blocks(rows: &[&str], warp: impl Fn(DVec3) -> DVec3) -> Value {
        let grid = from_block(&json!({"grid": {"rows": rows}})).unwrap();
        let blocks: Vec<Value> = grid
            .corners
            .iter()
            .map(|c| json!({"corners": c.iter().map(|p| { let w = warp(*p); [w.x, w.y, w.z] }).collect::<Vec<_>>()}))
            .collect();
        json!({ "blocks": blocks })
    }

    /// A smooth warp that keeps every block right-handed.
    fn bend(p: DVec3) -> DVec3 {
        DVec3::new(p.x + 0.3 * (p.z * 0.7).sin(), p.y * (1.0 + 0.05 * p.x), p.z + 0.25 * (p.x * 0.9).cos())
    }

    #[test]
    fn warped_blocks_join_where_faces_coincide_as_the_grid_does() {
        let rows = ["....", ".#..", "...."];
        let grid = from_block(&json!({"grid": {"rows": rows}})).unwrap();
        let warped = from_block(&as_blocks(&rows, bend)).unwrap();
        assert_eq!(warped.level(), grid.level(), "the same joins, the same shapes");
        for b in 0..warped.corners.len() {
            for k in 0..20 {
                let q = Vec3::new((k % 5) as f32 / 4.0, (k % 3) as f32 / 2.0, (k % 4) as f32 / 3.0) * 0.9 + 0.05;
                let p = warped.world(b, q);
                let (found, at) = warped.locate(p).unwrap();
                assert_eq!(found, b, "{q} of block {b}");
                assert!(at.distance(q) < 1e-4, "{at} against {q}");
            }
        }
    }

    #[test]
    fn the_largest_warped_level_joins_as_its_grid() {
        let row = ".".repeat(64);
        let rows = vec![row.as_str(); MAX_BLOCKS / 64];
        let grid = from_block(&json!({"grid": {"rows": rows}})).unwrap();
        let warped = from_block(&as_blocks(&rows, bend)).unwrap();
        assert_eq!(warped.level(), grid.level());
        let p = warped.world(2080, Vec3::splat(0.3));
        assert_eq!(warped.locate(p).map(|(b, _)| b), Some(2080));
    }

    #[test]
    fn bad_block_layouts_are_refused_naming_the_block_and_the_fix() {
        let shift = |d: DVec3| move |p: DVec3| p + d;
        let boxed = |lo: DVec3, hi: DVec3| json!({"corners": (0..8).map(|i| { let p = lo + unit_corner(i) * (hi - lo); [p.x, p.y, p.z] }).collect::<Vec<_>>()});
        let two = |second: &dyn Fn(DVec3) -> DVec3| {
            let mut blocks = as_blocks(&["."], |p| p);
            let other = as_blocks(&["."], second);
            blocks["blocks"].as_array_mut().unwrap().push(other["blocks"][0].clone());
            blocks
        };
        let mut inverted = as_blocks(&["."], |p| p);
        inverted["blocks"][0]["corners"].as_array_mut().unwrap().swap(0, 1);
        for (bad, named) in [
            (inverted, "blocks[0] is inverted, flat or folded"),
            (two(&shift(DVec3::new(1.0, 0.0, 0.0))), "blocks[0] and extras.relume.mrt.blocks[1] overlap"),
            (two(&shift(DVec3::new(2.0, 0.0, 0.5))), "blocks[0]'s +x face touches extras.relume.mrt.blocks[1] without being joined"),
            (two(&shift(DVec3::new(0.0, 2.0, 0.0))), "+y face is joined"),
            (json!({"blocks": [{"corners": [[0, 0, 0]]}]}), "blocks[0].corners must be 8 points"),
            (json!({"blocks": []}), "declares 0 blocks"),
            (two(&shift(DVec3::new(2.0, 0.0, 1.0))), "+x face touches"),
            (
                json!({"blocks": [boxed(DVec3::new(0.0, 0.0, 1.0), DVec3::new(4.0, 1.0, 2.0)), boxed(DVec3::new(2.5, 0.0, -3.0), DVec3::new(3.5, 1.0, 4.0))]}),
                "overlap",
            ),
            (
                json!({"blocks": [{"corners": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 2e7]]}]}),
                "within 1000000 m",
            ),
        ] {
            let error = from_block(&bad).unwrap_err();
            assert!(error.contains(named), "{error}");
        }
        let apart = from_block(&two(&shift(DVec3::new(2.5, 0.0, 0.0)))).unwrap();
        assert!(apart.level().shape(0).open_faces().is_empty(), "blocks apart are not joined");
    }

    /// Touching faces both listed `closed` are a wall between two blocks: not joined, not a
    /// dangling opening; listed on one block only, refused naming both.
    #[test]
    fn faces_closed_on_both_blocks_are_a_wall_between_them() {
        let mut blocks = as_blocks(&[".."], |p| p);
        blocks["blocks"][0]["closed"] = json!(["+x"]);
        let refused = from_block(&blocks).err().expect("closed on one block only");
        assert!(refused.contains("blocks[0]'s +x face is listed under `closed` but") && refused.contains("on both"), "{refused}");
        blocks["blocks"][1]["closed"] = json!(["-x"]);
        let walled = from_block(&blocks).unwrap();
        assert!(walled.level().shape(0).open_faces().is_empty() && walled.level().shape(1).open_faces().is_empty());
        blocks["blocks"][1]["closed"] = json!(["+y"]);
        assert!(from_block(&blocks).err().expect("a top is no side face").contains("closed must be a list of side faces"));
    }
}
