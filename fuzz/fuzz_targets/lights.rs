//! The lights file reader (`--lights FILE`, the viewer's saved lights) on any bytes: read and
//! checked, or refused.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = relume_bake::lights_file::read(&relume_fuzz::scratch_file("lights.json", data));
});
