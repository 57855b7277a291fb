//! Random sessions of object ops: after each, the world is the forward reference of the
//! tree; undoing them all gives back the first tree, models and world exactly, and redoing
//! the undos gives back the last.

use super::*;
use crate::edit::Mode;
use crate::objects::orient::Orientation;
use crate::objects::testing::{GRID, assert_matches, model, reference, start, table};
use crate::objects::tree::Layer;
use crate::shape::Shape;
use glam::DVec3;
use proptest::prelude::*;

/// A random op over the nodes 0..6 and models 0..3 (many are refused: a test of that too).
fn op() -> impl Strategy<Value = ObjectOp> {
    let node = (0u32..6).prop_map(NodeId);
    let p = (0usize..48, (8..56, 8..24, 8..40)).prop_map(|(r, (x, y, z))| Placement {
        rot: Orientation::all().nth(r).unwrap(),
        t: IVec3::new(x, y, z) - IVec3::new(24, 12, 20) * (x % 2),
    });
    prop_oneof![
        (
            node.clone(),
            (0..64, 0..32, 0..48),
            1.0f64..6.0,
            any::<bool>()
        )
            .prop_map(|(node, (x, y, z), radius, remove)| ObjectOp::Edit {
                node,
                edit: EditOp::Shape {
                    shape: Shape::Sphere {
                        centre: DVec3::new(x as f64, y as f64, z as f64) + 0.5,
                        radius,
                    },
                    mode: if remove { Mode::Remove } else { Mode::Add(4) },
                },
            }),
        (node.clone(), p.clone()).prop_map(|(node, placement)| ObjectOp::Place { node, placement }),
        (node.clone(), any::<bool>()).prop_map(|(node, visible)| ObjectOp::Show { node, visible }),
        (node.clone(), any::<bool>()).prop_map(|(node, locked)| ObjectOp::Lock { node, locked }),
        (node.clone(), node.clone(), 0usize..4).prop_map(|(node, parent, i)| ObjectOp::Move {
            node,
            parent,
            index: Some(i)
        }),
        (node.clone(), p.clone(), 0u32..3).prop_map(|(parent, placement, m)| ObjectOp::Add {
            parent,
            index: None,
            name: "new".into(),
            placement,
            new: NewNode::Object {
                model: ModelId(m),
                layer: LayerId(0)
            },
        }),
        node.clone().prop_map(|node| ObjectOp::Remove { node }),
        (node.clone(), node.clone(), p.clone()).prop_map(|(node, parent, placement)| {
            ObjectOp::Reparent {
                node,
                parent,
                index: None,
                placement,
            }
        }),
        (node.clone(), 0u32..3).prop_map(|(node, model)| ObjectOp::SetModel {
            node,
            model: ModelId(model)
        }),
        (0u32..3).prop_map(|m| ObjectOp::AddModel {
            model: ModelId(m),
            voxels: Box::new(model(IVec3::new(5, 5, 3), m as i32 + 2)),
        }),
        (0u32..3).prop_map(|m| ObjectOp::RemoveModel { model: ModelId(m) }),
        any::<bool>().prop_map(|visible| ObjectOp::ShowLayer {
            layer: LayerId(1),
            visible
        }),
        (node.clone(), 0u8..3).prop_map(|(node, l)| ObjectOp::SetLayer {
            node,
            layer: LayerId(l)
        }),
        (0u8..3).prop_map(|l| ObjectOp::RenameLayer {
            layer: LayerId(l),
            name: format!("renamed {l}")
        }),
        any::<bool>().prop_map(|visible| ObjectOp::AddLayer(Layer {
            name: "added".into(),
            visible
        })),
        Just(ObjectOp::RemoveLastLayer),
    ]
}

/// Everything an op may change: the tree, every model's content, the world's content.
fn state(o: &Objects, w: &World) -> (ObjectTree, Vec<(ModelId, u64)>, u64) {
    (
        o.tree().clone(),
        o.models()
            .iter()
            .map(|(id, m)| (*id, m.content_hash()))
            .collect(),
        w.read().content_hash(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]
    #[test]
    fn random_ops_undo_and_redo_exactly(
        ops in prop::collection::vec(op(), 1..14),
        batch in any::<bool>()
    ) {
        let t = table();
        let (mut o, w) = start(2);
        let first = state(&o, &w);
        // Half the sessions apply their ops as one batch (all or none).
        let ops = if batch { vec![ObjectOp::Batch(ops)] } else { ops };
        let mut undo = Vec::new();
        for op in ops {
            let before = state(&o, &w);
            match o.apply(&w, op, &t) {
                Ok(inverse) => undo.push(inverse),
                Err(_) => prop_assert_eq!(&state(&o, &w), &before, "a refused op changes nothing"),
            }
            assert_matches(&w, &reference(o.tree(), o.models()));
        }
        let last = state(&o, &w);
        let mut redo = Vec::new();
        for inverse in undo.into_iter().rev() {
            redo.push(o.apply(&w, inverse, &t).unwrap());
        }
        prop_assert_eq!(&state(&o, &w), &first);
        for op in redo.into_iter().rev() {
            o.apply(&w, op, &t).unwrap();
        }
        prop_assert_eq!(&state(&o, &w), &last);
        assert_matches(&w, &reference(o.tree(), o.models()));
    }
}

#[test]
fn locked_objects_refuse_edits_and_moves_and_a_shared_model_edit_shows_in_both() {
    let t = table();
    let (mut o, w) = start(1);
    let (b, c) = (NodeId(3), NodeId(4));
    assert_eq!(o.tree().instances(ModelId(1)), [b, c]);
    o.apply(
        &w,
        ObjectOp::Lock {
            node: c,
            locked: true,
        },
        &t,
    )
    .unwrap();
    let before = state(&o, &w);
    let centre = o.tree().world_placement(c).unwrap().t.as_dvec3();
    let edit = EditOp::Shape {
        shape: Shape::Sphere {
            centre,
            radius: 3.0,
        },
        mode: Mode::Remove,
    };
    assert!(matches!(
        o.apply(&w, ObjectOp::Edit { node: c, edit: edit.clone() }, &t),
        Err(ObjectError::Locked(n)) if n == c
    ));
    assert!(matches!(
        o.apply(
            &w,
            ObjectOp::Place {
                node: c,
                placement: Placement::IDENTITY
            },
            &t
        ),
        Err(ObjectError::Locked(_))
    ));
    assert!(matches!(
        o.apply(
            &w,
            ObjectOp::Remove {
                node: ObjectTree::ROOT
            },
            &t
        ),
        Err(ObjectError::Locked(_)) | Err(ObjectError::Tree(TreeError::Root))
    ));
    assert_eq!(state(&o, &w), before);
    // Editing b (unlocked) edits model 1, which c shows too.
    let centre_b = o.tree().world_placement(b).unwrap().t.as_dvec3();
    let edit_b = EditOp::Shape {
        shape: Shape::Sphere {
            centre: centre_b,
            radius: 3.0,
        },
        mode: Mode::Remove,
    };
    let solid = o.model(ModelId(1)).unwrap().solid_count();
    o.apply(
        &w,
        ObjectOp::Edit {
            node: b,
            edit: edit_b,
        },
        &t,
    )
    .unwrap();
    assert!(o.model(ModelId(1)).unwrap().solid_count() < solid);
    assert_matches(&w, &reference(o.tree(), o.models()));
    // A model in use cannot be removed; an object cannot leave the grid.
    assert!(matches!(
        o.apply(&w, ObjectOp::RemoveModel { model: ModelId(1) }, &t),
        Err(ObjectError::ModelInUse(_, 2))
    ));
    let before = state(&o, &w);
    let far = ObjectOp::Place {
        node: b,
        placement: Placement::at(GRID * 2),
    };
    assert!(matches!(
        o.apply(&w, far, &t),
        Err(ObjectError::Composite(_))
    ));
    assert_eq!(state(&o, &w), before);
}

#[test]
fn a_scene_that_outgrows_its_grid_moves_into_a_larger_one() {
    let t = table();
    let (mut o, w) = start(2);
    let c = NodeId(4);
    // Past the grid's far corner: refused, naming the grid.
    let far = ObjectOp::Place {
        node: c,
        placement: Placement::at(IVec3::new(74, 14, 30)),
    };
    let e = o.apply(&w, far.clone(), &t).unwrap_err();
    assert!(e.to_string().contains("[64, 32, 48] voxel grid"), "{e}");
    // Below the origin too: the extent says how much grid is needed.
    let low = ObjectOp::Place {
        node: NodeId(2),
        placement: Placement::at(IVec3::new(-40, 0, 0)),
    };
    assert!(o.apply(&w, low.clone(), &t).is_err());
    let (lo, hi) = o.extent().unwrap();
    assert!(lo.cmpge(IVec3::ZERO).all() && hi.cmple(GRID).all());
    // A grid with room on both sides: the scene moves in, shifted, the same voxels.
    let shift = IVec3::new(32, 0, 0);
    let big = World::new(
        crate::GridDims::from_voxels((GRID + IVec3::new(64, 0, 0)).as_uvec3()).unwrap(),
        crate::WorldConfig::with_workers(2),
    )
    .unwrap();
    big.replace_materials(t.clone()).unwrap();
    let before = reference(o.tree(), o.models());
    o.regrid(&big, shift).unwrap();
    assert_eq!(o.grid(), GRID + IVec3::new(64, 0, 0));
    let shifted: std::collections::HashMap<IVec3, u8> =
        before.into_iter().map(|(p, m)| (p + shift, m)).collect();
    assert_matches(&big, &shifted);
    // Now both places fit (relative to the shifted root: t − shift keeps the world spot).
    o.apply(&big, far, &t).unwrap();
    o.apply(&big, low, &t).unwrap();
    assert_matches(&big, &reference(o.tree(), o.models()));
    // A grid too small for the scene is refused and nothing changes.
    let tiny = World::new(
        crate::GridDims::new(1, 1, 1).unwrap(),
        crate::WorldConfig::with_workers(1),
    )
    .unwrap();
    let tree = o.tree().clone();
    assert!(o.regrid(&tiny, IVec3::ZERO).is_err());
    assert_eq!(o.tree(), &tree);
    assert_eq!(tiny.read().solid_count(), 0);
}

/// A grid adopted as one object: nothing written, and every edit through the object (a
/// shape, a restore of a move, the undo) leaves the world as the same edit of the world
/// itself; the counts are the world's.
#[test]
fn a_grid_adopted_as_one_object_edits_as_the_grid() {
    let t = table();
    let worlds = [
        crate::objects::testing::world(2),
        crate::objects::testing::world(1),
    ];
    for w in &worlds {
        let floor = EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::ZERO,
                max: IVec3::new(63, 5, 47),
            },
            mode: Mode::Add(3),
        };
        w.apply(floor).unwrap();
        w.take_dirty();
    }
    let (mut o, node) = Objects::of_world(&worlds[0]).unwrap();
    assert_eq!(worlds[0].take_dirty().bytes(), 0, "adopting writes nothing");
    assert_eq!(o.models()[&ModelId(0)].solid_count(), 64 * 6 * 48);
    let sphere = EditOp::Shape {
        shape: Shape::Sphere {
            centre: DVec3::new(20.5, 6.0, 20.5),
            radius: 7.0,
        },
        mode: Mode::Add(4),
    };
    let expect = worlds[1].apply(sphere.clone()).unwrap();
    let (undo, changed) = o
        .apply_counted(&worlds[0], ObjectOp::Edit { node, edit: sphere }, &t)
        .unwrap();
    assert_eq!(changed, expect.changed_voxels);
    assert_eq!(
        worlds[0].read().content_hash(),
        worlds[1].read().content_hash()
    );
    // The world's restore (what a paste or a move is) goes in brick by brick.
    let restore = EditOp::Restore(expect.inverse.clone());
    o.apply(
        &worlds[0],
        ObjectOp::Edit {
            node,
            edit: restore,
        },
        &t,
    )
    .unwrap();
    worlds[1].apply(EditOp::Restore(expect.inverse)).unwrap();
    assert_eq!(
        worlds[0].read().content_hash(),
        worlds[1].read().content_hash()
    );
    // The sphere's own undo (now a no-op on voxels) applies, and the model is the world.
    o.apply(&worlds[0], undo, &t).unwrap();
    assert_eq!(
        worlds[0].read().content_hash(),
        worlds[1].read().content_hash()
    );
    assert_eq!(
        o.models()[&ModelId(0)].solid_count(),
        worlds[1].read().solid_count()
    );
}

/// A click's object: at every solid world cell, the object the reference says drew it.
#[test]
fn the_object_at_a_cell_is_the_one_whose_voxel_shows_there() {
    let (o, w) = start(2);
    let view = w.read();
    let mut seen = 0;
    for d in o.tree().drawn() {
        let m = o.model(d.model).unwrap();
        for (b, brick) in m.bricks() {
            for bit in brick.mask.ones() {
                let v = b.as_ivec3() * 8
                    + IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
                let cell = d.placement.place(v, m.size());
                // The last drawn object with a voxel at the cell is the one shown.
                let shown = o
                    .tree()
                    .drawn()
                    .into_iter()
                    .rev()
                    .find(|e| {
                        let em = o.model(e.model).unwrap();
                        em.voxel(e.placement.unplace(cell, em.size())).is_some()
                    })
                    .unwrap();
                assert_eq!(o.object_at(cell), Some(shown.node), "{cell}");
                assert!(view.voxel(cell).unwrap().is_some());
                seen += 1;
            }
        }
    }
    assert!(seen > 100);
    assert_eq!(o.object_at(IVec3::new(-1, 0, 0)), None);
    let empty = (0..64)
        .map(|x| IVec3::new(x, 31, 47))
        .find(|v| view.voxel(*v).unwrap().is_none())
        .unwrap();
    assert_eq!(o.object_at(empty), None);
}
