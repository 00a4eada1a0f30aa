//! The image readers: the first byte picks the EXR reader (the rest is the file, as `compare`
//! and environment lighting read it) or a PNG texture (the rest is a PNG that a one-triangle
//! scene's material names, read through the scene loader, limits included).
#![no_main]

use libfuzzer_sys::fuzz_target;
use relume_bake::{gltf_load, image};

/// A one-triangle scene lit by a point light, whose base colour is `texture.png`.
const TEXTURED: &str = r#"{"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual"],
 "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10}]}},
 "scene": 0, "scenes": [{"nodes": [0, 1]}],
 "nodes": [{"mesh": 0}, {"translation": [0, 2, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
 "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
 "textures": [{"source": 0}], "images": [{"uri": "texture.png"}],
 "buffers": [{"uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/", "byteLength": 60}],
 "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
               {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}]}"#;

fuzz_target!(|data: &[u8]| {
    let Some((&which, file)) = data.split_first() else { return };
    match which % 2 {
        0 => {
            let _ = image::read_exr_layers(&relume_fuzz::scratch_file("image.exr", file));
        }
        _ => {
            relume_fuzz::scratch_file("texture.png", file);
            let _ = gltf_load::load(&relume_fuzz::scratch_file("textured.gltf", TEXTURED.as_bytes()));
        }
    }
});
