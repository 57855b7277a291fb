//! The canvas of an object's model: fit it to its voxels, crop it to the selection, or resize
//! it with an anchor. Each is a new model (the kept voxels, moved to the new origin) that the
//! object places instead, with its placement moved so that nothing moves in the world; the old
//! model goes when no other object places it. One `Batch` of object ops: its inverse puts the
//! old model and placement back exactly. A model's other instances keep the old model (the
//! object is made unique by the change).

use brickmap::MaterialTable;
use brickmap::objects::{
    Model, ModelId, NodeId, NodeKind, ObjectError, ObjectOp, Objects, Placement,
};
use glam::IVec3;
use serde::{Deserialize, Serialize};

/// What a canvas change does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Canvas {
    /// The smallest box holding the model's voxels.
    Fit,
    /// The selection's box (world voxels, inclusive corners); what lies outside goes.
    Crop {
        /// Its lowest voxel.
        min: IVec3,
        /// Its highest voxel.
        max: IVec3,
    },
    /// A new size; the old voxels stay at `anchor`'s side on each axis (−1: the low side,
    /// 0: centred, rounding down, 1: the high side); what no longer fits goes.
    Resize {
        /// The new size in voxels.
        size: IVec3,
        /// Per axis −1, 0 or 1.
        anchor: IVec3,
    },
}

/// Why a canvas change is refused.
fn refused(message: &str) -> super::error::EditError {
    super::error::invalid(message.to_string())
}

/// The ops that change `node`'s canvas.
pub(super) fn canvas_op(
    objects: &Objects,
    node: NodeId,
    how: Canvas,
    table: &MaterialTable,
) -> super::error::Result<ObjectOp> {
    let tree = objects.tree();
    let (n, model, old) = object_model(objects, node)?;
    let size = old.size();
    // The new model's origin in the old model's voxels, and its size.
    let (off, new_size) = match how {
        Canvas::Fit => {
            let (lo, hi) = content_box(old).ok_or_else(|| refused("the object is empty"))?;
            (lo, hi - lo + 1)
        }
        Canvas::Crop { min, max } => {
            let world = tree.world_placement(node)?;
            let (a, b) = (world.unplace(min, size), world.unplace(max, size));
            let (lo, hi) = (a.min(b).max(IVec3::ZERO), a.max(b).min(size - 1));
            if lo.cmpgt(hi).any() {
                return Err(refused("the selection misses the object"));
            }
            (lo, hi - lo + 1)
        }
        Canvas::Resize { size: s, anchor } => {
            if s.cmplt(IVec3::ONE).any() {
                return Err(refused("a model is at least 1 voxel on every side"));
            }
            if anchor.abs().max_element() > 1 {
                return Err(refused("an anchor is −1, 0 or 1 on each axis"));
            }
            let off = IVec3::from_array(std::array::from_fn(|i| match anchor[i] {
                -1 => 0,
                0 => (size[i] - s[i]).div_euclid(2),
                _ => size[i] - s[i],
            }));
            (off, s)
        }
    };
    if off == IVec3::ZERO && new_size == size {
        return Err(super::error::EditError::NothingToDo(
            "the canvas is already that",
        ));
    }
    let kept = old.bricks().flat_map(|(b, brick)| {
        let min = b.as_ivec3() * 8;
        brick.mask.ones().filter_map(move |bit| {
            let v = min + IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
            let at = v - off;
            (at.cmpge(IVec3::ZERO).all() && at.cmplt(new_size).all())
                .then(|| (at, brick.material(bit)))
        })
    });
    let voxels = Model::from_voxels(new_size, kept, table)?;
    // Nothing moves in the world: t' = t + R·(off + ⌊s'/2⌋ − ⌊s/2⌋).
    let half = |s: IVec3| s.div_euclid(IVec3::splat(2));
    let placement = Placement {
        t: n.placement.t + n.placement.rot.apply(off + half(new_size) - half(size)),
        ..n.placement
    };
    Ok(replace_model(objects, node, model, voxels, placement))
}

/// The model of `node` (now `model`) scaled × 2 (each voxel a 2³ block) or × ½ (each 2³
/// block's majority, `selection_scale::majority`) about its centre: the object keeps its
/// placement, so its pivot stays where it is; × 2 then × ½ is the identity.
pub(super) fn scale_op(
    objects: &Objects,
    node: NodeId,
    step: crate::selection_scale::ScaleStep,
    table: &MaterialTable,
) -> super::error::Result<ObjectOp> {
    use crate::selection_scale::{ScaleStep, majority};
    let (n, model, old) = object_model(objects, node)?;
    let size = old.size();
    let voxels = || {
        old.bricks().flat_map(|(b, brick)| {
            let min = b.as_ivec3() * 8;
            brick.mask.ones().map(move |bit| {
                let v = min + IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
                (v, brick.material(bit))
            })
        })
    };
    let new = match step {
        ScaleStep::Double => Model::from_voxels(
            size * 2,
            voxels().flat_map(|(v, m)| {
                (0..8).map(move |k| (2 * v + IVec3::new(k & 1, k >> 1 & 1, k >> 2), m))
            }),
            table,
        )?,
        ScaleStep::Halve => {
            if size.cmple(IVec3::ONE).all() {
                return Err(super::error::EditError::NothingToDo(
                    "a one-voxel object cannot be halved",
                ));
            }
            // Brick by brick of the new model: the 2 × 2 × 2 old bricks it covers, looked up
            // once, each new voxel the majority of its 8.
            let mut new_bricks: std::collections::BTreeSet<(u32, u32, u32)> = Default::default();
            for (b, _) in old.bricks() {
                let n = b / 2;
                new_bricks.insert((n.x, n.y, n.z));
            }
            let mut kept = Vec::new();
            for (x, y, z) in new_bricks {
                let nb = glam::UVec3::new(x, y, z);
                let olds: [Option<&brickmap::objects::ModelBrick>; 8] = std::array::from_fn(|k| {
                    let k = k as u32;
                    old.brick(nb * 2 + glam::UVec3::new(k & 1, k >> 1 & 1, k >> 2))
                });
                for bit in 0..512usize {
                    let u = IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
                    let block = (0..8).map(|k| {
                        // The old voxel 2u + k of the 16³ the new brick covers.
                        let o = 2 * u + IVec3::new(k & 1, k >> 1 & 1, k >> 2);
                        let which = (o.x / 8 + 2 * (o.y / 8) + 4 * (o.z / 8)) as usize;
                        let b = olds[which]?;
                        let obit = brickmap::brick::voxel_bit(o.x & 7, o.y & 7, o.z & 7);
                        b.mask.get(obit).then(|| b.material(obit))
                    });
                    if let Some(m) = majority(block) {
                        kept.push((nb.as_ivec3() * 8 + u, m));
                    }
                }
            }
            Model::from_voxels((size + 1) / 2, kept, table)?
        }
    };
    Ok(replace_model(objects, node, model, new, n.placement))
}

/// The node `node`, its model's id and its model (an error for a group or a missing model).
fn object_model(
    objects: &Objects,
    node: NodeId,
) -> super::error::Result<(&brickmap::objects::Node, ModelId, &Model)> {
    let n = objects.tree().node(node)?;
    let NodeKind::Object { model, .. } = n.kind else {
        return Err(ObjectError::NotAnObject(node).into());
    };
    let old = objects.model(model).ok_or(ObjectError::NoModel(model))?;
    Ok((n, model, old))
}

/// The ops that make `node` place `voxels` (a new model) at `placement` instead of `model`,
/// dropping `model` when no other object places it.
fn replace_model(
    objects: &Objects,
    node: NodeId,
    model: ModelId,
    voxels: Model,
    placement: Placement,
) -> ObjectOp {
    let tree = objects.tree();
    let fresh: ModelId = objects.free_model_id();
    let mut ops = vec![
        ObjectOp::AddModel {
            model: fresh,
            voxels: Box::new(voxels),
        },
        ObjectOp::SetModel { node, model: fresh },
        ObjectOp::Place { node, placement },
    ];
    if tree.instances(model).len() == 1 {
        ops.push(ObjectOp::RemoveModel { model });
    }
    ObjectOp::Batch(ops)
}

/// The box of a model's voxels (inclusive), if it has any.
fn content_box(m: &Model) -> Option<(IVec3, IVec3)> {
    let mut out: Option<(IVec3, IVec3)> = None;
    for (b, brick) in m.bricks() {
        let min = b.as_ivec3() * 8;
        for bit in brick.mask.ones() {
            let v = min + IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
            out = Some(out.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
        }
    }
    out
}
