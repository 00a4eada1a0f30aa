//! End to end on `cornell` (Umenhoffer et al. 2008, whole): bake the spectral obscurance and
//! the light path maps at the paper's sizes (4,096 entry points, 32 clusters, 2 eigen-textures,
//! short connections below L_max dropped), then move the spot light along a closed path of 32
//! positions inside the region the scene declares and render every position with the Vulkan
//! renderer, relit each frame without a re-bake. Each frame is compared with the reference
//! path tracer's `combined` layer at the same light; so is obscurance-only ambient (Iones et
//! al. 2003 with the scene's I_A and beta), which the method must beat at every position.
//! Four positions outside the region measure how the method degrades there: it must still
//! render finite images that beat direct light alone.

use glam::{Vec3, Vec4};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::light_path_maps::ClusteredTransfer;
use relume_bake::light_path_maps::{bake_transfers, compress, entry_points, test_points, Compression, LightPathMapSettings};
use relume_bake::light_path_maps::{LightPathMapsSceneSettings, LightRegion};
use relume_bake::metrics;
use relume_bake::obscurance::ObscuranceSceneSettings;
use relume_bake::obscurance::{bake_obscurance, ObscuranceSettings, Variant};
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::{Light, Scene};
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::light_path_maps::{Composition, LightPathMapsData};
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::vk::Context;
use relume_renderer::{Headless, RenderSettings};
use relume_tests::*;
use std::sync::Arc;

const SIZE: u32 = 64;
const SAMPLES: u32 = 256;
const PATH_POSITIONS: usize = 32;

/// What the bake leaves for the renderer: the scene with uv1, the spectral obscurance (for the
/// light path maps) and the plain obscurance (for the baseline), both with coverage in alpha,
/// and the compressed transfer.
struct Bake {
    scene: Scene,
    atlas: Atlas,
    spectral: Vec<Vec4>,
    obscurance: Vec<Vec4>,
    transfer: ClusteredTransfer,
}

fn bake_obscurance_texels(scene: &Scene, bvh: &SceneBvh, atlas: &Atlas, variant: Variant) -> Vec<Vec4> {
    let settings = ObscuranceSettings {
        variant,
        tau: ObscuranceSceneSettings::of(scene).unwrap().tau,
        l_max: ObscuranceSceneSettings::of(scene).unwrap().l_max,
        rays_per_texel: 256,
        work: WorkOptions { ..WorkOptions::default() },
    };
    let map = bake_obscurance(scene, bvh, atlas, &settings).unwrap();
    atlas.with_coverage(&map.values)
}

/// The bake of docs/BENCHMARKS.md's light path maps table: a 128-texel atlas of about 7,000
/// patches, E = 4,096 from the scene's 64 test points, one walk, threshold L_max, C 32, D 2.
fn bake(scene: &Scene) -> Bake {
    let atlas = Atlas::build_for_patch_count(scene, &AtlasSettings { max_size: 128, ..AtlasSettings::default() }, 7000).unwrap();
    let bvh = SceneBvh::new(scene);
    let tests = test_points(scene, LightPathMapsSceneSettings::of(scene).unwrap().region.as_ref(), 0).unwrap();
    let entries = entry_points(scene, &bvh, tests, 4096, 0).unwrap();
    let settings = LightPathMapSettings::new(4096, ObscuranceSceneSettings::of(scene).unwrap().l_max);
    let transfers = bake_transfers(scene, &bvh, &atlas, &entries.entries, &settings).unwrap();
    let compressed = compress(
        &transfers,
        &entries.entries,
        atlas.texels.len(),
        LightPathMapsSceneSettings::of(scene).unwrap().light_area,
        Compression::Fixed { clusters: 32, basis: 2 },
    )
    .unwrap();
    println!(
        "bake: {} entry points, {} texels, C {} D {}, relative error of the transfers {:.3}",
        entries.entries.len(),
        transfers.texels.len(),
        compressed.clusters,
        compressed.basis,
        compressed.relative_error
    );
    let mut applied = scene.clone();
    atlas.apply_to(&mut applied);
    Bake {
        spectral: bake_obscurance_texels(scene, &bvh, &atlas, Variant::Spectral),
        obscurance: bake_obscurance_texels(scene, &bvh, &atlas, Variant::Obscurance),
        scene: applied,
        atlas,
        transfer: compressed.transfer,
    }
}

/// A closed path through the region box: once around its middle in x and z while rising and
/// falling twice through 80% of its height.
fn path_inside(min: Vec3, max: Vec3) -> Vec<Vec3> {
    let (centre, half) = ((min + max) * 0.5, (max - min) * 0.5 * 0.8);
    (0..PATH_POSITIONS)
        .map(|i| {
            let t = std::f32::consts::TAU * i as f32 / PATH_POSITIONS as f32;
            centre + half * Vec3::new(t.cos(), (2.0 * t).sin(), t.sin())
        })
        .collect()
}

/// Positions the bake did not plan for: low between the blocks, against the red wall, at the
/// back by the green wall, and at ceiling height by the open front.
fn positions_outside() -> [Vec3; 4] {
    [Vec3::new(0.0, 0.2, -0.25), Vec3::new(-0.22, 0.3, -0.1), Vec3::new(0.2, 0.35, -0.48), Vec3::new(0.0, 0.47, -0.04)]
}

fn with_light_at(lights: &[Light], position: Vec3) -> Vec<Light> {
    lights.iter().map(|l| Light { position, ..l.clone() }).collect()
}

/// NRMSE of one image against the reference's `combined`, and of its indirect part (the
/// image minus the direct-only frame) against the reference's `indirect`.
#[derive(Clone, Copy)]
struct Error {
    combined: f64,
    indirect: f64,
}

/// One light position's errors.
struct Row {
    position: Vec3,
    direct: f64,
    obscurance: Error,
    /// One per [`Composition::ALL`].
    light_path_maps: [Error; 3],
}

/// The renderers of the comparison on one context: direct light only, obscurance ambient, and
/// light path maps (composition switched per frame).
struct Renderers {
    direct: Headless,
    obscurance: Headless,
    light_path_maps: Headless,
}

fn frame(renderer: &mut Headless, lights: &[Light]) -> Image {
    renderer.set_lights(lights).unwrap();
    renderer.render_and_read().unwrap().0
}

impl Renderers {
    fn new(ctx: &Arc<Context>, scene: &Scene, bake: &Bake) -> Renderers {
        let settings = RenderSettings { width: SIZE, height: SIZE, ..RenderSettings::default() };
        let ambient = RenderSettings { ambient: scene.settings.ambient, beta: scene.settings.beta, ..settings.clone() };
        let obscurance = ObscuranceData { obscurance: atlas_image(&bake.atlas, &bake.obscurance) };
        let spectral = atlas_image(&bake.atlas, &bake.spectral);
        let maps = LightPathMapsData { transfer: &bake.transfer, atlas: spectral, composition: Composition::default() };
        Renderers {
            direct: new_renderer(ctx, scene, &settings, &[]),
            obscurance: new_renderer(ctx, &bake.scene, &ambient, &[&obscurance]),
            light_path_maps: new_renderer(ctx, &bake.scene, &settings, &[&ObscuranceData { obscurance: spectral }, &maps]),
        }
    }

    fn row(&mut self, scene: &Scene, bvh: &SceneBvh, position: Vec3, name: &str) -> Row {
        let lights = with_light_at(&scene.lights, position);
        let mut moved = scene.clone();
        moved.lights = lights.clone();
        let settings = ReferenceSettings {
            samples_per_pixel: SAMPLES,
            width: SIZE,
            height: SIZE,
            pixel_centres: true,
            ..ReferenceSettings::default()
        };
        let reference = render_reference(&moved, bvh, &settings);
        let direct = frame(&mut self.direct, &lights);
        let error = |image: &Image, label: &str| Error {
            combined: nrmse_with_artifacts(&format!("light_path_maps_end_to_end/{name}_{label}"), image, &reference.combined),
            indirect: metrics::compare(&difference(image, &direct), &reference.indirect).unwrap().nrmse,
        };
        let obscurance = error(&frame(&mut self.obscurance, &lights), "obscurance");
        let light_path_maps = Composition::ALL.map(|composition| {
            set_composition(&mut self.light_path_maps, composition);
            error(&frame(&mut self.light_path_maps, &lights), &format!("light_path_maps_{composition:?}"))
        });
        Row { position, direct: error(&direct, "direct").combined, obscurance, light_path_maps }
    }
}

fn print_table(title: &str, rows: &[Row]) {
    println!("{title} (NRMSE of the image vs `combined` / of its indirect part vs `indirect`)");
    println!("| light position | direct only | obscurance ambient | LPM plain | LPM x W (default) | LPM x W with direct |\n|---|---|---|---|---|---|");
    let cell = |e: Error| format!("{:.4} / {:.4}", e.combined, e.indirect);
    for r in rows {
        let p = r.position;
        println!(
            "| {:.3}, {:.3}, {:.3} | {:.4} | {} | {} |",
            p.x,
            p.y,
            p.z,
            r.direct,
            cell(r.obscurance),
            r.light_path_maps.map(cell).join(" | ")
        );
    }
    let mean = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).sum::<f64>() / rows.len() as f64;
    let mean_error = |f: &dyn Fn(&Row) -> Error| Error { combined: mean(&|r| f(r).combined), indirect: mean(&|r| f(r).indirect) };
    let light_path_maps_means: Vec<String> = (0..3).map(|i| cell(mean_error(&|r| r.light_path_maps[i]))).collect();
    println!("| mean | {:.4} | {} | {} |", mean(&|r| r.direct), cell(mean_error(&|r| r.obscurance)), light_path_maps_means.join(" | "));
}

#[test]
fn light_path_maps_beat_obscurance_ambient_along_a_light_path_on_cornell() {
    let scene = load_scene("cornell");
    let Some(LightRegion::Box { min, max, .. }) = LightPathMapsSceneSettings::of(&scene).unwrap().region else {
        panic!("cornell declares a light region box")
    };
    let region = LightPathMapsSceneSettings::of(&scene).unwrap().region.unwrap();
    let bake = bake(&scene);
    let bvh = SceneBvh::new(&scene);
    let default_mode = Composition::ALL.iter().position(|c| *c == Composition::default()).unwrap();

    let ctx = validated_context();
    let mut renderers = Renderers::new(&ctx, &scene, &bake);
    let inside: Vec<Row> =
        path_inside(min, max).into_iter().enumerate().map(|(i, p)| renderers.row(&scene, &bvh, p, &format!("inside_{i:02}"))).collect();
    let outside: Vec<Row> = positions_outside()
        .into_iter()
        .enumerate()
        .map(|(i, p)| {
            assert!(!region.contains(p, 0.0), "{p} is meant to be outside the region");
            renderers.row(&scene, &bvh, p, &format!("outside_{i}"))
        })
        .collect();
    drop(renderers);
    assert_clean(ctx);

    print_table(&format!("NRMSE vs reference combined, {SIZE}x{SIZE}, {SAMPLES} spp, inside the region:"), &inside);
    print_table("outside the region:", &outside);
    for r in &inside {
        let (light_path_maps, obscurance) = (r.light_path_maps[default_mode].combined, r.obscurance.combined);
        assert!(
            light_path_maps < obscurance,
            "light at {}: light path maps {light_path_maps:.4} do not beat obscurance ambient {obscurance:.4}",
            r.position
        );
    }
    for r in &outside {
        let light_path_maps = r.light_path_maps[default_mode].combined;
        assert!(
            light_path_maps < r.direct,
            "light at {} (outside the region): light path maps {light_path_maps:.4} are worse than direct light alone {:.4}",
            r.position,
            r.direct
        );
    }
}
