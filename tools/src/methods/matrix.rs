//! Every method on every shipped scene (`relume scenes`): each renders, or is refused for the
//! physical reason that the scene has none of the light it models, and nothing else. Bakes run
//! at the least effort each method takes (the matrix tests that a method runs, not how well:
//! the end-to-end tests and docs/BENCHMARKS.md measure that), what a scene does not declare
//! derived as a user's bake derives it, each render made with validation on. The matrix is
//! printed as docs/BENCHMARKS.md shows it:
//!
//!     cargo test --release -p relume-tools --bin relume every_method -- --nocapture

use super::{refusal, Method, METHODS};
use crate::args::load_scene;
use crate::bake::bake_scene;
use crate::gpu::renderer;
use relume_bake::artifact::Artifact;
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use relume_renderer::vk::{Context, ContextOptions};
use relume_renderer::RenderSettings;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The least effort of each method's bake.
pub(super) fn least_effort(method: &str, dictionaries: &Path) -> Vec<(&'static str, String)> {
    let pairs: &[(&str, &str)] = match method {
        "obscurance" => &[("rays", "1"), ("patches", "400")],
        "light-path-maps" => &[("rays", "1"), ("patches", "400"), ("entry-points", "64"), ("uncompressed", "true")],
        "fiv" => &[("grid", "32x17x15"), ("difmap-width", "8")],
        "light-cloud" => {
            &[("samples", "1"), ("zones", "1"), ("no-light-clustering", "true"), ("uncompressed", "true"), ("emission-bands", "1")]
        }
        "mrt" => &[
            ("samples-per-face", "2"),
            ("gather-rays", "16"),
            ("modes", "4"),
            ("prior-modes", "4"),
            ("lightfield", "2"),
            ("lightfield-modes", "8"),
            ("response-modes", "4"),
        ],
        _ => &[],
    };
    let mut pairs: Vec<(&str, String)> = pairs.iter().map(|(k, v)| (*k, v.to_string())).collect();
    if method == "mrt" {
        pairs.push(("dictionary-cache", dictionaries.display().to_string()));
    }
    pairs
}

/// A scene as shipped; a declared light cloud made 2 x 2 x 2 (the maze's 1,024 cloud lights
/// would be minutes of work that says nothing more here).
pub(super) fn shipped(name: &str) -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.gltf"));
    let args = crate::args::SceneArgs {
        scene: path,
        camera: None,
        width: 16,
        height: 16,
        environment: None,
        allow_outside_files: false,
        max_texture_pixels: relume_bake::gltf_load::DEFAULT_MAX_TEXTURE_PIXELS,
        lights: None,
    };
    let mut scene = load_scene(&args).expect("a shipped scene loads");
    if let Some(grid) = scene.settings.blocks.get_mut("light_cloud").and_then(|b| b.get_mut("grid")) {
        grid["counts"] = serde_json::json!([2, 2, 2]);
    }
    scene
}

/// Bakes `method` on `scene` with the least effort (into a folder under `dir`) and loads it
/// with its default run-time values; Err: why it failed.
pub(super) fn least_effort_loaded(method: &dyn Method, scene: &Scene, dir: &Path) -> Result<Box<dyn super::Loaded>, String> {
    let pairs: Vec<(String, String)> =
        least_effort(method.name(), &dir.join("dictionaries")).into_iter().map(|(k, v)| (k.into(), v)).collect();
    let values = super::parse_values(method, &pairs, None).map_err(|e| format!("{e:#}"))?;
    let artifact = match method.bakes() {
        true => {
            let out = dir.join(format!("{}-{}", scene.source.file_stem().unwrap().to_string_lossy(), method.name()));
            let work = WorkOptions { threads: None, ..WorkOptions::default() };
            bake_scene(scene, method, &values, work, &out).map_err(|e| format!("bake: {e:#}"))?;
            Some(Artifact::read(&out).map_err(|e| format!("{e:#}"))?)
        }
        false => None,
    };
    let render_values = super::parse_values(method, &[], Some(super::params::Stage::Render)).map_err(|e| format!("{e:#}"))?;
    super::load(method, artifact.as_ref(), scene, &render_values).map_err(|e| format!("load: {e:#}"))
}

/// Bakes (with the least effort) and renders `method` on `scene`; Err: why it failed.
fn renders(method: &dyn Method, scene: &Scene, ctx: &Arc<Context>, dir: &Path) -> Result<(), String> {
    let loaded = least_effort_loaded(method, scene, dir)?;
    let (ambient, beta) = super::frame_ambient(method.ambient(scene), None, None);
    let settings = RenderSettings {
        width: 16,
        height: 16,
        shadow_map_size: 64,
        ambient,
        beta,
        environment_ambient: method.environment_ambient(),
        ..RenderSettings::default()
    };
    let mut headless = renderer(ctx, loaded.as_ref(), &settings).map_err(|e| format!("render: {e:#}"))?;
    let (image, _) = headless.render_and_read().map_err(|e| format!("render: {e:#}"))?;
    match image.pixels.iter().all(|p| p.is_finite()) {
        true => Ok(()),
        false => Err("render: NaN or infinite pixels".into()),
    }
}

#[test]
fn every_method_renders_every_scene_or_is_refused_for_want_of_its_light() {
    let dir = std::env::temp_dir().join(format!("relume-matrix-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ctx = Context::headless(&ContextOptions { validation: true, device: None }).expect("Vulkan");
    let log = ctx.message_log();
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for name in relume_tools::scenegen::SCENE_NAMES {
        let scene = shipped(name);
        let mut cells = Vec::new();
        for method in METHODS {
            let cell = match refusal(method, &scene) {
                Some(why) => {
                    // The only refusals: a scene without the light the method models.
                    assert!(why.contains("this scene has none"), "{name} x {}: {why}", method.name());
                    if why.contains("environment") { "no environment" } else { "no punctual light" }.to_string()
                }
                None => match renders(method, &scene, &ctx, &dir) {
                    Ok(()) => "renders".into(),
                    Err(why) => {
                        failures.push(format!("{name} x {}: {why}", method.name()));
                        "FAILED".into()
                    }
                },
            };
            cells.push(cell);
        }
        rows.push((name, cells));
    }
    drop(ctx);
    let messages = log.lock().map(|m| m.clone()).unwrap_or_default();
    std::fs::remove_dir_all(&dir).ok();
    let header: Vec<&str> = METHODS.iter().map(|m| m.name()).collect();
    println!("| scene | {} |\n|---|{}", header.join(" | "), "---|".repeat(header.len()));
    for (name, cells) in &rows {
        println!("| {name} | {} |", cells.join(" | "));
    }
    assert!(failures.is_empty(), "{} failed:\n{}", failures.len(), failures.join("\n"));
    assert!(messages.is_empty(), "{} validation messages, first: {}", messages.len(), messages[0]);
}
