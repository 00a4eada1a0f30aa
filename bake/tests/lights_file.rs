//! Lights files: written and read back the same, every malformed light refused by its item;
//! and where a scene's lights come from: its own, a lights file in their place, or, for a
//! scene with no light at all, the default rig (a headlight), said in a warning.

use glam::Vec3;
use relume_bake::gltf_load::{load_with_options, LightChoice, LoadOptions};
use relume_bake::lights_file;
use relume_bake::scene::{Light, LightKind};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("relume-lights-file-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn rig() -> Vec<Light> {
    vec![
        Light {
            name: "key".into(),
            kind: LightKind::Point,
            intensity: Vec3::new(10.0, 9.0, 8.0),
            range: None,
            position: Vec3::new(0.0, 2.0, 1.0),
            direction: Vec3::NEG_Z,
        },
        Light {
            name: "spot".into(),
            kind: LightKind::Spot { inner_cone: 0.25, outer_cone: 0.5 },
            intensity: Vec3::splat(40.0),
            range: None,
            position: Vec3::new(1.0, 3.0, 0.0),
            direction: Vec3::new(0.0, -1.0, 0.0),
        },
        Light {
            name: "sun".into(),
            kind: LightKind::Directional,
            intensity: Vec3::splat(3.0),
            range: None,
            position: Vec3::ZERO,
            direction: Vec3::new(0.6, -0.8, 0.0),
        },
    ]
}

fn same(a: &Light, b: &Light) -> bool {
    let kinds = match (a.kind, b.kind) {
        (LightKind::Spot { inner_cone: i, outer_cone: o }, LightKind::Spot { inner_cone: j, outer_cone: p }) => {
            (i - j).abs() < 1e-6 && (o - p).abs() < 1e-6
        }
        (x, y) => std::mem::discriminant(&x) == std::mem::discriminant(&y),
    };
    kinds && a.name == b.name && a.intensity == b.intensity && a.position == b.position && a.direction.distance(b.direction) < 1e-6
}

#[test]
fn a_lights_file_reads_back_as_written_and_bad_lights_are_refused_by_item() {
    let dir = temp_dir("round-trip");
    let path = dir.join("lights.json");
    std::fs::write(&path, lights_file::to_json(&rig())).unwrap();
    let read = lights_file::read(&path).unwrap();
    assert!(read.len() == 3 && read.iter().zip(&rig()).all(|(a, b)| same(a, b)), "{read:?}");

    let good: Value = serde_json::from_str(&lights_file::to_json(&rig())).unwrap();
    type Spoil = fn(&mut Value);
    let spoiled: [(&str, Spoil); 8] = [
        ("lights[0]: intensity", |f| f["lights"][0]["intensity"] = json!([1, -1, 1])),
        ("lights[1]: cones", |f| f["lights"][1]["outer_cone_degrees"] = json!(120)),
        ("lights[2]: \"direction\" must not be zero", |f| f["lights"][2]["direction"] = json!([0, 0, 0])),
        ("lights[0]: \"position\" must be three finite numbers", |f| f["lights"][0]["position"] = json!([0, "up", 1])),
        ("lights[1]: \"type\"", |f| f["lights"][1]["type"] = json!("area")),
        ("lights: is empty", |f| f["lights"] = json!([])),
        ("lights[0]: \"position\" [0, 1000000000000000000000000000000, 0] lies past 1e7 m", |f| {
            f["lights"][0]["position"] = json!([0, 1e30, 0])
        }),
        ("lights[0]: intensity [100000000000000000000000000000000000000, 1, 1] is negative or exceeds 1e9", |f| {
            f["lights"][0]["intensity"] = json!([1e38, 1, 1])
        }),
    ];
    for (words, spoil) in spoiled {
        let mut file = good.clone();
        spoil(&mut file);
        std::fs::write(&path, file.to_string()).unwrap();
        let error = lights_file::read(&path).unwrap_err().to_string();
        assert!(error.contains("lights.json") && error.contains(words) && error.contains("docs/FORMATS.md"), "{words}: {error}");
    }
    std::fs::write(&path, "{\"format\": \"relume-lights\", \"version\": 9, \"lights\": []}").unwrap();
    assert!(lights_file::read(&path).unwrap_err().to_string().contains("version 1"));
}

/// The shipped `occluder-plane` scene with its punctual light taken out, written into `dir`.
fn dark_scene(dir: &Path) -> PathBuf {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut json: Value = serde_json::from_slice(&std::fs::read(scenes.join("occluder-plane.gltf")).unwrap()).unwrap();
    json["nodes"].as_array_mut().unwrap().iter_mut().for_each(|n| _ = n.as_object_mut().unwrap().remove("extensions"));
    std::fs::copy(scenes.join("occluder-plane.bin"), dir.join("occluder-plane.bin")).unwrap();
    let path = dir.join("dark.gltf");
    std::fs::write(&path, json.to_string()).unwrap();
    path
}

#[test]
fn a_scene_without_light_gets_the_default_rig_or_the_given_lights() {
    let dir = temp_dir("choice");
    let path = dark_scene(&dir);
    let with = |lights| load_with_options(&path, &LoadOptions { lights, ..Default::default() });
    assert!(with(LightChoice::Scene).is_err(), "a dark scene is refused when the caller asks for its own lights");

    let loaded = with(LightChoice::SceneOrDefaultRig).unwrap();
    let (scene, warnings) = (loaded.scene, loaded.warnings);
    assert!(warnings.iter().any(|w| w.contains("default rig") && w.contains("--lights")), "{warnings:?}");
    let [headlight] = scene.lights.as_slice() else { panic!("{:?}", scene.lights) };
    let eye = scene.camera.world_from_camera.w_axis.truncate();
    assert_eq!((headlight.kind, headlight.position), (LightKind::Point, eye));
    // pi lux at the scene's centre from the light: I / d^2 = pi.
    let (min, max) = scene.bounds();
    let d = eye.distance((min + max) / 2.0).max((max - min).length() / 2.0);
    assert!((headlight.intensity.x / (d * d) - std::f32::consts::PI).abs() < 1e-4, "{headlight:?}");

    let given = rig();
    let scene = with(LightChoice::Given(&given)).unwrap().scene;
    assert!(scene.lights.iter().zip(&given).all(|(a, b)| same(a, b)) && scene.lights.len() == 3);
}
