//! Failure paths: running out of the brick or material budget in the middle of an edit
//! spanning several workers rolls the whole edit back, and a worker panic is an error, not
//! a hang.

use brickmap::{
    BrickmapError, EditOp, GridDims, Mode, Shape, VoxelEdit, VoxelOp, World, WorldConfig,
};
use glam::{DVec3, IVec3};

fn striped(world: &World, y: i32) -> EditOp {
    // A slab of voxels with per-voxel materials that alternate, so every brick needs bytes.
    let dims = world.dims().voxels();
    let mut list = Vec::new();
    for z in 0..dims.z {
        for x in 0..dims.x {
            list.push(VoxelEdit {
                pos: IVec3::new(x, y, z),
                op: VoxelOp::Set(((x + z) % 2) as u8),
            });
        }
    }
    EditOp::Voxels(list)
}

#[test]
fn exhausted_material_budget_rolls_back_everywhere() {
    // 16 × 2 × 16 bricks, 4 workers; one 64 KiB material chunk per worker fits 32 pages.
    let config = WorldConfig {
        workers: 4,
        max_material_bytes: 4 * 64 * 1024,
        ..Default::default()
    };
    let world = World::new(GridDims::new(16, 2, 16).unwrap(), config).unwrap();
    world
        .push_material(brickmap::Material::lambertian(9))
        .unwrap();
    let mut layers = 0;
    let err = loop {
        let hash = world.read().content_hash();
        let solid = world.read().solid_count();
        match world.apply(striped(&world, layers)) {
            Ok(_) => layers += 1,
            Err(e) => {
                assert_eq!(
                    world.read().content_hash(),
                    hash,
                    "failed edit changed the world"
                );
                assert_eq!(world.read().solid_count(), solid);
                break e;
            }
        }
        assert!(layers < 16, "budget never reached");
    };
    assert_eq!(err, BrickmapError::OutOfSpace("material byte"));
    assert!(layers >= 1);
    let view = world.read();
    view.validate().unwrap();
    // Edits that fit still work after the failure.
    drop(view);
    world
        .apply(EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::splat(8.0),
                radius: 3.0,
            },
            mode: Mode::Remove,
        })
        .unwrap();
    world.read().validate().unwrap();
}

#[test]
fn exhausted_brick_budget_rolls_back() {
    // Full interior cells need no stored brick; a sphere's surface needs thousands of partial
    // bricks (about 2π·200/8 around × 16 high), and the budget is one 1024-brick chunk.
    let config = WorldConfig {
        workers: 2,
        max_bricks: 1024,
        ..Default::default()
    };
    let world = World::new(GridDims::new(64, 16, 64).unwrap(), config).unwrap();
    let hash = world.read().content_hash();
    let sphere = Shape::Sphere {
        centre: DVec3::new(256.0, 64.0, 256.0),
        radius: 200.0,
    };
    let err = world
        .apply(EditOp::Shape {
            shape: sphere.clone(),
            mode: Mode::Add(0),
        })
        .unwrap_err();
    assert_eq!(err, BrickmapError::OutOfSpace("brick"));
    assert_eq!(world.read().content_hash(), hash);
    assert_eq!(world.read().solid_count(), 0);
    world.read().validate().unwrap();
    // A box of whole bricks still fits: it is stored as full cells.
    let cube = Shape::Box {
        min: IVec3::ZERO,
        max: IVec3::new(511, 127, 511),
    };
    world
        .apply(EditOp::Shape {
            shape: cube,
            mode: Mode::Add(0),
        })
        .unwrap();
    assert_eq!(world.read().memory().full_cells, 64 * 16 * 64);
    assert_eq!(world.read().memory().bricks_used, 0);
}

#[test]
fn worker_panic_is_an_error_not_a_hang() {
    let world = World::new(
        GridDims::new(8, 2, 8).unwrap(),
        WorldConfig::with_workers(2),
    )
    .unwrap();
    let err = world.inject_worker_panic(1).unwrap().wait().unwrap_err();
    assert!(
        matches!(err, BrickmapError::WorkerPanicked { worker: 1, .. }),
        "{err}"
    );
    // An edit touching the poisoned slab fails with a clear error; the other slab still works.
    let far = EditOp::Shape {
        shape: Shape::Sphere {
            centre: DVec3::new(60.0, 8.0, 8.0),
            radius: 2.0,
        },
        mode: Mode::Add(0),
    };
    assert!(matches!(
        world.apply(far),
        Err(BrickmapError::WorkerPanicked { worker: 1, .. })
    ));
    let near = EditOp::Shape {
        shape: Shape::Sphere {
            centre: DVec3::new(4.0, 8.0, 8.0),
            radius: 2.0,
        },
        mode: Mode::Add(0),
    };
    assert!(world.apply(near).unwrap().changed_voxels > 0);
    drop(world); // joins the workers without hanging
}

/// `count` partial bricks (every other voxel solid, so each needs a stored brick) in x-major
/// order across the grid, one brick named twice.
fn partial_bricks(
    world: &World,
    count: u32,
) -> Vec<(glam::UVec3, brickmap::Mask, brickmap::PriorMaterials)> {
    let b = world.dims().bricks();
    let mut mask = brickmap::Mask::EMPTY;
    for bit in (0..512).step_by(2) {
        mask.set(bit);
    }
    let mut list: Vec<_> = (0..count)
        .map(|i| {
            let brick = glam::UVec3::new(i % b.x, (i / b.x) % b.y, i / (b.x * b.y));
            (
                brick,
                mask,
                brickmap::PriorMaterials::Uniform((i % 2) as u8),
            )
        })
        .collect();
    list.push((
        list[0].0,
        brickmap::Mask::FULL,
        brickmap::PriorMaterials::Uniform(1),
    ));
    list
}

#[test]
fn an_unrecorded_bulk_write_is_the_same_edit_and_still_rolls_back() {
    let config = |max_bricks| WorldConfig {
        workers: 2,
        max_bricks,
        ..Default::default()
    };
    let dims = GridDims::new(16, 8, 16).unwrap();
    let prepared = |max_bricks| {
        let world = World::new(dims, config(max_bricks)).unwrap();
        world
            .push_material(brickmap::Material::lambertian(9))
            .unwrap();
        // Cells that are not empty before the write: their records are whole restores.
        world
            .apply(EditOp::Shape {
                shape: Shape::Sphere {
                    centre: DVec3::splat(20.0),
                    radius: 9.0,
                },
                mode: Mode::Add(1),
            })
            .unwrap();
        world
    };
    // The same write, recorded and not: the same world.
    let (a, b) = (prepared(u64::MAX), prepared(u64::MAX));
    let changed = a
        .apply(brickmap::terrain::set_bricks(partial_bricks(&a, 300)))
        .unwrap()
        .changed_voxels;
    let unrecorded = b
        .apply_unrecorded(brickmap::terrain::set_bricks(partial_bricks(&b, 300)))
        .unwrap();
    assert_eq!(unrecorded, changed);
    assert_eq!(a.read().content_hash(), b.read().content_hash());
    b.read().validate().unwrap();
    // Undone (its inverse applied as history does), the write that names a brick twice
    // leaves the world as before it.
    let c = prepared(u64::MAX);
    let before = c.read().content_hash();
    let done = c
        .apply(brickmap::terrain::set_bricks(partial_bricks(&c, 300)))
        .unwrap();
    c.apply(EditOp::Restore(done.inverse)).unwrap();
    assert_eq!(
        c.read().content_hash(),
        before,
        "the undo left part of the write"
    );
    // Over the brick budget part way (one 1024-brick chunk, 1500 bricks asked for across
    // both workers), recorded or not: the world as before, the pre-existing bricks and the
    // brick named twice included.
    // Both ways a restore reaches the workers: copied apart, or (in slab order) as runs of
    // one shared list.
    for (unrecorded, in_slab_order) in [(false, false), (true, false), (false, true), (true, true)]
    {
        let world = prepared(1024);
        let (hash, solid) = (world.read().content_hash(), world.read().solid_count());
        let mut bricks = partial_bricks(&world, 1500);
        if in_slab_order {
            bricks.sort_by_key(|b| b.0.x);
        }
        let write = brickmap::terrain::set_bricks(bricks);
        let err = if unrecorded {
            world.apply_unrecorded(write).unwrap_err()
        } else {
            world.apply(write).unwrap_err()
        };
        assert_eq!(err, BrickmapError::OutOfSpace("brick"));
        assert_eq!(
            world.read().content_hash(),
            hash,
            "failed write changed the world"
        );
        assert_eq!(world.read().solid_count(), solid);
        world.read().validate().unwrap();
    }
}
