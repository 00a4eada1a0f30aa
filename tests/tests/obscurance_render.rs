//! The obscurance illumination model in the lighting pass (001 eq. (5)-(7)), GPU against CPU:
//! with I_A = beta = 0 the frame is bit for bit the direct-only frame; the ambient term
//! albedo / pi * I_A * W with W read from the obscurance through uv1 matches a CPU evaluation at
//! pixel centres (primary rays through the BVH, uv1 interpolated with the hit's barycentrics,
//! the padded obscurance filtered bilinearly by the same convention); the beta term matches
//! albedo / pi * beta * sum_j E_j; bad obscurances, scenes and settings are refused.
//!
//! The ambient term of a frame is isolated by rendering it twice with one renderer, with and
//! without the ambient settings ([`Renderer::set_ambient`]), and subtracting: the direct term
//! is the same in both.

use glam::{Vec2, Vec3, Vec4};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::bvh::{Hit, SceneBvh};
use relume_bake::image::Image;
use relume_bake::scene::{Light, LightKind, Scene};
use relume_bake::testing::{self, Facing};
use relume_renderer::atlas_image::GpuAtlasImage;
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::{AtlasImage, MakeTechnique, RenderSettings};
use relume_tests::*;

const WIDTH: u32 = 192;
const HEIGHT: u32 = 160;

fn settings() -> RenderSettings {
    RenderSettings { width: WIDTH, height: HEIGHT, shadow_map_size: 512, ..RenderSettings::default() }
}

/// A 4 m floor (orange-ish) with a 0.8 x 0.7 x 0.8 m box (blue-ish) standing on it, one point
/// light, seen from above at an angle. Two albedos, so the test sees albedo per mesh.
fn floor_and_box(lights: Vec<Light>) -> Scene {
    let floor_material = testing::material("floor", Vec3::new(0.8, 0.6, 0.4), Vec3::ZERO);
    let box_material = testing::material("box", Vec3::new(0.3, 0.7, 0.9), Vec3::ZERO);
    let floor = testing::square(Vec3::ZERO, Vec3::X * 2.0, -Vec3::Z * 2.0, 4, 0);
    let block = testing::closed_box(Vec3::new(-0.4, 0.0, -0.4), Vec3::new(0.4, 0.7, 0.4), 2, Facing::Outward, 1);
    let camera = testing::look_at(Vec3::new(1.3, 2.8, 3.1), Vec3::new(0.0, 0.2, 0.0), Vec3::Y, 50f32.to_radians());
    testing::scene("floor and box", vec![floor, block], vec![floor_material, box_material], lights, camera)
}

fn point_light() -> Light {
    testing::point_light(Vec3::new(0.9, 2.2, 0.6), Vec3::splat(15.0))
}

/// A smooth, known obscurance per texel: a function of the texel's patch centre, different in
/// each channel (the spectral variant has three).
fn synthetic_w(centre: Vec3) -> Vec3 {
    Vec3::new(0.5 + 0.5 * (3.0 * centre.x).sin(), 0.5 + 0.5 * (2.0 * centre.z).cos(), 0.5 + 0.25 * (2.0 * centre.y + centre.x).sin())
}

/// The scene's atlas (small pages, so the floor and the box land on different pages), the
/// scene with the atlas applied (uv1 set), and the synthetic obscurance: rgb W, alpha coverage.
fn atlas_scene(scene: &Scene) -> (Atlas, Scene, Vec<Vec4>) {
    let atlas_settings = AtlasSettings { texel_density: 12.0, gutter: 2, max_size: 56, ..AtlasSettings::default() };
    let atlas = Atlas::build(scene, &atlas_settings).expect("atlas");
    let mut applied = scene.clone();
    atlas.apply_to(&mut applied);
    let texels =
        atlas.texels.iter().map(|t| if t.coverage > 0.0 { synthetic_w(t.centre).extend(t.coverage) } else { Vec4::ZERO }).collect();
    (atlas, applied, texels)
}

/// Bilinear filtering of a padded atlas image at uv1, as shaders/lighting.frag does it: page =
/// floor(u), texel centres at (i + 0.5) / size, clamped to the page's edge.
fn sample_atlas(padded: &[Vec4], (width, height, pages): (u32, u32, u32), uv1: Vec2) -> Vec3 {
    let (w, h) = (width as i64, height as i64);
    let page = uv1.x.floor();
    let layer = (page as i64).clamp(0, pages as i64 - 1);
    let x = (uv1.x - page) * width as f32 - 0.5;
    let y = uv1.y * height as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |i: i64, j: i64| padded[((layer * h + j.clamp(0, h - 1)) * w + i.clamp(0, w - 1)) as usize].truncate();
    let (i, j) = (x0 as i64, y0 as i64);
    let top = texel(i, j).lerp(texel(i + 1, j), fx);
    let bottom = texel(i, j + 1).lerp(texel(i + 1, j + 1), fx);
    top.lerp(bottom, fy)
}

fn hit_uv1(scene: &Scene, hit: &Hit) -> Vec2 {
    let mesh = &scene.meshes[hit.mesh as usize];
    let uv1 = mesh.uv1.as_ref().expect("the atlas gave every mesh uv1");
    let corner = |k: usize| uv1[mesh.indices[3 * hit.triangle as usize + k] as usize];
    let b = hit.barycentrics;
    corner(0) * (1.0 - b.x - b.y) + corner(1) * b.x + corner(2) * b.y
}

fn albedo(scene: &Scene, hit: &Hit) -> Vec3 {
    scene.materials[hit.material as usize].base_color.truncate()
}

/// Zeroes the pixels `keep` leaves out.
fn masked(image: &Image, keep: &[bool]) -> Image {
    let mut out = image.clone();
    for (p, k) in out.pixels.iter_mut().zip(keep) {
        if !k {
            *p = Vec3::ZERO;
        }
    }
    out
}

#[test]
fn zero_ambient_and_beta_give_the_direct_only_frame_bit_for_bit() {
    let scene = floor_and_box(vec![point_light()]);
    let (atlas, applied, texels) = atlas_scene(&scene);
    let ctx = validated_context();
    let mut plain = new_renderer(&ctx, &scene, &settings(), &[]);
    let direct_only = render(&mut plain);
    let mut lit = new_renderer(&ctx, &applied, &settings(), &[&ObscuranceData { obscurance: atlas_image(&atlas, &texels) }]);
    let with_obscurance = render(&mut lit);
    assert_eq!(with_obscurance, direct_only, "an obscurance with I_A = beta = 0 changed the frame");

    lit.set_ambient(Vec3::splat(2.0), 0.3).expect("valid ambient");
    let ambient = render(&mut lit);
    assert_ne!(ambient, direct_only, "the ambient term added nothing");
    lit.set_ambient(Vec3::ZERO, 0.0).expect("valid ambient");
    assert_eq!(render(&mut lit), direct_only, "back to I_A = beta = 0 is the direct-only frame again");
    lit.forget_states();
    lit.set_ambient(Vec3::splat(2.0), 0.3).expect("valid ambient");
    assert_eq!(render(&mut lit), ambient, "the obscurance survives forget_states");

    assert!(plain.creation_timings().is_empty(), "no obscurance, no padding time");
    if let Some((_, ms)) = lit.creation_timings().first().copied() {
        assert!(ms.is_finite() && ms >= 0.0, "padding took {ms} ms");
        println!("padding of a {}x{}x{} obscurance: {ms:.3} ms", atlas.width, atlas.height, atlas.pages);
    }
    drop((plain, lit));
    assert_clean(ctx);
}

/// Renders `scene` (uv1 on every mesh) with `obscurance` and I_A = 1, 1, 1, beta = 0, and returns
/// the NRMSE of its ambient term against the CPU's albedo / pi * I_A * W over the pixels away
/// from silhouettes, W filtered from `padded` (the obscurance as the GPU padded it). Also
/// returns how many pixels count, and the range of W's red channel over mesh 0.
fn ambient_term_nrmse(name: &str, scene: &Scene, obscurance: &AtlasImage, padded: &[Vec4]) -> (f64, usize, (f32, f32)) {
    let ambient = Vec3::ONE;
    let gpu = gpu_ambient_term(scene, Some(obscurance), ambient, 0.0);

    let bvh = SceneBvh::new(scene);
    let hits = primary_hits(scene, &bvh, WIDTH, HEIGHT);
    let keep = interior_pixels(&hits, WIDTH, HEIGHT);
    let dims = (obscurance.width, obscurance.height, obscurance.pages);
    let mut cpu = Image::new(WIDTH, HEIGHT);
    let mut first_mesh_w = (f32::INFINITY, f32::NEG_INFINITY);
    for (pixel, hit) in cpu.pixels.iter_mut().zip(&hits) {
        let Some(hit) = hit else { continue };
        let w = sample_atlas(padded, dims, hit_uv1(scene, hit));
        if hit.mesh == 0 {
            first_mesh_w = (first_mesh_w.0.min(w.x), first_mesh_w.1.max(w.x));
        }
        *pixel = albedo(scene, hit) / std::f32::consts::PI * ambient * w;
    }
    let kept = keep.iter().filter(|k| **k).count();
    assert!(kept * 3 > keep.len(), "{name}: only {kept} of {} pixels are away from silhouettes", keep.len());
    let nrmse = nrmse_with_artifacts(name, &masked(&gpu, &keep), &masked(&cpu, &keep));
    let worst = gpu
        .pixels
        .iter()
        .zip(&cpu.pixels)
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|((g, c), _)| (*g - *c).abs().max_element() / c.max_element().max(1e-6))
        .fold(0.0f32, f32::max);
    println!("{name}: {}x{}x{} obscurance, NRMSE {nrmse:.2e} over {kept} pixels, worst relative {worst:.2e}", dims.0, dims.1, dims.2);
    (nrmse, kept, first_mesh_w)
}

#[test]
fn the_ambient_term_through_the_obscurance_matches_the_cpu() {
    let scene = floor_and_box(vec![point_light()]);
    let (atlas, applied, texels) = atlas_scene(&scene);
    assert!(atlas.pages >= 2, "the floor and the box should land on different pages ({} pages)", atlas.pages);
    // The padded obscurance as the renderer holds it: the same texels uploaded and padded by
    // the same (deterministic) GPU pass, read back.
    let padded = {
        let ctx = validated_context();
        let padded = GpuAtlasImage::upload_blocking(&ctx, "obscurance", &atlas_image(&atlas, &texels))
            .expect("upload")
            .read_back_blocking()
            .expect("read back");
        assert_clean(ctx);
        padded
    };
    let obscurance = atlas_image(&atlas, &texels);
    let (nrmse, _, floor_w) = ambient_term_nrmse("obscurance_ambient_term", &applied, &obscurance, &padded);
    assert!(floor_w.1 - floor_w.0 > 0.5, "W hardly varies over the floor ({floor_w:?}); the test would prove little");
    assert!(nrmse <= 0.01, "NRMSE {nrmse} > 0.01");
}

/// An atlas never puts a chart against a page's edge; this floor's uv1 spans its whole page
/// in v and starts at its left edge in u, on page 1 of a 4 x 4 x 2 obscurance of contrasting
/// texels, so the filter's edge clamp (and not wrapping, nor the other page) shows.
#[test]
fn atlas_pages_are_clamped_at_their_edges() {
    let floor_material = testing::material("floor", Vec3::new(0.8, 0.6, 0.4), Vec3::ZERO);
    let mut floor = testing::square(Vec3::ZERO, Vec3::X * 2.0, -Vec3::Z * 2.0, 4, 0);
    floor.uv1 = Some(floor.positions.iter().map(|p| Vec2::new(1.0 + 0.75 * (p.x + 2.0) / 4.0, (p.z + 2.0) / 4.0)).collect());
    let camera = testing::look_at(Vec3::new(0.0, 4.0, 1.5), Vec3::ZERO, Vec3::Y, 70f32.to_radians());
    let scene = testing::scene("clamped page", vec![floor], vec![floor_material], vec![point_light()], camera);
    let texels: Vec<Vec4> = (0..32)
        .map(|t| {
            let (page, j, i) = (t / 16, t / 4 % 4, t % 4);
            let level = |k: u32| 0.1 + 0.8 * ((k % 5) as f32) / 4.0;
            if page == 0 {
                Vec4::new(5.0, 5.0, 5.0, 1.0)
            } else {
                Vec4::new(level(i * 3 + j * 7), level(i + j * 2 + 1), level(i * 2 + j * 3 + 2), 1.0)
            }
        })
        .collect();
    let obscurance = AtlasImage { width: 4, height: 4, pages: 2, texels: &texels };
    let (nrmse, _, w) = ambient_term_nrmse("obscurance_page_edges", &scene, &obscurance, &texels);
    assert!(w.1 <= 1.0, "page 0 bled into page 1 (W up to {})", w.1);
    assert!(nrmse <= 0.01, "NRMSE {nrmse} > 0.01");
}

/// The beta term alone (I_A = 0, no obscurance so W = 1) at the pixels whose ray hits the
/// floor, against albedo / pi * beta * sum_j E_j with E_j from the CPU's Light::incident at
/// the primary hit; returns the relative error at the image centre and the worst.
fn beta_term_errors(name: &str, scene: &Scene, beta: f32) -> (f32, f32) {
    let gpu = gpu_ambient_term(scene, None, Vec3::ZERO, beta);

    let bvh = SceneBvh::new(scene);
    let hits = primary_hits(scene, &bvh, WIDTH, HEIGHT);
    let keep = interior_pixels(&hits, WIDTH, HEIGHT);
    let expected = |hit: &Hit| {
        let unshadowed: Vec3 = scene.lights.iter().map(|l| l.incident(hit.position).irradiance).sum();
        albedo(scene, hit) / std::f32::consts::PI * beta * unshadowed
    };
    let relative = |i: usize| {
        let hit = hits[i].as_ref().expect("a floor hit");
        let e = expected(hit);
        ((gpu.pixels[i] - e).abs() / e.max(Vec3::splat(1e-9))).max_element()
    };
    let centre = (HEIGHT / 2 * WIDTH + WIDTH / 2) as usize;
    assert_eq!(hits[centre].map(|h| h.mesh), Some(0), "{name}: the image centre is not on the floor");
    let floor: Vec<usize> = (0..hits.len()).filter(|&i| keep[i] && hits[i].is_some_and(|h| h.mesh == 0)).collect();
    assert!(floor.len() * 4 > hits.len(), "{name}: the floor fills too little of the image");
    // Where a spot's cone or a range window takes the light to nothing, relative errors mean
    // nothing: those pixels are held to an absolute bound instead.
    let scale = floor.iter().map(|&i| expected(hits[i].as_ref().unwrap()).max_element()).fold(0.0f32, f32::max);
    let mut worst = 0.0f32;
    for &i in &floor {
        let e = expected(hits[i].as_ref().unwrap());
        if e.min_element() > 1e-2 * scale {
            worst = worst.max(relative(i));
        } else {
            let absolute = (gpu.pixels[i] - e).abs().max_element() / scale;
            assert!(absolute <= 1e-3, "{name}: pixel {i} is {} for {e}", gpu.pixels[i]);
        }
    }
    (relative(centre), worst)
}

#[test]
fn the_beta_term_is_beta_times_every_lights_unshadowed_irradiance() {
    // One point light of intensity I straight above a floor point: at the image centre the
    // term is albedo / pi * beta * I / r^2, r from the light to the primary hit.
    let intensity = 12.0;
    let light = testing::point_light(Vec3::new(0.2, 1.5, -0.1), Vec3::splat(intensity));
    let floor_material = testing::material("floor", Vec3::new(0.8, 0.6, 0.4), Vec3::ZERO);
    let floor = testing::square(Vec3::ZERO, Vec3::X * 2.0, -Vec3::Z * 2.0, 4, 0);
    // A blocker between the light and part of the floor: I'_S ignores visibility.
    let blocker = testing::square(Vec3::new(0.6, 0.8, 0.3), Vec3::X * 0.3, -Vec3::Z * 0.3, 1, 0);
    let camera = testing::look_at(Vec3::new(0.0, 2.5, 2.0), Vec3::ZERO, Vec3::Y, 60f32.to_radians());
    let scene = testing::scene("beta", vec![floor, blocker], vec![floor_material], vec![light.clone()], camera);
    let beta = 0.5;

    let bvh = SceneBvh::new(&scene);
    let centre_ray = scene.camera.ray_direction(WIDTH as f32 / 2.0 + 0.5, HEIGHT as f32 / 2.0 + 0.5, WIDTH, HEIGHT);
    let hit = bvh.closest_hit(scene.camera.position(), centre_ray, f32::INFINITY).expect("the centre ray hits the floor");
    let r = (light.position - hit.position).length();
    let by_hand = Vec3::new(0.8, 0.6, 0.4) / std::f32::consts::PI * beta * intensity / (r * r);
    let via_incident = Vec3::new(0.8, 0.6, 0.4) / std::f32::consts::PI * beta * light.incident(hit.position).irradiance;
    assert!((by_hand - via_incident).abs().max_element() <= 1e-6 * by_hand.max_element());

    let (centre, worst) = beta_term_errors("point light", &scene, beta);
    println!("beta term, one point light: relative error {centre:.2e} at the centre (r = {r:.4} m), worst {worst:.2e} over the floor");
    assert!(centre <= 1e-3, "relative error {centre} at the image centre");
    assert!(worst <= 1e-3, "relative error up to {worst} over the floor");

    // Every light kind's falloff: a spot with its cone and a range window, and a directional
    // light (its lux, whatever the direction), summed.
    let spot = Light {
        range: Some(3.0),
        ..testing::spot_light(Vec3::new(-0.5, 1.8, 0.3), Vec3::new(0.3, -1.0, -0.2), Vec3::new(20.0, 15.0, 10.0), 0.3, 0.6)
    };
    let sun = Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        intensity: Vec3::new(0.5, 0.6, 0.7),
        range: None,
        position: Vec3::ZERO,
        direction: Vec3::new(0.4, -1.0, 0.1).normalize(),
    };
    let kinds = testing::scene("beta, every kind", scene.meshes.clone(), scene.materials.clone(), vec![light, spot, sun], scene.camera);
    let (centre, worst) = beta_term_errors("every kind", &kinds, 0.3);
    println!("beta term, point + spot + directional: relative error {centre:.2e} at the centre, worst {worst:.2e} over the floor");
    assert!(centre <= 1e-3 && worst <= 1e-3, "relative error {centre} at the centre, up to {worst}");
}

#[test]
fn bad_obscurances_scenes_and_settings_are_refused() {
    let scene = floor_and_box(vec![point_light()]);
    let (atlas, applied, texels) = atlas_scene(&scene);
    let ctx = validated_context();

    let short = &texels[..texels.len() - 1];
    let message = refusal(try_new_renderer(&ctx, &applied, &settings(), &[&ObscuranceData { obscurance: atlas_image(&atlas, short) }]));
    says(&message, &[&format!("{} texels", texels.len()), &format!("{} were given", short.len())]);

    let obscurance = atlas_image(&atlas, &texels);
    let message = refusal(try_new_renderer(&ctx, &scene, &settings(), &[&ObscuranceData { obscurance }]));
    says(&message, &["mesh 0 \"square\"", "no uv1", "0 of 2"]);
    let mut half = scene.clone();
    half.meshes[0] = atlas.meshes[0].apply(&scene.meshes[0]);
    let message = refusal(try_new_renderer(&ctx, &half, &settings(), &[&ObscuranceData { obscurance }]));
    says(&message, &["mesh 1 \"box\"", "no uv1", "1 of 2"]);
    // uv1 on a page the atlas does not have.
    let first_page = (atlas.width * atlas.height) as usize;
    let one_page = AtlasImage { pages: 1, texels: &texels[..first_page], ..obscurance };
    let message = refusal(try_new_renderer(&ctx, &applied, &settings(), &[&ObscuranceData { obscurance: one_page }]));
    says(&message, &["1 pages", "uv1"]);
    // Without an obscurance, meshes with uv1 on some meshes only are fine (W = 1 everywhere).
    drop(try_new_renderer(&ctx, &half, &settings(), &[]).expect("no obscurance: uv1 is not needed"));

    let bad = [
        (RenderSettings { beta: 1.0, ..settings() }, "beta"),
        (RenderSettings { beta: -0.1, ..settings() }, "beta"),
        (RenderSettings { beta: f32::NAN, ..settings() }, "beta"),
        (RenderSettings { ambient: Vec3::new(1.0, f32::NAN, 1.0), ..settings() }, "ambient"),
        (RenderSettings { ambient: Vec3::new(1.0, -1.0, 1.0), ..settings() }, "ambient"),
        (RenderSettings { ambient: Vec3::splat(f32::INFINITY), ..settings() }, "ambient"),
    ];
    let mut renderer = new_renderer(&ctx, &scene, &settings(), &[]);
    for (settings, part) in bad {
        says(&settings.validate().expect_err("invalid settings accepted"), &[part]);
        says(&refusal(try_new_renderer(&ctx, &scene, &settings, &[])), &[part]);
        let refused = renderer.set_ambient(settings.ambient, settings.beta).expect_err("set_ambient accepted invalid values");
        says(&refused.to_string(), &[part]);
    }
    renderer.set_ambient(Vec3::new(0.0, 0.5, 100.0), 0.999).expect("valid values");
    renderer.render().expect("frame");
    drop(renderer);
    assert_clean(ctx);
}

/// The GPU's ambient term alone: a frame with `ambient` and `beta` minus the same frame
/// without them, on one renderer (validated).
fn gpu_ambient_term(scene: &Scene, obscurance: Option<&AtlasImage>, ambient: Vec3, beta: f32) -> Image {
    let ctx = validated_context();
    let obscurance = obscurance.map(|&obscurance| ObscuranceData { obscurance });
    let techniques: Vec<&dyn MakeTechnique> = obscurance.iter().map(|o| o as &dyn MakeTechnique).collect();
    let mut renderer = new_renderer(&ctx, scene, &settings(), &techniques);
    let direct = render(&mut renderer);
    renderer.set_ambient(ambient, beta).expect("valid ambient and beta");
    let term = difference(&render(&mut renderer), &direct);
    drop(renderer);
    assert_clean(ctx);
    term
}
