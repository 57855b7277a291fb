//! The Objects window (the outliner): the tree in drawing order with each node's visibility
//! and lock toggles, its name (click: pick it, and make it the one brushes edit if an
//! object; Ctrl + click: add to or take from the picked nodes; double-click: edit an
//! object's voxels, rename a group; drag: move the picked nodes before, after or into the
//! row let go on, each staying where it is in the world; right-click: rename, edit, put on a
//! layer), and for an object its model's size, voxel count and how many objects share the
//! model; the layers with their visibility (and a new one); and the arrange commands on the
//! picked nodes. Only the rows in view are laid
//! out, so a tree of 10,000 objects scrolls as one of ten. Every change is an
//! [`ObjectCommand`]: undoable, in the History, recorded.

use super::editing::window;
use super::intent::UiEvent;
use crate::editor::Document;
use crate::editor::objects::ObjectCommand;
use brickmap::objects::{Axis, LayerId, NodeId, NodeKind, ObjectTree, Objects};
use glam::IVec3;

/// What the window keeps between frames.
pub struct OutlinerState {
    /// Shown.
    pub open: bool,
    /// The picked nodes (what the arrange buttons act on), first picked first.
    pub picked: Vec<NodeId>,
    /// The node being renamed and the name typed so far.
    pub renaming: Option<(NodeId, String)>,
    /// How far the move buttons move, in voxels.
    pub step: i32,
    /// The size of a new object.
    pub new_size: [i32; 3],
}

impl Default for OutlinerState {
    /// Closed (View → Objects opens it), nothing picked, moves of one voxel.
    fn default() -> Self {
        Self {
            open: false,
            picked: Vec::new(),
            renaming: None,
            step: 1,
            new_size: [32, 32, 32],
        }
    }
}

/// One row: a node and its depth below the root.
fn rows(tree: &ObjectTree) -> Vec<(NodeId, usize)> {
    let mut out = Vec::with_capacity(tree.len());
    let mut stack = vec![(ObjectTree::ROOT, 0usize)];
    while let Some((id, depth)) = stack.pop() {
        if id != ObjectTree::ROOT {
            out.push((id, depth - 1));
        }
        if let Ok(n) = tree.node(id) {
            for c in n.children().iter().rev() {
                stack.push((*c, depth + 1));
            }
        }
    }
    out
}

/// Draws the window (when open).
pub fn draw(
    ctx: &egui::Context,
    area: egui::Rect,
    state: &mut OutlinerState,
    doc: &Document,
    out: &mut Vec<UiEvent>,
) {
    if !state.open {
        return;
    }
    let mut open = true;
    window(area, "Objects").open(&mut open).show(ctx, |ui| {
        let objects = doc.scene.objects();
        state.picked.retain(|n| objects.tree().node(*n).is_ok());
        new_object(ui, state, out);
        commands(ui, state, &objects, out);
        ui.separator();
        layers(ui, &objects, out);
        ui.separator();
        tree(ui, state, &objects, doc.scene.active(), out);
    });
    state.open = open;
}

fn send(out: &mut Vec<UiEvent>, c: ObjectCommand) {
    out.push(UiEvent::Objects(c));
}

/// A new empty object of the size asked (the editor puts it under the view's pivot).
fn new_object(ui: &mut egui::Ui, state: &mut OutlinerState, out: &mut Vec<UiEvent>) {
    ui.horizontal(|ui| {
        let new = ui
            .button("New object")
            .on_hover_text("an empty object of this size, under the view's pivot");
        for v in &mut state.new_size {
            ui.add(egui::DragValue::new(v).range(1..=256));
        }
        if new.clicked() {
            out.push(UiEvent::NewObject(IVec3::from_array(state.new_size)));
        }
    });
}

/// The arrange buttons, on the picked nodes.
fn commands(
    ui: &mut egui::Ui,
    state: &mut OutlinerState,
    objects: &Objects,
    out: &mut Vec<UiEvent>,
) {
    let first = state.picked.first().copied();
    let is_object = |n: NodeId| {
        objects
            .tree()
            .node(n)
            .is_ok_and(|n| matches!(n.kind, NodeKind::Object { .. }))
    };
    let object = first.filter(|n| is_object(*n));
    let group = first.filter(|n| !is_object(*n) && *n != ObjectTree::ROOT);
    ui.label(match first {
        None => "Pick a node below (Ctrl + click picks several).".to_string(),
        Some(n) if state.picked.len() == 1 => format!(
            "Picked: {}",
            objects.tree().node(n).map_or("?", |n| n.name.as_str())
        ),
        Some(_) => format!("Picked: {} nodes", state.picked.len()),
    });
    ui.horizontal_wrapped(|ui| {
        let step = state.step;
        if let Some(n) = object {
            if ui.button("Duplicate").clicked() {
                send(
                    out,
                    ObjectCommand::Duplicate {
                        node: n,
                        offset: IVec3::ZERO,
                    },
                );
            }
            if ui.button("Instance").clicked() {
                send(
                    out,
                    ObjectCommand::Instance {
                        node: n,
                        offset: IVec3::ZERO,
                    },
                );
            }
            if ui.button("Make unique").clicked() {
                send(out, ObjectCommand::MakeUnique(n));
            }
        }
        if let Some(n) = group
            && ui.button("Ungroup").clicked()
        {
            send(out, ObjectCommand::Ungroup(n));
        }
        if !state.picked.is_empty() && ui.button("Group").clicked() {
            send(
                out,
                ObjectCommand::Group {
                    nodes: state.picked.clone(),
                    name: "group".into(),
                },
            );
        }
        if state.picked.len() > 1
            && state.picked.iter().all(|n| is_object(*n))
            && ui.button("Merge").clicked()
        {
            send(
                out,
                ObjectCommand::Merge {
                    nodes: state.picked.clone(),
                    name: "merged".into(),
                },
            );
            state.picked.clear();
        }
        if first.is_some() && ui.button("Delete").clicked() {
            send(out, ObjectCommand::Delete(state.picked.clone()));
            state.picked.clear();
        }
        if first.is_some() {
            ui.end_row();
            for (axis, name) in [(Axis::X, "X"), (Axis::Y, "Y"), (Axis::Z, "Z")] {
                if ui.button(format!("Turn {name}")).clicked() {
                    send(
                        out,
                        ObjectCommand::Turn {
                            nodes: state.picked.clone(),
                            axis,
                            quarters: 1,
                        },
                    );
                }
            }
            for (axis, name) in [(Axis::X, "X"), (Axis::Y, "Y"), (Axis::Z, "Z")] {
                if ui.button(format!("Flip {name}")).clicked() {
                    send(
                        out,
                        ObjectCommand::Flip {
                            nodes: state.picked.clone(),
                            axis,
                        },
                    );
                }
            }
            ui.end_row();
            for (by, name) in [
                (IVec3::NEG_X, "−X"),
                (IVec3::X, "+X"),
                (IVec3::NEG_Y, "−Y"),
                (IVec3::Y, "+Y"),
                (IVec3::NEG_Z, "−Z"),
                (IVec3::Z, "+Z"),
            ] {
                if ui.button(name).clicked() {
                    send(
                        out,
                        ObjectCommand::Translate {
                            nodes: state.picked.clone(),
                            by: by * step,
                        },
                    );
                }
            }
            ui.add(
                egui::DragValue::new(&mut state.step)
                    .range(1..=256)
                    .suffix(" voxels"),
            );
        }
    });
}

fn layers(ui: &mut egui::Ui, objects: &Objects, out: &mut Vec<UiEvent>) {
    ui.horizontal_wrapped(|ui| {
        ui.label("Layers:");
        for (i, l) in objects.tree().layers().iter().enumerate() {
            let mut visible = l.visible;
            if ui.checkbox(&mut visible, &l.name).changed() {
                send(
                    out,
                    ObjectCommand::ShowLayer {
                        layer: LayerId(i as u8),
                        visible,
                    },
                );
            }
        }
        let count = objects.tree().layers().len();
        if count < 256 && ui.button("+").on_hover_text("a new layer").clicked() {
            send(out, ObjectCommand::AddLayer(format!("layer {count}")));
        }
    });
}

fn tree(
    ui: &mut egui::Ui,
    state: &mut OutlinerState,
    objects: &Objects,
    active: Option<NodeId>,
    out: &mut Vec<UiEvent>,
) {
    let tree = objects.tree();
    let rows = rows(tree);
    ui.label(format!("{} nodes", rows.len()));
    let height = ui.spacing().interact_size.y + 2.0;
    egui::ScrollArea::vertical()
        .max_height(360.0)
        .auto_shrink([false, true])
        .show_rows(ui, height, rows.len(), |ui, range| {
            for &(id, depth) in &rows[range] {
                let Ok(n) = tree.node(id) else { continue };
                let row = ui.horizontal(|ui| {
                    ui.add_space(depth as f32 * 14.0);
                    let mut visible = n.visible;
                    if ui
                        .checkbox(&mut visible, "")
                        .on_hover_text("shown")
                        .changed()
                    {
                        send(out, ObjectCommand::Show { node: id, visible });
                    }
                    let lock = if n.locked { "🔒" } else { "🔓" };
                    if ui
                        .selectable_label(n.locked, lock)
                        .on_hover_text("locked: refuses edits and moves")
                        .clicked()
                    {
                        send(
                            out,
                            ObjectCommand::Lock {
                                node: id,
                                locked: !n.locked,
                            },
                        );
                    }
                    if let Some((node, name)) = &mut state.renaming
                        && *node == id
                    {
                        let edit = ui.text_edit_singleline(name);
                        if edit.lost_focus() {
                            if ui.input(|i| i.key_pressed(egui::Key::Enter)) && *name != n.name {
                                send(
                                    out,
                                    ObjectCommand::Rename {
                                        node: id,
                                        name: name.clone(),
                                    },
                                );
                            }
                            state.renaming = None;
                        } else {
                            edit.request_focus();
                        }
                        return;
                    }
                    let object = matches!(n.kind, NodeKind::Object { .. });
                    let mut text = egui::RichText::new(&n.name);
                    if active == Some(id) {
                        text = text.strong();
                    }
                    if !object {
                        text = text.italics();
                    }
                    let picked = state.picked.contains(&id);
                    let label = ui
                        .selectable_label(picked, text)
                        .interact(egui::Sense::drag());
                    // A drag takes the picked nodes when it starts on one of them.
                    label.dnd_set_drag_payload(if picked {
                        state.picked.clone()
                    } else {
                        vec![id]
                    });
                    if label.double_clicked() {
                        if object {
                            out.push(UiEvent::EditObject(id));
                        } else {
                            state.renaming = Some((id, n.name.clone()));
                        }
                    } else if label.clicked() {
                        if ui.input(|i| i.modifiers.command) {
                            if picked {
                                state.picked.retain(|p| *p != id);
                            } else {
                                state.picked.push(id);
                            }
                        } else {
                            state.picked = vec![id];
                            if object && active != Some(id) {
                                send(out, ObjectCommand::Activate(Some(id)));
                            }
                        }
                    }
                    label.context_menu(|ui| {
                        if ui.button("Rename").clicked() {
                            state.renaming = Some((id, n.name.clone()));
                            ui.close();
                        }
                        if object && ui.button("Edit its voxels").clicked() {
                            out.push(UiEvent::EditObject(id));
                            ui.close();
                        }
                        ui.menu_button("Put on layer", |ui| {
                            let nodes = if picked {
                                state.picked.clone()
                            } else {
                                vec![id]
                            };
                            for (i, l) in tree.layers().iter().enumerate() {
                                if ui.button(&l.name).clicked() {
                                    send(
                                        out,
                                        ObjectCommand::SetLayer {
                                            nodes: nodes.clone(),
                                            layer: LayerId(i as u8),
                                        },
                                    );
                                    ui.close();
                                }
                            }
                        });
                    });
                    if let NodeKind::Object { model, .. } = n.kind
                        && let Some(m) = objects.model(model)
                    {
                        let s = m.size();
                        let shared = tree.instances(model).len();
                        ui.weak(format!(
                            "{}×{}×{}, {} voxels{}",
                            s.x,
                            s.y,
                            s.z,
                            m.solid_count(),
                            if shared > 1 {
                                format!(", shared by {shared}")
                            } else {
                                String::new()
                            }
                        ));
                    }
                });
                drop_on(ui, &row.response, tree, id, out);
            }
        });
    ui.weak(
        "Bold: the object brushes edit. Double-click an object to edit it, a group to rename \
         it; drag names to reorder or regroup; right-click for more.",
    );
}

/// Where nodes dropped on a row go: before it (its upper part), after it (its lower part),
/// or into it (the middle of a group's row).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Drop {
    Before,
    After,
    Into,
}

/// Which part of a row of height `h` a pointer `y` below its top is over.
fn drop_at(y: f32, h: f32, group: bool) -> Drop {
    let f = y / h.max(1.0);
    match (group, f) {
        (true, f) if (0.25..0.75).contains(&f) => Drop::Into,
        (_, f) if f < 0.5 => Drop::Before,
        _ => Drop::After,
    }
}

/// The reparent a drop on `id`'s row asks for: the group and the child to go before.
fn drop_target(tree: &ObjectTree, id: NodeId, drop: Drop) -> Option<(NodeId, Option<NodeId>)> {
    let n = tree.node(id).ok()?;
    if drop == Drop::Into {
        return Some((id, n.children().first().copied()));
    }
    let parent = n.parent()?;
    let siblings = tree.node(parent).ok()?.children();
    let at = siblings.iter().position(|c| *c == id)?;
    Some(match drop {
        Drop::Before => (parent, Some(id)),
        _ => (parent, siblings.get(at + 1).copied()),
    })
}

/// A row as a drop target of dragged nodes: a line where they would go (a frame round a
/// group they would go into), and the move when they are let go.
fn drop_on(
    ui: &egui::Ui,
    row: &egui::Response,
    tree: &ObjectTree,
    id: NodeId,
    out: &mut Vec<UiEvent>,
) {
    let Some(dragged) = row.dnd_hover_payload::<Vec<NodeId>>() else {
        return;
    };
    let Some(pointer) = ui.input(|i| i.pointer.interact_pos()) else {
        return;
    };
    let group = tree
        .node(id)
        .is_ok_and(|n| matches!(n.kind, NodeKind::Group { .. }));
    let rect = row.rect;
    let drop = drop_at(pointer.y - rect.top(), rect.height(), group);
    let stroke = ui.visuals().selection.stroke;
    match drop {
        Drop::Before => {
            ui.painter().hline(rect.x_range(), rect.top(), stroke);
        }
        Drop::After => {
            ui.painter().hline(rect.x_range(), rect.bottom(), stroke);
        }
        Drop::Into => {
            ui.painter()
                .rect_stroke(rect, 2.0, stroke, egui::StrokeKind::Inside);
        }
    }
    if row.dnd_release_payload::<Vec<NodeId>>().is_some()
        && !dragged.contains(&id)
        && let Some((parent, before)) = drop_target(tree, id, drop)
    {
        send(
            out,
            ObjectCommand::Reparent {
                nodes: dragged.to_vec(),
                parent,
                before,
            },
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brickmap::objects::{LayerId, ModelId, NewNode, Placement};

    #[test]
    fn rows_are_the_drawing_order_with_depths() {
        let mut t = ObjectTree::new();
        let object = NewNode::Object {
            model: ModelId(0),
            layer: LayerId(0),
        };
        let g = t
            .add(
                ObjectTree::ROOT,
                None,
                "g",
                Placement::IDENTITY,
                NewNode::Group,
            )
            .unwrap();
        let a = t.add(g, None, "a", Placement::IDENTITY, object).unwrap();
        let b = t
            .add(ObjectTree::ROOT, None, "b", Placement::IDENTITY, object)
            .unwrap();
        let c = t.add(g, None, "c", Placement::IDENTITY, object).unwrap();
        assert_eq!(rows(&t), vec![(g, 0), (a, 1), (c, 1), (b, 0)]);
        let order: Vec<NodeId> = t.subtree(ObjectTree::ROOT).unwrap()[1..].to_vec();
        assert_eq!(rows(&t).iter().map(|r| r.0).collect::<Vec<_>>(), order);
        // Drops: on a's upper half before it, its lower half after it (before c), on the
        // middle of g into g (before its first child); on b's lower half: the root's end.
        assert_eq!(drop_at(2.0, 20.0, false), Drop::Before);
        assert_eq!(drop_at(12.0, 20.0, false), Drop::After);
        assert_eq!(drop_at(10.0, 20.0, true), Drop::Into);
        assert_eq!(drop_at(18.0, 20.0, true), Drop::After);
        assert_eq!(drop_target(&t, a, Drop::Before), Some((g, Some(a))));
        assert_eq!(drop_target(&t, a, Drop::After), Some((g, Some(c))));
        assert_eq!(drop_target(&t, g, Drop::Into), Some((g, Some(a))));
        assert_eq!(
            drop_target(&t, b, Drop::After),
            Some((ObjectTree::ROOT, None))
        );
    }
}
