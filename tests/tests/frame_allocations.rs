//! The frame loop allocates nothing: a counting allocator watches the thread that renders
//! while frames are rendered, lights are moved and timings are read. (Its own test binary,
//! so no other test shares the allocator.)

use glam::Vec3;
use relume_renderer::{RenderSettings, Renderer};
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

#[test]
fn frames_allocate_nothing() {
    let scene = load_scene("cornell");
    let settings = RenderSettings { width: 64, height: 64, shadow_map_size: 64, ..RenderSettings::default() };
    let ctx = validated_context();
    let log = ctx.message_log();
    let mut renderer = Renderer::new(&ctx, &scene, &settings).expect("renderer");
    renderer.render().expect("warm-up frame");
    let mut lights = scene.lights.clone();

    let before = allocations();
    for frame in 0..10 {
        lights[0].position += Vec3::new(0.001 * frame as f32, 0.0, 0.0);
        renderer.set_lights(&lights).expect("same kinds");
        let timings = renderer.render().expect("frame");
        assert!(timings.passes_ms.is_none_or(|p| p.iter().all(|ms| ms.is_finite())));
    }
    let during = allocations() - before;

    drop(renderer);
    drop(ctx);
    assert_no_validation_messages(&log.lock().unwrap());
    assert_eq!(during, 0, "10 frames made {during} heap allocations");
}
