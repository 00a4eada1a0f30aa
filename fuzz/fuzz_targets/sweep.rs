//! The sweep file reader (`relume bench SWEEP`) on any text: read and checked, or refused.
#![no_main]

use libfuzzer_sys::fuzz_target;

// The very source relume compiles, without the renderer the rest of relume-tools needs.
#[allow(dead_code)]
#[path = "../../tools/src/bench/sweep.rs"]
mod sweep;

/// sweep.rs takes its default warm-up from relume's `gpu` module, which needs the renderer;
/// any value in its checked range parses the same.
mod gpu {
    pub const WARM_UP_SECONDS: f64 = 0.5;
}

/// sweep.rs names a scene without a name as `relume bake` does (tools/src/bake.rs, which
/// needs the renderer too): by its file name.
mod bake {
    pub fn scene_name(scene: &std::path::Path) -> String {
        scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into())
    }
}

fuzz_target!(|data: &[u8]| {
    let _ = sweep::Sweep::read(&relume_fuzz::scratch_file("sweep.toml", data));
});
