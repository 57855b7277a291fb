//! The `.vox` scene graph: the walk that places every visible model instance's voxels,
//! MagicaVoxel's rotation bytes read as `brickmap::objects::Orientation` (checked there,
//! because `dot_vox` asserts on bad bytes) and the placement about the integer pivot ⌊s/2⌋.

use super::*;
use brickmap::objects::{Orientation, Placement};

/// A node's transform, in MagicaVoxel's axes: an orientation and a translation about the
/// model's pivot, composed down the graph (the objects' own rule, `brickmap::objects`).
pub(super) type Transform = Placement;

/// Every placed voxel (voxbrick coordinates, before the shift) with its 0-based palette index.
pub(super) fn place_instances(
    data: &DotVoxData,
    options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Vec<(IVec3, u8)>, VoxError> {
    let mut out = Vec::new();
    if data.scenes.is_empty() {
        // Without a scene graph (files before MagicaVoxel 0.99), several SIZE/XYZI pairs are
        // the frames of one animated model, as MagicaVoxel reads them: keep the first.
        if let Some(model) = data.models.first() {
            place_model(model, Transform::IDENTITY, &mut out)?;
            report.instances += 1;
        }
        if data.models.len() > 1 {
            report.dropped.push(format!(
                "animation frames after the first ignored (×{}; a file without a scene graph holds frames of one model)",
                data.models.len() - 1
            ));
        }
        return Ok(out);
    }
    let mut notes = BTreeMap::<String, usize>::new();
    walk(
        data,
        0,
        Transform::IDENTITY,
        0,
        options,
        &mut out,
        report,
        &mut notes,
    )?;
    report.add_dropped(notes);
    Ok(out)
}

#[allow(clippy::too_many_arguments)]
pub(super) fn walk(
    data: &DotVoxData,
    node: u32,
    parent: Transform,
    depth: usize,
    options: &ImportOptions,
    out: &mut Vec<(IVec3, u8)>,
    report: &mut ImportReport,
    notes: &mut BTreeMap<String, usize>,
) -> Result<(), VoxError> {
    if depth > MAX_DEPTH {
        return Err(VoxError::TooDeep);
    }
    let Some(n) = data.scenes.get(node as usize) else {
        return Err(VoxError::MissingNode(node));
    };
    let hidden = |attrs: &dot_vox::Dict| attrs.get("_hidden").is_some_and(|v| v == "1");
    match n {
        SceneNode::Transform {
            attributes,
            frames,
            child,
            layer_id,
        } => {
            let layer_hidden = data
                .layers
                .get(*layer_id as usize)
                .is_some_and(|l| l.hidden());
            if (hidden(attributes) || layer_hidden) && !options.include_hidden {
                let what = if layer_hidden {
                    format!("hidden layer {layer_id} skipped")
                } else {
                    "hidden node skipped".into()
                };
                *notes.entry(what).or_default() += 1;
                return Ok(());
            }
            if frames.len() > 1 {
                *notes
                    .entry("animation frames after the first ignored".into())
                    .or_default() += 1;
            }
            let mut local = Transform::IDENTITY;
            if let Some(frame) = frames.first() {
                if let Some(t) = frame.attributes.get("_t") {
                    let v: Vec<i32> = t
                        .split_whitespace()
                        .filter_map(|s| s.parse().ok())
                        .collect();
                    if v.len() != 3 || v.iter().any(|c| c.abs() > 1 << 20) {
                        return Err(VoxError::BadTranslation {
                            node,
                            value: t.clone(),
                        });
                    }
                    local.t = IVec3::new(v[0], v[1], v[2]);
                }
                if let Some(r) = frame.attributes.get("_r") {
                    match r
                        .trim()
                        .parse::<u8>()
                        .ok()
                        .and_then(Orientation::from_vox_byte)
                    {
                        Some(rot) => local.rot = rot,
                        None => {
                            *notes
                                .entry(format!("invalid rotation {r:?} replaced by none"))
                                .or_default() += 1;
                        }
                    }
                }
            }
            walk(
                data,
                *child,
                parent.then(&local),
                depth + 1,
                options,
                out,
                report,
                notes,
            )
        }
        SceneNode::Group {
            attributes,
            children,
        } => {
            if hidden(attributes) && !options.include_hidden {
                *notes.entry("hidden group skipped".into()).or_default() += 1;
                return Ok(());
            }
            for c in children {
                walk(data, *c, parent, depth + 1, options, out, report, notes)?;
            }
            Ok(())
        }
        SceneNode::Shape { models, .. } => {
            if models.len() > 1 {
                *notes
                    .entry("animated shape: models after the first ignored".into())
                    .or_default() += 1;
            }
            if let Some(m) = models.first() {
                let model = data
                    .models
                    .get(m.model_id as usize)
                    .ok_or(VoxError::MissingModel {
                        model: m.model_id,
                        unread: Vec::new(),
                    })?;
                place_model(model, parent, out)?;
                report.instances += 1;
            }
            Ok(())
        }
    }
}

pub(super) fn place_model(
    model: &Model,
    tr: Transform,
    out: &mut Vec<(IVec3, u8)>,
) -> Result<(), VoxError> {
    if out.len() as u64 + model.voxels.len() as u64 > MAX_PLACED_VOXELS {
        return Err(VoxError::TooManyVoxels);
    }
    let size = IVec3::new(
        model.size.x as i32,
        model.size.y as i32,
        model.size.z as i32,
    );
    for v in &model.voxels {
        let vox = tr.place(IVec3::new(v.x as i32, v.y as i32, v.z as i32), size);
        out.push((IVec3::new(vox.x, vox.z, -vox.y - 1), v.i));
    }
    Ok(())
}
