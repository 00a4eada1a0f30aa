//! Shared helpers of relume's cross-crate tests: shipped scenes, validated headless renderers
//! and their refusals, techniques from test data, the reference's direct layer at pixel
//! centres, failure images, synthetic light path maps (`synthetic_light_path_maps`), and a quick
//! MRT level.

use glam::{Vec3, Vec4};
use relume_bake::atlas::Atlas;
use relume_bake::bvh::{Hit, SceneBvh};
use relume_bake::gltf_load;
use relume_bake::image::{write_exr_layers, write_png_rgb8, write_png_tonemapped, Image};
use relume_bake::metrics;
use relume_bake::mrt::baker::bake_level;
use relume_bake::mrt::dictionary::Dictionary;
use relume_bake::mrt::level_data::LevelData;
use relume_bake::mrt::map::Mapped;
use relume_bake::mrt::{BlockSettings, InterfaceSettings};
use relume_bake::outputs::Outputs;
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::Scene;
use relume_renderer::techniques::light_path_maps::{Composition, LightPathMaps};
use relume_renderer::vk::{Context, ContextOptions, Readback, VkResult};
use relume_renderer::{AtlasImage, Headless, MakeTechnique, RenderSettings, Renderer};
use std::path::PathBuf;
use std::sync::Arc;

pub mod synthetic_light_path_maps;

pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub fn load_scene(name: &str) -> Scene {
    let path = repo_root().join("scenes").join(format!("{name}.gltf"));
    gltf_load::load(&path).unwrap_or_else(|e| panic!("{e}")).scene
}

/// A headless context on lavapipe (or RELUME_DEVICE) with validation and synchronization
/// validation on.
pub fn validated_context() -> Arc<Context> {
    Context::headless(&ContextOptions { validation: true, device: None }).expect("Vulkan context")
}

/// Drops the last reference to `ctx` (every renderer made from it is gone) and fails on any
/// validation message, teardown's included.
pub fn assert_clean(ctx: Arc<Context>) {
    let log = ctx.message_log();
    assert_eq!(Arc::strong_count(&ctx), 1, "something made from the context is still alive");
    drop(ctx);
    assert_no_validation_messages(&log.lock().unwrap());
}

pub fn assert_no_validation_messages(messages: &[String]) {
    assert!(messages.is_empty(), "{} validation message(s):\n{}", messages.len(), messages.join("\n"));
}

/// A headless renderer of `scene` with `techniques`, or why it was refused.
pub fn try_new_renderer(
    ctx: &Arc<Context>,
    scene: &Scene,
    settings: &RenderSettings,
    techniques: &[&dyn MakeTechnique],
) -> VkResult<Headless> {
    Renderer::new_blocking(ctx, scene, settings, techniques).and_then(Headless::new)
}

pub fn new_renderer(ctx: &Arc<Context>, scene: &Scene, settings: &RenderSettings, techniques: &[&dyn MakeTechnique]) -> Headless {
    try_new_renderer(ctx, scene, settings, techniques).expect("renderer")
}

/// The message of a refusal.
pub fn refusal<T>(result: VkResult<T>) -> String {
    match result {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    }
}

/// Fails unless `message` says every one of `parts`.
pub fn says(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(message.contains(part), "\"{message}\" does not say \"{part}\"");
    }
}

/// `a - b`, pixel by pixel.
pub fn difference(a: &Image, b: &Image) -> Image {
    metrics::difference(a, b).expect("images of one size")
}

/// One frame's linear radiance.
pub fn render(renderer: &mut Headless) -> Image {
    renderer.render_and_read().expect("frame").0
}

/// Renders one frame with validation on; panics on any validation message.
pub fn render_validated(scene: &Scene, settings: &RenderSettings) -> Image {
    let ctx = validated_context();
    let image = render(&mut new_renderer(&ctx, scene, settings, &[]));
    assert_clean(ctx);
    image
}

/// `texels` (rgb a value, alpha the coverage) laid out as `atlas`.
pub fn atlas_image<'d>(atlas: &Atlas, texels: &'d [Vec4]) -> AtlasImage<'d> {
    AtlasImage::new(atlas.layout(), texels)
}

/// A resource of vec4s (see `Renderer::resource`) as the last frame left it.
pub fn read_vec4s(renderer: &mut Headless, name: &str) -> VkResult<Vec<Vec4>> {
    Ok(renderer.read_floats_blocking(name)?.chunks_exact(4).map(Vec4::from_slice).collect())
}

/// The linear radiance a `Readback` of `radiance` holds (RGBA32F, alpha dropped).
pub fn radiance_of(readback: &Readback, width: u32, height: u32) -> Image {
    let rgba = readback.floats().expect("read back");
    Image { width, height, pixels: rgba.chunks_exact(4).map(|p| Vec3::new(p[0], p[1], p[2])).collect() }
}

/// Switches the composition of the renderer's light path maps.
pub fn set_composition(renderer: &mut Headless, composition: Composition) {
    renderer.technique_mut::<LightPathMaps>().expect("a renderer with light path maps").set_composition(composition);
}

/// The reference's `direct` layer with every sample through the pixel centre: exact for
/// punctual lights after one sample.
pub fn reference_direct(scene: &Scene, width: u32, height: u32, shadows: bool) -> Image {
    let settings = ReferenceSettings {
        samples_per_pixel: 1,
        width,
        height,
        pixel_centres: true,
        shadows,
        max_bounces: 1,
        ..ReferenceSettings::default()
    };
    render_reference(scene, &SceneBvh::new(scene), &settings).direct
}

/// Renders `scene` with Vulkan and the reference's direct layer at pixel centres, and
/// returns the NRMSE of one against the other (printed, with artifacts kept under `name`).
pub fn direct_nrmse(name: &str, scene: &Scene, settings: &RenderSettings) -> f64 {
    let image = render_validated(scene, settings);
    let reference = reference_direct(scene, settings.width, settings.height, settings.shadows);
    let nrmse = nrmse_with_artifacts(name, &image, &reference);
    println!("{name}: NRMSE {nrmse:.5}");
    nrmse
}

/// NRMSE of `image` against `reference`; writes both and the error picture under
/// target/test-output/<name>/ so a failure can be looked at.
pub fn nrmse_with_artifacts(name: &str, image: &Image, reference: &Image) -> f64 {
    let dir = repo_root().join("target/test-output").join(name);
    std::fs::create_dir_all(&dir).expect("test output folder");
    let mut outputs = Outputs::new();
    write_exr_layers(&mut outputs, &dir.join("actual.exr"), &[("radiance", image)]).expect("write actual");
    write_exr_layers(&mut outputs, &dir.join("reference.exr"), &[("direct", reference)]).expect("write reference");
    let mean = reference.pixels.iter().map(|p| p.element_sum() / 3.0).sum::<f32>() / reference.pixels.len() as f32;
    let exposure = if mean > 0.0 { 0.18 / mean } else { 1.0 };
    write_png_tonemapped(&mut outputs, &dir.join("actual.png"), image, exposure).expect("write actual png");
    write_png_tonemapped(&mut outputs, &dir.join("reference.png"), reference, exposure).expect("write reference png");
    let rgb = metrics::false_colour(image, reference, 0.5).expect("sizes match");
    write_png_rgb8(&mut outputs, &dir.join("error.png"), image.width, image.height, &rgb).expect("write error");
    outputs.commit().expect("write the test's images");
    let lit = reference.pixels.iter().filter(|p| p.max_element() > 0.0).count();
    assert!(lit * 10 > reference.pixels.len(), "{name}: the reference is almost black; the test would prove nothing");
    let stats = metrics::compare(image, reference).expect("sizes match");
    assert_eq!(stats.non_finite_pixels, 0, "{name}: NaN or infinite pixels");
    stats.nrmse
}

/// Every pixel's primary ray through its centre, traced on the CPU.
pub fn primary_hits(scene: &Scene, bvh: &SceneBvh, width: u32, height: u32) -> Vec<Option<Hit>> {
    let eye = scene.camera.position();
    (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let dir = scene.camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
            bvh.closest_hit(eye, dir, f32::INFINITY)
        })
        .collect()
}

/// Pixels whose ray and all 8 neighbours' rays hit the same mesh in the same plane: away from
/// silhouettes and creases, where the rasteriser and the CPU ray may pick different faces.
pub fn interior_pixels(hits: &[Option<Hit>], width: u32, height: u32) -> Vec<bool> {
    let at = |x: i64, y: i64| hits[(y * width as i64 + x) as usize];
    let mut keep = vec![false; hits.len()];
    for y in 1..height as i64 - 1 {
        for x in 1..width as i64 - 1 {
            let Some(centre) = at(x, y) else { continue };
            let same =
                |h: Option<Hit>| h.is_some_and(|h| h.mesh == centre.mesh && h.geometric_normal.dot(centre.geometric_normal) > 0.9999);
            keep[(y * width as i64 + x) as usize] = (-1..=1).all(|dy| (-1..=1).all(|dx| same(at(x + dx, y + dy))));
        }
    }
    keep
}

/// A gathered light cloud reduced and compressed as the `light-cloud` method's defaults do: 8
/// zones, light clustering at Table 1's 0.5 / 20, 32 clusters of 8 vectors.
pub fn light_cloud_by_defaults(
    scene: &Scene,
    bvh: &SceneBvh,
    gathered: &relume_bake::light_cloud::LightCloud,
) -> relume_bake::light_cloud::LightCloud {
    use relume_bake::light_cloud as lc;
    let reduction = lc::Reduction { zones: 8, weights: Some((0.5, 20.0)), linkage: lc::Linkage::Complete };
    lc::compress(&lc::reduce(scene, bvh, gathered, reduction).expect("reduce").cloud, 32, lc::Vectors::Each(8), false).expect("compress")
}

/// A level of modular radiance transfer baked quickly: a small dictionary (8 x 8 samples a
/// face, 1,024 rays; a coarse lightfield) and `scene`'s level to d_max 8; and the scene with
/// the light map's uv1.
pub fn mrt_quick_bake(scene: &Scene) -> (Dictionary, Mapped, LevelData, Scene) {
    let dictionary = quick_dictionary();
    let (mapped, level) = bake_level(scene, &dictionary, 8).expect("the level bakes");
    let applied = with_light_map(scene, &mapped);
    (dictionary, mapped, level, applied)
}

/// `scene` with the light map's uv1 of `mapped` on its meshes.
fn with_light_map(scene: &Scene, mapped: &Mapped) -> Scene {
    let mut applied = scene.clone();
    for (mesh, atlas_mesh) in applied.meshes.iter_mut().zip(&mapped.meshes) {
        *mesh = atlas_mesh.apply(mesh);
    }
    applied
}

/// As [`mrt_quick_bake`], on the block proxy derived from `scene` (its own declaration
/// ignored): the scene as the derivation split it, with the light map's uv1.
pub fn mrt_quick_bake_derived(scene: &Scene) -> (Dictionary, Mapped, LevelData, Scene) {
    let mut bare = scene.clone();
    bare.settings.blocks.remove("mrt");
    let derived = relume_bake::mrt::derive::derive(&bare, &SceneBvh::new(&bare)).expect("a proxy derives");
    let fine = derived.split.as_ref().map_or_else(|| bare.clone(), |s| s.apply(&bare));
    let dictionary = quick_dictionary();
    let (mapped, level) =
        relume_bake::mrt::baker::bake_on(&fine, &derived.proxy, &derived.dynamic, &dictionary, 8).expect("the level bakes");
    let applied = with_light_map(&fine, &mapped);
    (dictionary, mapped, level, applied)
}

/// A small dictionary: 8 x 8 samples a face, 1,024 rays; a coarse lightfield. Built once per
/// test binary (the same bytes every time: its seeds are fixed) and shared by its tests.
fn quick_dictionary() -> Dictionary {
    static QUICK: std::sync::OnceLock<Dictionary> = std::sync::OnceLock::new();
    let build = || {
        let block = BlockSettings { samples_per_face: 8, gather_rays: 1024, ..BlockSettings::default() };
        let lightfield =
            InterfaceSettings { positions: 6, directions: 9, supersamples: 1, gather_rays: 512, ..InterfaceSettings::default() };
        Dictionary::build(&block, &lightfield, |_| Ok(())).expect("the dictionary builds")
    };
    QUICK.get_or_init(build).clone()
}
