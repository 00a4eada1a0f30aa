//! The light cloud's run time (004 §6) on the GPU against its CPU twin,
//! relume_bake::light_cloud::LightCloud::{cluster_sums, reconstruct}, uncompressed, clustered,
//! in zones and with vectors shared out among clusters, as the lights move; the single draw
//! against the paper's alpha-blended passes; its refusals; all with validation and
//! synchronization validation on.

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::{self as lc, LightCloud, LightCloudBakeSettings, LightCloudSceneSettings};
use relume_bake::scene::{Light, LightKind, Scene};
use relume_bake::testing::spot_light;
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::light_cloud::{LightCloudData, LightCloudTechnique, Visibility};
use relume_renderer::RenderSettings;
use relume_tests::*;
use std::sync::Arc;

/// `cornell-cloud` baked with two gather paths a vertex: enough for a transfer of the right
/// shape with every kind of value.
fn baked() -> (Scene, LightCloud, Visibility) {
    baked_with(1)
}

/// `cornell-cloud` baked with two gather paths a vertex and `emission` functions a cloud light.
fn baked_with(emission: usize) -> (Scene, LightCloud, Visibility) {
    let scene = load_scene("cornell-cloud");
    let bvh = SceneBvh::new(&scene);
    let settings = LightCloudBakeSettings {
        grid: Some(LightCloudSceneSettings::of(&scene).unwrap().grid),
        directions: 0,
        samples: 2,
        emission,
        work: WorkOptions::default(),
    };
    let cloud = lc::bake(&scene, &bvh, &settings).expect("bake");
    (scene, cloud, Arc::new(move |a, b| bvh.visible(a, b)))
}

fn settings() -> RenderSettings {
    RenderSettings { width: 32, height: 32, ..RenderSettings::default() }
}

/// The cluster sums and the per-vertex irradiance the GPU wrote against the CPU's, as the
/// first light moves and turns in four steps; returns the most weights a frame had.
fn gpu_equals_cpu(scene: &Scene, cloud: &LightCloud, visibility: Visibility) -> usize {
    let ctx = validated_context();
    let data = LightCloudData { cloud, nearest: 8, nearest_directions: 3, fade_seconds: 0.0, visibility };
    let mut renderer = new_renderer(&ctx, scene, &settings(), &[&data]);
    let mut lights = scene.lights.clone();
    let (mut previous, mut most): (Option<Vec<Vec3>>, usize) = (None, 0);
    for step in 0..4 {
        lights[0].position = scene.lights[0].position + Vec3::new(0.05 * step as f32, -0.06 * step as f32, 0.03 * step as f32);
        lights[0].direction = (scene.lights[0].direction + Vec3::new(0.1 * step as f32, 0.0, 0.06 * step as f32)).normalize();
        renderer.set_lights(&lights).unwrap();
        render(&mut renderer);
        let weights = renderer.technique_mut::<LightCloudTechnique>().unwrap().weights().to_vec();
        most = most.max(weights.len());
        let isotropic = weights.iter().filter(|w| w.column as usize % cloud.emission == 0);
        let sum = isotropic.fold(Vec3::ZERO, |s, w| s + w.weight);
        // Each zone's weights of the isotropic function sum to the lights' mean intensities.
        let mean = lights.iter().fold(Vec3::ZERO, |s, l| s + l.intensity * lc::emission(l, cloud.emission)[0]);
        let expected = mean * cloud.zone_count() as f32;
        assert!((sum - expected).abs().max_element() < 1e-4 * expected.max_element(), "weights sum to {sum}, not {expected}");
        let (gpu_sums, cpu_sums) = (read_vec4s(&mut renderer, "light_cloud.cluster_sums").unwrap(), cloud.cluster_sums(&weights));
        let gpu = read_vec4s(&mut renderer, "light_cloud.vertex_values").unwrap();
        let cpu = cloud.reconstruct(&weights);
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
    most
}

/// A spot light on cloud lights of 16 emission functions (bands 0 to 3): the weights shared
/// out over the functions by the cone reach the same sums (compression is the same on wider
/// rows, tested above).
#[test]
fn a_spot_light_on_emission_bands_equals_the_cpu_sum_as_it_moves() {
    let (mut scene, cloud, visibility) = baked_with(16);
    scene.lights = vec![spot_light(Vec3::new(0.0, 0.45, -0.28), Vec3::new(0.6, -0.8, 0.0), Vec3::splat(0.4), 0.3, 0.6)];
    gpu_equals_cpu(&scene, &cloud, visibility);
}

/// 32 spot lights on four zones' clouds of 16 emission functions: more weights than one
/// vkCmdUpdateBuffer carries (65,536 bytes: 4,096 weights, refused before), uploaded in pieces,
/// reach the CPU's sums (a scale hall's cloud has tens of thousands of columns).
#[test]
fn more_weights_than_one_update_carries_reach_the_cpu_sum() {
    let (mut scene, cloud, visibility) = baked_with(16);
    let zoned =
        lc::reduce(&scene, &SceneBvh::new(&scene), &cloud, lc::Reduction { zones: 4, weights: None, linkage: lc::Linkage::Complete })
            .unwrap()
            .cloud;
    scene.lights = (0..32)
        .map(|k| {
            // The first light, which the check moves 0.15 to +x, starts at the -x side.
            let turn = std::f32::consts::PI + k as f32 * std::f32::consts::TAU / 32.0;
            let position = Vec3::new(0.2 * turn.cos(), 0.42 + 0.03 * (k % 3) as f32, -0.28 + 0.2 * turn.sin());
            spot_light(position, Vec3::new(-turn.cos(), -0.5, -turn.sin()).normalize(), Vec3::splat(0.02), 0.3, 0.6)
        })
        .collect();
    let most = gpu_equals_cpu(&scene, &zoned, visibility);
    assert!(most > 4096, "the frames had at most {most} weights: one update's worth");
}

#[test]
fn per_vertex_irradiance_equals_the_cpu_sum_as_the_light_moves() {
    let (scene, cloud, visibility) = baked();
    gpu_equals_cpu(&scene, &cloud, Arc::clone(&visibility));
    // CPCA vertex reconstruction: 16 clusters of 4 vectors.
    gpu_equals_cpu(&scene, &lc::compress(&cloud, 16, lc::Vectors::Each(4), false).unwrap(), Arc::clone(&visibility));
    // 4 zones, each with its own clustered lights (004 §4): every cluster weighs its zone's.
    let reduction = lc::Reduction { zones: 4, weights: Some((0.5, 20.0)), linkage: lc::Linkage::Complete };
    let reduced = lc::reduce(&scene, &SceneBvh::new(&scene), &cloud, reduction).unwrap().cloud;
    assert!(reduced.lights.len() < 4 * cloud.lights.len(), "light clustering merged lights");
    gpu_equals_cpu(&scene, &lc::compress(&reduced, 16, lc::Vectors::Each(4), false).unwrap(), Arc::clone(&visibility));
    // Sloan's variable allocation: D_c from cluster to cluster.
    let shared = lc::compress(&reduced, 16, lc::Vectors::Shared(4), false).unwrap();
    assert!(shared.vectors.iter().any(|&d| d != 4), "every cluster kept 4 vectors: {:?}", shared.vectors);
    gpu_equals_cpu(&scene, &shared, visibility);
}

/// A sun on a cloud of directions alone (`sunroom`, 16 directions, no grid), clustered: the GPU
/// against the CPU as the sun turns.
#[test]
fn a_sun_on_the_clouds_directions_gives_what_the_cpu_does() {
    let scene = load_scene("sunroom");
    let bvh = SceneBvh::new(&scene);
    let settings = LightCloudBakeSettings { grid: None, directions: 16, samples: 2, emission: 1, work: WorkOptions::default() };
    let cloud = lc::bake(&scene, &bvh, &settings).expect("bake");
    gpu_equals_cpu(&scene, &lc::compress(&cloud, 8, lc::Vectors::Each(2), false).unwrap(), Arc::new(move |a, b| bvh.visible(a, b)));
}

#[test]
fn directional_lights_another_scenes_cloud_and_a_bad_m_are_refused_by_name() {
    let (scene, cloud, visibility) = baked();
    let ctx = validated_context();
    let data =
        |nearest| LightCloudData { cloud: &cloud, nearest, nearest_directions: 3, fade_seconds: 0.0, visibility: Arc::clone(&visibility) };
    let mut sun = scene.clone();
    sun.lights =
        vec![Light { name: "sun".into(), kind: LightKind::Directional, ..spot_light(Vec3::ZERO, Vec3::NEG_Y, Vec3::ONE, 0.3, 0.5) }];
    says(&refusal(try_new_renderer(&ctx, &sun, &settings(), &[&data(8)])), &["light cloud", "directional light", "no cloud of directions"]);
    says(&refusal(try_new_renderer(&ctx, &scene, &settings(), &[&data(0)])), &["light cloud", "m = 0"]);
    let other = load_scene("cornell");
    let mut point_lit = other.clone();
    point_lit.lights = scene.lights.clone();
    says(&refusal(try_new_renderer(&ctx, &point_lit, &settings(), &[&data(8)])), &["baked for 2535 vertices", "rebake"]);
    assert_clean(ctx);
}

/// The lighting pass's spherical harmonics (shaders/sh.glsl) against the CPU's
/// (relume_bake::sh): a black plane filling the view carries one set of 16 coefficients at
/// every vertex, from one cloud light under the scene's light, so each pixel is
/// max(0, y(towards the camera) . a), a direction per pixel: 4,096 directions within 1e-5 of
/// the largest value.
#[test]
fn the_shaders_spherical_harmonics_equal_the_cpus() {
    use relume_bake::sh;
    use relume_bake::testing::{look_at, material, point_light, scene, square};
    let plane = square(Vec3::ZERO, Vec3::X * 4.0, Vec3::Y * 4.0, 2, 0);
    let camera = look_at(Vec3::new(0.4, -0.3, 1.5), Vec3::new(0.1, 0.1, 0.0), Vec3::Y, 1.4);
    let light = Vec3::new(0.0, 0.0, 0.5);
    let s = scene("sh plane", vec![plane], vec![material("black", Vec3::ZERO, Vec3::ZERO)], vec![point_light(light, Vec3::ONE)], camera);
    let mut state = 99u64;
    let mut next = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    let a: Vec<Vec3> =
        (0..sh::COEFFICIENTS).map(|k| Vec3::new(next(), next(), next()) + Vec3::splat(if k == 0 { 2.0 } else { 0.0 })).collect();
    let row: Vec<f32> = a.iter().flat_map(|c| c.to_array()).collect();
    let vertices = s.meshes[0].positions.len();
    let cloud = LightCloud::uncompressed(vec![light], (sh::COEFFICIENTS, 1), 1, row.repeat(vertices));
    let ctx = validated_context();
    let data = LightCloudData { cloud: &cloud, nearest: 8, nearest_directions: 3, fade_seconds: 0.0, visibility: Arc::new(|_, _| true) };
    let (width, height) = (64, 64);
    let mut renderer = new_renderer(&ctx, &s, &RenderSettings { width, height, ..RenderSettings::default() }, &[&data]);
    let image = render(&mut renderer);
    drop(renderer);
    assert_clean(ctx);
    let expected: Vec<Vec3> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let y_k = sh::eval(-s.camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height));
            a.iter().zip(y_k).fold(Vec3::ZERO, |sum, (a, y)| sum + *a * y).max(Vec3::ZERO)
        })
        .collect();
    let scale = expected.iter().map(|e| e.max_element()).fold(0.0, f32::max);
    let worst = image.pixels.iter().zip(&expected).map(|(g, c)| (*g - *c).abs().max_element()).fold(0.0, f32::max);
    println!("largest difference {worst:.2e} of the largest value {scale:.3}");
    assert!(worst <= 1e-5 * scale, "GPU against CPU spherical harmonics: {worst} (largest value {scale})");
}

/// A glossy scene's transfer (16 spherical harmonics a light) through the same two passes:
/// cluster sums and every vertex's coefficients equal the CPU's as the light moves.
#[test]
fn spherical_harmonic_transfer_equals_the_cpus_as_the_light_moves() {
    let scene = load_scene("glossy-enclosure");
    let bvh = SceneBvh::new(&scene);
    // 2 x 2 x 2 cloud lights over the room: 384 values a vertex keep the test short.
    let grid = lc::CloudGrid { counts: [2; 3], ..LightCloudSceneSettings::of(&scene).unwrap().grid };
    let cloud = lc::bake(
        &scene,
        &bvh,
        &LightCloudBakeSettings { grid: Some(grid), directions: 0, samples: 1, emission: 1, work: WorkOptions::default() },
    )
    .expect("bake");
    assert_eq!(cloud.coefficients, relume_bake::sh::COEFFICIENTS);
    gpu_equals_cpu(&scene, &lc::compress(&cloud, 8, lc::Vectors::Each(4), false).unwrap(), Arc::new(move |a, b| bvh.visible(a, b)));
}

/// The paper's rendering (004 §5, eq. 13) draws every cluster in its own additive pass, its
/// vertices at alpha = 1 and all others at 0, so a triangle across clusters or zones blends.
/// relume draws once, each vertex reconstructed by its own cluster. On the CPU, the paper's
/// passes at every pixel centre (the hit's barycentrics) against the GPU's single draw less
/// its direct light, over pixels away from silhouettes, the triangles across borders counted
/// apart: both within 5e-4 of the image's largest value (first measured: 1.8e-4, at a pixel
/// inside a cluster, where the rasteriser's snapped vertex positions shift the interpolation
/// on a steep gradient; 2.1e-5 across borders). A triangle drawn in its first vertex's
/// cluster alone misses by more than 100 times that bar (2.3 of 3.6 measured): asserted, so
/// the comparison can tell.
#[test]
fn the_single_draw_equals_the_papers_per_cluster_alpha_blended_passes() {
    let (scene, gathered, visibility) = baked();
    let bvh = SceneBvh::new(&scene);
    let cloud = light_cloud_by_defaults(&scene, &bvh, &gathered);
    let (width, height) = (64, 64);
    let size = RenderSettings { width, height, ..RenderSettings::default() };
    let ctx = validated_context();
    let data = LightCloudData { cloud: &cloud, nearest: 8, nearest_directions: 3, fade_seconds: 0.0, visibility };
    let mut lit = new_renderer(&ctx, &scene, &size, &[&data]);
    let single_draw = render(&mut lit);
    let weights = lit.technique_mut::<LightCloudTechnique>().unwrap().weights().to_vec();
    let direct = render(&mut new_renderer(&ctx, &scene, &size, &[]));
    drop(lit);
    assert_clean(ctx);
    let indirect = difference(&single_draw, &direct);

    assert_eq!(cloud.coefficients, 1, "cornell-cloud is diffuse: one coefficient a light");
    let sums = cloud.cluster_sums(&weights);
    let (terms, starts) = (1 + cloud.basis(), cloud.coord_starts());
    // Cluster c's x^m + sum_d b_d z_vd at vertex v (v's coordinates, as far as c has vectors).
    let in_cluster = |c: usize, v: usize| -> Vec3 {
        let z = &cloud.coords[starts[v]..starts[v + 1]];
        z.iter().take(terms - 1).enumerate().fold(sums[c * terms], |a, (d, z)| a + sums[c * terms + d + 1] * *z).max(Vec3::ZERO)
    };
    // Pass c's value at vertex v: alpha_c(v) times that.
    let pass = |c: usize, v: usize| if cloud.assignment[v] as usize == c { in_cluster(c, v) } else { Vec3::ZERO };
    let first_vertex: Vec<usize> = scene.meshes.iter().scan(0, |n, m| Some(std::mem::replace(n, *n + m.positions.len()))).collect();
    let hits = primary_hits(&scene, &bvh, width, height);
    let keep = interior_pixels(&hits, width, height);
    let (mut worst, mut across, mut one_cluster) = ([0.0f32; 2], 0, 0.0f32);
    for ((hit, k), gpu) in hits.iter().zip(&keep).zip(&indirect.pixels) {
        let (Some(hit), true) = (hit, k) else { continue };
        let mesh = &scene.meshes[hit.mesh as usize];
        let corners: Vec<usize> =
            (0..3).map(|i| first_vertex[hit.mesh as usize] + mesh.indices[3 * hit.triangle as usize + i] as usize).collect();
        let b = [1.0 - hit.barycentrics.x - hit.barycentrics.y, hit.barycentrics.x, hit.barycentrics.y];
        let mut clusters: Vec<usize> = corners.iter().map(|&v| cloud.assignment[v] as usize).collect();
        clusters.sort_unstable();
        clusters.dedup();
        let blended =
            clusters.iter().fold(Vec3::ZERO, |sum, &c| sum + corners.iter().zip(b).fold(Vec3::ZERO, |s, (&v, w)| s + pass(c, v) * w));
        let albedo = scene.materials[hit.material as usize].base_color.truncate();
        let border = clusters.len() > 1;
        across += border as usize;
        let error = (*gpu - albedo / std::f32::consts::PI * blended).abs().max_element();
        worst[border as usize] = worst[border as usize].max(error);
        // What drawing the triangle in its first vertex's cluster alone would give.
        let first = cloud.assignment[corners[0]] as usize;
        let drawn_once = corners.iter().zip(b).fold(Vec3::ZERO, |s, (&v, w)| s + in_cluster(first, v) * w);
        one_cluster = one_cluster.max((*gpu - albedo / std::f32::consts::PI * drawn_once).abs().max_element());
    }
    let scale = indirect.pixels.iter().map(|p| p.max_element()).fold(0.0, f32::max);
    println!(
        "{across} pixels on triangles across clusters or zones; largest difference {:.2e} inside, {:.2e} across, of {scale:.3}; {one_cluster:.3} drawing each triangle in one cluster",
        worst[0], worst[1]
    );
    assert!(one_cluster > 100.0 * 5e-4 * scale, "one cluster a triangle would pass too ({one_cluster}): the test cannot tell them apart");
    assert!(across > 100, "only {across} pixels lie on triangles across clusters: the test would prove little");
    assert!(worst[0].max(worst[1]) <= 5e-4 * scale, "single draw against the alpha-blended passes: {worst:?} (largest value {scale})");
}
