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

    /// Bytes it holds on the heap (its name, its child list).
    fn heap_bytes(&self) -> usize {
        self.name.capacity()
            + match &self.kind {
                NodeKind::Group { children } => children.capacity() * 4,
                NodeKind::Object { .. } => 0,
            }
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
    /// A node named as a group's child is not one of its children.
    #[error("node #{} is not a child of group #{}", .node.0, .group.0)]
    NotAChild {
        /// The node.
        node: NodeId,
        /// The group.
        group: NodeId,
    },
    /// Deeper than [`MAX_DEPTH`].
    #[error("the tree would be deeper than {MAX_DEPTH} levels")]
    TooDeep,
    /// No layer has this id.
    #[error("no layer {}", .0.0)]
    NoLayer(LayerId),
    /// The layer holds objects, or is the only one.
    #[error("layer {} holds objects or is the only layer", .0.0)]
    LayerInUse(LayerId),
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

    /// Bytes it holds on the heap (the nodes and their names, child lists).
    pub fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<(NodeId, Node)>()
            + self
                .nodes
                .iter()
                .map(|(_, n)| n.heap_bytes())
                .sum::<usize>()
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
    /// The id the next added node takes: the lowest free one.
    pub fn next_id(&self) -> NodeId {
        match self.nodes.iter().position(Option::is_none) {
            Some(i) => NodeId(i as u32),
            None => NodeId(self.nodes.len() as u32),
        }
    }

    /// Bytes it holds on the heap (the nodes, their names and child lists, the layers).
    pub fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Option<Node>>()
            + self
                .nodes
                .iter()
                .flatten()
                .map(Node::heap_bytes)
                .sum::<usize>()
            + self.layers.capacity() * std::mem::size_of::<Layer>()
            + self.layers.iter().map(|l| l.name.capacity()).sum::<usize>()
    }

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

    /// Removes the last layer, which no object may be on (the inverse of `add_layer`).
    pub fn remove_last_layer(&mut self) -> Result<Layer, TreeError> {
        let last = LayerId((self.layers.len() - 1) as u8);
        let used = self
            .nodes
            .iter()
            .flatten()
            .any(|n| matches!(n.kind, NodeKind::Object { layer, .. } if layer == last));
        if self.layers.len() == 1 || used {
            return Err(TreeError::LayerInUse(last));
        }
        Ok(self.layers.pop().expect("more than one layer"))
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
        let id = self.next_id();
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
mod tests;
