//! The light cloud's run time (004 §6) on the GPU against its CPU twin,
//! relume_bake::light_cloud::LightCloud::{cluster_sums, irradiance}, uncompressed, clustered
//! and in zones, as the lights move; its refusals; all with validation and synchronization
//! validation on.

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::{self as lc, LightCloud, LightCloudBakeSettings, LightCloudSceneSettings};
use relume_bake::scene::Scene;
use relume_bake::testing::spot_light;
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::light_cloud::{LightCloudData, LightCloudTechnique, Visibility};
use relume_renderer::RenderSettings;
use relume_tests::*;
use std::sync::Arc;

/// `cornell-cloud` baked with two gather paths a vertex: enough for a transfer of the right
/// shape with every kind of value.
fn baked() -> (Scene, LightCloud, Visibility) {
    let scene = load_scene("cornell-cloud");
    let bvh = SceneBvh::new(&scene);
    let settings =
        LightCloudBakeSettings { grid: LightCloudSceneSettings::of(&scene).unwrap().grid, samples: 2, work: WorkOptions::default() };
    let cloud = lc::bake(&scene, &bvh, &settings).expect("bake");
    (scene, cloud, Arc::new(move |a, b| bvh.visible(a, b)))
}

fn settings() -> RenderSettings {
    RenderSettings { width: 32, height: 32, ..RenderSettings::default() }
}

/// The cluster sums and the per-vertex irradiance the GPU wrote against the CPU's, as the
/// light moves in four steps.
fn gpu_equals_cpu(scene: &Scene, cloud: &LightCloud, visibility: Visibility) {
    let ctx = validated_context();
    let data = LightCloudData { cloud, nearest: 8, fade_seconds: 0.0, visibility };
    let mut renderer = new_renderer(&ctx, scene, &settings(), &[&data]);
    let mut lights = scene.lights.clone();
    let mut previous: Option<Vec<Vec3>> = None;
    for step in 0..4 {
        lights[0].position = scene.lights[0].position + Vec3::new(0.05 * step as f32, -0.06 * step as f32, 0.03 * step as f32);
        renderer.set_lights(&lights).unwrap();
        render(&mut renderer);
        let weights = renderer.technique_mut::<LightCloudTechnique>().unwrap().weights().to_vec();
        let sum = weights.iter().fold(Vec3::ZERO, |s, w| s + w.weight);
        // Each zone's weights sum to the light's intensity.
        let expected = lights[0].intensity * cloud.zone_count() as f32;
        assert!((sum - expected).abs().max_element() < 1e-4 * expected.max_element(), "weights sum to {sum}");
        let (gpu_sums, cpu_sums) = (read_vec4s(&mut renderer, "light_cloud.cluster_sums").unwrap(), cloud.cluster_sums(&weights));
        let gpu = read_vec4s(&mut renderer, "light_cloud.irradiance").unwrap();
        let cpu = cloud.irradiance(&weights);
        assert_eq!((gpu.len(), gpu_sums.len()), (cpu.len(), cpu_sums.len()));
        let largest = |values: &[Vec3]| values.iter().map(|e| e.abs().max_element()).fold(0.0, f32::max);
        let (scale, sums_scale) = (largest(&cpu), largest(&cpu_sums));
        assert!(scale > 0.0, "no indirect light at all");
        for (t, (g, c)) in gpu_sums.iter().zip(&cpu_sums).enumerate() {
            assert!((g.truncate() - *c).abs().max_element() <= 1e-5 * sums_scale, "step {step}, term {t}: GPU {g}, CPU {c}");
        }
        for (v, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
            assert!((g.truncate() - *c).abs().max_element() <= 1e-5 * scale, "step {step}, vertex {v}: GPU {g}, CPU {c}");
        }
        assert_ne!(previous.as_ref(), Some(&cpu), "step {step}: the light moved and the irradiance did not");
        previous = Some(cpu);
    }
    drop(renderer);
    assert_clean(ctx);
}

#[test]
fn per_vertex_irradiance_equals_the_cpu_sum_as_the_light_moves() {
    let (scene, cloud, visibility) = baked();
    gpu_equals_cpu(&scene, &cloud, Arc::clone(&visibility));
    // CPCA vertex reconstruction: 16 clusters of 4 vectors.
    gpu_equals_cpu(&scene, &lc::compress(&cloud, 16, 4).unwrap(), Arc::clone(&visibility));
    // 4 zones, each with its own clustered lights (004 §4): every cluster weighs its zone's.
    let reduction = lc::Reduction { zones: 4, weights: Some((0.5, 20.0)) };
    let reduced = lc::reduce(&scene, &SceneBvh::new(&scene), &cloud, reduction).unwrap().cloud;
    assert!(reduced.lights.len() < 4 * cloud.lights.len(), "light clustering merged lights");
    gpu_equals_cpu(&scene, &lc::compress(&reduced, 16, 4).unwrap(), visibility);
}

#[test]
fn spot_lights_another_scenes_cloud_and_a_bad_m_are_refused_by_name() {
    let (scene, cloud, visibility) = baked();
    let ctx = validated_context();
    let data = |nearest| LightCloudData { cloud: &cloud, nearest, fade_seconds: 0.0, visibility: Arc::clone(&visibility) };
    let mut spot = scene.clone();
    spot.lights = vec![spot_light(Vec3::new(0.0, 0.5, -0.3), Vec3::NEG_Y, Vec3::ONE, 0.3, 0.5)];
    says(&refusal(try_new_renderer(&ctx, &spot, &settings(), &[&data(8)])), &["light cloud", "spot light", "point lights only"]);
    says(&refusal(try_new_renderer(&ctx, &scene, &settings(), &[&data(0)])), &["light cloud", "m = 0"]);
    let other = load_scene("cornell");
    let mut point_lit = other.clone();
    point_lit.lights = scene.lights.clone();
    says(&refusal(try_new_renderer(&ctx, &point_lit, &settings(), &[&data(8)])), &["baked for 2535 vertices", "rebake"]);
    assert_clean(ctx);
}
