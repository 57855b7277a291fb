//! Any bytes given to the project loader: an error or a scene, never a panic, a hang or an
//! allocation beyond what the input justifies.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(scene) = app::formats::project::from_bytes(data, std::path::Path::new("fuzz.ron"), 1) {
        // A file that loads must describe a consistent world.
        scene.world.read().validate().expect("loaded world keeps its invariants");
    }
});
