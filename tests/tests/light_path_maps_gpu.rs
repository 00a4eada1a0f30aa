//! The run-time side of the light path maps (000 §3.4 steps 2-5) on the GPU against the CPU
//! formulas of relume_bake::light_path_maps: entry-point irradiance (shadows off: exactly
//! `entry_irradiance_unshadowed` summed over the lights; shadows on: never more, and close to
//! the baker's ray-traced `entry_irradiance` for most entry points), cluster
//! sums and reconstruction (`cluster_sums` + `reconstruct` of the GPU's own I_e), the padding
//! of the indirect image, the three `Composition` modes of the lighting pass, and the
//! refusal of transfers that do not fit. Data is synthetic (tests/src/synthetic_light_path_maps.rs):
//! cornell's atlas, entry points at covered texel centres, hashed textures and weights.

use glam::{Vec3, Vec4};
use relume_bake::atlas::Atlas;
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::light_path_maps::entry_irradiance;
use relume_bake::light_path_maps::{entry_irradiance_unshadowed, ClusteredTransfer};
use relume_bake::metrics::add_scaled;
use relume_bake::scene::{Light, LightKind, Scene};
use relume_bake::testing;
use relume_renderer::techniques::light_path_maps::{Composition, LightPathMaps, LightPathMapsData};
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::vk::{Context, Readback, VkResult};
use relume_renderer::{AtlasImage, Headless, RenderSettings};
use relume_tests::synthetic_light_path_maps::{atlas_scene, constant_obscurance, synthetic_transfer};
use relume_tests::*;
use std::sync::Arc;

const SIZE: u32 = 96;
const TEXEL_DENSITY: f32 = 64.0;

fn settings(shadows: bool) -> RenderSettings {
    RenderSettings { width: SIZE, height: SIZE, shadow_map_size: 256, shadows, ..RenderSettings::default() }
}

/// Cornell with uv1, its atlas, and a transfer of 150 entry points in 4 clusters (one empty,
/// one larger than a workgroup) with D = 2.
fn cornell(extra_lights: Vec<Light>) -> (Atlas, Scene, ClusteredTransfer) {
    let mut scene = load_scene("cornell");
    scene.lights.extend(extra_lights);
    let (atlas, applied) = atlas_scene(&scene, TEXEL_DENSITY);
    let transfer = synthetic_transfer(&atlas, vec![0, 7, 7, 110, 150], 2, 7);
    (atlas, applied, transfer)
}

/// A renderer with the obscurance `w` and the light path maps of `transfer` on it.
fn with_maps(
    ctx: &Arc<Context>,
    scene: &Scene,
    settings: &RenderSettings,
    w: AtlasImage,
    transfer: &ClusteredTransfer,
) -> VkResult<Headless> {
    let maps = LightPathMapsData { transfer, atlas: w, composition: Composition::default() };
    try_new_renderer(ctx, scene, settings, &[&ObscuranceData { obscurance: w }, &maps])
}

fn gpu_entry_irradiance(renderer: &mut Headless) -> Vec<Vec3> {
    read_vec4s(renderer, "light_path_maps.entry_irradiance").expect("entry irradiance").iter().map(|v| v.truncate()).collect()
}

fn indirect(renderer: &mut Headless) -> Vec<Vec4> {
    read_vec4s(renderer, "light_path_maps.indirect").expect("indirect")
}

fn scaled(a: &Image, s: f32) -> Image {
    let mut out = a.clone();
    out.pixels.iter_mut().for_each(|p| *p *= s);
    out
}

fn sum(a: &Image, b: &Image) -> Image {
    add_scaled(a, b, 1.0).expect("same size")
}

fn max_value(image: &Image) -> f32 {
    image.pixels.iter().map(|p| p.abs().max_element()).fold(0.0, f32::max)
}

/// `actual` equals `expected` up to float rounding of frames as bright as `scale`: every
/// channel within 1e-5 * scale (a term is found as a difference of two frames, so its
/// rounding error follows the frames' brightness, not the term's).
fn assert_images_close(what: &str, actual: &Image, expected: &Image, scale: f32) {
    let worst = actual.pixels.iter().zip(&expected.pixels).map(|(a, e)| (*a - *e).abs().max_element()).fold(0.0f32, f32::max);
    println!("{what}: worst difference {worst:.3e} (frames up to {scale:.3e})");
    assert!(worst <= 1e-5 * scale, "{what}: differs by up to {worst} (frames up to {scale})");
}

#[test]
fn entry_irradiance_is_the_cpu_formula_without_shadows_and_never_more_with_them() {
    // Every light kind: cornell's spot, a point light with a range window, a directional light.
    let point = Light { range: Some(0.6), ..testing::point_light(Vec3::new(0.1, 0.35, -0.2), Vec3::new(0.3, 0.2, 0.1)) };
    let sun = Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        intensity: Vec3::new(2.0, 1.5, 1.0),
        range: None,
        position: Vec3::ZERO,
        direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
    };
    let (atlas, scene, transfer) = cornell(vec![point, sun]);
    let w = constant_obscurance(&atlas, Vec3::ONE);
    let cpu: Vec<Vec3> = transfer
        .entry_points
        .iter()
        .map(|e| scene.lights.iter().map(|l| entry_irradiance_unshadowed(l, e, transfer.light_area)).sum())
        .collect();
    let scale = cpu.iter().map(|i| i.max_element()).fold(0.0f32, f32::max);
    let lit = cpu.iter().filter(|i| i.max_element() > 1e-3 * scale).count();
    assert!(lit * 3 > cpu.len(), "only {lit} of {} entry points are lit; the test would prove little", cpu.len());

    let ctx = validated_context();
    let mut unshadowed = with_maps(&ctx, &scene, &settings(false), atlas_image(&atlas, &w), &transfer).expect("renderer");
    unshadowed.render().expect("frame");
    let gpu = gpu_entry_irradiance(&mut unshadowed);
    assert_eq!(gpu.len(), cpu.len());
    let mut worst = 0.0f32;
    for (e, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
        // Relative where the light is not (almost) cut off by a cone or range window.
        let error = ((*g - *c).abs() / c.max(Vec3::splat(1e-3 * scale))).max_element();
        assert!(error <= 1e-3, "entry point {e}: GPU {g}, CPU {c}");
        worst = worst.max(error);
    }
    println!("{} entry points, {lit} lit: worst relative error {worst:.2e}", gpu.len());

    let mut shadowed = with_maps(&ctx, &scene, &settings(true), atlas_image(&atlas, &w), &transfer).expect("renderer");
    shadowed.render().expect("frame");
    let with_shadows = gpu_entry_irradiance(&mut shadowed);
    for (e, (s, c)) in with_shadows.iter().zip(&cpu).enumerate() {
        assert!(s.cmpge(Vec3::ZERO).all() && s.cmple(*c * 1.001 + 1e-6 * scale).all(), "entry point {e}: shadowed {s} > unshadowed {c}");
    }
    let in_shadow =
        with_shadows.iter().zip(&cpu).filter(|(s, c)| c.max_element() > 1e-3 * scale && s.max_element() < 0.5 * c.max_element()).count();
    println!("with shadows: {in_shadow} of {lit} lit entry points at least half shadowed");
    assert!(in_shadow > 0, "no entry point is in shadow; the visibility factor went untested");
    // Against ray-traced visibility (the baker's entry_irradiance): the shadow map decides
    // the same for most entry points; it may differ near shadow edges (filtered moments) and
    // on surfaces at grazing angles to a light.
    let bvh = SceneBvh::new(&scene);
    let traced: Vec<Vec3> = transfer
        .entry_points
        .iter()
        .map(|e| scene.lights.iter().map(|l| entry_irradiance(&bvh, l, e, transfer.light_area)).sum())
        .collect();
    let agree =
        with_shadows.iter().zip(&traced).filter(|(s, t)| (**s - **t).abs().max_element() <= 0.1 * t.max_element() + 1e-3 * scale).count();
    let total_error: f32 = with_shadows.iter().zip(&traced).map(|(s, t)| (*s - *t).abs().element_sum()).sum();
    let total: f32 = traced.iter().map(|t| t.element_sum()).sum();
    println!(
        "shadow map vs ray tracing: {agree} of {} entry points within 10%; summed |error| {:.1}% of the summed irradiance",
        traced.len(),
        100.0 * total_error / total
    );
    assert!(agree * 10 >= traced.len() * 8, "the shadow map and ray tracing agree on only {agree} of {} entry points", traced.len());
    assert!(total_error <= 0.1 * total, "the shadow map's entry irradiance is off by {:.1}% in sum", 100.0 * total_error / total);
    drop((unshadowed, shadowed));
    assert_clean(ctx);
}

/// Cornell as given (its spot light, shadows on) with the synthetic transfer and W = 1: one
/// frame rendered, then the GPU's I_e and indirect image read back.
fn one_frame() -> (Atlas, ClusteredTransfer, Vec<Vec3>, Vec<Vec4>) {
    let (atlas, scene, transfer) = cornell(Vec::new());
    let w = constant_obscurance(&atlas, Vec3::ONE);
    let ctx = validated_context();
    let mut renderer = with_maps(&ctx, &scene, &settings(true), atlas_image(&atlas, &w), &transfer).expect("renderer");
    let timings = renderer.render().expect("frame");
    let names: Vec<&str> = timings.passes().iter().map(|(name, _)| *name).collect();
    if !names.is_empty() {
        let expected = ["vsm_moments", "vsm_blur", "light_path_maps.entry_irradiance", "light_path_maps.cluster_sums"];
        let expected = [&expected[..], &["light_path_maps.reconstruct", "light_path_maps.padding", "lighting", "tonemap"]].concat();
        assert_eq!(names, expected, "the frame's passes, in order");
        assert!(timings.passes().iter().all(|(_, t)| t.is_finite() && *t >= 0.0), "pass times {:?}", timings.passes());
        println!("pass times (ms): {:?}", timings.passes());
    }
    let entry = gpu_entry_irradiance(&mut renderer);
    let indirect_image = indirect(&mut renderer);
    // The passes are deterministic: a second frame (after the read-backs) gives the same bits.
    renderer.render().expect("frame");
    assert_eq!(gpu_entry_irradiance(&mut renderer), entry, "entry irradiance changed between frames");
    assert_eq!(indirect(&mut renderer), indirect_image, "the indirect image changed between frames");
    drop(renderer);
    assert_clean(ctx);
    (atlas, transfer, entry, indirect_image)
}

#[test]
fn reconstruction_is_the_cpu_formula_of_the_gpus_entry_irradiance() {
    let (atlas, transfer, entry, indirect) = one_frame();
    let cpu = transfer.reconstruct(&transfer.cluster_sums(&entry));
    let scale = cpu.iter().map(|i| i.abs().max_element()).fold(0.0f32, f32::max);
    assert!(scale > 0.0, "no indirect light at all");
    let mut worst = 0.0f32;
    let mut covered = 0;
    for (t, ((g, c), texel)) in indirect.iter().zip(&cpu).zip(&atlas.texels).enumerate() {
        if texel.coverage <= 0.0 {
            continue;
        }
        covered += 1;
        assert_eq!(g.w, texel.coverage, "texel {t}: alpha is not the coverage");
        let error = ((g.truncate() - *c).abs() / c.abs().max(Vec3::splat(1e-4 * scale))).max_element();
        assert!(error <= 1e-3, "texel {t}: GPU {}, CPU {c}", g.truncate());
        worst = worst.max(error);
    }
    let lit = cpu.iter().zip(&atlas.texels).filter(|(c, t)| t.coverage > 0.0 && c.min_element() > 1e-2 * scale).count();
    assert!(lit * 2 > covered, "only {lit} of {covered} covered texels have clear indirect light");
    println!("{covered} covered texels ({} in all, {} pages): worst relative error {worst:.2e}", atlas.texels.len(), atlas.pages);
}

#[test]
fn the_indirect_image_is_padded_from_covered_neighbours() {
    let (atlas, _, _, indirect) = one_frame();
    let (w, h) = (atlas.width as i64, atlas.height as i64);
    let at = |page: i64, x: i64, y: i64| ((page * h + y) * w + x) as usize;
    let inside = |x: i64, y: i64| (0..w).contains(&x) && (0..h).contains(&y);
    let mut checked = 0;
    for page in 0..atlas.pages as i64 {
        for y in 0..h {
            for x in 0..w {
                let t = at(page, x, y);
                if atlas.texels[t].coverage > 0.0 {
                    continue;
                }
                assert!(indirect[t].w < 0.0, "empty texel {t} was not padded (alpha {})", indirect[t].w);
                let next_to_covered = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                    .iter()
                    .any(|(dx, dy)| inside(x + dx, y + dy) && atlas.texels[at(page, x + dx, y + dy)].coverage > 0.0);
                if !next_to_covered {
                    continue;
                }
                // Jump flooding finds the nearest covered texel or one within a texel of it.
                assert!(indirect[t].w >= -2.0, "texel {t} next to a covered one took a value from {} texels away", -indirect[t].w);
                let rgb = indirect[t].truncate();
                let copied = (-2..=2).any(|dy| {
                    (-2..=2).any(|dx| {
                        let (nx, ny) = (x + dx, y + dy);
                        inside(nx, ny) && atlas.texels[at(page, nx, ny)].coverage > 0.0 && indirect[at(page, nx, ny)].truncate() == rgb
                    })
                });
                assert!(copied, "texel {t} next to a covered one holds {rgb}, no nearby covered texel's value");
                checked += 1;
            }
        }
    }
    println!("{checked} gutter texels next to charts hold a covered neighbour's value");
    assert!(checked > 100, "only {checked} gutter texels checked");
}

#[test]
fn composition_modes_add_what_their_formulas_say() {
    let (atlas, scene, transfer) = cornell(Vec::new());
    let ctx = validated_context();
    // The frames of one obscurance W: the frame without light path maps (direct light, no
    // ambient), and the light-path-map term of each mode (its frame minus that one).
    let frames = |w: f32| {
        let texels = constant_obscurance(&atlas, Vec3::splat(w));
        let obscurance = atlas_image(&atlas, &texels);
        let mut without = new_renderer(&ctx, &scene, &settings(true), &[&ObscuranceData { obscurance }]);
        let base = render(&mut without);
        // Without light path maps there is no composition to switch, and frames repeat bit for bit.
        assert!(without.technique_mut::<LightPathMaps>().is_none(), "a renderer without light path maps has them (W = {w})");
        assert_eq!(render(&mut without), base, "a frame without light path maps changed (W = {w})");
        let mut with = with_maps(&ctx, &scene, &settings(true), obscurance, &transfer).expect("renderer");
        let terms: Vec<Image> = Composition::ALL
            .iter()
            .map(|&mode| {
                set_composition(&mut with, mode);
                difference(&render(&mut with), &base)
            })
            .collect();
        let scale = terms.iter().map(|t| max_value(&sum(t, &base))).fold(max_value(&base), f32::max);
        (base, terms, scale)
    };
    let (direct, one, scale_one) = frames(1.0);
    let (_, half, scale_half) = frames(0.5);
    let [plain, times_w, with_direct] = [&one[0], &one[1], &one[2]];
    let lit = plain.pixels.iter().filter(|p| p.min_element() > 1e-2 * max_value(plain)).count();
    assert!(lit * 4 > plain.pixels.len(), "the light path maps light only {lit} pixels");
    assert!(max_value(plain) > 1e-2 * scale_one, "the light-path-map term is too faint to test");

    // Cornell has no emission: the direct-only frame is albedo / pi * E_d.
    let mut dark = scene.clone();
    dark.lights.iter_mut().for_each(|l| l.intensity = Vec3::ZERO);
    let emission = render_validated(&dark, &settings(true));
    assert_eq!(max_value(&emission), 0.0, "cornell emits light; this test assumes it does not");

    // W = 1: TimesObscurance is Plain, and WithDirect adds the direct light once more.
    assert_images_close("W = 1: TimesObscurance vs Plain", times_w, plain, scale_one);
    assert_images_close(
        "W = 1: WithDirect - TimesObscurance vs direct",
        &difference(with_direct, times_w),
        &difference(&direct, &emission),
        scale_one,
    );
    // W = 0.5: Plain ignores W; the other two are halved.
    assert_images_close("W = 0.5: Plain vs Plain at W = 1", &half[0], plain, scale_half.max(scale_one));
    assert_images_close("W = 0.5: TimesObscurance vs Plain / 2", &half[1], &scaled(plain, 0.5), scale_half);
    assert_images_close(
        "W = 0.5: WithDirect vs (Plain + direct) / 2",
        &half[2],
        &scaled(&sum(plain, &direct), 0.5),
        scale_half.max(scale_one),
    );
    assert_clean(ctx);
}

/// Frames recorded back to back into one command buffer, as an engine that does not wait
/// between frames would: a frame's writes of the per-frame buffers and of the indirect image
/// come after the previous frame's reads (write-after-read), which synchronization validation
/// checks within a command buffer. Then the same frame as when rendered alone.
#[test]
fn frames_recorded_back_to_back_are_ordered() {
    let (atlas, scene, transfer) = cornell(Vec::new());
    let w = constant_obscurance(&atlas, Vec3::ONE);
    let ctx = validated_context();
    let mut renderer = with_maps(&ctx, &scene, &settings(true), atlas_image(&atlas, &w), &transfer).expect("renderer");
    let alone = render(&mut renderer);
    let readback = Readback::for_image(&ctx, "radiance", renderer.radiance()).expect("readback");
    let cmd = relume_renderer::vk::CommandBuffer::new(&ctx).expect("command buffer");
    let fence = relume_renderer::vk::Fence::new(&ctx).expect("fence");
    let rec = ctx.begin(cmd.raw).expect("begin");
    for _ in 0..3 {
        renderer.record(&rec);
    }
    renderer.record_readback(&rec, "radiance", &readback).expect("radiance");
    ctx.submit_and_wait(rec, &fence).expect("submit");
    let (width, height) = (alone.width, alone.height);
    assert_eq!(radiance_of(&readback, width, height), alone, "frames recorded back to back differ from one alone");
    drop((renderer, readback, cmd, fence));
    assert_clean(ctx);
}

#[test]
fn transfers_that_do_not_fit_are_refused_by_name() {
    let (atlas, scene, transfer) = cornell(Vec::new());
    let w = constant_obscurance(&atlas, Vec3::ONE);
    let obscurance = atlas_image(&atlas, &w);
    let ctx = validated_context();
    let refused = |t: &ClusteredTransfer| refusal(with_maps(&ctx, &scene, &settings(true), obscurance, t));

    let mut short = transfer.clone();
    short.weights.pop();
    says(&refused(&short), &["light path maps", "weights"]);

    let (other_atlas, _) = atlas_scene(&load_scene("cornell"), TEXEL_DENSITY / 2.0);
    let other = synthetic_transfer(&other_atlas, vec![0, 10], 1, 3);
    says(&refused(&other), &["light path maps", &format!("{} texels", other.texel_count), &format!("has {}", w.len())]);

    let empty = ClusteredTransfer { texel_count: w.len(), cluster_starts: vec![0], ..ClusteredTransfer::default() };
    empty.validate().expect("an empty transfer is consistent");
    says(&refused(&empty), &["light path maps", "empty", "0 entry points"]);

    // Without light path maps there is nothing to read back.
    let mut plain = new_renderer(&ctx, &scene, &settings(true), &[&ObscuranceData { obscurance }]);
    plain.render().expect("frame");
    let no_maps = read_vec4s(&mut plain, "light_path_maps.entry_irradiance").expect_err("no light path maps").to_string();
    says(&no_maps, &["no resource", "light_path_maps.entry_irradiance", "obscurance.obscurance"]);
    says(&read_vec4s(&mut plain, "light_path_maps.indirect").expect_err("no light path maps").to_string(), &["no resource"]);
    drop(plain);
    assert_clean(ctx);
}
