//! The frame loop allocates nothing: a counting allocator watches the thread that renders
//! while frames are rendered, lights are moved, the ambient term changes and timings are
//! read, with and without a lightmap. (Its own test binary,
//! so no other test shares the allocator.)

use glam::{Vec3, Vec4};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::scene::Scene;
use relume_renderer::{LightmapData, RenderSettings, Renderer};
use relume_tests::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

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
fn frame_allocations(renderer: &mut Renderer, scene: &Scene, ambient: bool) -> usize {
    renderer.render().expect("warm-up frame");
    let mut lights = scene.lights.clone();
    let before = allocations();
    for frame in 0..10 {
        lights[0].position += Vec3::new(0.001 * frame as f32, 0.0, 0.0);
        renderer.set_lights(&lights).expect("same kinds");
        if ambient {
            renderer.set_ambient(Vec3::splat(0.1 * frame as f32), 0.05 * frame as f32).expect("valid ambient");
        }
        let timings = renderer.render().expect("frame");
        assert!(timings.passes_ms.is_none_or(|p| p.iter().all(|ms| ms.is_finite())));
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
    let log = ctx.message_log();
    let mut renderer = Renderer::new(&ctx, &scene, &settings()).expect("renderer");
    let during = frame_allocations(&mut renderer, &scene, false);
    drop(renderer);
    drop(ctx);
    assert_no_validation_messages(&log.lock().unwrap());
    assert_eq!(during, 0, "10 frames made {during} heap allocations");
}

#[test]
fn frames_with_a_lightmap_and_changing_ambient_allocate_nothing() {
    let mut scene = load_scene("cornell");
    let atlas = Atlas::build(&scene, &AtlasSettings { texel_density: 8.0, ..AtlasSettings::default() }).expect("atlas");
    for (mesh, atlas_mesh) in scene.meshes.iter_mut().zip(&atlas.meshes) {
        *mesh = atlas_mesh.apply(mesh);
    }
    let texels: Vec<Vec4> = atlas.texels.iter().map(|t| Vec4::new(0.7, 0.6, 0.5, t.coverage)).collect();
    let lightmap = LightmapData { width: atlas.width, height: atlas.height, pages: atlas.pages, texels: &texels };
    let ctx = validated_context();
    let log = ctx.message_log();
    let mut renderer = Renderer::with_lightmap(&ctx, &scene, &settings(), Some(&lightmap)).expect("renderer");
    let during = frame_allocations(&mut renderer, &scene, true);
    drop(renderer);
    drop(ctx);
    assert_no_validation_messages(&log.lock().unwrap());
    assert_eq!(during, 0, "10 frames made {during} heap allocations");
}
