//! An edit made in the world carried into an object's own frame, so a brush, fill or
//! selection acts on the object's model wherever and however the object is placed (and its
//! instances follow through the composite).
//!
//! The placement's inverse on points is x ↦ R⁻¹·(x − t) + ⌊s/2⌋ (the rule in `orient`, on
//! voxel centres), an isometry: spheres, cylinders and capsules keep their radius, boxes stay
//! boxes (their corner voxels are carried with `unplace`), single voxels and voxel sets are
//! carried voxel by voxel, exactly. A shape's centre or end points are doubles: subtracting
//! t may round their last bits, so a voxel centre within about 10⁻¹³ of a curved surface may
//! fall on the other side in the model frame than in the world; on the half- and
//! quarter-voxel positions the tools produce, it is exact.

use super::orient::Placement;
use crate::edit::{BrickUndo, EditInverse, EditOp, PriorMaterials, VoxelEdit, VoxelOp};
use crate::error::{BrickmapError, Result};
use crate::shape::Shape;
use crate::voxel_set::{VoxelSet, box_mask};
use glam::{DVec3, IVec3};
use std::sync::Arc;

impl Placement {
    /// A world point in the frame of a model of `size` placed here.
    pub fn to_model_point(&self, x: DVec3, size: IVec3) -> DVec3 {
        let inv = self.rot.inverse();
        let d = x - self.t.as_dvec3();
        let a = d.to_array();
        // A signed permutation moves and negates components: exact in floating point.
        let m = inv.matrix();
        let r: [f64; 3] = std::array::from_fn(|i| {
            (0..3)
                .find(|&j| m[i][j] != 0)
                .map_or(0.0, |j| if m[i][j] < 0 { -a[j] } else { a[j] })
        });
        DVec3::from_array(r) + (size / 2).as_dvec3()
    }

    /// A shape in world voxels as the same voxels of a model of `size` placed here.
    pub fn shape_to_model(&self, shape: &Shape, size: IVec3) -> Shape {
        let point = |p: &DVec3| self.to_model_point(*p, size);
        match shape {
            Shape::Voxel(v) => Shape::Voxel(self.unplace(*v, size)),
            Shape::Sphere { centre, radius } => Shape::Sphere {
                centre: point(centre),
                radius: *radius,
            },
            Shape::Box { min, max } => {
                let (a, b) = (self.unplace(*min, size), self.unplace(*max, size));
                Shape::Box {
                    min: a.min(b),
                    max: a.max(b),
                }
            }
            Shape::Cylinder { a, b, radius } => Shape::Cylinder {
                a: point(a),
                b: point(b),
                radius: *radius,
            },
            Shape::Line { points, radius } => Shape::Line {
                points: points.iter().map(point).collect(),
                radius: *radius,
            },
            Shape::Set(set) => Shape::Set(self.set_arc_to_model(set, size)),
            Shape::Within { shape, set } => Shape::Within {
                shape: Box::new(self.shape_to_model(shape, size)),
                set: self.set_arc_to_model(set, size),
            },
        }
    }

    /// [`Placement::set_to_model`], shared as it is where the model's frame is the world's
    /// (the model clips a set to itself as it clips any shape).
    fn set_arc_to_model(&self, set: &Arc<VoxelSet>, size: IVec3) -> Arc<VoxelSet> {
        if self.brick_shift(size) == Some(IVec3::ZERO) {
            set.clone()
        } else {
            Arc::new(self.set_to_model(set, size))
        }
    }

    /// A voxel set in world voxels as the same voxels of the model.
    pub fn set_to_model(&self, set: &VoxelSet, size: IVec3) -> VoxelSet {
        let mut out = VoxelSet::new();
        for v in set.voxels() {
            let m = self.unplace(v, size);
            // Only the model's part of the set can change.
            if m.cmpge(IVec3::ZERO).all() && m.cmplt(size).all() {
                out.insert(m);
            }
        }
        out
    }

    /// An edit in world voxels as the same edit of the model: shapes and voxel batches are
    /// carried (voxels outside the model are dropped from a batch, as a shape is clipped);
    /// a brick restore is carried brick by brick where the object is unrotated and placed on
    /// whole bricks, else voxel by voxel; a generator only where the model's frame is the
    /// world's (else it is refused).
    pub fn edit_to_model(&self, op: &EditOp, size: IVec3) -> Result<EditOp> {
        let inside = |v: IVec3| v.cmpge(IVec3::ZERO).all() && v.cmplt(size).all();
        Ok(match op {
            // One voxel outside the model is clipped away like any shape: nothing to do.
            EditOp::Shape {
                shape: Shape::Voxel(v),
                ..
            } if !inside(self.unplace(*v, size)) => EditOp::Voxels(Vec::new()),
            EditOp::Shape { shape, mode } => EditOp::Shape {
                shape: self.shape_to_model(shape, size),
                mode: *mode,
            },
            EditOp::Voxels(list) => EditOp::Voxels(
                list.iter()
                    .map(|e| VoxelEdit {
                        pos: self.unplace(e.pos, size),
                        op: e.op,
                    })
                    .filter(|e| inside(e.pos))
                    .collect(),
            ),
            EditOp::Restore(inverse) => match self.brick_shift(size) {
                Some(shift) => EditOp::Restore(restore_shifted(inverse, shift, size)),
                None => self.edit_to_model(&EditOp::Voxels(restore_voxels(inverse)), size)?,
            },
            // A generator fills the grid it was made for: the model's frame must be the
            // world's.
            EditOp::Generate(_) if self.brick_shift(size) == Some(IVec3::ZERO) => op.clone(),
            EditOp::Generate(_) => {
                return Err(BrickmapError::NotInModelFrame(
                    "a generator outside an object placed at the world's origin",
                ));
            }
        })
    }

    /// With no rotation and a translation of whole bricks, the world brick of model brick
    /// `b` is `b + shift`.
    fn brick_shift(&self, size: IVec3) -> Option<IVec3> {
        let offset = self.place(IVec3::ZERO, size);
        (self.rot == super::orient::Orientation::IDENTITY
            && offset.rem_euclid(IVec3::splat(8)) == IVec3::ZERO)
            .then_some(offset / 8)
    }
}

/// A world restore as the model's: bricks moved by `-shift`, what lies outside the model
/// dropped (the prior materials of the voxels kept, in the same order).
fn restore_shifted(inverse: &EditInverse, shift: IVec3, size: IVec3) -> EditInverse {
    let bricks = inverse
        .bricks
        .iter()
        .filter_map(|u| {
            let b = u.brick.as_ivec3() - shift;
            let inside = box_mask(b * 8, IVec3::ZERO, size - 1);
            let touched = u.touched.and(&inside);
            if touched.is_empty() {
                return None;
            }
            let prior = if touched == u.touched {
                u.prior.clone()
            } else {
                // Repacked: the prior materials of the solid touched voxels still inside.
                let kept = u.touched.and(&u.prior_mask);
                PriorMaterials::packed(
                    kept.ones()
                        .enumerate()
                        .filter(|(_, bit)| inside.get(*bit))
                        .map(|(k, _)| u.prior_material(k))
                        .collect(),
                )
            };
            Some(BrickUndo {
                brick: b.as_uvec3(),
                prior_mask: u.prior_mask.and(&touched),
                touched,
                prior,
            })
        })
        .collect();
    EditInverse { bricks }
}

/// A world restore as single-voxel edits in world voxels (for an object it cannot be
/// carried to brick by brick).
fn restore_voxels(inverse: &EditInverse) -> Vec<VoxelEdit> {
    let mut out = Vec::new();
    for u in &inverse.bricks {
        let min = u.brick.as_ivec3() * 8;
        let mut k = 0;
        for bit in u.touched.ones() {
            let pos = min + IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
            let op = if u.prior_mask.get(bit) {
                k += 1;
                VoxelOp::Set(u.prior_material(k - 1))
            } else {
                VoxelOp::Clear
            };
            out.push(VoxelEdit { pos, op });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edit::Mode;
    use crate::objects::composite::Composite;
    use crate::objects::model::Model;
    use crate::objects::orient::Orientation;
    use crate::objects::tree::{LayerId, ModelId, NewNode, ObjectTree};
    use crate::{GridDims, Material, World, WorldConfig};
    use proptest::prelude::*;
    use std::collections::BTreeMap;

    /// Points on an eighth-voxel lattice (exact in the frame change).
    fn point(lo: IVec3, hi: IVec3) -> impl Strategy<Value = DVec3> {
        (lo.x * 8..hi.x * 8, lo.y * 8..hi.y * 8, lo.z * 8..hi.z * 8)
            .prop_map(|(x, y, z)| DVec3::new(x as f64, y as f64, z as f64) / 8.0)
    }

    fn shape() -> impl Strategy<Value = Shape> {
        let (lo, hi) = (IVec3::splat(4), IVec3::new(44, 28, 44));
        let cell = (4..44, 4..28, 4..44).prop_map(|(x, y, z)| IVec3::new(x, y, z));
        let radius = (2..40).prop_map(|r| r as f64 / 4.0);
        prop_oneof![
            cell.clone().prop_map(Shape::Voxel),
            (point(lo, hi), radius.clone())
                .prop_map(|(centre, radius)| Shape::Sphere { centre, radius }),
            (cell.clone(), cell.clone()).prop_map(|(a, b)| Shape::Box {
                min: a.min(b),
                max: a.max(b)
            }),
            (point(lo, hi), point(lo, hi), radius.clone())
                .prop_filter("distinct caps", |(a, b, _)| a != b)
                .prop_map(|(a, b, radius)| Shape::Cylinder { a, b, radius }),
            (prop::collection::vec(point(lo, hi), 1..4), radius)
                .prop_map(|(points, radius)| Shape::Line { points, radius }),
            prop::collection::vec(cell, 1..30).prop_map(|v| {
                let mut s = VoxelSet::new();
                v.into_iter().for_each(|c| s.insert(c));
                Shape::Set(Arc::new(s))
            }),
        ]
    }

    /// Any of the 48 orientations anywhere, or (a third of the cases) unrotated on whole
    /// bricks, where a restore is carried brick by brick.
    fn placement() -> impl Strategy<Value = (Placement, IVec3)> {
        let any = (0usize..48, (18..30, 10..18, 18..30), (1..17, 1..13, 1..17)).prop_map(
            |(r, (x, y, z), (sx, sy, sz))| {
                let p = Placement {
                    rot: Orientation::all().nth(r).unwrap(),
                    t: IVec3::new(x, y, z),
                };
                (p, IVec3::new(sx, sy, sz))
            },
        );
        let aligned = ((0..3, 0..2, 0..3), (1..24, 1..16, 1..24)).prop_map(|(b, s)| {
            let size = IVec3::new(s.0, s.1, s.2);
            let at = IVec3::new(b.0, b.1, b.2) * 8;
            (Placement::at(at + size / 2), size)
        });
        prop_oneof![2 => any, 1 => aligned]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// The carried shape holds exactly the model voxels whose placed cells the world
        /// shape holds.
        #[test]
        fn a_carried_shape_holds_the_same_voxels(s in shape(), (p, size) in placement()) {
            let m = p.shape_to_model(&s, size);
            for z in 0..size.z {
                for y in 0..size.y {
                    for x in 0..size.x {
                        let v = IVec3::new(x, y, z);
                        prop_assert_eq!(m.contains(v), s.contains(p.place(v, size)), "{} {:?}", v, p);
                    }
                }
            }
        }

        /// Editing an object in its frame changes the composite exactly as the same edit of
        /// the flattened world changes it inside the object's box.
        #[test]
        fn an_edit_in_the_object_frame_is_the_world_edit_inside_its_box(
            s in shape(), (p, size) in placement(), remove in any::<bool>()
        ) {
            let table = {
                let mut t = crate::MaterialTable::default();
                t.push(Material::lambertian(1)).unwrap();
                t.push(Material::lambertian(2)).unwrap();
                t
            };
            let mut model = Model::new(size).unwrap();
            let fill = EditOp::Shape {
                shape: Shape::Sphere { centre: size.as_dvec3() / 2.0, radius: size.max_element() as f64 / 2.0 },
                mode: Mode::Add(1),
            };
            model.apply(&fill, &table).unwrap();
            let mut tree = ObjectTree::new();
            tree.add(ObjectTree::ROOT, None, "o", p, NewNode::Object { model: ModelId(0), layer: LayerId(0) }).unwrap();
            let mut models = BTreeMap::from([(ModelId(0), model)]);
            let grid = GridDims::new(6, 4, 6).unwrap();
            let composite = Composite::new(&tree, &models, grid.voxels()).unwrap();
            let worlds = [0, 1].map(|_| {
                let w = World::new(grid, WorldConfig::with_workers(2)).unwrap();
                w.replace_materials(table.clone()).unwrap();
                composite.write(&w, &composite.all_bricks(), &models).unwrap();
                w
            });
            let op = EditOp::Shape { shape: s, mode: if remove { Mode::Remove } else { Mode::Add(2) } };
            // The edit, then the world's restore of it carried the same way (a paste or a
            // move of the editor is a world restore).
            let undo = worlds[1].apply(op.clone()).unwrap().inverse;
            let (lo, hi) = p.bounds(size);
            for op in [op, EditOp::Restore(undo)] {
                if let EditOp::Restore(inverse) = &op {
                    worlds[1].apply(EditOp::Restore(inverse.clone())).unwrap();
                }
                let carried = p.edit_to_model(&op, size).unwrap();
                let model = models.get_mut(&ModelId(0)).unwrap();
                let out = model.apply(&carried, &table).unwrap();
                composite.model_edited(&worlds[0], &models, ModelId(0), &out.inverse).unwrap();
                let (a, b) = (worlds[0].read(), worlds[1].read());
                for z in lo.z..hi.z {
                    for y in lo.y..hi.y {
                        for x in lo.x..hi.x {
                            let w = IVec3::new(x, y, z);
                            prop_assert_eq!(a.voxel(w).unwrap(), b.voxel(w).unwrap(), "{}", w);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn generators_outside_the_origin_are_refused_and_batches_keep_the_model_part() {
        let p = Placement {
            rot: Orientation::quarter_turn(crate::objects::Axis::Y, 1),
            t: IVec3::new(10, 0, 10),
        };
        let size = IVec3::new(4, 2, 6);
        struct Nothing;
        impl crate::edit::ColumnSource for Nothing {
            fn column(&self, _: u32, _: u32, _: &mut dyn FnMut(u32, crate::Mask, PriorMaterials)) {}
            fn materials(&self) -> Vec<u8> {
                Vec::new()
            }
        }
        let generate = EditOp::Generate(crate::edit::Generator(Arc::new(Nothing)));
        assert!(matches!(
            p.edit_to_model(&generate, size),
            Err(BrickmapError::NotInModelFrame(_))
        ));
        let origin = Placement::at(IVec3::splat(4));
        assert!(matches!(
            origin.edit_to_model(&generate, IVec3::splat(8)),
            Ok(EditOp::Generate(_))
        ));
        let (lo, _) = p.bounds(size);
        let batch = EditOp::Voxels(vec![
            VoxelEdit {
                pos: lo,
                op: crate::VoxelOp::Clear,
            },
            VoxelEdit {
                pos: lo - 1,
                op: crate::VoxelOp::Clear,
            },
        ]);
        let EditOp::Voxels(list) = p.edit_to_model(&batch, size).unwrap() else {
            panic!("a batch stays a batch")
        };
        assert_eq!(list.len(), 1);
        assert_eq!(p.place(list[0].pos, size), lo);
    }
}
