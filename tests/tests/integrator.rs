//! The integrator example (renderer/examples/integrator.rs) as a test: an engine with its own
//! instance, device, queue, command buffer and image records relume's frame between two passes
//! of its own and submits it itself. With validation and synchronization validation on: no
//! message (a wrong handed-back layout or a missing barrier would be one), the state relume
//! hands back is the copy's, the engine's pixels are relume's own headless renderer's on the
//! same device, and the engine destroys its device and instance after relume is gone (a
//! double destroy would crash).

#[path = "../../renderer/examples/integrator.rs"]
mod integrator;

use relume_renderer::vk::{Access, Context, ContextOptions};
use relume_renderer::RenderSettings;
use relume_tests::*;

#[test]
fn an_engine_records_relumes_frame_between_its_own_passes_on_its_own_device() {
    let (width, height) = (128, 96);
    let path = repo_root().join("scenes").join("occluder-plane.gltf");
    let outcome = integrator::run(&path, width, height, true).expect("the engine's frame");
    assert_no_validation_messages(&outcome.validation_messages);
    assert_eq!(outcome.handed_back, Access::TransferDestination.state(), "relume leaves the engine's image as its copy wrote it");

    let ctx = Context::headless(&ContextOptions { validation: true, device: Some(outcome.device.clone()) }).expect("context");
    let settings = RenderSettings { width, height, ..RenderSettings::default() };
    let (_, display) = new_renderer(&ctx, &load_scene("occluder-plane"), &settings, &[]).render_and_read().expect("frame");
    assert_clean(ctx);
    assert!(display.chunks_exact(4).any(|p| p[..3] != [0, 0, 0]), "the frame is not black");
    assert_eq!(outcome.pixels, display, "the engine's image holds relume's display pixels");
}
