//! The GPU path tracer against closed forms and against the CPU reference.
use super::*;
use brickmap::{MaterialKind, World};
use common::sun_floor;
use glam::DVec3;
use render::SceneParams;
use render::cpu::RenderJob;
use render::vulkan::trace::PathTracer;
use render::vulkan::world::GpuWorld;

fn gpu_render(
    ctx: &GpuContext,
    w: &World,
    p: &SceneParams,
    size: u32,
    spp: u32,
    seed: u64,
) -> Image {
    common::gpu_render_with(ctx, w, p, size, spp, seed, |v| v, true)
}

use super::common::cpu_render;

#[test]
fn gpu_white_furnace_is_exact() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    for kind in [MaterialKind::Lambertian, MaterialKind::Metal] {
        let (w, p) = common::block_scene(kind, 0);
        let img = gpu_render(&ctx, &w, &p, 24, 4, 1);
        for px in &img.pixels {
            for c in 0..3 {
                assert!((px[c] - common::SKY[c]).abs() < 1e-4, "{kind:?}: {px:?}");
            }
        }
    }
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn gpu_sun_disc_irradiance_matches_the_closed_form() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let (w, p, expected) = sun_floor();
    let img = gpu_render(&ctx, &w, &p, 16, 256, 5);
    let (mean, se) = common::mean_and_error(&img);
    assert!(
        (mean - expected).abs() < 4.0 * se + 1e-3 * expected,
        "{mean} ± {se}, expected {expected}"
    );
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn gpu_has_no_nan_in_hard_places() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let (w, views) = common::hard_places();
    for (i, p) in views.iter().enumerate() {
        let img = gpu_render(&ctx, &w, p, 20, 4, i as u64);
        common::assert_finite_and_nonnegative(&img, &format!("camera {i}"));
    }
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn gpu_has_no_nan_near_the_largest_grids_far_corner() {
    // f32 is coarsest there (1/2048 of a voxel at 4096); the centre ray of the cameras
    // that look at geometry must also hit the voxel the CPU ray cast hits.
    use render::vulkan::primary::PrimaryTracer;
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let (w, views) = common::far_places();
    let view = w.read();
    let world = GpuWorld::upload(&ctx, &view).unwrap();
    let mut tracer = PathTracer::new(&ctx).unwrap();
    let primary = PrimaryTracer::new(&ctx).unwrap();
    for (i, p) in views.iter().enumerate() {
        let job = RenderJob {
            width: 10,
            height: 8,
            spp: 4,
            seed: i as u64,
        };
        let img = tracer
            .render(&ctx, &world, &view, p, &job, RenderHow::SCENE)
            .unwrap()
            .image;
        common::assert_finite_and_nonnegative(&img, &format!("camera {i}"));
    }
    // The centre rays of the cameras looking at geometry hit what the exact f64 cast of
    // the same (f32) ray hits, up to f32's resolution of crossing times: two crossings
    // closer than an f32 ulp of t (camera 0 has a y and an x crossing 1.4e-7 apart at
    // t = 13.11) tie in f32 and are ordered by the tie rule, so the GPU may report the
    // solid neighbour entered at the same instant. Nothing may be skipped or lost.
    for i in [0, 1] {
        let c = &views[i].camera;
        let (forward, _, _) = c.basis(1.0);
        let (o, d) = (c.position.as_vec3(), forward.as_vec3());
        let cpu = view
            .ray_cast(
                &brickmap::Ray {
                    origin: o.as_dvec3(),
                    dir: d.as_dvec3(),
                },
                f64::INFINITY,
            )
            .unwrap()
            .map(|(hit, _)| hit)
            .expect("the camera looks at geometry");
        let gpu = primary.trace(&ctx, &world, &[(o, d)], None).unwrap()[0]
            .expect("the GPU finds the geometry too");
        let apart = (gpu.voxel - cpu.voxel).abs().max_element();
        assert!(
            apart <= 1 && view.voxel(gpu.voxel).unwrap().is_some(),
            "camera {i}: GPU {:?} vs CPU {:?}",
            gpu.voxel,
            cpu.voxel
        );
        assert!(
            (gpu.t as f64 - cpu.t).abs() <= 1e-5 * cpu.t.max(1.0),
            "camera {i}: t {} vs {}",
            gpu.t,
            cpu.t
        );
    }
    primary.destroy(&ctx);
    tracer.destroy(&ctx);
    drop(view);
    world.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn gpu_error_falls_as_one_over_sqrt_spp() {
    // RMS error against the closed form at 4, 16 and 64 spp: each 4× more samples must
    // halve it (no plateau, so no bias), within sampling slack.
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let (w, p, expected) = sun_floor();
    common::assert_error_halves(
        |spp| gpu_render(&ctx, &w, &p, 24, spp, 100 + spp as u64),
        expected,
    );
    assert_eq!(ctx.validation_errors(), 0);
}

/// The rays and their steps, without the lane steps a subgroup paid (they follow which
/// rays share a subgroup).
fn traced(r: render::vulkan::trace::RayCounts) -> render::vulkan::trace::RayCounts {
    render::vulkan::trace::RayCounts {
        lane_steps: [0; 2],
        ..r
    }
}

/// Two renders of the same samples, summed in another order: equal up to f32 rounding.
fn assert_same_up_to_rounding(a: &Image, b: &Image, what: &str) {
    for (x, y) in a.pixels.iter().zip(&b.pixels) {
        for k in 0..3 {
            assert!(
                (x[k] - y[k]).abs() <= 1e-5 * y[k].abs().max(1.0),
                "{what}: {x:?} vs {y:?}"
            );
        }
    }
}

/// A context and the showcase scene uploaded, on a device with float atomic adds (shadow
/// queue, sample slices). Every driver we test on has them, so without them the test fails
/// under VOXBRICK_REQUIRE_GPU=1 and otherwise skips, saying so.
fn showcase_with_float_atomics(what: &str) -> Option<(GpuContext, World, SceneParams, GpuWorld)> {
    let ctx = context(DeviceChoice::Best)?;
    if !ctx.shadow_queue {
        assert_ne!(
            std::env::var("VOXBRICK_REQUIRE_GPU").as_deref(),
            Ok("1"),
            "{} cannot {what}",
            ctx.name
        );
        eprintln!("SKIPPED: {} cannot {what}", ctx.name);
        return None;
    }
    let (w, p) = common::showcase();
    let world = GpuWorld::upload(&ctx, &w.read()).unwrap();
    Some((ctx, w, p, world))
}

#[test]
fn sliced_samples_render_what_one_invocation_per_pixel_renders() {
    // The same samples (same random sequences) whether a pixel's samples of a dispatch run
    // in one invocation or are split among several and added with atomics; 13 spp in
    // dispatches of 2 × 3 leaves a short last dispatch with fewer slices.
    let Some((ctx, w, p, world)) = showcase_with_float_atomics("split samples") else {
        return;
    };
    let view = w.read();
    let job = RenderJob {
        width: 24,
        height: 16,
        spp: 13,
        seed: 9,
    };
    let mut tracer = PathTracer::new(&ctx).unwrap();
    let mut render = |per: u32, slices: u32| {
        tracer.set_samples_per_dispatch(Some(per));
        tracer.set_sample_slices(Some(slices));
        assert_eq!(tracer.sample_slices(384), slices);
        let r = tracer
            .render(&ctx, &world, &view, &p, &job, RenderHow::SCENE.counted())
            .unwrap();
        (r.image, r.rays.unwrap())
    };
    let (whole, rays) = render(4, 1);
    let (sliced, sliced_rays) = render(2, 3);
    assert_eq!(traced(sliced_rays), traced(rays));
    assert!(rays.primary == 24 * 16 * 13, "{rays:?}");
    assert_same_up_to_rounding(&sliced, &whole, "sliced");
    // Without a fixed split, a small image is split (the GPU would be mostly idle).
    tracer.set_sample_slices(None);
    assert_eq!(
        tracer.sample_slices(24 * 16),
        render::vulkan::trace::MAX_SLICES
    );
    assert_eq!(tracer.sample_slices(1024 * 576), 2);
    assert_eq!(tracer.sample_slices(1920 * 1080), 1);
    tracer.set_samples_per_dispatch(None);
    assert_eq!(tracer.samples_per_dispatch(1920 * 1080), 8);
    assert_eq!(tracer.samples_per_dispatch(1024 * 576), 4);
    tracer.destroy(&ctx);
    world.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn queued_shadow_rays_render_what_shadow_rays_traced_in_place_render() {
    let Some((ctx, w, p, world)) = showcase_with_float_atomics("queue shadow rays") else {
        return;
    };
    let view = w.read();
    let job = RenderJob {
        width: 24,
        height: 16,
        spp: 4,
        seed: 5,
    };
    let mut tracer = PathTracer::new(&ctx).unwrap();
    assert!(tracer.deferred_shadows());
    let mut render = |deferred: bool, limit: u64| {
        tracer.set_deferred_shadows(&ctx, deferred);
        tracer.set_queue_limit(limit);
        let r = tracer
            .render(&ctx, &world, &view, &p, &job, RenderHow::SCENE.counted())
            .unwrap();
        (r.image, r.rays.unwrap())
    };
    let (in_place, rays) = render(false, u64::MAX);
    // The limit of 100 rays makes the queue overflow: the rest are traced in place.
    assert!(rays.shadow > 300, "{rays:?}");
    for limit in [u64::MAX, 100] {
        let (queued, queued_rays) = render(true, limit);
        assert_eq!(traced(queued_rays), traced(rays), "queue limit {limit}");
        assert_same_up_to_rounding(&queued, &in_place, &format!("queue limit {limit}"));
    }
    tracer.destroy(&ctx);
    world.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn camera_rays_started_by_their_tiles_march_find_what_rays_from_the_camera_find() {
    // trace.comp starts a camera ray where its workgroup tile's frustum first meets an
    // occupied coarse cell (experiment bit 13 turns that off): the same hits, fewer steps.
    // A 192 × 96 × 192 grid with its content in one corner, seen from far outside it,
    // from its far corner and from within the content; every path the same.
    use brickmap::{EditOp, GridDims, Mode, Shape, WorldConfig};
    let Some((ctx, _, showcase, _world)) = showcase_with_float_atomics("split samples") else {
        return;
    };
    _world.destroy(&ctx);
    let w = World::new(
        GridDims::new(24, 12, 24).unwrap(),
        WorldConfig::with_workers(2),
    )
    .unwrap();
    let stone = common::add_material(&w, MaterialKind::Lambertian, 0, [150, 140, 120]);
    let metal = common::add_material(&w, MaterialKind::Metal, 20, [230, 200, 120]);
    let glass = common::add_material(&w, MaterialKind::Dielectric, 0, [240, 250, 255]);
    for (shape, m) in [
        (
            Shape::Box {
                min: glam::IVec3::new(130, 0, 130),
                max: glam::IVec3::new(180, 3, 180),
            },
            stone,
        ),
        (
            Shape::Sphere {
                centre: DVec3::new(150.0, 14.0, 150.0),
                radius: 9.0,
            },
            metal,
        ),
        (
            Shape::Box {
                min: glam::IVec3::new(165, 4, 135),
                max: glam::IVec3::new(172, 20, 142),
            },
            glass,
        ),
    ] {
        w.apply(EditOp::Shape {
            shape,
            mode: Mode::Add(m),
        })
        .unwrap();
    }
    let view = w.read();
    let world = GpuWorld::upload(&ctx, &view).unwrap();
    let mut p = showcase;
    let job = RenderJob {
        width: 40,
        height: 24,
        spp: 2,
        seed: 7,
    };
    let centre = DVec3::new(155.0, 8.0, 155.0);
    let mut tracer = PathTracer::new(&ctx).unwrap();
    for (eye, fewer) in [
        (DVec3::new(-300.0, 250.0, -260.0), true),
        (DVec3::new(2.0, 60.0, 4.0), true),
        (DVec3::new(150.0, 8.0, 140.0), false),
    ] {
        p.camera = render::Camera::looking_at(eye, centre, 40.0);
        let scene = render::vulkan::trace::Variant::for_scene(&view, &p);
        let mut render = |experiment: u32| {
            let v = render::vulkan::trace::Variant {
                experiment,
                ..scene
            };
            let r = tracer
                .render(
                    &ctx,
                    &world,
                    &view,
                    &p,
                    &job,
                    RenderHow::variant(v).counted(),
                )
                .unwrap();
            (r.image, r.rays.unwrap())
        };
        let (marched, rays) = render(0);
        let (walked, walked_rays) = render(8192);
        let what = format!("camera at {eye}");
        assert_same_up_to_rounding(&marched, &walked, &what);
        assert_eq!(
            (
                rays.primary,
                rays.secondary,
                rays.shadow,
                rays.steps[1],
                rays.steps[2]
            ),
            (
                walked_rays.primary,
                walked_rays.secondary,
                walked_rays.shadow,
                walked_rays.steps[1],
                walked_rays.steps[2]
            ),
            "{what}"
        );
        assert!(
            rays.secondary > 0 && rays.steps[0] <= walked_rays.steps[0],
            "{what}"
        );
        if fewer {
            assert!(
                rays.steps[0] * 10 < walked_rays.steps[0] * 9,
                "{what}: {} against {} camera steps",
                rays.steps[0],
                walked_rays.steps[0]
            );
        }
    }
    tracer.destroy(&ctx);
    world.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn gpu_and_cpu_agree_within_sampling_noise() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let (w, p) = common::showcase();
    assert_gpu_matches_cpu(&ctx, &w, &p, "perspective");
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn gpu_orthographic_camera_matches_the_closed_form_and_the_cpu() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let (w, p, lit) = common::orthographic_walls();
    common::assert_orthographic_walls(&gpu_render(&ctx, &w, &p, 32, 4, 3), &lit, "GPU");
    // An image plane cutting through glass and water: each ray starts in the medium its
    // origin is in (found per ray on the GPU, as the CPU does).
    let (w, mut p) = common::showcase();
    p.camera = render::Camera {
        position: DVec3::new(11.5, 6.5, 11.5),
        yaw_deg: 225.0,
        pitch_deg: -30.0,
        fov_y_deg: 55.0,
        projection: render::Projection::Orthographic { height: 40.0 },
    };
    assert_gpu_matches_cpu(&ctx, &w, &p, "orthographic through glass");
    // An image plane inside glass looking out: η²·L only if every ray starts in the glass.
    let (w, p, expected) = common::inside_glass(true);
    let (mean, se) = common::mean_and_error(&gpu_render(&ctx, &w, &p, 20, 64, 21));
    assert!(
        (mean - expected).abs() < 4.0 * se + 2e-3 * expected,
        "inside glass: {mean} ± {se}, expected {expected}"
    );
    assert_eq!(ctx.validation_errors(), 0);
}

/// If the GPU estimator is the CPU one, RMS(GPU − CPU₁) ≈ RMS(CPU₂ − CPU₁) for
/// independent renders; a bias shows as a larger ratio (and a shifted mean).
fn assert_gpu_matches_cpu(ctx: &GpuContext, w: &World, p: &SceneParams, what: &str) {
    let (size, spp) = (32, 64);
    let g = gpu_render(ctx, w, p, size, spp, 11);
    let c1 = cpu_render(w, p, size, spp, 12);
    let c2 = cpu_render(w, p, size, spp, 13);
    assert!(g.all_finite(), "{what}");
    let rms = |a: &Image, b: &Image| {
        (a.pixels
            .iter()
            .zip(&b.pixels)
            .map(|(x, y)| {
                (0..3)
                    .map(|k| (x[k] as f64 - y[k] as f64).powi(2))
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (3.0 * a.pixels.len() as f64))
            .sqrt()
    };
    let (gc, cc) = (rms(&g, &c1), rms(&c2, &c1));
    eprintln!(
        "{what}: RMS(GPU − CPU) = {gc:.5}, RMS(CPU − CPU) = {cc:.5}, means {:?} vs {:?}",
        g.mean(),
        c1.mean()
    );
    assert!(
        gc < 1.3 * cc,
        "{what}: GPU differs from the CPU more than sampling noise: {gc} vs {cc}"
    );
    for k in 0..3 {
        let (a, b) = (g.mean()[k], c1.mean()[k]);
        assert!(
            (a - b).abs() < 0.02 * b.max(1e-3) + 4.0 * cc / (g.pixels.len() as f64).sqrt(),
            "{what}: channel {k}: {a} vs {b}"
        );
    }
}
