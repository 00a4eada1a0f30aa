//! The lightmap atlas every per-texel method shares (Iones et al., "Fast realistic lighting
//! for video games", §3), as plain data: the meshes re-indexed with uv1, the page layout and
//! each texel's geometry; and its artifact section, `atlas`. Building it (behind the `baking`
//! feature) is `builder.rs`, with `unfold.rs` (charts unfolded onto their neighbours) and
//! `pack.rs` (charts packed into pages).
//!
//! Texel space: page `p` is `width` x `height` texels; texel (i, j) is the square
//! [i, i+1] x [j, j+1], row 0 at the top. A vertex's uv1 is its texel-space position divided
//! by the page size, with the page number added to u: u in [p, p+1) lies on page p. Charts
//! never touch a page's border (there is a gutter all round), so a triangle's three u values
//! always have the same integer part.

#[cfg(feature = "baking")]
mod builder;
#[cfg(feature = "baking")]
pub use builder::*;
#[cfg(feature = "baking")]
mod pack;
#[cfg(feature = "baking")]
pub mod stage;
#[cfg(feature = "baking")]
mod unfold;

use crate::artifact::{fail, Artifact, ArtifactError, Key, PageLayout, Section, REBAKE};
use crate::binary::{Reader, Writer};
use crate::scene::{Mesh, Scene};
use glam::{Vec2, Vec3, Vec4};
use serde_json::Value;

/// The geometry image of one texel (its patch). Empty texels have coverage 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Texel {
    /// Share of the texel's area that faces cover, in (0, 1] for covered texels.
    pub coverage: f32,
    /// Patch centre: the area-weighted average point of the face pieces in the texel.
    pub centre: Vec3,
    /// The vertex normals interpolated over the pieces, area-weighted, unit length.
    pub normal: Vec3,
    /// The triangle covering most of the texel, in the scene's flattened order (meshes in
    /// order, as `SceneBvh::primitive_index`); [`EMPTY`] for empty texels.
    pub triangle: u32,
}

/// [`Texel::triangle`] of an empty texel.
pub const EMPTY: u32 = u32::MAX;

/// A mesh as the atlas re-indexes it: vertices shared by faces of different charts are
/// split, so each vertex has one uv1. Triangle order is kept, so triangle ids stay valid.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AtlasMesh {
    /// For each new vertex, the mesh vertex it copies.
    pub source_vertex: Vec<u32>,
    pub uv1: Vec<Vec2>,
    pub indices: Vec<u32>,
}

impl AtlasMesh {
    /// `mesh` with its vertices split as this atlas needs and uv1 set.
    pub fn apply(&self, mesh: &Mesh) -> Mesh {
        let gather = |v: &[Vec3]| self.source_vertex.iter().map(|&i| v[i as usize]).collect();
        Mesh {
            name: mesh.name.clone(),
            positions: gather(&mesh.positions),
            normals: gather(&mesh.normals),
            uv0: mesh.uv0.as_ref().map(|uv| self.source_vertex.iter().map(|&i| uv[i as usize]).collect()),
            uv1: Some(self.uv1.clone()),
            indices: self.indices.clone(),
            material: mesh.material,
        }
    }
}

/// The atlas as the artifact holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct AtlasSection {
    pub meshes: Vec<AtlasMesh>,
    pub layout: PageLayout,
    pub texels: Vec<Texel>,
}

pub const SECTION: &str = "atlas";
pub const SECTION_VERSION: u32 = 1;
const FILE: &str = "atlas.bin";
const MAGIC: &[u8; 8] = b"RLATLAS\0";

/// `scene` with every mesh re-indexed by `meshes` and given its uv1.
pub(crate) fn apply_meshes(meshes: &[AtlasMesh], scene: &mut Scene) {
    for (mesh, atlas_mesh) in scene.meshes.iter_mut().zip(meshes) {
        *mesh = atlas_mesh.apply(mesh);
    }
}

/// Per-texel `values` as the renderer uploads them: rgb the value, alpha the texel's coverage.
pub(crate) fn with_coverage(texels: &[Texel], values: &[Vec3]) -> Vec<Vec4> {
    values.iter().zip(texels).map(|(v, t)| v.extend(t.coverage)).collect()
}

/// The section (`atlas.bin`, keyed to the scene) of an atlas's parts, with `summary` for the manifest.
pub(crate) fn section(meshes: &[AtlasMesh], layout: PageLayout, texels: &[Texel], summary: Value) -> Section {
    let mut w = Writer::new(MAGIC);
    w.u32s(&[meshes.len() as u32]);
    for mesh in meshes {
        w.u32s(&[mesh.source_vertex.len() as u32, mesh.indices.len() as u32]);
        w.u32s(&mesh.source_vertex);
        w.f32s(&mesh.uv1.iter().flat_map(|uv| uv.to_array()).collect::<Vec<_>>());
        w.u32s(&mesh.indices);
    }
    w.u32s(&[layout.width, layout.height, layout.pages]);
    for t in texels {
        w.f32s(&[t.coverage, t.centre.x, t.centre.y, t.centre.z, t.normal.x, t.normal.y, t.normal.z, f32::from_bits(t.triangle)]);
    }
    Section { name: SECTION.into(), version: SECTION_VERSION, key: Key::Scene, summary, files: vec![(FILE.into(), w.bytes)] }
}

impl AtlasSection {
    /// The scene with every mesh re-indexed and given its uv1.
    pub fn apply_to(&self, scene: &mut Scene) {
        apply_meshes(&self.meshes, scene);
    }

    /// Per-texel `values` as the renderer uploads them: rgb the value, alpha the coverage.
    pub fn with_coverage(&self, values: &[Vec3]) -> Vec<Vec4> {
        with_coverage(&self.texels, values)
    }

    /// The section (`atlas.bin`, keyed to the scene), with `summary` for the manifest.
    pub fn section(&self, summary: Value) -> Section {
        section(&self.meshes, self.layout, &self.texels, summary)
    }

    /// The atlas of `artifact`, checked against `scene` (as loaded, before any atlas was
    /// applied to it): mesh and index counts, indices and source vertices in range, uv1 on the
    /// pages, a possible page layout.
    pub fn read(artifact: &Artifact, scene: &Scene) -> Result<AtlasSection, ArtifactError> {
        Self::read_for(artifact, scene, scene)
    }

    /// The atlas of `artifact`, keyed to `keyed` (the scene as loaded) and made for `scene` (the
    /// same, or its tessellation when the bake split it: the `tessellation` section).
    pub fn read_for(artifact: &Artifact, keyed: &Scene, scene: &Scene) -> Result<AtlasSection, ArtifactError> {
        let data = artifact.section(SECTION, SECTION_VERSION, Some(keyed))?;
        let (bytes, path) = data.file(FILE)?;
        let mut r = Reader::new(&bytes, &path, MAGIC, "atlas")?;
        let mesh_count = r.u32("the mesh count")?;
        if mesh_count as usize != scene.meshes.len() {
            return Err(fail(
                &path,
                format!("holds {mesh_count} meshes but the scene has {}", scene.meshes.len()),
                "bake this scene again",
            ));
        }
        let meshes = scene.meshes.iter().enumerate().map(|(m, mesh)| read_mesh(&mut r, m, mesh)).collect::<Result<Vec<_>, _>>()?;
        let [width, height, pages] = [r.u32("the page width")?, r.u32("the page height")?, r.u32("the page count")?];
        let layout = PageLayout { width, height, pages };
        if width == 0 || height == 0 || pages == 0 || width > 16384 || height > 16384 || layout.texel_count() > 1 << 28 {
            return Err(fail(&path, format!("impossible atlas size {width} x {height} x {pages} pages"), REBAKE));
        }
        // A page's u is its number plus the place on it; v is the place alone.
        let outside = |uv: &&Vec2| !((0.0..=pages as f32).contains(&uv.x) && (0.0..=1.0).contains(&uv.y));
        if let Some((m, uv)) = meshes.iter().enumerate().find_map(|(m, mesh)| mesh.uv1.iter().find(outside).map(|uv| (m, uv))) {
            return Err(fail(
                &path,
                format!("mesh {m}: uv1 {uv} lies outside the atlas's {pages} page(s) (u in 0..={pages}, v in 0..=1)"),
                REBAKE,
            ));
        }
        let floats = r.f32s(layout.texel_count() * 8, "the texels")?;
        let texels = floats
            .chunks_exact(8)
            .map(|f| Texel {
                coverage: f[0],
                centre: Vec3::new(f[1], f[2], f[3]),
                normal: Vec3::new(f[4], f[5], f[6]),
                triangle: f[7].to_bits(),
            })
            .collect::<Vec<_>>();
        r.finish("the texels")?;
        if let Some((t, problem)) = texels.iter().enumerate().find_map(|(t, texel)| texel_problem(texel, scene).map(|p| (t, p))) {
            return Err(fail(&path, format!("texel {t} {problem}"), REBAKE));
        }
        Ok(AtlasSection { meshes, layout, texels })
    }
}

/// What is wrong with a texel read back, if anything: an empty one has coverage 0; a covered
/// one a coverage in (0, 1], a finite centre, a unit normal (zero where the pieces' normals
/// cancel) and a triangle of `scene`.
fn texel_problem(texel: &Texel, scene: &Scene) -> Option<String> {
    if texel.triangle == EMPTY {
        return (texel.coverage != 0.0).then(|| format!("is empty but has coverage {}", texel.coverage));
    }
    let length = texel.normal.length();
    if !(texel.coverage > 0.0 && texel.coverage <= 1.0) {
        Some(format!("has coverage {}, outside (0, 1]", texel.coverage))
    } else if !texel.centre.is_finite() || !(length == 0.0 || (length - 1.0).abs() < 1e-3) {
        Some(format!("has centre {} and normal {}: not a finite point and a unit normal", texel.centre, texel.normal))
    } else if texel.triangle as usize >= scene.triangle_count() {
        Some(format!("names triangle {}, but the scene has {}", texel.triangle, scene.triangle_count()))
    } else {
        None
    }
}

fn read_mesh(r: &mut Reader, m: usize, mesh: &Mesh) -> Result<AtlasMesh, ArtifactError> {
    let item = format!("mesh {m} (\"{}\")", mesh.name);
    let [vertices, index_count] = [r.u32(&format!("{item}'s vertex count"))?, r.u32(&format!("{item}'s index count"))?];
    if index_count as usize != mesh.indices.len() || vertices as usize > 3 * mesh.indices.len() {
        let problem =
            format!("{item}: {vertices} vertices and {index_count} indices, but the scene's mesh has {} indices", mesh.indices.len());
        return Err(fail(r.path(), problem, "bake this scene again"));
    }
    let source_vertex = r.u32s(vertices as usize, &format!("{item}'s source vertices"))?;
    let uv1: Vec<Vec2> = r.f32s(2 * vertices as usize, &format!("{item}'s uv1"))?.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect();
    let indices = r.u32s(index_count as usize, &format!("{item}'s indices"))?;
    let bad_source = source_vertex.iter().any(|&v| v as usize >= mesh.positions.len());
    let bad_index = indices.iter().any(|&i| i >= vertices);
    let bad_uv = uv1.iter().any(|uv| !uv.is_finite());
    if bad_source || bad_index || bad_uv {
        return Err(fail(r.path(), format!("{item}: a vertex or index out of range, or a uv1 that is not finite"), REBAKE));
    }
    Ok(AtlasMesh { source_vertex, uv1, indices })
}
