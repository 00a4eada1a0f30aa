//! Building the atlas (Iones et al., "Fast realistic lighting for video games", §3): triangles
//! grouped into charts by breadth-first search over their adjacency, each chart mapped to a
//! plane, small charts unfolded onto their neighbours (`unfold.rs`), each cut into patches by
//! a regular grid (one patch a texel), the charts packed into pages with a gutter between
//! them (turned a quarter where that packs lower), and per texel the geometry a baker needs: coverage,
//! patch centre, smoothed normal, triangle, and the pieces of faces the patch is made of (so a
//! baker can spread its samples over the whole patch).

use super::pack::pack;
use super::unfold::{unfold, ChartCost, Layout};
use super::{AtlasMesh, AtlasSection, Texel, EMPTY};
use crate::artifact::{PageLayout, Section};
use crate::scene::{Mesh, Scene};
use crate::settings::{first_failed_check, ValueRange};
use glam::{UVec2, Vec2, Vec3, Vec4};
use serde_json::Value;
use std::collections::HashMap;

/// How the atlas is cut and packed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasSettings {
    /// Texels per metre in the mapping plane (a chart's projection or its scaled uv0).
    pub texel_density: f32,
    /// Empty texels kept between charts and around each page's border (>= 1).
    pub gutter: u32,
    /// Largest page side in texels; charts that do not fit one page go to the next.
    pub max_size: u32,
    /// Largest angle between neighbouring faces of one chart, and between a face and its
    /// chart's projection axis, radians (001 §3: "often it is equal to 60°").
    pub discontinuity_angle: f32,
}

impl Default for AtlasSettings {
    fn default() -> Self {
        AtlasSettings { texel_density: 32.0, gutter: 2, max_size: 4096, discontinuity_angle: 60f32.to_radians() }
    }
}

impl AtlasSettings {
    /// Texels per metre: past a million, one metre of a scene needs more texels than a page holds.
    pub const TEXEL_DENSITY: ValueRange = ValueRange::number(0.0, 1e6, true);
    pub const GUTTER: ValueRange = ValueRange::count(1, 64);
    pub const MAX_SIZE: ValueRange = ValueRange::count(16, 16384);
    /// In degrees: at 90 a chart could fold onto its projection plane edge-on.
    pub const DISCONTINUITY_DEGREES: ValueRange = ValueRange::between(0.0, 90.0);

    pub fn validate(&self) -> Result<(), String> {
        let checks = [
            (Self::TEXEL_DENSITY.admits(self.texel_density.into()), "texel density must be in >0..=1e6 texels per metre"),
            (Self::GUTTER.admits_count(self.gutter.into()), "gutter must be 1..=64 texels"),
            (Self::MAX_SIZE.admits_count(self.max_size.into()), "atlas maximum size must be 16..=16384 texels"),
            (
                Self::DISCONTINUITY_DEGREES.admits(self.discontinuity_angle.to_degrees().into()),
                "discontinuity angle must be in (0, 90) degrees",
            ),
        ];
        first_failed_check(&checks)
    }
}

/// How a chart's faces are laid flat (001 §3's two clustering criteria).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChartMapping {
    /// Criterion 1: projection onto the plane of the world axis (0 = x, 1 = y, 2 = z)
    /// closest to the chart's first normal.
    Projection { axis: usize },
    /// Criterion 2: the mesh's own continuous uv0, scaled to metres by `scale`.
    Uv0 { scale: f32 },
}

#[derive(Clone, Debug)]
pub struct Chart {
    pub mesh: u32,
    /// Triangle indices within the mesh.
    pub triangles: Vec<u32>,
    /// The mapping of its first part (of all, where `parts` is 1).
    pub mapping: ChartMapping,
    /// How many of 001's charts were unfolded into it (`unfold.rs`): each part is laid out by
    /// its own mapping, moved rigidly into the first part's plane; only the first's is kept.
    pub parts: u32,
    pub page: u32,
    /// Top-left texel of the chart's rectangle on its page.
    pub origin: UVec2,
    /// Rectangle size in texels (the gutter not included).
    pub size: UVec2,
}

/// A part of one face inside one texel, as a triangle in that face's barycentric coordinates
/// (weights of the face's second and third vertices).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    pub triangle: u32,
    pub corners: [Vec2; 3],
    /// World-space area, square metres.
    pub area: f32,
}

#[derive(Clone, Debug)]
pub struct Atlas {
    pub width: u32,
    pub height: u32,
    pub pages: u32,
    pub charts: Vec<Chart>,
    /// `pages * height * width` texels, page by page, rows top to bottom.
    pub texels: Vec<Texel>,
    /// Every texel's pieces: those of texel t are `pieces[piece_start[t]..piece_start[t + 1]]`.
    pub pieces: Vec<Piece>,
    pub piece_start: Vec<u32>,
    /// One per scene mesh, in order.
    pub meshes: Vec<AtlasMesh>,
    /// Triangles (flattened ids) whose area in texel space is too small to cover any texel's
    /// footprint measurably: they are mapped, but no texel takes its value from them.
    pub too_small: Vec<u32>,
}

/// Why no atlas could be made.
#[derive(Debug, thiserror::Error)]
pub enum AtlasError {
    #[error("{0}")]
    Settings(String),
    #[error("{scene}: mesh \"{mesh}\": a chart is {w} x {h} texels at {density} texels per metre, larger than the {max} texel page; lower the texel density or raise the atlas maximum size")]
    ChartTooLarge { scene: String, mesh: String, w: u32, h: u32, density: f32, max: u32 },
}

impl Atlas {
    /// Charts, packs and rasterises every mesh of `scene`.
    pub fn build(scene: &Scene, settings: &AtlasSettings) -> Result<Atlas, AtlasError> {
        settings.validate().map_err(AtlasError::Settings)?;
        let mut charts = Vec::new();
        let mut flat = Vec::new();
        let limit = settings.max_size - 2 * settings.gutter;
        let cost = ChartCost { density: settings.texel_density, gutter: settings.gutter, limit };
        for (m, mesh) in scene.meshes.iter().enumerate() {
            let adjacency = Adjacency::new(mesh);
            for layout in unfold(mesh, &adjacency, segment_mesh(mesh, &adjacency, settings.discontinuity_angle), cost) {
                let chart = FlatChart::new(&layout.corners, settings.texel_density);
                if chart.size.x > limit || chart.size.y > limit {
                    return Err(AtlasError::ChartTooLarge {
                        scene: scene.source.display().to_string(),
                        mesh: mesh.name.clone(),
                        w: chart.size.x,
                        h: chart.size.y,
                        density: settings.texel_density,
                        max: settings.max_size,
                    });
                }
                let Layout { triangles, mapping, parts, .. } = layout;
                charts.push(Chart { mesh: m as u32, triangles, mapping, parts, page: 0, origin: UVec2::ZERO, size: chart.size });
                flat.push(chart);
            }
        }
        let (width, height, pages) = pack(&mut charts, &mut flat, settings);
        let mut raster = Raster::new(width, height, pages);
        let mesh_offsets = mesh_offsets(scene);
        let mut too_small = Vec::new();
        for (chart, flat) in charts.iter().zip(&flat) {
            let mesh = &scene.meshes[chart.mesh as usize];
            let offset = chart.origin.as_vec2() + flat.slack;
            for (k, &t) in chart.triangles.iter().enumerate() {
                let corners = flat.corners[k].map(|c| c + offset);
                let id = mesh_offsets[chart.mesh as usize] + t;
                if !raster.add_triangle(mesh, t, id, corners, chart.page) {
                    too_small.push(id);
                }
            }
        }
        let meshes =
            scene.meshes.iter().enumerate().map(|(m, mesh)| split_vertices(mesh, m as u32, &charts, &flat, (width, height))).collect();
        let (texels, pieces, piece_start) = raster.finish();
        Ok(Atlas { width, height, pages, charts, texels, pieces, piece_start, meshes, too_small })
    }

    /// The atlas whose covered-texel count is closest to `patches`, found by bisecting the
    /// texel density in log space (coverage grows about as the density squared).
    pub fn build_for_patch_count(scene: &Scene, settings: &AtlasSettings, patches: u32) -> Result<Atlas, AtlasError> {
        let area: f32 = scene.meshes.iter().map(mesh_area).sum();
        let mut density = (patches as f32 / area.max(1e-9)).sqrt();
        let (mut lo, mut hi) = (density / 8.0, density * 2.0);
        let mut best: Option<Atlas> = None;
        for _ in 0..16 {
            let atlas = Atlas::build(scene, &AtlasSettings { texel_density: density, ..*settings })?;
            let covered = atlas.covered_texels();
            if covered > patches as usize {
                hi = density;
            } else {
                lo = density;
            }
            let closer = |a: &Atlas| (a.covered_texels() as i64 - patches as i64).abs();
            if best.as_ref().is_none_or(|b| closer(&atlas) < closer(b)) {
                best = Some(atlas);
            }
            density = (lo * hi).sqrt();
        }
        Ok(best.expect("the loop runs at least once"))
    }

    pub fn layout(&self) -> PageLayout {
        PageLayout { width: self.width, height: self.height, pages: self.pages }
    }

    /// What a bake artifact keeps of the atlas.
    pub fn to_section(&self) -> AtlasSection {
        AtlasSection { meshes: self.meshes.clone(), layout: self.layout(), texels: self.texels.clone() }
    }

    /// Its section, written from its parts (as [`AtlasSection::section`]).
    pub fn section(&self, summary: Value) -> Section {
        super::section(&self.meshes, self.layout(), &self.texels, summary)
    }

    /// The scene with every mesh re-indexed and given its uv1 (as [`AtlasSection::apply_to`]).
    pub fn apply_to(&self, scene: &mut Scene) {
        super::apply_meshes(&self.meshes, scene);
    }

    /// Per-texel `values` with the coverage as alpha (as [`AtlasSection::with_coverage`]).
    pub fn with_coverage(&self, values: &[Vec3]) -> Vec<Vec4> {
        super::with_coverage(&self.texels, values)
    }

    pub fn covered_texels(&self) -> usize {
        self.texels.iter().filter(|t| t.coverage > 0.0).count()
    }

    /// Covered texels over all texels of all pages.
    pub fn utilization(&self) -> f64 {
        self.covered_texels() as f64 / self.texels.len().max(1) as f64
    }

    pub fn pieces_of(&self, texel: usize) -> &[Piece] {
        &self.pieces[self.piece_start[texel] as usize..self.piece_start[texel + 1] as usize]
    }

    /// The texel a uv1 coordinate falls in, as an index into [`Atlas::texels`].
    pub fn texel_at(&self, uv1: Vec2) -> Option<usize> {
        let page = uv1.x.floor();
        let x = ((uv1.x - page) * self.width as f32).floor();
        let y = (uv1.y * self.height as f32).floor();
        let inside =
            page >= 0.0 && (page as u32) < self.pages && (0.0..self.width as f32).contains(&x) && (0.0..self.height as f32).contains(&y);
        inside.then(|| ((page as u32 * self.height + y as u32) * self.width + x as u32) as usize)
    }
}

/// Where each mesh's triangles start in the scene's flattened triangle order.
pub fn mesh_offsets(scene: &Scene) -> Vec<u32> {
    scene
        .meshes
        .iter()
        .scan(0u32, |next, m| {
            let start = *next;
            *next += (m.indices.len() / 3) as u32;
            Some(start)
        })
        .collect()
}

fn triangle_positions(mesh: &Mesh, t: u32) -> [Vec3; 3] {
    let i = 3 * t as usize;
    [0, 1, 2].map(|k| mesh.positions[mesh.indices[i + k] as usize])
}

fn face_normal(p: [Vec3; 3]) -> Vec3 {
    (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero()
}

fn triangle_area(mesh: &Mesh, t: u32) -> f32 {
    let p = triangle_positions(mesh, t);
    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
}

fn mesh_area(mesh: &Mesh) -> f32 {
    (0..(mesh.indices.len() / 3) as u32).map(|t| triangle_area(mesh, t)).sum()
}

pub(super) fn signed_area_2d(c: [Vec2; 3]) -> f32 {
    0.5 * (c[1] - c[0]).perp_dot(c[2] - c[0])
}

// --- segmentation (001 §3) ----------------------------------------------------------------------

/// Groups a mesh's triangles into charts, each with its mapping. Criterion 2 (continuous uv0)
/// when every face has a non-degenerate uv0 triangle, criterion 1 (axis projection) otherwise.
fn segment_mesh(mesh: &Mesh, adjacency: &Adjacency, max_angle: f32) -> Vec<Layout> {
    let count = (mesh.indices.len() / 3) as u32;
    let normals: Vec<Vec3> = (0..count).map(|t| face_normal(triangle_positions(mesh, t))).collect();
    let uv_faces: Option<Vec<[Vec2; 3]>> = mesh.uv0.as_ref().and_then(|uv| {
        let faces: Vec<[Vec2; 3]> = (0..count as usize).map(|t| [0, 1, 2].map(|k| uv[mesh.indices[3 * t + k] as usize])).collect();
        faces.iter().all(|f| signed_area_2d(*f).abs() > 1e-12).then_some(faces)
    });
    let cos_max = max_angle.cos();
    let mut chart_of = vec![u32::MAX; count as usize];
    let mut charts = Vec::new();
    for seed in 0..count {
        if chart_of[seed as usize] != u32::MAX {
            continue;
        }
        let chart_id = charts.len() as u32;
        let mapping = match &uv_faces {
            Some(_) => ChartMapping::Uv0 { scale: 1.0 },
            None => ChartMapping::Projection { axis: normals[seed as usize].abs().max_position() },
        };
        let flatten = |t: u32| match (&uv_faces, mapping) {
            (Some(faces), _) => faces[t as usize],
            (None, ChartMapping::Projection { axis }) => triangle_positions(mesh, t).map(|p| project(p, axis)),
            (None, ChartMapping::Uv0 { .. }) => unreachable!("uv0 charts only exist with uv0"),
        };
        let axis_normal = normals[seed as usize].signum()
            * Vec3::from(match mapping {
                ChartMapping::Projection { axis } => [0, 1, 2].map(|k| (k == axis) as u32 as f32),
                ChartMapping::Uv0 { .. } => [0.0; 3],
            });
        let seed_orientation = signed_area_2d(flatten(seed)).signum();
        let mut placed = OverlapGrid::new(flatten(seed));
        let mut members = vec![seed];
        chart_of[seed as usize] = chart_id;
        placed.insert(flatten(seed));
        let mut next = 0;
        while next < members.len() {
            let from = members[next];
            next += 1;
            for (to, continuous_uv) in adjacency.neighbours(from) {
                if chart_of[to as usize] != u32::MAX {
                    continue;
                }
                let n = normals[to as usize];
                let joins = n.dot(normals[from as usize]) > cos_max
                    && (uv_faces.is_some() || n.dot(axis_normal) > cos_max)
                    && (uv_faces.is_none() || continuous_uv)
                    && signed_area_2d(flatten(to)).signum() == seed_orientation
                    && !placed.overlaps(flatten(to));
                if joins {
                    chart_of[to as usize] = chart_id;
                    placed.insert(flatten(to));
                    members.push(to);
                }
            }
        }
        members.sort_unstable();
        let (mapping, scale) = match mapping {
            ChartMapping::Uv0 { .. } => {
                let faces = uv_faces.as_ref().expect("uv0 charts only exist with uv0");
                let world: f32 = members.iter().map(|&t| triangle_area(mesh, t)).sum();
                let uv: f32 = members.iter().map(|&t| signed_area_2d(faces[t as usize]).abs()).sum();
                let scale = (world / uv).sqrt();
                (ChartMapping::Uv0 { scale }, scale)
            }
            projection => (projection, 1.0),
        };
        let corners = members.iter().map(|&t| flatten(t).map(|p| p * scale)).collect();
        charts.push(Layout { triangles: members, corners, mapping, parts: 1 });
    }
    charts
}

/// The plane coordinates of a point projected along a world axis.
fn project(p: Vec3, axis: usize) -> Vec2 {
    match axis {
        0 => Vec2::new(p.z, p.y),
        1 => Vec2::new(p.x, p.z),
        _ => Vec2::new(p.x, p.y),
    }
}

/// Which triangles share an edge, with vertices welded by position (files split vertices
/// at normal and uv seams, which must not split charts by themselves).
pub(super) struct Adjacency {
    /// Per triangle t, `across[start[t]..start[t + 1]]`: for each of its edges k (vertices
    /// k, k+1) in order, each other triangle across it with its own edge there.
    across: Vec<(u8, u32, u8)>,
    start: Vec<u32>,
    welded: Vec<u32>,
    mesh_indices: Vec<u32>,
    uv0: Option<Vec<Vec2>>,
}

impl Adjacency {
    pub(super) fn new(mesh: &Mesh) -> Self {
        let mut by_position: HashMap<[u32; 3], u32> = HashMap::new();
        let welded: Vec<u32> = mesh
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| *by_position.entry(p.to_array().map(f32::to_bits)).or_insert(i as u32))
            .collect();
        let count = (mesh.indices.len() / 3) as u32;
        let mut edges: HashMap<(u32, u32), Vec<(u32, u8)>> = HashMap::new();
        for t in 0..count {
            for k in 0..3 {
                edges.entry(Self::edge_key(&welded, &mesh.indices, t, k)).or_default().push((t, k as u8));
            }
        }
        let (mut across, mut start) = (Vec::new(), Vec::with_capacity(count as usize + 1));
        for t in 0..count {
            start.push(across.len() as u32);
            for k in 0..3 {
                let sharing = &edges[&Self::edge_key(&welded, &mesh.indices, t, k)];
                across.extend(sharing.iter().filter(|&&(o, _)| o != t).map(|&(o, ok)| (k as u8, o, ok)));
            }
        }
        start.push(across.len() as u32);
        Adjacency { across, start, welded, mesh_indices: mesh.indices.clone(), uv0: mesh.uv0.clone() }
    }

    fn edge_key(welded: &[u32], indices: &[u32], t: u32, k: usize) -> (u32, u32) {
        let a = welded[indices[3 * t as usize + k] as usize];
        let b = welded[indices[3 * t as usize + (k + 1) % 3] as usize];
        (a.min(b), a.max(b))
    }

    /// The triangles sharing an edge with `t`, in a fixed order, each with whether uv0 is
    /// continuous across that edge (the same uv0 at both of its ends on both sides).
    fn neighbours(&self, t: u32) -> Vec<(u32, bool)> {
        self.shared_edges(t).map(|(k, other, ok)| (other, self.uv_continuous((t, k), (other, ok)))).collect()
    }

    /// Per edge k of `t`, each other triangle across it with its own edge there.
    pub(super) fn shared_edges(&self, t: u32) -> impl Iterator<Item = (usize, u32, usize)> + '_ {
        let range = self.start[t as usize] as usize..self.start[t as usize + 1] as usize;
        self.across[range].iter().map(|&(k, o, ok)| (k as usize, o, ok as usize))
    }

    /// Whether edge `k` of `t` and edge `ok` of `o` start at the same point.
    pub(super) fn same_point(&self, (t, k): (u32, usize), (o, ok): (u32, usize)) -> bool {
        let start = |t: u32, k: usize| self.welded[self.mesh_indices[3 * t as usize + k] as usize];
        start(t, k) == start(o, ok)
    }

    fn uv_continuous(&self, (t, k): (u32, usize), (o, ok): (u32, usize)) -> bool {
        let Some(uv) = &self.uv0 else { return true };
        let vertex = |t: u32, k: usize| self.mesh_indices[3 * t as usize + k % 3] as usize;
        let ends = |t, k| [vertex(t, k), vertex(t, k + 1)];
        let (a, b) = (ends(t, k), ends(o, ok));
        let same = |x: usize, y: usize| self.welded[x] == self.welded[y] && uv[x] == uv[y];
        (same(a[0], b[0]) && same(a[1], b[1])) || (same(a[0], b[1]) && same(a[1], b[0]))
    }
}

/// The faces already in a chart, bucketed on a grid in the mapping plane, for criterion 3
/// (a face joins only if it overlaps none of them).
pub(super) struct OverlapGrid {
    cell: f32,
    cells: HashMap<(i32, i32), Vec<usize>>,
    faces: Vec<[Vec2; 3]>,
}

impl OverlapGrid {
    pub(super) fn new(seed: [Vec2; 3]) -> Self {
        let (lo, hi) = bounds_2d(&seed);
        OverlapGrid { cell: (hi - lo).max_element().max(1e-6), cells: HashMap::new(), faces: Vec::new() }
    }

    fn cell_range(&self, face: &[Vec2; 3]) -> impl Iterator<Item = (i32, i32)> {
        let (lo, hi) = bounds_2d(face);
        let (lo, hi) = ((lo / self.cell).floor(), (hi / self.cell).floor());
        // A face far larger than the cell is bucketed coarsely; it is still checked exactly.
        let clamp = |a: f32, b: f32| (a as i32, (b as i32).min(a as i32 + 64));
        let ((x0, x1), (y0, y1)) = (clamp(lo.x, hi.x), clamp(lo.y, hi.y));
        (x0..=x1).flat_map(move |x| (y0..=y1).map(move |y| (x, y)))
    }

    pub(super) fn insert(&mut self, face: [Vec2; 3]) {
        let index = self.faces.len();
        self.faces.push(face);
        for key in self.cell_range(&face).collect::<Vec<_>>() {
            self.cells.entry(key).or_default().push(index);
        }
    }

    pub(super) fn overlaps(&self, face: [Vec2; 3]) -> bool {
        // Relative to the face and to where it lies: the rounding of projected coordinates
        // grows with their magnitude, and must not make neighbours of a finely triangulated
        // surface overlap (a face 1e-3 of its coordinates across split charts).
        let (lo, hi) = bounds_2d(&face);
        let tolerance = 1e-5 * (hi - lo).max_element() + 1e-6 * lo.abs().max(hi.abs()).max_element();
        let big_face = self.cell_range(&face).count() >= 64 * 64;
        if big_face {
            return self.faces.iter().any(|f| triangles_overlap(f, &face, tolerance));
        }
        self.cell_range(&face)
            .filter_map(|key| self.cells.get(&key))
            .flatten()
            .any(|&i| triangles_overlap(&self.faces[i], &face, tolerance))
    }
}

pub(super) fn bounds_2d(points: &[Vec2]) -> (Vec2, Vec2) {
    points.iter().fold((Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

/// Whether two triangles' interiors overlap by more than `tolerance` (separating axes: the
/// six edge normals); faces that only share an edge or a corner do not overlap.
fn triangles_overlap(a: &[Vec2; 3], b: &[Vec2; 3], tolerance: f32) -> bool {
    let separated_along = |axis: Vec2| {
        let span =
            |t: &[Vec2; 3]| t.iter().map(|p| p.dot(axis)).fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)));
        let ((a0, a1), (b0, b1)) = (span(a), span(b));
        a1.min(b1) - a0.max(b0) <= tolerance * axis.length()
    };
    let edge_normals = |t: &[Vec2; 3]| [0, 1, 2].map(|k| (t[(k + 1) % 3] - t[k]).perp());
    !edge_normals(a).into_iter().chain(edge_normals(b)).any(separated_along)
}

// --- patch grid ----------------------------------------------------------------------------------

/// A chart laid flat in texel units, its corner at the origin of its rectangle.
pub(super) struct FlatChart {
    /// Per chart triangle, its corners in texels relative to the rectangle's origin.
    corners: Vec<[Vec2; 3]>,
    pub(super) size: UVec2,
    /// Offset centring the chart in its whole-texel rectangle.
    slack: Vec2,
}

impl FlatChart {
    /// From the chart's corners in its plane, metres.
    fn new(plane: &[[Vec2; 3]], density: f32) -> Self {
        let (lo, hi) = bounds_2d(plane.as_flattened());
        let extent = (hi - lo) * density;
        let size = texel_size(hi - lo, density);
        let corners = plane.iter().map(|face| face.map(|p| (p - lo) * density)).collect();
        FlatChart { corners, size, slack: (size.as_vec2() - extent) * 0.5 }
    }

    /// The chart turned a quarter in its rectangle (which turns with it).
    pub(super) fn turn(&mut self) {
        let (slack, width) = (self.slack, self.size.x as f32);
        for face in &mut self.corners {
            *face = face.map(|p| Vec2::new(p.y + slack.y, width - p.x - slack.x));
        }
        (self.size, self.slack) = (UVec2::new(self.size.y, self.size.x), Vec2::ZERO);
    }
}

/// The whole-texel rectangle a chart of `extent` metres takes.
pub(super) fn texel_size(extent: Vec2, density: f32) -> UVec2 {
    (extent * density).ceil().max(Vec2::ONE).as_uvec2()
}

// --- rasterisation into geometry images -----------------------------------------------------------

#[derive(Clone, Copy, Default)]
struct Accumulator {
    area: f32,
    centre: Vec3,
    normal: Vec3,
    best: (f32, u32),
}

struct Raster {
    width: u32,
    height: u32,
    texels: Vec<Accumulator>,
    pieces: Vec<(u32, Piece)>,
}

impl Raster {
    fn new(width: u32, height: u32, pages: u32) -> Self {
        Raster {
            width,
            height,
            texels: vec![Accumulator { best: (0.0, EMPTY), ..Default::default() }; (width * height * pages) as usize],
            pieces: Vec::new(),
        }
    }

    /// Clips the face (corners in page texels) against every texel square it touches and
    /// accumulates the pieces. False when the face covers no measurable area.
    fn add_triangle(&mut self, mesh: &Mesh, t: u32, id: u32, corners: [Vec2; 3], page: u32) -> bool {
        let area_2d = signed_area_2d(corners).abs();
        if area_2d < 1e-7 {
            return false;
        }
        let positions = triangle_positions(mesh, t);
        let normals = [0, 1, 2].map(|k| mesh.normals[mesh.indices[3 * t as usize + k] as usize]);
        let world_per_texel_area = triangle_area(mesh, t) / area_2d;
        let to_bary = Barycentric::new(corners);
        let (lo, hi) = bounds_2d(&corners);
        let (x0, y0) = (lo.x.floor().max(0.0) as u32, lo.y.floor().max(0.0) as u32);
        let (x1, y1) = ((hi.x.ceil() as u32).min(self.width), (hi.y.ceil() as u32).min(self.height));
        for y in y0..y1 {
            for x in x0..x1 {
                let square = Vec2::new(x as f32, y as f32);
                let polygon = clip_to_square(&corners, square);
                let texel = ((page * self.height + y) * self.width + x) as usize;
                let mut mine = 0.0;
                for fan in 1..polygon.len().saturating_sub(1) {
                    let piece = [polygon[0], polygon[fan], polygon[fan + 1]];
                    let area = signed_area_2d(piece).abs();
                    if area <= 0.0 {
                        continue;
                    }
                    let bary = piece.map(|p| to_bary.of(p));
                    let centroid = (bary[0] + bary[1] + bary[2]) / 3.0;
                    let weights = Vec3::new(1.0 - centroid.x - centroid.y, centroid.x, centroid.y);
                    let point = positions[0] * weights.x + positions[1] * weights.y + positions[2] * weights.z;
                    let normal = normals[0] * weights.x + normals[1] * weights.y + normals[2] * weights.z;
                    let acc = &mut self.texels[texel];
                    acc.area += area;
                    acc.centre += point * area;
                    acc.normal += normal * area;
                    mine += area;
                    self.pieces.push((texel as u32, Piece { triangle: id, corners: bary, area: area * world_per_texel_area }));
                }
                let acc = &mut self.texels[texel];
                if mine > acc.best.0 {
                    acc.best = (mine, id);
                }
            }
        }
        true
    }

    fn finish(mut self) -> (Vec<Texel>, Vec<Piece>, Vec<u32>) {
        let texels = self
            .texels
            .iter()
            .map(|a| match a.area > 0.0 {
                true => {
                    Texel { coverage: a.area.min(1.0), centre: a.centre / a.area, normal: a.normal.normalize_or_zero(), triangle: a.best.1 }
                }
                false => Texel { triangle: EMPTY, ..Default::default() },
            })
            .collect::<Vec<_>>();
        self.pieces.sort_by_key(|(texel, _)| *texel);
        let mut piece_start = vec![0u32; texels.len() + 1];
        for (texel, _) in &self.pieces {
            piece_start[*texel as usize + 1] += 1;
        }
        for i in 1..piece_start.len() {
            piece_start[i] += piece_start[i - 1];
        }
        (texels, self.pieces.into_iter().map(|(_, p)| p).collect(), piece_start)
    }
}

/// Barycentric coordinates (weights of the second and third corner) in a 2D triangle.
struct Barycentric {
    origin: Vec2,
    inverse: glam::Mat2,
}

impl Barycentric {
    fn new(c: [Vec2; 3]) -> Self {
        Barycentric { origin: c[0], inverse: glam::Mat2::from_cols(c[1] - c[0], c[2] - c[0]).inverse() }
    }

    fn of(&self, p: Vec2) -> Vec2 {
        self.inverse * (p - self.origin)
    }
}

/// The part of a triangle inside the unit square at `corner` (Sutherland-Hodgman).
fn clip_to_square(triangle: &[Vec2; 3], corner: Vec2) -> Vec<Vec2> {
    let mut polygon = triangle.to_vec();
    let planes = [(Vec2::X, corner.x), (Vec2::NEG_X, -(corner.x + 1.0)), (Vec2::Y, corner.y), (Vec2::NEG_Y, -(corner.y + 1.0))];
    for (normal, offset) in planes {
        let inside = |p: Vec2| p.dot(normal) - offset;
        let mut clipped = Vec::with_capacity(polygon.len() + 1);
        for (i, &a) in polygon.iter().enumerate() {
            let b = polygon[(i + 1) % polygon.len()];
            let (da, db) = (inside(a), inside(b));
            if da >= 0.0 {
                clipped.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                clipped.push(a + (b - a) * (da / (da - db)));
            }
        }
        polygon = clipped;
        if polygon.len() < 3 {
            return Vec::new();
        }
    }
    polygon
}

// --- uv1 ----------------------------------------------------------------------------------------

/// Splits the mesh's vertices per chart and gives each its uv1 (see the module doc).
fn split_vertices(mesh: &Mesh, m: u32, charts: &[Chart], flat: &[FlatChart], page_size: (u32, u32)) -> AtlasMesh {
    let page_size = Vec2::new(page_size.0 as f32, page_size.1 as f32);
    let mut corner_uv = vec![[Vec2::ZERO; 3]; mesh.indices.len() / 3];
    let mut chart_of = vec![0u32; mesh.indices.len() / 3];
    for (c, (chart, flat)) in charts.iter().zip(flat).enumerate().filter(|(_, (ch, _))| ch.mesh == m) {
        let offset = chart.origin.as_vec2() + flat.slack;
        for (k, &t) in chart.triangles.iter().enumerate() {
            corner_uv[t as usize] = flat.corners[k].map(|p| (p + offset) / page_size + Vec2::new(chart.page as f32, 0.0));
            chart_of[t as usize] = c as u32;
        }
    }
    let mut out = AtlasMesh::default();
    // A vertex of two parts of an unfolded chart may lie at two places in it: one per place.
    let mut new_index: HashMap<(u32, u32, [u32; 2]), u32> = HashMap::new();
    for (i, &source) in mesh.indices.iter().enumerate() {
        let t = i / 3;
        let key = (source, chart_of[t], corner_uv[t][i % 3].to_array().map(f32::to_bits));
        let index = *new_index.entry(key).or_insert_with(|| {
            out.source_vertex.push(source);
            out.uv1.push(corner_uv[t][i % 3]);
            (out.source_vertex.len() - 1) as u32
        });
        out.indices.push(index);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_a_triangle_to_squares_conserves_its_area() {
        let t = [Vec2::new(0.3, 0.2), Vec2::new(3.7, 1.1), Vec2::new(1.2, 2.9)];
        let total: f32 = (0..4)
            .flat_map(|y| (0..4).map(move |x| Vec2::new(x as f32, y as f32)))
            .map(|corner| {
                let p = clip_to_square(&t, corner);
                (1..p.len().saturating_sub(1)).map(|k| signed_area_2d([p[0], p[k], p[k + 1]]).abs()).sum::<f32>()
            })
            .sum();
        assert!((total - signed_area_2d(t).abs()).abs() < 1e-5, "{total}");
    }

    #[test]
    fn triangles_sharing_an_edge_do_not_overlap_but_crossing_ones_do() {
        let a = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let b = [Vec2::X, Vec2::ONE, Vec2::Y];
        let c = [Vec2::splat(0.2), Vec2::new(2.0, 0.2), Vec2::new(0.2, 2.0)];
        assert!(!triangles_overlap(&a, &b, 1e-6));
        assert!(triangles_overlap(&a, &c, 1e-6));
        assert!(triangles_overlap(&b, &c, 1e-6));
    }
}
