//! The light path maps' transfer (Umenhoffer et al. §3.2.1-3.2.2) against the path tracer,
//! with nothing else in the way: no compression (every T_e kept), no short-connection cut
//! (threshold 0, so the transfer must carry every path of two or more bounces), and the
//! entry points' true irradiance (ray-traced visibility, no shadow map). The indirect
//! irradiance sum_e I_e T_e is shown through the obscurance model with the lights off,
//! I_A = 1 and W = that irradiance, which renders exactly albedo / pi * I: the reference's
//! `indirect` layer. 256 test points over the scene's region keep the entry-point weights
//! 1 / d(e) even.

use glam::Vec3;
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::light_path_maps::{
    bake_transfers, entry_irradiance, entry_points, test_points, LightPathMapSettings, LightPathMapsSceneSettings, LightRegion,
};
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::Scene;
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::RenderSettings;
use relume_tests::*;

const SIZE: u32 = 128;
const TEST_POINTS: u32 = 256;

/// The indirect radiance image the transfer predicts for the scene's own lights.
fn transfer_indirect(scene: &Scene, entries_wanted: u32, walks: u32) -> Image {
    let atlas = Atlas::build(scene, &AtlasSettings { texel_density: 48.0, ..Default::default() }).unwrap();
    let bvh = SceneBvh::new(scene);
    let region = match LightPathMapsSceneSettings::of(scene).unwrap().region {
        Some(LightRegion::Box { min, max, .. }) => LightRegion::Box { min, max, test_points: TEST_POINTS },
        other => other.unwrap(),
    };
    let tests = test_points(scene, Some(&region), 0).unwrap();
    let entries = entry_points(scene, &bvh, tests, entries_wanted, 0).unwrap();
    let settings = LightPathMapSettings { walks, ..LightPathMapSettings::new(entries_wanted, 0.0) };
    let transfers = bake_transfers(scene, &bvh, &atlas, &entries.entries, &settings).unwrap();
    println!(
        "{} entry points, {} texels, {} virtual lights, {} connections in {:.1} s",
        entries.entries.len(),
        transfers.texels.len(),
        transfers.virtual_lights,
        transfers.connections,
        transfers.seconds
    );
    let irradiance: Vec<Vec3> =
        entries.entries.iter().map(|e| scene.lights.iter().map(|l| entry_irradiance(&bvh, l, &e.point, 0.0)).sum()).collect();
    let indirect = transfers.irradiance(&irradiance, atlas.texels.len());
    let texels: Vec<_> = atlas.with_coverage(&indirect);
    let obscurance = ObscuranceData { obscurance: atlas_image(&atlas, &texels) };
    let mut unlit = scene.clone();
    unlit.lights.clear();
    atlas.apply_to(&mut unlit);
    let settings = RenderSettings { width: SIZE, height: SIZE, ambient: Vec3::ONE, beta: 0.0, ..RenderSettings::default() };
    let ctx = validated_context();
    let image = render(&mut new_renderer(&ctx, &unlit, &settings, &[&obscurance]));
    assert_clean(ctx);
    image
}

#[test]
fn uncompressed_transfer_reproduces_the_reference_indirect_light_on_cornell() {
    let scene = load_scene("cornell");
    let region = LightPathMapsSceneSettings::of(&scene).unwrap().region.expect("cornell declares a light region");
    assert!(scene.lights.iter().all(|l| region.contains(l.position, 0.0)), "the test light must be inside the region");
    let reference = render_reference(
        &scene,
        &SceneBvh::new(&scene),
        &ReferenceSettings { samples_per_pixel: 512, width: SIZE, height: SIZE, pixel_centres: true, ..ReferenceSettings::default() },
    );
    // Many entry points with one walk each beat fewer with several walks: the first bounce
    // near a corner is what a virtual light misses, and only more entry points sample it
    // (docs/BENCHMARKS.md: E = 1,024 x 4 walks gives 0.16, 4,096 x 1 0.10, 8,192 x 1 0.089).
    let image = transfer_indirect(&scene, 8192, 1);
    let nrmse = nrmse_with_artifacts("light_path_maps_transfer", &image, &reference.indirect);
    let scale = relume_bake::metrics::best_scale(&Image::new(SIZE, SIZE), &image, &reference.indirect).unwrap();
    println!("uncompressed transfer vs reference indirect: NRMSE {nrmse:.4} (best scale {scale:.3})");
    assert!(nrmse <= 0.10, "NRMSE {nrmse:.4} > 0.10");
}
