//! A technique made outside the renderer crate, as a new method or an integrator would make
//! one, hands the lighting pass a vertex term or a pixel term (the texel term is the
//! obscurance's and the light path maps', tested with them). Every frame its one pass copies
//! the term's values into place, so the lighting pass reads data written earlier in the same
//! frame, across the tracker's barrier. With no light and no ambient, a frame is exactly
//! albedo / pi * E (shaders/lighting.frag): for a vertex term of a linear function of the
//! vertex position, the function at the point each pixel sees; for a pixel term, the pixel's
//! own value. Two irradiance terms in one frame are refused.

use glam::{Vec3, Vec4};
use gpu_allocator::MemoryLocation;
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::scene::Scene;
use relume_bake::testing::{self, Facing};
use relume_renderer::technique::{MakeTechnique, Shared, Source, Technique, Term};
use relume_renderer::vk::{vk, Access, Buffer, CommandRecorder, Image as GpuImage, ImageDesc, Tracker, Use, VkResult};
use relume_renderer::RenderSettings;
use relume_tests::*;

const WIDTH: u32 = 160;
const HEIGHT: u32 = 128;

/// The irradiance term's kind, and where it lives on the GPU.
enum Target {
    Vertices(Buffer),
    Pixels(GpuImage),
}

struct TermTechnique {
    staging: Buffer,
    target: Target,
}

/// A vertex term of `irradiance(position)` at every vertex, or a pixel term of
/// `irradiance(x, y, 0)` at every pixel.
struct TermData {
    per_pixel: bool,
}

/// Irradiance that varies over space (or the image) in every channel, positive on the scene.
fn irradiance(p: Vec3) -> Vec3 {
    Vec3::new(0.5 + 0.2 * p.x, 0.7 + 0.15 * p.z, 0.3 + 0.1 * p.y)
}

fn pixel_value(x: u32, y: u32) -> Vec3 {
    irradiance(Vec3::new(x as f32 / WIDTH as f32, 0.0, y as f32 / HEIGHT as f32))
}

impl MakeTechnique for TermData {
    fn make_blocking(&self, shared: &Shared) -> VkResult<Box<dyn Technique>> {
        let (ctx, settings) = (shared.ctx, shared.settings);
        let values: Vec<Vec4> = match self.per_pixel {
            false => shared.scene.meshes.iter().flat_map(|m| m.positions.iter().map(|p| irradiance(*p).extend(0.0))).collect(),
            true => (0..settings.height).flat_map(|y| (0..settings.width).map(move |x| pixel_value(x, y).extend(0.0))).collect(),
        };
        if !self.per_pixel {
            assert_eq!(values.len(), shared.gpu_scene.vertex_count(), "one value per vertex of the vertex buffer");
        }
        let staging = Buffer::with_data(ctx, "term staging", vk::BufferUsageFlags::TRANSFER_SRC, &values)?;
        let target = match self.per_pixel {
            false => {
                let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
                Target::Vertices(Buffer::new(ctx, "vertex term", staging.size, usage, MemoryLocation::GpuOnly)?)
            }
            true => Target::Pixels(GpuImage::new(
                ctx,
                "pixel term",
                ImageDesc {
                    width: settings.width,
                    height: settings.height,
                    layers: 1,
                    format: vk::Format::R32G32B32A32_SFLOAT,
                    usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
                    view_type: vk::ImageViewType::TYPE_2D_ARRAY,
                },
            )?),
        };
        Ok(Box::new(TermTechnique { staging, target }))
    }
}

impl Technique for TermTechnique {
    fn name(&self) -> &'static str {
        "term_test"
    }

    fn passes(&self) -> &'static [&'static str] {
        &["term_test.copy"]
    }

    fn record(&self, _pass: usize, rec: &CommandRecorder, tracker: &mut Tracker) {
        match &self.target {
            Target::Vertices(buffer) => tracker.pass(rec, [Use::buffer(buffer, Access::TransferDestination)], |rec| {
                rec.copy_buffer(self.staging.raw, 0, buffer.raw, self.staging.size)
            }),
            Target::Pixels(image) => tracker.pass(rec, [Use::image(image, Access::TransferDestination)], |rec| {
                rec.copy_buffer_to_image_layer(self.staging.raw, 0, image, 0, image.desc.extent())
            }),
        }
    }

    fn term(&self) -> Option<Term<'_>> {
        let source = match &self.target {
            Target::Vertices(buffer) => Source::Vertex(buffer),
            Target::Pixels(image) => Source::Pixel(image),
        };
        Some(Term::Irradiance { source, times_occlusion: false, occluded_direct: false })
    }
}

/// A lit-by-nothing floor (orange-ish) and box (blue-ish), tessellated so that a vertex term
/// has vertices to vary over.
fn dark_scene() -> Scene {
    let floor_material = testing::material("floor", Vec3::new(0.8, 0.6, 0.4), Vec3::ZERO);
    let box_material = testing::material("box", Vec3::new(0.3, 0.7, 0.9), Vec3::ZERO);
    let floor = testing::square(Vec3::ZERO, Vec3::X * 2.0, -Vec3::Z * 2.0, 6, 0);
    let block = testing::closed_box(Vec3::new(-0.4, 0.0, -0.4), Vec3::new(0.4, 0.7, 0.4), 3, Facing::Outward, 1);
    let camera = testing::look_at(Vec3::new(1.3, 2.8, 3.1), Vec3::new(0.0, 0.2, 0.0), Vec3::Y, 50f32.to_radians());
    testing::scene("dark floor and box", vec![floor, block], vec![floor_material, box_material], Vec::new(), camera)
}

/// The frame of `scene` with the term technique, and the worst relative error against
/// albedo / pi * `expected(pixel, hit position)` over the interior pixels (and how many).
fn worst_error(scene: &Scene, per_pixel: bool, expected: impl Fn(u32, u32, Vec3) -> Vec3) -> (f32, usize) {
    let ctx = validated_context();
    let settings = RenderSettings { width: WIDTH, height: HEIGHT, ..RenderSettings::default() };
    let mut renderer = new_renderer(&ctx, scene, &settings, &[&TermData { per_pixel }]);
    let first: Image = render(&mut renderer);
    assert_eq!(render(&mut renderer), first, "the term's frames repeat");
    drop(renderer);
    assert_clean(ctx);
    let hits = primary_hits(scene, &SceneBvh::new(scene), WIDTH, HEIGHT);
    let keep = interior_pixels(&hits, WIDTH, HEIGHT);
    let (mut worst, mut counted) = (0.0f32, 0);
    for (i, (hit, kept)) in hits.iter().zip(&keep).enumerate() {
        let Some(hit) = hit.filter(|_| *kept) else { continue };
        let albedo = scene.materials[hit.material as usize].base_color.truncate();
        let want = albedo / std::f32::consts::PI * expected(i as u32 % WIDTH, i as u32 / WIDTH, hit.position);
        worst = worst.max(((first.pixels[i] - want).abs() / want).max_element());
        counted += 1;
    }
    (worst, counted)
}

#[test]
fn a_vertex_term_is_interpolated_from_the_scenes_vertices() {
    let (worst, counted) = worst_error(&dark_scene(), false, |_, _, p| irradiance(p));
    println!("vertex term: worst relative error {worst:.2e} over {counted} pixels");
    assert!(counted > (WIDTH * HEIGHT / 3) as usize, "only {counted} interior pixels");
    // Measured 1.7e-6 on lavapipe (rasteriser interpolation against the CPU ray's hit point).
    assert!(worst <= 1e-5, "the vertex term is off by up to {worst} (relative)");
}

#[test]
fn a_pixel_term_is_read_at_each_pixel() {
    let (worst, counted) = worst_error(&dark_scene(), true, |x, y, _| pixel_value(x, y));
    println!("pixel term: worst relative error {worst:.2e} over {counted} pixels");
    assert!(counted > (WIDTH * HEIGHT / 3) as usize, "only {counted} interior pixels");
    // Measured 0 on lavapipe: the same f32 products on both sides.
    assert!(worst <= 1e-6, "the pixel term is off by up to {worst} (relative)");
}

#[test]
fn two_irradiance_terms_in_one_frame_are_refused() {
    let ctx = validated_context();
    let settings = RenderSettings { width: 16, height: 16, ..RenderSettings::default() };
    let (vertices, pixels) = (TermData { per_pixel: false }, TermData { per_pixel: true });
    says(
        &refusal(try_new_renderer(&ctx, &dark_scene(), &settings, &[&vertices, &pixels])),
        &["term_test", "an irradiance or radiance term"],
    );
    assert_clean(ctx);
}
