//! Selection: a region of the grid built from boxes added and subtracted in order (what a
//! drag with or without modifiers makes), its voxels (`brickmap::VoxelSet`, computed once per
//! change), and what the editor does with it: delete, fill, paint, move, copy, cut and paste.
//! A selection is a region of space, empty voxels included (fill makes them solid); move,
//! copy and cut take its solid voxels. Moving and pasting put voxels down over what is there
//! (empty clipboard voxels leave the destination alone); what lands outside the grid is lost,
//! and undo brings it back. The selection moves with what it moved and becomes what was
//! pasted.
//!
//! In detail:
//! `Region` (boxes added and subtracted in order; corners may leave the grid), `SelectOp`,
//! `Selection` (region + its `VoxelSet`, computed once per change), `Clip` (the copied solid
//! voxels per source brick, relative to the copy's minimum corner), and the one `Restore` edit
//! a move or a paste is (each target brick written once, so the inverse is the world's exact
//! sparse one; a shifted brick straddles at most 2×2×2 targets). A selection is a region of
//! space: fill makes its empty voxels solid; move / copy / cut take its solid voxels; what
//! lands outside the grid is lost and undo brings it back. `Scene` keeps the session's
//! selection and clipboard (never saved; the editor carries the clipboard to the next
//! document). Outside `editor/` so `scene.rs` can hold it without an import loop.

use crate::wand::Combine;
use brickmap::{BrickUndo, EditInverse, EditOp, Mask, PriorMaterials, VoxelSet, WorldView};
use glam::{IVec3, UVec3};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::Arc;

/// One box of a region.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RegionBox {
    /// Inclusive minimum corner.
    pub min: IVec3,
    /// Inclusive maximum corner.
    pub max: IVec3,
    /// Taken away from what the boxes before it selected.
    pub subtract: bool,
}

/// Boxes added and subtracted in order. Corners may lie outside the grid (a moved
/// selection); only voxels inside it are selected.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Region {
    /// Voxels chosen as a set (a magic wand, by material, inverted, grown, shrunk), before
    /// the boxes apply. Not saved in scripts: their steps compute it again.
    #[serde(skip)]
    pub base: Option<Arc<VoxelSet>>,
    /// The boxes, applied in order.
    pub boxes: Vec<RegionBox>,
}

impl Region {
    /// The region moved by `offset`.
    pub fn translated(&self, offset: IVec3) -> Region {
        Region {
            base: self.base.as_ref().map(|b| Arc::new(b.shifted(offset))),
            boxes: self
                .boxes
                .iter()
                .map(|b| RegionBox {
                    min: b.min + offset,
                    max: b.max + offset,
                    ..*b
                })
                .collect(),
        }
    }

    /// The region's voxels inside a grid of `voxels`.
    pub fn voxels(&self, voxels: IVec3) -> VoxelSet {
        let mut set = VoxelSet::new();
        if let Some(base) = &self.base {
            // Whole bricks: a grid is a whole number of them.
            let bricks = (voxels / 8).as_uvec3();
            for (b, m) in base.iter() {
                if b.cmplt(bricks).all() {
                    set.set_brick(b, *m);
                }
            }
        }
        for b in &self.boxes {
            set.apply_box(b.min, b.max, voxels, b.subtract);
        }
        set
    }
}

/// How a box drag changes the selection.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SelectOp {
    /// The box becomes the selection.
    Replace {
        /// A corner.
        min: IVec3,
        /// The opposite corner.
        max: IVec3,
    },
    /// The box is added (Shift).
    Add {
        /// A corner.
        min: IVec3,
        /// The opposite corner.
        max: IVec3,
    },
    /// The box is taken away (Ctrl).
    Subtract {
        /// A corner.
        min: IVec3,
        /// The opposite corner.
        max: IVec3,
    },
    /// Only the selected voxels inside the box stay (Shift + Ctrl).
    Intersect {
        /// A corner.
        min: IVec3,
        /// The opposite corner.
        max: IVec3,
    },
    /// The whole grid.
    All,
    /// Nothing.
    None,
    /// The magic wand from `start` ([`crate::wand::wand`]).
    Wand {
        /// The clicked voxel.
        start: IVec3,
        /// Only voxels of its material (else every solid voxel).
        by_material: bool,
        /// Connected through edges and corners too (26), not only faces (6).
        diagonal: bool,
        /// How it combines with the selection.
        how: Combine,
    },
    /// The face wand from the face of `start` facing `normal` ([`crate::wand::face_region`]).
    Face {
        /// The clicked voxel.
        start: IVec3,
        /// The clicked face's normal (one axis, ±1).
        normal: IVec3,
        /// Only voxels of its material.
        by_material: bool,
        /// Joined through corners in the plane too, not only edges.
        diagonal: bool,
        /// How it combines with the selection.
        how: Combine,
    },
    /// A rectangle on the screen, through all depth or visible voxels only
    /// ([`crate::rect_select`]).
    Rect {
        /// The rectangle and the view it was dragged in.
        rect: Box<crate::rect_select::ScreenRect>,
        /// How it combines with the selection.
        how: Combine,
    },
    /// Every voxel of a material.
    Material {
        /// The material.
        material: u8,
        /// How it combines with the selection.
        how: Combine,
    },
    /// Every voxel of the grid that is not selected.
    Invert,
    /// One voxel more on every side (through faces).
    Grow,
    /// One voxel less on every side.
    Shrink,
}

/// A region and its voxels (shared: edits and the viewport read it without copying).
#[derive(Clone, Debug, PartialEq)]
pub struct Selection {
    /// What was selected, as boxes.
    pub region: Region,
    /// Its voxels inside the grid.
    pub voxels: Arc<VoxelSet>,
}

impl Selection {
    /// The selection of a region in a grid of `voxels`.
    pub fn new(region: Region, voxels: IVec3) -> Self {
        let set = region.voxels(voxels);
        Selection {
            region,
            voxels: Arc::new(set),
        }
    }
}

/// The selection after `op` on the voxels of `view` (None: nothing selected).
pub fn select(
    current: Option<&Selection>,
    op: SelectOp,
    view: &WorldView<'_>,
) -> Option<Selection> {
    let voxels = view.dims().voxels();
    let boxed = |a: IVec3, b: IVec3, subtract| RegionBox {
        min: a.min(b),
        max: a.max(b),
        subtract,
    };
    let mut region = current.map(|s| s.region.clone()).unwrap_or_default();
    match op {
        SelectOp::None => return None,
        SelectOp::All => {
            region = Region {
                base: None,
                boxes: vec![boxed(IVec3::ZERO, voxels - 1, false)],
            }
        }
        SelectOp::Replace { min, max } => {
            region = Region {
                base: None,
                boxes: vec![boxed(min, max, false)],
            }
        }
        SelectOp::Add { min, max } => region.boxes.push(boxed(min, max, false)),
        SelectOp::Subtract { min, max } => {
            // Nothing selected stays nothing.
            current?;
            region.boxes.push(boxed(min, max, true));
        }
        // The set-based ones: the result becomes the region's set, without boxes.
        _ => {
            let now = current.map(|s| s.voxels.as_ref());
            let set = match op {
                SelectOp::Wand {
                    start,
                    by_material,
                    diagonal,
                    how,
                } => how.apply(now, crate::wand::wand(view, start, by_material, diagonal)),
                SelectOp::Face {
                    start,
                    normal,
                    by_material,
                    diagonal,
                    how,
                } => how.apply(
                    now,
                    crate::wand::face_region(view, start, normal, by_material, diagonal),
                ),
                SelectOp::Rect { rect, how } => {
                    how.apply(now, crate::rect_select::rect_set(view, &rect))
                }
                SelectOp::Intersect { min, max } => {
                    let mut b = VoxelSet::new();
                    b.apply_box(min.min(max), min.max(max), voxels, false);
                    now?.intersection(&b)
                }
                SelectOp::Material { material, how } => {
                    how.apply(now, crate::wand::of_material(view, material))
                }
                SelectOp::Invert => now.map_or_else(
                    || VoxelSet::new().complement(voxels),
                    |s| s.complement(voxels),
                ),
                SelectOp::Grow => now?.grown(voxels),
                SelectOp::Shrink => now?.shrunk(),
                _ => unreachable!("the box operations are above"),
            };
            region = Region {
                base: Some(Arc::new(set)),
                boxes: Vec::new(),
            };
        }
    }
    let selection = Selection::new(region, voxels);
    (!selection.voxels.is_empty()).then_some(selection)
}

/// The solid voxels of a selection, copied: the clipboard.
#[derive(Clone, PartialEq)]
pub struct Clip {
    /// The region they were copied from, relative to `origin`.
    pub region: Region,
    /// The minimum corner of the copied selection's bounds, where the copy came from.
    pub origin: IVec3,
    /// Per source brick: its minimum voxel relative to `origin`, the copied solid voxels and
    /// their materials by voxel index.
    bricks: Vec<(IVec3, Mask, Box<[u8; 512]>)>,
    /// Solid voxels copied.
    pub voxels: u64,
    /// Size of the copied selection's bounds.
    pub size: IVec3,
}

impl std::fmt::Debug for Clip {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Clip({} voxels, {} from {})",
            self.voxels, self.size, self.origin
        )
    }
}

impl Clip {
    /// The copied voxels as bricks of the grid they came from: (brick coordinates, solid
    /// voxels). A paste at `at` puts them `at - origin` further on.
    pub fn source_bricks(&self) -> Vec<(IVec3, Mask)> {
        self.bricks
            .iter()
            .map(|(rel, mask, _)| ((self.origin + *rel).div_euclid(IVec3::splat(8)), *mask))
            .collect()
    }
    /// Every copied solid voxel relative to the copy's minimum corner, with its material.
    pub fn solid_voxels(&self) -> impl Iterator<Item = (IVec3, u8)> + '_ {
        self.bricks.iter().flat_map(|(rel, mask, mats)| {
            mask.ones().map(move |bit| {
                let b = bit as i32;
                (*rel + IVec3::new(b & 7, (b >> 3) & 7, b >> 6), mats[bit])
            })
        })
    }

    /// Copies the solid voxels of `selection` (None when it selects no voxel).
    pub fn copy(view: &WorldView<'_>, selection: &Selection) -> Option<Clip> {
        let (lo, hi) = selection.voxels.bounds()?;
        let mut bricks = Vec::new();
        let mut voxels = 0;
        for (b, sel) in selection.voxels.iter() {
            let (solid, dense) = view.brick_voxels(b);
            let keep = solid.and(sel);
            if keep.is_empty() {
                continue;
            }
            voxels += keep.count() as u64;
            bricks.push((b.as_ivec3() * 8 - lo, keep, Box::new(dense)));
        }
        Some(Clip {
            region: selection.region.translated(-lo),
            origin: lo,
            bricks,
            voxels,
            size: hi - lo + 1,
        })
    }
}

/// Per target brick: voxels written, which of them end solid, and their materials.
#[derive(Default)]
struct Target {
    touched: Mask,
    solid: Mask,
    dense: Option<Box<[u8; 512]>>,
}

/// Builds the one `Restore` edit that writes whole target bricks (each brick once, so its
/// inverse is exact).
#[derive(Default)]
pub(crate) struct Writes {
    targets: HashMap<(u32, u32, u32), Target>,
}

impl Writes {
    /// Makes each voxel `v` of `writes` solid with its material (nothing outside a grid of
    /// `voxels`). Meant for the voxels of one source brick, which land in a few target bricks:
    /// each is gathered here first and joins the edit once.
    pub(crate) fn set_all(&mut self, voxels: IVec3, writes: impl IntoIterator<Item = (IVec3, u8)>) {
        let mut local: Vec<(UVec3, Mask, [u8; 512])> = Vec::with_capacity(8);
        let mut last = 0;
        for (v, m) in writes {
            if v.cmplt(IVec3::ZERO).any() || v.cmpge(voxels).any() {
                continue;
            }
            let b = (v / 8).as_uvec3();
            if local.get(last).is_none_or(|e| e.0 != b) {
                last = match local.iter().position(|e| e.0 == b) {
                    Some(i) => i,
                    None => {
                        local.push((b, Mask::EMPTY, [0; 512]));
                        local.len() - 1
                    }
                };
            }
            let bit = ((v.x & 7) + 8 * (v.y & 7) + 64 * (v.z & 7)) as usize;
            let (_, mask, mats) = &mut local[last];
            mask.set(bit);
            mats[bit] = m;
        }
        for (b, mask, mats) in local {
            let t = self.target(b);
            t.touched = t.touched.or(&mask);
            t.solid = t.solid.or(&mask);
            let dense = t.dense.get_or_insert_with(|| Box::new([0; 512]));
            for bit in mask.ones() {
                dense[bit] = mats[bit];
            }
        }
    }

    /// Adds the writes of `other`, which only puts voxels (no clears) and none where this
    /// puts one: its voxels become solid with their materials.
    pub(crate) fn merge_puts(&mut self, other: Writes) {
        for (key, t) in other.targets {
            let mine = self.targets.entry(key).or_default();
            mine.touched = mine.touched.or(&t.touched);
            mine.solid = mine.solid.or(&t.solid);
            if let Some(d) = t.dense {
                let dense = mine.dense.get_or_insert_with(|| Box::new([0; 512]));
                for bit in t.solid.ones() {
                    dense[bit] = d[bit];
                }
            }
        }
    }

    fn target(&mut self, b: UVec3) -> &mut Target {
        self.targets.entry((b.x, b.y, b.z)).or_default()
    }

    /// Empties the voxels `mask` of brick `b`.
    pub(crate) fn clear(&mut self, b: UVec3, mask: &Mask) {
        let t = self.target(b);
        t.touched = t.touched.or(mask);
        t.solid = t.solid.and_not(mask);
    }

    /// Puts the voxels `mask` (materials by voxel index) of the brick whose minimum voxel is
    /// `min` down shifted by `offset`, dropping those outside a grid of `voxels` (whole
    /// bricks: a grid is a whole number of them). A shifted brick straddles at most 2 × 2 × 2
    /// target bricks; each gets its part a row of 8 voxels at a time (mask bits shifted,
    /// material bytes copied as a slice).
    fn put(&mut self, min: IVec3, mask: &Mask, mats: &[u8; 512], offset: IVec3, voxels: IVec3) {
        let base = min + offset;
        let first = base.div_euclid(IVec3::splat(8));
        let r = base.rem_euclid(IVec3::splat(8));
        let bricks = voxels / 8;
        let row = |y: i32, z: i32| (mask.0[(2 * z + y / 4) as usize] >> (8 * (y & 3))) & 0xFF;
        // The source rows (or columns) that land in the lower (0) or upper (1) target brick.
        let span = |k: i32, r: i32| if k == 0 { 0..8 - r } else { 8 - r..8 };
        for k in 0..8 {
            let k = IVec3::new(k & 1, k >> 1 & 1, k >> 2);
            let tb = first + k;
            let empty = (k.cmpeq(IVec3::ONE) & r.cmpeq(IVec3::ZERO)).any();
            if empty || tb.cmplt(IVec3::ZERO).any() || tb.cmpge(bricks).any() {
                continue;
            }
            // Each row's target bits and where its bytes go.
            let rows = |f: &mut dyn FnMut(u32, usize, usize, usize, usize)| {
                for z in span(k.z, r.z) {
                    let tz = z + r.z - 8 * k.z;
                    for y in span(k.y, r.y) {
                        let src = row(y, z);
                        let ty = y + r.y - 8 * k.y;
                        let (bits, from, to, n) = if k.x == 0 {
                            ((src << r.x) & 0xFF, 0, r.x, 8 - r.x)
                        } else {
                            (src >> (8 - r.x), 8 - r.x, 0, r.x)
                        };
                        if bits != 0 {
                            let word = (2 * tz + ty / 4) as usize;
                            let s = (8 * y + 64 * z + from) as usize;
                            let t = (8 * ty + 64 * tz + to) as usize;
                            f(bits << (8 * (ty & 3)), word, s, t, n as usize);
                        }
                    }
                }
            };
            let mut part = Mask::EMPTY;
            rows(&mut |bits, word, _, _, _| part.0[word] |= bits);
            if part.is_empty() {
                continue;
            }
            let t = self.target(tb.as_uvec3());
            t.touched = t.touched.or(&part);
            t.solid = t.solid.or(&part);
            // Sources never overlap in a target: whole row slices are copied (bytes of empty
            // source voxels land on voxels no other source writes, and are never read).
            let dense = t.dense.get_or_insert_with(|| Box::new([0; 512]));
            rows(&mut |_, _, s, t, n| dense[t..t + n].copy_from_slice(&mats[s..s + n]));
        }
    }

    pub(crate) fn into_edit(self) -> EditOp {
        let mut bricks: Vec<BrickUndo> = self
            .targets
            .into_iter()
            .map(|((x, y, z), t)| {
                let prior = match &t.dense {
                    // Whole bricks of one material are common (terrain interiors): one byte.
                    Some(d) if t.solid.is_full() && d.iter().all(|m| *m == d[0]) => {
                        PriorMaterials::Uniform(d[0])
                    }
                    Some(d) if t.solid.is_full() => PriorMaterials::PerVoxel(d.to_vec()),
                    Some(d) => PriorMaterials::PerVoxel(t.solid.ones().map(|b| d[b]).collect()),
                    None => PriorMaterials::PerVoxel(Vec::new()),
                };
                BrickUndo {
                    brick: UVec3::new(x, y, z),
                    prior_mask: t.solid,
                    touched: t.touched,
                    prior,
                }
            })
            .collect();
        bricks.sort_by_key(|b| (b.brick.x, b.brick.y, b.brick.z));
        EditOp::Restore(EditInverse { bricks })
    }
}

/// The edit that moves the solid voxels of `selection` by `offset` (the selected region is
/// emptied, its solid voxels put down at the new place).
pub fn move_edit(view: &WorldView<'_>, selection: &Selection, offset: IVec3) -> EditOp {
    let voxels = view.dims().voxels();
    let mut w = Writes::default();
    for (b, sel) in selection.voxels.iter() {
        w.clear(b, sel);
    }
    for (b, sel) in selection.voxels.iter() {
        let (solid, dense) = view.brick_voxels(b);
        let keep = solid.and(sel);
        if !keep.is_empty() {
            w.put(b.as_ivec3() * 8, &keep, &dense, offset, voxels);
        }
    }
    w.into_edit()
}

/// The edit that puts the clipboard down with its origin at `at`.
pub fn paste_edit(clip: &Clip, at: IVec3, voxels: IVec3) -> EditOp {
    let mut w = Writes::default();
    for (min, mask, mats) in &clip.bricks {
        w.put(*min, mask, mats, at, voxels);
    }
    w.into_edit()
}
