//! The frame loop allocates nothing: a counting allocator watches the thread that renders
//! while frames are rendered, lights are moved, the ambient term (and the composition of the
//! light path maps) changes, occluders move and timings are read, without obscurance, with
//! it, with light path maps, with FIV, and with a light cloud (whose weights follow the lights
//! on the CPU); and an effect's frames as an engine records them. (Its own test binary, so no
//! other test shares the allocator.)

use glam::{Vec3, Vec4};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::bvh::SceneBvh;
use relume_bake::fiv::{self, FivBakeSettings, Grid, SumOptions};
use relume_bake::light_cloud::{self, LightCloudBakeSettings, LightCloudSceneSettings};
use relume_bake::light_path_maps::ClusteredTransfer;
use relume_bake::scene::{Light, Scene};
use relume_bake::testing;
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::fiv::FivData;
use relume_renderer::techniques::light_cloud::LightCloudData;
use relume_renderer::techniques::light_path_maps::{Composition, LightPathMapsData};
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::vk::{CommandBuffer, Fence};
use relume_renderer::{Effect, EngineInputs, Headless, MakeTechnique, RenderSettings, TermReads};
use relume_tests::synthetic_light_path_maps::{atlas_scene, constant_obscurance, synthetic_transfer};
use relume_tests::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::Arc;

struct CountingAllocator;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; the counter is a const-initialised thread-local
// that never allocates.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|n| n.set(n.get() + 1));
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|n| n.set(n.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// Heap allocations made by 10 frames that move the first light (and, with `ambient`,
/// change the ambient term) every frame, after one warm-up frame.
fn frame_allocations(renderer: &mut Headless, scene: &Scene, ambient: bool) -> usize {
    frame_allocations_with(renderer, scene, |renderer, frame| {
        if ambient {
            renderer.set_ambient(Vec3::splat(0.1 * frame as f32), 0.05 * frame as f32).expect("valid ambient");
        }
    })
}

/// Heap allocations made by 10 frames that move the first light (if there is one) and call
/// `change` (with the frame number) every frame, after one warm-up frame.
fn frame_allocations_with(renderer: &mut Headless, scene: &Scene, change: impl Fn(&mut Headless, usize)) -> usize {
    renderer.render().expect("warm-up frame");
    let mut lights = scene.lights.clone();
    let before = allocations();
    for frame in 0..10 {
        if let Some(light) = lights.first_mut() {
            light.position += Vec3::new(0.001 * frame as f32, 0.0, 0.0);
            renderer.set_lights(&lights).expect("same kinds");
        }
        change(renderer, frame);
        let timings = renderer.render().expect("frame");
        assert!(timings.passes().iter().all(|(_, ms)| ms.is_finite()));
    }
    allocations() - before
}

fn settings() -> RenderSettings {
    RenderSettings { width: 64, height: 64, shadow_map_size: 64, ..RenderSettings::default() }
}

#[test]
fn frames_allocate_nothing() {
    let scene = load_scene("cornell");
    let ctx = validated_context();
    let mut renderer = new_renderer(&ctx, &scene, &settings(), &[]);
    let during = frame_allocations(&mut renderer, &scene, false);
    drop(renderer);
    assert_clean(ctx);
    assert_eq!(during, 0, "10 frames made {during} heap allocations");
}

#[test]
fn frames_with_a_moving_occluder_allocate_nothing() {
    let scene = load_scene("occluder-stacked");
    let ctx = validated_context();
    let mut renderer = new_renderer(&ctx, &scene, &settings(), &[]);
    let last = scene.meshes.len() - 1;
    let during = frame_allocations_with(&mut renderer, &scene, |renderer, frame| {
        renderer.set_mesh_translation(last, Vec3::new(0.01 * frame as f32, 0.0, 0.0)).expect("a mesh of the scene");
    });
    drop(renderer);
    assert_clean(ctx);
    assert_eq!(during, 0, "10 frames with a moving occluder made {during} heap allocations");
}

#[test]
fn frames_with_obscurance_and_changing_ambient_allocate_nothing() {
    let mut scene = load_scene("cornell");
    let atlas = Atlas::build(&scene, &AtlasSettings { texel_density: 8.0, ..AtlasSettings::default() }).expect("atlas");
    atlas.apply_to(&mut scene);
    let texels: Vec<Vec4> = atlas.texels.iter().map(|t| Vec4::new(0.7, 0.6, 0.5, t.coverage)).collect();
    let obscurance = ObscuranceData { obscurance: atlas_image(&atlas, &texels) };
    let ctx = validated_context();
    let mut renderer = new_renderer(&ctx, &scene, &settings(), &[&obscurance]);
    let during = frame_allocations(&mut renderer, &scene, true);
    drop(renderer);
    assert_clean(ctx);
    assert_eq!(during, 0, "10 frames made {during} heap allocations");
}

/// Cornell on an atlas, a constant obscurance on it and a synthetic transfer: the light path
/// maps' data (with the obscurance they hand over beside their own term).
fn light_path_maps_data() -> (Atlas, Scene, Vec<Vec4>, ClusteredTransfer) {
    let (atlas, scene) = atlas_scene(&load_scene("cornell"), 16.0);
    let texels = constant_obscurance(&atlas, Vec3::new(0.7, 0.6, 0.5));
    let transfer = synthetic_transfer(&atlas, vec![0, 20, 40, 64], 2, 1);
    (atlas, scene, texels, transfer)
}

#[test]
fn frames_with_light_path_maps_allocate_nothing() {
    let (atlas, scene, texels, transfer) = light_path_maps_data();
    let obscurance = ObscuranceData { obscurance: atlas_image(&atlas, &texels) };
    let maps = LightPathMapsData { transfer: &transfer, atlas: atlas_image(&atlas, &texels), composition: Composition::default() };
    let ctx = validated_context();
    let mut renderer = new_renderer(&ctx, &scene, &settings(), &[&obscurance, &maps]);
    let during = frame_allocations_with(&mut renderer, &scene, |renderer, frame| {
        set_composition(renderer, Composition::ALL[frame % 3]);
        renderer.set_ambient(Vec3::splat(0.1 * frame as f32), 0.0).expect("valid ambient");
    });
    drop(renderer);
    assert_clean(ctx);
    assert_eq!(during, 0, "10 frames made {during} heap allocations");
}

#[test]
fn frames_with_fiv_moving_occluders_and_a_deforming_receiver_allocate_nothing() {
    let scene = testing::occluders_over_ground(
        &[(Vec3::new(0.0, 1.0, 0.0), 0.5), (Vec3::new(0.8, 0.7, 0.0), 0.3)],
        |d| Vec3::splat(d.y.max(0.1)),
        8,
    );
    let settings_fiv = FivBakeSettings { grid: Grid::parse("8x5x3").unwrap(), difmap_width: 16, ..FivBakeSettings::default() };
    let (baked, types) = fiv::bake(&scene, &settings_fiv, &WorkOptions::default()).expect("bake");
    let data = FivData { bake: &baked, occluders: &fiv::occluders(&scene, &types), options: SumOptions::default() };
    let ctx = validated_context();
    let mut renderer = new_renderer(&ctx, &scene, &settings(), &[&data]);
    // The ground's shapes are made before the frames: a deforming receiver's data is the caller's.
    let waves: Vec<_> = (0..3).map(|k| testing::waved(&scene.meshes[0], 0.05 * k as f32, 2.0)).collect();
    let during = frame_allocations_with(&mut renderer, &scene, |renderer, frame| {
        renderer.set_mesh_translation(1, Vec3::new(0.02 * frame as f32, 0.0, 0.0)).expect("an occluder of the scene");
        renderer.set_mesh_translation(2, Vec3::new(0.0, 0.01 * frame as f32, 0.0)).expect("an occluder of the scene");
        let (positions, normals) = &waves[frame % waves.len()];
        renderer.set_mesh_vertices(0, positions, normals).expect("the ground's vertices");
    });
    drop(renderer);
    assert_clean(ctx);
    assert_eq!(during, 0, "10 frames with moving occluders made {during} heap allocations");
}

#[test]
fn frames_with_a_light_cloud_and_moving_lights_allocate_nothing() {
    let scene = load_scene("cornell-cloud");
    let bvh = SceneBvh::new(&scene);
    let grid = LightCloudSceneSettings::of(&scene).unwrap().grid;
    let cloud = light_cloud::bake(
        &scene,
        &bvh,
        &LightCloudBakeSettings { grid: Some(grid), directions: 0, samples: 1, emission: 1, work: WorkOptions::default() },
    )
    .expect("bake");
    // In zones of clustered lights, as the method's defaults bake it.
    let cloud = light_cloud_by_defaults(&scene, &bvh, &cloud);
    let data = LightCloudData {
        cloud: &cloud,
        nearest: 8,
        nearest_directions: 3,
        fade_seconds: 0.25,
        visibility: Arc::new(move |a, b| bvh.visible(a, b)),
    };
    let ctx = validated_context();
    let mut renderer = new_renderer(&ctx, &scene, &settings(), &[&data]);
    // Each frame also moves the light continuously (the fade advancing), from lists made
    // before the frames.
    let moved: Vec<Vec<Light>> = (0..10)
        .map(|k| {
            let mut lights = scene.lights.clone();
            lights[0].position += Vec3::new(0.0, -0.01 * k as f32, 0.02 * k as f32);
            lights
        })
        .collect();
    let during = frame_allocations_with(&mut renderer, &scene, |renderer, frame| {
        renderer.move_lights(&moved[frame], 1.0 / 60.0).expect("same kinds");
    });
    drop(renderer);
    assert_clean(ctx);
    assert_eq!(during, 0, "10 frames with a light cloud made {during} heap allocations");
}

#[test]
fn effect_frames_for_an_engine_allocate_nothing() {
    // Light path maps as an effect: relume's shadow maps, the technique's four passes and the
    // barriers to the engine's reads, recorded as an engine records them.
    let (atlas, scene, texels, transfer) = light_path_maps_data();
    let obscurance = ObscuranceData { obscurance: atlas_image(&atlas, &texels) };
    let maps = LightPathMapsData { transfer: &transfer, atlas: atlas_image(&atlas, &texels), composition: Composition::default() };
    let ctx = validated_context();
    let techniques: [&dyn MakeTechnique; 2] = [&obscurance, &maps];
    let mut effect = Effect::new_blocking(&ctx, &scene, &settings(), &techniques, &EngineInputs::default()).expect("effect");
    let (cmd, fence) = (CommandBuffer::new(&ctx).expect("command buffer"), Fence::new(&ctx).expect("fence"));
    let frame = |effect: &mut Effect| {
        let rec = ctx.begin(cmd.raw).expect("begin");
        effect.record(&rec, TermReads::default()).expect("the effect's frame");
        ctx.submit_and_wait(rec, &fence).expect("submitted");
    };
    frame(&mut effect);
    let mut lights = scene.lights.clone();
    let before = allocations();
    for k in 0..10 {
        lights[0].position += Vec3::new(0.001 * k as f32, 0.0, 0.0);
        effect.set_lights(&lights).expect("same kinds");
        frame(&mut effect);
    }
    let during = allocations() - before;
    drop((effect, cmd, fence));
    assert_clean(ctx);
    assert_eq!(during, 0, "10 effect frames made {during} heap allocations");
}
