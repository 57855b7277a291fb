//! A stroke being drawn: one undo step that grows while the mouse moves. Each new segment's
//! edits go to the world's workers as soon as it is given (the edit thread runs it; the UI
//! never waits), so it is visible the next frame; on release the step's inverse is the
//! union of its segments' inverses, and the history gets the whole stroke as one command
//! (scripts and the recorder replay it at once, to the same content hash). A segment that
//! fails undoes everything the stroke applied.
//!
//! Segments are applied one after another, not pipelined: if a later edit were queued
//! behind one that fails, the failed edit's rollback would land after it and undo part of
//! it too.

use super::brush::{BrushShape, Stroke, stroke_edits};
use super::error::{EditError, Result, invalid};
use super::inverse::{Inverse, undo_all};
use crate::scene::Scene;
use brickmap::EditOp;
use brickmap::objects::ObjectOp;
use glam::DVec3;

/// The open stroke of a document.
#[derive(Debug)]
pub struct LiveStroke {
    /// The stroke so far (every point given).
    pub stroke: Stroke,
    inverses: Vec<ObjectOp>,
    /// The voxels recoloured so far, for colour modes that change each voxel once.
    done: brickmap::VoxelSet,
    /// Voxels changed so far (by the segments; a voxel changed twice counts twice).
    pub changed_voxels: u64,
}

impl LiveStroke {
    /// Starts a stroke at its first points and applies them (a box waits for its last corner:
    /// nothing is applied until the end). On error nothing changed.
    pub fn begin(scene: &Scene, stroke: Stroke) -> Result<Self> {
        // The material before touching the world (the points and size are checked with the
        // first segment, before it is applied).
        if stroke.mode != super::brush::BrushMode::Erase {
            scene.world.materials().check(stroke.material as u32)?;
        }
        stroke.paint.check(
            stroke.mode == super::brush::BrushMode::Erase,
            stroke.mode == super::brush::BrushMode::Attach,
            &scene.world.materials(),
        )?;
        let mut live = LiveStroke {
            stroke: Stroke {
                points: Vec::new(),
                ..stroke.clone()
            },
            inverses: Vec::new(),
            done: brickmap::VoxelSet::new(),
            changed_voxels: 0,
        };
        live.extend(scene, &stroke.points)?;
        Ok(live)
    }

    /// Adds points: the next segment. On error everything the stroke applied is undone (the
    /// caller drops the stroke) and the error returned.
    pub fn extend(&mut self, scene: &Scene, points: &[DVec3]) -> Result<()> {
        if points.is_empty() {
            return Ok(());
        }
        let edits = match self.segment(scene, points) {
            Ok(e) => e,
            Err(e) => return Err(self.fail(scene, e)),
        };
        self.stroke.points.extend_from_slice(points);
        if self.stroke.paint.reads_materials() {
            for edit in &edits {
                if let EditOp::Shape {
                    shape: brickmap::Shape::Set(set),
                    ..
                } = edit
                {
                    self.done = self.done.union(set);
                }
            }
        }
        if self.stroke.shape == BrushShape::Box && self.stroke.points.len() > 2 {
            // A box is its first and latest corners.
            let last = self.stroke.points[self.stroke.points.len() - 1];
            self.stroke.points.truncate(1);
            self.stroke.points.push(last);
        }
        for edit in edits {
            match scene.edit(edit) {
                Ok((inverse, changed)) => {
                    self.changed_voxels += changed;
                    self.inverses.push(inverse);
                }
                Err(e) => return Err(self.fail(scene, e.into())),
            }
        }
        Ok(())
    }

    /// Whether the stroke is applied only at its end: a box (its first and last corners), a
    /// gradient (its colours run from the first point to the last).
    fn at_the_end(&self) -> bool {
        self.stroke.shape == BrushShape::Box || self.stroke.paint.needs_whole_stroke()
    }

    /// The edits of the segment that adds `points`: the brush swept on from the last point
    /// (so the stroke stays connected however far apart the points are); a stroke applied
    /// at the end gives none.
    fn segment(&self, scene: &Scene, points: &[DVec3]) -> Result<Vec<EditOp>> {
        let mut part = Stroke {
            points: points.to_vec(),
            ..self.stroke.clone()
        };
        if self.stroke.shape != BrushShape::Box
            && let Some(last) = self.stroke.points.last()
        {
            part.points.insert(0, *last);
        }
        if self.at_the_end() {
            // Its points are checked now, its edits made at the end.
            part.paint = super::brush::PaintMode::Solid;
            stroke_edits(&part, None, &scene.world.read(), None)?;
            return Ok(Vec::new());
        }
        stroke_edits(
            &part,
            scene.selection.as_ref(),
            &scene.world.read(),
            Some(&self.done),
        )
    }

    /// Undoes what the stroke applied and returns `error` (or the failure to undo).
    fn fail(&mut self, scene: &Scene, error: EditError) -> EditError {
        match undo_all(scene, std::mem::take(&mut self.inverses)) {
            Ok(()) => error,
            Err(undo) => undo,
        }
    }

    /// Ends the stroke: a box or a gradient is applied now. Returns the
    /// command for the history (the whole stroke) and its inverse; on error nothing the
    /// stroke applied remains.
    pub fn finish(mut self, scene: &Scene) -> Result<(Stroke, Inverse, u64)> {
        if self.stroke.points.is_empty() {
            return Err(invalid("a stroke needs at least one point"));
        }
        if self.at_the_end() {
            let edits = stroke_edits(
                &self.stroke,
                scene.selection.as_ref(),
                &scene.world.read(),
                None,
            )?;
            for edit in edits {
                match scene.edit(edit) {
                    Ok((inverse, changed)) => {
                        self.changed_voxels += changed;
                        self.inverses.push(inverse);
                    }
                    Err(e) => return Err(self.fail(scene, e.into())),
                }
            }
        }
        Ok((
            self.stroke,
            Inverse::Voxels(self.inverses, None),
            self.changed_voxels,
        ))
    }

    /// Abandons the stroke, undoing what it applied.
    pub fn abort(self, scene: &Scene) -> Result<()> {
        undo_all(scene, self.inverses)
    }
}
