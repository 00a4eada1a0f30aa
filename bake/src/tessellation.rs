//! Finer triangles for methods that store light per vertex: a per-vertex term is interpolated
//! across triangles, so a flat-shaded model (three vertices a triangle, a wall in two
//! triangles) gives it nothing to interpolate. The tessellation welds
//! each mesh's vertices that are equal in every attribute (a flat face's vertices become
//! shared; creases keep their own) and splits every triangle of a mesh into k x k, k the
//! mesh's longest edge over the largest edge asked for. Shared part: a method bakes on the
//! tessellated scene, keeps the tessellation as its own section (`tessellation`, keyed to the
//! scene) and renders the same scene from it; an engine rebuilds it from the section's data.
//!
//! Each new vertex is plain data: three source vertices of its mesh and the barycentric
//! weights of the second and third, so positions, normals (renormalised), uv0 and uv1 are
//! interpolated from the scene as loaded, and nothing about the algorithm needs repeating.

use crate::artifact::{fail, Artifact, ArtifactError, Key, Section, REBAKE};
use crate::binary::{Reader, Writer};
use crate::scene::{Mesh, Scene};
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// One mesh tessellated: per new vertex its sources and weights, and the new triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct TessellatedMesh {
    /// Per new vertex: source vertices a, b, c of the mesh and the weights of b and c (a takes
    /// the rest).
    pub sources: Vec<([u32; 3], [f32; 2])>,
    /// Triangle list into the new vertices, each source triangle's winding kept.
    pub indices: Vec<u32>,
}

/// Every mesh of a scene tessellated, in the scene's order.
#[derive(Clone, Debug, PartialEq)]
pub struct Tessellation {
    /// The largest edge asked for, metres; 0 for a scene split along other lines (a method's
    /// own boundaries).
    pub max_edge: f32,
    pub meshes: Vec<TessellatedMesh>,
}

/// The most vertices a tessellated scene may have: past it the per-vertex terms outgrow what
/// one storage buffer holds on many devices.
pub const MAX_VERTICES: usize = 4 << 20;

/// Vertices that belong to one triangle only, and all vertices: where most do (flat-shaded
/// meshes), a per-vertex term varies only within each triangle.
pub fn lone_vertices(scene: &Scene) -> (usize, usize) {
    let mut lone = 0;
    for mesh in &scene.meshes {
        let mut uses = vec![0u32; mesh.positions.len()];
        mesh.indices.iter().for_each(|&i| uses[i as usize] += 1);
        lone += uses.iter().filter(|&&n| n <= 1).count();
    }
    (lone, scene.meshes.iter().map(|m| m.positions.len()).sum())
}

/// Whether most of the scene's vertices belong to one triangle only (flat-shaded meshes).
pub fn flat_shaded(scene: &Scene) -> bool {
    let (lone, vertices) = lone_vertices(scene);
    2 * lone > vertices
}

impl Tessellation {
    /// Welds and splits every mesh of `scene` so that no edge is longer than `max_edge`
    /// metres; refused when the result would pass [`MAX_VERTICES`].
    pub fn new(scene: &Scene, max_edge: f32) -> Result<Tessellation, String> {
        if !(max_edge.is_finite() && max_edge > 0.0) {
            return Err(format!("the largest edge must be a finite length > 0, not {max_edge}"));
        }
        let splits: Vec<u64> = scene.meshes.iter().map(|m| splits(m, max_edge)).collect();
        Self::split(scene, max_edge, splits, format!("edges of at most {max_edge} m"), "give a larger --max-edge")
    }

    /// Every triangle of `scene` split `k` x `k` (the regular grid of k^2 triangles; for k = 2^L
    /// the triangles of L midpoint subdivisions): the same surfaces in k^2 times the
    /// triangles, for measuring what should not depend on the triangulation (`relume rays
    /// --subdivide`).
    pub fn uniform(scene: &Scene, k: u32) -> Result<Tessellation, String> {
        if k == 0 {
            return Err("the subdivision must split each triangle at least 1 x 1".into());
        }
        Self::split(
            scene,
            0.0,
            vec![k as u64; scene.meshes.len()],
            format!("splitting every triangle {k} x {k}"),
            "give a smaller subdivision",
        )
    }

    fn split(scene: &Scene, max_edge: f32, splits: Vec<u64>, what: String, fix: &str) -> Result<Tessellation, String> {
        // At most (k + 1)(k + 2) / 2 vertices a triangle: refused before anything is made.
        let most: u64 = scene.meshes.iter().zip(&splits).map(|(m, &k)| (m.indices.len() / 3) as u64 * (k + 1) * (k + 2) / 2).sum();
        if most > MAX_VERTICES as u64 {
            return Err(format!("{what} would make up to {most} vertices, more than {MAX_VERTICES}; {fix}"));
        }
        let meshes = scene.meshes.iter().zip(splits).map(|(m, k)| tessellate(m, k as u32)).collect();
        Ok(Tessellation { max_edge, meshes })
    }

    pub fn vertex_count(&self) -> usize {
        self.meshes.iter().map(|m| m.sources.len()).sum()
    }

    /// `scene` with every mesh replaced by its tessellation.
    pub fn apply(&self, scene: &Scene) -> Scene {
        let mut out = scene.clone();
        for (mesh, t) in out.meshes.iter_mut().zip(&self.meshes) {
            *mesh = t.apply(mesh);
        }
        out
    }
}

impl TessellatedMesh {
    /// `mesh` tessellated: every attribute interpolated, normals renormalised.
    pub fn apply(&self, mesh: &Mesh) -> Mesh {
        let vec3s = |values: &[Vec3]| -> Vec<Vec3> { self.sources.iter().map(|&(s, w)| mix(values, s, w)).collect() };
        let vec2s = |values: &[Vec2]| -> Vec<Vec2> { self.sources.iter().map(|&(s, w)| mix(values, s, w)).collect() };
        Mesh {
            name: mesh.name.clone(),
            positions: vec3s(&mesh.positions),
            normals: vec3s(&mesh.normals).into_iter().map(|n| n.normalize_or_zero()).collect(),
            uv0: mesh.uv0.as_deref().map(vec2s),
            uv1: mesh.uv1.as_deref().map(vec2s),
            indices: self.indices.clone(),
            material: mesh.material,
        }
    }
}

fn mix<T>(values: &[T], s: [u32; 3], w: [f32; 2]) -> T
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    values[s[0] as usize] * (1.0 - w[0] - w[1]) + values[s[1] as usize] * w[0] + values[s[2] as usize] * w[1]
}

/// A vertex's attributes as bits: vertices equal in all of them are one.
fn attribute_bits(mesh: &Mesh, v: usize) -> Vec<u32> {
    let mut bits: Vec<u32> = mesh.positions[v].to_array().into_iter().chain(mesh.normals[v].to_array()).map(f32::to_bits).collect();
    for uv in [&mesh.uv0, &mesh.uv1].into_iter().flatten() {
        bits.extend(uv[v].to_array().map(f32::to_bits));
    }
    bits
}

/// k for one mesh: its longest edge / `max_edge`, rounded up (at least 1).
fn splits(mesh: &Mesh, max_edge: f32) -> u64 {
    let edge = |a: u32, b: u32| mesh.positions[a as usize].distance(mesh.positions[b as usize]);
    let longest = mesh.indices.chunks_exact(3).flat_map(|t| [edge(t[0], t[1]), edge(t[1], t[2]), edge(t[2], t[0])]).fold(0.0, f32::max);
    ((longest / max_edge).ceil() as u64).max(1)
}

/// One mesh welded and split k x k.
fn tessellate(mesh: &Mesh, k: u32) -> TessellatedMesh {
    let mut first: HashMap<Vec<u32>, u32> = HashMap::new();
    let welded: Vec<u32> = (0..mesh.positions.len()).map(|v| *first.entry(attribute_bits(mesh, v)).or_insert(v as u32)).collect();
    let triangles: Vec<[u32; 3]> = mesh.indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| welded[t[k] as usize])).collect();
    let mut out = TessellatedMesh { sources: Vec::new(), indices: Vec::new() };
    // A point on a source edge is keyed by the edge's ends and its step from the lower one,
    // so the triangles on either side share it; a corner by its vertex; others are their own.
    let mut shared: HashMap<(u32, u32, u32), u32> = HashMap::new();
    for t in &triangles {
        let mut grid = vec![0u32; ((k + 1) * (k + 2) / 2) as usize];
        let at = |i: u32, j: u32| (j * (k + 1) - j * (j.saturating_sub(1)) / 2 + i) as usize;
        for j in 0..=k {
            for i in 0..=k - j {
                let key = point_key(*t, i, j, k);
                let mut new_vertex = || {
                    out.sources.push((*t, [i as f32 / k as f32, j as f32 / k as f32]));
                    out.sources.len() as u32 - 1
                };
                grid[at(i, j)] = match key {
                    Some(key) => *shared.entry(key).or_insert_with(new_vertex),
                    None => new_vertex(),
                };
            }
        }
        for j in 0..k {
            for i in 0..k - j {
                out.indices.extend([grid[at(i, j)], grid[at(i + 1, j)], grid[at(i, j + 1)]]);
                if i + j + 1 < k {
                    out.indices.extend([grid[at(i + 1, j)], grid[at(i + 1, j + 1)], grid[at(i, j + 1)]]);
                }
            }
        }
    }
    out
}

/// The key of grid point (i, j) of triangle `t` split k x k (weights i / k on b, j / k on c)
/// when it lies on the triangle's boundary: (lower end, upper end, steps from the lower end);
/// a corner is (vertex, vertex, 0). None inside.
fn point_key(t: [u32; 3], i: u32, j: u32, k: u32) -> Option<(u32, u32, u32)> {
    let [a, b, c] = t;
    let on_edge = |from: u32, to: u32, steps: u32| match (steps, from.cmp(&to)) {
        (0, _) => (from, from, 0),
        (s, _) if s == k => (to, to, 0),
        (s, std::cmp::Ordering::Less) => (from, to, s),
        (s, _) => (to, from, k - s),
    };
    if j == 0 {
        Some(on_edge(a, b, i))
    } else if i == 0 {
        Some(on_edge(a, c, j))
    } else if i + j == k {
        Some(on_edge(b, c, j))
    } else {
        None
    }
}

pub const SECTION: &str = "tessellation";
pub const SECTION_VERSION: u32 = 1;
const BIN: &str = "tessellation.bin";
const MAGIC: &[u8; 8] = b"RLTESS\0\0";

/// The section: `tessellation.bin` (docs/FORMATS.md), keyed to the scene.
pub fn section(t: &Tessellation) -> Section {
    let mut w = Writer::new(MAGIC);
    w.f32s(&[t.max_edge]);
    w.u32s(&[t.meshes.len() as u32]);
    for mesh in &t.meshes {
        w.u32s(&[mesh.sources.len() as u32, mesh.indices.len() as u32]);
        for (s, weights) in &mesh.sources {
            w.u32s(s);
            w.f32s(weights);
        }
        w.u32s(&mesh.indices);
    }
    let summary = serde_json::json!({ "max_edge": t.max_edge, "vertices": t.vertex_count() });
    Section { name: SECTION.into(), version: SECTION_VERSION, key: Key::Scene, summary, files: vec![(BIN.into(), w.bytes)] }
}

/// The tessellation `artifact` holds for `scene`, None when it holds none; refused when it
/// does not fit the scene's meshes.
pub fn read(artifact: &Artifact, scene: &Scene) -> Result<Option<Tessellation>, ArtifactError> {
    if !artifact.has_section(SECTION) {
        return Ok(None);
    }
    let data = artifact.section(SECTION, SECTION_VERSION, Some(scene))?;
    let (bin, path) = data.file(BIN)?;
    let mut r = Reader::new(&bin, &path, MAGIC, "tessellation")?;
    let max_edge = r.f32s(1, "the largest edge")?[0];
    let count = r.u32("the mesh count")?;
    if count as usize != scene.meshes.len() || !(max_edge.is_finite() && max_edge >= 0.0) {
        let problem = format!("{count} meshes of edges up to {max_edge} m for a scene of {} meshes", scene.meshes.len());
        return Err(fail(&path, problem, REBAKE));
    }
    let mut meshes = Vec::with_capacity(scene.meshes.len());
    for (m, mesh) in scene.meshes.iter().enumerate() {
        let (vertices, indices) = (r.u32("a vertex count")? as usize, r.u32("an index count")? as usize);
        let raw = r.u32s(5 * vertices, "the vertices' sources")?;
        let sources: Vec<([u32; 3], [f32; 2])> =
            raw.chunks_exact(5).map(|s| ([s[0], s[1], s[2]], [f32::from_bits(s[3]), f32::from_bits(s[4])])).collect();
        let indices = r.u32s(indices, "the indices")?;
        let bad_source = sources.iter().position(|(s, w)| {
            s.iter().any(|&v| v as usize >= mesh.positions.len())
                || !(w.iter().all(|w| w.is_finite() && *w >= 0.0) && w[0] + w[1] <= 1.0 + 1e-6)
        });
        if let Some(v) = bad_source {
            return Err(fail(&path, format!("mesh {m}'s vertex {v} names sources or weights outside its mesh's triangles"), REBAKE));
        }
        if indices.len() % 3 != 0 || indices.iter().any(|&i| i as usize >= vertices) {
            return Err(fail(&path, format!("mesh {m}'s indices are not triangles of its {vertices} vertices"), REBAKE));
        }
        meshes.push(TessellatedMesh { sources, indices });
    }
    r.finish("the last mesh")?;
    Ok(Some(Tessellation { max_edge, meshes }))
}
