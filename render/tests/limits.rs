//! The renderer within the device's limits: with `maxStorageBufferRange` and
//! `maxMemoryAllocationSize` capped far below the real ones (as `VOXBRICK_MAX_STORAGE_RANGE` /
//! `VOXBRICK_MAX_ALLOCATION` do), the world goes to the GPU in one buffer per region, the
//! shadow-ray queue holds what fits and the rest is traced in place, the light visibility cache
//! (an experiment) takes the entries that fit, and the image is the uncapped renderer's (same
//! seed, within float rounding), with no validation message. What
//! cannot fit is refused with [`GpuError::Limit`], never bound past a limit, and the
//! interactive viewport traces a smaller internal image instead.

mod common;

use brickmap::GpuBuffer;
use render::Image;
use render::viewport::{FrameRequest, IMAGE_BYTES_PER_PIXEL, RenderHow, Viewport};
use render::vulkan::trace::{EXPERIMENT_LIGHT_CACHE, PathTracer, Variant, queue_fit};
use render::vulkan::{ContextOptions, DeviceChoice, GpuContext, GpuError};
use std::sync::Arc;

/// Image side of the comparisons (64 × 64 pixels: 64 KiB of accumulation).
const SIZE: u32 = 64;

/// A context whose limits are capped to `range` and `allocation` bytes (validation on).
fn capped(range: u64, allocation: u64) -> GpuContext {
    GpuContext::new(&ContextOptions {
        validation: true,
        max_storage_range: Some(range),
        max_allocation: Some(allocation),
        ..Default::default()
    })
    .expect("a second context on the same device")
}

/// Per pixel and channel, |a − b| within float rounding of the larger (relative 1e-4, and
/// 1e-6 absolute for near-black pixels): the same samples added in another order.
fn assert_same_within_rounding(a: &Image, b: &Image, what: &str) {
    assert_eq!((a.width, a.height), (b.width, b.height), "{what}");
    let mut worst: f64 = 0.0;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for k in 0..3 {
            let (x, y) = (p[k] as f64, q[k] as f64);
            let err = (x - y).abs() / (1e-2 + x.abs().max(y.abs()));
            worst = worst.max(err);
            assert!(
                (x - y).abs() <= 1e-6 + 1e-4 * x.abs().max(y.abs()),
                "{what}: {x} against {y}"
            );
        }
    }
    assert!(a.mean()[0] > 0.0, "{what}: a black image proves nothing");
    eprintln!("{what}: worst relative difference {worst:.2e}");
}

#[test]
fn capped_limits_render_the_uncapped_image_without_validation_messages() {
    let Some(full) = common::gpu_context(DeviceChoice::Best) else {
        return;
    };
    let (_, room, room_params) = common::lamp_rooms().remove(1);
    let (show, show_params) = common::showcase();
    for (what, world, params) in [
        ("lamp-lit room", &room, &room_params),
        ("showcase", &show, &show_params),
    ] {
        let view = world.read();
        let regions = GpuBuffer::ALL.map(|b| view.gpu_buffer_size(b));
        let (largest, total) = (*regions.iter().max().unwrap(), regions.iter().sum::<u64>());
        let variant = Variant::for_scene(&view, params);
        assert!(
            variant.sun || variant.lights,
            "{what}: shadow rays are queued"
        );
        drop(view);
        // Caps: every region and the accumulation fit, but not the whole world in one buffer
        // nor the queue a dispatch asks for (a ray per sample at least).
        let range = largest
            .max(u64::from(SIZE * SIZE) * 16)
            .next_multiple_of(256);
        let ctx = capped(range, range);
        assert!(ctx.limits.capped);
        assert!(
            total > ctx.limits.allocation,
            "{what}: the world ({total} bytes) must not fit one capped buffer ({range})"
        );
        let wanted = u64::from(SIZE * SIZE) * 4;
        assert!(
            queue_fit(&ctx.limits) < wanted,
            "{what}: the capped queue ({}) must be smaller than a dispatch's rays ({wanted})",
            queue_fit(&ctx.limits)
        );
        for seed in [3, 4] {
            let a = common::gpu_render_with(&full, world, params, SIZE, 8, seed, |v| v, true);
            let b = common::gpu_render_with(&ctx, world, params, SIZE, 8, seed, |v| v, true);
            assert_same_within_rounding(&a, &b, &format!("{what}, seed {seed}"));
        }
        // The light visibility cache (an experiment), in the entries that fit.
        let cache = |v: Variant| Variant {
            experiment: EXPERIMENT_LIGHT_CACHE,
            ..v
        };
        let cached = common::gpu_render_with(&ctx, world, params, SIZE, 8, 5, cache, true);
        common::assert_finite_and_nonnegative(&cached, what);
        assert_eq!(ctx.validation_errors(), 0, "{what}: capped");
    }
    assert_eq!(full.validation_errors(), 0);
}

#[test]
fn what_cannot_fit_is_refused_and_the_viewport_traces_a_smaller_image() {
    if common::gpu_context(DeviceChoice::Best).is_none() {
        return;
    }
    let (world, params) = common::showcase();
    let ctx = Arc::new(capped(256 << 10, 1 << 20));
    // A one-shot render whose accumulation passes the storage range: a clear error.
    let view = world.read();
    let gpu_world = render::vulkan::world::GpuWorld::upload(&ctx, &view).unwrap();
    let mut tracer = PathTracer::new(&ctx).unwrap();
    let job = render::cpu::RenderJob {
        width: 256,
        height: 256,
        spp: 1,
        seed: 1,
    };
    let err = tracer
        .render(&ctx, &gpu_world, &view, &params, &job, RenderHow::SCENE)
        .map(|_| ())
        .unwrap_err();
    assert!(
        matches!(&err, GpuError::Limit { limit, .. } if limit.contains("maxStorageBufferRange") || limit.contains("maxMemoryAllocationSize")),
        "{err}"
    );
    assert!(err.to_string().contains("256 × 256"), "{err}");
    tracer.destroy(&ctx);
    gpu_world.destroy(&ctx);
    drop(view);

    // The viewport asked for the same size, denoised: it traces the largest image of that
    // aspect whose buffers fit, and displays it at the size asked.
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    let fit = vp.fit_internal((256, 256));
    assert!(fit.0 < 256 && fit.0 == fit.1, "{fit:?}");
    assert!(u64::from(fit.0 * fit.1) * IMAGE_BYTES_PER_PIXEL <= 256 << 10);
    let req = FrameRequest {
        params: &params,
        internal: (256, 256),
        output: (256, 256),
        spp: 2,
        target_spp: 4,
        exposure: 0.0,
        bgra: false,
        denoise: true,
        reproject: true,
        dim: None,
        grid: None,
    };
    for _ in 0..4000 {
        if vp.samples() >= 4 {
            break;
        }
        if vp.try_draw(&world, &req).unwrap().is_none() {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }
    vp.wait_idle().unwrap();
    assert_eq!(vp.samples(), 4);
    let hdr = vp.live_hdr().unwrap().unwrap();
    assert_eq!((hdr.width, hdr.height), fit);
    assert_eq!(ctx.validation_errors(), 0);
}
