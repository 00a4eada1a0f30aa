//! The scene loader on any bytes, as a .glb (binary, with embedded buffers and PNGs) when they
//! start with glTF's magic, else as a .gltf (JSON naming the shipped scenes' buffers): every
//! input loads or is refused with an error; none panics, hangs or exhausts memory.
#![no_main]

use libfuzzer_sys::fuzz_target;
use relume_bake::gltf_load;

fuzz_target!(|data: &[u8]| {
    let name = if data.starts_with(b"glTF") { "scene.glb" } else { "scene.gltf" };
    let path = relume_fuzz::scratch_file(name, data);
    let _ = gltf_load::load(&path);
});
