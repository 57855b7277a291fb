//! The Vulkan layer on a real device (lavapipe in CI), with the validation layer and
//! synchronization validation on: every validation error fails the test. Machines without
//! any Vulkan driver skip, saying so, unless VOXBRICK_REQUIRE_GPU=1 (CI) makes that a failure.
//! Here: the context, the messenger and the traversal against the exact CPU ray cast; the
//! path tracer against closed forms and the CPU reference (`trace.rs`), the world's GPU
//! mirror under edits (`mirror.rs`), progressive accumulation and variants (`progressive.rs`).

#[path = "../common/mod.rs"]
mod common;
mod mirror;
mod progressive;
mod trace;

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
