//! The composite against a voxel-by-voxel reference: every model voxel placed forward, in
//! drawing order, a later object overwriting; after random model edits, moves, rotations,
//! hides, reorders and removals, and after undoing them all.

use super::*;
use crate::edit::{EditOp, Mode};
use crate::objects::orient::{Orientation, Placement};
use crate::objects::testing::{GRID, assert_matches, model, reference, table, world};
use crate::objects::tree::{LayerId, NewNode};
use crate::shape::Shape;
use glam::DVec3;
use proptest::prelude::*;

/// One step of a random session.
#[derive(Clone, Debug)]
enum Step {
    /// A sphere added or removed in model `m`'s frame.
    Edit {
        m: u32,
        centre: IVec3,
        radius: f64,
        remove: bool,
    },
    /// Object (by position among the objects) moved to a new placement.
    Place { o: usize, rot: usize, t: IVec3 },
    /// Visibility toggled.
    Hide { o: usize },
    /// Moved to the front of the drawing order.
    Reorder { o: usize },
    /// Removed.
    Remove { o: usize },
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        (0u32..3, (0..20, 0..20, 0..20), 1.0f64..6.0, any::<bool>()).prop_map(
            |(m, (x, y, z), radius, remove)| Step::Edit {
                m,
                centre: IVec3::new(x, y, z),
                radius,
                remove
            }
        ),
        (0usize..5, 0usize..48, (4..60, 4..28, 4..44)).prop_map(|(o, rot, (x, y, z))| {
            Step::Place {
                o,
                rot,
                t: IVec3::new(x, y, z),
            }
        }),
        (0usize..5).prop_map(|o| Step::Hide { o }),
        (0usize..5).prop_map(|o| Step::Reorder { o }),
        (0usize..5).prop_map(|o| Step::Remove { o }),
    ]
}

struct Session {
    tree: ObjectTree,
    models: BTreeMap<ModelId, Model>,
    objects: Vec<NodeId>,
    composite: Composite,
    world: World,
}

impl Session {
    fn new(workers: usize) -> Self {
        let mut tree = ObjectTree::new();
        let mut models = BTreeMap::new();
        models.insert(ModelId(0), model(IVec3::new(9, 6, 5), 0));
        models.insert(ModelId(1), model(IVec3::new(16, 8, 16), 1));
        models.insert(ModelId(2), model(IVec3::new(3, 11, 7), 2));
        let g = tree
            .add(
                ObjectTree::ROOT,
                None,
                "g",
                Placement::at(IVec3::new(24, 12, 20)),
                NewNode::Group,
            )
            .unwrap();
        let mut objects = Vec::new();
        // Model 1 placed twice (instances), the others once; two inside the group.
        for (i, (parent, m, t)) in [
            (ObjectTree::ROOT, 1, IVec3::new(12, 12, 12)),
            (g, 0, IVec3::new(5, 3, 3)),
            (ObjectTree::ROOT, 1, IVec3::new(18, 14, 18)),
            (g, 2, IVec3::new(0, 6, 0)),
            (ObjectTree::ROOT, 0, IVec3::new(50, 16, 36)),
        ]
        .into_iter()
        .enumerate()
        {
            let placement = Placement {
                rot: Orientation::all().nth(i * 11 % 48).unwrap(),
                t,
            };
            let new = NewNode::Object {
                model: ModelId(m),
                layer: LayerId(0),
            };
            objects.push(
                tree.add(parent, None, format!("o{i}"), placement, new)
                    .unwrap(),
            );
        }
        let world = world(workers);
        let composite = Composite::new(&tree, &models, GRID).unwrap();
        composite
            .write(&world, &composite.all_bricks(), &models)
            .unwrap();
        Self {
            tree,
            models,
            objects,
            composite,
            world,
        }
    }

    /// Applies a step; returns how to undo it (None when it was refused or did nothing).
    fn run(&mut self, s: &Step) -> Option<Undo> {
        match *s {
            Step::Edit {
                m,
                centre,
                radius,
                remove,
            } => {
                let op = EditOp::Shape {
                    shape: Shape::Sphere {
                        centre: centre.as_dvec3() + DVec3::splat(0.5),
                        radius,
                    },
                    mode: if remove { Mode::Remove } else { Mode::Add(3) },
                };
                let out = self
                    .models
                    .get_mut(&ModelId(m))
                    .unwrap()
                    .apply(&op, &table())
                    .unwrap();
                self.composite
                    .model_edited(&self.world, &self.models, ModelId(m), &out.inverse)
                    .unwrap();
                Some(Undo::Model(ModelId(m), out.inverse))
            }
            Step::Place { o, rot, t } => {
                let node = *self.objects.get(o)?;
                let before = self.tree.node(node).ok()?.placement;
                self.tree.node_mut(node).unwrap().placement = Placement {
                    rot: Orientation::all().nth(rot).unwrap(),
                    t,
                };
                if self
                    .composite
                    .update(&self.world, &self.tree, &self.models, &[])
                    .is_err()
                {
                    // Outside the grid: refused, and put back.
                    self.tree.node_mut(node).unwrap().placement = before;
                    return None;
                }
                Some(Undo::Place(node, before))
            }
            Step::Hide { o } => {
                let node = *self.objects.get(o)?;
                let n = self.tree.node_mut(node).ok()?;
                n.visible = !n.visible;
                if self
                    .composite
                    .update(&self.world, &self.tree, &self.models, &[])
                    .is_err()
                {
                    // Shown again outside the grid (it moved while hidden): refused.
                    let n = self.tree.node_mut(node).unwrap();
                    n.visible = !n.visible;
                    return None;
                }
                Some(Undo::Hide(node))
            }
            Step::Reorder { o } => {
                let node = *self.objects.get(o)?;
                let parent = self.tree.node(node).ok()?.parent()?;
                let back = self.tree.move_node(node, parent, Some(0)).unwrap();
                self.composite
                    .update(&self.world, &self.tree, &self.models, &[node])
                    .unwrap();
                Some(Undo::Move(node, back))
            }
            Step::Remove { o } => {
                let node = *self.objects.get(o)?;
                let d = self.tree.remove(node).ok()?;
                self.composite
                    .update(&self.world, &self.tree, &self.models, &[])
                    .unwrap();
                Some(Undo::Remove(d))
            }
        }
    }

    fn undo(&mut self, u: Undo) {
        let mut also = Vec::new();
        match u {
            Undo::Model(m, inverse) => {
                let out = self
                    .models
                    .get_mut(&m)
                    .unwrap()
                    .apply(&EditOp::Restore(inverse), &table())
                    .unwrap();
                self.composite
                    .model_edited(&self.world, &self.models, m, &out.inverse)
                    .unwrap();
                return;
            }
            Undo::Place(node, p) => self.tree.node_mut(node).unwrap().placement = p,
            Undo::Hide(node) => {
                let n = self.tree.node_mut(node).unwrap();
                n.visible = !n.visible;
            }
            Undo::Move(node, (parent, index)) => {
                self.tree.move_node(node, parent, Some(index)).unwrap();
                also.push(node);
            }
            Undo::Remove(d) => self.tree.restore(d).unwrap(),
        }
        self.composite
            .update(&self.world, &self.tree, &self.models, &also)
            .unwrap();
    }
}

enum Undo {
    Model(ModelId, EditInverse),
    Place(NodeId, Placement),
    Hide(NodeId),
    Move(NodeId, (NodeId, usize)),
    Remove(crate::objects::tree::Detached),
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn the_composite_follows_every_change_and_its_undo(steps in prop::collection::vec(step(), 1..12)) {
        let mut s = Session::new(2);
        let start = s.world.read().content_hash();
        assert_matches(&s.world, &reference(&s.tree, &s.models));
        let mut undo = Vec::new();
        for st in &steps {
            if let Some(u) = s.run(st) {
                undo.push(u);
            }
            assert_matches(&s.world, &reference(&s.tree, &s.models));
        }
        // The same session with another worker count gives the same world.
        let mut other = Session::new(3);
        for st in &steps {
            other.run(st);
        }
        prop_assert_eq!(other.world.read().content_hash(), s.world.read().content_hash());
        for u in undo.into_iter().rev() {
            s.undo(u);
        }
        assert_matches(&s.world, &reference(&s.tree, &s.models));
        prop_assert_eq!(s.world.read().content_hash(), start);
    }
}

#[test]
fn objects_outside_the_grid_or_without_a_model_are_refused() {
    let mut s = Session::new(1);
    let before = s.world.read().content_hash();
    let node = s.objects[0];
    s.tree.node_mut(node).unwrap().placement = Placement::at(IVec3::new(60, 0, 0));
    let e = s
        .composite
        .update(&s.world, &s.tree, &s.models, &[])
        .unwrap_err();
    assert!(
        matches!(e, CompositeError::OutsideGrid { node: n, .. } if n == node),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("outside the [64, 32, 48] voxel grid"),
        "{e}"
    );
    assert_eq!(s.world.read().content_hash(), before, "nothing written");
    s.tree.node_mut(node).unwrap().placement = Placement::at(IVec3::new(12, 12, 12));
    let lone = s
        .tree
        .add(
            ObjectTree::ROOT,
            None,
            "lost",
            Placement::IDENTITY,
            NewNode::Object {
                model: ModelId(9),
                layer: LayerId(0),
            },
        )
        .unwrap();
    assert!(matches!(
        Composite::new(&s.tree, &s.models, GRID),
        Err(CompositeError::NoModel { node, model: ModelId(9) }) if node == lone
    ));
}

#[test]
fn an_instance_edit_shows_in_every_instance() {
    let mut s = Session::new(2);
    // Objects 0 and 2 both place model 1.
    s.run(&Step::Edit {
        m: 1,
        centre: IVec3::new(8, 4, 8),
        radius: 3.0,
        remove: true,
    });
    let view = s.world.read();
    for o in [0, 2] {
        let p = s.tree.world_placement(s.objects[o]).unwrap();
        let w = p.place(IVec3::new(8, 4, 8), IVec3::new(16, 8, 16));
        // Emptied in the model; in the world only if no later object covers it.
        let want = reference(&s.tree, &s.models).get(&w).copied();
        assert_eq!(view.voxel(w).unwrap(), want, "object {o} at {w}");
    }
    drop(view);
    assert_matches(&s.world, &reference(&s.tree, &s.models));
}
