//! The world's worker threads: the jobs they take (an edit's part for their slab), their
//! loop (a panic becomes the edit's error, never a dead thread), and the `Ticket` an edit's
//! caller waits on (which rolls back the parts that succeeded when one fails).

use super::*;

pub(super) enum Job {
    Work {
        item: WorkItem,
        /// Record whole-brick writes into empty cells as positions (`apply_unrecorded`).
        compact: bool,
        reply: Sender<PartResult>,
    },
    Stop,
}

pub(super) type PartResult = (usize, Result<(crate::slab::Undo, u64)>);

pub(super) fn worker_loop(worker: usize, slab: Arc<RwLock<Slab>>, rx: Receiver<Job>) {
    for job in rx {
        let Job::Work {
            item,
            compact,
            reply,
        } = job
        else {
            break;
        };
        let result =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match slab.write() {
                Ok(mut s) => s.run(item, compact),
                Err(_) => Err(BrickmapError::WorkerPanicked {
                    worker,
                    message: "an earlier edit panicked; the slab may be inconsistent".into(),
                }),
            }));
        let result = result.unwrap_or_else(|payload| {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(BrickmapError::WorkerPanicked { worker, message })
        });
        let _ = reply.send((worker, result));
    }
}

/// Waits for an edit's parts.
#[must_use = "an edit's result is only known once waited for"]
pub struct Ticket<'w> {
    pub(super) world: &'w World,
    pub(super) rx: Receiver<PartResult>,
    pub(super) expected: usize,
}

impl Ticket<'_> {
    /// Waits for every part; on failure of any part rolls back the others and returns the
    /// first error, leaving the world as before the edit.
    pub fn wait(self) -> Result<EditOutcome> {
        let (undo, changed_voxels) = self.collect()?;
        Ok(EditOutcome {
            inverse: inverse_of(undo),
            changed_voxels,
        })
    }

    /// [`Ticket::wait`] without the inverse: the voxels changed.
    pub(super) fn wait_unrecorded(self) -> Result<u64> {
        Ok(self.collect()?.1)
    }

    /// Every part's record (in worker order) and the voxels changed, the lights refreshed;
    /// on a failure the parts that succeeded rolled back and the first error.
    fn collect(self) -> Result<(Vec<crate::slab::Undo>, u64)> {
        let mut parts = Vec::with_capacity(self.expected);
        let mut first_error = None;
        for _ in 0..self.expected {
            match self.rx.recv() {
                Ok((w, Ok(part))) => parts.push((w, part)),
                Ok((_, Err(e))) => {
                    first_error.get_or_insert(e);
                }
                Err(_) => {
                    first_error.get_or_insert(BrickmapError::WorkerGone(usize::MAX));
                }
            }
        }
        parts.sort_by_key(|(w, _)| *w);
        let changed_voxels = parts.iter().map(|(_, (_, c))| c).sum();
        let undo: Vec<crate::slab::Undo> = parts.into_iter().map(|(_, (u, _))| u).collect();
        crate::census::undo_records(undo.iter().map(|u| u.records() as u64).sum());
        if let Some(e) = first_error {
            let inverse = inverse_of(undo);
            if !inverse.is_empty()
                && let Err(rollback) = self.world.apply(EditOp::Restore(inverse))
            {
                return Err(BrickmapError::RollbackFailed {
                    cause: Box::new(e),
                    rollback: Box::new(rollback),
                });
            }
            return Err(e);
        }
        if self.world.lights_matter() {
            let changed: Vec<UVec3> = undo.iter().flat_map(|u| u.bricks()).collect();
            self.world.refresh_lights(&changed);
        }
        Ok((undo, changed_voxels))
    }
}

/// The parts' records as one inverse (each part's in the order that puts it back; the
/// parts touch disjoint slabs).
fn inverse_of(undo: Vec<crate::slab::Undo>) -> EditInverse {
    let mut inverse = EditInverse::default();
    for u in undo {
        inverse.bricks.extend(u.into_inverse());
    }
    inverse
}
