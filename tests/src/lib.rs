//! Shared helpers of relume's cross-crate tests: shipped scenes, a validated headless Vulkan
//! render, the reference's direct layer at pixel centres, failure images, and synthetic light
//! path maps (`synthetic_lpm`).

use relume_bake::bvh::SceneBvh;
use relume_bake::gltf_load;
use relume_bake::image::{write_exr_layers, Image};
use relume_bake::metrics;
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::Scene;
use relume_renderer::vk::{Context, ContextOptions};
use relume_renderer::{RenderSettings, Renderer};
use std::path::PathBuf;

pub mod synthetic_lpm;

pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub fn load_scene(name: &str) -> Scene {
    let path = repo_root().join("scenes").join(format!("{name}.gltf"));
    gltf_load::load(&path).unwrap_or_else(|e| panic!("{e}")).scene
}

/// A headless context on lavapipe (or RELUME_DEVICE) with validation and synchronization
/// validation on.
pub fn validated_context() -> Context {
    Context::headless(&ContextOptions { validation: true, device: None }).expect("Vulkan context")
}

/// Renders one frame with validation on; panics on any validation message.
pub fn render_validated(scene: &Scene, settings: &RenderSettings) -> Image {
    let ctx = validated_context();
    let log = ctx.message_log();
    let mut renderer = Renderer::new(&ctx, scene, settings).expect("renderer");
    let (image, _) = renderer.render_and_read().expect("frame");
    drop(renderer);
    drop(ctx);
    assert_no_validation_messages(&log.lock().unwrap());
    image
}

pub fn assert_no_validation_messages(messages: &[String]) {
    assert!(messages.is_empty(), "{} validation message(s):\n{}", messages.len(), messages.join("\n"));
}

/// The reference's `direct` layer with every sample through the pixel centre: exact for
/// punctual lights after one sample.
pub fn reference_direct(scene: &Scene, width: u32, height: u32, shadows: bool) -> Image {
    let settings = ReferenceSettings {
        samples_per_pixel: 1,
        width,
        height,
        pixel_centres: true,
        shadows,
        max_bounces: 1,
        ..ReferenceSettings::default()
    };
    render_reference(scene, &SceneBvh::new(scene), &settings).direct
}

/// Renders `scene` with Vulkan and the reference's direct layer at pixel centres, and
/// returns the NRMSE of one against the other (printed, with artifacts kept under `name`).
pub fn direct_nrmse(name: &str, scene: &Scene, settings: &RenderSettings) -> f64 {
    let image = render_validated(scene, settings);
    let reference = reference_direct(scene, settings.width, settings.height, settings.shadows);
    let nrmse = nrmse_with_artifacts(name, &image, &reference);
    println!("{name}: NRMSE {nrmse:.5}");
    nrmse
}

/// NRMSE of `image` against `reference`; writes both and the error picture under
/// target/test-output/<name>/ so a failure can be looked at.
pub fn nrmse_with_artifacts(name: &str, image: &Image, reference: &Image) -> f64 {
    let dir = repo_root().join("target/test-output").join(name);
    std::fs::create_dir_all(&dir).expect("test output folder");
    write_exr_layers(&dir.join("actual.exr"), &[("radiance", image)]).expect("write actual");
    write_exr_layers(&dir.join("reference.exr"), &[("direct", reference)]).expect("write reference");
    let mean = reference.pixels.iter().map(|p| p.element_sum() / 3.0).sum::<f32>() / reference.pixels.len() as f32;
    let exposure = if mean > 0.0 { 0.18 / mean } else { 1.0 };
    relume_bake::image::write_png_tonemapped(&dir.join("actual.png"), image, exposure).expect("write actual png");
    relume_bake::image::write_png_tonemapped(&dir.join("reference.png"), reference, exposure).expect("write reference png");
    let rgb = metrics::false_colour(image, reference, 0.5).expect("sizes match");
    relume_bake::image::write_png_rgb8(&dir.join("error.png"), image.width, image.height, &rgb).expect("write error");
    let lit = reference.pixels.iter().filter(|p| p.max_element() > 0.0).count();
    assert!(lit * 10 > reference.pixels.len(), "{name}: the reference is almost black; the test would prove nothing");
    let stats = metrics::compare(image, reference).expect("sizes match");
    assert_eq!(stats.non_finite_pixels, 0, "{name}: NaN or infinite pixels");
    stats.nrmse
}
