//! The ambient methods' environment light (`RenderSettings::environment_ambient`): the lighting
//! pass adds the environment's unoccluded irradiance at each normal from nine spherical
//! harmonics; its image against the CPU's `sh::irradiance` of the same coefficients, pixel by
//! pixel, under validation.

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::sh;
use relume_bake::testing::{environment, look_at, material, scene, sphere, Facing};
use relume_renderer::RenderSettings;
use relume_tests::*;

const SIZE: u32 = 64;

#[test]
fn the_lighting_pass_adds_the_environments_irradiance_at_each_normal() {
    let albedo = Vec3::new(0.8, 0.6, 0.4);
    let camera = look_at(Vec3::new(0.0, 1.0, 3.0), Vec3::ZERO, Vec3::Y, 0.8);
    let mut ball =
        scene("ball", vec![sphere(Vec3::ZERO, 1.0, 2, Facing::Outward, 0)], vec![material("ball", albedo, Vec3::ZERO)], vec![], camera);
    // A sky brighter above and to one side, with a sun: every band l <= 2 is lit, and the
    // coefficients ring below zero facing away from the sun (clamped on both sides).
    ball.environment = Some(environment(relume_bake::testing::sky(Vec3::new(0.6, 0.5, 0.2), Vec3::splat(60.0), 4.0), 16));
    let settings = RenderSettings { width: SIZE, height: SIZE, environment_ambient: true, ..RenderSettings::default() };
    let image = render_validated(&ball, &settings);
    let without = render_validated(&ball, &RenderSettings { environment_ambient: false, ..settings.clone() });
    assert!(without.pixels.iter().all(|p| *p == glam::Vec4::ZERO.truncate()), "without it the unlit ball is black");

    let coefficients = ball.environment.as_ref().unwrap().radiance_sh();
    let bvh = SceneBvh::new(&ball);
    let hits = primary_hits(&ball, &bvh, SIZE, SIZE);
    let interior = interior_pixels(&hits, SIZE, SIZE);
    let (mut worst, mut checked) = (0f32, 0);
    for (i, hit) in hits.iter().enumerate().filter(|(i, _)| interior[*i]) {
        let n = hit.expect("an interior pixel hits").shading_normal;
        let expected = albedo / std::f32::consts::PI * sh::irradiance(&coefficients, n).max(Vec3::ZERO);
        worst = worst.max((image.pixels[i] - expected).abs().max_element() / expected.max_element().max(1e-3));
        checked += 1;
    }
    println!("{checked} pixels; largest relative difference from the CPU {worst:.2e}");
    assert!(checked > 300, "{checked} interior pixels");
    assert!(worst < 1e-4, "{worst}");
}
