//! The bake artifact round-trips, every way it can be wrong is refused with the file named,
//! and its sections are checked against what they are keyed to: the scene, one mesh of it
//! (refused for another mesh), or nothing (read without any scene).
#![cfg(feature = "baking")]

use glam::Vec3;
use relume_bake::artifact::{Artifact, BakeOutput, Key, Section};
use relume_bake::atlas::{Atlas, AtlasSection, AtlasSettings};
use relume_bake::obscurance;
use relume_bake::scene::Scene;
use relume_bake::testing::{closed_box, look_at, material, point_light, scene, Facing};
use serde_json::json;
use std::path::{Path, PathBuf};

fn test_scene(size: f32) -> Scene {
    let camera = look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, 1.0);
    let room = closed_box(Vec3::ZERO, Vec3::splat(size), 2, Facing::Inward, 0);
    let mut room = scene(
        "artifact test",
        vec![room],
        vec![material("grey", Vec3::splat(0.5), Vec3::ZERO)],
        vec![point_light(Vec3::ONE, Vec3::ONE)],
        camera,
    );
    room.meshes[0].name = "room".into();
    room
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("relume-artifact-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// An obscurance bake of `scene` (values made up), written into `dir`.
fn write(scene: &Scene, dir: &Path) -> Atlas {
    let atlas = Atlas::build(scene, &AtlasSettings { texel_density: 6.0, ..Default::default() }).unwrap();
    let values: Vec<Vec3> = atlas.texels.iter().map(|t| t.centre * 0.1 + Vec3::splat(t.coverage)).collect();
    let sections = vec![
        atlas.to_section().section(json!({ "charts": atlas.charts.len() })),
        obscurance::section(&values, atlas.layout(), json!({ "tau": 0.1 })).unwrap(),
    ];
    let output = BakeOutput {
        method: "obscurance",
        scene: Some(scene),
        parameters: json!({ "tau": 0.1 }),
        sections,
        stats: json!({ "seconds": 0.0 }),
    };
    output.write(dir).unwrap();
    atlas
}

#[test]
fn an_artifact_reads_back_as_written_and_applies_uv1() {
    let scene = test_scene(2.0);
    let dir = temp_dir("roundtrip");
    let atlas = write(&scene, &dir);
    let artifact = Artifact::read(&dir).unwrap();
    let read = AtlasSection::read(&artifact, &scene).unwrap();
    assert_eq!(read, atlas.to_section());
    assert_eq!(read.layout.texel_count(), atlas.texels.len());
    assert_eq!(artifact.method(), "obscurance");
    let values = obscurance::read(&artifact, &scene, read.layout).unwrap();
    assert_eq!(values.len(), atlas.texels.len());
    let mut applied = scene.clone();
    read.apply_to(&mut applied);
    assert_eq!(applied.meshes[0].uv1.as_ref(), Some(&atlas.meshes[0].uv1));
    assert_eq!(applied.triangle_count(), scene.triangle_count());
    let manifest = std::fs::read(dir.join("manifest.json")).unwrap();
    write(&scene, &dir);
    assert_eq!(std::fs::read(dir.join("manifest.json")).unwrap(), manifest, "same inputs, same manifest bytes");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn refusal(dir: &Path, scene: &Scene) -> String {
    match Artifact::read(dir).and_then(|artifact| AtlasSection::read(&artifact, scene)) {
        Ok(_) => panic!("{} was accepted", dir.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn corrupt_old_foreign_and_mismatched_artifacts_are_refused() {
    let scene = test_scene(2.0);
    let dir = temp_dir("refusals");
    write(&scene, &dir);
    let atlas_bin = dir.join("atlas.bin");
    let original = std::fs::read(&atlas_bin).unwrap();

    let mut flipped = original.clone();
    flipped[100] ^= 1;
    std::fs::write(&atlas_bin, &flipped).unwrap();
    let error = refusal(&dir, &scene);
    assert!(error.contains("atlas.bin") && error.contains("checksum"), "{error}");
    std::fs::write(&atlas_bin, &original[..original.len() / 2]).unwrap();
    assert!(refusal(&dir, &scene).contains("truncated"));
    std::fs::write(&atlas_bin, &original).unwrap();

    let error = refusal(&dir, &test_scene(2.5));
    assert!(error.contains("manifest.json") && error.contains("bake this scene"), "{error}");

    let manifest_path = dir.join("manifest.json");
    let manifest = std::fs::read_to_string(&manifest_path).unwrap();
    std::fs::write(&manifest_path, manifest.replace("\"version\": 2", "\"version\": 0")).unwrap();
    let error = refusal(&dir, &scene);
    assert!(error.contains("version 0") && error.contains("relume bake"), "{error}");
    let mut newer: serde_json::Value = serde_json::from_str(&manifest).unwrap();
    newer["sections"][0]["version"] = json!(7);
    std::fs::write(&manifest_path, newer.to_string()).unwrap();
    let error = refusal(&dir, &scene);
    assert!(error.contains("section atlas is version 7") && error.contains("relume bake"), "{error}");
    std::fs::write(&manifest_path, "{ not json").unwrap();
    assert!(refusal(&dir, &scene).contains("not valid JSON"));
    std::fs::remove_file(&manifest_path).unwrap();
    assert!(refusal(&dir, &scene).contains("manifest.json"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Data whose checksum matches but whose values a bake never makes is refused by name:
/// a texel's coverage, normal or triangle out of range, a NaN lightmap texel; and a file whose
/// size is not the manifest's.
#[test]
fn decoded_values_out_of_range_are_refused() {
    let scene = test_scene(2.0);
    let dir = temp_dir("ranges");
    let atlas = write(&scene, &dir);
    let covered = atlas.texels.iter().position(|t| t.coverage > 0.0).unwrap();
    type Spoil = fn(&mut relume_bake::atlas::Texel);
    let texel_errors: [(&str, Spoil); 4] = [
        ("coverage 2", |t| t.coverage = 2.0),
        ("unit normal", |t| t.normal = Vec3::new(f32::NAN, 0.0, 0.0)),
        ("names triangle 4000000000", |t| t.triangle = 4_000_000_000),
        ("unit normal", |t| t.normal *= 3.0),
    ];
    let refused_atlas = |section: AtlasSection| {
        let sections = vec![section.section(json!({}))];
        BakeOutput { method: "obscurance", scene: Some(&scene), parameters: json!({}), sections, stats: json!({}) }.write(&dir).unwrap();
        refusal(&dir, &scene)
    };
    for (words, spoil) in texel_errors {
        let mut section = atlas.to_section();
        spoil(&mut section.texels[covered]);
        let error = refused_atlas(section);
        assert!(error.contains("atlas.bin") && error.contains(&format!("texel {covered}")) && error.contains(words), "{error}");
    }
    // A v of 1e6 (u was always checked) and a u past the pages.
    for (uv, words) in [(glam::Vec2::new(0.5, 1e6), "1000000"), (glam::Vec2::new(3.5, 0.5), "3.5")] {
        let mut section = atlas.to_section();
        section.meshes[0].uv1[0] = uv;
        let error = refused_atlas(section);
        assert!(
            error.contains("atlas.bin") && error.contains("mesh 0: uv1") && error.contains(words) && error.contains("outside the atlas"),
            "{error}"
        );
    }
    // Not finite, and finite but past any light (3e38 made a render's pixels infinite).
    for bad in [f32::INFINITY, 3e38] {
        let mut values = vec![Vec3::ONE; atlas.texels.len()];
        values[7] = Vec3::new(0.0, bad, 0.0);
        let section = obscurance::section(&values, atlas.layout(), json!({})).unwrap();
        let output =
            BakeOutput { method: "obscurance", scene: Some(&scene), parameters: json!({}), sections: vec![section], stats: json!({}) };
        output.write(&dir).unwrap();
        let error = obscurance::read(&Artifact::read(&dir).unwrap(), &scene, atlas.layout()).err().unwrap().to_string();
        assert!(error.contains("obscurance.exr") && error.contains("texel 7") && error.contains("0..=1e9"), "{error}");
    }
    let manifest_path = dir.join("manifest.json");
    let manifest = std::fs::read_to_string(&manifest_path).unwrap();
    let bytes = std::fs::metadata(dir.join("obscurance.exr")).unwrap().len();
    std::fs::write(&manifest_path, manifest.replace(&format!("\"bytes\": {bytes}"), "\"bytes\": 12")).unwrap();
    let error = Artifact::read(&dir).unwrap_err().to_string();
    assert!(error.contains("obscurance.exr") && error.contains(&format!("is {bytes} bytes")) && error.contains("says 12"), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The manifest an artifact of format version 1 (before sections) began with, as relume wrote it.
const VERSION_1_MANIFEST: &str = r#"{
  "format": "relume-bake",
  "version": 1,
  "relume": "0.1.0",
  "method": "obscurance",
  "scene": { "file": "cornell.gltf", "checksum": "fnv1a64:0123456789abcdef" },
  "lightmap": "obscurance.exr",
  "files": { "atlas.bin": { "bytes": 8, "checksum": "fnv1a64:0123456789abcdef" } }
}"#;

#[test]
fn an_artifact_of_the_old_format_is_refused_with_the_rebake_hint() {
    let dir = temp_dir("old");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("manifest.json"), VERSION_1_MANIFEST).unwrap();
    let error = Artifact::read(&dir).unwrap_err().to_string();
    assert!(error.contains("manifest.json") && error.contains("version 1") && error.contains("reads version 2"), "{error}");
    assert!(error.contains("bake it again with `relume bake`"), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An artifact of two made-up sections: a dictionary keyed to nothing, a table keyed to the
/// mesh "room".
fn keyed_artifact(scene: &Scene, dir: &Path) {
    let section = |name: &str, key| Section {
        name: name.into(),
        version: 3,
        key,
        summary: json!({}),
        files: vec![(format!("{name}.bin"), name.as_bytes().to_vec())],
    };
    let sections = vec![section("dictionary", Key::Nothing), section("occluder-table", Key::Mesh("room".into()))];
    let output = BakeOutput { method: "keyed", scene: Some(scene), parameters: json!({}), sections, stats: json!({}) };
    output.write(dir).unwrap();
}

#[test]
fn a_scene_independent_section_is_read_only_without_a_scene_and_a_mesh_keyed_one_only_for_its_mesh() {
    let scene = test_scene(2.0);
    let dir = temp_dir("keys");
    keyed_artifact(&scene, &dir);
    let artifact = Artifact::read(&dir).unwrap();
    let dictionary = artifact.section("dictionary", 3, None).expect("no scene needed");
    assert_eq!(dictionary.file("dictionary.bin").unwrap().0, b"dictionary");
    // Read as a section keyed to a scene, a key to nothing would skip the scene's check.
    let error = artifact.section("dictionary", 3, Some(&scene)).err().expect("keyed to nothing, read for a scene").to_string();
    assert!(error.contains("section dictionary is keyed to no scene") && error.contains("manifest.json"), "{error}");

    // The same mesh in another scene (more meshes, no lights) is the same mesh.
    let mut bigger = test_scene(2.0);
    bigger.meshes.push(closed_box(Vec3::splat(3.0), Vec3::splat(4.0), 1, Facing::Outward, 0));
    bigger.lights.clear();
    assert!(artifact.section("occluder-table", 3, Some(&bigger)).is_ok(), "the mesh is unchanged");
    let error = artifact.section("occluder-table", 3, Some(&test_scene(2.5))).err().expect("another room").to_string();
    assert!(error.contains("mesh \"room\"") && error.contains("checksum"), "{error}");
    let mut renamed = test_scene(2.0);
    renamed.meshes[0].name = "hall".into();
    let error = artifact.section("occluder-table", 3, Some(&renamed)).err().expect("no room").to_string();
    assert!(error.contains("mesh \"room\"") && error.contains("lacks"), "{error}");
    let error = artifact.section("occluder-table", 3, None).err().expect("no scene").to_string();
    assert!(error.contains("keyed to a scene"), "{error}");
    let error = artifact.section("lightmap", 3, None).err().expect("no such section").to_string();
    assert!(error.contains("no section lightmap") && error.contains("dictionary, occluder-table"), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_folder_that_is_not_an_artifact_is_never_replaced() {
    let scene = test_scene(2.0);
    let dir = temp_dir("foreign");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    let atlas = Atlas::build(&scene, &AtlasSettings::default()).unwrap();
    let output = BakeOutput {
        method: "obscurance",
        scene: Some(&scene),
        parameters: json!({}),
        sections: vec![atlas.to_section().section(json!({}))],
        stats: json!({}),
    };
    let error = output.write(&dir).unwrap_err().to_string();
    assert!(error.contains("choose an empty or new --out folder"), "{error}");
    assert_eq!(std::fs::read_to_string(dir.join("notes.txt")).unwrap(), "mine");
    // An artifact with a user's file beside it is not replaced either (issue: a folder that
    // merely holds a manifest.json lost everything else in it); its own bake may replace it.
    std::fs::remove_file(dir.join("notes.txt")).unwrap();
    write(&scene, &dir);
    write(&scene, &dir);
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    let error = output.write(&dir).unwrap_err().to_string();
    assert!(error.contains("\"notes.txt\", which no bake wrote there") && error.contains("empty or new"), "{error}");
    assert_eq!(std::fs::read_to_string(dir.join("notes.txt")).unwrap(), "mine");
    assert!(Artifact::read(&dir).is_ok(), "the artifact beside it is intact");
    // Something other than a folder in the way is refused too.
    let file = dir.join("notes.txt");
    assert!(output.write(&file).unwrap_err().to_string().contains("is not a folder"));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    std::fs::remove_dir_all(&dir).unwrap();
}
