//! `bench-viewport --edits`, objects: a 256 × 64 × 256 part of the default scene split into
//! an object of its own (about 2 M voxels) and moved by a voxel; a 40 × 64 × 40 column split
//! off, a sphere drawn into it with one instance of its model and with 100 instances (on a
//! lattice over the terrain); the bytes the objects hold beside the world. Each operation applied (timed), shown (timed, to the first frame with all of it
//! uploaded) and undone (not timed), several times.

use super::{edit_request, frames_until_shown, stats};
use anyhow::Result;
use app::editor::Document;
use app::editor::command::{BrushMode, BrushShape, Command, Mirror, Stroke};
use app::editor::objects::ObjectCommand;
use app::selection::SelectOp;
use brickmap::objects::{NodeId, NodeKind};
use glam::{DVec3, IVec3};
use render::viewport::{FrameRequest, Viewport};
use std::time::Instant;

/// Runs of each timed operation.
pub(super) const REPEATS: usize = 7;

/// One operation's figures: voxels changed, apply ms and edit → frame ms (median, max),
/// frames to show it, MB uploaded.
pub(super) struct Timed {
    pub(super) changed: u64,
    pub(super) apply: (f64, f64),
    pub(super) shown: (f64, f64),
    pub(super) frames: f64,
    pub(super) mb: f64,
}

/// Applies `command` `REPEATS` times, each shown and (when `undo`) undone untimed.
pub(super) fn timed(
    vp: &mut Viewport,
    doc: &mut Document,
    req: &FrameRequest<'_>,
    command: &Command,
    undo: bool,
) -> Result<Timed> {
    let (mut apply, mut shown, mut frames, mut mb, mut changed) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), 0);
    for _ in 0..REPEATS {
        let event = Instant::now();
        let done = doc.execute(command.clone())?;
        apply.push(event.elapsed().as_secs_f64() * 1e3);
        changed = done.changed_voxels;
        if !undo {
            // Selecting and copying change no voxel: nothing to show.
            continue;
        }
        let (n, bytes) = frames_until_shown(vp, &doc.scene.world, req)?;
        shown.push(event.elapsed().as_secs_f64() * 1e3);
        frames.push(f64::from(n));
        mb.push(bytes as f64 / 1e6);
        doc.undo()?;
        frames_until_shown(vp, &doc.scene.world, req)?;
    }
    let (_, a50, _, amax) = stats(apply);
    let (_, s50, _, smax) = if undo {
        stats(shown)
    } else {
        (0.0, 0.0, 0.0, 0.0)
    };
    Ok(Timed {
        changed,
        apply: (a50, amax),
        shown: (s50, smax),
        frames: if undo { stats(frames).1 } else { 0.0 },
        mb: if undo { stats(mb).1 } else { 0.0 },
    })
}

/// The selection `min..=max` of the active object split into an object of its own (the
/// world shows the same: nothing to draw); the new object brushes edit is the original.
/// Returns the new object and the split's milliseconds.
fn split_off(doc: &mut Document, min: IVec3, max: IVec3) -> Result<(NodeId, f64)> {
    let before: Vec<NodeId> = objects_of(doc);
    doc.execute(Command::Select(SelectOp::Replace { min, max }))?;
    let started = Instant::now();
    doc.execute(Command::Object(ObjectCommand::SplitSelection))?;
    let ms = started.elapsed().as_secs_f64() * 1e3;
    doc.execute(Command::Select(SelectOp::None))?;
    let part = objects_of(doc)
        .into_iter()
        .find(|n| !before.contains(n))
        .ok_or_else(|| anyhow::anyhow!("the split made no object"))?;
    Ok((part, ms))
}

/// The scene's objects, in drawing order.
fn objects_of(doc: &Document) -> Vec<NodeId> {
    let objects = doc.scene.objects();
    let tree = objects.tree();
    tree.subtree(brickmap::objects::ObjectTree::ROOT)
        .unwrap_or_default()
        .into_iter()
        .filter(|n| {
            tree.node(*n)
                .is_ok_and(|n| matches!(n.kind, NodeKind::Object { .. }))
        })
        .collect()
}

/// An object's model's solid voxels.
fn solid(doc: &Document, node: NodeId) -> u64 {
    let objects = doc.scene.objects();
    match objects.tree().node(node).map(|n| &n.kind) {
        Ok(NodeKind::Object { model, .. }) => objects.model(*model).map_or(0, |m| m.solid_count()),
        _ => 0,
    }
}

/// The object cases (see the module doc); `doc` is the default scene, left with the parts
/// split off and the instances added.
pub(super) fn object_edits(
    vp: &mut Viewport,
    doc: &mut Document,
    size: (u32, u32),
    params: &render::SceneParams,
) -> Result<String> {
    let req = edit_request(params, size, 0.5);
    let (min, max) = (IVec3::new(64, 48, 64), IVec3::new(319, 111, 319));
    let (part, split) = split_off(doc, min, max)?;
    let mut text = format!(
        "\nobjects: internal scale 0.5, {REPEATS} runs each; a box of the default scene split into an object of its own, then\noperation                         model voxels changed   apply ms median (max)   edit → frame ms median (max), frames   uploaded MB   models / tree + index MB\n"
    );
    let row = |doc: &mut Document, vp: &mut Viewport, name: &str, c: &Command| {
        let t = timed(vp, doc, &req, c, true)?;
        let (models, index) = doc.scene.objects().bytes();
        anyhow::Ok(format!(
            "{name:<33} {:<22} {:.1} ({:.1})            {:.1} ({:.1}), {:.0}                 {:.2}          {:.2} / {:.3}\n",
            t.changed,
            t.apply.0,
            t.apply.1,
            t.shown.0,
            t.shown.1,
            t.frames,
            t.mb,
            models as f64 / 1e6,
            index as f64 / 1e6
        ))
    };
    text += &format!(
        "({min} … {max}: {} voxels, split in {split:.0} ms)\n",
        solid(doc, part)
    );
    let by_one = Command::Object(ObjectCommand::Translate {
        nodes: vec![part],
        by: IVec3::X,
    });
    text += &row(doc, vp, "move the object by (1,0,0)", &by_one)?;
    // A column of the rest, a tree's size, to be placed 100 times over the terrain.
    let (min, max) = (IVec3::new(8, 48, 8), IVec3::new(47, 111, 47));
    let (column, split) = split_off(doc, min, max)?;
    text += &format!(
        "({min} … {max}: {} voxels, split in {split:.0} ms)\n",
        solid(doc, column)
    );
    let centre = (min.as_dvec3() + max.as_dvec3()) * 0.5;
    let sphere = Command::Stroke(Stroke {
        mode: BrushMode::Attach,
        shape: BrushShape::Sphere,
        size: 16.0,
        material: 1,
        mirror: Mirror::default(),
        points: vec![DVec3::new(centre.x, centre.y, centre.z)],
        axis: Default::default(),
        in_selection: false,
        paint: Default::default(),
    });
    doc.execute(Command::Object(ObjectCommand::Activate(Some(column))))?;
    text += &row(doc, vp, "sphere r 16, 1 instance", &sphere)?;
    // 99 more objects placing the same model, on a 10 × 10 lattice 48 voxels apart (apart
    // from each other, over the terrain).
    let started = Instant::now();
    for k in 1..100 {
        let offset = IVec3::new(48 * (k % 10), 0, 48 * (k / 10));
        doc.execute(Command::Object(ObjectCommand::Instance {
            node: column,
            offset,
        }))?;
    }
    let added = started.elapsed().as_secs_f64() * 1e3;
    frames_until_shown(vp, &doc.scene.world, &req)?;
    text += &row(doc, vp, "sphere r 16, 100 instances", &sphere)?;
    text += &format!(
        "(99 instances added in {added:.0} ms; {} nodes)\n",
        doc.scene.objects().tree().len()
    );
    Ok(text)
}
