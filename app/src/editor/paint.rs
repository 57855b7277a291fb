//! The brush's colour modes: what material each voxel a stroke covers gets, when that is not
//! simply the brush's material.
//!
//! - **Gradient** from the brush's material at the stroke's first point to `to` at its last:
//!   the brush covers the whole drag as any stroke does (following the surface), and a
//!   covered voxel's centre is projected on the segment from the first point to the last
//!   (t clamped to 0..=1) and takes the table entry `from + round(t · (to − from))` — the
//!   entries between the two in table order, as indexed palettes are laid out (a row of
//!   shades). Each mirror image uses its own mirrored segment. The colours depend on the last
//!   point, so a live gradient stroke is applied at the release (previewed meanwhile).
//! - **Random** among chosen entries: entry `among[h mod n]`, `h` a hash of the voxel's
//!   position and the stroke's seed; the same voxel gets the same entry within a stroke, so a
//!   live stroke and its replay agree, and a new seed per stroke varies the next one.
//! - **Darken / brighten** by a palette neighbour: a solid voxel of material `m` takes the
//!   neighbour `m − 1` or `m + 1` (in the table) whose colour is darker (brighter) than `m`'s,
//!   the darkest (brightest) of the two when both are; it keeps `m` when neither is. Luminance
//!   is Rec. 709's weights on the linear colour. Each voxel changes once per stroke, however
//!   often the drag passes over it (a live stroke leaves out what it already changed), and
//!   the materials read are those shown (the world's composite).
//!
//! Every mode becomes one shape edit per material (a `Shape::Set` of the voxels that get it),
//! so the workers apply it brick by brick like any brush and undo is the usual exact inverse.

use super::error::{Result, invalid};
use brickmap::{EditOp, MaterialTable, Mode, Shape, VoxelSet, WorldView};
use glam::{DVec3, IVec3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;

/// How a stroke colours the voxels it covers.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PaintMode {
    /// Every voxel the brush's material.
    #[default]
    Solid,
    /// From the brush's material at the first point to `to` at the last, through the table
    /// entries between them.
    Gradient {
        /// The material at the stroke's last point.
        to: u8,
    },
    /// Each voxel one of `among`, chosen by a hash of its position and `seed`.
    Random {
        /// The materials chosen among (at least one).
        among: Vec<u8>,
        /// Varies the choice from stroke to stroke.
        seed: u32,
    },
    /// Each solid voxel its darker table neighbour (paint only).
    Darken,
    /// Each solid voxel its brighter table neighbour (paint only).
    Brighten,
}

impl PaintMode {
    /// Whether the material of a voxel depends on the whole stroke (its last point), so a
    /// live stroke applies it only at the release.
    pub fn needs_whole_stroke(&self) -> bool {
        matches!(self, PaintMode::Gradient { .. })
    }

    /// Whether each voxel may change only once per stroke (its new material depends on its
    /// old one).
    pub fn reads_materials(&self) -> bool {
        matches!(self, PaintMode::Darken | PaintMode::Brighten)
    }

    /// Checks the mode against the brush's (erasing, attaching, else painting) and the
    /// material table.
    pub fn check(&self, erase: bool, attach: bool, table: &MaterialTable) -> Result<()> {
        match self {
            PaintMode::Solid => Ok(()),
            _ if erase => Err(invalid("erasing has no colour mode")),
            PaintMode::Gradient { to } => Ok(table.check(*to as u32)?),
            PaintMode::Random { among, .. } => {
                if among.is_empty() {
                    return Err(invalid("random paint needs at least one material"));
                }
                for m in among {
                    table.check(*m as u32)?;
                }
                Ok(())
            }
            PaintMode::Darken | PaintMode::Brighten if attach => Err(invalid(
                "darken and brighten repaint solid voxels: use the paint mode",
            )),
            PaintMode::Darken | PaintMode::Brighten => Ok(()),
        }
    }
}

/// One mirror image of a stroke: its points (mirrored) and the voxels its brush covers
/// (already limited to the selection and the grid).
pub(super) struct Image {
    /// The image's stroke points.
    pub points: Vec<DVec3>,
    /// The voxels it covers.
    pub voxels: VoxelSet,
}

/// The edits that colour the images' voxels by `paint` (not `Solid`): one `Set` edit per
/// material, adding (`attach`) or painting. `done` voxels are left out (a live stroke's
/// earlier segments, for the modes that read materials).
pub(super) fn coloured_edits(
    paint: &PaintMode,
    attach: bool,
    from: u8,
    images: Vec<Image>,
    view: &WorldView<'_>,
    done: Option<&VoxelSet>,
) -> Result<Vec<EditOp>> {
    let table = view.materials();
    paint.check(false, attach, table)?;
    let mut by_material: BTreeMap<u8, VoxelSet> = BTreeMap::new();
    let mut edits = Vec::new();
    let mut flush = |by: &mut BTreeMap<u8, VoxelSet>| {
        for (m, set) in std::mem::take(by) {
            edits.push(EditOp::Shape {
                shape: Shape::Set(Arc::new(set)),
                mode: if attach { Mode::Add(m) } else { Mode::Paint(m) },
            });
        }
    };
    match paint {
        PaintMode::Solid => return Err(invalid("a solid stroke has no colour edits")),
        PaintMode::Gradient { to } => {
            // Image by image: a later image wins where two overlap, as for solid strokes.
            for image in images {
                let (a, b) = (image.points[0], image.points[image.points.len() - 1]);
                let ab = b - a;
                let len2 = ab.length_squared();
                for v in image.voxels.voxels() {
                    let t = if len2 > 0.0 {
                        ((v.as_dvec3() + 0.5 - a).dot(ab) / len2).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let m = from as f64 + (t * (*to as f64 - from as f64)).round();
                    insert(&mut by_material, m as u8, v);
                }
                flush(&mut by_material);
            }
        }
        PaintMode::Random { among, seed } => {
            for image in images {
                for v in image.voxels.voxels() {
                    let h = hash(v, *seed);
                    insert(&mut by_material, among[h as usize % among.len()], v);
                }
            }
            flush(&mut by_material);
        }
        PaintMode::Darken | PaintMode::Brighten => {
            let next = neighbours(table, *paint == PaintMode::Brighten);
            let mut all = VoxelSet::new();
            for image in images {
                all = all.union(&image.voxels);
            }
            if let Some(done) = done {
                all = all.difference(done);
            }
            for (b, within) in all.iter() {
                let (solid, mats) = view.brick_voxels(b);
                for bit in solid.and(within).ones() {
                    let m = mats[bit];
                    if next[m as usize] != m {
                        let local =
                            IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
                        insert(&mut by_material, next[m as usize], b.as_ivec3() * 8 + local);
                    }
                }
            }
            flush(&mut by_material);
        }
    }
    Ok(edits)
}

fn insert(by: &mut BTreeMap<u8, VoxelSet>, m: u8, v: IVec3) {
    by.entry(m).or_default().insert(v);
}

/// A well-mixed 32-bit hash of a voxel position and a seed (integer avalanche steps; a pure
/// function, the same on every machine).
pub fn hash(v: IVec3, seed: u32) -> u32 {
    let mut h = seed ^ 0x9e37_79b9;
    for c in [v.x, v.y, v.z] {
        h ^= c as u32;
        h = h.wrapping_mul(0x85eb_ca6b);
        h ^= h >> 13;
        h = h.wrapping_mul(0xc2b2_ae35);
        h ^= h >> 16;
    }
    h
}

/// Each material's darker (or, with `brighter`, brighter) table neighbour, itself where
/// neither neighbour is.
pub fn neighbours(table: &MaterialTable, brighter: bool) -> [u8; 256] {
    let luma = |m: u8| -> f64 {
        let Ok(mat) = table.get(m) else { return 0.0 };
        let c = table.colour(mat.colour);
        let lin = |u: u8| {
            let s = u as f64 / 255.0;
            if s <= 0.04045 {
                s / 12.92
            } else {
                ((s + 0.055) / 1.055).powf(2.4)
            }
        };
        0.2126 * lin(c[0]) + 0.7152 * lin(c[1]) + 0.0722 * lin(c[2])
    };
    let mut out = [0u8; 256];
    let n = table.len();
    for (m, o) in out.iter_mut().enumerate() {
        *o = m as u8;
        if m >= n {
            continue;
        }
        let own = luma(m as u8);
        let mut best = (m as u8, own);
        for k in [m.wrapping_sub(1), m + 1] {
            if k >= n {
                continue;
            }
            let l = luma(k as u8);
            if (brighter && l > best.1) || (!brighter && l < best.1) {
                best = (k as u8, l);
            }
        }
        *o = best.0;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use brickmap::Material;

    #[test]
    fn darken_and_brighten_step_to_the_darker_or_brighter_neighbour_or_stay() {
        let mut table = MaterialTable::default();
        // Colours 10, 11, 12: mid grey, dark grey, white; materials 0..3 use them in order.
        table.set_colour(10, [128, 128, 128]);
        table.set_colour(11, [40, 40, 40]);
        table.set_colour(12, [250, 250, 250]);
        while table.len() < 3 {
            table.push(Material::lambertian(0)).unwrap();
        }
        for (m, c) in [(0u8, 10u8), (1, 11), (2, 12)] {
            table.set(m, Material::lambertian(c)).unwrap();
        }
        let dark = neighbours(&table, false);
        let bright = neighbours(&table, true);
        assert_eq!(&dark[..3], &[1, 1, 1], "0 → 1 (darker); 1 stays; 2 → 1");
        assert_eq!(
            &bright[..3],
            &[0, 2, 2],
            "0 stays (its one neighbour is darker); 1 → 2, the brighter of two; 2 stays"
        );
    }

    #[test]
    fn the_hash_spreads_neighbouring_voxels_over_the_choices() {
        let mut counts = [0u32; 4];
        for x in 0..32 {
            for z in 0..32 {
                counts[hash(IVec3::new(x, 5, z), 7) as usize % 4] += 1;
            }
        }
        // 1024 draws over 4: each near 256 (a fixed, deterministic hash).
        assert!(counts.iter().all(|c| (200..=312).contains(c)), "{counts:?}");
        assert_ne!(hash(IVec3::ONE, 1), hash(IVec3::ONE, 2));
    }
}
