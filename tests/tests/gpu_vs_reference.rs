//! The Vulkan renderer against the reference path tracer on the same scene, camera and
//! lights, with validation on (a validation message fails the test).

use relume_renderer::RenderSettings;
use relume_tests::*;

fn settings(size: u32, shadows: bool) -> RenderSettings {
    RenderSettings { width: size, height: size, shadows, ..RenderSettings::default() }
}

#[test]
fn cornell_unshadowed_direct_light_matches_the_reference() {
    let nrmse = direct_nrmse("cornell_unshadowed", &load_scene("cornell"), &settings(256, false));
    assert!(nrmse <= 0.01, "NRMSE {nrmse} > 0.01");
}

#[test]
fn occluder_plane_vsm_direct_light_matches_the_reference() {
    let nrmse = direct_nrmse("occluder_plane_vsm", &load_scene("occluder-plane"), &settings(256, true));
    assert!(nrmse <= 0.05, "NRMSE {nrmse} > 0.05");
}

#[test]
fn cornell_with_shadows_matches_the_reference_direct_layer() {
    let nrmse = direct_nrmse("cornell_vsm", &load_scene("cornell"), &settings(256, true));
    assert!(nrmse <= 0.05, "NRMSE {nrmse} > 0.05");
}
