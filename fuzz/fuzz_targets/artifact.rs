//! The bake artifact reader on any bytes: the first byte picks what the rest is, which is then
//! written into an otherwise well-formed artifact (manifest, checksums and keys right, as a
//! corrupt but consistent bake would be) and read as relume reads it. Two-file sections take
//! a little-endian u32 length, then the first file, then the second.
//! 0: manifest.json; 1: atlas.bin; 2: obscurance.exr after a u16 width and height of the atlas;
//! 3: light-path-maps.bin after a u16 width and height; 4: fiv_environment.bin;
//! 5: fiv_environment.bin and fiv_occluder_0.bin; 6: light-cloud.bin (for cornell-cloud);
//! 7: mrt-dictionary.bin (keyed to nothing, read with whatever parameters it holds);
//! 8: mrt-dictionary.bin and mrt-level.bin (for mrt-cube), the level read with that dictionary.
#![no_main]

use libfuzzer_sys::fuzz_target;
use relume_bake::artifact::{Artifact, BakeOutput, Key, PageLayout, Section};
use relume_bake::scene::Scene;
use relume_bake::{atlas, fiv, light_cloud, light_path_maps, mrt, obscurance};
use serde_json::json;
use std::sync::OnceLock;

/// The committed scenes the sections are read for, each loaded once.
const SCENES: [&str; 4] = ["cornell", "fiv-blobs", "cornell-cloud", "mrt-cube"];

fn loaded(which: usize) -> &'static Scene {
    static LOADED: [OnceLock<Scene>; SCENES.len()] = [const { OnceLock::new() }; SCENES.len()];
    LOADED[which].get_or_init(|| relume_fuzz::scene(SCENES[which]))
}

fn cornell() -> &'static Scene {
    loaded(0)
}

fn fiv_blobs() -> &'static Scene {
    loaded(1)
}

fn cornell_cloud() -> &'static Scene {
    loaded(2)
}

fn mrt_cube() -> &'static Scene {
    loaded(3)
}

/// An artifact of `files` (one section each: name, key, file name, bytes) for `scene`, read.
fn artifact(scene: &Scene, sections: Vec<(String, Key, String, Vec<u8>)>, version: u32) -> Option<Artifact> {
    artifact_of(scene, sections.into_iter().map(|(name, key, file, bytes)| (name, key, file, bytes, version)).collect())
}

/// As [`artifact`], each section with its own version.
fn artifact_of(scene: &Scene, sections: Vec<(String, Key, String, Vec<u8>, u32)>) -> Option<Artifact> {
    let sections = sections
        .into_iter()
        .map(|(name, key, file, bytes, version)| Section { name, version, key, summary: json!({}), files: vec![(file, bytes)] })
        .collect();
    let dir = relume_fuzz::scratch().join("bake");
    let output = BakeOutput { method: "fuzz", scene: Some(scene), parameters: json!({}), sections, stats: json!({}) };
    output.write(&dir).ok()?;
    Artifact::read(&dir).ok()
}

/// A layout of `width` x `height`, one page, from two u16 at the start of `data`; and the rest.
fn layout(data: &[u8]) -> Option<(PageLayout, &[u8])> {
    let (size, rest) = (data.get(..4)?, data.get(4..)?);
    let [w0, w1, h0, h1] = size.try_into().ok()?;
    Some((PageLayout { width: u16::from_le_bytes([w0, w1]) as u32, height: u16::from_le_bytes([h0, h1]) as u32, pages: 1 }, rest))
}

/// Two files: a u32 length, the first, then the second.
fn two_files(data: &[u8]) -> Option<(&[u8], &[u8])> {
    let length = u32::from_le_bytes(data.get(..4)?.try_into().ok()?) as usize;
    let rest = data.get(4..)?;
    Some((rest.get(..length)?, rest.get(length..)?))
}

fn scene_section(name: &str, file: &str, bytes: &[u8]) -> (String, Key, String, Vec<u8>) {
    (name.into(), Key::Scene, file.into(), bytes.to_vec())
}

fn read(which: u8, data: &[u8]) -> Option<()> {
    match which % 9 {
        0 => {
            let dir = relume_fuzz::scratch().join("manifest");
            std::fs::create_dir_all(&dir).ok()?;
            std::fs::write(dir.join("manifest.json"), data).ok()?;
            let artifact = Artifact::read(&dir).ok()?;
            let _ = atlas::AtlasSection::read(&artifact, cornell());
        }
        1 => {
            let artifact = artifact(cornell(), vec![scene_section(atlas::SECTION, "atlas.bin", data)], atlas::SECTION_VERSION)?;
            let _ = atlas::AtlasSection::read(&artifact, cornell());
        }
        2 => {
            let (layout, exr) = layout(data)?;
            let sections = vec![scene_section(obscurance::SECTION, "obscurance.exr", exr)];
            let _ = obscurance::read(&artifact(cornell(), sections, obscurance::SECTION_VERSION)?, cornell(), layout);
        }
        3 => {
            let (layout, bin) = layout(data)?;
            let sections = vec![scene_section(light_path_maps::SECTION, "light-path-maps.bin", bin)];
            let _ = light_path_maps::read(&artifact(cornell(), sections, light_path_maps::SECTION_VERSION)?, cornell(), layout);
        }
        4 => {
            let environment = (fiv::ENVIRONMENT_SECTION.into(), Key::Environment, "fiv_environment.bin".into(), data.to_vec());
            let _ = fiv::read(&artifact(fiv_blobs(), vec![environment], fiv::SECTION_VERSION)?, fiv_blobs(), &[]);
        }
        6 => {
            let sections = vec![scene_section(light_cloud::SECTION, "light-cloud.bin", data)];
            let _ = light_cloud::read(&artifact(cornell_cloud(), sections, light_cloud::SECTION_VERSION)?, cornell_cloud());
        }
        7 => {
            let sections = vec![(mrt::dictionary::SECTION.into(), Key::Nothing, "mrt-dictionary.bin".into(), data.to_vec())];
            let _ = mrt::dictionary::read(&artifact(cornell(), sections, mrt::dictionary::SECTION_VERSION)?, None);
        }
        8 => {
            let (dictionary, level) = two_files(data)?;
            let sections = vec![
                (mrt::dictionary::SECTION.into(), Key::Nothing, "mrt-dictionary.bin".into(), dictionary.to_vec(), mrt::dictionary::SECTION_VERSION),
                (mrt::level_data::SECTION.into(), Key::Scene, "mrt-level.bin".into(), level.to_vec(), mrt::level_data::SECTION_VERSION),
            ];
            let artifact = artifact_of(mrt_cube(), sections)?;
            let (read, checksum) = mrt::dictionary::read(&artifact, None).ok()?;
            let _ = mrt::level_data::read(&artifact, mrt_cube(), &read, &checksum);
        }
        _ => {
            let (environment, table) = two_files(data)?;
            let mesh = fiv_blobs().meshes[0].name.clone();
            let sections = vec![
                (fiv::ENVIRONMENT_SECTION.into(), Key::Environment, "fiv_environment.bin".into(), environment.to_vec()),
                ("fiv_occluder_0".into(), Key::Mesh(mesh.clone()), "fiv_occluder_0.bin".into(), table.to_vec()),
            ];
            let artifact = artifact(fiv_blobs(), sections, fiv::SECTION_VERSION)?;
            let _ = fiv::read(&artifact, fiv_blobs(), &[mesh.as_str()]);
        }
    }
    Some(())
}

fuzz_target!(|data: &[u8]| {
    if let Some((&which, rest)) = data.split_first() {
        read(which, rest);
    }
});
