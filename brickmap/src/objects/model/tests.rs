//! The model against the world: the same edits give the same voxels and exact inverses.
use super::*;
use crate::material::{Material, MaterialKind};
use crate::shape::Shape;
use crate::{GridDims, World, WorldConfig};
use glam::DVec3;
use proptest::prelude::*;

fn table(n: u8) -> MaterialTable {
    let mut t = MaterialTable::default();
    for i in 1..n {
        t.push(Material {
            kind: MaterialKind::Lambertian,
            param: 0,
            colour: i,
        })
        .unwrap();
    }
    t
}

fn op_strategy(size: IVec3) -> impl Strategy<Value = EditOp> {
    let m = 0u8..4;
    let mode = prop_oneof![
        m.clone().prop_map(Mode::Add),
        Just(Mode::Remove),
        m.clone().prop_map(Mode::Paint)
    ];
    let p =
        (-4..size.x + 4, -4..size.y + 4, -4..size.z + 4).prop_map(|(x, y, z)| IVec3::new(x, y, z));
    let inside = (0..size.x, 0..size.y, 0..size.z).prop_map(|(x, y, z)| IVec3::new(x, y, z));
    let sphere = (p.clone(), 0.5f64..9.0).prop_map(|(c, r)| Shape::Sphere {
        centre: c.as_dvec3() + DVec3::splat(0.25),
        radius: r,
    });
    let cuboid = (p.clone(), p).prop_map(|(a, b)| Shape::Box {
        min: a.min(b),
        max: a.max(b),
    });
    let voxel_op = prop_oneof![
        m.clone().prop_map(VoxelOp::Set),
        Just(VoxelOp::Clear),
        m.prop_map(VoxelOp::Paint)
    ];
    prop_oneof![
        (prop_oneof![sphere, cuboid], mode).prop_map(|(shape, mode)| EditOp::Shape { shape, mode }),
        prop::collection::vec((inside, voxel_op), 1..40).prop_map(|v| EditOp::Voxels(
            v.into_iter()
                .map(|(pos, op)| VoxelEdit { pos, op })
                .collect()
        )),
    ]
}

fn same(model: &Model, world: &World) {
    let view = world.read();
    let s = model.size();
    for z in 0..s.z {
        for y in 0..s.y {
            for x in 0..s.x {
                let v = IVec3::new(x, y, z);
                assert_eq!(model.voxel(v), view.voxel(v).unwrap(), "{v}");
            }
        }
    }
    assert_eq!(model.solid_count(), view.solid_count());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// A model of a whole number of bricks behaves as a world of that size, and every
    /// inverse puts back the exact content, and its own inverse redoes.
    #[test]
    fn a_model_edits_as_the_world_does_and_undoes_exactly(
        ops in prop::collection::vec(op_strategy(IVec3::new(24, 16, 16)), 1..8)
    ) {
        let size = IVec3::new(24, 16, 16);
        let t = table(4);
        let world = World::new(GridDims::new(3, 2, 2).unwrap(), WorldConfig::with_workers(2)).unwrap();
        for i in 0..4 {
            if i > 0 {
                world.push_material(t.get(i).unwrap()).unwrap();
            }
        }
        let mut model = Model::new(size).unwrap();
        let mut undo = Vec::new();
        for op in &ops {
            let before = model.content_hash();
            let m = model.apply(op, &t).unwrap();
            let w = world.apply(op.clone()).unwrap();
            prop_assert_eq!(m.changed_voxels, w.changed_voxels);
            undo.push((before, m.inverse));
        }
        same(&model, &world);
        let end = model.content_hash();
        let mut redo = Vec::new();
        for (before, inv) in undo.into_iter().rev() {
            let r = model.apply(&EditOp::Restore(inv), &t).unwrap();
            prop_assert_eq!(model.content_hash(), before);
            redo.push(r.inverse);
        }
        prop_assert_eq!(model.solid_count(), 0);
        for inv in redo.into_iter().rev() {
            model.apply(&EditOp::Restore(inv), &t).unwrap();
        }
        prop_assert_eq!(model.content_hash(), end);
    }
}

#[test]
fn a_large_shape_computed_on_every_core_matches_the_world() {
    let t = table(4);
    let size = IVec3::new(128, 64, 96);
    let world = World::new(
        GridDims::from_voxels(size.as_uvec3()).unwrap(),
        WorldConfig::with_workers(3),
    )
    .unwrap();
    world.replace_materials(t.clone()).unwrap();
    let mut model = Model::new(size).unwrap();
    let ops = [
        EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::new(60.3, 30.0, 50.0),
                radius: 40.0,
            },
            mode: Mode::Add(2),
        },
        EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::new(10, 5, 10),
                max: IVec3::new(120, 40, 90),
            },
            mode: Mode::Paint(3),
        },
        EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::new(70.0, 40.5, 40.0),
                radius: 25.0,
            },
            mode: Mode::Remove,
        },
    ];
    let mut undo = Vec::new();
    for op in &ops {
        let before = model.content_hash();
        let m = model.apply(op, &t).unwrap();
        if let EditOp::Shape { shape, .. } = op {
            let (lo, hi) = shape.voxel_bounds();
            let (lo, hi) = (
                lo.clamp(IVec3::ZERO, size - 1) / 8,
                hi.clamp(IVec3::ZERO, size - 1) / 8,
            );
            let bricks = (hi - lo + 1).element_product() as usize;
            assert!(
                bricks >= PARALLEL_BRICKS,
                "the parallel path runs: {bricks}"
            );
        }
        let w = world.apply(op.clone()).unwrap();
        assert_eq!(m.changed_voxels, w.changed_voxels);
        undo.push((before, m.inverse));
    }
    same(&model, &world);
    for (before, inv) in undo.into_iter().rev() {
        model.apply(&EditOp::Restore(inv), &t).unwrap();
        assert_eq!(model.content_hash(), before);
    }
}

#[test]
fn odd_sizes_clip_shapes_and_refuse_voxels_outside() {
    let t = table(2);
    let mut m = Model::new(IVec3::new(5, 3, 9)).unwrap();
    let all = EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::splat(-10),
            max: IVec3::splat(100),
        },
        mode: Mode::Add(1),
    };
    let out = m.apply(&all, &t).unwrap();
    assert_eq!(m.solid_count(), 5 * 3 * 9);
    assert_eq!(out.changed_voxels, 135);
    assert_eq!(m.bricks_size(), UVec3::new(1, 1, 2));
    let before = m.clone();
    let outside = EditOp::Voxels(vec![
        VoxelEdit {
            pos: IVec3::new(0, 0, 0),
            op: VoxelOp::Clear,
        },
        VoxelEdit {
            pos: IVec3::new(5, 0, 0),
            op: VoxelOp::Clear,
        },
    ]);
    assert!(matches!(
        m.apply(&outside, &t),
        Err(BrickmapError::OutOfRange(..))
    ));
    let bad_material = EditOp::Shape {
        shape: Shape::Voxel(IVec3::ZERO),
        mode: Mode::Paint(7),
    };
    assert!(matches!(
        m.apply(&bad_material, &t),
        Err(BrickmapError::MaterialIndex { .. })
    ));
    // A restore that writes past the model's box.
    let mut wide = out.inverse.clone();
    wide.bricks[0].touched = Mask::FULL;
    assert!(matches!(
        m.apply(&EditOp::Restore(wide), &t),
        Err(BrickmapError::BadInverse(_))
    ));
    assert_eq!(m, before, "refused edits change nothing");
    assert!(Model::new(IVec3::new(0, 1, 1)).is_err());
    assert!(Model::new(IVec3::new(1, 1025, 1)).is_err());
    assert_eq!(m.voxel(IVec3::new(5, 0, 0)), None);
    assert_eq!(m.voxel(IVec3::new(4, 2, 8)), Some(1));
}

#[test]
fn generate_fills_the_columns_and_undoes() {
    use crate::edit::{ColumnSource, Generator};
    struct Floor;
    impl ColumnSource for Floor {
        fn column(&self, _: u32, _: u32, emit: &mut dyn FnMut(u32, Mask, PriorMaterials)) {
            emit(0, Mask::FULL, PriorMaterials::Uniform(1));
        }
        fn materials(&self) -> Vec<u8> {
            vec![1]
        }
    }
    let t = table(2);
    let mut m = Model::new(IVec3::new(10, 20, 3)).unwrap();
    m.apply(
        &EditOp::Shape {
            shape: Shape::Voxel(IVec3::new(1, 15, 1)),
            mode: Mode::Add(0),
        },
        &t,
    )
    .unwrap();
    let before = m.content_hash();
    let out = m
        .apply(&EditOp::Generate(Generator(std::sync::Arc::new(Floor))), &t)
        .unwrap();
    assert_eq!(
        m.solid_count(),
        10 * 8 * 3,
        "the first brick layer, clipped; the rest empty"
    );
    assert_eq!(m.voxel(IVec3::new(1, 15, 1)), None);
    m.apply(&EditOp::Restore(out.inverse), &t).unwrap();
    assert_eq!(m.content_hash(), before);
}

/// A generator of per-voxel materials over many columns: a model whose size is not a
/// multiple of 8 takes the clipped part with the right materials, on every core.
#[test]
fn a_generator_fills_a_clipped_model_as_it_fills_the_world() {
    use crate::edit::{ColumnSource, Generator};
    struct Stripes;
    impl ColumnSource for Stripes {
        fn column(&self, bx: u32, bz: u32, emit: &mut dyn FnMut(u32, Mask, PriorMaterials)) {
            for by in 0..2 {
                let mut mask = Mask::EMPTY;
                let mut mats = Vec::new();
                for bit in 0..512usize {
                    if !(bit + bx as usize * 3 + bz as usize + by as usize * 5).is_multiple_of(4) {
                        mask.set(bit);
                        mats.push(((bit / 7 + bx as usize) % 3 + 1) as u8);
                    }
                }
                emit(by, mask, PriorMaterials::PerVoxel(mats));
            }
        }
        fn materials(&self) -> Vec<u8> {
            vec![1, 2, 3]
        }
    }
    let t = table(4);
    let size = IVec3::new(203, 13, 205);
    let world = World::new(
        GridDims::new(26, 2, 26).unwrap(),
        WorldConfig::with_workers(2),
    )
    .unwrap();
    world.replace_materials(t.clone()).unwrap();
    let op = EditOp::Generate(Generator(std::sync::Arc::new(Stripes)));
    world.apply(op.clone()).unwrap();
    let mut model = Model::new(size).unwrap();
    let before = model.content_hash();
    let out = model.apply(&op, &t).unwrap();
    // The 26 × 26 columns take the parallel path.
    const _: () = assert!(26 * 26 >= PARALLEL_BRICKS);
    let view = world.read();
    for z in 0..size.z {
        for y in 0..size.y {
            for x in 0..size.x {
                let v = IVec3::new(x, y, z);
                assert_eq!(model.voxel(v), view.voxel(v).unwrap(), "{v}");
            }
        }
    }
    drop(view);
    model.apply(&EditOp::Restore(out.inverse), &t).unwrap();
    assert_eq!(model.content_hash(), before);
}
