//! The scene's geometry on the blocks (§6.2, §7.1): every triangle lies on (or is projected
//! onto) one present face of the block it stands in; each present face of each block gets a
//! tile of the light map, its samples' texels with a one-texel border; and the border is filled
//! by copy records (the padded atlas the design card names): across a seam into a connected
//! block the next block's texels, at a crease (the face turns) the face's own edge, clamped.

use super::level::Level;
use super::level_data::LevelSample;
use super::proxy::Proxy;
use super::{Face, Samples};
use crate::artifact::PageLayout;
use crate::atlas::{AtlasMesh, Texel, EMPTY};
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// The mapped scene: its meshes with uv1 on the light map, the map's texels (sample texels
/// covered by a triangle have coverage 1), the level's samples and the copy records.
pub struct Mapped {
    pub meshes: Vec<AtlasMesh>,
    pub layout: PageLayout,
    pub texels: Vec<Texel>,
    pub samples: Vec<LevelSample>,
    pub copies: Vec<[u32; 2]>,
    pub tiles: Tiles,
}

/// How far a triangle's centroid is moved along its normal to find the block it faces, in the
/// proxy's shortest block edges (at least: a derived proxy's reach, since its faces may stand
/// a wall's lean or thickness from the surfaces they hold).
const SLACK: f32 = 1e-3;

/// The light map's tiles: one per present face of each block, `grid` + 2 texels a side.
pub struct Tiles {
    grid: usize,
    columns: usize,
    /// Per block: its samples and the first tile (= the first of its faces).
    blocks: Vec<(Samples, usize)>,
    layout: PageLayout,
}

impl Tiles {
    fn new(level: &Level, grid: usize) -> Result<Tiles, String> {
        let mut blocks = Vec::with_capacity(level.len());
        let mut count = 0;
        for b in 0..level.len() {
            let samples = Samples::new(level.shape(b), grid);
            let faces = samples.faces.len();
            blocks.push((samples, count));
            count += faces;
        }
        let columns = (count as f64).sqrt().ceil() as usize;
        let rows = count.div_ceil(columns);
        let side = grid + 2;
        if columns * side > 16384 || rows * side > 16384 {
            return Err(format!(
                "{count} block faces of {grid}^2 samples need a light map past 16384 texels a side; use fewer blocks or samples"
            ));
        }
        let layout = PageLayout { width: (columns * side) as u32, height: (rows * side) as u32, pages: 1 };
        Ok(Tiles { grid, columns, blocks, layout })
    }

    fn tile(&self, block: usize, face: Face) -> Option<usize> {
        let (samples, first) = &self.blocks[block];
        samples.faces.iter().position(|f| *f == face).map(|slot| first + slot)
    }

    /// The texel index of (x, y) in -1..=grid of a tile (-1 and grid: the border).
    fn texel(&self, tile: usize, x: i64, y: i64) -> u32 {
        let side = self.grid as i64 + 2;
        let (tx, ty) = ((tile % self.columns) as i64 * side + 1 + x, (tile / self.columns) as i64 * side + 1 + y);
        (ty * self.layout.width as i64 + tx) as u32
    }

    /// uv1 of face coordinates `uv` of `block`'s face `face` (None: the face is open).
    pub fn uv1_of(&self, block: usize, face: Face, uv: Vec2) -> Option<Vec2> {
        self.tile(block, face).map(|tile| self.uv1(tile, uv))
    }

    /// uv1 of face coordinates `uv` on a tile.
    fn uv1(&self, tile: usize, uv: Vec2) -> Vec2 {
        let side = (self.grid + 2) as f32;
        let corner = Vec2::new((tile % self.columns) as f32, (tile / self.columns) as f32) * side + 1.0;
        (corner + uv * self.grid as f32) / Vec2::new(self.layout.width as f32, self.layout.height as f32)
    }
}

/// Maps `scene` onto `proxy`'s blocks with `grid` x `grid` samples a face; the meshes
/// `dynamic` (ascending) stay off the light map (the light volume lights them: their uv1 are 0).
pub fn map(scene: &Scene, proxy: &Proxy, level: &Level, grid: usize, dynamic: &[usize]) -> Result<Mapped, String> {
    let tiles = Tiles::new(level, grid)?;
    let mut texels = vec![Texel { triangle: EMPTY, ..Texel::default() }; tiles.layout.texel_count()];
    let mut samples = Vec::new();
    for (b, (own, first)) in tiles.blocks.iter().enumerate() {
        for i in 0..own.len() {
            let (face, p, _) = own.sample(i);
            let (x, y) = ((i % (grid * grid)) % grid, (i % (grid * grid)) / grid);
            let texel = tiles.texel(first + i / (grid * grid), x as i64, y as i64);
            samples.push(LevelSample { position: proxy.world(b, p), normal: proxy.inward(b, face, p), albedo: Vec3::ZERO, texel });
            debug_assert_eq!(Some(first + i / (grid * grid)), tiles.tile(b, face));
        }
    }
    // For each sample texel, the distance off its face of the triangle covering it so far.
    let mut nearest: HashMap<u32, f32> = HashMap::new();
    let sample_at: HashMap<u32, usize> = samples.iter().enumerate().map(|(i, s)| (s.texel, i)).collect();
    let mut meshes = Vec::with_capacity(scene.meshes.len());
    let mut triangle_id = 0u32;
    for (m, mesh) in scene.meshes.iter().enumerate() {
        if dynamic.binary_search(&m).is_ok() {
            let count = mesh.positions.len();
            meshes.push(AtlasMesh {
                source_vertex: (0..count as u32).collect(),
                uv1: vec![Vec2::ZERO; count],
                indices: mesh.indices.clone(),
            });
            triangle_id += (mesh.indices.len() / 3) as u32;
            continue;
        }
        let albedo = scene.materials[mesh.material].base_color.truncate();
        let mut out = AtlasMesh::default();
        let mut split: HashMap<(u32, usize), u32> = HashMap::new();
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let (block, face, uvs, distance) = place(proxy, level, &mesh.positions, &mesh.normals, tri).map_err(|e| {
                format!(
                    "mesh \"{}\" triangle {t}: {e}; split the geometry at the block boundaries of extras.relume.mrt or change the blocks",
                    mesh.name
                )
            })?;
            let tile = tiles.tile(block, face).expect("placed on a present face");
            for (k, &v) in tri.iter().enumerate() {
                let next = out.source_vertex.len() as u32;
                let index = *split.entry((v, tile)).or_insert_with(|| {
                    out.source_vertex.push(v);
                    out.uv1.push(tiles.uv1(tile, uvs[k]));
                    next
                });
                out.indices.push(index);
            }
            cover(&tiles, tile, uvs, |texel| {
                let Some(&s) = sample_at.get(&texel) else { return };
                if nearest.get(&texel).is_none_or(|d| distance < *d) {
                    nearest.insert(texel, distance);
                    samples[s].albedo = albedo;
                    texels[texel as usize] =
                        Texel { coverage: 1.0, centre: samples[s].position, normal: samples[s].normal, triangle: triangle_id };
                }
            });
            triangle_id += 1;
        }
        meshes.push(out);
    }
    let copies = copy_records(&tiles, level);
    Ok(Mapped { meshes, layout: tiles.layout, texels, samples, copies, tiles })
}

/// The meshes (ascending) with a triangle that lies on no face of `proxy`: none stands in a
/// block (of a declared proxy), or it reaches past its face by more than the proxy's reach.
pub fn unplaced(scene: &Scene, proxy: &Proxy, level: &Level) -> Vec<usize> {
    let fits = |m: &crate::scene::Mesh| m.indices.chunks_exact(3).all(|t| place(proxy, level, &m.positions, &m.normals, t).is_ok());
    scene.meshes.iter().enumerate().filter(|(_, m)| !fits(m)).map(|(i, _)| i).collect()
}

/// The block and present face a triangle lies on, its vertices' face coordinates, and its
/// centroid's distance off the face (in block sides).
fn place(proxy: &Proxy, level: &Level, positions: &[Vec3], normals: &[Vec3], tri: &[u32]) -> Result<(usize, Face, [Vec2; 3], f32), String> {
    let p = [0, 1, 2].map(|k| positions[tri[k] as usize]);
    let normal = tri.iter().map(|&v| normals[v as usize]).sum::<Vec3>().normalize_or_zero();
    if normal == Vec3::ZERO {
        return Err("its vertex normals cancel: no side it faces".into());
    }
    // The block it faces into; else, for a face on a block's boundary facing out of it (the
    // underside of something standing on the floor), the block behind it.
    let centroid = (p[0] + p[1] + p[2]) / 3.0;
    let step = normal * SLACK.max(proxy.reach()) * proxy.side();
    let located = proxy
        .locate(centroid + step)
        .or_else(|| proxy.locate(centroid - step))
        .or_else(|| proxy.locate_near(centroid + step))
        .or_else(|| proxy.locate_near(centroid - step));
    // Outside every derived block (a wall's outer face, a roof's top: seen from no room), on
    // the nearest block's face, clamped: what it shows there is a guess no view inside sees.
    let beyond = located.is_none() && proxy.derived();
    let (block, centre) = match located {
        Some(found) => found,
        None if beyond => (proxy.nearest(centroid), Vec3::splat(0.5)),
        None => return Err(format!("it stands at {centroid}, in no block")),
    };
    let outside = || format!("it reaches past the face it lies on (block {block})");
    let local = p.map(|q| proxy.local(block, q));
    let local = match local {
        [Some(a), Some(b), Some(c)] => [a, b, c],
        _ if beyond => [centre; 3],
        _ => return Err(outside()),
    };
    // A normal is a covector: in the block's local frame it is J^T n.
    let facing = proxy.jacobian(block, centre).transpose() * normal;
    let face = level
        .shape(block)
        .present()
        .into_iter()
        .max_by(|a, b| a.inward().dot(facing).total_cmp(&b.inward().dot(facing)))
        .expect("top and bottom");
    let uvs = local.map(|q| face.uv(q));
    let reach = proxy.reach();
    if !beyond && uvs.iter().any(|uv| uv.min_element() < -reach || uv.max_element() > 1.0 + reach) {
        return Err(outside());
    }
    let off = |q: Vec3| (q[face.axis] - face.positive as u32 as f32).abs();
    Ok((block, face, uvs.map(|uv| uv.clamp(Vec2::ZERO, Vec2::ONE)), off((local[0] + local[1] + local[2]) / 3.0)))
}

/// Calls `at` with each sample texel of `tile` whose centre the triangle of face coordinates
/// `uvs` covers (edges included).
fn cover(tiles: &Tiles, tile: usize, uvs: [Vec2; 3], mut at: impl FnMut(u32)) {
    let g = tiles.grid;
    let cross = |a: Vec2, b: Vec2, c: Vec2| (b - a).perp_dot(c - a);
    let area = cross(uvs[0], uvs[1], uvs[2]);
    if area.abs() < 1e-12 {
        return;
    }
    for y in 0..g {
        for x in 0..g {
            let q = (Vec2::new(x as f32, y as f32) + 0.5) / g as f32;
            let w = [cross(uvs[1], uvs[2], q), cross(uvs[2], uvs[0], q), cross(uvs[0], uvs[1], q)].map(|w| w / area);
            if w.iter().all(|&w| w >= -1e-5) {
                at(tiles.texel(tile, x as i64, y as i64));
            }
        }
    }
}

/// The padded atlas: each border texel of each tile copies the sample texel its centre reaches
/// by walking across seams (an edge whose far side is the same face of the next block, open
/// to this one) and clamping at creases. A corner texel walks along u first, then v: where a
/// seam ends at a concave corner (the floor of an L round a solid cell), the two tiles' corner
/// texels cannot both equal their clamped wall edges, so within half a texel of that end the
/// seam reads differently from its two sides.
fn copy_records(tiles: &Tiles, level: &Level) -> Vec<[u32; 2]> {
    let g = tiles.grid as i64;
    let mut copies = Vec::new();
    for (block, (samples, _)) in tiles.blocks.iter().enumerate() {
        for &face in &samples.faces {
            let tile = tiles.tile(block, face).expect("a present face");
            for y in -1..=g {
                for x in -1..=g {
                    if (0..g).contains(&x) && (0..g).contains(&y) {
                        continue;
                    }
                    let (to, sx, sy) = walk(level, block, face, [x, y], g);
                    let source = tiles.tile(to, face).expect("walks only onto present faces");
                    copies.push([tiles.texel(tile, x, y), tiles.texel(source, sx, sy)]);
                }
            }
        }
    }
    copies
}

/// Where texel (x, y) of `block`'s `face` lands: (the block, the sample texel), after crossing
/// each seam its coordinates pass.
fn walk(level: &Level, mut block: usize, face: Face, mut at: [i64; 2], g: i64) -> (usize, i64, i64) {
    let (a, b) = face.tangents();
    for (k, axis) in [a, b].into_iter().enumerate() {
        let past = if at[k] < 0 {
            Some(false)
        } else if at[k] >= g {
            Some(true)
        } else {
            None
        };
        let Some(positive) = past else { continue };
        let across = Face { axis, positive };
        let next = level.neighbour(block, across).filter(|&n| !level.shape(n).is_open(face));
        if let Some(n) = next {
            block = n;
            at[k] += if positive { -g } else { g };
        }
    }
    (block, at[0].clamp(0, g - 1), at[1].clamp(0, g - 1))
}
