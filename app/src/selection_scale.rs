//! Scaling the selection's solid voxels × 2 and × ½ about the selection box's centre (the
//! Tools panel's "×2" and "×½"): one `Restore` edit, as a move is, and the region scaled with
//! them.
//!
//! × 2: each voxel becomes the 2 × 2 × 2 block at `lo' + 2·(v − lo)`, with `lo' = lo − ⌊s/2⌋`
//! for a box `lo` of size `s`. × ½: the box of size `⌈s/2⌉` at `lo + ⌊(s − ⌈s/2⌉)/2⌋`; each of
//! its voxels looks at the 2³ block of the source it covers (inside the selection) and is
//! solid when at least 4 of those 8 are — ties keep the voxel — with the material most of the
//! solid ones have, the lowest index where two are as many. So × 2 then × ½ gives back the
//! selection's voxels and region exactly (what the bigger box covered outside the selection
//! stays overwritten, as a move overwrites).

use crate::selection::{Region, RegionBox, Selection, Writes};
use brickmap::{EditOp, VoxelSet, WorldView};
use glam::IVec3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Which way to scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ScaleStep {
    /// Twice the size (nearest: each voxel a 2 × 2 × 2 block).
    Double,
    /// Half the size (the majority of each 2 × 2 × 2 block).
    Halve,
}

/// The × ½ rule for one 2 × 2 × 2 block (its voxels' materials, None where empty): solid
/// when at least 4 of the 8 are, with the material most of them have, the lowest index
/// where two are as many.
pub fn majority(block: impl IntoIterator<Item = Option<u8>>) -> Option<u8> {
    let mut counts: Vec<(u8, u32)> = Vec::new();
    let mut n = 0;
    for m in block.into_iter().flatten() {
        n += 1;
        match counts.iter_mut().find(|(c, _)| *c == m) {
            Some((_, c)) => *c += 1,
            None => counts.push((m, 1)),
        }
    }
    (n >= 4).then(|| {
        counts.sort_by_key(|(m, c)| (std::cmp::Reverse(*c), *m));
        counts[0].0
    })
}

/// The new box's low corner and how a source voxel's offset from the old one maps.
fn placement(step: ScaleStep, lo: IVec3, size: IVec3) -> IVec3 {
    match step {
        ScaleStep::Double => lo - size.div_euclid(IVec3::splat(2)),
        ScaleStep::Halve => {
            let half = (size + 1) / 2;
            lo + (size - half).div_euclid(IVec3::splat(2))
        }
    }
}

/// The edit that scales the solid voxels of `selection` and the region they go to (None when
/// nothing is selected).
pub fn scale_edit(
    view: &WorldView<'_>,
    selection: &Selection,
    step: ScaleStep,
) -> Option<(EditOp, Region)> {
    let (lo, hi) = selection.voxels.bounds()?;
    let size = hi - lo + 1;
    let to = placement(step, lo, size);
    let voxels = view.dims().voxels();
    let mut w = Writes::default();
    for (b, sel) in selection.voxels.iter() {
        w.clear(b, sel);
    }
    let solid = |v: IVec3| {
        if selection.voxels.contains(v) {
            view.voxel(v).ok().flatten()
        } else {
            None
        }
    };
    match step {
        ScaleStep::Double => {
            for (b, sel) in selection.voxels.iter() {
                let (mask, dense) = view.brick_voxels(b);
                let keep = mask.and(sel);
                let min = b.as_ivec3() * 8;
                let blocks = keep.ones().flat_map(|bit| {
                    let v =
                        min + IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
                    let corner = to + 2 * (v - lo);
                    (0..8)
                        .map(move |k| (corner + IVec3::new(k & 1, k >> 1 & 1, k >> 2), dense[bit]))
                });
                w.set_all(voxels, blocks);
            }
        }
        ScaleStep::Halve => {
            let half = (size + 1) / 2;
            let mut out = Vec::new();
            for x in 0..half.x {
                for y in 0..half.y {
                    for z in 0..half.z {
                        let u = IVec3::new(x, y, z);
                        let block = (0..8)
                            .map(|k| solid(lo + 2 * u + IVec3::new(k & 1, k >> 1 & 1, k >> 2)));
                        if let Some(m) = majority(block) {
                            out.push((to + u, m));
                        }
                    }
                }
            }
            w.set_all(voxels, out);
        }
    }
    let map_box = |b: &RegionBox| match step {
        ScaleStep::Double => RegionBox {
            min: to + 2 * (b.min - lo),
            max: to + 2 * (b.max - lo) + 1,
            subtract: b.subtract,
        },
        ScaleStep::Halve => RegionBox {
            min: to + (b.min - lo).div_euclid(IVec3::splat(2)),
            max: to + (b.max - lo).div_euclid(IVec3::splat(2)),
            subtract: b.subtract,
        },
    };
    let region = Region {
        base: selection.region.base.as_ref().map(|set| {
            let mut out = VoxelSet::new();
            for v in set.voxels() {
                let b = map_box(&RegionBox {
                    min: v,
                    max: v,
                    subtract: false,
                });
                if b.max.cmpge(IVec3::ZERO).all() {
                    out.apply_box(b.min, b.max, voxels, false);
                }
            }
            Arc::new(out)
        }),
        boxes: selection.region.boxes.iter().map(map_box).collect(),
    };
    Some((w.into_edit(), region))
}
