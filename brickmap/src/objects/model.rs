//! A model: a voxel grid of its own size, in its own frame, that objects place. Stored sparse
//! as 8³ bricks: a mask and either one material for all its solid voxels or one byte per
//! voxel (a model is edited through the composite, so its store favours simple exact edits
//! over the world's packed GPU layout). A shape over many bricks is computed on every core
//! and committed in order. Edits are the world's `EditOp`s, checked first by the same validation
//! (`edit::validate`) and answered with the same `EditInverse`, so a model edit undoes and
//! redoes exactly as a world edit does; voxels outside the model's box are clipped (shapes)
//! or refused (single voxels, restores).

use crate::brick::{Mask, voxel_bit};
use crate::edit::{
    BrickUndo, EditInverse, EditOp, EditOutcome, Mode, PriorMaterials, VoxelEdit, VoxelOp,
};
use crate::error::{BrickmapError, Result};
use crate::material::MaterialTable;
use crate::voxel_set::box_mask;
use glam::{IVec3, UVec3};
use std::collections::BTreeMap;
use store::BrickStore;

/// The largest model side on each axis (the world's own limits, so a model placed at
/// identity fits the largest grid).
pub const MAX_MODEL_VOXELS: IVec3 = IVec3::new(4096, 1024, 4096);

/// One brick of a model: which voxels are solid and their materials.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModelBrick {
    /// Solid voxels.
    pub mask: Mask,
    materials: BrickMaterials,
}

/// A brick's materials: one for every solid voxel (most bricks inside a solid: 65 bytes), or
/// one per voxel in bit order (0 where empty).
#[derive(Clone, Debug, PartialEq, Eq)]
enum BrickMaterials {
    Uniform(u8),
    PerVoxel(Box<[u8; 512]>),
}

impl ModelBrick {
    /// Every voxel solid with material `m`.
    pub const fn full(m: u8) -> Self {
        Self {
            mask: Mask::FULL,
            materials: BrickMaterials::Uniform(m),
        }
    }

    /// No voxel solid.
    pub const fn empty() -> Self {
        Self {
            mask: Mask::EMPTY,
            materials: BrickMaterials::Uniform(0),
        }
    }

    /// The material of voxel `bit` (meaningful where the mask is set).
    #[inline]
    pub fn material(&self, bit: usize) -> u8 {
        match &self.materials {
            BrickMaterials::Uniform(m) => *m,
            BrickMaterials::PerVoxel(v) => v[bit],
        }
    }

    /// The one material of every solid voxel, if they share one.
    pub fn uniform(&self) -> Option<u8> {
        match self.materials {
            BrickMaterials::Uniform(m) => Some(m),
            BrickMaterials::PerVoxel(_) => None,
        }
    }

    /// Heap and inline bytes it takes.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + match self.materials {
                BrickMaterials::Uniform(_) => 0,
                BrickMaterials::PerVoxel(_) => 512,
            }
    }

    /// A brick of a mask and per-voxel materials, kept uniform when the solid voxels share one.
    fn packed(mask: Mask, per_voxel: Box<[u8; 512]>) -> Self {
        let mut bits = mask.ones();
        let first = bits.next().map(|b| per_voxel[b]);
        let materials = match first {
            Some(m) if bits.all(|b| per_voxel[b] == m) => BrickMaterials::Uniform(m),
            None => BrickMaterials::Uniform(0),
            _ => BrickMaterials::PerVoxel(per_voxel),
        };
        Self { mask, materials }
    }

    fn per_voxel(&self) -> Box<[u8; 512]> {
        match &self.materials {
            BrickMaterials::Uniform(m) => {
                let mut v = Box::new([0u8; 512]);
                for bit in self.mask.ones() {
                    v[bit] = *m;
                }
                v
            }
            BrickMaterials::PerVoxel(v) => v.clone(),
        }
    }
}

/// A model's voxels.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Model {
    size: IVec3,
    /// Non-empty bricks by brick coordinate.
    bricks: BrickStore,
}

/// A model's size refused unless each side is 1..=[`MAX_MODEL_VOXELS`].
fn check_size(size: IVec3) -> Result<()> {
    if size.cmplt(IVec3::ONE).any() || size.cmpgt(MAX_MODEL_VOXELS).any() {
        return Err(BrickmapError::Config(format!(
            "a model of {}×{}×{} voxels: each side is 1..={} × 1..={} × 1..={}",
            size.x, size.y, size.z, MAX_MODEL_VOXELS.x, MAX_MODEL_VOXELS.y, MAX_MODEL_VOXELS.z
        )));
    }
    Ok(())
}

fn key(b: UVec3) -> [u32; 3] {
    b.to_array()
}

impl Model {
    /// An empty model of `size` voxels (each axis 1..=[`MAX_MODEL_VOXELS`]).
    pub fn new(size: IVec3) -> Result<Self> {
        check_size(size)?;
        Ok(Self {
            size,
            bricks: BrickStore::new(((size + 7) / 8).as_uvec3()),
        })
    }

    /// Its size in voxels.
    pub fn size(&self) -> IVec3 {
        self.size
    }

    /// Its size in bricks (rounded up).
    pub fn bricks_size(&self) -> UVec3 {
        ((self.size + 7) / 8).as_uvec3()
    }

    /// The material at `v`, `None` where empty or outside.
    pub fn voxel(&self, v: IVec3) -> Option<u8> {
        if v.cmplt(IVec3::ZERO).any() || v.cmpge(self.size).any() {
            return None;
        }
        let b = self.bricks.get((v / 8).as_uvec3())?;
        let bit = voxel_bit(v.x & 7, v.y & 7, v.z & 7);
        b.mask.get(bit).then(|| b.material(bit))
    }

    /// A brick (`None` where empty).
    pub fn brick(&self, b: UVec3) -> Option<&ModelBrick> {
        self.bricks.get(b)
    }

    /// The non-empty bricks in the world's cell order (`GridDims::cell_index` over the
    /// model's bricks: x, then z, then y fastest).
    pub fn bricks(&self) -> impl Iterator<Item = (UVec3, &ModelBrick)> + '_ {
        self.bricks.iter()
    }

    /// Bytes its bricks take: the brick index (4 bytes a brick cell), the partly filled or
    /// many-material bricks' masks and materials.
    pub fn brick_bytes(&self) -> usize {
        self.bricks.bytes()
    }

    /// Solid voxels.
    pub fn solid_count(&self) -> u64 {
        self.bricks.iter().map(|(_, b)| b.mask.count() as u64).sum()
    }

    /// A hash of the size and every solid voxel with its material (equal content, equal
    /// hash).
    pub fn content_hash(&self) -> u64 {
        let mut h = xxhash_rust::xxh3::Xxh3::new();
        h.update(bytemuck::bytes_of(&self.size.to_array()));
        for (k, b) in self.bricks.iter() {
            h.update(bytemuck::bytes_of(&k.to_array()));
            h.update(bytemuck::bytes_of(&b.mask.0));
            for bit in b.mask.ones() {
                h.update(&[b.material(bit)]);
            }
        }
        h.digest()
    }

    /// The voxels of brick `b` that lie inside the model's box.
    fn inside(&self, b: UVec3) -> Mask {
        let min = b.as_ivec3() * 8;
        box_mask(min, IVec3::ZERO, self.size - 1)
    }

    /// Applies an edit against `table` (the scene's materials): all of it or, on an error,
    /// nothing. Shapes are clipped to the model; a single voxel or a restored brick outside
    /// it is refused; `Generate` fills the model's brick columns.
    pub fn apply(&mut self, op: &EditOp, table: &MaterialTable) -> Result<EditOutcome> {
        crate::edit::validate(op, table, self.size)?;
        let mut undo = Vec::new();
        let changed = match op {
            EditOp::Shape { shape, mode } => {
                let (lo, hi) = shape.voxel_bounds();
                let lo = lo.clamp(IVec3::ZERO, self.size - 1) / 8;
                let hi = hi.clamp(IVec3::ZERO, self.size - 1) / 8;
                let mut list = Vec::new();
                for z in lo.z..=hi.z {
                    for y in lo.y..=hi.y {
                        for x in lo.x..=hi.x {
                            list.push(UVec3::new(x as u32, y as u32, z as u32));
                        }
                    }
                }
                let value = |_: usize, _: Option<u8>| match mode {
                    Mode::Add(m) | Mode::Paint(m) => Some(*m),
                    Mode::Remove => None,
                };
                let paint = matches!(mode, Mode::Paint(_));
                let constant = match mode {
                    Mode::Add(m) => Some(Some(*m)),
                    Mode::Remove => Some(None),
                    Mode::Paint(_) => None,
                };
                let one = |b: &UVec3| {
                    // As the world does: whole bricks inside or outside the shape need no
                    // voxel-by-voxel mask.
                    let region = match shape.coverage(b.as_ivec3() * 8) {
                        crate::shape::Coverage::Outside => return None,
                        crate::shape::Coverage::Inside => Mask::FULL,
                        crate::shape::Coverage::Partial => shape.mask(b.as_ivec3() * 8),
                    };
                    let touched = region.and(&self.inside(*b));
                    match constant {
                        Some(v) => self.rewrite_to(*b, &touched, v),
                        None => self.rewrite(*b, &touched, value, paint),
                    }
                };
                let rewrites = self.on_cores(&list, |b| one(b).into_iter().collect());
                rewrites
                    .into_iter()
                    .map(|r| self.commit(r, &mut undo))
                    .sum()
            }
            EditOp::Voxels(list) => self.apply_voxels(list, &mut undo),
            EditOp::Restore(inv) => {
                for u in &inv.bricks {
                    if !u.touched.and_not(&self.inside(u.brick)).is_empty() {
                        return Err(BrickmapError::BadInverse("voxels outside the model"));
                    }
                }
                let mut changed = 0;
                for u in &inv.bricks {
                    if let Some(r) = self.restore_uniform(u) {
                        changed += r.map_or(0, |r| self.commit(r, &mut undo));
                        continue;
                    }
                    let prior = u.prior_mask.and(&u.touched);
                    changed += self.write(
                        u.brick,
                        &u.touched,
                        &mut undo,
                        |bit, _| prior.get(bit).then(|| u.prior_material(prior.rank(bit))),
                        false,
                    );
                }
                changed
            }
            EditOp::Generate(g) => {
                let n = self.bricks_size();
                let columns: Vec<(u32, u32)> = (0..n.z)
                    .flat_map(|bz| (0..n.x).map(move |bx| (bx, bz)))
                    .collect();
                // A column's bricks: what is emitted, and empty where it emits nothing
                // (clipped to the model; materials ranked in the emitted mask).
                let column = |&(bx, bz): &(u32, u32)| {
                    let mut emitted: BTreeMap<u32, (Mask, PriorMaterials)> = BTreeMap::new();
                    g.0.column(bx, bz, &mut |by, mask, mats| {
                        if by < n.y {
                            emitted.insert(by, (mask, mats));
                        }
                    });
                    (0..n.y)
                        .filter_map(|by| {
                            let b = UVec3::new(bx, by, bz);
                            let (full, mats) = emitted
                                .remove(&by)
                                .unwrap_or((Mask::EMPTY, PriorMaterials::Uniform(0)));
                            if full.is_empty() && !self.bricks.contains(b) {
                                return None;
                            }
                            let inside = self.inside(b);
                            let mask = full.and(&inside);
                            let probe = BrickUndo {
                                brick: b,
                                prior_mask: full,
                                touched: Mask::FULL,
                                prior: mats,
                            };
                            let value = |bit: usize, _: Option<u8>| {
                                mask.get(bit).then(|| probe.prior_material(full.rank(bit)))
                            };
                            self.rewrite(b, &inside, value, false)
                        })
                        .collect::<Vec<_>>()
                };
                let rewrites = self.on_cores(&columns, column);
                rewrites
                    .into_iter()
                    .map(|r| self.commit(r, &mut undo))
                    .sum()
            }
        };
        Ok(EditOutcome {
            inverse: EditInverse { bricks: undo },
            changed_voxels: changed,
        })
    }

    fn apply_voxels(&mut self, list: &[VoxelEdit], undo: &mut Vec<BrickUndo>) -> u64 {
        // Per brick, in cell order; each voxel's writes composed in list order (a later write
        // wins; a paint paints what the earlier writes left).
        let mut per: BTreeMap<[u32; 3], Box<[Option<VoxelOp>; 512]>> = BTreeMap::new();
        for e in list {
            let bit = voxel_bit(e.pos.x & 7, e.pos.y & 7, e.pos.z & 7);
            let slot = &mut per
                .entry(key((e.pos / 8).as_uvec3()))
                .or_insert_with(|| Box::new([None; 512]))[bit];
            *slot = Some(match (*slot, e.op) {
                (Some(VoxelOp::Set(_)), VoxelOp::Paint(m)) => VoxelOp::Set(m),
                (Some(VoxelOp::Clear), VoxelOp::Paint(_)) => VoxelOp::Clear,
                (_, op) => op,
            });
        }
        let mut changed = 0;
        for (k, ops) in per {
            let mut touched = Mask::EMPTY;
            for (bit, op) in ops.iter().enumerate() {
                if op.is_some() {
                    touched.set(bit);
                }
            }
            let new = |bit: usize, now: Option<u8>| match ops[bit] {
                Some(VoxelOp::Set(m)) => Some(m),
                Some(VoxelOp::Clear) => None,
                Some(VoxelOp::Paint(m)) => now.map(|_| m),
                None => now,
            };
            changed += self.write(UVec3::from_array(k), &touched, undo, new, false);
        }
        changed
    }

    /// Rewrites the `touched` voxels of brick `b` with `new(bit, current)` (`None`: empty;
    /// with `paint_only` an empty voxel stays empty), records the brick's undo when anything
    /// changed, and returns the voxels changed.
    fn write(
        &mut self,
        b: UVec3,
        touched: &Mask,
        undo: &mut Vec<BrickUndo>,
        new: impl Fn(usize, Option<u8>) -> Option<u8>,
        paint_only: bool,
    ) -> u64 {
        match self.rewrite(b, touched, new, paint_only) {
            Some(r) => self.commit(r, undo),
            None => 0,
        }
    }

    /// Rewrites computed for each item (independent bricks or columns), on every core when
    /// there are at least [`PARALLEL_BRICKS`] items: contiguous chunks joined in order, so
    /// the result is the same whatever the core count.
    fn on_cores<T: Sync>(
        &self,
        items: &[T],
        each: impl Fn(&T) -> Vec<Rewrite> + Sync,
    ) -> Vec<Rewrite> {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        if items.len() < PARALLEL_BRICKS || threads < 2 {
            return items.iter().flat_map(&each).collect();
        }
        let chunk = items.len().div_ceil(threads);
        let each = &each;
        std::thread::scope(|s| {
            let parts: Vec<_> = items
                .chunks(chunk)
                .map(|part| s.spawn(move || part.iter().flat_map(each).collect::<Vec<_>>()))
                .collect();
            parts
                .into_iter()
                .flat_map(|h| h.join().expect("model threads do not panic"))
                .collect()
        })
    }

    /// What [`Model::write`] would do to brick `b`, computed without changing anything
    /// (`None`: nothing would change).
    fn rewrite(
        &self,
        b: UVec3,
        touched: &Mask,
        new: impl Fn(usize, Option<u8>) -> Option<u8>,
        paint_only: bool,
    ) -> Option<Rewrite> {
        if touched.is_empty() {
            return None;
        }
        crate::census::voxel_brick();
        let empty = ModelBrick {
            mask: Mask::EMPTY,
            materials: BrickMaterials::Uniform(0),
        };
        let old = self.bricks.get(b).unwrap_or(&empty);
        let mut mask = old.mask;
        let mut mats = old.per_voxel();
        let mut changed = 0;
        for bit in touched.ones() {
            let now = old.mask.get(bit).then(|| old.material(bit));
            let v = if paint_only && now.is_none() {
                None
            } else {
                new(bit, now)
            };
            if v != now {
                changed += 1;
            }
            match v {
                Some(m) => {
                    mask.set(bit);
                    mats[bit] = m;
                }
                None => {
                    mask.clear(bit);
                    mats[bit] = 0;
                }
            }
        }
        if changed == 0 {
            return None;
        }
        let held = old.mask.and(touched);
        let prior = match old.uniform() {
            Some(m) => PriorMaterials::Uniform(m),
            None => PriorMaterials::packed(held.ones().map(|bit| old.material(bit)).collect()),
        };
        Some(Rewrite {
            undo: BrickUndo {
                brick: b,
                prior_mask: old.mask,
                touched: *touched,
                prior,
            },
            brick: (!mask.is_empty()).then(|| ModelBrick::packed(mask, mats)),
            changed,
        })
    }

    /// [`Model::rewrite`] of every touched voxel to one value (`None`: empty), a mask at a
    /// time where the brick holds one material (most bricks a shape covers); else voxel by
    /// voxel.
    fn rewrite_to(&self, b: UVec3, touched: &Mask, v: Option<u8>) -> Option<Rewrite> {
        let old = self.bricks.get(b);
        let (old_mask, u) = match old {
            None => (Mask::EMPTY, 0),
            Some(o) => match o.uniform() {
                Some(u) => (o.mask, u),
                None => return self.rewrite(b, touched, |_, _| v, false),
            },
        };
        if touched.is_empty() {
            return None;
        }
        let held = old_mask.and(touched);
        let (mask, materials, changed) = match v {
            Some(m) => {
                let mask = old_mask.or(touched);
                let recoloured = if u == m { 0 } else { held.count() };
                let changed = touched.and_not(&old_mask).count() + recoloured;
                let kept = old_mask.and_not(touched);
                let materials = if u == m || kept.is_empty() {
                    BrickMaterials::Uniform(m)
                } else {
                    let mut per = Box::new([0u8; 512]);
                    kept.ones().for_each(|bit| per[bit] = u);
                    touched.ones().for_each(|bit| per[bit] = m);
                    BrickMaterials::PerVoxel(per)
                };
                (mask, materials, changed)
            }
            None => (
                old_mask.and_not(touched),
                BrickMaterials::Uniform(u),
                held.count(),
            ),
        };
        if changed == 0 {
            return None;
        }
        Some(Rewrite {
            undo: BrickUndo {
                brick: b,
                prior_mask: old_mask,
                touched: *touched,
                prior: PriorMaterials::Uniform(u),
            },
            brick: (!mask.is_empty()).then_some(ModelBrick { mask, materials }),
            changed: changed as u64,
        })
    }

    /// A brick restore a mask at a time, where the brick and the restored voxels each hold
    /// one material (what pastes, moves and imports mostly write); `None` where it does not
    /// apply (then voxel by voxel), `Some(None)` where nothing changes.
    fn restore_uniform(&self, u: &BrickUndo) -> Option<Option<Rewrite>> {
        let PriorMaterials::Uniform(p) = u.prior else {
            return self.restore_into_empty(u);
        };
        let (old_mask, c) = match self.bricks.get(u.brick) {
            None => (Mask::EMPTY, 0),
            Some(o) => (o.mask, o.uniform()?),
        };
        let touched = u.touched;
        let set = u.prior_mask.and(&touched);
        let kept = old_mask.and_not(&touched);
        let mask = kept.or(&set);
        let flipped = Mask(std::array::from_fn(|i| old_mask.0[i] ^ set.0[i])).and(&touched);
        let recoloured = if c == p {
            0
        } else {
            old_mask.and(&set).count()
        };
        let changed = flipped.count() + recoloured;
        if changed == 0 {
            return Some(None);
        }
        let materials = if set.is_empty() || c == p {
            BrickMaterials::Uniform(if set.is_empty() { c } else { p })
        } else if kept.is_empty() {
            BrickMaterials::Uniform(p)
        } else {
            let mut per = Box::new([0u8; 512]);
            kept.ones().for_each(|bit| per[bit] = c);
            set.ones().for_each(|bit| per[bit] = p);
            BrickMaterials::PerVoxel(per)
        };
        Some(Some(Rewrite {
            undo: BrickUndo {
                brick: u.brick,
                prior_mask: old_mask,
                touched,
                prior: PriorMaterials::Uniform(c),
            },
            brick: (!mask.is_empty()).then_some(ModelBrick { mask, materials }),
            changed: changed as u64,
        }))
    }

    /// A brick restore with per-voxel materials into an empty brick (a model being built):
    /// the restored voxels are the brick. `None` where the brick holds voxels.
    fn restore_into_empty(&self, u: &BrickUndo) -> Option<Option<Rewrite>> {
        if self.bricks.contains(u.brick) {
            return None;
        }
        let set = u.prior_mask.and(&u.touched);
        if set.is_empty() {
            return Some(None);
        }
        let mut per = Box::new([0u8; 512]);
        for (k, bit) in set.ones().enumerate() {
            per[bit] = u.prior_material(k);
        }
        Some(Some(Rewrite {
            undo: BrickUndo {
                brick: u.brick,
                prior_mask: Mask::EMPTY,
                touched: u.touched,
                prior: PriorMaterials::Uniform(0),
            },
            brick: Some(ModelBrick::packed(set, per)),
            changed: set.count() as u64,
        }))
    }

    /// Stores a computed rewrite and records its undo; returns the voxels changed.
    fn commit(&mut self, r: Rewrite, undo: &mut Vec<BrickUndo>) -> u64 {
        match r.brick {
            Some(b) => self.bricks.insert(r.undo.brick, b),
            None => self.bricks.remove(r.undo.brick),
        }
        undo.push(r.undo);
        r.changed
    }
}

/// Shapes over at least this many bricks (generators: columns) are computed on every core.
const PARALLEL_BRICKS: usize = 256;

/// One brick's new content, its undo and the voxels it changes.
struct Rewrite {
    undo: BrickUndo,
    brick: Option<ModelBrick>,
    changed: u64,
}

mod build;
mod store;
#[cfg(test)]
mod tests;
