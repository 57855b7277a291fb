//! Turns and mirrors of the selection's solid voxels about the selection's centre (Alt + X /
//! Y / Z with a selection, the Tools panel's buttons): one `Restore` edit, as a move is, and
//! the region turned with them.
//!
//! The centre is the selection box's, in doubled coordinates (`lo + hi + 1`), exact when the
//! box's sides keep their parity under the turn. A quarter turn that swaps an odd side with
//! an even one cannot keep it: the centre moves half a voxel on those axes, up from a whole
//! coordinate and down from a half one, so the next quarter turn moves it back — four turns,
//! or a turn and its reverse, are the identity, and so are two mirrors.

use crate::selection::{Region, RegionBox, Selection, Writes};
use brickmap::objects::{Axis, Orientation};
use brickmap::{EditOp, WorldView};
use glam::IVec3;
use serde::{Deserialize, Serialize};

/// A turn or a mirror of the selection.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SelectionTransform {
    /// Quarter turns about an axis (counter-clockwise looking down it).
    Turn {
        /// The axis.
        axis: Axis,
        /// Quarter turns (negative: clockwise).
        quarters: i32,
    },
    /// A mirror along an axis.
    Flip(Axis),
}

impl SelectionTransform {
    /// Its orientation.
    pub fn orientation(&self) -> Orientation {
        match *self {
            Self::Turn { axis, quarters } => Orientation::quarter_turn(axis, quarters),
            Self::Flip(axis) => Orientation::flip(axis),
        }
    }
}

/// Where voxels of a box `lo..=hi` go under `rot` about its centre.
#[derive(Clone, Copy, Debug)]
pub struct VoxelMap {
    rot: Orientation,
    from: IVec3,
    to: IVec3,
}

impl VoxelMap {
    /// The map for the box `lo..=hi`.
    pub fn new(rot: Orientation, lo: IVec3, hi: IVec3) -> Self {
        let from = lo + hi + 1;
        let size = hi - lo + 1;
        let turned = rot.apply(size).abs();
        // A doubled centre is even on an even side, odd on an odd one.
        let to = IVec3::from_array(std::array::from_fn(|i| {
            let c = from[i];
            if c.rem_euclid(2) == turned[i].rem_euclid(2) {
                c
            } else if c.rem_euclid(2) == 0 {
                c + 1
            } else {
                c - 1
            }
        }));
        Self { rot, from, to }
    }

    /// Where voxel `v` goes.
    pub fn apply(&self, v: IVec3) -> IVec3 {
        let twice = self.rot.apply(2 * v + 1 - self.from) + self.to;
        (twice - 1).div_euclid(IVec3::splat(2))
    }

    /// The map as `v ↦ x·v.x + y·v.y + z·v.z + k` (the turned axes and where the origin
    /// goes), for stepping through a brick without a matrix product per voxel.
    fn affine(&self) -> [IVec3; 4] {
        let r = |e| self.rot.apply(e);
        [
            r(IVec3::X),
            r(IVec3::Y),
            r(IVec3::Z),
            self.apply(IVec3::ZERO),
        ]
    }

    /// The box `min..=max` turned (its corners sorted).
    pub fn apply_box(&self, b: &RegionBox) -> RegionBox {
        let (a, c) = (self.apply(b.min), self.apply(b.max));
        RegionBox {
            min: a.min(c),
            max: a.max(c),
            subtract: b.subtract,
        }
    }
}

/// The edit that turns the solid voxels of `selection` and the region they go to.
pub fn transform_edit(
    view: &WorldView<'_>,
    selection: &Selection,
    t: SelectionTransform,
) -> Option<(EditOp, Region)> {
    let (lo, hi) = selection.voxels.bounds()?;
    let map = VoxelMap::new(t.orientation(), lo, hi);
    let voxels = view.dims().voxels();
    let mut w = Writes::default();
    for (b, sel) in selection.voxels.iter() {
        w.clear(b, sel);
    }
    let [ax, ay, az, k] = map.affine();
    // The voxels gathered on every core, a share of the source bricks each, then merged:
    // the map is one to one, so no two shares put the same voxel.
    let bricks: Vec<_> = selection.voxels.iter().collect();
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(16);
    let share = bricks.len().div_ceil(threads).max(64);
    let parts: Vec<Writes> = std::thread::scope(|s| {
        let handles: Vec<_> = bricks
            .chunks(share)
            .map(|chunk| {
                s.spawn(move || {
                    let mut w = Writes::default();
                    for (b, sel) in chunk {
                        let (solid, dense) = view.brick_voxels(*b);
                        let min = b.as_ivec3() * 8;
                        let base = ax * min.x + ay * min.y + az * min.z + k;
                        let keep = solid.and(sel);
                        let moved = keep.ones().map(|bit| {
                            let (x, y, z) =
                                (bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
                            (base + ax * x + ay * y + az * z, dense[bit])
                        });
                        w.set_all(voxels, moved);
                    }
                    w
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a gather thread"))
            .collect()
    });
    for part in parts {
        w.merge_puts(part);
    }
    let region = Region {
        base: selection.region.base.as_ref().map(|set| {
            let mut out = brickmap::VoxelSet::new();
            for (b, m) in set.iter() {
                let min = b.as_ivec3() * 8;
                let origin = ax * min.x + ay * min.y + az * min.z + k;
                for bit in m.ones() {
                    let (x, y, z) = (bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
                    let v = origin + ax * x + ay * y + az * z;
                    if v.cmpge(IVec3::ZERO).all() {
                        out.insert(v);
                    }
                }
            }
            std::sync::Arc::new(out)
        }),
        boxes: selection
            .region
            .boxes
            .iter()
            .map(|b| map.apply_box(b))
            .collect(),
    };
    Some((w.into_edit(), region))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes() -> Vec<(IVec3, IVec3)> {
        let mut out = Vec::new();
        for (x, y, z) in [(0, 0, 0), (1, 2, 3), (-4, 5, 7)] {
            for (a, b, c) in [(1, 1, 1), (2, 3, 4), (5, 2, 6), (3, 3, 2)] {
                let lo = IVec3::new(x, y, z);
                out.push((lo, lo + IVec3::new(a, b, c) - 1));
            }
        }
        out
    }

    #[test]
    fn every_turn_and_mirror_maps_the_box_onto_its_turned_box_one_to_one() {
        for (lo, hi) in boxes() {
            for axis in [Axis::X, Axis::Y, Axis::Z] {
                for t in [
                    SelectionTransform::Turn { axis, quarters: 1 },
                    SelectionTransform::Turn { axis, quarters: -1 },
                    SelectionTransform::Turn { axis, quarters: 2 },
                    SelectionTransform::Flip(axis),
                ] {
                    let map = VoxelMap::new(t.orientation(), lo, hi);
                    let image = map.apply_box(&RegionBox {
                        min: lo,
                        max: hi,
                        subtract: false,
                    });
                    let size = image.max - image.min + 1;
                    assert_eq!(size, t.orientation().apply(hi - lo + 1).abs());
                    let mut seen = std::collections::HashSet::new();
                    for x in lo.x..=hi.x {
                        for y in lo.y..=hi.y {
                            for z in lo.z..=hi.z {
                                let v = map.apply(IVec3::new(x, y, z));
                                assert!(v.cmpge(image.min).all() && v.cmple(image.max).all());
                                assert!(seen.insert(v), "two voxels land on {v}");
                            }
                        }
                    }
                    // The centre stays within half a voxel.
                    let moved = (image.min + image.max) - (lo + hi);
                    assert!(moved.abs().max_element() <= 1, "{t:?} {lo} {hi}: {moved}");
                }
            }
        }
    }

    #[test]
    fn the_affine_form_is_the_map() {
        for (lo, hi) in boxes() {
            for rot in Orientation::all() {
                let map = VoxelMap::new(rot, lo, hi);
                let [ax, ay, az, k] = map.affine();
                for v in [lo, hi, lo + 1, IVec3::new(hi.x, lo.y, hi.z)] {
                    assert_eq!(ax * v.x + ay * v.y + az * v.z + k, map.apply(v));
                }
            }
        }
    }

    #[test]
    fn four_turns_a_turn_and_back_and_two_mirrors_are_the_identity() {
        for (lo, hi) in boxes() {
            for axis in [Axis::X, Axis::Y, Axis::Z] {
                let run = |steps: &[SelectionTransform]| {
                    let (mut lo2, mut hi2) = (lo, hi);
                    let mut v = lo + IVec3::new(0, hi.y - lo.y, 0);
                    for t in steps {
                        let map = VoxelMap::new(t.orientation(), lo2, hi2);
                        v = map.apply(v);
                        let b = map.apply_box(&RegionBox {
                            min: lo2,
                            max: hi2,
                            subtract: false,
                        });
                        (lo2, hi2) = (b.min, b.max);
                    }
                    (v, lo2, hi2)
                };
                let start = (lo + IVec3::new(0, hi.y - lo.y, 0), lo, hi);
                let turn = |quarters| SelectionTransform::Turn { axis, quarters };
                assert_eq!(run(&[turn(1); 4]), start, "{axis:?} {lo} {hi}");
                assert_eq!(run(&[turn(1), turn(-1)]), start);
                assert_eq!(run(&[turn(-1), turn(1)]), start);
                assert_eq!(run(&[SelectionTransform::Flip(axis); 2]), start);
            }
        }
    }
}
