//! The renderer as a library: every light kind's shadows against the reference, the
//! caller-owned command buffer contract, moving lights and occluders, refusal of bad settings, and proof
//! that a validation message is caught.

use glam::Vec3;
use gpu_allocator::MemoryLocation;
use relume_bake::scene::{Light, LightKind, Scene};
use relume_bake::testing::{self, Facing};
use relume_renderer::vk::{vk, Access, Buffer, CommandBuffer, CommandRecorder, Fence, Readback};
use relume_renderer::RenderSettings;
use relume_tests::*;

/// A 4 m ground plane with a 0.6 m box floating 0.8 m above it, seen from above at an angle.
fn floating_box(light: Light) -> Scene {
    let grey = testing::material("grey", Vec3::splat(0.7), Vec3::ZERO);
    let ground = testing::square(Vec3::ZERO, Vec3::X * 2.0, -Vec3::Z * 2.0, 4, 0);
    let occluder = testing::closed_box(Vec3::new(-0.3, 0.8, -0.3), Vec3::new(0.3, 1.4, 0.3), 1, Facing::Outward, 0);
    let camera = testing::look_at(Vec3::new(0.0, 3.5, 3.5), Vec3::ZERO, Vec3::Y, 50f32.to_radians());
    testing::scene("floating box", vec![ground, occluder], vec![grey], vec![light], camera)
}

fn settings() -> RenderSettings {
    RenderSettings { width: 256, height: 256, ..RenderSettings::default() }
}

#[test]
fn point_light_cube_shadows_match_the_reference() {
    // Above the box (its shadow in the -Y face), then beside it on each side, so the shadow
    // falls through the -X, +X, -Z and +Z faces while the ground near the light uses -Y.
    let positions = [
        Vec3::new(0.2, 2.5, 0.1),
        Vec3::new(1.5, 2.0, 0.2),
        Vec3::new(-1.5, 2.0, -0.2),
        Vec3::new(0.2, 2.0, 1.5),
        Vec3::new(-0.2, 2.0, -1.5),
    ];
    for (i, position) in positions.into_iter().enumerate() {
        let scene = floating_box(testing::point_light(position, Vec3::splat(20.0)));
        let nrmse = direct_nrmse(&format!("point_light_vsm_{i}"), &scene, &settings());
        assert!(nrmse <= 0.05, "light at {position}: NRMSE {nrmse} > 0.05");
    }
}

#[test]
fn directional_light_shadows_match_the_reference() {
    let light = Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        intensity: Vec3::splat(3.0),
        range: None,
        position: Vec3::ZERO,
        direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
    };
    assert!(direct_nrmse("directional_vsm", &floating_box(light), &settings()) <= 0.05);
}

#[test]
fn a_frame_records_into_the_callers_command_buffer() {
    let scene = load_scene("occluder-plane");
    let ctx = validated_context();
    let mut headless = new_renderer(&ctx, &scene, &settings(), &[]);
    let (own_frame, _) = headless.render_and_read().expect("frame");

    // The caller owns the command buffer, the fence and the submission.
    let mut library = headless.into_renderer();
    let readback = Readback::for_image(&ctx, "caller's readback", library.radiance()).expect("readback");
    let cmd = CommandBuffer::new(&ctx).expect("command buffer");
    let fence = Fence::new(&ctx).expect("fence");
    let rec = ctx.begin(cmd.raw).expect("begin");
    let callers = CommandRecorder::wrap(&ctx, rec.cmd);
    library.record(&callers);
    assert_eq!(library.radiance_state(), Access::ComputeStorageRead.state());
    assert_eq!(library.display_state(), Access::ComputeStorageWrite.state());
    library.record_readback(&callers, "radiance", &readback).expect("radiance is a resource");
    ctx.submit_and_wait(rec, &fence).expect("submit");
    let callers_frame = radiance_of(&readback, own_frame.width, own_frame.height);
    assert_eq!(own_frame, callers_frame, "the caller's frame has the renderer's own pixels");
    assert!(callers_frame.pixels.iter().any(|p| p.max_element() > 0.0), "the frame is not black");

    let mut headless = relume_renderer::Headless::new(library).expect("headless driver");
    let (again, _) = headless.render_and_read().expect("frame");
    assert_eq!(own_frame, again, "the same frame twice gives the same pixels");
    drop((headless, readback, fence, cmd));
    assert_clean(ctx);
}

#[test]
fn moving_a_light_needs_no_new_renderer() {
    let scene = load_scene("occluder-plane");
    let mut moved = scene.clone();
    moved.lights[0].position += Vec3::new(0.4, 0.0, -0.3);
    let ctx = validated_context();
    let mut renderer = new_renderer(&ctx, &scene, &settings(), &[]);
    let (before, _) = renderer.render_and_read().expect("frame");
    renderer.set_lights(&moved.lights).expect("same kinds");
    let (after, _) = renderer.render_and_read().expect("frame");
    let mut fresh = new_renderer(&ctx, &moved, &settings(), &[]);
    let (expected, _) = fresh.render_and_read().expect("frame");
    let mut wrong_kind = moved.lights.clone();
    wrong_kind[0].kind = LightKind::Point;
    assert!(renderer.set_lights(&wrong_kind).is_err(), "a light changing kind is refused");
    drop((renderer, fresh));
    assert_clean(ctx);
    assert_ne!(before, after, "the light moved");
    assert_eq!(after, expected, "a moved light renders as a fresh renderer does");
}

#[test]
fn moving_an_occluder_needs_no_new_renderer() {
    let scene = load_scene("occluder-plane");
    let (cube, shift) = (scene.meshes.len() - 1, Vec3::new(0.3, 0.1, -0.2));
    let mut moved = scene.clone();
    for p in &mut moved.meshes[cube].positions {
        *p += shift;
    }
    let ctx = validated_context();
    let mut renderer = new_renderer(&ctx, &scene, &settings(), &[]);
    let (before, _) = renderer.render_and_read().expect("frame");
    renderer.set_mesh_translation(cube, shift).expect("a mesh of the scene");
    renderer.set_lights(&scene.lights).expect("same lights: refits the shadow maps to the moved scene");
    let (after, _) = renderer.render_and_read().expect("frame");
    let mut fresh = new_renderer(&ctx, &moved, &settings(), &[]);
    let (expected, _) = fresh.render_and_read().expect("frame");
    assert!(renderer.set_mesh_translation(scene.meshes.len(), shift).is_err(), "a mesh the scene lacks is refused");
    assert!(renderer.set_mesh_translation(cube, Vec3::NAN).is_err(), "a NaN translation is refused");
    drop((renderer, fresh));
    assert_clean(ctx);
    assert_ne!(before, after, "the occluder moved");
    assert_eq!(after, expected, "a moved occluder renders as a fresh renderer of the moved scene does");
}

#[test]
fn impossible_settings_are_refused() {
    let bad = [
        RenderSettings { width: 0, ..settings() },
        RenderSettings { shadow_map_size: 4, ..settings() },
        RenderSettings { bleeding_reduction: 1.0, ..settings() },
        RenderSettings { min_variance: f32::NAN, ..settings() },
        RenderSettings { exposure: -1.0, ..settings() },
    ];
    for settings in bad {
        assert!(settings.validate().is_err(), "{settings:?} was accepted");
    }
    assert!(settings().validate().is_ok());
}

#[test]
fn a_validation_error_is_caught() {
    let ctx = validated_context();
    // A buffer with no usage at all is invalid Vulkan (VUID-VkBufferCreateInfo-usage-requiredbitmask).
    let buffer = Buffer::new(&ctx, "no usage", 64, vk::BufferUsageFlags::empty(), MemoryLocation::GpuOnly);
    drop(buffer);
    let messages = ctx.validation_messages();
    assert!(messages.iter().any(|m| m.contains("usage")), "no validation message: {messages:?}");
}

#[test]
fn base_colour_textures_match_the_reference() {
    let mut plane = testing::square(Vec3::ZERO, Vec3::X * 2.0, -Vec3::Z * 2.0, 2, 0);
    // Two repeats of the texture across the plane, so repeat wrapping is exercised.
    plane.uv0 = Some(plane.positions.iter().map(|p| glam::Vec2::new(p.x + 2.0, p.z + 2.0) * 0.5).collect());
    let checker: Vec<glam::Vec4> =
        (0..16).map(|i| if (i % 4 + i / 4) % 2 == 0 { glam::Vec4::new(1.0, 0.2, 0.1, 1.0) } else { glam::Vec4::ONE }).collect();
    let texture = relume_bake::scene::Texture { name: "checker".into(), width: 4, height: 4, texels: checker };
    let mut material = testing::material("checked", Vec3::splat(0.8), Vec3::ZERO);
    material.base_color_texture = Some(0);
    let camera = testing::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 50f32.to_radians());
    let light = testing::point_light(Vec3::new(0.3, 2.0, 0.2), Vec3::splat(10.0));
    let mut scene = testing::scene("checker", vec![plane], vec![material], vec![light], camera);
    scene.textures.push(texture);
    let nrmse = direct_nrmse("textured", &scene, &RenderSettings { shadows: false, ..settings() });
    assert!(nrmse <= 0.01, "NRMSE {nrmse} > 0.01");
}

#[test]
fn the_gpu_tonemap_matches_the_cpu_display_transform() {
    let scene = load_scene("cornell");
    let ctx = validated_context();
    let settings = RenderSettings { exposure: 1.7, ..settings() };
    let mut renderer = new_renderer(&ctx, &scene, &settings, &[]);
    let (radiance, display) = renderer.render_and_read().expect("frame");
    let mut worst = 0;
    for (pixel, rgba) in radiance.pixels.iter().zip(display.chunks_exact(4)) {
        let cpu = relume_bake::image::tonemap_to_srgb8(*pixel, settings.exposure);
        for c in 0..3 {
            worst = worst.max((cpu[c] as i32 - rgba[c] as i32).abs());
        }
    }
    assert!(worst <= 1, "GPU and CPU display values differ by up to {worst} levels");
}
