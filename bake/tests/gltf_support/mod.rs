//! What the glTF loader's tests share: the shipped scenes, fresh folders, scenes written with
//! one defect each, and their loads.
#![allow(dead_code)]

use relume_bake::gltf_load::{self, Loaded, SceneError};
use relume_bake::scene::Scene;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

/// A fresh folder under the system temp dir, removed when the test ends (pass or fail).
pub struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

pub fn temp_dir(tag: &str) -> TempDir {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("relume-gltf-load-{}-{tag}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

pub fn load_ok(path: &Path) -> Loaded {
    gltf_load::load(path).unwrap_or_else(|e| panic!("{e}"))
}

pub fn load_err(path: &Path) -> SceneError {
    match gltf_load::load(path) {
        Ok(_) => panic!("{} loaded but should have been refused", path.display()),
        Err(e) => {
            let line = e.to_string();
            assert!(!line.contains('\n'), "not one line: {line}");
            assert!(line.starts_with(&path.display().to_string()), "does not name the file: {line}");
            e
        }
    }
}

/// A generated scene's JSON and binary buffer.
pub fn read_scene(name: &str) -> (Value, Vec<u8>) {
    let dir = scenes_dir();
    let json: Value = serde_json::from_slice(&std::fs::read(dir.join(format!("{name}.gltf"))).unwrap()).unwrap();
    let bin = std::fs::read(dir.join(format!("{name}.bin"))).unwrap();
    (json, bin)
}

/// Writes `<dir>/<name>.gltf` and, if given, the `.bin` its buffer uri names.
pub fn write_scene(dir: &Path, name: &str, json: &Value, bin: Option<&[u8]>) -> PathBuf {
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_vec_pretty(json).unwrap()).unwrap();
    if let Some(bin) = bin {
        let uri = json["buffers"][0]["uri"].as_str().unwrap();
        std::fs::write(dir.join(uri), bin).unwrap();
    }
    path
}

/// The same scene as a .glb: the buffer's uri dropped, the bytes in the BIN chunk.
pub fn to_glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = json.clone();
    json["buffers"][0].as_object_mut().unwrap().remove("uri");
    let mut text = serde_json::to_vec(&json).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// Byte offset in the .bin of accessor `a`'s first element.
pub fn accessor_offset(json: &Value, a: usize) -> usize {
    let acc = &json["accessors"][a];
    let view = &json["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
    (view["byteOffset"].as_u64().unwrap_or(0) + acc["byteOffset"].as_u64().unwrap_or(0)) as usize
}

pub fn mesh<'a>(scene: &'a Scene, name: &str) -> &'a relume_bake::scene::Mesh {
    scene.meshes.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no mesh {name}"))
}

pub fn assert_same_scene(a: &Scene, b: &Scene) {
    assert_eq!(a.meshes.len(), b.meshes.len());
    for (ma, mb) in a.meshes.iter().zip(&b.meshes) {
        assert_eq!(ma.name, mb.name);
        assert_eq!(ma.positions, mb.positions);
        assert_eq!(ma.normals, mb.normals);
        assert_eq!(ma.indices, mb.indices);
        assert_eq!(ma.material, mb.material);
    }
    assert_eq!(a.materials.len(), b.materials.len());
    assert_eq!(a.lights.len(), b.lights.len());
    for (la, lb) in a.lights.iter().zip(&b.lights) {
        assert_eq!(
            (la.kind, la.intensity, la.position, la.direction, la.range),
            (lb.kind, lb.intensity, lb.position, lb.direction, lb.range)
        );
    }
    assert_eq!(a.camera.world_from_camera, b.camera.world_from_camera);
    assert_eq!((a.camera.yfov, a.camera.znear, a.camera.zfar), (b.camera.yfov, b.camera.znear, b.camera.zfar));
}

// --- the generated scenes -----------------------------------------------------------------
