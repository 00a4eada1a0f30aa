//! Passes are checked against their shaders' SPIR-V when their pipelines are made: a pass that
//! binds another kind of resource than its shader declares, binds nothing where the shader
//! reads, or pushes a shorter block than the shader's is refused at creation, with the pass and
//! the binding named, not left to a validation message at draw time. And no pass outside the
//! backend records a barrier by hand: every barrier comes from the uses a pass declares.

use relume_renderer::passes::compute::{ComputePass, Slot};
use relume_renderer::passes::graphics::{GraphicsPass, Shaders};
use relume_renderer::shaders;
use relume_renderer::vk::{vk, Access, Buffer, Image, ImageDesc};
use relume_tests::*;

fn image(ctx: &std::sync::Arc<relume_renderer::vk::Context>, format: vk::Format, usage: vk::ImageUsageFlags) -> Image {
    let desc = ImageDesc { width: 4, height: 4, layers: 1, format, usage, view_type: vk::ImageViewType::TYPE_2D };
    Image::new(ctx, "pass interface test", desc).expect("image")
}

#[test]
fn a_pass_that_disagrees_with_its_shader_is_refused_naming_the_pass_and_the_binding() {
    let ctx = validated_context();
    let storage = image(&ctx, vk::Format::R32G32B32A32_SFLOAT, vk::ImageUsageFlags::STORAGE);
    let display = image(&ctx, vk::Format::R8G8B8A8_UNORM, vk::ImageUsageFlags::STORAGE);
    let buffer = Buffer::with_data(&ctx, "pass interface test", vk::BufferUsageFlags::STORAGE_BUFFER, &[0.0f32; 4]).expect("buffer");
    let (read, write) = (Access::ComputeStorageRead, Access::ComputeStorageWrite);

    // tonemap.comp: binding 0 a storage image read, binding 1 one written, a 4-byte push block.
    let right = [Slot::StorageImage(&storage, read), Slot::StorageImage(&display, write)];
    ComputePass::<f32>::new(&ctx, "tonemap", shaders::TONEMAP_COMP, &right).expect("the pass as relume makes it");

    let wrong_kind = [Slot::Buffer(&buffer, read), Slot::StorageImage(&display, write)];
    let why = refusal(ComputePass::<f32>::new(&ctx, "tonemap", shaders::TONEMAP_COMP, &wrong_kind));
    says(&why, &["pass tonemap", "binding 0", "STORAGE_IMAGE in its shader", "binds a STORAGE_BUFFER"]);

    let missing = [Slot::StorageImage(&storage, read)];
    let why = refusal(ComputePass::<f32>::new(&ctx, "tonemap", shaders::TONEMAP_COMP, &missing));
    says(&why, &["pass tonemap", "binding 1", "binds nothing"]);

    let why = refusal(ComputePass::<u16>::new(&ctx, "tonemap", shaders::TONEMAP_COMP, &right));
    says(&why, &["pass tonemap", "push block is 4 bytes", "pushes 2"]);

    // A ping-pong pass's sets bind the same kinds in the same places.
    let other = [Slot::Buffer(&buffer, read), Slot::StorageImage(&display, write)];
    let why = refusal(ComputePass::<f32>::with_sets(&ctx, "tonemap", shaders::TONEMAP_COMP, &[&right, &other]));
    says(&why, &["pass tonemap", "set 1 binds", "set 0 binds"]);

    // vsm_moments: binding 0 the lights' storage buffer, binding 1 the layers'; an 8-byte push.
    let scene = relume_renderer::gpu_scene::GpuScene::upload_blocking(&ctx, &load_scene("cornell")).expect("scene");
    let moments = image(&ctx, vk::Format::R32G32_SFLOAT, vk::ImageUsageFlags::COLOR_ATTACHMENT);
    let depth = image(&ctx, vk::Format::D32_SFLOAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT);
    let vsm = Shaders { vertex: shaders::VSM_MOMENTS_VERT, fragment: shaders::VSM_MOMENTS_FRAG, specialization: &[], attributes: 1 };
    let wrong_kind = [Slot::Updated(&scene.lights), Slot::Uniform(&scene.frame)];
    let why = refusal(GraphicsPass::<[u32; 2], 1>::new(&ctx, "vsm_moments", &scene, &vsm, &wrong_kind, ([&moments], &depth)));
    says(&why, &["pass vsm_moments", "binding 1", "STORAGE_BUFFER in its shader", "binds a UNIFORM_BUFFER"]);
    let right = [Slot::Updated(&scene.lights), Slot::Updated(&scene.layers)];
    let why = refusal(GraphicsPass::<u32, 1>::new(&ctx, "vsm_moments", &scene, &vsm, &right, ([&moments], &depth)));
    says(&why, &["pass vsm_moments", "push block is 8 bytes", "pushes 4"]);
    drop((scene, storage, display, buffer, moments, depth));
    assert_clean(ctx);
}

/// Calls that record a barrier, or bring a resource into a use, by hand.
const BY_HAND: [&str; 8] = [
    "use_image(",
    "use_buffer(",
    ".declare(",
    "image_barrier(",
    "buffer_barrier(",
    "cmd_pipeline_barrier",
    "transition(",
    "barrier_between(",
];

/// The one exception: the caller's own image, which no tracker knows, taken from the state the
/// caller gives (`Renderer::record_to`, inside the pass that copies into it).
const CALLERS_IMAGE: (&str, &str) =
    ("renderer/src/frame.rs", "state = transition(rec, target_ref, target.state, Access::TransferDestination);");

#[test]
fn no_pass_outside_the_backend_records_a_barrier_by_hand() {
    let mut folders = vec![repo_root().join("renderer/src")];
    let mut offenders = Vec::new();
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).expect("a renderer folder") {
            let path = entry.expect("a folder entry").path();
            if path.is_dir() {
                if !path.ends_with("vk") {
                    folders.push(path);
                }
                continue;
            }
            let text = std::fs::read_to_string(&path).expect("a source file");
            for (n, line) in text.lines().enumerate() {
                if path.ends_with(CALLERS_IMAGE.0) && line.trim() == CALLERS_IMAGE.1 {
                    continue;
                }
                if let Some(call) = BY_HAND.iter().find(|call| line.contains(*call)) {
                    offenders.push(format!("{}:{}: {call}", path.display(), n + 1));
                }
            }
        }
    }
    assert!(offenders.is_empty(), "passes declare their uses (Tracker::pass) and never barrier by hand:\n{}", offenders.join("\n"));
}
