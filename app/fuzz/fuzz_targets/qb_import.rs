//! Any bytes given to the Qubicle importer: an error or a scene whose composite keeps the
//! world's invariants, never a panic or a hang.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok((scene, report)) = app::formats::qb::import(data, std::path::Path::new("fuzz.qb"), 1) {
        let view = scene.world.read();
        view.validate().expect("imported world keeps its invariants");
        assert_eq!(view.solid_count() > 0, report.voxels > 0);
    }
});
