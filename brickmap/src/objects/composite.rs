//! The composite: the visible objects written into the one `World` the renderers trace.
//!
//! A world brick's content is computed from scratch from every drawn object whose placed box
//! overlaps it, in drawing order, so a later object's solid voxel replaces an earlier one's
//! and empty voxels hide nothing (docs/DESIGN.md, "Objects"). Recomputed bricks are written
//! whole through the world's bulk restore, so the world's workers, dirty ranges and light
//! faces serve the objects unchanged. Only what a change touched is recomputed:
//! [`Composite::model_edited`] the world bricks a model edit's touched bricks land in, in
//! every visible instance; [`Composite::update`] the old and new boxes of the objects whose
//! placement, model or visibility changed (and of the nodes the caller names, for a change of
//! drawing order).
//!
//! The composite is derived state: it is never saved and never undone itself; undoing a model
//! edit or a tree change and then updating the composite gives the same world.

use super::model::Model;
use super::orient::Orientation;
use super::tree::{Drawn, ModelId, NodeId, ObjectTree};
use crate::brick::{Mask, voxel_bit};
use crate::edit::{EditInverse, PriorMaterials};
use crate::error::Result as WorldResult;
use crate::world::World;
use glam::{IVec3, UVec3};
use std::collections::{BTreeMap, BTreeSet, HashMap};

/// Where the composite finds a model.
pub trait ModelSource {
    /// The model, if it exists.
    fn model(&self, id: ModelId) -> Option<&Model>;
}

impl ModelSource for BTreeMap<ModelId, Model> {
    fn model(&self, id: ModelId) -> Option<&Model> {
        self.get(&id)
    }
}

impl ModelSource for HashMap<ModelId, Model> {
    fn model(&self, id: ModelId) -> Option<&Model> {
        self.get(&id)
    }
}

/// Why a composite cannot be built or written; the world is unchanged.
#[derive(Debug, thiserror::Error)]
pub enum CompositeError {
    /// An object places a model that does not exist.
    #[error("object #{} places model {}, which does not exist", .node.0, .model.0)]
    NoModel {
        /// The object.
        node: NodeId,
        /// The model it names.
        model: ModelId,
    },
    /// Objects' placed boxes leave the world's grid.
    #[error(
        "object #{} (with any other outside) covers {lo}..{hi}, outside the {grid} voxel grid",
        .node.0
    )]
    OutsideGrid {
        /// The first object outside.
        node: NodeId,
        /// The lowest cell of the objects outside.
        lo: IVec3,
        /// One past their highest.
        hi: IVec3,
        /// The grid in voxels.
        grid: IVec3,
    },
    /// The world refused the write.
    #[error(transparent)]
    World(#[from] crate::error::BrickmapError),
}

/// Side of a cell of the index of object boxes, in bricks.
const CELL_BRICKS: i32 = 4;

/// One drawn object with what the composite needs of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Entry {
    drawn: Drawn,
    size: IVec3,
    lo: IVec3,
    hi: IVec3,
}

/// The drawn objects of a tree, their boxes, and an index from world regions to the objects
/// overlapping them.
#[derive(Clone, Debug)]
pub struct Composite {
    grid: IVec3,
    entries: Vec<Entry>,
    /// Index cell (CELL_BRICKS³ bricks) → drawing positions of the entries overlapping it,
    /// ascending.
    index: HashMap<[i32; 3], Vec<u32>>,
}

impl Composite {
    /// Bytes it holds on the heap: its entries and the index's region lists.
    pub fn heap_bytes(&self) -> usize {
        self.entries.capacity() * std::mem::size_of::<Entry>()
            + self.index.capacity() * std::mem::size_of::<([i32; 3], Vec<u32>)>()
            + self.index.values().map(|v| v.capacity() * 4).sum::<usize>()
    }

    /// The composite of a tree's visible objects for a world of `grid` voxels. Refuses an
    /// object outside the grid or naming a missing model.
    pub fn new(
        tree: &ObjectTree,
        models: &impl ModelSource,
        grid: IVec3,
    ) -> Result<Self, CompositeError> {
        let mut entries = Vec::new();
        let mut outside: Option<(NodeId, IVec3, IVec3)> = None;
        for drawn in tree.drawn() {
            let model = models.model(drawn.model).ok_or(CompositeError::NoModel {
                node: drawn.node,
                model: drawn.model,
            })?;
            let size = model.size();
            let (lo, hi) = drawn.placement.bounds(size);
            if lo.cmplt(IVec3::ZERO).any() || hi.cmpgt(grid).any() {
                // Every object outside, in one box (a grid that holds it holds them all).
                outside = Some(match outside {
                    None => (drawn.node, lo, hi),
                    Some((node, a, b)) => (node, a.min(lo), b.max(hi)),
                });
                continue;
            }
            entries.push(Entry {
                drawn,
                size,
                lo,
                hi,
            });
        }
        if let Some((node, lo, hi)) = outside {
            return Err(CompositeError::OutsideGrid { node, lo, hi, grid });
        }
        let mut index: HashMap<[i32; 3], Vec<u32>> = HashMap::new();
        for (i, e) in entries.iter().enumerate() {
            let (a, b) = (e.lo / (8 * CELL_BRICKS), (e.hi - 1) / (8 * CELL_BRICKS));
            for z in a.z..=b.z {
                for y in a.y..=b.y {
                    for x in a.x..=b.x {
                        index.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        Ok(Self {
            grid,
            entries,
            index,
        })
    }

    /// The model of the only drawn object when it places it unrotated at the origin and
    /// it fills the grid (a flat scene): the world is then the model, voxel for voxel, and
    /// an edit of the model is the same edit of the world.
    pub fn flat(&self) -> Option<ModelId> {
        match self.entries.as_slice() {
            [e] if e.lo == IVec3::ZERO
                && e.size == self.grid
                && e.drawn.placement.rot == super::orient::Orientation::IDENTITY =>
            {
                Some(e.drawn.model)
            }
            _ => None,
        }
    }

    /// The drawn object whose voxel shows at world cell `v` (the last in drawing order
    /// holding one there), if any.
    pub fn object_at(&self, v: IVec3, models: &impl ModelSource) -> Option<NodeId> {
        if v.cmplt(IVec3::ZERO).any() {
            return None;
        }
        let cell = (v / (8 * CELL_BRICKS)).to_array();
        self.index.get(&cell)?.iter().rev().find_map(|&i| {
            let e = &self.entries[i as usize];
            let inside = v.cmpge(e.lo).all() && v.cmplt(e.hi).all();
            let model = models.model(e.drawn.model)?;
            (inside && model.voxel(e.drawn.placement.unplace(v, e.size)).is_some())
                .then_some(e.drawn.node)
        })
    }

    /// The drawn objects, in drawing order.
    pub fn drawn(&self) -> impl Iterator<Item = Drawn> + '_ {
        self.entries.iter().map(|e| e.drawn)
    }

    /// The content of world brick `b`: solid voxels and their materials (0 where empty).
    pub fn brick(&self, b: UVec3, models: &impl ModelSource) -> (Mask, Box<[u8; 512]>) {
        let mut mask = Mask::EMPTY;
        let mut mats = Box::new([0u8; 512]);
        let min = b.as_ivec3() * 8;
        let max = min + 7;
        let cell = (b.as_ivec3() / CELL_BRICKS).to_array();
        let Some(list) = self.index.get(&cell) else {
            return (mask, mats);
        };
        for &i in list {
            let e = &self.entries[i as usize];
            let lo = e.lo.max(min);
            let hi = (e.hi - 1).min(max);
            if lo.cmpgt(hi).any() {
                continue;
            }
            let Some(model) = models.model(e.drawn.model) else {
                continue;
            };
            let p = e.drawn.placement;
            // At identity, model voxel v lands at v + offset.
            let offset = p.t - e.size / 2;
            if p.rot == Orientation::IDENTITY && offset % 8 == IVec3::ZERO {
                // Brick-aligned: the model brick is the world brick, copied whole (a model's
                // voxels outside its size are never solid).
                if let Some(mb) = model.brick((min - offset).as_uvec3() / 8) {
                    mask = mask.or(&mb.mask);
                    for bit in mb.mask.ones() {
                        mats[bit] = mb.material(bit);
                    }
                }
                continue;
            }
            if p.rot == Orientation::IDENTITY {
                // Moved by whole voxels: each model brick this world brick overlaps, its mask
                // shifted into place (a model's voxels outside its size are never solid, so
                // every bit lands inside the object's box).
                let (ma, mb) = ((lo - offset) / 8, (hi - offset) / 8);
                for z in ma.z..=mb.z {
                    for y in ma.y..=mb.y {
                        for x in ma.x..=mb.x {
                            let at = IVec3::new(x, y, z);
                            let Some(brick) = model.brick(at.as_uvec3()) else {
                                continue;
                            };
                            let o = at * 8 + offset - min;
                            let moved = brick.mask.shifted(o);
                            let shift = (o.x + 8 * o.y + 64 * o.z) as isize;
                            for bit in moved.ones() {
                                mats[bit] = brick.material((bit as isize - shift) as usize);
                            }
                            mask = mask.or(&moved);
                        }
                    }
                }
                continue;
            }
            // Along a world row (+x) the model voxel steps ±1 along one model axis: walk it,
            // looking a model brick up only when the walk enters another one.
            let d = p.rot.inverse().apply(IVec3::X);
            let axis = (0..3).find(|&i| d[i] != 0).expect("a unit vector");
            let step = d[axis];
            let bit_step = [1isize, 8, 64][axis] * step as isize;
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    // Every voxel of lo..=hi lies in the object's box: v is inside the model.
                    let mut v = p.unplace(IVec3::new(lo.x, y, z), e.size);
                    let mut mb = model.brick((v / 8).as_uvec3());
                    let mut from = voxel_bit(v.x & 7, v.y & 7, v.z & 7) as isize;
                    let row = voxel_bit(0, y & 7, z & 7);
                    for x in lo.x..=hi.x {
                        if let Some(b) = mb
                            && b.mask.get(from as usize)
                        {
                            let bit = row + (x & 7) as usize;
                            mask.set(bit);
                            mats[bit] = b.material(from as usize);
                        }
                        if x == hi.x {
                            break;
                        }
                        let before = v[axis] >> 3;
                        v[axis] += step;
                        if v[axis] >> 3 != before {
                            mb = model.brick((v / 8).as_uvec3());
                            from = voxel_bit(v.x & 7, v.y & 7, v.z & 7) as isize;
                        } else {
                            from += bit_step;
                        }
                    }
                }
            }
        }
        (mask, mats)
    }

    /// A brick's content as the world's bulk write takes it, or `None` where the world holds
    /// exactly that already.
    fn changed(
        &self,
        b: UVec3,
        models: &(impl ModelSource + Sync),
        view: &crate::world::WorldView<'_>,
    ) -> Option<(UVec3, Mask, PriorMaterials)> {
        let (mask, mats) = self.brick(b, models);
        let (now_mask, now) = view.brick_voxels(b);
        if now_mask == mask && mask.ones().all(|bit| now[bit] == mats[bit]) {
            return None;
        }
        let prior = PriorMaterials::packed(mask.ones().map(|bit| mats[bit]).collect());
        Some((b, mask, prior))
    }

    /// Recomputes world bricks and writes those whose content differs, whole; returns the
    /// world's inverse (which the caller may drop: the composite is derived).
    pub fn write(
        &self,
        world: &World,
        bricks: &BTreeSet<[u32; 3]>,
        models: &(impl ModelSource + Sync),
    ) -> WorldResult<EditInverse> {
        let list: Vec<UVec3> = bricks.iter().map(|k| UVec3::from_array(*k)).collect();
        crate::census::composited(list.len() as u64);
        // Bricks are independent: computed on as many threads as the world has workers, in
        // contiguous chunks joined in order (the same result whatever the count).
        let threads = world.workers().clamp(1, list.len().max(1));
        let chunk = list.len().div_ceil(threads).max(1);
        let view = world.read();
        let contents: Vec<_> = std::thread::scope(|s| {
            let view = &view;
            let parts: Vec<_> = list
                .chunks(chunk)
                .map(|part| {
                    s.spawn(move || {
                        part.iter()
                            .filter_map(|b| self.changed(*b, models, view))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            parts
                .into_iter()
                .flat_map(|h| h.join().expect("composite threads do not panic"))
                .collect()
        });
        // The readers' locks go before the write takes the slabs.
        drop(view);
        if contents.is_empty() {
            return Ok(EditInverse::default());
        }
        Ok(world.apply(crate::terrain::set_bricks(contents))?.inverse)
    }

    /// The model drawn where it is the whole world: one drawn object, unturned, whose model
    /// fills the grid exactly, so the world is that model's voxels brick for brick (what
    /// [`super::Objects::of_world`] makes).
    pub fn sole_cover(&self) -> Option<ModelId> {
        match self.entries.as_slice() {
            [e] if e.drawn.placement.rot == Orientation::IDENTITY
                && e.lo == IVec3::ZERO
                && e.hi == self.grid
                && e.size == self.grid =>
            {
                Some(e.drawn.model)
            }
            _ => None,
        }
    }

    /// Every world brick the composite covers (for a first write into an empty world).
    pub fn all_bricks(&self) -> BTreeSet<[u32; 3]> {
        let mut out = BTreeSet::new();
        for e in &self.entries {
            add_box(&mut out, e.lo, e.hi);
        }
        out
    }

    /// After a model edit (its inverse names the touched model bricks): rewrites the world
    /// bricks they land in, in every drawn instance.
    pub fn model_edited(
        &self,
        world: &World,
        models: &(impl ModelSource + Sync),
        model: ModelId,
        edit: &EditInverse,
    ) -> WorldResult<EditInverse> {
        let mut bricks = BTreeSet::new();
        for e in self.entries.iter().filter(|e| e.drawn.model == model) {
            for u in &edit.bricks {
                let a = (u.brick.as_ivec3() * 8).min(e.size - 1);
                let b = (u.brick.as_ivec3() * 8 + 7).min(e.size - 1);
                let (pa, pb) = (
                    e.drawn.placement.place(a, e.size),
                    e.drawn.placement.place(b, e.size),
                );
                add_box(&mut bricks, pa.min(pb), pa.max(pb) + 1);
            }
        }
        self.write(world, &bricks, models)
    }

    /// Replaces this composite by the one of the tree as it is now and rewrites the world
    /// bricks that may differ: the old and new boxes of every object that appeared,
    /// disappeared, or changed model or placement, and of the `also` nodes (objects whose
    /// place in the drawing order changed). The world is unchanged on an error.
    pub fn update(
        &mut self,
        world: &World,
        tree: &ObjectTree,
        models: &(impl ModelSource + Sync),
        also: &[NodeId],
    ) -> Result<EditInverse, CompositeError> {
        let next = Composite::new(tree, models, self.grid)?;
        let old: HashMap<NodeId, &Entry> = self.entries.iter().map(|e| (e.drawn.node, e)).collect();
        let new: HashMap<NodeId, &Entry> = next.entries.iter().map(|e| (e.drawn.node, e)).collect();
        let mut bricks = BTreeSet::new();
        for (map, other) in [(&old, &new), (&new, &old)] {
            for (node, e) in map {
                let same = other
                    .get(node)
                    .is_some_and(|o| o.drawn == e.drawn && o.size == e.size);
                if !same || also.contains(node) {
                    add_box(&mut bricks, e.lo, e.hi);
                }
            }
        }
        let inverse = next.write(world, &bricks, models)?;
        *self = next;
        Ok(inverse)
    }
}

/// Adds the world bricks that voxel box lo..hi (exclusive) touches.
fn add_box(out: &mut BTreeSet<[u32; 3]>, lo: IVec3, hi: IVec3) {
    let (a, b) = (lo / 8, (hi - 1) / 8);
    for z in a.z..=b.z {
        for y in a.y..=b.y {
            for x in a.x..=b.x {
                out.insert([x as u32, y as u32, z as u32]);
            }
        }
    }
}

#[cfg(test)]
mod tests;
