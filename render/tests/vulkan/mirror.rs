//! The world's GPU mirror: byte for byte equal to the CPU world after random edit batches,
//! and large scattered edits uploaded within the region budget.

use super::*;

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
