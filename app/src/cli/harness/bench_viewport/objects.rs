//! `bench-viewport --edits`, objects: a 256 × 64 × 256 part of the default scene split into
//! an object of its own (about 2 M voxels); moved by a voxel; a sphere drawn into it with
//! one instance of its model and with 100 instances; the bytes the objects hold beside the
//! world. Each operation applied (timed), shown (timed, to the first frame with all of it
//! uploaded) and undone (not timed), several times.

use super::{edit_request, frames_until_shown, stats};
use anyhow::Result;
use app::editor::Document;
use app::editor::command::{BrushMode, BrushShape, Command, Mirror, Stroke};
use app::editor::objects::ObjectCommand;
use app::selection::SelectOp;
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

/// The object cases (see the module doc); `doc` is the default scene, left with the part
/// split off and its instances added.
pub(super) fn object_edits(
    vp: &mut Viewport,
    doc: &mut Document,
    size: (u32, u32),
    params: &render::SceneParams,
) -> Result<String> {
    let req = edit_request(params, size, 0.5);
    let (min, max) = (IVec3::new(64, 48, 64), IVec3::new(319, 111, 319));
    doc.execute(Command::Select(SelectOp::Replace { min, max }))?;
    let started = Instant::now();
    doc.execute(Command::Object(ObjectCommand::SplitSelection))?;
    // The world shows the same voxels: nothing to show.
    let split = started.elapsed().as_secs_f64() * 1e3;
    let part = doc.scene.active().expect("an object");
    let objects_now = |doc: &Document| {
        let objects = doc.scene.objects();
        let node = objects.tree().node(part).expect("the part");
        let solid = match node.kind {
            brickmap::objects::NodeKind::Object { model, .. } => {
                objects.model(model).map_or(0, |m| m.solid_count())
            }
            brickmap::objects::NodeKind::Group { .. } => 0,
        };
        (solid, objects.bytes(), objects.tree().len())
    };
    // The split leaves the part after the rest: brushes edit the scene's first object.
    doc.execute(Command::Object(ObjectCommand::Activate(Some(part))))?;
    let (solid, _, _) = objects_now(doc);
    let mut text = format!(
        "\nobjects: {min} … {max} split into an object of its own ({solid} voxels) in {split:.1} ms; internal scale 0.5, {REPEATS} runs each\noperation                         voxels changed   apply ms median (max)   edit → frame ms median (max), frames   uploaded MB   model / tree + index MB\n"
    );
    let centre = (min.as_dvec3() + max.as_dvec3()) * 0.5;
    let sphere = Command::Stroke(Stroke {
        mode: BrushMode::Attach,
        shape: BrushShape::Sphere,
        size: 16.0,
        material: 1,
        mirror: Mirror::default(),
        points: vec![DVec3::new(centre.x, 100.0, centre.z)],
        axis: Default::default(),
        in_selection: false,
    });
    let row = |doc: &mut Document, vp: &mut Viewport, name: &str, c: &Command| {
        let t = timed(vp, doc, &req, c, true)?;
        let (_, (models, index), _) = objects_now(doc);
        anyhow::Ok(format!(
            "{name:<33} {:<16} {:.1} ({:.1})            {:.1} ({:.1}), {:.0}                 {:.2}          {:.2} / {:.3}\n",
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
    let by_one = Command::Object(ObjectCommand::Translate {
        nodes: vec![part],
        by: IVec3::X,
    });
    text += &row(doc, vp, "move the object by (1,0,0)", &by_one)?;
    text += &row(doc, vp, "sphere r 16, 1 instance", &sphere)?;
    // 99 more objects placing the same model, spread over the grid (overlapping: the later
    // one shows), none past it.
    let started = Instant::now();
    for k in 0..99 {
        let offset = IVec3::new(
            (k * 37) % 256 - 64,
            (k * 13) % 144 - 48,
            (k * 53) % 256 - 64,
        );
        doc.execute(Command::Object(ObjectCommand::Instance {
            node: part,
            offset,
        }))?;
    }
    let added = started.elapsed().as_secs_f64() * 1e3;
    frames_until_shown(vp, &doc.scene.world, &req)?;
    text += &row(doc, vp, "sphere r 16, 100 instances", &sphere)?;
    let (_, _, nodes) = objects_now(doc);
    text += &format!("(99 instances added in {added:.0} ms; {nodes} nodes)\n");
    Ok(text)
}
