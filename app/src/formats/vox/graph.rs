//! The `.vox` scene graph: MagicaVoxel's rotations as signed permutation matrices
//! ([`IMat3`], [`decode_rotation`], checked here because `dot_vox` asserts on bad bytes),
//! transforms, and the walk that places every visible model instance's voxels about its
//! integer pivot ⌊s/2⌋.

use super::*;

/// A 3×3 integer matrix (MagicaVoxel rotations are signed permutations), rows stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IMat3(pub [[i32; 3]; 3]);

impl IMat3 {
    /// The identity.
    pub const IDENTITY: IMat3 = IMat3([[1, 0, 0], [0, 1, 0], [0, 0, 1]]);
    /// Determinant.
    pub fn det(&self) -> i32 {
        let m = &self.0;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }
}

impl std::ops::Mul<IVec3> for IMat3 {
    type Output = IVec3;
    fn mul(self, v: IVec3) -> IVec3 {
        let r = |i: usize| self.0[i][0] * v.x + self.0[i][1] * v.y + self.0[i][2] * v.z;
        IVec3::new(r(0), r(1), r(2))
    }
}

impl std::ops::Mul for IMat3 {
    type Output = IMat3;
    fn mul(self, o: IMat3) -> IMat3 {
        IMat3(std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| self.0[i][k] * o.0[k][j]).sum())
        }))
    }
}

/// A node's transform: rotation then translation, in MagicaVoxel coordinates.
#[derive(Clone, Copy)]
pub(super) struct Transform {
    rot: IMat3,
    t: IVec3,
}

impl Transform {
    const IDENTITY: Transform = Transform {
        rot: IMat3::IDENTITY,
        t: IVec3::ZERO,
    };
    fn then(self, local: Transform) -> Transform {
        Transform {
            rot: self.rot * local.rot,
            t: self.rot * local.t + self.t,
        }
    }
}

/// Decodes MagicaVoxel's packed rotation byte (bits 0–1: column of row 0's non-zero entry,
/// bits 2–3: row 1's, bits 4–6: signs of rows 0–2). `None` when invalid.
pub fn decode_rotation(byte: u8) -> Option<IMat3> {
    let (c0, c1) = ((byte & 3) as usize, (byte >> 2 & 3) as usize);
    if c0 == 3 || c1 == 3 || c0 == c1 {
        return None;
    }
    let c2 = 3 - c0 - c1;
    let sign = |bit: u8| if byte >> bit & 1 == 1 { -1 } else { 1 };
    let mut rows = [[0i32; 3]; 3];
    rows[0][c0] = sign(4);
    rows[1][c1] = sign(5);
    rows[2][c2] = sign(6);
    Some(IMat3(rows))
}

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
                    match r.trim().parse::<u8>().ok().and_then(decode_rotation) {
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
                parent.then(local),
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
        // ⌊R·(v + ½ − ⌊s/2⌋) + t⌋, in doubled integers to stay exact: 2v + 1 − 2⌊s/2⌋.
        let twice = IVec3::new(v.x as i32, v.y as i32, v.z as i32) * 2 + 1 - (size / 2) * 2;
        let p = tr.rot * twice + tr.t * 2;
        let vox = IVec3::new(p.x.div_euclid(2), p.y.div_euclid(2), p.z.div_euclid(2));
        out.push((IVec3::new(vox.x, vox.z, -vox.y - 1), v.i));
    }
    Ok(())
}
