//! Any bytes given to the Sponge schematic importer (gzip or raw NBT): an error or a scene
//! whose composite keeps the world's invariants, never a panic or a hang.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let table = app::formats::schem::BlockTable::builtin();
    if let Ok((scene, report)) =
        app::formats::schem::import(data, std::path::Path::new("fuzz.schem"), &table, 1)
    {
        let view = scene.world.read();
        view.validate().expect("imported world keeps its invariants");
        assert_eq!(view.solid_count(), report.voxels);
    }
});
