//! The bake artifact: the one contract between `relume bake` and the renderer, a folder of
//! plain files whose format docs/FORMATS.md describes. A manifest names the method that baked
//! it, its parameters, and its sections; a section is named and versioned, says what it is
//! keyed to (the scene, one mesh of it, or nothing: scene-independent data) and owns its
//! files, each with its size and checksum. Sections are defined by the parts that own them
//! (the atlas, each method); this module knows none of them.
//!
//! Reading checks everything before anything is used: a corrupt, truncated, old or foreign
//! artifact is refused with the file and the fix named, and a section is handed out only
//! after its version and its key (against the scene or mesh it is read for) are checked.

use crate::environment::Environment;
use crate::image::{read_exr_layer, Image};
use crate::outputs::{write_staged, OutputError, Outputs};
use crate::scene::{Mesh, Scene};
use serde_json::{json, Map, Value};
use std::io::Read;
use std::path::{Path, PathBuf};

pub const FORMAT: &str = "relume-bake";
/// Bumped whenever the manifest's layout or meaning changes; older artifacts are refused.
/// Version 1 had a fixed set of files instead of sections.
pub const VERSION: u32 = 2;

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

/// What a section's data depends on, checked when it is read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Key {
    /// The scene's surfaces ([`scene_checksum`]).
    Scene,
    /// One mesh of the scene, by name ([`mesh_checksum`] of it as loaded): data that goes
    /// with that mesh alone, whatever else the scene holds.
    Mesh(String),
    /// The scene's environment light ([`environment_checksum`] of its working cube): data
    /// that goes with the lighting whatever surfaces the scene holds.
    Environment,
    /// Nothing: data made once for every scene (a dictionary).
    Nothing,
}

/// A section as a bake writes it.
pub struct Section {
    pub name: String,
    pub version: u32,
    pub key: Key,
    /// Facts about the section for the manifest (sizes, counts, what it was made with).
    pub summary: Value,
    /// File name (unique in the artifact) and bytes.
    pub files: Vec<(String, Vec<u8>)>,
}

/// Everything a bake writes.
pub struct BakeOutput<'a> {
    /// The method that baked it (the registry's name).
    pub method: &'a str,
    /// The scene it was baked from: its file name is recorded, and it keys the sections.
    pub scene: Option<&'a Scene>,
    /// The method's parameters, as given (recorded in the manifest).
    pub parameters: Value,
    pub sections: Vec<Section>,
    /// Timings and memory (`stats.json`; not checksummed, it differs run to run).
    pub stats: Value,
}

/// Why an artifact could not be written or read: the file, what is wrong, what to do.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}; {fix}", path.display())]
pub struct ArtifactError {
    pub path: PathBuf,
    pub problem: String,
    pub fix: String,
}

pub(crate) const REBAKE: &str = "bake it again with `relume bake`";

pub(crate) fn fail(path: &Path, problem: impl Into<String>, fix: &str) -> ArtifactError {
    ArtifactError { path: path.to_path_buf(), problem: problem.into(), fix: fix.to_string() }
}

/// FNV-1a, 64 bits, fed piece by piece: enough to catch corruption and mismatched files (not
/// an adversary).
struct Fnv(u64);

impl Fnv {
    fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    fn write(&mut self, bytes: &[u8]) {
        self.0 = bytes.iter().fold(self.0, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    }

    fn floats<'a>(&mut self, values: impl IntoIterator<Item = &'a f32>) {
        values.into_iter().for_each(|f| self.write(&f.to_le_bytes()));
    }

    fn mesh(&mut self, mesh: &Mesh) {
        self.floats(mesh.positions.iter().chain(&mesh.normals).flat_map(|v| v.as_ref()));
        self.floats(mesh.uv0.iter().flatten().flat_map(|v| v.as_ref()));
        mesh.indices.iter().for_each(|i| self.write(&i.to_le_bytes()));
        self.write(&(mesh.material as u64).to_le_bytes());
    }

    fn finish(&self) -> String {
        format!("fnv1a64:{:016x}", self.0)
    }
}

pub fn checksum(bytes: &[u8]) -> String {
    let mut hash = Fnv::new();
    hash.write(bytes);
    hash.finish()
}

/// The checksum of the file at `path`, read in pieces (no file is held whole to check it).
pub fn file_checksum(path: &Path) -> std::io::Result<String> {
    let mut file = std::fs::File::open(path)?;
    let (mut hash, mut buffer) = (Fnv::new(), vec![0u8; 1 << 16]);
    loop {
        match file.read(&mut buffer)? {
            0 => return Ok(hash.finish()),
            n => hash.write(&buffer[..n]),
        }
    }
}

/// A checksum of everything a bake or the path tracer reads of the scene's surfaces: meshes
/// (positions, normals, uv0, triangles, material), materials (base colour, its texture,
/// emission) and textures. Lights and camera are not in it: a bake does not depend on them.
pub fn scene_checksum(scene: &Scene) -> String {
    let mut hash = Fnv::new();
    scene.meshes.iter().for_each(|mesh| hash.mesh(mesh));
    for material in &scene.materials {
        hash.floats(material.base_color.as_ref().iter().chain(material.emission.as_ref()));
        hash.write(&material.base_color_texture.map_or(u64::MAX, |t| t as u64).to_le_bytes());
        // Only when present, so that every Lambertian scene keeps its checksum.
        if let Some(phong) = &material.phong {
            hash.floats(phong.specular.as_ref().iter().chain([&phong.exponent]));
        }
    }
    for texture in &scene.textures {
        [texture.width, texture.height].iter().for_each(|v| hash.write(&v.to_le_bytes()));
        hash.floats(texture.texels.iter().flat_map(|t| t.as_ref()));
    }
    hash.finish()
}

/// A checksum of an environment's working cube: its size and every texel's radiance.
pub fn environment_checksum(environment: &Environment) -> String {
    let mut hash = Fnv::new();
    hash.write(&environment.face.to_le_bytes());
    hash.floats(environment.radiance.iter().flat_map(|l| l.as_ref()));
    hash.finish()
}

/// A checksum of one mesh's shape: positions, normals, uv0, triangles and material index.
pub fn mesh_checksum(mesh: &Mesh) -> String {
    let mut hash = Fnv::new();
    hash.mesh(mesh);
    hash.finish()
}

impl Key {
    /// The manifest's record of the key, with the checksum of what it names (`scene_sum`: the
    /// scene's, taken once for every section).
    fn record(&self, scene: Option<&Scene>, scene_sum: Option<&str>, section: &str, dir: &Path) -> Result<Value, ArtifactError> {
        let need_scene = || {
            scene.ok_or_else(|| {
                fail(dir, format!("section {section} is keyed to the scene, but no scene was given"), "report this as a bug")
            })
        };
        Ok(match self {
            Key::Scene => {
                need_scene()?;
                json!({ "kind": "scene", "checksum": scene_sum })
            }
            Key::Mesh(name) => {
                let mesh = need_scene()?.meshes.iter().find(|m| &m.name == name);
                let mesh = mesh.ok_or_else(|| {
                    fail(dir, format!("section {section} is keyed to mesh \"{name}\", which the scene lacks"), "report this as a bug")
                })?;
                json!({ "kind": "mesh", "mesh": name, "checksum": mesh_checksum(mesh) })
            }
            Key::Environment => {
                let environment = need_scene()?.environment.as_ref().ok_or_else(|| {
                    fail(dir, format!("section {section} is keyed to the environment, which the scene lacks"), "report this as a bug")
                })?;
                json!({ "kind": "environment", "checksum": environment_checksum(environment) })
            }
            Key::Nothing => json!({ "kind": "none" }),
        })
    }
}

/// Whether a number read from a bake is one a bake makes: finite and within 1e9 either side
/// (`scene::MAX_LIGHT`; a light map's 3e38, finite, made a render's pixels infinite).
pub fn stored(v: f32) -> bool {
    v.is_finite() && v.abs() <= crate::scene::MAX_LIGHT
}

fn unwritten(e: OutputError) -> ArtifactError {
    fail(&e.path, e.message, "check the path, free space and permissions")
}

impl BakeOutput<'_> {
    /// Writes the artifact into `dir` (created if missing). Files are first written into a
    /// hidden sibling folder, which then replaces `dir` ([`Outputs::folder`]), so `dir` never
    /// holds a half-written artifact. A non-empty `dir` that is not an artifact is never
    /// replaced.
    pub fn write(&self, dir: &Path) -> Result<(), ArtifactError> {
        let mut outputs = Outputs::new();
        self.stage(&mut outputs, dir)?;
        outputs.commit().map_err(unwritten)
    }

    /// Stages the artifact for `dir` among `outputs`, to be moved in place by their commit
    /// with the command's other outputs; returns the staging folder, which reads as the
    /// artifact until then.
    pub fn stage(&self, outputs: &mut Outputs, dir: &Path) -> Result<PathBuf, ArtifactError> {
        refuse_foreign_folder(dir)?;
        let manifest = self.manifest(dir)?;
        let staging = outputs.folder(dir).map_err(unwritten)?;
        self.write_files(&staging, &manifest)?;
        Ok(staging)
    }

    fn manifest(&self, dir: &Path) -> Result<Value, ArtifactError> {
        let mut sections = Vec::with_capacity(self.sections.len());
        let mut names: Vec<&str> = Vec::new();
        let scene_sum = self.scene.map(scene_checksum);
        for (k, section) in self.sections.iter().enumerate() {
            if self.sections[..k].iter().any(|s| s.name == section.name) {
                return Err(fail(dir, format!("two sections named {}", section.name), "report this as a bug"));
            }
            let mut files = Map::new();
            for (name, bytes) in &section.files {
                if names.contains(&name.as_str()) || name == "manifest.json" || name == "stats.json" {
                    return Err(fail(dir, format!("two files named {name}"), "report this as a bug"));
                }
                names.push(name);
                files.insert(name.clone(), json!({ "bytes": bytes.len(), "checksum": checksum(bytes) }));
            }
            sections.push(json!({
                "name": section.name,
                "version": section.version,
                "key": section.key.record(self.scene, scene_sum.as_deref(), &section.name, dir)?,
                "summary": section.summary,
                "files": files,
            }));
        }
        let scene_file = self.scene.and_then(|s| s.source.file_name()).map(|n| n.to_string_lossy().into_owned());
        Ok(json!({
            "format": FORMAT,
            "version": VERSION,
            "relume": env!("CARGO_PKG_VERSION"),
            "method": self.method,
            "scene": scene_file,
            "parameters": self.parameters,
            "sections": sections,
        }))
    }

    fn write_files(&self, dir: &Path, manifest: &Value) -> Result<(), ArtifactError> {
        for (name, bytes) in self.sections.iter().flat_map(|s| &s.files) {
            let path = dir.join(name);
            write_staged(&path, bytes).map_err(|e| fail(&path, format!("cannot write ({e})"), "check free space and permissions"))?;
        }
        write_json(&dir.join("stats.json"), &self.stats)?;
        write_json(&dir.join("manifest.json"), manifest)
    }
}

fn write_json(path: &Path, value: &Value) -> Result<(), ArtifactError> {
    let mut text = serde_json::to_string_pretty(value).map_err(|e| fail(path, e.to_string(), "report this as a bug"))?;
    text.push('\n');
    write_staged(path, text.as_bytes()).map_err(|e| fail(path, format!("cannot write ({e})"), "check free space and permissions"))
}

/// A bake replaces only what a bake wrote: `dir` must be new, empty, or a bake artifact
/// whose every entry its manifest names (the manifest, the stats and the sections' files);
/// anything else in it (a user's file, a folder) refuses the bake, by name.
pub fn refuse_foreign_folder(dir: &Path) -> Result<(), ArtifactError> {
    const FIX: &str = "choose an empty or new --out folder";
    crate::inputs::refuse_output_folder(dir).map_err(|e| fail(dir, e, FIX))?;
    match std::fs::symlink_metadata(dir) {
        Err(_) => return Ok(()),
        Ok(m) if !m.is_dir() => return Err(fail(dir, "exists and is not a folder", FIX)),
        Ok(_) => {}
    }
    let entries: Vec<String> = std::fs::read_dir(dir)
        .map_err(|e| fail(dir, format!("cannot be listed ({e})"), FIX))?
        .map(|e| e.map(|e| e.file_name().to_string_lossy().into_owned()))
        .collect::<Result<_, _>>()
        .map_err(|e| fail(dir, format!("cannot be listed ({e})"), FIX))?;
    if entries.is_empty() {
        return Ok(());
    }
    let manifest: Option<Value> = std::fs::read(dir.join("manifest.json")).ok().and_then(|b| serde_json::from_slice(&b).ok());
    let Some(manifest) = manifest.filter(|m| m["format"] == FORMAT) else {
        return Err(fail(dir, "exists, is not empty and holds no bake artifact (no relume manifest.json)", FIX));
    };
    let sections = manifest["sections"].as_array().into_iter().flatten();
    let listed: Vec<&str> = sections.filter_map(|s| s["files"].as_object()).flat_map(|f| f.keys().map(String::as_str)).collect();
    let foreign = entries.iter().find(|e| !["manifest.json", "stats.json"].contains(&e.as_str()) && !listed.contains(&e.as_str()));
    match foreign {
        Some(name) => Err(fail(dir, format!("holds \"{name}\", which no bake wrote there; a bake replaces the whole folder"), FIX)),
        None => Ok(()),
    }
}

// --- reading ------------------------------------------------------------------------------------

/// An artifact read back: its manifest checked and every file's checksum with it (each file
/// read in pieces; it is read again when its section is decoded, so no bytes are held).
#[derive(Debug)]
pub struct Artifact {
    dir: PathBuf,
    manifest: Value,
    sections: Vec<StoredSection>,
}

#[derive(Debug)]
struct StoredSection {
    name: String,
    version: u32,
    key: Value,
    /// Each file's name (its checksum checked by `read`).
    files: Vec<String>,
}

/// One section's files, once its version and key have been checked.
pub struct SectionData<'a> {
    dir: &'a Path,
    pub name: &'a str,
    files: &'a [String],
}

impl SectionData<'_> {
    /// The path of `file`; refused when the section lacks it.
    fn path(&self, file: &str) -> Result<PathBuf, ArtifactError> {
        let path = self.dir.join(file);
        match self.files.iter().any(|name| name == file) {
            true => Ok(path),
            false => Err(fail(&path, format!("section {} has no file {file}", self.name), REBAKE)),
        }
    }

    /// The bytes of `file` and its path.
    pub fn file(&self, file: &str) -> Result<(Vec<u8>, PathBuf), ArtifactError> {
        let path = self.path(file)?;
        let bytes = std::fs::read(&path).map_err(|e| fail(&path, format!("cannot read ({e})"), REBAKE))?;
        Ok((bytes, path))
    }

    /// Layer `layer` of the EXR `file`, streamed, refused unless it is `width` x `height`;
    /// with its path.
    pub fn exr_layer(&self, file: &str, layer: &str, (width, height): (u32, u32)) -> Result<(Image, PathBuf), ArtifactError> {
        let path = self.path(file)?;
        let image = read_exr_layer(&path, Some(layer)).map_err(|e| fail(&path, e.to_string(), REBAKE))?;
        if (image.width, image.height) != (width, height) {
            return Err(fail(&path, format!("is {} x {}, where {width} x {height} belong", image.width, image.height), REBAKE));
        }
        Ok((image, path))
    }
}

const GIVE_ARTIFACT: &str = "give the folder `relume bake --out` wrote";

impl Artifact {
    /// Reads and checks the artifact in `dir`: the manifest's format and version, its
    /// sections' shape, and every file's checksum.
    pub fn read(dir: &Path) -> Result<Artifact, ArtifactError> {
        let manifest_path = dir.join("manifest.json");
        crate::inputs::admit(&manifest_path).map_err(|e| fail(&manifest_path, e, GIVE_ARTIFACT))?;
        let text =
            std::fs::read_to_string(&manifest_path).map_err(|e| fail(&manifest_path, format!("cannot read ({e})"), GIVE_ARTIFACT))?;
        let manifest: Value = serde_json::from_str(&text).map_err(|e| fail(&manifest_path, format!("not valid JSON ({e})"), REBAKE))?;
        if manifest["format"] != FORMAT {
            return Err(fail(&manifest_path, "not a relume bake manifest (no \"format\": \"relume-bake\")", GIVE_ARTIFACT));
        }
        if manifest["version"] != VERSION {
            let problem =
                format!("bake format version {} (relume {}); this relume reads version {VERSION}", manifest["version"], manifest["relume"]);
            return Err(fail(&manifest_path, problem, REBAKE));
        }
        if !manifest["method"].is_string() {
            return Err(fail(&manifest_path, "names no method", REBAKE));
        }
        let listed = manifest["sections"].as_array().ok_or_else(|| fail(&manifest_path, "has no list of sections", REBAKE))?;
        let sections = listed.iter().map(|s| read_section(dir, &manifest_path, s)).collect::<Result<Vec<_>, _>>()?;
        if let Some((_, twice)) = sections.iter().enumerate().find(|(k, s)| sections[..*k].iter().any(|t| t.name == s.name)) {
            return Err(fail(&manifest_path, format!("lists section {} twice", twice.name), REBAKE));
        }
        Ok(Artifact { dir: dir.to_path_buf(), manifest, sections })
    }

    pub fn method(&self) -> &str {
        self.manifest["method"].as_str().unwrap_or("")
    }

    /// Whether the artifact holds section `name` (for a section a bake writes only sometimes).
    pub fn has_section(&self, name: &str) -> bool {
        self.sections.iter().any(|s| s.name == name)
    }

    /// Section `name` at `version`, after checking its key against `scene`: a section keyed
    /// to the scene, a mesh or its environment is read with the scene (and one keyed to
    /// nothing is then refused); a scene-independent one is read without.
    pub fn section(&self, name: &str, version: u32, scene: Option<&Scene>) -> Result<SectionData<'_>, ArtifactError> {
        let manifest_path = self.dir.join("manifest.json");
        let Some(section) = self.sections.iter().find(|s| s.name == name) else {
            let held: Vec<&str> = self.sections.iter().map(|s| s.name.as_str()).collect();
            let problem = format!("a {} bake has no section {name} (it has: {})", self.method(), held.join(", "));
            return Err(fail(&manifest_path, problem, "bake with the method that makes it"));
        };
        if section.version != version {
            let problem = format!("section {name} is version {}; this relume reads version {version}", section.version);
            return Err(fail(&manifest_path, problem, REBAKE));
        }
        check_key(&manifest_path, name, &section.key, scene)?;
        Ok(SectionData { dir: &self.dir, name: &section.name, files: &section.files })
    }
}

fn read_section(dir: &Path, manifest_path: &Path, entry: &Value) -> Result<StoredSection, ArtifactError> {
    let bad = |what: &str| fail(manifest_path, format!("a section {what}"), REBAKE);
    let name = entry["name"].as_str().ok_or_else(|| bad("has no name"))?.to_string();
    let version = entry["version"].as_u64().and_then(|v| u32::try_from(v).ok()).ok_or_else(|| bad("has no version"))?;
    let files = entry["files"].as_object().ok_or_else(|| bad("lists no files"))?;
    for (file, facts) in files {
        if file.contains(['/', '\\']) || file.starts_with('.') {
            return Err(fail(manifest_path, format!("section {name} names a file outside the folder: {file}"), REBAKE));
        }
        let path = dir.join(file);
        crate::inputs::admit(&path).map_err(|e| fail(&path, e, REBAKE))?;
        let size = std::fs::metadata(&path).map_err(|e| fail(&path, format!("cannot read ({e})"), REBAKE))?.len();
        if facts["bytes"].as_u64() != Some(size) {
            let problem =
                format!("is {size} bytes, where the manifest says {}: the file is truncated or from another bake", facts["bytes"]);
            return Err(fail(&path, problem, REBAKE));
        }
        let expected = facts["checksum"].as_str().unwrap_or("(none)");
        let actual = file_checksum(&path).map_err(|e| fail(&path, format!("cannot read ({e})"), REBAKE))?;
        if actual != expected {
            let problem = format!("checksum {actual} differs from the manifest's {expected}: the file is corrupt or from another bake");
            return Err(fail(&path, problem, REBAKE));
        }
    }
    Ok(StoredSection { name, version, key: entry["key"].clone(), files: files.keys().cloned().collect() })
}

fn check_key(manifest_path: &Path, section: &str, key: &Value, scene: Option<&Scene>) -> Result<(), ArtifactError> {
    let kind = key["kind"].as_str().unwrap_or("");
    // A section read for a scene is keyed to it (its surfaces, a mesh, its environment): one
    // keyed to nothing would skip the check of what it was baked for.
    match (kind, scene) {
        ("none", None) => return Ok(()),
        ("none", Some(_)) => {
            return Err(fail(
                manifest_path,
                format!("section {section} is keyed to no scene, where it must be keyed to the scene it was baked for"),
                REBAKE,
            ))
        }
        _ => {}
    }
    let Some(scene) = scene else {
        return Err(fail(
            manifest_path,
            format!("section {section} is keyed to a scene, but none was given"),
            "read it with the scene it was baked for",
        ));
    };
    let recorded = key["checksum"].as_str().unwrap_or("(none)");
    match kind {
        "scene" => {
            let actual = scene_checksum(scene);
            if recorded != actual {
                let problem = format!(
                    "section {section} was baked for a scene with checksum {recorded}, but {} has checksum {actual}",
                    scene.source.display()
                );
                return Err(fail(manifest_path, problem, "bake this scene, or give the scene this bake was made for"));
            }
        }
        "mesh" => {
            let name = key["mesh"].as_str().unwrap_or("");
            let Some(mesh) = scene.meshes.iter().find(|m| m.name == name) else {
                let problem = format!("section {section} was baked for mesh \"{name}\", which {} lacks", scene.source.display());
                return Err(fail(manifest_path, problem, "give the scene with that mesh, or bake this one"));
            };
            let actual = mesh_checksum(mesh);
            if recorded != actual {
                let problem = format!(
                    "section {section} was baked for a mesh \"{name}\" with checksum {recorded}, but this scene's has checksum {actual}"
                );
                return Err(fail(manifest_path, problem, "bake this scene, or give the scene this bake was made for"));
            }
        }
        "environment" => {
            let Some(environment) = &scene.environment else {
                let problem = format!("section {section} was baked for an environment, which {} does not declare", scene.source.display());
                return Err(fail(manifest_path, problem, "give the scene this bake was made for"));
            };
            let actual = environment_checksum(environment);
            if recorded != actual {
                let problem = format!(
                    "section {section} was baked for an environment with checksum {recorded}, but {}'s has checksum {actual}",
                    scene.source.display()
                );
                return Err(fail(
                    manifest_path,
                    problem,
                    "bake again for this environment (its image, intensity, rotation or cube face changed; `relume bake --environment` bakes for another image)",
                ));
            }
        }
        other => return Err(fail(manifest_path, format!("section {section} has a key of unknown kind \"{other}\""), REBAKE)),
    }
    Ok(())
}
