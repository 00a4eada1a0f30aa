//! End to end on `cornell-cloud` (004's Cornell scene): bake the cloud's transfer, then move
//! the point light along a path inside the cloud and render every position with the Vulkan
//! renderer, relit each frame without a re-bake. Each frame's indirect part (the frame less
//! the direct-only frame) is compared with the reference path tracer's `indirect` layer at the
//! same light. With m = 1 and the light on a cloud point, the frame is that light's stored
//! transfer alone: the bake itself against the reference (spec light-clouds.md D9).

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::light_cloud::{self as lc, LightCloud, LightCloudBakeSettings, LightCloudSceneSettings};
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::light_cloud::{LightCloudData, Visibility};
use relume_renderer::vk::Context;
use relume_renderer::{Headless, RenderSettings};
use relume_tests::*;
use std::sync::Arc;

const SIZE: u32 = 64;

/// How many gather paths a vertex and reference samples a pixel a measurement takes.
#[derive(Clone, Copy)]
struct Effort {
    gather: u32,
    reference: u32,
}

/// The test's effort: about half a minute.
const QUICK: Effort = Effort { gather: 32, reference: 256 };

fn settings() -> RenderSettings {
    RenderSettings { width: SIZE, height: SIZE, ..RenderSettings::default() }
}

fn bake(scene: &Scene, effort: Effort) -> (LightCloud, Visibility) {
    let bvh = SceneBvh::new(scene);
    let grid = LightCloudSceneSettings::of(scene).unwrap().grid;
    let settings =
        LightCloudBakeSettings { grid: Some(grid), directions: 0, samples: effort.gather, emission: 1, work: WorkOptions::default() };
    let cloud = lc::bake(scene, &bvh, &settings).expect("bake");
    (cloud, Arc::new(move |a, b| bvh.visible(a, b)))
}

fn reference_indirect(scene: &Scene, effort: Effort) -> Image {
    let settings = ReferenceSettings { samples_per_pixel: effort.reference, width: SIZE, height: SIZE, ..ReferenceSettings::default() };
    render_reference(scene, &SceneBvh::new(scene), &settings).indirect
}

/// The frame's indirect part at the scene's light: the frame with the cloud less the
/// direct-only frame.
fn indirect(with_cloud: &mut Headless, direct: &mut Headless, scene: &Scene) -> Image {
    with_cloud.set_lights(&scene.lights).unwrap();
    direct.set_lights(&scene.lights).unwrap();
    let (lit, only_direct) = (render(with_cloud), render(direct));
    difference(&lit, &only_direct)
}

/// What one measurement found: the indirect NRMSE of every frame along the light's path, for
/// the transfer as gathered and as the method's defaults reduce it, and of the stored column.
struct Measured {
    gathered: Vec<f64>,
    reduced: Vec<f64>,
    column: f64,
}

fn nrmse_along_a_path(ctx: &Arc<Context>, effort: Effort) -> Measured {
    let scene = load_scene("cornell-cloud");
    let (cloud, visibility) = bake(&scene, effort);
    let reduced = light_cloud_by_defaults(&scene, &SceneBvh::new(&scene), &cloud);
    let interpolated =
        LightCloudData { cloud: &cloud, nearest: 8, nearest_directions: 3, fade_seconds: 0.0, visibility: Arc::clone(&visibility) };
    let by_default =
        LightCloudData { cloud: &reduced, nearest: 8, nearest_directions: 3, fade_seconds: 0.0, visibility: Arc::clone(&visibility) };
    let nearest_one = LightCloudData { cloud: &cloud, nearest: 1, nearest_directions: 3, fade_seconds: 0.0, visibility };
    let mut with_cloud = new_renderer(ctx, &scene, &settings(), &[&interpolated]);
    let mut with_reduced = new_renderer(ctx, &scene, &settings(), &[&by_default]);
    let mut only_column = new_renderer(ctx, &scene, &settings(), &[&nearest_one]);
    let mut direct = new_renderer(ctx, &scene, &settings(), &[]);
    let start = scene.lights[0].position;
    let (mut gathered, mut by_defaults) = (Vec::new(), Vec::new());
    for k in 0..6 {
        // A circle of 12 cm radius, 3 cm under the scene's light (4 cm over the tall block),
        // through cells and their borders.
        let angle = std::f32::consts::TAU * k as f32 / 6.0;
        let mut moved = scene.clone();
        moved.lights[0].position = start + Vec3::new(0.12 * angle.cos(), -0.03, 0.12 * angle.sin());
        let reference = reference_indirect(&moved, effort);
        let image = indirect(&mut with_cloud, &mut direct, &moved);
        gathered.push(nrmse_with_artifacts(&format!("light_cloud_path_{k}"), &image, &reference));
        let image = indirect(&mut with_reduced, &mut direct, &moved);
        by_defaults.push(nrmse_with_artifacts(&format!("light_cloud_path_reduced_{k}"), &image, &reference));
    }
    // The cloud light nearest the scene's light, standing on it alone.
    let j = (0..cloud.lights.len()).min_by(|&a, &b| cloud.lights[a].distance(start).total_cmp(&cloud.lights[b].distance(start))).unwrap();
    let mut at_cloud_point = scene.clone();
    at_cloud_point.lights[0].position = cloud.lights[j];
    let image = indirect(&mut only_column, &mut direct, &at_cloud_point);
    let column = nrmse_with_artifacts("light_cloud_column", &image, &reference_indirect(&at_cloud_point, effort));
    Measured { gathered, reduced: by_defaults, column }
}

fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted[sorted.len() / 2]
}

#[test]
fn indirect_light_along_a_path_inside_the_cloud_follows_the_reference() {
    let ctx = validated_context();
    let Measured { gathered: frames, reduced, column } = nrmse_along_a_path(&ctx, QUICK);
    assert_clean(ctx);
    println!("indirect NRMSE per frame {frames:.4?}, by the defaults {reduced:.4?}; one stored column (m = 1, light at a cloud point) {column:.4}");
    // Bars from the first honest measurement (32 gather paths, 256 reference samples; the
    // reference alone is 0.065 from a converged one): frames 0.141, 0.164, 0.173, 0.370,
    // 0.270, 0.152, the column 0.163. Frame 3 is the light 4 cm over the tall block, whose hot
    // spot its nearest visible cloud lights (8 cm and more away) underestimate.
    // The spec's bar for the column is 0.10 (light-clouds.md D9); this one is 0.18 because both
    // sides are noisy at a test's effort: at 128 gather paths and 4,096 samples the same column
    // is 0.091 (the ignored test below, docs/BENCHMARKS.md "The papers' claims").
    assert!(column < 0.18, "the stored column: indirect NRMSE {column}");
    assert!(median(&frames) < 0.19 && frames.iter().all(|&e| e < 0.41), "indirect NRMSE per frame {frames:?}");
    // The defaults (8 zones of clustered lights, 32 clusters x 8 vectors), bars from their first
    // measurement: 0.206, 0.184, 0.193, 0.451, 0.306, 0.156. Reduced lights stand at their
    // members' mean, farther from a light near the block than the cloud's own.
    assert!(median(&reduced) < 0.23 && reduced.iter().all(|&e| e < 0.50), "by the defaults, indirect NRMSE per frame {reduced:?}");
}

/// Spec light-clouds.md D9 against a converged reference: the stored column (m = 1, the light
/// on a cloud point) with 128 gather paths a vertex against 4,096 samples a pixel. Minutes in
/// a release build (docs/BENCHMARKS.md).
#[test]
#[ignore]
fn a_stored_column_is_within_ten_percent_of_a_converged_reference() {
    let ctx = validated_context();
    let Measured { gathered: frames, reduced, column } = nrmse_along_a_path(&ctx, Effort { gather: 128, reference: 4096 });
    assert_clean(ctx);
    println!("indirect NRMSE per frame {frames:.4?}, by the defaults {reduced:.4?}; one stored column (m = 1, light at a cloud point) {column:.4}");
    assert!(column <= 0.10, "the stored column: indirect NRMSE {column}");
}
