//! Modular radiance transfer end to end with validation on, on `mrt-maze` (11 blocks, a cycle)
//! and `mrt-cave` (19 warped blocks, four lights): the quick level (tests/src/lib.rs) rendered
//! by the Vulkan renderer as a light moves through the level, relit every frame without a
//! re-bake. Each frame's indirect part (the frame
//! less the direct-only frame) is compared with the reference path tracer's `indirect` layer
//! at the same light, and with the best constant ambient light (the constant method's, its
//! ambient fitted to that reference by least squares). On `mrt-figures`, the two figures' pixels
//! alone: lit by the light volume (§6.5) against mapped onto the blocks' faces (002 Fig. 5).

use glam::{Mat4, Vec3};
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::Scene;
use relume_renderer::techniques::mrt::MrtData;
use relume_renderer::RenderSettings;
use relume_tests::*;

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

fn reference_indirect(scene: &Scene) -> Image {
    let settings =
        ReferenceSettings { samples_per_pixel: 2048, width: WIDTH, height: HEIGHT, pixel_centres: true, ..ReferenceSettings::default() };
    render_reference(scene, &SceneBvh::new(scene), &settings).indirect
}

/// `shape` scaled by the least-squares factor against `reference` over the pixels `mask`
/// marks (every pixel: None).
fn best_scaled(shape: &Image, reference: &Image, mask: Option<&[bool]>) -> Image {
    let kept = |i: usize| mask.is_none_or(|m| m[i]);
    let dot = |a: &Image, b: &Image| {
        a.pixels.iter().zip(&b.pixels).enumerate().filter(|(i, _)| kept(*i)).map(|(_, (x, y))| x.dot(*y) as f64).sum::<f64>()
    };
    let s = (dot(shape, reference) / dot(shape, shape)) as f32;
    Image { width: shape.width, height: shape.height, pixels: shape.pixels.iter().map(|p| *p * s).collect() }
}

/// The scene's camera moved by 2-3 mm: the maze's edges lie on round coordinates, and at the
/// scene's own camera some project exactly onto a pixel centre, where the rasteriser's tie rule
/// and the path tracer's can pick different surfaces (one pixel off by the whole direct light).
fn off_the_ties(scene: &mut Scene) {
    scene.camera.world_from_camera = Mat4::from_translation(Vec3::new(0.0011, 0.0013, 0.0017)) * scene.camera.world_from_camera;
}

/// Checks MRT's indirect NRMSE per frame, as light 0 of scene `name` visits `path`, against
/// `bar` and a third of the best constant's, for each variant (derived, bar): on the scene's
/// declared proxy, or on the one derived from it; the references traced once, for the first.
fn along_path(name: &str, path: &[Vec3], variants: &[(bool, f64)]) {
    let mut references = Vec::new();
    for &(derived, bar) in variants {
        along_path_with(name, path, bar, derived, &mut references);
    }
}

fn along_path_with(name: &str, path: &[Vec3], bar: f64, derived: bool, references: &mut Vec<Image>) {
    let scene = load_scene(name);
    let (dictionary, _, level, mut applied) = if derived { mrt_quick_bake_derived(&scene) } else { mrt_quick_bake(&scene) };
    off_the_ties(&mut applied);
    let ctx = validated_context();
    let settings = RenderSettings { width: WIDTH, height: HEIGHT, ..RenderSettings::default() };
    let data = MrtData { dictionary: &dictionary, level: &level, feedback: true };
    let mut with_mrt = new_renderer(&ctx, &applied, &settings, &[&data]);
    let mut direct = new_renderer(&ctx, &applied, &settings, &[]);
    let mut ambient = new_renderer(&ctx, &applied, &RenderSettings { ambient: Vec3::ONE, beta: 0.0, ..settings.clone() }, &[]);
    let (mut errors, mut constants) = (Vec::new(), Vec::new());
    for (k, position) in path.iter().enumerate() {
        let mut moved = applied.clone();
        moved.lights[0].position = *position;
        for renderer in [&mut with_mrt, &mut direct, &mut ambient] {
            renderer.set_lights(&moved.lights).unwrap();
        }
        let only_direct = render(&mut direct);
        let image = difference(&render(&mut with_mrt), &only_direct);
        let constant = difference(&render(&mut ambient), &only_direct);
        if references.len() <= k {
            references.push(reference_indirect(&moved));
        }
        let reference = &references[k];
        let id = format!("{}{}", name.replace('-', "_"), if derived { "_derived" } else { "" });
        errors.push(nrmse_with_artifacts(&format!("{id}_path_{k}"), &image, reference));
        constants.push(nrmse_with_artifacts(&format!("{id}_path_constant_{k}"), &best_scaled(&constant, reference, None), reference));
    }
    eprintln!("{name} indirect NRMSE along the light path (derived proxy: {derived}): MRT {errors:.3?}, best constant {constants:.3?}");
    drop((with_mrt, direct, ambient));
    assert_clean(ctx);
    for (k, (e, c)) in errors.iter().zip(&constants).enumerate() {
        assert!(*e < bar && *e < c / 3.0, "{name} frame {k}: MRT {e:.3}, the best constant ambient {c:.3}");
    }
}

#[test]
fn indirect_light_along_a_light_path_through_the_maze_follows_the_reference_and_beats_constant_ambient() {
    // Along the first row of blocks and round into the third (cells of 2 m).
    let path = [Vec3::new(1.0, 1.4, 1.0), Vec3::new(5.0, 1.4, 1.2), Vec3::new(7.0, 1.4, 3.0)];
    // The bar from the first honest measurement (0.091, 0.056, 0.057 against the best
    // constant's 0.814, 0.425, 0.330; the reference alone is about 0.05 from a converged one).
    along_path("mrt-maze", &path, &[(false, 0.12)]);
}

/// Then the cave's blocks derived from its geometry (its declaration ignored), against the
/// same references: within 1.5 times the declared proxy's error (its bar's 0.056 measured,
/// so 0.084; first measured 0.054, 0.056, 0.056, as the declared). The maze's derived proxy is
/// its grid exactly (bake/tests/mrt_derive.rs), so its images are the declared ones.
#[test]
fn indirect_light_in_the_warped_cave_follows_the_reference_and_beats_constant_ambient() {
    // Down the first column of blocks, the other three lights still.
    let path = [Vec3::new(1.0, 1.4, 1.0), Vec3::new(1.0, 1.4, 3.0), Vec3::new(1.0, 1.4, 5.0)];
    // The bar from the first honest measurement (0.054, 0.056, 0.056 against the best
    // constant's 0.530, 0.540, 0.585).
    along_path("mrt-cave", &path, &[(false, 0.075), (true, 1.5 * 0.056)]);
}

/// The relative RMS difference of `image` from `reference` over the pixels `mask` marks.
fn masked_nrmse(image: &Image, reference: &Image, mask: &[bool]) -> f64 {
    let (mut error, mut total) = (0.0f64, 0.0f64);
    for ((a, b), _) in image.pixels.iter().zip(&reference.pixels).zip(mask).filter(|(_, m)| **m) {
        error += (*a - *b).length_squared() as f64;
        total += b.length_squared() as f64;
    }
    (error / total).sqrt()
}

#[test]
fn figures_lit_by_the_light_volume_follow_the_reference_better_than_mapped_onto_the_blocks() {
    const W: u32 = 96;
    const H: u32 = 72;
    let scene = load_scene("mrt-figures");
    // The same figures mapped onto the blocks' faces, as a level without the volume has them
    // (002 Fig. 5, left).
    let mut mapped_scene = scene.clone();
    mapped_scene.settings.blocks.get_mut("mrt").and_then(|b| b.as_object_mut()).expect("an mrt block").remove("dynamic");
    let ctx = validated_context();
    let settings = RenderSettings { width: W, height: H, ..RenderSettings::default() };
    let (dictionary, _, level, mut applied) = mrt_quick_bake(&scene);
    let (_, _, mapped_level, mut mapped_applied) = mrt_quick_bake(&mapped_scene);
    off_the_ties(&mut applied);
    off_the_ties(&mut mapped_applied);
    // The pixels whose centre sees a figure first.
    let bvh = SceneBvh::new(&applied);
    let mask: Vec<bool> = (0..W * H)
        .map(|i| {
            let d = applied.camera.ray_direction((i % W) as f32 + 0.5, (i / W) as f32 + 0.5, W, H);
            bvh.closest_hit(applied.camera.position(), d, f32::INFINITY).is_some_and(|hit| level.dynamic.contains(&hit.mesh))
        })
        .collect();
    let with_volume = MrtData { dictionary: &dictionary, level: &level, feedback: true };
    let without = MrtData { dictionary: &dictionary, level: &mapped_level, feedback: true };
    let mut volume_renderer = new_renderer(&ctx, &applied, &settings, &[&with_volume]);
    let mut mapped_renderer = new_renderer(&ctx, &mapped_applied, &settings, &[&without]);
    let mut direct = new_renderer(&ctx, &applied, &settings, &[]);
    let mut ambient = new_renderer(&ctx, &applied, &RenderSettings { ambient: Vec3::ONE, beta: 0.0, ..settings.clone() }, &[]);
    // The scene's light round the cycle from the figures, then one in their row.
    let path = [applied.lights[0].position, Vec3::new(7.0, 1.4, 5.0)];
    let mut rows = Vec::new();
    for (k, position) in path.iter().enumerate() {
        let mut moved = applied.clone();
        moved.lights[0].position = *position;
        for renderer in [&mut volume_renderer, &mut mapped_renderer, &mut direct, &mut ambient] {
            renderer.set_lights(&moved.lights).unwrap();
        }
        let only_direct = render(&mut direct);
        let volume = difference(&render(&mut volume_renderer), &only_direct);
        let mapped = difference(&render(&mut mapped_renderer), &only_direct);
        let constant = difference(&render(&mut ambient), &only_direct);
        let settings =
            ReferenceSettings { samples_per_pixel: 1024, width: W, height: H, pixel_centres: true, ..ReferenceSettings::default() };
        let reference = render_reference(&moved, &SceneBvh::new(&moved), &settings).indirect;
        nrmse_with_artifacts(&format!("mrt_figures_{k}"), &volume, &reference);
        let best_constant = best_scaled(&constant, &reference, Some(&mask));
        rows.push([
            masked_nrmse(&volume, &reference, &mask),
            masked_nrmse(&mapped, &reference, &mask),
            masked_nrmse(&best_constant, &reference, &mask),
        ]);
    }
    let pixels = mask.iter().filter(|m| **m).count();
    eprintln!("figures' indirect NRMSE over {pixels} pixels, per light [volume, mapped onto the blocks, best constant]: {rows:.3?}");
    drop((volume_renderer, mapped_renderer, direct, ambient));
    assert_clean(ctx);
    assert!(pixels > 200, "the figures are in view: {pixels} pixels");
    // The bars from the first honest measurement: [0.366, 1.014, 0.423] with the light round
    // the cycle (the 1,024-spp reference's own noise there is about 0.19 on these dim pixels,
    // and MRT's surfaces in view read 7-16 % bright too) and [0.052, 0.376, 0.380] with it in
    // the figures' row.
    for (k, ([volume, mapped, constant], bar)) in rows.iter().zip([0.45, 0.08]).enumerate() {
        assert!(
            *volume < bar && *volume < mapped / 2.0 && volume < constant,
            "light {k}: volume {volume:.3}, mapped {mapped:.3}, constant {constant:.3}"
        );
    }
}
