//! The `relume` program refuses bad input with one clear line naming the file and the item,
//! a non-zero exit code, no panic, and no output file.

use std::path::{Path, PathBuf};
use std::process::Command;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("relume-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A one-triangle scene lit by a point light; `positions` and `indices` may be made invalid.
fn write_scene(dir: &Path, positions: [[f32; 3]; 3], indices: [u32; 3], with_light: bool) -> PathBuf {
    let mut bin = Vec::new();
    for p in positions.iter().flatten() {
        bin.extend_from_slice(&p.to_le_bytes());
    }
    for i in indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(dir.join("scene.bin"), &bin).expect("write bin");
    let light_ext = r#""extensionsUsed": ["KHR_lights_punctual"],
      "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10}]}},"#;
    let light_node = r#",{"translation": [0, 2, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}"#;
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, {ext}
      "scene": 0, "scenes": [{{"nodes": [0{light_ref}]}}],
      "nodes": [{{"mesh": 0}}{light_node}],
      "meshes": [{{"name": "Tri", "primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
      "buffers": [{{"uri": "scene.bin", "byteLength": 48}}],
      "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 12}}],
      "accessors": [
        {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}},
        {{"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}}]}}"#,
        ext = if with_light { light_ext } else { "" },
        light_ref = if with_light { ",1" } else { "" },
        light_node = if with_light { light_node } else { "" },
    );
    let path = dir.join("scene.gltf");
    std::fs::write(&path, json).expect("write gltf");
    path
}

const GOOD: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// Runs `relume reference` (the CPU path; no GPU needed) and checks the refusal.
fn assert_refused(scene: &Path, expected: &[&str]) {
    let out = scene.with_file_name("out.exr");
    let result = Command::new(env!("CARGO_BIN_EXE_relume"))
        .args(["reference", "--width", "8", "--height", "8", "--spp", "1", "--out"])
        .arg(&out)
        .arg(scene)
        .output()
        .expect("run relume");
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success(), "accepted {}: {stderr}", scene.display());
    assert_eq!(result.status.code(), Some(1), "a panic exits with 101: {stderr}");
    let lines: Vec<_> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "one error line expected, got:\n{stderr}");
    assert!(lines[0].starts_with("error: "), "{stderr}");
    for word in expected {
        assert!(lines[0].contains(word), "\"{word}\" missing from: {stderr}");
    }
    assert!(!out.exists(), "an output file was left behind");
    let leftovers: Vec<_> = std::fs::read_dir(scene.parent().unwrap())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("out."))
        .collect();
    assert!(leftovers.is_empty(), "temporary output left behind: {leftovers:?}");
}

#[test]
fn a_good_scene_is_accepted() {
    let dir = temp_dir("good");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    let out = dir.join("out.exr");
    let status = Command::new(env!("CARGO_BIN_EXE_relume"))
        .args(["reference", "--width", "8", "--height", "8", "--spp", "1", "--out"])
        .arg(&out)
        .arg(&scene)
        .status()
        .expect("run relume");
    assert!(status.success());
    assert!(out.exists());
}

#[test]
fn a_missing_file_is_refused() {
    let dir = temp_dir("missing");
    assert_refused(&dir.join("nowhere.gltf"), &["nowhere.gltf"]);
}

#[test]
fn a_missing_buffer_is_refused() {
    let dir = temp_dir("missing-bin");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    std::fs::remove_file(dir.join("scene.bin")).unwrap();
    assert_refused(&scene, &["scene.gltf", "scene.bin"]);
}

#[test]
fn a_truncated_buffer_is_refused() {
    let dir = temp_dir("truncated");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    let bin = std::fs::read(dir.join("scene.bin")).unwrap();
    std::fs::write(dir.join("scene.bin"), &bin[..20]).unwrap();
    assert_refused(&scene, &["scene.gltf", "scene.bin"]);
}

#[test]
fn nan_positions_are_refused() {
    let dir = temp_dir("nan");
    let scene = write_scene(&dir, [[0.0, f32::NAN, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [0, 1, 2], true);
    assert_refused(&scene, &["scene.gltf", "Tri"]);
}

#[test]
fn an_index_out_of_range_is_refused() {
    let dir = temp_dir("index");
    let scene = write_scene(&dir, GOOD, [0, 1, 7], true);
    assert_refused(&scene, &["scene.gltf", "Tri", "7"]);
}

/// A scene without any light renders with the default rig, saying so; with `--lights` it
/// renders exactly as with those lights in the glTF; a bad lights file is refused by item.
#[test]
fn a_scene_without_lights_takes_the_default_rig_or_a_lights_file() {
    let dir = temp_dir("dark");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], false);
    let scene = scene.to_str().unwrap();
    let reference = |extra: &[&str], out: &str| {
        let mut args = vec!["reference", scene, "--width", "8", "--height", "8", "--spp", "2", "--out", out];
        args.extend(extra);
        relume(&args, &dir)
    };
    let rigged = reference(&[], "rig.exr");
    assert!(rigged.status.success() && String::from_utf8_lossy(&rigged.stderr).contains("default rig"), "{rigged:?}");
    // `relume lights` writes the rig out; given back, it renders the same image, silently.
    assert!(relume(&["lights", scene, "--out", "rig.json"], &dir).status.success());
    let again = reference(&["--lights", "rig.json"], "rig-again.exr");
    assert!(again.status.success() && !String::from_utf8_lossy(&again.stderr).contains("default rig"), "{again:?}");
    assert_eq!(std::fs::read(dir.join("rig.exr")).unwrap(), std::fs::read(dir.join("rig-again.exr")).unwrap());
    // The glTF light of write_scene (a point light of 10 cd at (0, 2, 0)) as a lights file.
    let file =
        r#"{"format": "relume-lights", "version": 1, "lights": [{"type": "point", "position": [0, 2, 0], "intensity": [10, 10, 10]}]}"#;
    std::fs::write(dir.join("lights.json"), file).unwrap();
    let filed = reference(&["--lights", "lights.json"], "filed.exr");
    assert!(filed.status.success(), "{filed:?}");
    assert!(!String::from_utf8_lossy(&filed.stderr).contains("default rig"));
    let lit = write_scene(&dir, GOOD, [0, 1, 2], true);
    let own = relume(&["reference", lit.to_str().unwrap(), "--width", "8", "--height", "8", "--spp", "2", "--out", "own.exr"], &dir);
    assert!(own.status.success());
    assert_eq!(std::fs::read(dir.join("filed.exr")).unwrap(), std::fs::read(dir.join("own.exr")).unwrap());
    std::fs::write(dir.join("bad.json"), file.replace("point", "torch")).unwrap();
    assert_one_error(&reference(&["--lights", "bad.json"], "bad.exr"), &["bad.json", "lights[0]", "\"type\""]);
}

/// A bake whose manifest names a method relume lacks is refused naming the manifest.
#[test]
fn a_bake_of_an_unknown_method_is_refused_by_its_manifest() {
    let dir = temp_dir("unknown-method");
    let cornell = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell.gltf");
    let cornell = cornell.to_str().unwrap();
    let bake = relume(&["bake", cornell, "--method", "obscurance", "--patches", "500", "--rays", "4", "--out", "bake"], &dir);
    assert!(bake.status.success(), "{}", String::from_utf8_lossy(&bake.stderr));
    let manifest = std::fs::read_to_string(dir.join("bake/manifest.json")).unwrap();
    std::fs::write(dir.join("bake/manifest.json"), manifest.replace("\"method\": \"obscurance\"", "\"method\": \"nonsense\"")).unwrap();
    let render = relume(&["render", cornell, "--bake", "bake", "--out", "r.exr"], &dir);
    assert_one_error(&render, &["manifest.json", "nonsense", "relume bake"]);
    assert!(!dir.join("r.exr").exists());
}

/// A value outside its flag's range is a usage error like one that is not a number: exit 2,
/// the flag named, before any work (`--threads 10000` once ran for minutes).
#[test]
fn impossible_parameters_are_refused() {
    let dir = temp_dir("params");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    let scene = scene.to_str().unwrap();
    for args in [
        ["reference", "--spp", "0"],
        ["reference", "--time-limit", "0"],
        ["reference", "--threads", "0"],
        ["reference", "--threads", "10000"],
        ["reference", "--width", "0"],
        ["reference", "--exposure", "nan"],
        ["render", "--frames", "0"],
        ["render", "--beta", "1"],
        ["bench", "--budget", "0"],
        ["bake", "--ray-backend", "optix"],
    ] {
        let result = relume(&[args[0], scene, args[1], args[2]], &dir);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(args[1]) && stderr.contains(args[2]), "{args:?}: {stderr}");
    }
}

/// A build without Embree refuses `--ray-backend embree` as a usage error that says how to get
/// it, before any work.
#[cfg(not(feature = "embree"))]
#[test]
fn the_embree_backend_is_refused_by_a_build_without_it() {
    let dir = temp_dir("embree");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    for command in ["reference", "bake", "rays"] {
        let result = relume(&[command, scene.to_str().unwrap(), "--ray-backend", "embree"], &dir);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{command}: {stderr}");
        assert!(stderr.contains("--ray-backend") && stderr.contains("--features embree"), "{command}: {stderr}");
    }
}

#[test]
fn comparing_images_of_different_sizes_is_refused() {
    let dir = temp_dir("compare");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    for (size, name) in [("8", "a.exr"), ("4", "b.exr")] {
        let status = Command::new(env!("CARGO_BIN_EXE_relume"))
            .args(["reference", "--width", size, "--height", size, "--spp", "1", "--out"])
            .arg(dir.join(name))
            .arg(&scene)
            .status()
            .unwrap();
        assert!(status.success());
    }
    let result = Command::new(env!("CARGO_BIN_EXE_relume")).arg("compare").arg(dir.join("a.exr")).arg(dir.join("b.exr")).output().unwrap();
    assert_eq!(result.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&result.stderr).contains("8x8"));
}

fn relume(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_relume")).args(args).current_dir(dir).output().expect("run relume")
}

/// `render --bake` with a light-path-maps bake runs the run-time passes (validation on) and
/// takes `--composition`; a composition without such a bake, or an unknown one, is refused.
#[test]
fn render_takes_a_light_path_maps_bake_and_its_composition() {
    let dir = temp_dir("light-path-maps");
    let cornell = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell.gltf");
    let cornell = cornell.to_str().unwrap();
    let bake = relume(
        &[
            "bake",
            cornell,
            "--method",
            "light-path-maps",
            "--entry-points",
            "256",
            "--clusters",
            "4",
            "--basis",
            "1",
            "--patches",
            "500",
            "--rays",
            "16",
            "--out",
            "light-path-maps",
        ],
        &dir,
    );
    assert!(bake.status.success(), "{}", String::from_utf8_lossy(&bake.stderr));
    let small = ["--width", "32", "--height", "32", "--shadow-map-size", "64"];
    let render = relume(
        &[
            &["render", cornell, "--bake", "light-path-maps", "--validation", "--composition", "plain", "--out", "light-path-maps.exr"][..],
            &small,
        ]
        .concat(),
        &dir,
    );
    let stdout = String::from_utf8_lossy(&render.stdout);
    assert!(render.status.success(), "{}", String::from_utf8_lossy(&render.stderr));
    assert!(dir.join("light-path-maps.exr").exists() && dir.join("light-path-maps.png").exists());
    if stdout.contains("GPU time") {
        for pass in ["light_path_maps.entry_irradiance", "light_path_maps.cluster_sums", "light_path_maps.reconstruct"] {
            assert!(stdout.contains(pass), "no {pass} timing in:\n{stdout}");
        }
    }
    // A value the flag's parser refuses is a usage error (exit code 2, clap's); the rest are 1.
    for (args, expected, code) in [
        (vec!["render", cornell, "--composition", "plain", "--out", "none.exr"], "light-path-maps", 1),
        (vec!["render", cornell, "--bake", "light-path-maps", "--composition", "sideways", "--out", "none.exr"], "times-obscurance", 2),
    ] {
        let result = relume(&[&args[..], &small].concat(), &dir);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(code), "{args:?}: {stderr}");
        assert!(stderr.contains("--composition") && stderr.contains(expected), "{args:?}: {stderr}");
        assert!(!dir.join("none.exr").exists(), "{args:?} left an output");
    }
}

/// Runs `relume reference` on `scene` at 8 x 8, 1 spp, into `out`.
fn reference_into(scene: &Path, out: &Path) -> std::process::Output {
    let args = ["reference", "--width", "8", "--height", "8", "--spp", "1", "--out"];
    Command::new(env!("CARGO_BIN_EXE_relume")).args(args).arg(out).arg(scene).output().expect("run relume")
}

/// Exit code 1 and one error line (warnings aside) holding every one of `words`.
fn assert_one_error(result: &std::process::Output, words: &[&str]) {
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    let lines: Vec<_> = stderr.lines().filter(|l| !l.trim().is_empty() && !l.starts_with("warning:")).collect();
    assert_eq!(lines.len(), 1, "one error line expected, got:\n{stderr}");
    for word in words {
        assert!(lines[0].contains(word), "\"{word}\" missing from: {stderr}");
    }
}

#[test]
fn outputs_never_replace_inputs_devices_or_a_users_folder() {
    let dir = temp_dir("outputs");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    let scene_bytes = std::fs::read(&scene).unwrap();
    // The scene itself as the output, also by another spelling of its path.
    assert_one_error(&reference_into(&scene, &scene), &["is the input", "scene.gltf"]);
    assert_one_error(&reference_into(&scene, &dir.join("../").join(dir.file_name().unwrap()).join("scene.gltf")), &["is the input"]);
    assert_eq!(std::fs::read(&scene).unwrap(), scene_bytes);
    // A device (run as root, /dev/null was replaced by a regular file).
    assert_one_error(&reference_into(&scene, Path::new("/dev/null")), &["/dev/null", "not a regular file"]);
    assert!(!std::fs::metadata("/dev/null").unwrap().is_file(), "/dev/null is no longer a device");
    // compare's error image over one of its inputs.
    assert!(reference_into(&scene, &dir.join("a.exr")).status.success());
    let a_bytes = std::fs::read(dir.join("a.exr")).unwrap();
    let compare = |image: &str, reference: &str, error_image: &str| {
        let args = ["compare", image, reference, "--error-image", error_image];
        Command::new(env!("CARGO_BIN_EXE_relume")).args(args).current_dir(&dir).output().unwrap()
    };
    assert_one_error(&compare("a.exr", "a.exr", "a.exr"), &["a.exr", "is the input"]);
    assert_eq!(std::fs::read(dir.join("a.exr")).unwrap(), a_bytes);
    // A bake into a folder holding a user's file is refused before any work.
    let mine = dir.join("bake-out");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "mine").unwrap();
    let cornell = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell.gltf");
    let bake = Command::new(env!("CARGO_BIN_EXE_relume"))
        .args(["bake", "--method", "obscurance", "--out"])
        .arg(&mine)
        .arg(&cornell)
        .output()
        .unwrap();
    assert_one_error(&bake, &["bake-out", "no relume manifest.json", "empty or new"]);
    assert_eq!(std::fs::read_dir(&mine).unwrap().count(), 1);
    assert_eq!(std::fs::read_to_string(mine.join("notes.txt")).unwrap(), "mine");
}

/// A command writes all its outputs or none: the reference's PNG path taken by a folder
/// refuses the run, and the EXR (written first) is neither made nor, if there was one,
/// changed; no temporary is left.
#[test]
fn a_command_writes_all_its_outputs_or_none() {
    let dir = temp_dir("all-or-none");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    std::fs::create_dir(dir.join("r.png")).unwrap();
    assert_one_error(&reference_into(&scene, &dir.join("r.exr")), &["r.png", "not a regular file"]);
    assert!(!dir.join("r.exr").exists(), "the EXR was written without its PNG");
    std::fs::write(dir.join("r.exr"), "an earlier image").unwrap();
    assert_one_error(&reference_into(&scene, &dir.join("r.exr")), &["r.png", "not a regular file"]);
    assert_eq!(std::fs::read_to_string(dir.join("r.exr")).unwrap(), "an earlier image");
    let hidden = std::fs::read_dir(&dir).unwrap().filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().starts_with('.')).count();
    assert_eq!(hidden, 0, "a temporary is left");
}

#[test]
fn compare_refuses_a_black_or_non_finite_reference() {
    use relume_bake::image::{write_exr_layers, Image};
    use relume_bake::outputs::Outputs;
    let dir = temp_dir("compare-reference");
    let mut image = Image::new(4, 4);
    image.pixels.iter_mut().for_each(|p| *p = glam::Vec3::splat(0.5));
    let mut nan = image.clone();
    nan.pixels[3] = glam::Vec3::new(f32::NAN, 0.0, 0.0);
    let mut outputs = Outputs::new();
    for (name, picture) in [("image.exr", &image), ("black.exr", &Image::new(4, 4)), ("nan.exr", &nan)] {
        write_exr_layers(&mut outputs, &dir.join(name), &[("combined", picture)]).unwrap();
    }
    outputs.commit().unwrap();
    let compare = |reference: &str| relume(&["compare", "image.exr", reference], &dir);
    assert_one_error(&compare("black.exr"), &["black.exr", "black everywhere"]);
    assert_one_error(&compare("nan.exr"), &["nan.exr", "1 pixel(s)", "NaN"]);
    assert!(compare("image.exr").status.success());
}

#[test]
fn a_fifo_or_a_device_as_an_input_is_refused_without_blocking() {
    let dir = temp_dir("fifo");
    let fifo = dir.join("pipe.gltf");
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo").success());
    assert_refused(&fifo, &["pipe.gltf", "not a regular file"]);
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    // The viewer's script too: refused before any window opens, not read until killed.
    let view = relume(&["view", scene.to_str().unwrap(), "--script", fifo.to_str().unwrap()], &dir);
    assert_one_error(&view, &["pipe.gltf", "not a regular file"]);
    let endless = std::fs::read_to_string(&scene).unwrap().replace("\"uri\": \"scene.bin\"", "\"uri\": \"/dev/zero\"");
    std::fs::write(&scene, endless).unwrap();
    // Outside the scene's folder: refused as such, and, allowed, as no regular file.
    assert_refused(&scene, &["scene.gltf", "/dev/zero", "outside the scene's folder", "--allow-outside-files"]);
    let scene = scene.to_str().unwrap();
    let allowed =
        relume(&["reference", scene, "--width", "8", "--height", "8", "--spp", "1", "--allow-outside-files", "--out", "x.exr"], &dir);
    assert_one_error(&allowed, &["scene.gltf", "/dev/zero", "not a regular file"]);
}

/// A value its flag cannot read is a usage error, exit code 2, whichever flag: a number, a
/// choice, a method's name, a camera.
#[test]
fn every_value_that_cannot_be_read_exits_with_2() {
    let dir = temp_dir("usage");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    let scene = scene.to_str().unwrap();
    for args in [
        vec!["reference", scene, "--spp", "abc"],
        vec!["bake", scene, "--method", "foo"],
        vec!["bake", scene, "--method", "direct"],
        vec!["methods", "foo"],
        vec!["reference", scene, "--camera", "eye=1"],
        vec!["bake", scene, "--method", "fiv", "--grid", "7x7"],
        // Ranges the bake's own check gave and the help did not (issue 35): one source now.
        vec!["bake", scene, "--method", "obscurance", "--discontinuity-angle", "90"],
        vec!["bake", scene, "--method", "fiv", "--difmap-width", "9"],
        // More seconds than a clock counts panicked (exit 101) converting to a Duration.
        vec!["bake", scene, "--method", "obscurance", "--time-limit", "1e20"],
        vec!["reference", scene, "--time-limit", "1e20"],
        vec!["run", scene, "--time-limit", "1e20"],
    ] {
        let result = relume(&args, &dir);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(args[args.len() - 1]), "{args:?}: {stderr}");
    }
}

/// Values past what the maths downstream keeps finite are refused where they enter: a lights
/// file's intensity of 1e38 (exit 1, naming the file and the light), `--ambient 1e38` (a
/// usage error); and a bake whose manifest names a method that makes no bake.
#[test]
fn huge_values_and_a_bakeless_method_in_a_manifest_are_refused() {
    let dir = temp_dir("huge");
    let scene = write_scene(&dir, GOOD, [0, 1, 2], true);
    let scene = scene.to_str().unwrap();
    let lights =
        r#"{"format": "relume-lights", "version": 1, "lights": [{"type": "point", "position": [0, 1, 0], "intensity": [1e38, 1, 1]}]}"#;
    std::fs::write(dir.join("lights.json"), lights).unwrap();
    let result =
        relume(&["reference", scene, "--lights", "lights.json", "--spp", "1", "--width", "8", "--height", "8", "--out", "r.exr"], &dir);
    assert_one_error(&result, &["lights.json", "lights[0]", "exceeds 1e9"]);
    let result = relume(&["render", scene, "--ambient", "1e38", "--out", "r.exr"], &dir);
    assert_eq!(result.status.code(), Some(2), "{}", String::from_utf8_lossy(&result.stderr));
    assert!(String::from_utf8_lossy(&result.stderr).contains("0..=1e9"));
    assert!(!dir.join("r.exr").exists());

    let bake = relume(&["bake", scene, "--method", "obscurance", "--rays", "1", "--out", "bk"], &dir);
    assert!(bake.status.success(), "{}", String::from_utf8_lossy(&bake.stderr));
    let manifest = std::fs::read_to_string(dir.join("bk/manifest.json")).unwrap();
    std::fs::write(dir.join("bk/manifest.json"), manifest.replace("\"method\": \"obscurance\"", "\"method\": \"direct\"")).unwrap();
    let result = relume(&["render", scene, "--bake", "bk", "--out", "r.exr"], &dir);
    assert_one_error(&result, &["manifest.json", "names direct", "makes no bake"]);
}

/// The light cloud bakes a spot-lit, flat-shaded scene with what it derives named in warning
/// lines and in the manifest (emission bands for the spot, a tessellation for the flat
/// meshes); a bake without directions refuses a directional light at render time by its
/// name, naming the flag; a sun's bake derives its directions and no grid of points; and,
/// told not to tessellate, bakes a flat-shaded scene with a warning that its vertices have
/// nothing to interpolate.
#[test]
fn light_cloud_derives_bands_a_tessellation_and_directions() {
    let dir = temp_dir("light-cloud");
    let cornell = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell.gltf");
    let bake = |extra: &[&str]| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_relume"));
        command.args(["bake", "--method", "light-cloud", "--samples", "1", "--uncompressed"]).args(extra).arg("--out").arg(dir.join("lc"));
        command.arg(&cornell).output().unwrap()
    };
    let baked = bake(&[]);
    let out = String::from_utf8_lossy(&baked.stdout).to_string() + &String::from_utf8_lossy(&baked.stderr);
    assert!(baked.status.success(), "{out}");
    assert!(out.contains("warning: derived emission_bands: 2") && out.contains("--emission-bands sets it instead"), "{out}");
    assert!(out.contains("warning: derived max_edge") && out.contains("--max-edge sets it instead"), "{out}");
    let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("lc/manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["parameters"]["derived"]["emission_bands"], 2, "{manifest}");
    assert!(manifest["parameters"]["derived"]["max_edge"].as_f64().is_some_and(|e| e > 0.0), "{manifest}");
    let sun = r#"{ "format": "relume-lights", "version": 1, "lights": [{ "type": "directional", "name": "Sun", "direction": [0, -1, 0], "intensity": [1, 1, 1] }] }"#;
    std::fs::write(dir.join("sun.json"), sun).unwrap();
    let sun = dir.join("sun.json");
    let sun = sun.to_str().unwrap();
    // The bake without directions refuses the sun at render time, naming the fix.
    let render = Command::new(env!("CARGO_BIN_EXE_relume"))
        .args(["render", cornell.to_str().unwrap(), "--bake"])
        .arg(dir.join("lc"))
        .args(["--lights", sun, "--width", "16", "--height", "16", "--out"])
        .arg(dir.join("sun.exr"))
        .output()
        .unwrap();
    assert_one_error(&render, &["Sun", "directional light", "no cloud of directions", "--directions"]);
    let baked = bake(&["--lights", sun]);
    let out = String::from_utf8_lossy(&baked.stdout).to_string() + &String::from_utf8_lossy(&baked.stderr);
    assert!(baked.status.success(), "{out}");
    assert!(out.contains("warning: derived directions: 128") && out.contains("0 cloud lights (0 grid points"), "{out}");
    let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("lc/manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["parameters"]["derived"]["directions"], 128, "{manifest}");
    assert!(manifest["parameters"]["grid"].is_null(), "a sun alone needs no grid of points: {manifest}");
    let lights = r#"{ "format": "relume-lights", "version": 1, "lights": [{ "type": "point", "position": [0, 0.4, -0.28], "intensity": [0.5, 0.5, 0.5] }] }"#;
    std::fs::write(dir.join("point.json"), lights).unwrap();
    let baked = bake(&["--lights", dir.join("point.json").to_str().unwrap(), "--max-edge", "0"]);
    let out = String::from_utf8_lossy(&baked.stdout).to_string() + &String::from_utf8_lossy(&baked.stderr);
    assert!(baked.status.success(), "{out}");
    assert!(out.contains("warning: 90 of 90 vertices belong to one triangle only"), "{out}");
}

/// An mrt bake reuses the dictionary of an earlier one (`--dictionary`), byte for byte, and
/// refuses one made with other parameters, naming the file, the parameter and the fix; without
/// `--dictionary` it reads the one kept for its parameters (`--dictionary-cache`), and makes
/// again one that no longer reads.
#[test]
fn an_mrt_bake_reuses_a_dictionary_and_refuses_one_of_other_parameters() {
    let dir = temp_dir("mrt-dictionary");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let small = [
        "--samples-per-face",
        "4",
        "--gather-rays",
        "64",
        "--modes",
        "4",
        "--prior-modes",
        "8",
        "--lightfield",
        "2",
        "--lightfield-modes",
        "4",
        "--response-modes",
        "4",
    ];
    let bake = |scene: &str, out: &str, extra: &[&str]| {
        let scene = scenes.join(format!("{scene}.gltf"));
        let args = [&["bake", scene.to_str().unwrap(), "--method", "mrt", "--out", out][..], &small[..], extra].concat();
        relume(&args, &dir)
    };
    assert!(bake("mrt-cube", "cube", &[]).status.success());
    let reused = bake("mrt-corridor", "corridor", &["--dictionary", "cube"]);
    assert!(reused.status.success(), "{}", String::from_utf8_lossy(&reused.stderr));
    assert!(!String::from_utf8_lossy(&reused.stderr).contains("mrt:   block shape"), "the dictionary is read, not made");
    let bytes = |bake: &str| std::fs::read(dir.join(bake).join("mrt-dictionary.bin")).unwrap();
    assert!(bytes("cube") == bytes("corridor"));
    let refused = bake("mrt-corridor", "other", &["--dictionary", "cube", "--no-enrich"]);
    assert_eq!(refused.status.code(), Some(1));
    let error = String::from_utf8_lossy(&refused.stderr);
    assert!(
        error.contains("mrt-dictionary.bin") && error.contains("enrich 1, not the 0") && error.contains("bake without --dictionary"),
        "{error}"
    );
    assert!(!dir.join("other").exists(), "nothing written");
    // The first bake kept its dictionary under the working folder's out/mrt-dictionary.
    let kept = bake("mrt-corridor", "kept", &[]);
    let said = String::from_utf8_lossy(&kept.stderr).to_string();
    let folder =
        format!("the dictionary made with these parameters, from out/mrt-dictionary/v{}-", relume_bake::mrt::dictionary::SECTION_VERSION);
    assert!(kept.status.success() && said.contains(&folder), "{said}");
    assert!(!said.contains("mrt:   block shape") && bytes("kept") == bytes("cube"), "{said}");
    // Other parameters: another entry, made and kept beside it.
    let other = bake("mrt-cube", "other-kept", &["--no-enrich"]);
    assert!(String::from_utf8_lossy(&other.stderr).contains("mrt:   block shape"));
    let cache = dir.join("out/mrt-dictionary");
    let entries: Vec<std::path::PathBuf> = std::fs::read_dir(&cache).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(entries.len(), 2, "one kept dictionary per parameter set: {entries:?}");
    // A kept dictionary cut short is made again, with a warning naming the file.
    let kept_bytes = |folder: &Path| std::fs::read(folder.join("mrt-dictionary.bin")).unwrap_or_default();
    let entry = entries.iter().find(|e| kept_bytes(e) == bytes("cube")).expect("the cube's dictionary is kept");
    let bin = entry.join("mrt-dictionary.bin");
    let length = std::fs::metadata(&bin).unwrap().len();
    std::fs::OpenOptions::new().write(true).open(&bin).unwrap().set_len(length / 2).unwrap();
    let remade = bake("mrt-cube", "remade", &[]);
    let said = String::from_utf8_lossy(&remade.stderr).to_string();
    assert!(
        remade.status.success() && said.contains("warning: mrt: the kept dictionary does not read") && said.contains("mrt-dictionary.bin"),
        "{said}"
    );
    assert!(said.contains("mrt:   block shape") && bytes("remade") == bytes("cube") && kept_bytes(entry) == bytes("cube"), "{said}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bake --recommended` bakes what a bench's budget chose for the scene (its method, its bake
/// parameters; a flag beside it overrides one), and refuses, naming the file, a scene the file
/// lacks and a chosen method that has no bake; `run --recommended` refuses a scene the file
/// lacks the same way, and --ambient beside it.
#[test]
fn bake_takes_the_method_and_parameters_a_budget_recommended() {
    let dir = temp_dir("recommended");
    let cornell = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell.gltf");
    let cornell = cornell.to_str().unwrap();
    let recommended = r#"
[cornell]
method = "obscurance"

[cornell.obscurance]
params = { rays = 4, patches = 500, ambient = 0.5 }

[cornell.constant]
params = { ambient = 0.5 }

[classroom]
method = "constant"
"#;
    std::fs::write(dir.join("recommended.toml"), recommended).unwrap();
    let bake = relume(&["bake", cornell, "--recommended", "recommended.toml", "--out", "chosen"], &dir);
    assert!(bake.status.success(), "{}", String::from_utf8_lossy(&bake.stderr));
    let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("chosen/manifest.json")).unwrap()).unwrap();
    assert_eq!(
        (manifest["method"].as_str(), manifest["parameters"]["rays_per_texel"].as_u64()),
        (Some("obscurance"), Some(4)),
        "{manifest}"
    );
    let bake = relume(&["bake", cornell, "--recommended", "recommended.toml", "--rays", "8", "--out", "given"], &dir);
    assert!(bake.status.success(), "{}", String::from_utf8_lossy(&bake.stderr));
    let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("given/manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["parameters"]["rays_per_texel"].as_u64(), Some(8), "the flag overrides the file: {manifest}");
    let classroom = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/classroom.gltf");
    let refused = relume(&["bake", classroom.to_str().unwrap(), "--recommended", "recommended.toml", "--out", "x"], &dir);
    assert_one_error(&refused, &["recommended.toml", "scene \"classroom\"", "constant", "needs no bake"]);
    let maze = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/maze.gltf");
    let refused = relume(&["bake", maze.to_str().unwrap(), "--recommended", "recommended.toml", "--out", "x"], &dir);
    assert_one_error(&refused, &["recommended.toml", "no scene \"maze\"", "--budget"]);
    // `run --recommended` refuses the same way, before any work, and takes no --ambient beside it.
    let refused = relume(&["run", maze.to_str().unwrap(), "--recommended", "recommended.toml", "--out", "x"], &dir);
    assert_one_error(&refused, &["recommended.toml", "no scene \"maze\"", "--budget"]);
    let refused = relume(&["run", cornell, "--recommended", "recommended.toml", "--ambient", "1", "--out", "x"], &dir);
    assert!(String::from_utf8_lossy(&refused.stderr).contains("cannot be used with"), "{}", String::from_utf8_lossy(&refused.stderr));
    assert!(!dir.join("x").exists());
}
