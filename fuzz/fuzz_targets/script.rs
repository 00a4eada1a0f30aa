//! The viewer's script reader (`relume view --script FILE`) on any bytes: read and checked,
//! or refused.
#![no_main]

use libfuzzer_sys::fuzz_target;

// The very source relume compiles, without the window and Vulkan the rest of the viewer needs.
#[allow(dead_code)]
#[path = "../../viewer/src/script.rs"]
mod script;

fuzz_target!(|data: &[u8]| {
    let _ = script::read(&relume_fuzz::scratch_file("script.txt", data));
});
