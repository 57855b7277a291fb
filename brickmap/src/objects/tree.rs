//! The object tree: groups and objects, each with a name, a visible and a locked flag and a
//! [`Placement`]; an object places a model (several objects may place the same one: instances)
//! and belongs to one layer (named, hideable, as MagicaVoxel's).
//!
//! Identity: a node keeps its [`NodeId`] for its life; a new node takes the lowest free id, and
//! [`ObjectTree::restore`] puts a removed subtree back under its old ids, so a command's undo
//! and redo give the same ids and a recorded script's ids stay valid.
//!
//! Order: the tree's pre-order (a group, then its children in order) is the drawing order;
//! where visible objects overlap, the voxel of the object drawn later shows
//! ([`ObjectTree::drawn`]). A hidden node hides its subtree; a hidden layer hides its objects.

use super::orient::Placement;

/// A node of the tree; the root is `NodeId(0)`.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub struct NodeId(pub u32);

/// A model (a voxel grid of its own size) that objects place.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub struct ModelId(pub u32);

/// A layer.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub struct LayerId(pub u8);

/// The deepest a node may sit below the root (MagicaVoxel files are read to the same depth).
pub const MAX_DEPTH: usize = 64;

/// What a node is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NodeKind {
    /// A group and its children, in drawing order.
    Group {
        /// The children.
        children: Vec<NodeId>,
    },
    /// An object: a model placed.
    Object {
        /// The model.
        model: ModelId,
        /// Its layer.
        layer: LayerId,
    },
}

/// What [`ObjectTree::add`] adds: an empty group, or an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NewNode {
    /// A group without children (they join by moving).
    Group,
    /// An object placing `model`, in `layer`.
    Object {
        /// The model.
        model: ModelId,
        /// Its layer.
        layer: LayerId,
    },
}

/// A group or an object.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Node {
    /// Shown in the outliner.
    pub name: String,
    /// Hidden nodes and their subtrees are not drawn.
    pub visible: bool,
    /// Locked nodes refuse selection and edits (the editor's rule).
    pub locked: bool,
    /// Relative to the parent.
    pub placement: Placement,
    /// Group or object.
    pub kind: NodeKind,
    parent: Option<NodeId>,
}

impl Node {
    /// The parent (`None` for the root).
    pub fn parent(&self) -> Option<NodeId> {
        self.parent
    }

    /// The children (none for an object).
    pub fn children(&self) -> &[NodeId] {
        match &self.kind {
            NodeKind::Group { children } => children,
            NodeKind::Object { .. } => &[],
        }
    }
}

/// A layer: objects belong to one.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Layer {
    /// Shown in the outliner.
    pub name: String,
    /// A hidden layer hides its objects.
    pub visible: bool,
}

/// Why a tree operation was refused; the tree is unchanged.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TreeError {
    /// No node has this id.
    #[error("no node #{}", .0.0)]
    NoNode(NodeId),
    /// A node that must be a group is an object.
    #[error("node #{} is an object, not a group", .0.0)]
    NotAGroup(NodeId),
    /// The root cannot be moved or removed.
    #[error("the root group cannot be moved or removed")]
    Root,
    /// A group cannot go inside itself.
    #[error("node #{} cannot go inside its own subtree (#{})", .node.0, .parent.0)]
    IntoItself {
        /// The node moved.
        node: NodeId,
        /// The group asked for, inside it.
        parent: NodeId,
    },
    /// A position past the end of a group's children.
    #[error("group #{} has {len} children; position {index} is past the end", .group.0)]
    Index {
        /// The group.
        group: NodeId,
        /// The position asked for.
        index: usize,
        /// Its children.
        len: usize,
    },
    /// Deeper than [`MAX_DEPTH`].
    #[error("the tree would be deeper than {MAX_DEPTH} levels")]
    TooDeep,
    /// No layer has this id.
    #[error("no layer {}", .0.0)]
    NoLayer(LayerId),
    /// 256 layers exist already.
    #[error("a scene has at most 256 layers")]
    TooManyLayers,
    /// A restored node's id is taken (the history is out of order).
    #[error("node #{} exists already", .0.0)]
    Taken(NodeId),
}

/// A removed subtree, with what [`ObjectTree::restore`] needs to put it back exactly.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Detached {
    parent: NodeId,
    index: usize,
    /// The subtree's nodes with their ids, its top first.
    nodes: Vec<(NodeId, Node)>,
}

impl Detached {
    /// The top of the removed subtree.
    pub fn top(&self) -> NodeId {
        self.nodes[0].0
    }
}

/// A visible object as drawn: its world placement, in drawing order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Drawn {
    /// The object.
    pub node: NodeId,
    /// Its model.
    pub model: ModelId,
    /// Composed from the root down.
    pub placement: Placement,
}

/// Groups and objects; see the module doc.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjectTree {
    nodes: Vec<Option<Node>>,
    layers: Vec<Layer>,
}

impl Default for ObjectTree {
    fn default() -> Self {
        Self::new()
    }
}

impl ObjectTree {
    /// The root group alone, with one visible layer.
    pub fn new() -> Self {
        Self {
            nodes: vec![Some(Node {
                name: "scene".into(),
                visible: true,
                locked: false,
                placement: Placement::IDENTITY,
                kind: NodeKind::Group {
                    children: Vec::new(),
                },
                parent: None,
            })],
            layers: vec![Layer {
                name: "layer 0".into(),
                visible: true,
            }],
        }
    }

    /// The root group.
    pub const ROOT: NodeId = NodeId(0);

    /// A node.
    pub fn node(&self, id: NodeId) -> Result<&Node, TreeError> {
        self.nodes
            .get(id.0 as usize)
            .and_then(Option::as_ref)
            .ok_or(TreeError::NoNode(id))
    }

    /// A node to change its name, flags or placement (use the other methods to move it).
    pub fn node_mut(&mut self, id: NodeId) -> Result<&mut Node, TreeError> {
        self.nodes
            .get_mut(id.0 as usize)
            .and_then(Option::as_mut)
            .ok_or(TreeError::NoNode(id))
    }

    /// How many nodes, the root included.
    pub fn len(&self) -> usize {
        self.nodes.iter().flatten().count()
    }

    /// Never: the root is always there.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The layers.
    pub fn layers(&self) -> &[Layer] {
        &self.layers
    }

    /// A layer to rename or hide.
    pub fn layer_mut(&mut self, id: LayerId) -> Result<&mut Layer, TreeError> {
        self.layers
            .get_mut(id.0 as usize)
            .ok_or(TreeError::NoLayer(id))
    }

    /// Adds a layer at the end.
    pub fn add_layer(&mut self, layer: Layer) -> Result<LayerId, TreeError> {
        if self.layers.len() >= 256 {
            return Err(TreeError::TooManyLayers);
        }
        self.layers.push(layer);
        Ok(LayerId((self.layers.len() - 1) as u8))
    }

    /// Adds a node under `parent` at `index` (the end when `None`); it takes the lowest free
    /// id. An object's layer must exist.
    pub fn add(
        &mut self,
        parent: NodeId,
        index: Option<usize>,
        name: impl Into<String>,
        placement: Placement,
        new: NewNode,
    ) -> Result<NodeId, TreeError> {
        let kind = match new {
            NewNode::Group => NodeKind::Group {
                children: Vec::new(),
            },
            NewNode::Object { model, layer } => {
                if layer.0 as usize >= self.layers.len() {
                    return Err(TreeError::NoLayer(layer));
                }
                NodeKind::Object { model, layer }
            }
        };
        let index = self.insertion(parent, index)?;
        if self.depth(parent)? + 1 > MAX_DEPTH {
            return Err(TreeError::TooDeep);
        }
        let id = match self.nodes.iter().position(Option::is_none) {
            Some(i) => NodeId(i as u32),
            None => NodeId(self.nodes.len() as u32),
        };
        let node = Node {
            name: name.into(),
            visible: true,
            locked: false,
            placement,
            kind,
            parent: Some(parent),
        };
        if id.0 as usize == self.nodes.len() {
            self.nodes.push(Some(node));
        } else {
            self.nodes[id.0 as usize] = Some(node);
        }
        self.children_mut(parent)?.insert(index, id);
        Ok(id)
    }

    /// Moves a node (with its subtree) under `parent` at `index` (the end when `None`;
    /// counted after the node left its old place). Returns its old parent and index, which
    /// move it back.
    pub fn move_node(
        &mut self,
        id: NodeId,
        parent: NodeId,
        index: Option<usize>,
    ) -> Result<(NodeId, usize), TreeError> {
        let old_parent = self.node(id)?.parent.ok_or(TreeError::Root)?;
        if !matches!(self.node(parent)?.kind, NodeKind::Group { .. }) {
            return Err(TreeError::NotAGroup(parent));
        }
        if self.ancestors(parent)?.contains(&id) || parent == id {
            return Err(TreeError::IntoItself { node: id, parent });
        }
        if self.depth(parent)? + 1 + self.height(id)? > MAX_DEPTH {
            return Err(TreeError::TooDeep);
        }
        let old_index = self.index_in_parent(id)?;
        let len = self.node(parent)?.children().len() - usize::from(parent == old_parent);
        let index = position(parent, index, len)?;
        self.children_mut(old_parent)?.remove(old_index);
        self.children_mut(parent)?.insert(index, id);
        self.node_mut(id)?.parent = Some(parent);
        Ok((old_parent, old_index))
    }

    /// Removes a node and its subtree; [`ObjectTree::restore`] puts it back.
    pub fn remove(&mut self, id: NodeId) -> Result<Detached, TreeError> {
        let parent = self.node(id)?.parent.ok_or(TreeError::Root)?;
        let index = self.index_in_parent(id)?;
        let order = self.subtree(id)?;
        self.children_mut(parent)?.remove(index);
        let nodes = order
            .into_iter()
            .map(|n| (n, self.nodes[n.0 as usize].take().expect("in the subtree")))
            .collect();
        // Trailing free slots go, so a tree equals itself after a remove and its restore.
        while self.nodes.last().is_some_and(Option::is_none) {
            self.nodes.pop();
        }
        Ok(Detached {
            parent,
            index,
            nodes,
        })
    }

    /// Puts a removed subtree back where it was, under its old ids.
    pub fn restore(&mut self, d: Detached) -> Result<(), TreeError> {
        let len = self.node(d.parent)?.children().len();
        if d.index > len {
            return Err(TreeError::Index {
                group: d.parent,
                index: d.index,
                len,
            });
        }
        if let Some((id, _)) = d
            .nodes
            .iter()
            .find(|(id, _)| self.nodes.get(id.0 as usize).is_some_and(Option::is_some))
        {
            return Err(TreeError::Taken(*id));
        }
        let top = d.top();
        self.children_mut(d.parent)?.insert(d.index, top);
        for (id, node) in d.nodes {
            let i = id.0 as usize;
            if i >= self.nodes.len() {
                self.nodes.resize(i + 1, None);
            }
            self.nodes[i] = Some(node);
        }
        Ok(())
    }

    /// The placement of a node in the world: its ancestors' composed with its own.
    pub fn world_placement(&self, id: NodeId) -> Result<Placement, TreeError> {
        let mut p = self.node(id)?.placement;
        let mut at = self.node(id)?.parent;
        while let Some(a) = at {
            let n = self.node(a)?;
            p = n.placement.then(&p);
            at = n.parent;
        }
        Ok(p)
    }

    /// The visible objects in drawing order (pre-order; a later one wins where they overlap).
    pub fn drawn(&self) -> Vec<Drawn> {
        let mut out = Vec::new();
        let mut stack = vec![(Self::ROOT, Placement::IDENTITY)];
        while let Some((id, above)) = stack.pop() {
            let Ok(n) = self.node(id) else { continue };
            if !n.visible {
                continue;
            }
            let here = above.then(&n.placement);
            match &n.kind {
                NodeKind::Group { children } => {
                    stack.extend(children.iter().rev().map(|c| (*c, here)));
                }
                NodeKind::Object { model, layer } => {
                    if self.layers.get(layer.0 as usize).is_some_and(|l| l.visible) {
                        out.push(Drawn {
                            node: id,
                            model: *model,
                            placement: here,
                        });
                    }
                }
            }
        }
        out
    }

    /// Every object that places `model` (visible or not), in id order.
    pub fn instances(&self, model: ModelId) -> Vec<NodeId> {
        self.nodes
            .iter()
            .enumerate()
            .filter_map(|(i, n)| match n.as_ref()?.kind {
                NodeKind::Object { model: m, .. } if m == model => Some(NodeId(i as u32)),
                _ => None,
            })
            .collect()
    }

    /// A node's subtree in pre-order, itself first.
    pub fn subtree(&self, id: NodeId) -> Result<Vec<NodeId>, TreeError> {
        let mut out = Vec::new();
        let mut stack = vec![id];
        while let Some(n) = stack.pop() {
            out.push(n);
            stack.extend(self.node(n)?.children().iter().rev());
        }
        Ok(out)
    }

    fn ancestors(&self, id: NodeId) -> Result<Vec<NodeId>, TreeError> {
        let mut out = Vec::new();
        let mut at = self.node(id)?.parent;
        while let Some(a) = at {
            out.push(a);
            at = self.node(a)?.parent;
        }
        Ok(out)
    }

    fn depth(&self, id: NodeId) -> Result<usize, TreeError> {
        Ok(self.ancestors(id)?.len())
    }

    /// Levels from a node down to its deepest descendant (0 for a leaf).
    fn height(&self, id: NodeId) -> Result<usize, TreeError> {
        let mut most = 0;
        for c in self.node(id)?.children() {
            most = most.max(1 + self.height(*c)?);
        }
        Ok(most)
    }

    fn index_in_parent(&self, id: NodeId) -> Result<usize, TreeError> {
        let parent = self.node(id)?.parent.ok_or(TreeError::Root)?;
        Ok(self
            .node(parent)?
            .children()
            .iter()
            .position(|c| *c == id)
            .expect("a node is among its parent's children"))
    }

    fn insertion(&self, parent: NodeId, index: Option<usize>) -> Result<usize, TreeError> {
        let n = self.node(parent)?;
        if !matches!(n.kind, NodeKind::Group { .. }) {
            return Err(TreeError::NotAGroup(parent));
        }
        position(parent, index, n.children().len())
    }

    fn children_mut(&mut self, id: NodeId) -> Result<&mut Vec<NodeId>, TreeError> {
        match &mut self.node_mut(id)?.kind {
            NodeKind::Group { children } => Ok(children),
            NodeKind::Object { .. } => Err(TreeError::NotAGroup(id)),
        }
    }
}

/// A position among a group's `len` children (the end when `None`).
fn position(group: NodeId, index: Option<usize>, len: usize) -> Result<usize, TreeError> {
    let index = index.unwrap_or(len);
    if index > len {
        return Err(TreeError::Index { group, index, len });
    }
    Ok(index)
}

#[cfg(test)]
mod tests {
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
}
