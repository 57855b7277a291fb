//! The object tree: drawing order, placements composed, hidden nodes and layers, moves,
//! removals and their exact inverses, ids, depth.
use super::*;
use crate::objects::orient::{Axis, Orientation};
use glam::IVec3;

fn object(model: u32) -> NewNode {
    NewNode::Object {
        model: ModelId(model),
        layer: LayerId(0),
    }
}

fn group() -> NewNode {
    NewNode::Group
}

/// A house (wall, roof, door) and two trees sharing one model.
fn village() -> (ObjectTree, [NodeId; 6]) {
    let mut t = ObjectTree::new();
    let root = ObjectTree::ROOT;
    let house = t
        .add(
            root,
            None,
            "house",
            Placement::at(IVec3::new(10, 0, 0)),
            group(),
        )
        .unwrap();
    let wall = t
        .add(house, None, "wall", Placement::IDENTITY, object(0))
        .unwrap();
    let roof = t
        .add(house, None, "roof", Placement::at(IVec3::Y * 8), object(1))
        .unwrap();
    let door = t
        .add(house, Some(0), "door", Placement::IDENTITY, object(2))
        .unwrap();
    let tree_a = t
        .add(root, None, "tree", Placement::at(IVec3::X * 30), object(3))
        .unwrap();
    let tree_b = t
        .add(root, None, "tree", Placement::at(IVec3::X * 40), object(3))
        .unwrap();
    (t, [house, wall, roof, door, tree_a, tree_b])
}

#[test]
fn drawing_order_is_pre_order_and_placements_compose() {
    let (t, [house, wall, roof, door, a, b]) = village();
    let drawn: Vec<_> = t.drawn().iter().map(|d| d.node).collect();
    assert_eq!(drawn, [door, wall, roof, a, b]);
    assert_eq!(t.world_placement(roof).unwrap().t, IVec3::new(10, 8, 0));
    assert_eq!(t.instances(ModelId(3)), [a, b]);
    assert_eq!(t.subtree(house).unwrap(), [house, door, wall, roof]);
    assert_eq!(t.len(), 7);
}

#[test]
fn hidden_nodes_and_layers_hide_what_they_hold() {
    let (mut t, [house, wall, roof, door, a, b]) = village();
    t.node_mut(house).unwrap().visible = false;
    assert_eq!(t.drawn().iter().map(|d| d.node).collect::<Vec<_>>(), [a, b]);
    t.node_mut(house).unwrap().visible = true;
    let hidden = t
        .add_layer(Layer {
            name: "scaffolding".into(),
            visible: false,
        })
        .unwrap();
    if let NodeKind::Object { layer, .. } = &mut t.node_mut(wall).unwrap().kind {
        *layer = hidden;
    }
    assert_eq!(
        t.drawn().iter().map(|d| d.node).collect::<Vec<_>>(),
        [door, roof, a, b]
    );
    assert_eq!(
        t.add(
            ObjectTree::ROOT,
            None,
            "x",
            Placement::IDENTITY,
            NewNode::Object {
                model: ModelId(0),
                layer: LayerId(9)
            }
        ),
        Err(TreeError::NoLayer(LayerId(9)))
    );
}

#[test]
fn a_rotated_group_turns_its_children_about_its_own_origin() {
    let mut t = ObjectTree::new();
    let g = t
        .add(
            ObjectTree::ROOT,
            None,
            "g",
            Placement {
                rot: Orientation::quarter_turn(Axis::Y, 1),
                t: IVec3::new(100, 0, 100),
            },
            group(),
        )
        .unwrap();
    let o = t
        .add(g, None, "o", Placement::at(IVec3::X * 5), object(0))
        .unwrap();
    let p = t.world_placement(o).unwrap();
    assert_eq!(p.t, IVec3::new(100, 0, 95), "+x turned to −z");
    assert_eq!(p.rot, Orientation::quarter_turn(Axis::Y, 1));
    assert_eq!(t.drawn()[0].placement, p);
}

#[test]
fn moves_are_refused_into_their_own_subtree_and_undo_exactly() {
    let (mut t, [house, wall, roof, door, a, _]) = village();
    let before = t.clone();
    assert_eq!(
        t.move_node(house, wall, None),
        Err(TreeError::NotAGroup(wall))
    );
    let inner = t
        .add(house, None, "inner", Placement::IDENTITY, group())
        .unwrap();
    let with_inner = t.clone();
    assert_eq!(
        t.move_node(house, inner, None),
        Err(TreeError::IntoItself {
            node: house,
            parent: inner
        })
    );
    assert_eq!(
        t.move_node(ObjectTree::ROOT, house, None),
        Err(TreeError::Root)
    );
    assert_eq!(t, with_inner, "refusals change nothing");
    let (p, i) = t.move_node(a, house, Some(1)).unwrap();
    assert_eq!((p, i), (ObjectTree::ROOT, 1));
    assert_eq!(
        t.node(house).unwrap().children(),
        [door, a, wall, roof, inner]
    );
    t.move_node(a, p, Some(i)).unwrap();
    assert_eq!(t, with_inner);
    // Within one group: the index counts after the node left.
    let (p, i) = t.move_node(door, house, None).unwrap();
    assert_eq!(t.node(house).unwrap().children(), [wall, roof, inner, door]);
    t.move_node(door, p, Some(i)).unwrap();
    assert_eq!(t, with_inner);
    let d = t.remove(inner).unwrap();
    t.restore(d.clone()).unwrap();
    t.remove(inner).unwrap();
    assert_eq!(t, before);
}

#[test]
fn remove_and_restore_keep_ids_and_new_nodes_take_the_lowest_free_id() {
    let (mut t, [house, wall, roof, door, a, b]) = village();
    let before = t.clone();
    let d = t.remove(house).unwrap();
    assert_eq!(t.len(), 3);
    for n in [house, wall, roof, door] {
        assert_eq!(t.node(n), Err(TreeError::NoNode(n)));
    }
    assert_eq!(t.drawn().iter().map(|d| d.node).collect::<Vec<_>>(), [a, b]);
    t.restore(d.clone()).unwrap();
    assert_eq!(t, before);
    // Undo of an add, then its redo, gives the same id.
    let d = t.remove(door).unwrap();
    let again = t
        .add(house, Some(0), "door", Placement::IDENTITY, object(2))
        .unwrap();
    assert_eq!(again, door);
    assert_eq!(t.restore(d), Err(TreeError::Taken(door)));
    assert_eq!(t, before);
    assert_eq!(t.remove(ObjectTree::ROOT), Err(TreeError::Root));
}

#[test]
fn the_tree_stays_within_its_depth() {
    let mut t = ObjectTree::new();
    let mut at = ObjectTree::ROOT;
    for _ in 0..MAX_DEPTH {
        at = t.add(at, None, "g", Placement::IDENTITY, group()).unwrap();
    }
    assert_eq!(
        t.add(at, None, "too deep", Placement::IDENTITY, object(0)),
        Err(TreeError::TooDeep)
    );
    let side = t
        .add(ObjectTree::ROOT, None, "side", Placement::IDENTITY, group())
        .unwrap();
    let first = t.node(ObjectTree::ROOT).unwrap().children()[0];
    assert_eq!(t.move_node(first, side, None), Err(TreeError::TooDeep));
}
