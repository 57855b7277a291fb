//! The Vulkan layer on a real device (lavapipe in CI), with the validation layer and
//! synchronization validation on: every validation error fails the test. Machines without
//! any Vulkan driver skip, saying so, unless VOXBRICK_REQUIRE_GPU=1 (CI) makes that a failure.

mod common;

use render::Image;
use render::viewport::RenderHow;
use render::vulkan::tonemap::ToneMapper;
use render::vulkan::{ContextOptions, DeviceChoice, GpuContext, GpuError};

fn context(device: DeviceChoice) -> Option<GpuContext> {
    common::gpu_context(device)
}

#[test]
fn gpu_tone_map_matches_the_cpu_curve() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    eprintln!("device: {}", ctx.name);
    let mut s = 12345u32;
    let mut next = || {
        s = s.wrapping_mul(1664525).wrapping_add(1013904223);
        (s >> 8) as f32 / (1u32 << 24) as f32
    };
    // Values from black through very bright, including exact zeros and huge ones.
    let pixels: Vec<[f32; 3]> = (0..5000)
        .map(|i| match i % 5 {
            0 => [0.0, 0.0, 0.0],
            1 => [1e4, 2.0, 0.5],
            _ => [next() * 4.0, next() * next() * 16.0, next()],
        })
        .collect();
    let image = Image {
        width: 100,
        height: 50,
        pixels,
    };
    let tone = ToneMapper::new(&ctx).unwrap();
    for exposure in [0.0, -1.5, 2.0] {
        let gpu = tone.run(&ctx, &image, exposure).unwrap();
        let cpu = image.to_srgb8(exposure);
        assert_eq!(gpu.len(), cpu.len());
        let worst = gpu
            .iter()
            .zip(&cpu)
            .flat_map(|(g, c)| (0..3).map(move |k| (g[k] as i32 - c[k] as i32).abs()))
            .max()
            .unwrap();
        // float rounding of pow/exp may move a value across a rounding boundary by one step
        assert!(
            worst <= 1,
            "exposure {exposure}: GPU and CPU differ by {worst} steps"
        );
    }
    tone.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0, "validation errors");
}

#[test]
fn unknown_device_names_are_a_clear_error() {
    if context(DeviceChoice::Best).is_none() {
        return;
    }
    let err = GpuContext::new(&ContextOptions {
        device: DeviceChoice::Name("no such gpu 9000".into()),
        ..Default::default()
    })
    .err()
    .expect("no such device");
    assert!(matches!(err, GpuError::NoDevice(_)), "{err}");
    assert!(err.to_string().contains("no such gpu 9000"), "{err}");
}

#[test]
fn the_messenger_counts_validation_errors() {
    // Without this, "zero validation errors" could pass because nothing is listening.
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    assert_eq!(ctx.validation_errors(), 0);
    // Invalid usage the layer must report: a buffer of size 0 with no usage flags.
    let info = ash::vk::BufferCreateInfo::default()
        .size(0)
        .usage(ash::vk::BufferUsageFlags::empty());
    // SAFETY: the (invalid) buffer, if created, is destroyed right away and never used.
    unsafe {
        if let Ok(b) = ctx.device.create_buffer(&info, None) {
            ctx.device.destroy_buffer(b, None);
        }
    }
    assert!(
        ctx.validation_errors() >= 1,
        "the validation layer's errors are not counted"
    );
}

#[test]
fn synchronization_validation_reports_a_missing_barrier() {
    // Without this, "zero hazards" could pass because synchronization validation is off.
    use ash::vk;
    use gpu_allocator::MemoryLocation;
    use render::vulkan::buffer::HostBuffer;
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let buf = HostBuffer::new(&ctx, "hazard", 256, MemoryLocation::GpuOnly).unwrap();
    let src = HostBuffer::new(&ctx, "hazard source", 256, MemoryLocation::CpuToGpu).unwrap();
    assert_eq!(ctx.validation_errors(), 0);
    // Two copies into the same bytes with no barrier between them: a write-after-write.
    let region = [vk::BufferCopy::default().size(256)];
    ctx.submit_and_wait(|cmd| unsafe {
        ctx.device
            .cmd_copy_buffer(cmd, src.binding().buffer, buf.binding().buffer, &region);
        ctx.device
            .cmd_copy_buffer(cmd, src.binding().buffer, buf.binding().buffer, &region);
    })
    .unwrap();
    assert!(
        ctx.validation_errors() >= 1,
        "synchronization validation did not report the hazard"
    );
    buf.destroy(&ctx);
    src.destroy(&ctx);
}

#[test]
fn gpu_traversal_matches_the_cpu_ray_cast() {
    use brickmap::{
        EditOp, GridDims, Mode, Shape, VoxelEdit, VoxelOp, World, WorldConfig, terrain,
    };
    use glam::{DVec3, IVec3, Vec3};
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    // Terrain (full cells, uniform and per-voxel bricks), a floating sphere, scattered voxels.
    let world = World::new(
        GridDims::new(16, 8, 16).unwrap(),
        WorldConfig::with_workers(2),
    )
    .unwrap();
    for c in 0..3 {
        world
            .push_material(brickmap::Material::lambertian(c))
            .unwrap();
    }
    world.apply(terrain::rolling_hills(world.dims())).unwrap();
    world
        .apply(EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::new(64.0, 55.0, 64.0),
                radius: 6.0,
            },
            mode: Mode::Add(1),
        })
        .unwrap();
    let mut rng = XorShift(7);
    let mut next = || rng.next();
    let scattered: Vec<VoxelEdit> = (0..300)
        .map(|_| VoxelEdit {
            pos: IVec3::new(
                (next() * 128.0) as i32,
                40 + (next() * 24.0) as i32,
                (next() * 128.0) as i32,
            ),
            op: VoxelOp::Set(2),
        })
        .collect();
    world.apply(EditOp::Voxels(scattered)).unwrap();
    let view = world.read();
    // Random rays from around and inside the grid, camera-like rays, axis-aligned rays.
    let mut rays: Vec<(Vec3, Vec3)> = Vec::new();
    for k in 0..20_000 {
        let o = Vec3::new(
            (next() * 200.0 - 36.0) as f32,
            (next() * 120.0 - 20.0) as f32,
            (next() * 200.0 - 36.0) as f32,
        );
        let d = match k % 4 {
            0 => Vec3::new(
                [1.0, -1.0, 0.0][k / 4 % 3],
                [0.0, -1.0, 1.0][k / 7 % 3],
                [0.0, 0.0, -1.0][k / 11 % 3],
            ),
            _ => Vec3::new(
                (next() * 2.0 - 1.0) as f32,
                (next() * 2.0 - 1.2) as f32,
                (next() * 2.0 - 1.0) as f32,
            ),
        };
        if d != Vec3::ZERO {
            rays.push((if k % 4 == 0 { o.floor() } else { o }, d));
        }
    }
    let (agree, hits) = gpu_and_cpu_first_hits(&ctx, &view, &rays, None);
    let n = rays.len();
    // f32 on the GPU may resolve a few exact edge/corner ties differently from the f64 CPU cast.
    eprintln!("GPU and CPU agree on {agree} of {n} rays ({hits} hits)");
    assert!(
        agree as f64 >= 0.999 * n as f64,
        "GPU and CPU agree on {agree} of {n} rays"
    );
    assert!(hits > n / 4, "the scene is hit: {hits} of {n}");
    assert_eq!(ctx.validation_errors(), 0, "validation errors");
}

/// Xorshift64: uniform numbers in [0, 1) for test rays.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Occupancy seen from inside a dielectric medium: every voxel that is not the medium.
struct NotMedium<'a, 'w> {
    view: &'a brickmap::WorldView<'w>,
    medium: u8,
}

impl brickmap::Occupancy for NotMedium<'_, '_> {
    fn dims(&self) -> brickmap::GridDims {
        self.view.dims()
    }
    fn coarse_occupied(&self, _: glam::UVec3) -> bool {
        true
    }
    fn brick_occupied(&self, _: glam::UVec3) -> bool {
        true
    }
    fn solid(&self, v: glam::IVec3) -> bool {
        self.view.voxel(v).unwrap() != Some(self.medium)
    }
}

/// Traces `rays` on the GPU (shaders/primary.comp) and with the f64 CPU ray cast (in air, or
/// voxel by voxel inside `medium`); returns how many agree (same voxel and t, or both miss)
/// and how many of those are hits.
fn gpu_and_cpu_first_hits(
    ctx: &GpuContext,
    view: &brickmap::WorldView,
    rays: &[(glam::Vec3, glam::Vec3)],
    medium: Option<u8>,
) -> (usize, usize) {
    use render::vulkan::primary::PrimaryTracer;
    use render::vulkan::world::GpuWorld;
    let gpu_world = GpuWorld::upload(ctx, view).unwrap();
    let tracer = PrimaryTracer::new(ctx).unwrap();
    let gpu = tracer.trace(ctx, &gpu_world, rays, medium).unwrap();
    tracer.destroy(ctx);
    gpu_world.destroy(ctx);
    let (mut agree, mut hits) = (0, 0);
    for ((o, d), g) in rays.iter().zip(&gpu) {
        let ray = brickmap::Ray {
            origin: o.as_dvec3(),
            dir: d.as_dvec3(),
        };
        let cpu = match medium {
            None => brickmap::cast(view, &ray, f64::INFINITY),
            Some(medium) => brickmap::cast(&NotMedium { view, medium }, &ray, f64::INFINITY),
        }
        .unwrap();
        match (cpu, g) {
            (None, None) => agree += 1,
            (Some(c), Some(g)) if c.voxel == g.voxel => {
                assert!(
                    (c.t - g.t as f64).abs() <= 1e-3 * c.t.max(1.0),
                    "t {} vs {} for {o} {d}",
                    c.t,
                    g.t
                );
                agree += 1;
                hits += 1;
            }
            _ => {}
        }
    }
    (agree, hits)
}

#[test]
fn gpu_traversal_inside_a_medium_matches_the_cpu_ray_cast() {
    // Water filling whole bricks (which the GPU skips whole) and parts of bricks at its edges,
    // with stone spheres, scattered stones and air bubbles inside it.
    use brickmap::{
        EditOp, GridDims, Material, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp, World,
        WorldConfig,
    };
    use glam::{DVec3, IVec3, Vec3};
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let world = World::new(
        GridDims::new(8, 4, 8).unwrap(),
        WorldConfig::with_workers(2),
    )
    .unwrap();
    world.push_material(Material::lambertian(1)).unwrap();
    let water = world
        .push_material(Material {
            kind: MaterialKind::Dielectric,
            param: 1,
            colour: 2,
        })
        .unwrap();
    let box_of = |min: IVec3, max: IVec3, mode| EditOp::Shape {
        shape: Shape::Box { min, max },
        mode,
    };
    world
        .apply(box_of(
            IVec3::new(3, 2, 5),
            IVec3::new(60, 28, 57),
            Mode::Add(water),
        ))
        .unwrap();
    world
        .apply(EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::new(40.0, 12.0, 20.0),
                radius: 5.0,
            },
            mode: Mode::Add(0),
        })
        .unwrap();
    let mut rng = XorShift(11);
    let point = |rng: &mut XorShift| {
        IVec3::new(
            4 + (rng.next() * 56.0) as i32,
            3 + (rng.next() * 25.0) as i32,
            6 + (rng.next() * 51.0) as i32,
        )
    };
    let edits: Vec<VoxelEdit> = (0..120)
        .map(|k| VoxelEdit {
            pos: point(&mut rng),
            op: if k % 2 == 0 {
                VoxelOp::Set(0)
            } else {
                VoxelOp::Clear
            },
        })
        .collect();
    world.apply(EditOp::Voxels(edits)).unwrap();
    let view = world.read();
    let full = (0..8 * 4 * 8)
        .filter(|i| {
            let b = IVec3::new(i % 8, i / 8 % 4, i / 32);
            (0..512).all(|v| {
                view.voxel(b * 8 + IVec3::new(v % 8, v / 8 % 8, v / 64))
                    .unwrap()
                    == Some(water)
            })
        })
        .count();
    assert!(full >= 20, "bricks full of water: {full}");
    // Rays from points in the water: random directions, and along axes and diagonals.
    let mut rays = Vec::new();
    for k in 0..8_000 {
        let o = point(&mut rng).as_vec3()
            + Vec3::new(rng.next() as f32, rng.next() as f32, rng.next() as f32);
        let d = if k % 4 == 0 {
            Vec3::new(
                [1.0, -1.0, 0.0][k / 4 % 3],
                [0.0, -1.0, 1.0][k / 7 % 3],
                [1.0, 0.0, -1.0][k / 11 % 3],
            )
        } else {
            Vec3::new(rng.next() as f32, rng.next() as f32, rng.next() as f32) * 2.0 - 1.0
        };
        if d != Vec3::ZERO && view.voxel(o.floor().as_ivec3()).unwrap() == Some(water) {
            rays.push((if k % 4 == 0 { o.floor() + 0.5 } else { o }, d));
        }
    }
    let (agree, hits) = gpu_and_cpu_first_hits(&ctx, &view, &rays, Some(water));
    let n = rays.len();
    eprintln!("inside water: GPU and CPU agree on {agree} of {n} rays ({hits} hits)");
    assert!(n > 5_000, "rays from inside the water: {n}");
    assert!(
        agree as f64 >= 0.999 * n as f64,
        "GPU and CPU agree on {agree} of {n} rays"
    );
    assert!(
        hits == agree,
        "every ray in the water ends at the water's edge: {hits} of {agree}"
    );
    assert_eq!(ctx.validation_errors(), 0, "validation errors");
}

mod trace {
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
    fn showcase_with_float_atomics(
        what: &str,
    ) -> Option<(GpuContext, World, SceneParams, GpuWorld)> {
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
}

#[test]
fn gpu_world_equals_the_cpu_world_byte_for_byte_after_random_edit_batches() {
    // Random edit batches (shapes added and removed, scattered voxels, paint, table edits)
    // on a world that starts empty, so the buffer grows; a small staging ring, so uploads
    // are deferred across frames. After each batch's frames the GPU's five regions must
    // equal the CPU world's bytes, and the bytes uploaded must be within 2× of the bytes
    // changed (counted as the 4-byte words that differ: buffers are u32 arrays to shaders).
    use brickmap::{
        EditOp, GpuBuffer, GridDims, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp, World,
        WorldConfig,
    };
    use common::add_material;
    use glam::{DVec3, IVec3};
    use render::vulkan::world::GpuWorld;
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let w = World::new(
        GridDims::new(8, 4, 8).unwrap(),
        WorldConfig::with_workers(2),
    )
    .unwrap();
    // Two of them emissive: the light faces (a sixth region) must stay byte-equal too.
    let mats: Vec<u8> = (0..6)
        .map(|i| {
            let kind = if i % 3 == 0 {
                MaterialKind::Emissive
            } else {
                MaterialKind::Lambertian
            };
            add_material(&w, kind, i / 3, [40 * i, 100, 200 - 30 * i])
        })
        .collect();
    let mut most_light_faces = 0;
    let images = |w: &World| {
        let v = w.read();
        GpuBuffer::ALL.map(|b| v.gpu_image(b))
    };
    let mut gpu = GpuWorld::with_ring(&ctx, &w.read(), 2, 1024).unwrap();
    let mut prev = images(&w);
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut rand = move |n: u64| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed % n
    };
    let (mut grew, mut deferred, mut total_up, mut total_changed) = (false, false, 0, 0);
    let mut interleaved = 0;
    for batch in 0..14 {
        // Every third batch edits again while the previous edits' uploads are deferred:
        // the queued bytes are owned, so the later frames must still end byte-equal.
        let rounds = if batch % 3 == 2 { 2 } else { 1 };
        for round in 0..rounds {
            if round == 1 && gpu.update(&ctx, &w).unwrap().deferred_bytes > 0 {
                interleaved += 1;
            }
            for _ in 0..1 + rand(4) {
                let m = mats[rand(mats.len() as u64) as usize];
                let centre = DVec3::new(rand(64) as f64, rand(32) as f64, rand(64) as f64);
                let op = match rand(5) {
                    0 => EditOp::Shape {
                        shape: Shape::Sphere {
                            centre,
                            radius: 2.0 + rand(14) as f64,
                        },
                        mode: Mode::Add(m),
                    },
                    1 => EditOp::Shape {
                        shape: Shape::Sphere {
                            centre,
                            radius: 2.0 + rand(6) as f64,
                        },
                        mode: Mode::Remove,
                    },
                    2 => EditOp::Shape {
                        shape: Shape::Box {
                            min: centre.as_ivec3(),
                            max: centre.as_ivec3()
                                + IVec3::new(3, 20, 5).min(IVec3::splat(63) - centre.as_ivec3()),
                        },
                        mode: Mode::Paint(m),
                    },
                    3 => EditOp::Voxels(
                        (0..1 + rand(60))
                            .map(|_| VoxelEdit {
                                pos: IVec3::new(rand(64) as i32, rand(32) as i32, rand(64) as i32),
                                op: if rand(3) == 0 {
                                    VoxelOp::Clear
                                } else {
                                    VoxelOp::Set(mats[rand(mats.len() as u64) as usize])
                                },
                            })
                            .collect(),
                    ),
                    _ => {
                        w.set_colour(rand(256) as u8, [rand(256) as u8, 7, 9]);
                        // A lamp's strength: the light weights change, no voxel does.
                        w.set_param(MaterialKind::Emissive, rand(2) as u8, 0.5 + rand(8) as f32)
                            .unwrap();
                        continue;
                    }
                };
                w.apply(op).unwrap();
            }
        }
        let now = images(&w);
        most_light_faces = most_light_faces.max(w.read().lights().len());
        let changed: u64 = prev
            .iter()
            .zip(&now)
            .map(|(a, b)| {
                b.chunks(4)
                    .enumerate()
                    // Bytes past the old end count against zeros: a grown region starts
                    // zeroed, and unused slots of a new chunk are zero in the image too.
                    .filter(|(i, word)| {
                        a.get(i * 4..i * 4 + word.len())
                            .map_or(word.iter().any(|&x| x != 0), |o| o != *word)
                    })
                    .count() as u64
                    * 4
            })
            .sum();
        let mut uploaded = 0;
        let mut frames = 0;
        loop {
            let r = gpu.update(&ctx, &w).unwrap();
            grew |= r.grew;
            uploaded += r.uploaded_bytes;
            frames += 1;
            if r.deferred_bytes == 0 {
                break;
            }
            deferred = true;
            assert!(
                r.uploaded_bytes == 1024,
                "a deferring frame fills its slot: {r:?}"
            );
        }
        for (b, image) in GpuBuffer::ALL.into_iter().zip(&now) {
            let back = gpu.read_back(&ctx, b).unwrap();
            assert!(
                back == *image,
                "batch {batch}: {b:?} differs on the GPU ({} vs {} bytes)",
                back.len(),
                image.len()
            );
        }
        eprintln!("batch {batch}: {changed} bytes changed, {uploaded} uploaded in {frames} frames");
        if rounds == 1 {
            assert!(uploaded >= changed, "batch {batch}: {uploaded} < {changed}");
            assert!(
                uploaded <= 2 * changed,
                "batch {batch}: {uploaded} > 2 × {changed}"
            );
            total_up += uploaded;
            total_changed += changed;
        }
        prev = now;
    }
    assert!(
        interleaved > 0,
        "no batch edited while uploads were deferred"
    );
    assert!(grew, "the world never outgrew its regions");
    assert!(
        most_light_faces > 100,
        "too few light faces: {most_light_faces}"
    );
    assert!(deferred, "the ring never deferred an upload");
    eprintln!("total: {total_changed} bytes changed, {total_up} uploaded");
    gpu.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn a_large_scattered_edit_uploads_within_the_region_budget() {
    // One edit of scattered voxels (every 5th along x, every 3rd along z: thousands of
    // runs of changed words) onto an empty world: the upload joins runs until it fits the
    // region budget, and the GPU still ends byte-equal to the CPU world.
    use brickmap::{EditOp, GpuBuffer, MaterialKind, VoxelEdit, VoxelOp};
    use common::{add_material, world};
    use glam::IVec3;
    use render::vulkan::world::{GpuWorld, REGION_BUDGET};
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let w = world((16, 4, 16));
    let m = add_material(&w, MaterialKind::Lambertian, 0, [200, 100, 50]);
    let mut gpu = GpuWorld::upload(&ctx, &w.read()).unwrap();
    let voxels: Vec<VoxelEdit> = (0..128)
        .step_by(5)
        .flat_map(|x| (0..128).step_by(3).map(move |z| IVec3::new(x, 7, z)))
        .map(|pos| VoxelEdit {
            pos,
            op: VoxelOp::Set(m),
        })
        .collect();
    // Far more voxels than regions, each in a word of its own.
    assert!(voxels.len() > 4 * REGION_BUDGET);
    w.apply(EditOp::Voxels(voxels)).unwrap();
    let r = gpu.sync(&ctx, &w).unwrap();
    // Flushes may cut a region at a staging slot's end: one more region per flush.
    assert!(
        r.copy_regions as usize <= REGION_BUDGET + r.flushes as usize,
        "{r:?}"
    );
    assert!(
        r.uploaded_bytes >= r.queued_bytes && r.queued_bytes > 0,
        "{r:?}"
    );
    let v = w.read();
    for b in GpuBuffer::ALL {
        assert!(
            gpu.read_back(&ctx, b).unwrap() == v.gpu_image(b),
            "{b:?} differs"
        );
    }
    drop(v);
    // A small edit afterwards keeps the small-edit rule: a handful of regions.
    w.apply(EditOp::Voxels(vec![VoxelEdit {
        pos: IVec3::new(1, 1, 1),
        op: VoxelOp::Set(m),
    }]))
    .unwrap();
    let r = gpu.sync(&ctx, &w).unwrap();
    assert!(r.copy_regions >= 1 && r.copy_regions <= 8, "{r:?}");
    gpu.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0);
}

mod progressive {
    //! Progressive accumulation, restarts, pipeline variants and the internal resolution.
    use super::*;
    use brickmap::{EditOp, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp};
    use common::{add_material as add, params, sun_floor};
    use glam::{DVec3, IVec3};
    use render::cpu::RenderJob;
    use render::vulkan::progressive::Progressive;
    use render::vulkan::trace::{PathTracer, Variant};
    use render::vulkan::world::GpuWorld;
    use render::{Camera, Sky};

    #[test]
    fn accumulation_continues_while_nothing_changes_and_restarts_on_any_change() {
        let Some(ctx) = context(DeviceChoice::Best) else {
            return;
        };
        let (w, mut p, _) = sun_floor();
        let mut gpu = GpuWorld::upload(&ctx, &w.read()).unwrap();
        let mut tracer = PathTracer::new(&ctx).unwrap();
        let size = (16, 12);
        let mut acc = Progressive::new(&ctx, size, size, 7).unwrap();
        let mut frame = |acc: &mut Progressive, gpu: &mut GpuWorld, p: &render::SceneParams| {
            let changed = gpu.update(&ctx, &w).unwrap().changed();
            acc.frame(&ctx, &mut tracer, gpu, &w.read(), p, changed, 4)
                .unwrap()
        };
        let first = frame(&mut acc, &mut gpu, &p);
        assert!(first.restarted);
        assert_eq!(first.samples, 4);
        for k in 2..=4 {
            let r = frame(&mut acc, &mut gpu, &p);
            assert!(!r.restarted);
            assert_eq!(r.samples, 4 * k);
        }
        // 4 frames of 4 samples are the 16-sample render with the same seed, here in dispatches
        // of 3, 3, 3, 3, 3 and 1 samples (one submission).
        let accumulated = acc.hdr(&ctx).unwrap();
        let mut one = PathTracer::new(&ctx).unwrap();
        one.set_samples_per_dispatch(Some(3));
        let direct = one
            .render(
                &ctx,
                &gpu,
                &w.read(),
                &p,
                &RenderJob {
                    width: size.0,
                    height: size.1,
                    spp: 16,
                    seed: 7,
                },
                RenderHow::SCENE,
            )
            .unwrap()
            .image;
        for (a, b) in accumulated.pixels.iter().zip(&direct.pixels) {
            for k in 0..3 {
                assert!(
                    (a[k] - b[k]).abs() <= 1e-5 * b[k].abs().max(1.0),
                    "{a:?} vs {b:?}"
                );
            }
        }
        one.destroy(&ctx);
        // Exposure is display-only: no restart.
        p.settings.exposure += 1.0;
        let r = frame(&mut acc, &mut gpu, &p);
        assert!(!r.restarted && r.samples == 20, "{r:?}");
        // Camera, sun, bounces, world edits and material edits each restart.
        let mut moved = p.clone();
        moved.camera.position.x += 0.5;
        let r = frame(&mut acc, &mut gpu, &moved);
        assert!(r.restarted && r.samples == 4, "camera: {r:?}");
        frame(&mut acc, &mut gpu, &moved);
        let mut dimmer = moved.clone();
        dimmer.sun.intensity *= 0.5;
        assert!(frame(&mut acc, &mut gpu, &dimmer).restarted, "sun");
        let mut deeper = dimmer.clone();
        deeper.settings.max_bounces += 1;
        assert!(frame(&mut acc, &mut gpu, &deeper).restarted, "bounces");
        assert!(!frame(&mut acc, &mut gpu, &deeper).restarted);
        w.apply(EditOp::Voxels(vec![VoxelEdit {
            pos: IVec3::new(3, 9, 3),
            op: VoxelOp::Set(0),
        }]))
        .unwrap();
        assert!(frame(&mut acc, &mut gpu, &deeper).restarted, "world edit");
        assert!(!frame(&mut acc, &mut gpu, &deeper).restarted);
        w.set_colour(0, [10, 200, 30]);
        assert!(frame(&mut acc, &mut gpu, &deeper).restarted, "colour edit");
        let r = frame(&mut acc, &mut gpu, &deeper);
        assert!(!r.restarted && r.samples == 8, "{r:?}");
        acc.destroy(&ctx);
        tracer.destroy(&ctx);
        gpu.destroy(&ctx);
        assert_eq!(ctx.validation_errors(), 0);
    }

    #[test]
    fn variants_follow_the_scene_and_render_what_the_everything_variant_renders() {
        let Some(ctx) = context(DeviceChoice::Best) else {
            return;
        };
        // Lambertian and metal only, no sun, uniform sky: the scene's variant drops
        // dielectrics, emission, the sun and the gradient; its image must be the everything
        // variant's (same seeds, same random numbers consumed).
        let w = common::world((4, 3, 4));
        let floor = add(&w, MaterialKind::Lambertian, 0, [180, 170, 150]);
        let metal = add(&w, MaterialKind::Metal, 20, [220, 200, 160]);
        for (shape, m) in [
            (
                Shape::Box {
                    min: IVec3::ZERO,
                    max: IVec3::new(31, 1, 31),
                },
                floor,
            ),
            (
                Shape::Sphere {
                    centre: DVec3::new(16.0, 8.0, 16.0),
                    radius: 5.0,
                },
                metal,
            ),
        ] {
            w.apply(EditOp::Shape {
                shape,
                mode: Mode::Add(m),
            })
            .unwrap();
        }
        let cam = Camera::looking_at(
            DVec3::new(-4.0, 14.0, -6.0),
            DVec3::new(16.0, 5.0, 16.0),
            50.0,
        );
        let p = params(
            cam,
            Sky::Uniform {
                colour: [0.8, 0.9, 1.0],
            },
            None,
            3,
        );
        let view = w.read();
        let v = Variant::for_scene(&view, &p);
        assert!(v.lambertian && v.metal, "{v:?}");
        assert!(
            !v.dielectric && !v.emissive && !v.sun && !v.gradient_sky,
            "{v:?}"
        );
        assert_eq!(v.max_bounces, 3);
        let gpu = GpuWorld::upload(&ctx, &view).unwrap();
        let mut tracer = PathTracer::new(&ctx).unwrap();
        let job = RenderJob {
            width: 24,
            height: 16,
            spp: 8,
            seed: 3,
        };
        let a = tracer
            .render(&ctx, &gpu, &view, &p, &job, RenderHow::variant(v))
            .unwrap()
            .image;
        let b = tracer
            .render(
                &ctx,
                &gpu,
                &view,
                &p,
                &job,
                RenderHow::variant(Variant::everything(3)),
            )
            .unwrap()
            .image;
        assert_eq!(tracer.variants(), 2);
        // Compilers may contract arithmetic differently per variant, so allow a few pixels
        // whose paths took another branch; the rest agree to float precision.
        let close = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .filter(|(x, y)| (0..3).all(|k| (x[k] - y[k]).abs() <= 1e-4 * y[k].abs().max(1.0)))
            .count();
        assert!(
            close * 100 >= a.pixels.len() * 98,
            "{close} of {} pixels agree",
            a.pixels.len()
        );
        let (ma, mb) = (a.mean(), b.mean());
        for k in 0..3 {
            assert!((ma[k] - mb[k]).abs() < 0.01 * mb[k], "{ma:?} vs {mb:?}");
        }
        drop(view);
        // A scene with a dielectric, an emitter, the sun and a gradient sky gets them all.
        w.push_material(brickmap::Material {
            kind: MaterialKind::Dielectric,
            param: 0,
            colour: 1,
        })
        .unwrap();
        let (_, sunny, _) = sun_floor();
        let v2 = Variant::for_scene(&w.read(), &sunny);
        assert!(
            v2.dielectric && v2.sun && v2.gradient_sky == matches!(sunny.sky, Sky::Gradient { .. })
        );

        tracer.destroy(&ctx);
        gpu.destroy(&ctx);
        assert_eq!(ctx.validation_errors(), 0);
    }

    #[test]
    fn back_to_back_benchmark_dispatches_are_each_timed_and_ordered() {
        let Some(ctx) = context(DeviceChoice::Best) else {
            return;
        };
        let (w, p, _) = sun_floor();
        let gpu = GpuWorld::upload(&ctx, &w.read()).unwrap();
        let mut tracer = PathTracer::new(&ctx).unwrap();
        let size = (16, 12);
        let mut acc = Progressive::new(&ctx, size, size, 3).unwrap();
        let variant = Variant::for_scene(&w.read(), &p);
        let times = acc
            .time_repeated(&ctx, &mut tracer, &gpu, &w.read(), &p, variant, 2, 5)
            .unwrap();
        if ctx.timestamp_period > 0.0 {
            assert_eq!(times.len(), 5);
            assert!(times.iter().all(|t| t.is_finite() && *t > 0.0), "{times:?}");
        } else {
            assert!(times.is_empty());
        }
        // The buffer holds one batch (each dispatch starts it over), the same as a render.
        let repeated = acc.hdr(&ctx).unwrap();
        let job = RenderJob {
            width: size.0,
            height: size.1,
            spp: 2,
            seed: 3,
        };
        let direct = tracer
            .render(&ctx, &gpu, &w.read(), &p, &job, RenderHow::SCENE)
            .unwrap()
            .image;
        // Equal up to the order of the shadow pass's float atomic adds.
        for (a, b) in repeated.pixels.iter().zip(&direct.pixels) {
            for k in 0..3 {
                assert!(
                    (a[k] - b[k]).abs() <= 1e-5 * b[k].abs().max(1.0),
                    "{a:?} vs {b:?}"
                );
            }
        }
        acc.destroy(&ctx);
        tracer.destroy(&ctx);
        gpu.destroy(&ctx);
        // Sync validation reports a missing barrier between the dispatches.
        assert_eq!(ctx.validation_errors(), 0);
    }

    #[test]
    fn internal_resolution_is_upscaled_bilinearly_before_the_curve() {
        let Some(ctx) = context(DeviceChoice::Best) else {
            return;
        };
        let (w, p, _) = sun_floor();
        let gpu = GpuWorld::upload(&ctx, &w.read()).unwrap();
        let mut tracer = PathTracer::new(&ctx).unwrap();
        let tone = ToneMapper::new(&ctx).unwrap();
        let (internal, output) = ((12, 8), (30, 21));
        let mut acc = Progressive::new(&ctx, internal, output, 1).unwrap();
        acc.frame(&ctx, &mut tracer, &gpu, &w.read(), &p, false, 8)
            .unwrap();
        let shown = acc.display(&ctx, &tone, 0.5).unwrap();
        let hdr = acc.hdr(&ctx).unwrap();
        assert_eq!((hdr.width, hdr.height), internal);
        let expected = hdr.resized_bilinear(output.0, output.1).to_srgb8(0.5);
        assert_eq!(shown.len(), expected.len());
        let worst = shown
            .iter()
            .zip(&expected)
            .flat_map(|(a, b)| (0..3).map(move |k| (a[k] as i32 - b[k] as i32).abs()))
            .max()
            .unwrap();
        assert!(
            worst <= 1,
            "display differs from the CPU upscale by {worst} levels"
        );
        // A structured image (a ramp times a checkerboard) makes interpolation visible: the
        // upscale has more distinct colours than the source has pixels, and still matches.
        let src = Image {
            width: 6,
            height: 4,
            pixels: (0..24)
                .map(|i| {
                    let (x, y) = (i % 6, i / 6);
                    let v = 0.05 * (x + 6 * y) as f32 * if (x + y) % 2 == 0 { 1.0 } else { 0.3 };
                    [v, 0.5 * v, 0.2]
                })
                .collect(),
        };
        let up = tone.upscale(&ctx, &src, (23, 17), 0.0).unwrap();
        let cpu = src.resized_bilinear(23, 17).to_srgb8(0.0);
        for (a, b) in up.iter().zip(&cpu) {
            assert!(
                (0..3).all(|k| (a[k] as i32 - b[k] as i32).abs() <= 1),
                "{a:?} vs {b:?}"
            );
        }
        let distinct: std::collections::HashSet<_> = up.iter().collect();
        assert!(distinct.len() > 24, "{} colours", distinct.len());
        acc.destroy(&ctx);
        tone.destroy(&ctx);
        tracer.destroy(&ctx);
        gpu.destroy(&ctx);
        assert_eq!(ctx.validation_errors(), 0);
    }
}
