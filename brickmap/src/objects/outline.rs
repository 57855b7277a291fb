//! The tree as text: a line per node in drawing order, indented two spaces a level — what
//! `voxbrick info` prints, and what tests compare before and after a round trip (they pass
//! the description of a model they compare by).

use super::{Model, ModelId, NodeKind, ObjectTree, Objects};

impl Objects {
    /// A line per node below the root, parents before their children in drawing order:
    /// `#id ` (with `ids`: what scripts name nodes by; a file's round trip may number them
    /// anew) and `"name"`, then `group of N` or the object's model as `model` describes it and its
    /// layer, ` hidden` / ` locked` where so, and its world placement (`at [x, y, z]`, and
    /// MagicaVoxel's rotation byte `_r` when turned or mirrored).
    pub fn outline(&self, ids: bool, model: impl Fn(ModelId, &Model) -> String) -> Vec<String> {
        let tree = self.tree();
        let mut out = Vec::with_capacity(tree.len());
        let mut stack = vec![(ObjectTree::ROOT, 0usize)];
        while let Some((id, depth)) = stack.pop() {
            let Ok(n) = tree.node(id) else { continue };
            stack.extend(n.children().iter().rev().map(|c| (*c, depth + 1)));
            if id == ObjectTree::ROOT {
                continue;
            }
            let what = match n.kind {
                NodeKind::Group { .. } => format!("group of {}", n.children().len()),
                NodeKind::Object { model: m, layer } => match self.model(m) {
                    Some(data) => format!("{} on layer {}", model(m, data), layer.0),
                    None => format!("model {} (missing) on layer {}", m.0, layer.0),
                },
            };
            let at = tree.world_placement(id).unwrap_or(n.placement);
            let turned = if at.rot == Default::default() {
                String::new()
            } else {
                format!(" _r {}", at.rot.to_vox_byte())
            };
            out.push(format!(
                "{:indent$}{}{:?} {what}{}{} at [{}, {}, {}]{turned}",
                "",
                if ids {
                    format!("#{} ", id.0)
                } else {
                    String::new()
                },
                n.name,
                if n.visible { "" } else { " hidden" },
                if n.locked { " locked" } else { "" },
                at.t.x,
                at.t.y,
                at.t.z,
                indent = 2 * (depth - 1),
            ));
        }
        out
    }
}
