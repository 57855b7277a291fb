//! Any bytes given to the Sponge schematic importer (gzip or raw NBT): an error or a scene
//! whose composite keeps the world's invariants, never a panic or a hang.
#![no_main]

use libfuzzer_sys::fuzz_target;

static TABLE: std::sync::OnceLock<app::formats::schem::BlockTable> = std::sync::OnceLock::new();

fuzz_target!(|data: &[u8]| {
    // The table is parsed once, not per input (it was most of each run's time).
    let table = TABLE.get_or_init(app::formats::schem::BlockTable::builtin);
    if let Ok((scene, report)) =
        app::formats::schem::import(data, std::path::Path::new("fuzz.schem"), table, 1)
    {
        let view = scene.world.read();
        view.validate().expect("imported world keeps its invariants");
        assert_eq!(view.solid_count(), report.voxels);
    }
});
