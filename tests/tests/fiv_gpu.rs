//! FIV's run time on the GPU (003 §5) against its CPU twin, relume_bake::fiv::FivBake::irradiance,
//! evaluated at the positions and normals the surfaces pass wrote; the lighting pass adding
//! albedo / pi * I; moving occluders and a deforming receiver against a renderer made for
//! the moved or deformed scene; all with
//! validation and synchronization validation on.

use glam::{Vec3, Vec4};
use relume_bake::fiv::{
    bake, occluders, Beyond, FivBake, FivBakeSettings, Grid, Occluder, OccluderType, Radial, Receiver, SelfShadow, SumOptions,
};
use relume_bake::scene::Scene;
use relume_bake::testing::{occluders_over_ground, sky, waved};
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::fiv::{Fiv, FivData};
use relume_renderer::vk::Context;
use relume_renderer::{Headless, RenderSettings};
use relume_tests::*;
use std::f32::consts::PI;
use std::sync::Arc;

const SIZE: u32 = 64;

/// Three balls: two overlapping as seen from the ground, one sunk halfway into it (case B).
fn scene() -> Scene {
    let balls = [(Vec3::new(-0.4, 1.2, 0.0), 0.6), (Vec3::new(0.3, 1.5, 0.2), 0.5), (Vec3::new(1.2, 0.1, -0.8), 0.4)];
    occluders_over_ground(&balls, sky(Vec3::new(0.4, 0.8, 0.3), Vec3::splat(80.0), 4.0), 16)
}

fn baked(scene: &Scene) -> (FivBake, Vec<OccluderType>) {
    let settings = FivBakeSettings { grid: Grid::parse("16x9x8").unwrap(), difmap_width: 32, ..FivBakeSettings::default() };
    bake(scene, &settings, &WorkOptions::default()).expect("bake")
}

/// `scene` baked, its occluders, and a renderer of it with FIV's default choices.
fn baked_renderer(ctx: &Arc<Context>, scene: &Scene) -> (FivBake, Vec<Occluder>, Headless) {
    let (fiv, types) = baked(scene);
    let occluders = occluders(scene, &types);
    let renderer = new_renderer(ctx, scene, &settings(), &[&FivData { bake: &fiv, occluders: &occluders, options: SumOptions::default() }]);
    (fiv, occluders, renderer)
}

fn settings() -> RenderSettings {
    RenderSettings { width: SIZE, height: SIZE, ..RenderSettings::default() }
}

/// The irradiance the GPU wrote against the CPU formula at the GPU's own surface points; the
/// number of surface pixels compared.
fn compare_with_cpu(renderer: &mut Headless, fiv: &FivBake, occluders: &[Occluder], options: SumOptions) -> usize {
    let positions = read_vec4s(renderer, "fiv.positions").expect("positions");
    let normals = read_vec4s(renderer, "fiv.normals").expect("normals");
    let irradiance = read_vec4s(renderer, "fiv.irradiance").expect("irradiance");
    let mut surfaces = 0;
    for (pixel, ((p, n), gpu)) in positions.iter().zip(&normals).zip(&irradiance).enumerate() {
        if p.w == 0.0 {
            assert_eq!(*gpu, Vec4::ZERO, "pixel {pixel} has no surface but irradiance {gpu}");
            continue;
        }
        surfaces += 1;
        let normal = n.truncate().normalize();
        let receiver = Receiver { point: p.truncate(), normal, occluder: (n.w > 0.0).then(|| n.w as usize - 1) };
        let cpu = fiv.irradiance(occluders, receiver, options);
        let scale = fiv.environment.difmap_lookup(normal).max_element().max(1e-6);
        assert!((gpu.truncate() - cpu).abs().max_element() <= 1e-3 * scale, "pixel {pixel}: GPU {gpu}, CPU {cpu} ({options:?})");
    }
    surfaces
}

#[test]
fn occluder_sums_equal_the_cpu_formula_and_the_lighting_pass_adds_albedo_over_pi() {
    let scene = scene();
    let ctx = validated_context();
    let options = SumOptions::default();
    let (fiv, occluders, mut renderer) = baked_renderer(&ctx, &scene);
    let radiance = render(&mut renderer);
    let surfaces = compare_with_cpu(&mut renderer, &fiv, &occluders, options);
    assert!(surfaces > (SIZE * SIZE / 2) as usize, "only {surfaces} surface pixels");
    // Nothing else lights the scene: radiance is albedo / pi * I on the ground, 0 on the balls.
    let positions = read_vec4s(&mut renderer, "fiv.positions").unwrap();
    let irradiance = read_vec4s(&mut renderer, "fiv.irradiance").unwrap();
    for (pixel, (p, e)) in positions.iter().zip(&irradiance).enumerate() {
        let albedo = if p.w == 1.0 && p.y.abs() < 1e-4 { 0.5 } else { 0.0 };
        let expected = albedo / PI * e.truncate();
        assert!((radiance.pixels[pixel] - expected).abs().max_element() <= 1e-5 * (1.0 + expected.max_element()), "pixel {pixel}");
    }
    // Every other choice of the paper's options, on the same renderer.
    for options in [
        SumOptions { partial: false, overlap: false, beyond: Beyond::Drop, radial: Radial::Linear, self_shadow: SelfShadow::Off },
        SumOptions { partial: true, overlap: false, beyond: Beyond::Scale, radial: Radial::Linear, self_shadow: SelfShadow::Paper },
        SumOptions { partial: false, overlap: true, beyond: Beyond::Drop, radial: Radial::InverseSquare, self_shadow: SelfShadow::Surface },
    ] {
        renderer.technique_mut::<Fiv>().expect("fiv").set_options(options);
        render(&mut renderer);
        compare_with_cpu(&mut renderer, &fiv, &occluders, options);
    }
    drop(renderer);
    assert_clean(ctx);
}

#[test]
fn occluders_follow_their_moved_meshes_as_a_renderer_made_for_the_moved_scene() {
    let scene = scene();
    let ctx = validated_context();
    let options = SumOptions::default();
    let (fiv, occluders, mut moving) = baked_renderer(&ctx, &scene);
    render(&mut moving);
    let offsets = [Vec3::new(0.5, 0.2, 0.0), Vec3::new(-0.3, 0.0, 0.4), Vec3::new(0.0, 0.3, 0.0)];
    let mut moved_scene = scene.clone();
    let mut moved_occluders = occluders.clone();
    for (k, offset) in offsets.iter().enumerate() {
        let mesh = occluders[k].mesh;
        moving.set_mesh_translation(mesh, *offset).expect("move the mesh");
        moved_scene.meshes[mesh].positions.iter_mut().for_each(|p| *p += *offset);
        moved_occluders[k].centre = occluders[k].centre + *offset;
    }
    // The ground moves too, but is no occluder: nothing of FIV follows it.
    moving.set_mesh_translation(0, Vec3::new(0.0, -0.1, 0.0)).expect("move the ground");
    moved_scene.meshes[0].positions.iter_mut().for_each(|p| p.y -= 0.1);
    let after_moving = render(&mut moving);
    let mut fresh = new_renderer(&ctx, &moved_scene, &settings(), &[&FivData { bake: &fiv, occluders: &moved_occluders, options }]);
    let made_moved = render(&mut fresh);
    let differing = after_moving.pixels.iter().zip(&made_moved.pixels).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} pixels differ from a renderer made for the moved scene");
    drop((moving, fresh));
    assert_clean(ctx);
}

#[test]
fn occluders_of_a_type_the_bake_lacks_are_refused() {
    let scene = scene();
    let (fiv, _) = baked(&scene);
    let ctx = validated_context();
    let wrong = [Occluder { table: 5, mesh: 1, centre: Vec3::ZERO }];
    let message =
        refusal(try_new_renderer(&ctx, &scene, &settings(), &[&FivData { bake: &fiv, occluders: &wrong, options: SumOptions::default() }]));
    says(&message, &["fiv", "type 5", "3 tables"]);
    assert_clean(ctx);
}

#[test]
fn a_deformed_receiver_renders_as_a_renderer_made_for_the_deformed_scene() {
    let scene = scene();
    let ctx = validated_context();
    let options = SumOptions::default();
    let (fiv, occluders, mut deforming) = baked_renderer(&ctx, &scene);
    let flat = render(&mut deforming);
    let mut waving = scene.clone();
    for frame in 1..=3 {
        let (positions, normals) = waved(&scene.meshes[0], 0.1 * frame as f32, 3.0);
        deforming.set_mesh_vertices(0, &positions, &normals).expect("the ground's vertices");
        waving.meshes[0].positions = positions;
        waving.meshes[0].normals = normals;
    }
    let deformed = render(&mut deforming);
    let mut fresh = new_renderer(&ctx, &waving, &settings(), &[&FivData { bake: &fiv, occluders: &occluders, options }]);
    let made_deformed = render(&mut fresh);
    let differing = deformed.pixels.iter().zip(&made_deformed.pixels).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} pixels differ from a renderer made for the deformed scene");
    assert!(deformed.pixels != flat.pixels, "the wave changed nothing");
    says(&refusal(deforming.set_mesh_vertices(0, &[Vec3::ZERO], &[Vec3::Y])), &["mesh 0", "1 positions", "vertices"]);
    drop((deforming, fresh));
    assert_clean(ctx);
}

#[test]
fn surfaces_face_the_viewer_and_a_lone_ball_does_not_shade_its_top() {
    // From under the ground its back faces show: their normal turns down, as the lighting
    // pass and the path tracer turn it, so they take the dim light from below (every ball is
    // above them: case C) and nothing of the sky.
    let mut below = scene();
    below.camera = relume_bake::testing::look_at(Vec3::new(0.0, -4.0, 0.5), Vec3::ZERO, Vec3::Y, 0.8);
    let ctx = validated_context();
    let (fiv, occluders, mut renderer) = baked_renderer(&ctx, &below);
    render(&mut renderer);
    let from_below = fiv.environment.difmap_lookup(Vec3::NEG_Y);
    let positions = read_vec4s(&mut renderer, "fiv.positions").unwrap();
    let irradiance = read_vec4s(&mut renderer, "fiv.irradiance").unwrap();
    let ground: Vec<Vec3> =
        positions.iter().zip(&irradiance).filter(|(p, _)| p.w == 1.0 && p.y.abs() < 1e-4).map(|(_, e)| e.truncate()).collect();
    assert!(ground.len() > 100, "only {} ground pixels seen from below", ground.len());
    for e in &ground {
        assert!((*e - from_below).abs().max_element() < 0.02 * from_below.max_element(), "{e} against DifMap(-Y) {from_below}");
    }
    drop(renderer);
    assert_clean(ctx);
    // On top of a lone ball, nothing occludes: without self-shadowing its own table takes
    // nothing; with it, a convex ball hides its lower hemisphere only, which is what DifMap
    // leaves out too.
    let top = Receiver { point: occluders[0].centre + Vec3::Y * fiv.tables[occluders[0].table].radius, normal: Vec3::Y, occluder: Some(0) };
    let open = fiv.environment.difmap_lookup(Vec3::Y);
    let off = SumOptions { self_shadow: SelfShadow::Off, ..SumOptions::default() };
    assert_eq!(fiv.irradiance(&occluders[..1], top, off), open);
    let shadowed = fiv.irradiance(&occluders[..1], top, SumOptions::default());
    assert!((shadowed - open).abs().max_element() < 0.02 * open.max_element(), "{shadowed} against DifMap(+Y) {open}");
}
