//! Every technique in effect mode, inside an engine that is not relume
//! (renderer/examples/engine.rs: its own device, geometry, lights, surfaces and forward passes
//! and shaders, which sample relume's terms with shaders/include/relume.glsl; fiv reads the
//! engine's surfaces instead of drawing its own). Each method is baked with
//! the least effort on a scene that gives its term each kind it comes in (occlusion, texel,
//! vertex, pixel, texel or vertex, radiance); the engine's image must equal relume's own frame
//! of the same scene, lights and term within 1e-4 of its largest value, with validation and
//! synchronization validation clean on both. The engine draws its own shadow maps for
//! relume's shadow views and shades its direct light with them, and hands them to the effect
//! (light path maps and mrt shadow their direct light with the engine's); relume's frame draws
//! its own. The lighting models agree where the engine models what relume's frame does: shadow
//! maps without a blur (the engine blurs none), untextured scenes, no environment in the
//! ambient light.
//!
//!     cargo test -p relume-tools --bin relume every_technique_as_an_effect -- --nocapture

#[path = "../../../renderer/examples/engine.rs"]
#[allow(dead_code)]
mod engine;

use super::matrix::{least_effort_loaded, shipped};
use super::{find, frame_ambient};
use crate::gpu::renderer;
use relume_renderer::vk::{Context, ContextOptions};
use relume_renderer::{MakeTechnique, RenderSettings};

/// A method and a shipped scene, with the shader variant the engine must compile for them
/// (the kinds of the terms the method hands over there).
const CASES: [(&str, &str, &str); 7] = [
    ("obscurance", "cornell", "RELUME_TERM=0 OCCLUSION="),
    ("light-path-maps", "cornell", "RELUME_TERM=1 OCCLUSION="),
    ("light-cloud", "cornell-cloud", "RELUME_TERM=2"),
    ("light-cloud", "glossy-enclosure", "RELUME_TERM=0 RADIANCE="),
    ("fiv", "fiv-blobs", "RELUME_TERM=3"),
    ("mrt", "mrt-cube", "RELUME_TERM=1"),
    ("mrt", "mrt-figures", "RELUME_TERM=4"),
];

#[test]
fn every_technique_as_an_effect_in_an_engine_equals_relumes_frame() {
    let dir = std::env::temp_dir().join(format!("relume-effects-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, scene_name, variant) in CASES {
        let method = find(name).expect("a registered method");
        let scene = shipped(scene_name);
        let loaded = least_effort_loaded(method, &scene, &dir).unwrap_or_else(|e| panic!("{name} on {scene_name}: {e}"));
        let (ambient, beta) = frame_ambient(method.ambient(&scene), None, None);
        let settings = RenderSettings { width: 64, height: 48, blur_radius: 0, ambient, beta, ..RenderSettings::default() };

        let ctx = Context::headless(&ContextOptions { validation: true, device: None }).expect("Vulkan");
        let log = ctx.message_log();
        let (relume, _) = renderer(&ctx, loaded.as_ref(), &settings).and_then(|mut r| Ok(r.render_and_read()?)).expect("relume's frame");
        drop(ctx);
        let messages = log.lock().map(|m| m.clone()).unwrap_or_default();
        assert!(messages.is_empty(), "{name} on {scene_name}: relume's frame: {messages:#?}");

        let techniques = loaded.techniques();
        let techniques: Vec<&dyn MakeTechnique> = techniques.iter().map(|t| t.as_ref()).collect();
        let outcome = engine::run(loaded.scene(), &techniques, &settings, true).expect("the engine's frame");
        assert!(outcome.validation_messages.is_empty(), "{name} on {scene_name}: the engine: {:#?}", outcome.validation_messages);
        assert_eq!(outcome.variant, variant, "{name} on {scene_name}: the terms it hands over");
        let pixel_term = variant.contains("RELUME_TERM=3");
        assert_eq!(outcome.drew_surfaces, pixel_term, "{name} on {scene_name}: a pixel term, and only it, reads the engine's surfaces");

        let expected: Vec<f32> = relume.pixels.iter().flat_map(|p| p.to_array()).collect();
        let got: Vec<f32> = outcome.radiance.chunks_exact(4).flat_map(|p| p[..3].to_vec()).collect();
        let largest = expected.iter().fold(0.0f32, |a, &b| a.max(b));
        let worst = expected.iter().zip(&got).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        println!("{name} on {scene_name} ({variant}): largest {largest:.4}, largest difference {worst:.3e}");
        assert!(largest > 0.0, "{name} on {scene_name}: relume's frame is black");
        assert!(worst <= 1e-4 * largest, "{name} on {scene_name}: the engine differs from relume's frame by {worst} of {largest}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
