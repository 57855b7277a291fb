//! Any bytes given to the heightmap reader: an error or a map of the size it says.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = app::formats::heightmap::from_png(data);
});
