//! Any bytes given to the .vox importer (flattened, as objects, and as objects added to a
//! scene): an error or a scene, never a panic or a hang.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let options = app::formats::vox::ImportOptions::default();
    if let Ok((scene, report)) = app::formats::vox::import_bytes(data, std::path::Path::new("fuzz.vox"), &options, 1) {
        let view = scene.world.read();
        view.validate().expect("imported world keeps its invariants");
        assert_eq!(view.solid_count(), report.voxels);
    }
    // Imported as objects: an error or objects whose composite keeps the invariants.
    if let Ok(import) = app::formats::vox::import_objects(data, std::path::Path::new("fuzz.vox"), 1) {
        import.scene.world.read().validate().expect("the composite keeps the world's invariants");
    }
    // Added to a scene (File → Import): an error, or models that fit and a tree.
    let world = brickmap::World::new(
        brickmap::GridDims::new(8, 4, 8).unwrap(),
        brickmap::WorldConfig::with_workers(1),
    )
    .unwrap();
    if let Ok(into) = app::formats::vox::objects_into(&world, data, glam::IVec3::new(3, 0, 5)) {
        assert!(into.tree.len() >= 1);
    }
});
