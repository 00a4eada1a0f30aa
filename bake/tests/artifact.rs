//! The bake artifact round-trips, and every way it can be wrong is refused with the file named.
#![cfg(feature = "baking")]

use glam::Vec3;
use relume_bake::artifact::{BakeOutput, Baked, PageLayout};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::scene::Scene;
use relume_bake::testing::{closed_box, look_at, material, point_light, scene, Facing};
use serde_json::json;
use std::path::{Path, PathBuf};

fn test_scene(size: f32) -> Scene {
    let camera = look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, 1.0);
    let room = closed_box(Vec3::ZERO, Vec3::splat(size), 2, Facing::Inward, 0);
    scene(
        "artifact test",
        vec![room],
        vec![material("grey", Vec3::splat(0.5), Vec3::ZERO)],
        vec![point_light(Vec3::ONE, Vec3::ONE)],
        camera,
    )
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("relume-artifact-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn write(scene: &Scene, dir: &Path) -> Atlas {
    let atlas = Atlas::build(scene, &AtlasSettings { texel_density: 6.0, ..Default::default() }).unwrap();
    let lightmap: Vec<Vec3> = atlas.texels.iter().map(|t| t.centre * 0.1 + Vec3::splat(t.coverage)).collect();
    let output = BakeOutput {
        method: "obscurance",
        scene,
        parameters: json!({ "tau": 0.1 }),
        atlas_summary: json!({ "charts": atlas.charts.len() }),
        layout: PageLayout { width: atlas.width, height: atlas.height, pages: atlas.pages },
        meshes: &atlas.meshes,
        texels: &atlas.texels,
        lightmap: &lightmap,
        transfer: None,
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
    let baked = Baked::read(&dir, &scene).unwrap();
    assert_eq!(baked.texels, atlas.texels);
    assert_eq!(baked.meshes, atlas.meshes);
    assert_eq!(baked.layout.texel_count(), atlas.texels.len());
    assert_eq!(baked.method(), "obscurance");
    let mut applied = scene.clone();
    baked.apply_to(&mut applied);
    assert_eq!(applied.meshes[0].uv1.as_ref(), Some(&atlas.meshes[0].uv1));
    assert_eq!(applied.triangle_count(), scene.triangle_count());
    let manifest = std::fs::read(dir.join("manifest.json")).unwrap();
    write(&scene, &dir);
    assert_eq!(std::fs::read(dir.join("manifest.json")).unwrap(), manifest, "same inputs, same manifest bytes");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn refusal(dir: &Path, scene: &Scene) -> String {
    Baked::read(dir, scene).unwrap_err().to_string()
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
    assert!(refusal(&dir, &scene).contains("checksum"));
    std::fs::write(&atlas_bin, &original).unwrap();

    let error = refusal(&dir, &test_scene(2.5));
    assert!(error.contains("manifest.json") && error.contains("bake this scene"), "{error}");

    let manifest_path = dir.join("manifest.json");
    let manifest = std::fs::read_to_string(&manifest_path).unwrap();
    std::fs::write(&manifest_path, manifest.replace("\"version\": 1", "\"version\": 0")).unwrap();
    let error = refusal(&dir, &scene);
    assert!(error.contains("version 0") && error.contains("relume bake"), "{error}");
    std::fs::write(&manifest_path, "{ not json").unwrap();
    assert!(refusal(&dir, &scene).contains("not valid JSON"));
    std::fs::remove_file(&manifest_path).unwrap();
    assert!(refusal(&dir, &scene).contains("manifest.json"));
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
        scene: &scene,
        parameters: json!({}),
        atlas_summary: json!({}),
        layout: PageLayout { width: atlas.width, height: atlas.height, pages: atlas.pages },
        meshes: &atlas.meshes,
        texels: &atlas.texels,
        lightmap: &vec![Vec3::ONE; atlas.texels.len()],
        transfer: None,
        stats: json!({}),
    };
    let error = output.write(&dir).unwrap_err().to_string();
    assert!(error.contains("choose another --out"), "{error}");
    assert_eq!(std::fs::read_to_string(dir.join("notes.txt")).unwrap(), "mine");
    std::fs::remove_dir_all(&dir).unwrap();
}
