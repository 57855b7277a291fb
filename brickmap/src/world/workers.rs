//! The world's worker threads: the jobs they take (an edit's part for their slab), their
//! loop (a panic becomes the edit's error, never a dead thread), and the `Ticket` an edit's
//! caller waits on (which rolls back the parts that succeeded when one fails).

use super::*;

pub(super) enum Job {
    Work {
        item: WorkItem,
        reply: Sender<PartResult>,
    },
    Stop,
}

pub(super) type PartResult = (usize, Result<(Vec<crate::edit::BrickUndo>, u64)>);

pub(super) fn worker_loop(worker: usize, slab: Arc<RwLock<Slab>>, rx: Receiver<Job>) {
    for job in rx {
        let Job::Work { item, reply } = job else {
            break;
        };
        let result =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match slab.write() {
                Ok(mut s) => s.run(item),
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
        let mut inverse = EditInverse::default();
        let mut changed_voxels = 0;
        for (_, (undo, changed)) in parts {
            inverse.bricks.extend(undo);
            changed_voxels += changed;
        }
        if first_error.is_none() {
            let changed: Vec<UVec3> = inverse.bricks.iter().map(|u| u.brick).collect();
            self.world.refresh_lights(&changed);
        }
        if let Some(e) = first_error {
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
        Ok(EditOutcome {
            inverse,
            changed_voxels,
        })
    }
}
