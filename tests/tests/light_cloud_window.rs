//! 004's Window scene (`cornell-window`, Fig. 7): a point light carried at 60 frames a second
//! from the yard through the window into the room, and one sliding past the window 2 cm in
//! front of the 2 cm wall (spec light-clouds.md's "light beside a thin wall"). As it passes,
//! the cloud lights it sees change at once. Each frame's indirect part (the frame less the
//! direct-only frame) against the reference's: no NaN, and popping (`metrics::flicker`: the
//! frame-to-frame change the reference lacks) under bars from the first measurement, without
//! the fade (the default) and, reported, with cloud lights fading in and out over 0.25 s
//! (spec B5).

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::light_cloud::{self as lc, LightCloud, LightCloudBakeSettings, LightCloudSceneSettings};
use relume_bake::metrics;
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::light_cloud::LightCloudData;
use relume_renderer::RenderSettings;
use relume_tests::*;
use std::sync::Arc;

const SIZE: u32 = 48;
/// Moves of 1/60 s between the frames compared: 0.1 s.
const MOVES_PER_FRAME: usize = 6;

/// Per frame along the path (the light's 72 moves in 1.2 s), the largest flicker with the
/// fade and without it.
fn flicker_along(scene: &Scene, cloud: &LightCloud, bvh: &Arc<SceneBvh>, from: Vec3, to: Vec3) -> (Vec<f64>, Vec<f64>) {
    let data = |fade_seconds| {
        let bvh = Arc::clone(bvh);
        LightCloudData { cloud, nearest: 8, nearest_directions: 3, fade_seconds, visibility: Arc::new(move |a, b| bvh.visible(a, b)) }
    };
    let settings = RenderSettings { width: SIZE, height: SIZE, shadow_map_size: 256, ..RenderSettings::default() };
    let reference =
        ReferenceSettings { samples_per_pixel: 256, width: SIZE, height: SIZE, pixel_centres: true, ..ReferenceSettings::default() };
    let ctx = validated_context();
    let (faded, unfaded) = (data(0.25), data(0.0));
    let mut renderers = [new_renderer(&ctx, scene, &settings, &[&faded]), new_renderer(&ctx, scene, &settings, &[&unfaded])];
    let mut direct = new_renderer(&ctx, scene, &settings, &[]);
    let mut moved = scene.clone();
    let mut previous: Option<([Image; 2], Image)> = None;
    let mut flicker = (Vec::new(), Vec::new());
    for step in 0..=12 * MOVES_PER_FRAME {
        moved.lights[0].position = from.lerp(to, step as f32 / (12 * MOVES_PER_FRAME) as f32);
        // The path's start is a cut; from there the light moves.
        match step {
            0 => renderers.iter_mut().for_each(|r| r.set_lights(&moved.lights).unwrap()),
            _ => renderers.iter_mut().for_each(|r| r.move_lights(&moved.lights, 1.0 / 60.0).unwrap()),
        }
        if step % MOVES_PER_FRAME != 0 {
            continue;
        }
        direct.set_lights(&moved.lights).unwrap();
        let only_direct = render(&mut direct);
        let frames = renderers.each_mut().map(|r| difference(&render(r), &only_direct));
        assert!(frames.iter().all(|f| f.pixels.iter().all(|p| p.is_finite())), "step {step}: a NaN or infinity");
        let truth = render_reference(&moved, bvh, &reference).indirect;
        if let Some((before, truth_before)) = &previous {
            flicker.0.push(metrics::flicker(&before[0], &frames[0], truth_before, &truth));
            flicker.1.push(metrics::flicker(&before[1], &frames[1], truth_before, &truth));
        }
        previous = Some((frames, truth));
    }
    drop((renderers, direct));
    assert_clean(ctx);
    flicker
}

#[test]
fn a_light_through_and_past_the_window_pops_no_more_than_first_measured() {
    let scene = load_scene("cornell-window");
    let bvh = SceneBvh::new(&scene);
    let grid = LightCloudSceneSettings::of(&scene).unwrap().grid;
    let gathered = lc::bake(
        &scene,
        &bvh,
        &LightCloudBakeSettings { grid: Some(grid), directions: 0, samples: 16, emission: 1, work: WorkOptions::default() },
    )
    .expect("bake");
    let cloud = light_cloud_by_defaults(&scene, &bvh, &gathered);
    let bvh = Arc::new(bvh);
    let largest = |f: &[f64]| f.iter().copied().fold(0.0, f64::max);
    // Through the window's middle: from 25 cm behind the wall to 30 cm into the room.
    let (faded, unfaded) = flicker_along(&scene, &cloud, &bvh, Vec3::new(0.0, 0.42, -0.83), Vec3::new(0.0, 0.42, -0.26));
    println!("through the window: flicker {faded:.3?} with the fade, {unfaded:.3?} without");
    let through = (largest(&faded), largest(&unfaded));
    // Past it, 2 cm in front of the wall, from one side wall to the other.
    let (faded, unfaded) = flicker_along(&scene, &cloud, &bvh, Vec3::new(-0.25, 0.42, -0.539), Vec3::new(0.25, 0.42, -0.539));
    println!("past the window: flicker {faded:.3?} with the fade, {unfaded:.3?} without");
    let past = (largest(&faded), largest(&unfaded));
    println!(
        "largest flicker through the window {:.3} with the fade, {:.3} without; past it {:.3}, {:.3}",
        through.0, through.1, past.0, past.1
    );
    // Bars from the first measurement (16 gather paths, 256 reference samples, 48 x 48): 0.276
    // through the window (the true light changes at once as the light crosses the wall: the
    // fade lags it, 0.320), 0.421 past it (0.421 with the fade, which moves no frame's flicker
    // there by more than 0.02).
    assert!(through.1 < 0.31 && past.1 < 0.46, "largest flicker through the window {}, past it {}", through.1, past.1);
}
