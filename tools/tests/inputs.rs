//! What enters and what leaves. No output over any input: every command refuses an output
//! path (or a companion file, such as the PNG beside an EXR) that is one of the files it reads
//! — the scene, its buffers and images, a bake's files, lights files, sweeps, scripts — by any
//! name (a symlink, `..`, a hard link), with exit code 1 and one error line, and the folder is
//! byte for byte as it was. A failed command replaces none of the outputs an earlier run left.
//! Values too large for the maths downstream are refused where they enter, the same way; a
//! downloaded model's quirks (a cloud that would lie inside closed geometry, an emissive
//! texture) do not fail `run` or light a scene wrongly.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("relume-inputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn relume(args: &[&str], dir: &Path) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_relume"));
    command.args(args).current_dir(dir);
    // The viewer's refusals come before any window: no display is needed, nor wanted.
    for variable in ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"] {
        command.env_remove(variable);
    }
    command.output().expect("run relume")
}

/// Every file under `dir`, by relative path, with its bytes.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut folders = vec![dir.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap().map(Result::unwrap) {
            let path = entry.path();
            match std::fs::symlink_metadata(&path).unwrap().is_dir() {
                true => folders.push(path),
                false => {
                    files.insert(path.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&path).unwrap_or_default());
                }
            }
        }
    }
    files
}

/// `args` run in `dir` is refused with exit code 1 and one `error:` line holding each of `words`,
/// and every file under `dir` is as it was (none added, none changed, no temporary left).
fn assert_refused_unchanged(dir: &Path, args: &[&str], words: &[&str]) {
    let before = snapshot(dir);
    let result = relume(args, dir);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{args:?}: {stderr}");
    // Progress and estimates aside (run prints its bakes'), one error line.
    let lines: Vec<_> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(lines.len(), 1, "{args:?}: one error line expected, got:\n{stderr}");
    for word in words {
        assert!(lines[0].contains(word), "{args:?}: \"{word}\" missing from: {stderr}");
    }
    let after = snapshot(dir);
    let changed: Vec<_> = after.iter().filter(|(path, bytes)| before.get(*path) != Some(bytes)).map(|(p, _)| p).collect();
    assert!(changed.is_empty() && before.len() == after.len(), "{args:?} changed {changed:?}");
}

/// A quad textured by `tex.png` and lit by a point light: scene.gltf, scene.bin, tex.png.
fn textured_scene(dir: &Path) {
    let mut png_bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png_bytes, 2, 2);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.write_header().unwrap().write_image_data(&[200, 40, 40, 40, 200, 40, 40, 40, 200, 200, 200, 40]).unwrap();
    }
    std::fs::write(dir.join("tex.png"), png_bytes).unwrap();
    let positions = [[-1.0f32, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]];
    let uvs = [[0.0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let mut bin: Vec<u8> = positions.iter().flatten().chain(uvs.iter().flatten()).flat_map(|v| v.to_le_bytes()).collect();
    bin.extend([0u32, 2, 1, 0, 3, 2].iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.join("scene.bin"), &bin).unwrap();
    let gltf = serde_json::json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": { "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": 10 }] } },
        "scene": 0, "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "translation": [0, 1, 0], "extensions": { "KHR_lights_punctual": { "light": 0 } } }],
        "meshes": [{ "name": "Floor", "primitives": [{ "attributes": { "POSITION": 0, "TEXCOORD_0": 1 }, "indices": 2, "material": 0 }] }],
        "materials": [{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }],
        "textures": [{ "source": 0 }],
        "images": [{ "uri": "tex.png" }],
        "buffers": [{ "uri": "scene.bin", "byteLength": bin.len() }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 32 },
            { "buffer": 0, "byteOffset": 80, "byteLength": 24 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 2, "componentType": 5125, "count": 6, "type": "SCALAR" }
        ]
    });
    std::fs::write(dir.join("scene.gltf"), serde_json::to_string_pretty(&gltf).unwrap()).unwrap();
}

const SMALL: [&str; 4] = ["--width", "8", "--height", "8"];

/// For each command, an output path chosen among the command's own inputs (the scene, its
/// buffer and texture, each file of a bake) is refused and changes nothing.
#[test]
fn every_command_refuses_each_of_its_inputs_as_an_output() {
    let dir = temp_dir("property");
    textured_scene(&dir);
    let scene_files = ["scene.gltf", "scene.bin", "tex.png"];
    let trace = [&SMALL[..], &["--spp", "1"]].concat();
    for input in scene_files {
        let refused = ["is the input", input, "elsewhere"];
        assert_refused_unchanged(&dir, &[&["reference", "scene.gltf", "--out", input][..], &trace].concat(), &refused);
        assert_refused_unchanged(&dir, &["lights", "scene.gltf", "--out", input], &refused);
        assert_refused_unchanged(&dir, &[&["render", "scene.gltf", "--out", input][..], &SMALL].concat(), &refused);
        let script = format!("screenshot {input}\n");
        std::fs::write(dir.join("script.txt"), script).unwrap();
        assert_refused_unchanged(&dir, &["view", "scene.gltf", "--script", "script.txt"], &refused);
        std::fs::write(dir.join("script.txt"), format!("save-lights {input}\n")).unwrap();
        assert_refused_unchanged(&dir, &["view", "scene.gltf", "--script", "script.txt"], &refused);
    }
    // The PNG beside the EXR is the scene's texture.
    let companion = ["tex.exr", "is the input", "tex.png"];
    assert_refused_unchanged(&dir, &[&["reference", "scene.gltf", "--out", "tex.exr"][..], &trace].concat(), &companion);
    assert_refused_unchanged(&dir, &[&["render", "scene.gltf", "--out", "tex.exr"][..], &SMALL].concat(), &companion);
    // The script writing over itself.
    std::fs::write(dir.join("script.txt"), "screenshot script.txt\n").unwrap();
    assert_refused_unchanged(&dir, &["view", "scene.gltf", "--script", "script.txt"], &["is the input", "script.txt"]);
    // A bake into the folder that holds the scene.
    assert_refused_unchanged(&dir, &["bake", "scene.gltf", "--method", "obscurance", "--out", "."], &["holds the input", "scene.gltf"]);

    let bake = relume(&["bake", "scene.gltf", "--method", "obscurance", "--rays", "4", "--out", "bk"], &dir);
    assert!(bake.status.success(), "{}", String::from_utf8_lossy(&bake.stderr));
    let bake_files: Vec<String> =
        std::fs::read_dir(dir.join("bk")).unwrap().map(|e| format!("bk/{}", e.unwrap().file_name().to_string_lossy())).collect();
    assert!(bake_files.len() >= 3, "{bake_files:?}");
    for file in bake_files.iter().filter(|f| !f.ends_with("stats.json")) {
        let refused = ["is the input", file.as_str()];
        assert_refused_unchanged(&dir, &[&["render", "scene.gltf", "--bake", "bk", "--out", file][..], &SMALL].concat(), &refused);
        std::fs::write(dir.join("script.txt"), format!("screenshot {file}\n")).unwrap();
        assert_refused_unchanged(&dir, &["view", "scene.gltf", "--bake", "bk", "--script", "script.txt"], &refused);
    }

    // compare's error image over either image, also through a symlink and a hard link.
    let reference = relume(&[&["reference", "scene.gltf", "--out", "a.exr"][..], &trace].concat(), &dir);
    assert!(reference.status.success(), "{}", String::from_utf8_lossy(&reference.stderr));
    std::os::unix::fs::symlink(dir.join("a.exr"), dir.join("soft.exr")).unwrap();
    std::fs::hard_link(dir.join("a.exr"), dir.join("hard.exr")).unwrap();
    for error_image in ["a.exr", "soft.exr", "hard.exr", "./bk/../a.exr"] {
        assert_refused_unchanged(&dir, &["compare", "a.exr", "a.exr", "--error-image", error_image], &["is the input", "a.exr"]);
    }
}

/// bench refuses, before any work, a sweep named as one of its results in its --out folder,
/// and run a lights file named as one of its outputs.
#[test]
fn bench_and_run_refuse_their_inputs_as_outputs_before_any_work() {
    let dir = temp_dir("bench-run");
    textured_scene(&dir);
    std::fs::create_dir(dir.join("d")).unwrap();
    let sweep = "name = 'x'\nwidth = 8\nheight = 8\nreference_spp = 1\nframes = 1\n[[scenes]]\npath = '../scene.gltf'\n[[methods]]\nmethod = 'direct'\n";
    for name in ["results.csv", "report.md"] {
        std::fs::write(dir.join("d").join(name), sweep).unwrap();
        assert_refused_unchanged(&dir, &["bench", &format!("d/{name}"), "--out", "d"], &["is the input", name]);
        std::fs::remove_file(dir.join("d").join(name)).unwrap();
    }
    std::fs::write(dir.join("d/sweep.toml"), sweep).unwrap();
    assert_refused_unchanged(&dir, &["bench", "d/sweep.toml", "--out", "d", "--overview", "scene.gltf"], &["is the input", "scene.gltf"]);
    let lights = relume(&["lights", "scene.gltf", "--out", "d/report.md"], &dir);
    assert!(lights.status.success(), "{}", String::from_utf8_lossy(&lights.stderr));
    let run = ["run", "scene.gltf", "--lights", "d/report.md", "--out", "d", "--spp", "1", "--width", "8", "--height", "8"];
    assert_refused_unchanged(&dir, &run, &["is the input", "report.md"]);
}

/// A reference that fails (its light so bright that samples would overflow: refused where it
/// enters) replaces none of the good outputs an earlier run left under the same --out, and
/// says which scene, which light and what to fix.
#[test]
fn a_failed_reference_leaves_the_earlier_outputs_as_they_were() {
    let dir = temp_dir("failed-reference");
    textured_scene(&dir);
    let trace = [&SMALL[..], &["--spp", "2"]].concat();
    let good = relume(&[&["reference", "scene.gltf", "--out", "r.exr"][..], &trace].concat(), &dir);
    assert!(good.status.success(), "{}", String::from_utf8_lossy(&good.stderr));
    let mut huge: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("scene.gltf")).unwrap()).unwrap();
    huge["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = serde_json::json!(3e38);
    huge["nodes"][1]["translation"] = serde_json::json!([0.0, 0.01, 0.0]);
    std::fs::write(dir.join("huge.gltf"), huge.to_string()).unwrap();
    let args = [&["reference", "huge.gltf", "--out", "r.exr"][..], &trace].concat();
    assert_refused_unchanged(&dir, &args, &["huge.gltf", "light 0", "exceeds 1e9", "at most 1e9"]);
}

/// `run` moves its bakes in with its images and report, or nothing: an output it cannot write
/// at the end (the reference's PNG path is a folder) leaves no bake folder behind.
#[test]
fn a_failed_run_leaves_no_bake_behind() {
    let dir = temp_dir("failed-run");
    textured_scene(&dir);
    std::fs::create_dir_all(dir.join("d/reference.png")).unwrap();
    let run = ["run", "scene.gltf", "--out", "d", "--spp", "1", "--rays", "1", "--frames", "1", "--width", "8", "--height", "8"];
    assert_refused_unchanged(&dir, &run, &["reference.png", "not a regular file"]);
    assert!(!dir.join("d/bake").exists(), "a bake folder was moved in");
}

/// The textured quad with `spoil` applied to its glTF JSON, written as `name`.gltf beside it.
fn spoiled_scene(dir: &Path, name: &str, spoil: impl FnOnce(&mut serde_json::Value)) -> String {
    let mut json: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("scene.gltf")).unwrap()).unwrap();
    spoil(&mut json);
    std::fs::write(dir.join(format!("{name}.gltf")), json.to_string()).unwrap();
    format!("{name}.gltf")
}

/// Huge finite values are refused where they enter (exit 1, one error line, nothing changed):
/// a Phong exponent of 1e30, an MRT grid cell of 1e30 m, an environment texel of 1e38, a
/// light map texel of 3e38 in a bake whose checksums match.
#[test]
fn huge_finite_values_are_refused_where_they_enter_by_every_command() {
    let dir = temp_dir("huge");
    textured_scene(&dir);
    let trace = [&SMALL[..], &["--spp", "1", "--out", "r.exr"]].concat();
    let phong = spoiled_scene(&dir, "phong", |j| {
        j["materials"][0]["extras"] = serde_json::json!({ "relume": { "phong": { "specular": 0.1, "exponent": 1e30 } } })
    });
    assert_refused_unchanged(&dir, &[&["reference", &phong][..], &trace].concat(), &["phong.gltf", "exponent", "past 1e6"]);
    let cell = serde_json::json!({ "relume": { "mrt": { "grid": { "cell": [1e30, 2.0, 2.0], "rows": ["."] } } } });
    let mrt = spoiled_scene(&dir, "mrt", move |j| j["scenes"][0]["extras"] = cell);
    assert_refused_unchanged(&dir, &[&["reference", &mrt][..], &trace].concat(), &["mrt.gltf", "within 1000000 m"]);

    let mut sky = relume_bake::image::Image::new(16, 8);
    sky.pixels.iter_mut().for_each(|p| *p = glam::Vec3::ONE);
    sky.set(3, 2, glam::Vec3::new(1e38, 1.0, 1.0));
    let mut outputs = relume_bake::outputs::Outputs::new();
    relume_bake::image::write_exr_layers(&mut outputs, &dir.join("sky.exr"), &[("rgb", &sky)]).unwrap();
    outputs.commit().unwrap();
    let args = [&["reference", "scene.gltf", "--environment", "sky.exr"][..], &trace].concat();
    assert_refused_unchanged(&dir, &args, &["sky.exr", "texel (3, 2)", "at most 1e9"]);

    let bake = relume(&["bake", "scene.gltf", "--method", "obscurance", "--rays", "1", "--out", "bk"], &dir);
    assert!(bake.status.success(), "{}", String::from_utf8_lossy(&bake.stderr));
    let path = dir.join("bk/obscurance.exr");
    let mut lightmap = relume_bake::image::read_exr_layer(&path, Some("W")).unwrap();
    lightmap.pixels[0].y = 3e38;
    let mut outputs = relume_bake::outputs::Outputs::new();
    relume_bake::image::write_exr_layers(&mut outputs, &path, &[("W", &lightmap)]).unwrap();
    outputs.commit().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let mut manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("bk/manifest.json")).unwrap()).unwrap();
    for section in manifest["sections"].as_array_mut().unwrap() {
        if let Some(file) = section["files"].get_mut("obscurance.exr") {
            *file = serde_json::json!({ "bytes": bytes.len(), "checksum": relume_bake::artifact::checksum(&bytes) });
        }
    }
    std::fs::write(dir.join("bk/manifest.json"), serde_json::to_string_pretty(&manifest).unwrap()).unwrap();
    let args = [&["render", "scene.gltf", "--bake", "bk", "--out", "r.exr"][..], &SMALL].concat();
    assert_refused_unchanged(&dir, &args, &["obscurance.exr", "texel 0", "0..=1e9"]);
}

/// A closed cube from -1 to 1, faces outward, lit by a point light 0.05 m off its +z face:
/// cube.gltf and cube.bin.
fn cube_scene(dir: &Path) {
    let faces: [([f32; 3], [f32; 3], [f32; 3]); 6] = [
        ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
        ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
        ([0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]),
    ];
    let (mut positions, mut indices) = (Vec::new(), Vec::new());
    for (k, (n, u, v)) in faces.iter().enumerate() {
        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            positions.extend((0..3).map(|c| n[c] + su * u[c] + sv * v[c]));
        }
        let b = 4 * k as u32;
        indices.extend([b, b + 1, b + 2, b, b + 2, b + 3]);
    }
    let mut bin: Vec<u8> = positions.iter().flat_map(|p: &f32| p.to_le_bytes()).collect();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.join("cube.bin"), &bin).unwrap();
    let gltf = serde_json::json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": { "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": 1 }] } },
        // 8 texels a metre: at the default 32, run's light path maps (32 clusters, 2 eigen-
        // textures) store more than one storage buffer holds, and it fails at render time.
        "scene": 0, "scenes": [{ "nodes": [0, 1], "extras": { "relume": { "texel_density": 8.0 } } }],
        "nodes": [{ "mesh": 0 }, { "translation": [0, 0, 1.05], "extensions": { "KHR_lights_punctual": { "light": 0 } } }],
        "meshes": [{ "name": "Cube", "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1 }] }],
        "buffers": [{ "uri": "cube.bin", "byteLength": bin.len() }],
        "bufferViews": [{ "buffer": 0, "byteOffset": 0, "byteLength": 288 }, { "buffer": 0, "byteOffset": 288, "byteLength": 144 }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 24, "type": "VEC3", "min": [-1, -1, -1], "max": [1, 1, 1] },
            { "bufferView": 1, "componentType": 5125, "count": 36, "type": "SCALAR" }
        ]
    });
    std::fs::write(dir.join("cube.gltf"), gltf.to_string()).unwrap();
}

/// A downloaded model's quirks: a light just outside a closed box derives a cloud whose every
/// light lies inside the box, so `run` skips light clouds, saying why in its report (it failed
/// after baking the others); a material with an emissive texture emits nothing, with a
/// warning, and the scene nothing else lights takes the headlight.
#[test]
fn run_skips_a_method_that_cannot_succeed_and_an_emissive_texture_does_not_light_the_scene() {
    let dir = temp_dir("downloaded");
    cube_scene(&dir);
    let run = ["run", "cube.gltf", "--out", "d", "--spp", "1", "--rays", "1", "--frames", "1", "--width", "8", "--height", "8"];
    let result = relume(&run, &dir);
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    let report = std::fs::read_to_string(dir.join("d/report.md")).unwrap();
    assert!(!dir.join("d/bake/light-cloud").exists() && report.contains("light-cloud"), "{report}");

    textured_scene(&dir);
    let glow = spoiled_scene(&dir, "glow", |j| {
        j["extensions"]["KHR_lights_punctual"]["lights"] = serde_json::json!([]);
        j["nodes"] = serde_json::json!([{ "mesh": 0 }]);
        j["scenes"][0]["nodes"] = serde_json::json!([0]);
        j["materials"][0]["emissiveFactor"] = serde_json::json!([1.0, 1.0, 1.0]);
        j["materials"][0]["emissiveTexture"] = serde_json::json!({ "index": 0 });
    });
    let result = relume(&[&["reference", &glow][..], &SMALL, &["--spp", "1", "--out", "g.exr"]].concat(), &dir);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    assert!(stderr.contains("emissiveTexture is not read") && stderr.contains("default rig"), "{stderr}");
}
