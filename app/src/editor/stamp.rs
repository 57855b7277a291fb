//! Stamp: the clipboard used as a brush — put down at each place a drag of the Stamp tool
//! reached, turned by quarter turns about the vertical axis (a key turns it). Each stamp
//! writes the clip's solid voxels (its empty ones leave the world as it is), later stamps
//! winning where two overlap; the whole drag is one `Restore` edit, so undo is exact.
//!
//! A stamp at `at` puts the turned clip's minimum corner there; the turn maps the clip's box
//! onto itself about its centre (doubled coordinates, exact for every size).

use super::error::{EditError, Result, invalid};
use crate::selection::{Clip, Writes};
use brickmap::EditOp;
use brickmap::objects::{Axis, Orientation};
use glam::IVec3;

/// The most stamps one command puts down.
pub const MAX_STAMPS: usize = 4096;

/// The clip's size after `quarters` quarter turns about the vertical.
pub fn turned_size(size: IVec3, quarters: i32) -> IVec3 {
    Orientation::quarter_turn(Axis::Y, quarters)
        .apply(size)
        .abs()
}

/// Where a clip voxel `p` (relative to its minimum corner, in a box of `size`) lies in the
/// clip turned `quarters` times (relative to the turned box's minimum corner).
pub fn turned(rot: &Orientation, p: IVec3, size: IVec3, turned: IVec3) -> IVec3 {
    (rot.apply(2 * p + 1 - size) + turned - 1).div_euclid(IVec3::splat(2))
}

/// The edit that stamps `clip` turned `quarters` times at each of `at` (minimum corners) in a
/// grid of `voxels`.
pub(super) fn stamp_edit(
    clip: Option<&Clip>,
    at: &[IVec3],
    quarters: i32,
    voxels: IVec3,
) -> Result<EditOp> {
    let clip = clip.ok_or(EditError::NothingToDo("the clipboard is empty"))?;
    if at.is_empty() {
        return Err(invalid("a stamp needs at least one place"));
    }
    if at.len() > MAX_STAMPS {
        return Err(invalid(format!(
            "{} stamps: at most {MAX_STAMPS} in one drag",
            at.len()
        )));
    }
    let rot = Orientation::quarter_turn(Axis::Y, quarters);
    let size = turned_size(clip.size, quarters);
    // The turned voxels with the source brick they came from: `Writes::set_all` takes the
    // voxels of one source brick at a time (they land in a few target bricks).
    let voxels_turned: Vec<(IVec3, IVec3, u8)> = clip
        .solid_voxels()
        .map(|(p, m)| {
            (
                p.div_euclid(IVec3::splat(8)),
                turned(&rot, p, clip.size, size),
                m,
            )
        })
        .collect();
    let mut writes = Writes::default();
    for a in at {
        // A stamp wholly outside the grid writes nothing.
        if (*a + size).cmple(IVec3::ZERO).any() || a.cmpge(voxels).any() {
            continue;
        }
        for brick in voxels_turned.chunk_by(|x, y| x.0 == y.0) {
            writes.set_all(voxels, brick.iter().map(|(_, p, m)| (*a + *p, *m)));
        }
    }
    Ok(writes.into_edit())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_turned_clip_fills_its_turned_box_and_four_turns_are_none() {
        let size = IVec3::new(3, 2, 6);
        for q in -4..=4 {
            let rot = Orientation::quarter_turn(Axis::Y, q);
            let t = turned_size(size, q);
            let mut seen = std::collections::HashSet::new();
            for x in 0..size.x {
                for y in 0..size.y {
                    for z in 0..size.z {
                        let p = turned(&rot, IVec3::new(x, y, z), size, t);
                        assert!(p.cmpge(IVec3::ZERO).all() && p.cmplt(t).all(), "{q} {p}");
                        assert!(seen.insert(p), "{q}: two voxels onto {p}");
                    }
                }
            }
            if q % 4 == 0 {
                assert_eq!(t, size);
                assert_eq!(
                    turned(&rot, IVec3::new(2, 1, 4), size, t),
                    IVec3::new(2, 1, 4)
                );
            }
        }
    }
}
