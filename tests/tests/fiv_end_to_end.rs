//! FIV end to end on the shipped `fiv-blobs` scene (003 Fig. 12's stand-in): baked at the
//! paper's two smaller grids, rendered on the GPU, and compared over the ground's pixels with the
//! exact direct light of the same working cube (the reference's `direct` layer without its
//! noise: albedo / pi times the traced quadrature at each pixel's ground point, spec fiv.md
//! B12-B13).

use relume_bake::bvh::SceneBvh;
use relume_bake::fiv::{bake, occluder_types, occluders, FivBakeSettings, FivSceneSettings, Grid, SumOptions};
use relume_bake::image::Image;
use relume_bake::metrics::compare_masked;
use relume_bake::reference::environment_irradiance;
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::fiv::FivData;
use relume_renderer::RenderSettings;
use relume_tests::*;
use std::f32::consts::PI;

const SIZE: u32 = 96;

#[test]
fn ground_error_against_the_exact_direct_light_falls_as_the_grid_grows() {
    let scene = load_scene("fiv-blobs");
    let bvh = SceneBvh::new(&scene);
    let hits = primary_hits(&scene, &bvh, SIZE, SIZE);
    let ground = scene.meshes.iter().position(|m| m.name == "Ground").expect("a ground");
    let interior = interior_pixels(&hits, SIZE, SIZE);
    let mask: Vec<bool> = hits.iter().zip(&interior).map(|(h, inside)| *inside && h.is_some_and(|h| h.mesh as usize == ground)).collect();
    assert!(mask.iter().filter(|m| **m).count() > (SIZE * SIZE / 3) as usize, "too few ground pixels");
    let albedo = scene.materials[scene.meshes[ground].material].base_color.truncate();
    let mut exact = Image::new(SIZE, SIZE);
    for (pixel, hit) in hits.iter().enumerate() {
        if mask[pixel] {
            let hit = hit.expect("a ground hit");
            exact.pixels[pixel] = albedo / PI * environment_irradiance(&scene, &bvh, hit.position, hit.geometric_normal, 1);
        }
    }
    let types = occluder_types(&scene, &FivSceneSettings::of(&scene).unwrap()).unwrap();
    let ctx = validated_context();
    let settings = RenderSettings { width: SIZE, height: SIZE, ..RenderSettings::default() };
    let mut errors = Vec::new();
    for grid in ["32x17x15", "64x33x30"] {
        let bake_settings = FivBakeSettings {
            grid: Grid::parse(grid).unwrap(),
            distance_min: 0.1,
            distance_max: 16.0,
            mask_supersample: 1,
            difmap_width: 128,
        };
        let (fiv, _) = bake(&scene, &bake_settings, &WorkOptions::default()).unwrap();
        let data = FivData { bake: &fiv, occluders: &occluders(&scene, &types), options: SumOptions::default() };
        let image = render(&mut new_renderer(&ctx, &scene, &settings, &[&data]));
        let nrmse = compare_masked(&image, &exact, &mask).unwrap().nrmse;
        println!("{grid}: ground NRMSE {nrmse:.4}");
        errors.push(nrmse);
    }
    assert_clean(ctx);
    // Bars 10 % over the first honest measurement (0.0283 and 0.0189, docs/BENCHMARKS.md
    // "FIV"), next to the paper's 0.023 and 0.008 on its bunny under a softer probe.
    assert!(errors[0] < 0.031, "32x17x15: {}", errors[0]);
    assert!(errors[1] < 0.021, "64x33x30: {}", errors[1]);
    assert!(errors[1] < errors[0], "the error does not fall with the grid: {errors:?}");
}
