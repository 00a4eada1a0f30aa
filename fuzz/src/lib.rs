//! What the fuzz targets share: a scratch folder per process (the readers under test take
//! paths, as relume does) and the shipped scenes the artifact's sections are keyed to.

use relume_bake::gltf_load;
use relume_bake::scene::Scene;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The repository's `scenes/` folder.
pub fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

/// An empty-at-start folder of this process, with the shipped scenes' buffers copied in, so
/// a fuzzed .gltf naming `cornell.bin` finds it.
pub fn scratch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("relume-fuzz-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch folder");
        for entry in std::fs::read_dir(scenes()).expect("scenes/").flatten() {
            if entry.path().extension().is_some_and(|e| e == "bin") {
                std::fs::copy(entry.path(), dir.join(entry.file_name())).expect("copy a scene buffer");
            }
        }
        dir
    })
}

/// Writes `bytes` as `name` in the scratch folder and returns its path.
pub fn scratch_file(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch().join(name);
    std::fs::write(&path, bytes).expect("scratch file");
    path
}

/// A shipped scene, loaded once.
pub fn scene(name: &str) -> Scene {
    gltf_load::load(&scenes().join(format!("{name}.gltf"))).expect("a shipped scene loads").scene
}
