//! The bake artifact: the one contract between `relume bake` and the renderer, a folder of
//! plain files (format in docs/FORMATS.md, the only description of it):
//!
//! - `manifest.json`: format and version, method, parameters, the scene's checksum, the
//!   atlas summary and every other file's size and checksum. Deterministic: the same inputs
//!   and seed give the same bytes.
//! - `stats.json`: what the bake cost (seconds and peak memory per stage, rays per second).
//! - `atlas.bin`: the re-indexed meshes with uv1, and the per-texel geometry images.
//! - `<method>.exr`: the lightmap, pages stacked top to bottom in one RGB layer.
//! - for methods with a large-scale transfer (light path maps), `transfer.bin` (entry points,
//!   clusters, weights) and `transfer.exr` (cluster means and eigen-textures).
//!
//! Reading checks everything before anything is used: a corrupt, truncated, old or foreign
//! artifact, or one baked for another scene, is refused with the file and the fix named.

use crate::clustered_transfer::{ClusteredTransfer, EntryPoint};
use crate::image::{read_exr_layer, write_atomically, write_exr_layers, Image};
use crate::scene::{Mesh, Scene};
use glam::{Vec2, Vec3, Vec4};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

pub const FORMAT: &str = "relume-bake";
/// Bumped whenever a file's layout or meaning changes; older artifacts are refused.
pub const VERSION: u32 = 1;
const ATLAS_MAGIC: &[u8; 8] = b"RLATLAS\0";
const TRANSFER_MAGIC: &[u8; 8] = b"RLTRANS\0";

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

/// Page size and count of an atlas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PageLayout {
    pub width: u32,
    pub height: u32,
    pub pages: u32,
}

impl PageLayout {
    pub fn texel_count(&self) -> usize {
        self.width as usize * self.height as usize * self.pages as usize
    }
}

/// Everything a bake writes.
pub struct BakeOutput<'a> {
    /// The method's name; also names the lightmap file (`<method>.exr`).
    pub method: &'a str,
    pub scene: &'a Scene,
    /// The method's parameters, as given (recorded in the manifest).
    pub parameters: Value,
    /// Atlas facts for the manifest (size, charts, utilization...).
    pub atlas_summary: Value,
    pub layout: PageLayout,
    pub meshes: &'a [AtlasMesh],
    pub texels: &'a [Texel],
    pub lightmap: &'a [Vec3],
    /// The light path maps' compressed transfer, for methods that have one.
    pub transfer: Option<&'a ClusteredTransfer>,
    /// Timings and memory (`stats.json`; not checksummed, it differs run to run).
    pub stats: Value,
}

/// A bake read back and checked against the scene it is for.
#[derive(Clone, Debug)]
pub struct Baked {
    pub manifest: Value,
    pub layout: PageLayout,
    pub meshes: Vec<AtlasMesh>,
    pub texels: Vec<Texel>,
    pub lightmap: Vec<Vec3>,
    pub transfer: Option<ClusteredTransfer>,
}

/// Why an artifact could not be written or read: the file, what is wrong, what to do.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}; {fix}", path.display())]
pub struct ArtifactError {
    pub path: PathBuf,
    pub problem: String,
    pub fix: String,
}

const REBAKE: &str = "bake it again with `relume bake`";

fn fail(path: &Path, problem: impl Into<String>, fix: &str) -> ArtifactError {
    ArtifactError { path: path.to_path_buf(), problem: problem.into(), fix: fix.to_string() }
}

/// FNV-1a, 64 bits: enough to catch corruption and mismatched files (not an adversary).
pub fn checksum(bytes: &[u8]) -> String {
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    format!("fnv1a64:{hash:016x}")
}

/// A checksum of everything a bake or the path tracer reads of the scene's surfaces: meshes
/// (positions, normals, uv0, triangles, material), materials (base colour, its texture,
/// emission) and textures. Lights and camera are not in it: a bake does not depend on them.
pub fn scene_checksum(scene: &Scene) -> String {
    fn floats<'a>(bytes: &mut Vec<u8>, values: impl IntoIterator<Item = &'a f32>) {
        bytes.extend(values.into_iter().flat_map(|f| f.to_le_bytes()));
    }
    let mut bytes = Vec::new();
    for mesh in &scene.meshes {
        floats(&mut bytes, mesh.positions.iter().chain(&mesh.normals).flat_map(|v| v.as_ref()));
        floats(&mut bytes, mesh.uv0.iter().flatten().flat_map(|v| v.as_ref()));
        bytes.extend(mesh.indices.iter().flat_map(|i| i.to_le_bytes()));
        bytes.extend((mesh.material as u64).to_le_bytes());
    }
    for material in &scene.materials {
        floats(&mut bytes, material.base_color.as_ref().iter().chain(material.emission.as_ref()));
        bytes.extend(material.base_color_texture.map_or(u64::MAX, |t| t as u64).to_le_bytes());
    }
    for texture in &scene.textures {
        bytes.extend([texture.width, texture.height].iter().flat_map(|v| v.to_le_bytes()));
        floats(&mut bytes, texture.texels.iter().flat_map(|t| t.as_ref()));
    }
    checksum(&bytes)
}

impl BakeOutput<'_> {
    /// Writes the artifact into `dir` (created if missing). Files are first written into a
    /// sibling folder, which then replaces `dir`, so `dir` never holds a half-written
    /// artifact. A non-empty `dir` that is not an artifact is never replaced.
    pub fn write(&self, dir: &Path) -> Result<(), ArtifactError> {
        refuse_foreign_folder(dir)?;
        let staging = staging_folder(dir);
        let _ = std::fs::remove_dir_all(&staging);
        std::fs::create_dir_all(&staging)
            .map_err(|e| fail(&staging, format!("cannot create the folder ({e})"), "check the path and permissions"))?;
        let written = self.write_files(&staging).and_then(|()| replace_folder(&staging, dir));
        if written.is_err() {
            let _ = std::fs::remove_dir_all(&staging);
        }
        written
    }

    fn write_files(&self, dir: &Path) -> Result<(), ArtifactError> {
        let atlas_bytes = encode_atlas(self.meshes, self.layout, self.texels);
        let atlas_path = dir.join("atlas.bin");
        std::fs::write(&atlas_path, &atlas_bytes)
            .map_err(|e| fail(&atlas_path, format!("cannot write ({e})"), "check free space and permissions"))?;
        let lightmap_name = format!("{}.exr", self.method);
        let lightmap_path = dir.join(&lightmap_name);
        let image = Image { width: self.layout.width, height: self.layout.height * self.layout.pages, pixels: self.lightmap.to_vec() };
        write_exr_layers(&lightmap_path, &[("W", &image)])
            .map_err(|e| fail(&lightmap_path, e.to_string(), "check free space and permissions"))?;
        let lightmap_bytes = std::fs::read(&lightmap_path).map_err(|e| fail(&lightmap_path, e.to_string(), "check permissions"))?;
        let file_entry = |bytes: &[u8]| json!({ "bytes": bytes.len(), "checksum": checksum(bytes) });
        let mut files = json!({ "atlas.bin": file_entry(&atlas_bytes), lightmap_name.clone(): file_entry(&lightmap_bytes) });
        if let Some(transfer) = self.transfer {
            for (name, bytes) in self.write_transfer(dir, transfer)? {
                files[name] = file_entry(&bytes);
            }
        }
        let manifest = json!({
            "format": FORMAT,
            "version": VERSION,
            "relume": env!("CARGO_PKG_VERSION"),
            "method": self.method,
            "scene": {
                "file": self.scene.source.file_name().map(|n| n.to_string_lossy().into_owned()),
                "checksum": scene_checksum(self.scene),
            },
            "parameters": self.parameters,
            "atlas": self.atlas_summary,
            "layout": { "width": self.layout.width, "height": self.layout.height, "pages": self.layout.pages },
            "lightmap": lightmap_name,
            "files": files,
        });
        write_json(&dir.join("stats.json"), &self.stats)?;
        write_json(&dir.join("manifest.json"), &manifest)
    }
}

impl BakeOutput<'_> {
    /// Writes `transfer.bin` and `transfer.exr`; returns each file's name and bytes.
    fn write_transfer(&self, dir: &Path, transfer: &ClusteredTransfer) -> Result<[(&'static str, Vec<u8>); 2], ArtifactError> {
        let bin = encode_transfer(transfer);
        let bin_path = dir.join(TRANSFER_BIN);
        std::fs::write(&bin_path, &bin).map_err(|e| fail(&bin_path, format!("cannot write ({e})"), "check free space and permissions"))?;
        let exr_path = dir.join(TRANSFER_EXR);
        let rows = (transfer.textures.len() / self.layout.width as usize) as u32;
        let image = Image { width: self.layout.width, height: rows, pixels: transfer.textures.clone() };
        write_exr_layers(&exr_path, &[("T", &image)]).map_err(|e| fail(&exr_path, e.to_string(), "check free space and permissions"))?;
        let exr = std::fs::read(&exr_path).map_err(|e| fail(&exr_path, e.to_string(), "check permissions"))?;
        Ok([(TRANSFER_BIN, bin), (TRANSFER_EXR, exr)])
    }
}

const TRANSFER_BIN: &str = "transfer.bin";
const TRANSFER_EXR: &str = "transfer.exr";

fn encode_transfer(t: &ClusteredTransfer) -> Vec<u8> {
    let mut out = TRANSFER_MAGIC.to_vec();
    let u32s = |out: &mut Vec<u8>, values: &[u32]| out.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    let f32s = |out: &mut Vec<u8>, values: &[f32]| out.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    u32s(&mut out, &[VERSION, t.entry_points.len() as u32, t.cluster_count() as u32, t.basis_count, t.texel_count as u32]);
    f32s(&mut out, &[t.light_area]);
    u32s(&mut out, &t.cluster_starts);
    for e in &t.entry_points {
        f32s(&mut out, &[e.position.x, e.position.y, e.position.z, e.normal.x, e.normal.y, e.normal.z]);
    }
    f32s(&mut out, &t.weights);
    out
}

/// Reads `transfer.bin` and `transfer.exr` (checksums already checked) for an atlas of
/// `texel_count` texels.
fn decode_transfer(dir: &Path, bin: &[u8], layout: PageLayout) -> Result<ClusteredTransfer, ArtifactError> {
    let path = dir.join(TRANSFER_BIN);
    let mut r = Reader { bytes: bin, at: 0, path: &path };
    if r.take(8, "the magic number")? != TRANSFER_MAGIC {
        return Err(fail(&path, "not a relume transfer file (wrong magic number)", REBAKE));
    }
    let version = r.u32("the version")?;
    if version != VERSION {
        return Err(fail(&path, format!("transfer format version {version}; this relume reads version {VERSION}"), REBAKE));
    }
    let [entries, clusters, basis_count, texel_count] =
        [r.u32("the entry-point count")?, r.u32("the cluster count")?, r.u32("D")?, r.u32("the texel count")?];
    if texel_count as usize != layout.texel_count() || entries > 1 << 24 || clusters > entries || basis_count > 1024 {
        return Err(fail(
            &path,
            format!(
                "{entries} entry points, {clusters} clusters, D = {basis_count}, {texel_count} texels do not fit an atlas of {} texels",
                layout.texel_count()
            ),
            REBAKE,
        ));
    }
    let light_area = r.f32s(1, "the light area")?[0];
    let cluster_starts = r.u32s(clusters + 1, "the cluster starts")?;
    let entry_points = r
        .f32s(entries as usize * 6, "the entry points")?
        .chunks_exact(6)
        .map(|f| EntryPoint { position: Vec3::new(f[0], f[1], f[2]), normal: Vec3::new(f[3], f[4], f[5]) })
        .collect();
    let weights = r.f32s(entries as usize * basis_count as usize, "the weights")?;
    if r.at != bin.len() {
        return Err(fail(&path, format!("{} bytes after the weights", bin.len() - r.at), REBAKE));
    }
    let exr_path = dir.join(TRANSFER_EXR);
    let image = read_exr_layer(&exr_path, Some("T")).map_err(|e| fail(&exr_path, e.to_string(), REBAKE))?;
    let transfer = ClusteredTransfer {
        entry_points,
        cluster_starts,
        basis_count,
        weights,
        texel_count: texel_count as usize,
        textures: image.pixels,
        light_area,
    };
    transfer.validate().map_err(|e| fail(&path, e, REBAKE))?;
    Ok(transfer)
}

fn write_json(path: &Path, value: &Value) -> Result<(), ArtifactError> {
    let mut text = serde_json::to_string_pretty(value).map_err(|e| fail(path, e.to_string(), "report this as a bug"))?;
    text.push('\n');
    write_atomically(path, |tmp| std::fs::write(tmp, &text).map_err(|e| e.to_string()))
        .map_err(|e| fail(path, e.to_string(), "check free space and permissions"))
}

fn staging_folder(dir: &Path) -> PathBuf {
    let mut name = dir.file_name().map(|n| n.to_os_string()).unwrap_or_else(|| "bake".into());
    name.push(format!(".partial-{}", std::process::id()));
    dir.with_file_name(name)
}

fn refuse_foreign_folder(dir: &Path) -> Result<(), ArtifactError> {
    let Ok(mut entries) = std::fs::read_dir(dir) else { return Ok(()) };
    if entries.next().is_some() && !dir.join("manifest.json").is_file() {
        return Err(fail(dir, "exists, is not empty and holds no bake artifact (no manifest.json)", "choose another --out folder"));
    }
    Ok(())
}

fn replace_folder(staging: &Path, dir: &Path) -> Result<(), ArtifactError> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).map_err(|e| fail(dir, format!("cannot replace the old artifact ({e})"), "check permissions"))?;
    }
    std::fs::rename(staging, dir).map_err(|e| fail(dir, format!("cannot move the new artifact in place ({e})"), "check permissions"))
}

// --- atlas.bin ----------------------------------------------------------------------------------

fn encode_atlas(meshes: &[AtlasMesh], layout: PageLayout, texels: &[Texel]) -> Vec<u8> {
    let mut out = ATLAS_MAGIC.to_vec();
    let u32s = |out: &mut Vec<u8>, values: &[u32]| out.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    u32s(&mut out, &[VERSION, meshes.len() as u32]);
    for mesh in meshes {
        u32s(&mut out, &[mesh.source_vertex.len() as u32, mesh.indices.len() as u32]);
        u32s(&mut out, &mesh.source_vertex);
        out.extend(mesh.uv1.iter().flat_map(|uv| uv.to_array()).flat_map(f32::to_le_bytes));
        u32s(&mut out, &mesh.indices);
    }
    u32s(&mut out, &[layout.width, layout.height, layout.pages]);
    for t in texels {
        let floats = [t.coverage, t.centre.x, t.centre.y, t.centre.z, t.normal.x, t.normal.y, t.normal.z];
        out.extend(floats.iter().flat_map(|f| f.to_le_bytes()));
        out.extend(t.triangle.to_le_bytes());
    }
    out
}

/// Reads little-endian values, refusing to read past the end with the offset named.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    path: &'a Path,
}

impl Reader<'_> {
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], ArtifactError> {
        let end = self.at.checked_add(n).filter(|&end| end <= self.bytes.len());
        let Some(end) = end else {
            return Err(fail(
                self.path,
                format!("truncated: {what} needs {n} bytes at offset {} but the file has {}", self.at, self.bytes.len()),
                REBAKE,
            ));
        };
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    fn u32(&mut self, what: &str) -> Result<u32, ArtifactError> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes")))
    }

    fn u32s(&mut self, count: u32, what: &str) -> Result<Vec<u32>, ArtifactError> {
        let bytes = self.take(count as usize * 4, what)?;
        Ok(bytes.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes"))).collect())
    }

    fn f32s(&mut self, count: usize, what: &str) -> Result<Vec<f32>, ArtifactError> {
        let bytes = self.take(count * 4, what)?;
        Ok(bytes.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes"))).collect())
    }
}

fn decode_atlas(path: &Path, bytes: &[u8], scene: &Scene) -> Result<(Vec<AtlasMesh>, PageLayout, Vec<Texel>), ArtifactError> {
    let mut r = Reader { bytes, at: 0, path };
    if r.take(8, "the magic number")? != ATLAS_MAGIC {
        return Err(fail(path, "not a relume atlas file (wrong magic number)", REBAKE));
    }
    let version = r.u32("the version")?;
    if version != VERSION {
        return Err(fail(path, format!("atlas format version {version}; this relume reads version {VERSION}"), REBAKE));
    }
    let mesh_count = r.u32("the mesh count")?;
    if mesh_count as usize != scene.meshes.len() {
        return Err(fail(path, format!("holds {mesh_count} meshes but the scene has {}", scene.meshes.len()), "bake this scene again"));
    }
    let meshes = scene.meshes.iter().enumerate().map(|(m, mesh)| decode_mesh(&mut r, m, mesh)).collect::<Result<Vec<_>, _>>()?;
    let [width, height, pages] = [r.u32("the page width")?, r.u32("the page height")?, r.u32("the page count")?];
    let layout = PageLayout { width, height, pages };
    if width == 0 || height == 0 || pages == 0 || width > 16384 || height > 16384 || layout.texel_count() > 1 << 28 {
        return Err(fail(path, format!("impossible atlas size {width} x {height} x {pages} pages"), REBAKE));
    }
    let floats = r.f32s(layout.texel_count() * 8, "the texels")?;
    let texels: Vec<Texel> = floats
        .chunks_exact(8)
        .map(|f| Texel {
            coverage: f[0],
            centre: Vec3::new(f[1], f[2], f[3]),
            normal: Vec3::new(f[4], f[5], f[6]),
            triangle: f[7].to_bits(),
        })
        .collect();
    if r.at != bytes.len() {
        return Err(fail(path, format!("{} bytes after the texels", bytes.len() - r.at), REBAKE));
    }
    Ok((meshes, layout, texels))
}

fn decode_mesh(r: &mut Reader, m: usize, mesh: &Mesh) -> Result<AtlasMesh, ArtifactError> {
    let item = format!("mesh {m} (\"{}\")", mesh.name);
    let [vertices, index_count] = [r.u32(&format!("{item}'s vertex count"))?, r.u32(&format!("{item}'s index count"))?];
    if index_count as usize != mesh.indices.len() || vertices as usize > 3 * mesh.indices.len() {
        return Err(fail(
            r.path,
            format!("{item}: {vertices} vertices and {index_count} indices, but the scene's mesh has {} indices", mesh.indices.len()),
            "bake this scene again",
        ));
    }
    let source_vertex = r.u32s(vertices, &format!("{item}'s source vertices"))?;
    let uv1: Vec<Vec2> = r.f32s(2 * vertices as usize, &format!("{item}'s uv1"))?.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect();
    let indices = r.u32s(index_count, &format!("{item}'s indices"))?;
    let bad_source = source_vertex.iter().any(|&v| v as usize >= mesh.positions.len());
    let bad_index = indices.iter().any(|&i| i >= vertices);
    let bad_uv = uv1.iter().any(|uv| !uv.is_finite());
    if bad_source || bad_index || bad_uv {
        return Err(fail(r.path, format!("{item}: a vertex or index out of range, or a uv1 that is not finite"), REBAKE));
    }
    Ok(AtlasMesh { source_vertex, uv1, indices })
}

// --- reading ------------------------------------------------------------------------------------

impl Baked {
    /// Reads and checks the artifact in `dir` against `scene` (as loaded, before any
    /// artifact was applied to it).
    pub fn read(dir: &Path, scene: &Scene) -> Result<Baked, ArtifactError> {
        let manifest_path = dir.join("manifest.json");
        let text = std::fs::read_to_string(&manifest_path)
            .map_err(|e| fail(&manifest_path, format!("cannot read ({e})"), "give the folder `relume bake --out` wrote"))?;
        let manifest: Value = serde_json::from_str(&text).map_err(|e| fail(&manifest_path, format!("not valid JSON ({e})"), REBAKE))?;
        check_header(&manifest_path, &manifest, scene)?;
        let file = |name: &str| -> Result<Vec<u8>, ArtifactError> {
            let path = dir.join(name);
            let bytes = std::fs::read(&path).map_err(|e| fail(&path, format!("cannot read ({e})"), REBAKE))?;
            let expected = manifest["files"][name]["checksum"].as_str().unwrap_or("(none)");
            if checksum(&bytes) != expected {
                return Err(fail(
                    &path,
                    format!(
                        "checksum {} differs from the manifest's {expected}: the file is corrupt or from another bake",
                        checksum(&bytes)
                    ),
                    REBAKE,
                ));
            }
            Ok(bytes)
        };
        let atlas_path = dir.join("atlas.bin");
        let (meshes, layout, texels) = decode_atlas(&atlas_path, &file("atlas.bin")?, scene)?;
        let lightmap_name = manifest["lightmap"].as_str().unwrap_or("").to_string();
        let lightmap_path = dir.join(&lightmap_name);
        file(&lightmap_name)?;
        let image = read_exr_layer(&lightmap_path, Some("W")).map_err(|e| fail(&lightmap_path, e.to_string(), REBAKE))?;
        if (image.width, image.height) != (layout.width, layout.height * layout.pages) {
            return Err(fail(
                &lightmap_path,
                format!("is {} x {}, the atlas {} x {} x {} pages", image.width, image.height, layout.width, layout.height, layout.pages),
                REBAKE,
            ));
        }
        let transfer = match manifest["files"].get(TRANSFER_BIN) {
            Some(_) => {
                file(TRANSFER_EXR)?;
                Some(decode_transfer(dir, &file(TRANSFER_BIN)?, layout)?)
            }
            None => None,
        };
        Ok(Baked { manifest, layout, meshes, texels, lightmap: image.pixels, transfer })
    }

    /// The scene with every mesh re-indexed and given its uv1.
    pub fn apply_to(&self, scene: &mut Scene) {
        for (mesh, atlas_mesh) in scene.meshes.iter_mut().zip(&self.meshes) {
            *mesh = atlas_mesh.apply(mesh);
        }
    }

    /// The lightmap as the renderer uploads it: rgb the baked value, alpha the coverage.
    pub fn lightmap_rgba(&self) -> Vec<Vec4> {
        self.lightmap.iter().zip(&self.texels).map(|(v, t)| v.extend(t.coverage)).collect()
    }

    pub fn method(&self) -> &str {
        self.manifest["method"].as_str().unwrap_or("")
    }
}

fn check_header(path: &Path, manifest: &Value, scene: &Scene) -> Result<(), ArtifactError> {
    if manifest["format"] != FORMAT {
        return Err(fail(path, "not a relume bake manifest (no \"format\": \"relume-bake\")", "give the folder `relume bake --out` wrote"));
    }
    if manifest["version"] != VERSION {
        return Err(fail(
            path,
            format!("bake format version {} (relume {}); this relume reads version {VERSION}", manifest["version"], manifest["relume"]),
            REBAKE,
        ));
    }
    let expected = scene_checksum(scene);
    if manifest["scene"]["checksum"] != expected.as_str() {
        return Err(fail(
            path,
            format!(
                "baked for scene {} with checksum {}, but {} has checksum {expected}",
                manifest["scene"]["file"],
                manifest["scene"]["checksum"],
                scene.source.display()
            ),
            "bake this scene, or give the scene this bake was made for",
        ));
    }
    Ok(())
}
