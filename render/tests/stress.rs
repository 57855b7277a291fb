//! The numerical stress suite's smaller CI run (`voxbrick stress` runs the full one): every
//! ray class through the GPU traversal against the exact CPU cast in both ray worlds, and
//! every adversarial scene on the GPU and the CPU reference, with every count zero.

mod common;

use render::stress::{StressConfig, image_suite, ray_suite};
use render::vulkan::DeviceChoice;
use std::sync::Arc;

const CONFIG: StressConfig = StressConfig {
    rays_per_class: 20_000,
    gpu_size: 16,
    gpu_renders: 2,
    cpu_size: 8,
    cpu_renders: 1,
    seed: 3,
};

#[test]
fn gpu_traversal_agrees_with_the_cpu_cast_on_adversarial_rays() {
    let Some(ctx) = common::gpu_context(DeviceChoice::Best) else {
        return;
    };
    let ctx = Arc::new(ctx);
    let rows = ray_suite(&ctx, &CONFIG, |_| {}).unwrap();
    assert_eq!(rows.len(), 24, "12 classes in 2 worlds");
    for r in &rows {
        let t = &r.tally;
        assert_eq!(
            t.tried, CONFIG.rays_per_class as u64,
            "{} {}",
            r.world, r.class
        );
        assert_eq!(
            t.exact + t.edge_faces + t.f32_ties + t.mismatches + t.cpu_errors,
            t.tried,
            "{} {}: every ray judged",
            r.world,
            r.class
        );
        assert_eq!(
            (t.mismatches, t.caps_hit, t.cpu_errors),
            (0, 0, 0),
            "{} {}: {:?}",
            r.world,
            r.class,
            t.examples
        );
    }
    // The rays reach geometry: inside-voxel rays all hit, the dense world is hit often.
    assert!(
        rows.iter()
            .all(|r| r.class != "from inside voxels" || r.tally.hits == r.tally.tried)
    );
    assert!(rows[0].tally.hits > 1000, "random rays hit the dense world");
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn adversarial_scenes_have_no_bad_samples_and_furnaces_keep_their_energy() {
    let Some(ctx) = common::gpu_context(DeviceChoice::Best) else {
        return;
    };
    let ctx = Arc::new(ctx);
    let rows = image_suite(Some(&ctx), &CONFIG, |_| {}).unwrap();
    assert!(
        rows.len() >= 26,
        "13 scenes on both renderers: {}",
        rows.len()
    );
    for r in &rows {
        assert!(r.samples > 0);
        assert!(r.clean(), "{} on the {}: {r:?}", r.scene, r.renderer);
    }
    // The conserving furnaces and the closed lamp box are exact (zero variance).
    for r in rows.iter().filter(|r| {
        r.scene == "furnace: lambertian"
            || r.scene == "furnace: mirror"
            || r.scene.starts_with("emissive only")
    }) {
        let e = r.expected.unwrap();
        assert!((r.mean - e).abs() <= 1e-5 * e, "{r:?}");
    }
    assert_eq!(ctx.validation_errors(), 0);
}
