//! The Vulkan renderer against the reference path tracer on the same scene, camera and
//! lights, with validation on (a validation message fails the test).

use relume_renderer::RenderSettings;
use relume_tests::*;

fn settings(size: u32, shadows: bool) -> RenderSettings {
    RenderSettings { width: size, height: size, shadows, ..RenderSettings::default() }
}

#[test]
fn cornell_unshadowed_direct_light_matches_the_reference() {
    let scene = load_scene("cornell");
    let image = render_validated(&scene, &settings(256, false));
    let reference = reference_direct(&scene, 256, 256, false);
    let nrmse = nrmse_with_artifacts("cornell_unshadowed", &image, &reference);
    println!("cornell, shadows off, 256x256: NRMSE {nrmse:.5}");
    assert!(nrmse <= 0.01, "NRMSE {nrmse} > 0.01");
}

#[test]
fn occluder_plane_vsm_direct_light_matches_the_reference() {
    let scene = load_scene("occluder-plane");
    let image = render_validated(&scene, &settings(256, true));
    let reference = reference_direct(&scene, 256, 256, true);
    let nrmse = nrmse_with_artifacts("occluder_plane_vsm", &image, &reference);
    println!("occluder-plane, VSM, 256x256: NRMSE {nrmse:.5}");
    assert!(nrmse <= 0.05, "NRMSE {nrmse} > 0.05");
}

#[test]
fn cornell_with_shadows_matches_the_reference_direct_layer() {
    let scene = load_scene("cornell");
    let image = render_validated(&scene, &settings(256, true));
    let reference = reference_direct(&scene, 256, 256, true);
    let nrmse = nrmse_with_artifacts("cornell_vsm", &image, &reference);
    println!("cornell, VSM, 256x256: NRMSE {nrmse:.5}");
    assert!(nrmse <= 0.05, "NRMSE {nrmse} > 0.05");
}
