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
    /// Non-empty bricks by brick coordinate (x, y, z), in that order.
    bricks: BTreeMap<[u32; 3], ModelBrick>,
}

fn key(b: UVec3) -> [u32; 3] {
    b.to_array()
}

impl Model {
    /// An empty model of `size` voxels (each axis 1..=[`MAX_MODEL_VOXELS`]).
    pub fn new(size: IVec3) -> Result<Self> {
        if size.cmplt(IVec3::ONE).any() || size.cmpgt(MAX_MODEL_VOXELS).any() {
            return Err(BrickmapError::Config(format!(
                "a model of {}×{}×{} voxels: each side is 1..={} × 1..={} × 1..={}",
                size.x, size.y, size.z, MAX_MODEL_VOXELS.x, MAX_MODEL_VOXELS.y, MAX_MODEL_VOXELS.z
            )));
        }
        Ok(Self {
            size,
            bricks: BTreeMap::new(),
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
        let b = self.bricks.get(&key((v / 8).as_uvec3()))?;
        let bit = voxel_bit(v.x & 7, v.y & 7, v.z & 7);
        b.mask.get(bit).then(|| b.material(bit))
    }

    /// A brick (`None` where empty).
    pub fn brick(&self, b: UVec3) -> Option<&ModelBrick> {
        self.bricks.get(&key(b))
    }

    /// The non-empty bricks in (x, y, z) order.
    pub fn bricks(&self) -> impl Iterator<Item = (UVec3, &ModelBrick)> + '_ {
        self.bricks.iter().map(|(k, b)| (UVec3::from_array(*k), b))
    }

    /// Bytes its bricks take (masks, materials, the map's keys), without the map's own nodes.
    pub fn brick_bytes(&self) -> usize {
        self.bricks.values().map(|b| b.bytes() + 12).sum()
    }

    /// Solid voxels.
    pub fn solid_count(&self) -> u64 {
        self.bricks.values().map(|b| b.mask.count() as u64).sum()
    }

    /// A hash of the size and every solid voxel with its material (equal content, equal
    /// hash).
    pub fn content_hash(&self) -> u64 {
        let mut h = xxhash_rust::xxh3::Xxh3::new();
        h.update(bytemuck::bytes_of(&self.size.to_array()));
        for (k, b) in &self.bricks {
            h.update(bytemuck::bytes_of(k));
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
                let one = |b: &UVec3| {
                    let touched = shape.mask(b.as_ivec3() * 8).and(&self.inside(*b));
                    self.rewrite(*b, &touched, value, paint)
                };
                // Bricks are independent: a large shape is computed on every core in
                // contiguous chunks joined in order, then committed in that order.
                let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
                let rewrites: Vec<Rewrite> = if list.len() < PARALLEL_BRICKS || threads < 2 {
                    list.iter().filter_map(one).collect()
                } else {
                    let chunk = list.len().div_ceil(threads);
                    std::thread::scope(|s| {
                        let parts: Vec<_> = list
                            .chunks(chunk)
                            .map(|part| {
                                s.spawn(move || part.iter().filter_map(one).collect::<Vec<_>>())
                            })
                            .collect();
                        parts
                            .into_iter()
                            .flat_map(|h| h.join().expect("model threads do not panic"))
                            .collect()
                    })
                };
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
                let mut emitted: BTreeMap<[u32; 3], (Mask, PriorMaterials)> = BTreeMap::new();
                for bz in 0..n.z {
                    for bx in 0..n.x {
                        g.0.column(bx, bz, &mut |by, mask, mats| {
                            if by < n.y {
                                emitted.insert([bx, by, bz], (mask, mats));
                            }
                        });
                    }
                }
                // Every brick: what was there or what is emitted, whichever is non-empty.
                let mut cells: Vec<[u32; 3]> = self.bricks.keys().copied().collect();
                cells.extend(emitted.keys().copied());
                cells.sort_unstable();
                cells.dedup();
                let mut changed = 0;
                for c in cells {
                    let b = UVec3::from_array(c);
                    let inside = self.inside(b);
                    let (mask, mats) = emitted
                        .remove(&c)
                        .unwrap_or((Mask::EMPTY, PriorMaterials::Uniform(0)));
                    let mask = mask.and(&inside);
                    let probe = BrickUndo {
                        brick: b,
                        prior_mask: mask,
                        touched: Mask::FULL,
                        prior: mats,
                    };
                    changed += self.write(
                        b,
                        &inside,
                        &mut undo,
                        |bit, _| mask.get(bit).then(|| probe.prior_material(mask.rank(bit))),
                        false,
                    );
                }
                changed
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
        let empty = ModelBrick {
            mask: Mask::EMPTY,
            materials: BrickMaterials::Uniform(0),
        };
        let old = self.bricks.get(&key(b)).unwrap_or(&empty);
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
            None => {
                let held: Vec<u8> = held.ones().map(|bit| old.material(bit)).collect();
                match held.first() {
                    Some(&m) if held.iter().all(|x| *x == m) => PriorMaterials::Uniform(m),
                    None => PriorMaterials::Uniform(0),
                    _ => PriorMaterials::PerVoxel(held),
                }
            }
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

    /// Stores a computed rewrite and records its undo; returns the voxels changed.
    fn commit(&mut self, r: Rewrite, undo: &mut Vec<BrickUndo>) -> u64 {
        let k = key(r.undo.brick);
        match r.brick {
            Some(b) => self.bricks.insert(k, b),
            None => self.bricks.remove(&k),
        };
        undo.push(r.undo);
        r.changed
    }
}

/// Shapes over at least this many bricks are computed on every core.
const PARALLEL_BRICKS: usize = 256;

/// One brick's new content, its undo and the voxels it changes.
struct Rewrite {
    undo: BrickUndo,
    brick: Option<ModelBrick>,
    changed: u64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Material, MaterialKind};
    use crate::shape::Shape;
    use crate::{GridDims, World, WorldConfig};
    use glam::DVec3;
    use proptest::prelude::*;

    fn table(n: u8) -> MaterialTable {
        let mut t = MaterialTable::default();
        for i in 1..n {
            t.push(Material {
                kind: MaterialKind::Lambertian,
                param: 0,
                colour: i,
            })
            .unwrap();
        }
        t
    }

    fn op_strategy(size: IVec3) -> impl Strategy<Value = EditOp> {
        let m = 0u8..4;
        let mode = prop_oneof![
            m.clone().prop_map(Mode::Add),
            Just(Mode::Remove),
            m.clone().prop_map(Mode::Paint)
        ];
        let p = (-4..size.x + 4, -4..size.y + 4, -4..size.z + 4)
            .prop_map(|(x, y, z)| IVec3::new(x, y, z));
        let inside = (0..size.x, 0..size.y, 0..size.z).prop_map(|(x, y, z)| IVec3::new(x, y, z));
        let sphere = (p.clone(), 0.5f64..9.0).prop_map(|(c, r)| Shape::Sphere {
            centre: c.as_dvec3() + DVec3::splat(0.25),
            radius: r,
        });
        let cuboid = (p.clone(), p).prop_map(|(a, b)| Shape::Box {
            min: a.min(b),
            max: a.max(b),
        });
        let voxel_op = prop_oneof![
            m.clone().prop_map(VoxelOp::Set),
            Just(VoxelOp::Clear),
            m.prop_map(VoxelOp::Paint)
        ];
        prop_oneof![
            (prop_oneof![sphere, cuboid], mode)
                .prop_map(|(shape, mode)| EditOp::Shape { shape, mode }),
            prop::collection::vec((inside, voxel_op), 1..40).prop_map(|v| EditOp::Voxels(
                v.into_iter()
                    .map(|(pos, op)| VoxelEdit { pos, op })
                    .collect()
            )),
        ]
    }

    fn same(model: &Model, world: &World) {
        let view = world.read();
        let s = model.size();
        for z in 0..s.z {
            for y in 0..s.y {
                for x in 0..s.x {
                    let v = IVec3::new(x, y, z);
                    assert_eq!(model.voxel(v), view.voxel(v).unwrap(), "{v}");
                }
            }
        }
        assert_eq!(model.solid_count(), view.solid_count());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// A model of a whole number of bricks behaves as a world of that size, and every
        /// inverse puts back the exact content, and its own inverse redoes.
        #[test]
        fn a_model_edits_as_the_world_does_and_undoes_exactly(
            ops in prop::collection::vec(op_strategy(IVec3::new(24, 16, 16)), 1..8)
        ) {
            let size = IVec3::new(24, 16, 16);
            let t = table(4);
            let world = World::new(GridDims::new(3, 2, 2).unwrap(), WorldConfig::with_workers(2)).unwrap();
            for i in 0..4 {
                if i > 0 {
                    world.push_material(t.get(i).unwrap()).unwrap();
                }
            }
            let mut model = Model::new(size).unwrap();
            let mut undo = Vec::new();
            for op in &ops {
                let before = model.content_hash();
                let m = model.apply(op, &t).unwrap();
                let w = world.apply(op.clone()).unwrap();
                prop_assert_eq!(m.changed_voxels, w.changed_voxels);
                undo.push((before, m.inverse));
            }
            same(&model, &world);
            let end = model.content_hash();
            let mut redo = Vec::new();
            for (before, inv) in undo.into_iter().rev() {
                let r = model.apply(&EditOp::Restore(inv), &t).unwrap();
                prop_assert_eq!(model.content_hash(), before);
                redo.push(r.inverse);
            }
            prop_assert_eq!(model.solid_count(), 0);
            for inv in redo.into_iter().rev() {
                model.apply(&EditOp::Restore(inv), &t).unwrap();
            }
            prop_assert_eq!(model.content_hash(), end);
        }
    }

    #[test]
    fn a_large_shape_computed_on_every_core_matches_the_world() {
        let t = table(4);
        let size = IVec3::new(128, 64, 96);
        let world = World::new(
            GridDims::from_voxels(size.as_uvec3()).unwrap(),
            WorldConfig::with_workers(3),
        )
        .unwrap();
        world.replace_materials(t.clone()).unwrap();
        let mut model = Model::new(size).unwrap();
        let ops = [
            EditOp::Shape {
                shape: Shape::Sphere {
                    centre: DVec3::new(60.3, 30.0, 50.0),
                    radius: 40.0,
                },
                mode: Mode::Add(2),
            },
            EditOp::Shape {
                shape: Shape::Box {
                    min: IVec3::new(10, 5, 10),
                    max: IVec3::new(120, 40, 90),
                },
                mode: Mode::Paint(3),
            },
            EditOp::Shape {
                shape: Shape::Sphere {
                    centre: DVec3::new(70.0, 40.5, 40.0),
                    radius: 25.0,
                },
                mode: Mode::Remove,
            },
        ];
        let mut undo = Vec::new();
        for op in &ops {
            let before = model.content_hash();
            let m = model.apply(op, &t).unwrap();
            if let EditOp::Shape { shape, .. } = op {
                let (lo, hi) = shape.voxel_bounds();
                let (lo, hi) = (
                    lo.clamp(IVec3::ZERO, size - 1) / 8,
                    hi.clamp(IVec3::ZERO, size - 1) / 8,
                );
                let bricks = (hi - lo + 1).element_product() as usize;
                assert!(
                    bricks >= PARALLEL_BRICKS,
                    "the parallel path runs: {bricks}"
                );
            }
            let w = world.apply(op.clone()).unwrap();
            assert_eq!(m.changed_voxels, w.changed_voxels);
            undo.push((before, m.inverse));
        }
        same(&model, &world);
        for (before, inv) in undo.into_iter().rev() {
            model.apply(&EditOp::Restore(inv), &t).unwrap();
            assert_eq!(model.content_hash(), before);
        }
    }

    #[test]
    fn odd_sizes_clip_shapes_and_refuse_voxels_outside() {
        let t = table(2);
        let mut m = Model::new(IVec3::new(5, 3, 9)).unwrap();
        let all = EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::splat(-10),
                max: IVec3::splat(100),
            },
            mode: Mode::Add(1),
        };
        let out = m.apply(&all, &t).unwrap();
        assert_eq!(m.solid_count(), 5 * 3 * 9);
        assert_eq!(out.changed_voxels, 135);
        assert_eq!(m.bricks_size(), UVec3::new(1, 1, 2));
        let before = m.clone();
        let outside = EditOp::Voxels(vec![
            VoxelEdit {
                pos: IVec3::new(0, 0, 0),
                op: VoxelOp::Clear,
            },
            VoxelEdit {
                pos: IVec3::new(5, 0, 0),
                op: VoxelOp::Clear,
            },
        ]);
        assert!(matches!(
            m.apply(&outside, &t),
            Err(BrickmapError::OutOfRange(..))
        ));
        let bad_material = EditOp::Shape {
            shape: Shape::Voxel(IVec3::ZERO),
            mode: Mode::Paint(7),
        };
        assert!(matches!(
            m.apply(&bad_material, &t),
            Err(BrickmapError::MaterialIndex { .. })
        ));
        // A restore that writes past the model's box.
        let mut wide = out.inverse.clone();
        wide.bricks[0].touched = Mask::FULL;
        assert!(matches!(
            m.apply(&EditOp::Restore(wide), &t),
            Err(BrickmapError::BadInverse(_))
        ));
        assert_eq!(m, before, "refused edits change nothing");
        assert!(Model::new(IVec3::new(0, 1, 1)).is_err());
        assert!(Model::new(IVec3::new(1, 1025, 1)).is_err());
        assert_eq!(m.voxel(IVec3::new(5, 0, 0)), None);
        assert_eq!(m.voxel(IVec3::new(4, 2, 8)), Some(1));
    }

    #[test]
    fn generate_fills_the_columns_and_undoes() {
        use crate::edit::{ColumnSource, Generator};
        struct Floor;
        impl ColumnSource for Floor {
            fn column(&self, _: u32, _: u32, emit: &mut dyn FnMut(u32, Mask, PriorMaterials)) {
                emit(0, Mask::FULL, PriorMaterials::Uniform(1));
            }
            fn materials(&self) -> Vec<u8> {
                vec![1]
            }
        }
        let t = table(2);
        let mut m = Model::new(IVec3::new(10, 20, 3)).unwrap();
        m.apply(
            &EditOp::Shape {
                shape: Shape::Voxel(IVec3::new(1, 15, 1)),
                mode: Mode::Add(0),
            },
            &t,
        )
        .unwrap();
        let before = m.content_hash();
        let out = m
            .apply(&EditOp::Generate(Generator(std::sync::Arc::new(Floor))), &t)
            .unwrap();
        assert_eq!(
            m.solid_count(),
            10 * 8 * 3,
            "the first brick layer, clipped; the rest empty"
        );
        assert_eq!(m.voxel(IVec3::new(1, 15, 1)), None);
        m.apply(&EditOp::Restore(out.inverse), &t).unwrap();
        assert_eq!(m.content_hash(), before);
    }
}
