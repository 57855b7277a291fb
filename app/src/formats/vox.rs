//! MagicaVoxel `.vox` import and export, through the `dot_vox` crate.
//!
//! Coordinates: MagicaVoxel is z-up, voxbrick y-up, both right-handed; voxel cell (vx, vy, vz)
//! becomes (vx, vz, −vy − 1) and back. A model instance is placed MagicaVoxel's way: voxel v
//! of a model of size s under a transform (R, t) lands at ⌊R·(v + ½ − ⌊s/2⌋) + t⌋: the pivot
//! is the integer point ⌊s/2⌋ (opengametools' ogt_vox.h, "explanation of model pivots"; vengi
//! computes the same), which matters on odd axes that R negates.
//!
//! Import walks the scene graph (nTRN translation and packed rotation byte, nGRP, nSHP),
//! skips hidden layers and hidden nodes unless asked, maps the palette and MATL materials,
//! and reports everything it dropped. Each axis is shifted by max(0, −min) plus the requested
//! offset, so files centred on the origin land in the grid and voxbrick's own exports come back
//! at the same positions.
//!
//! Traps handled: `dot_vox`'s `Voxel::i` is the file's palette index − 1 and its writer adds
//! the 1 back with a `u8` add that overflows at 255, so export uses at most 255 palette slots;
//! `Rotation::from_byte` (and `Frame::orientation`) assert on invalid bytes, so rotations are
//! decoded here; chunks `dot_vox` does not map are found by walking the chunk headers.
//!
//! Emission: MagicaVoxel stores `_emit` (0..1) and `_flux` (a power); voxbrick's strength is
//! `_emit · 2^_flux`, and export writes the exact inverse.

use super::FormatError;
use crate::scene::Scene;
use brickmap::{
    BrickMaterials, BrickUndo, GridDims, Mask, Material, MaterialKind, PriorMaterials, World,
};
use dot_vox::{Color, DotVoxData, Model, SceneNode, Size, Voxel};
use glam::IVec3;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// How to import.
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    /// Added to every voxel position after the shift into the grid.
    pub offset: IVec3,
    /// Import nodes on hidden layers, and hidden nodes, too.
    pub include_hidden: bool,
}

/// What an import did and what it left out.
#[derive(Clone, Debug, Default)]
pub struct ImportReport {
    /// Models in the file.
    pub models: usize,
    /// Model instances placed.
    pub instances: usize,
    /// Voxels written.
    pub voxels: u64,
    /// Materials created.
    pub materials: usize,
    /// Everything dropped or changed, one line each.
    pub dropped: Vec<String>,
}

/// What an export wrote.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ExportReport {
    /// Models (≤ 256³ each).
    pub models: usize,
    /// Voxels.
    pub voxels: u64,
    /// Palette slots used.
    pub materials: usize,
    /// Bytes written.
    pub bytes: u64,
}

/// The start of the error for a shape whose model does not exist.
const MISSING_MODEL: &str = "shape refers to missing model";

/// Limits that keep a hostile file from exhausting memory or time.
const MAX_DEPTH: usize = 64;
const MAX_PLACED_VOXELS: u64 = 1 << 28;

/// The dimensions of a SLAB6 `.vox`: three little-endian u32 sizes, x·y·z voxel bytes and a
/// 768-byte palette, exactly filling the file (and no MagicaVoxel magic).
fn slab6_dims(bytes: &[u8]) -> Option<(u64, u64, u64)> {
    if bytes.starts_with(b"VOX ") || bytes.len() < 12 {
        return None;
    }
    let d = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap()) as u64;
    let (x, y, z) = (d(0), d(1), d(2));
    let voxels = x.checked_mul(y)?.checked_mul(z)?;
    (x > 0 && y > 0 && z > 0 && voxels.checked_add(12 + 768)? == bytes.len() as u64)
        .then_some((x, y, z))
}

/// Parses `.vox` bytes; a `dot_vox` panic on malformed input is caught and reported.
pub fn parse(bytes: &[u8]) -> Result<DotVoxData, String> {
    if let Some((x, y, z)) = slab6_dims(bytes) {
        return Err(format!(
            "this is a Ken Silverman SLAB6 .vox (a plain {x}×{y}×{z} volume with a 768-byte palette, no \"VOX \" header), which voxbrick does not import; MagicaVoxel or vengi can convert it"
        ));
    }
    super::vox_check::check(bytes).map_err(|e| format!("not a valid .vox file: {e}"))?;
    let parsed = std::panic::catch_unwind(|| dot_vox::load_bytes(bytes));
    match parsed {
        Ok(Ok(data)) => Ok(data),
        Ok(Err(e)) => Err(format!("not a valid .vox file: {e}")),
        Err(_) => Err("not a valid .vox file: the parser failed on malformed data".into()),
    }
}

/// Imports a `.vox` file into a new scene sized to fit it.
pub fn import_file(
    path: &Path,
    options: &ImportOptions,
    workers: usize,
) -> Result<(Scene, ImportReport), FormatError> {
    let bytes = std::fs::read(path).map_err(|e| FormatError::io(path, e))?;
    import_bytes(&bytes, path, options, workers)
}

/// Imports `.vox` bytes into a new scene (`path` only names the file in errors).
pub fn import_bytes(
    bytes: &[u8],
    path: &Path,
    options: &ImportOptions,
    workers: usize,
) -> Result<(Scene, ImportReport), FormatError> {
    let invalid = |m: String| FormatError::invalid(path, m);
    let (data, placed, mut report) = prepare(bytes, options).map_err(invalid)?;
    let top = bounds(&placed).map_or(IVec3::ZERO, |b| b.1);
    let dims = GridDims::from_voxels((top + 1).max(IVec3::ONE).as_uvec3()).map_err(|_| {
        invalid(format!(
            "the model needs a {} voxel grid, beyond the largest supported",
            top + 1
        ))
    })?;
    let mut scene = Scene::empty(dims, workers).map_err(|e| FormatError::world(path, e))?;
    if let Some((lo, hi)) = bounds(&placed) {
        // Framed whole (the default camera's direction), as the editor's "frame the scene".
        scene.params.camera = scene
            .params
            .camera
            .framing(lo.as_dvec3(), (hi + 1).as_dvec3())
            .0;
    }
    // A new scene takes the file's palette as its colour table, index for index.
    let palette = palette_of(&data);
    for (i, c) in palette.iter().enumerate() {
        scene.world.set_colour(i as u8, [c.r, c.g, c.b]);
    }
    let map = install_materials(&scene.world, &data, &placed, &mut report, Ok).map_err(invalid)?;
    write_voxels(&scene.world, &placed, |i| map[i as usize], &mut report)
        .map_err(|e| FormatError::world(path, e))?;
    scene.world.take_dirty();
    Ok((scene, report))
}

/// Imports `.vox` bytes into an existing world. With `material`, every voxel gets that
/// material; otherwise colours are merged into the colour table (an identical colour is
/// reused, else a slot no material uses) and identical materials are reused. Voxels that
/// land outside the grid are dropped and reported. One voxel edit, whose inverse is returned
/// (the editor's undo); colours and materials it added stay.
pub fn import_into(
    world: &World,
    bytes: &[u8],
    options: &ImportOptions,
    material: Option<u8>,
) -> Result<(ImportReport, brickmap::EditInverse), String> {
    let (data, mut placed, mut report) = prepare(bytes, options)?;
    let dims = world.dims();
    let before = placed.len();
    placed.retain(|(p, _)| dims.contains_voxel(*p));
    if placed.is_empty() && before > 0 {
        return Err(format!(
            "nothing to import: all {before} voxels land outside the {} voxel grid (try another offset)",
            dims.voxels()
        ));
    }
    if placed.len() < before {
        report.dropped.push(format!(
            "{} voxels outside the grid dropped",
            before - placed.len()
        ));
    }
    let map = match material {
        Some(m) => {
            world
                .materials()
                .check(m as u32)
                .map_err(|e| e.to_string())?;
            [m; 256]
        }
        None => {
            let palette = palette_of(&data);
            let mut taken = std::collections::HashSet::new();
            install_materials(world, &data, &placed, &mut report, |i| {
                colour_slot(world, palette[i as usize], &mut taken)
            })?
        }
    };
    let inverse = write_voxels(world, &placed, |i| map[i as usize], &mut report)
        .map_err(|e| e.to_string())?;
    Ok((report, inverse))
}

/// The size in voxels (voxbrick axes) of what importing `bytes` would place.
pub fn extent(bytes: &[u8]) -> Result<IVec3, String> {
    let (_, placed, _) = prepare(bytes, &ImportOptions::default())?;
    Ok(bounds(&placed).map_or(IVec3::ZERO, |(lo, hi)| hi - lo + 1))
}

/// A parsed file, its placed voxels (grid coordinates, 0-based palette index), the report.
type Prepared = (DotVoxData, Vec<(IVec3, u8)>, ImportReport);

/// Parses, places every instance and shifts into the grid (see the module docs).
fn prepare(bytes: &[u8], options: &ImportOptions) -> Result<Prepared, String> {
    let data = parse(bytes)?;
    let mut report = ImportReport {
        models: data.models.len(),
        ..Default::default()
    };
    let unmapped = unmapped_chunks(bytes);
    report.dropped.extend(
        unmapped
            .iter()
            .map(|(id, n)| format!("unsupported chunk {id} ignored (×{n})")),
    );
    let mut placed = place_instances(&data, options, &mut report).map_err(|e| {
        // A shape whose model is not in SIZE/XYZI chunks: its voxels are elsewhere.
        if e.starts_with(MISSING_MODEL) && !unmapped.is_empty() {
            let chunks: Vec<String> = unmapped.keys().map(|id| describe_chunk(id)).collect();
            format!(
                "{e}: its voxels are not in SIZE/XYZI chunks; the file also holds {}, which voxbrick does not read",
                chunks.join(", ")
            )
        } else {
            e
        }
    })?;
    let declared: u64 = data.models.iter().map(|m| m.voxels.len() as u64).sum();
    if placed.is_empty() && declared > 0 {
        // Never less than the file declares without saying so: nothing placed is an error.
        let why = if report.dropped.is_empty() {
            "no model is placed by the scene graph".to_string()
        } else {
            report.dropped.join("; ")
        };
        return Err(format!(
            "nothing to import: the file's {} models hold {declared} voxels, and every one was left out ({why})",
            data.models.len()
        ));
    }
    if let Some((lo, _)) = bounds(&placed) {
        let shift = (-lo).max(IVec3::ZERO) + options.offset;
        if (lo + shift).cmplt(IVec3::ZERO).any() {
            return Err(format!(
                "the offset {} moves voxels below the grid origin",
                options.offset
            ));
        }
        for (p, _) in &mut placed {
            *p += shift;
        }
    }
    Ok((data, placed, report))
}

/// Writes the placed voxels as whole bricks: one restore per touched brick whose touched mask
/// is exactly the imported voxels (other voxels keep what they hold; a later voxel at the
/// same position wins). Much cheaper than single-voxel writes for large models.
fn write_voxels(
    world: &World,
    placed: &[(IVec3, u8)],
    material: impl Fn(u8) -> u8,
    report: &mut ImportReport,
) -> brickmap::Result<brickmap::EditInverse> {
    let mut bricks: HashMap<glam::UVec3, (Mask, Box<[u8; 512]>)> = HashMap::new();
    for &(p, i) in placed {
        let b = (p / 8).as_uvec3();
        let l = p - (p / 8) * 8;
        let bit = brickmap::brick::voxel_bit(l.x, l.y, l.z);
        let entry = bricks
            .entry(b)
            .or_insert_with(|| (Mask::EMPTY, Box::new([0; 512])));
        entry.0.set(bit);
        entry.1[bit] = material(i);
    }
    report.voxels = bricks.values().map(|(mask, _)| mask.count() as u64).sum();
    let mut list: Vec<BrickUndo> = bricks
        .into_iter()
        .map(|(brick, (mask, dense))| {
            let mats: Vec<u8> = mask.ones().map(|bit| dense[bit]).collect();
            let prior = if mats.iter().all(|&m| m == mats[0]) {
                PriorMaterials::Uniform(mats[0])
            } else {
                PriorMaterials::PerVoxel(mats)
            };
            BrickUndo {
                brick,
                prior_mask: mask,
                touched: mask,
                prior,
            }
        })
        .collect();
    list.sort_by_key(|u| (u.brick.x, u.brick.z, u.brick.y));
    Ok(world
        .apply(brickmap::EditOp::Restore(brickmap::EditInverse {
            bricks: list,
        }))?
        .inverse)
}

fn palette_of(data: &DotVoxData) -> Vec<Color> {
    if data.palette.len() >= 256 {
        data.palette[..256].to_vec()
    } else {
        dot_vox::DEFAULT_PALETTE.to_vec()
    }
}

/// A colour-table index holding `c`: an identical colour, else a slot no material uses.
fn colour_slot(
    world: &World,
    c: Color,
    taken: &mut std::collections::HashSet<u8>,
) -> Result<u8, String> {
    let rgb = [c.r, c.g, c.b];
    let table = world.materials();
    if let Some(i) = (0..=255u8).find(|&i| table.colour(i) == rgb) {
        return Ok(i);
    }
    let used: std::collections::HashSet<u8> = (0..table.len())
        .filter_map(|i| table.get(i as u8).ok())
        .map(|m| m.colour)
        .collect();
    let free = (0..=255u8)
        .rev()
        .find(|i| !used.contains(i) && !taken.contains(i));
    drop(table);
    let slot = free.ok_or("no free colour slot: every colour is used by a material")?;
    taken.insert(slot);
    world.set_colour(slot, rgb);
    Ok(slot)
}

fn bounds(placed: &[(IVec3, u8)]) -> Option<(IVec3, IVec3)> {
    let first = placed.first()?.0;
    Some(
        placed
            .iter()
            .fold((first, first), |(lo, hi), (p, _)| (lo.min(*p), hi.max(*p))),
    )
}

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
struct Transform {
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
fn place_instances(
    data: &DotVoxData,
    options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Vec<(IVec3, u8)>, String> {
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
    for (note, n) in notes {
        report.dropped.push(if n > 1 {
            format!("{note} (×{n})")
        } else {
            note
        });
    }
    Ok(out)
}

#[allow(clippy::too_many_arguments)]
fn walk(
    data: &DotVoxData,
    node: u32,
    parent: Transform,
    depth: usize,
    options: &ImportOptions,
    out: &mut Vec<(IVec3, u8)>,
    report: &mut ImportReport,
    notes: &mut BTreeMap<String, usize>,
) -> Result<(), String> {
    if depth > MAX_DEPTH {
        return Err(format!(
            "scene graph deeper than {MAX_DEPTH} levels (or cyclic)"
        ));
    }
    let Some(n) = data.scenes.get(node as usize) else {
        return Err(format!("scene graph refers to missing node {node}"));
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
                        return Err(format!(
                            "node {node}: translation {t:?} is not three integers within ±2^20"
                        ));
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
                    .ok_or_else(|| format!("{MISSING_MODEL} {}", m.model_id))?;
                place_model(model, parent, out)?;
                report.instances += 1;
            }
            Ok(())
        }
    }
}

fn place_model(model: &Model, tr: Transform, out: &mut Vec<(IVec3, u8)>) -> Result<(), String> {
    if out.len() as u64 + model.voxels.len() as u64 > MAX_PLACED_VOXELS {
        return Err(format!(
            "the scene places more than {MAX_PLACED_VOXELS} voxels"
        ));
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

/// Creates (or reuses) one material per used palette entry from its MATL chunk, with the
/// colour index `colour_of(palette index)` gives; returns palette index → material index.
fn install_materials(
    world: &World,
    data: &DotVoxData,
    placed: &[(IVec3, u8)],
    report: &mut ImportReport,
    mut colour_of: impl FnMut(u8) -> Result<u8, String>,
) -> Result<[u8; 256], String> {
    let matl: HashMap<u32, &dot_vox::Dict> = data
        .materials
        .iter()
        .map(|m| (m.id, &m.properties))
        .collect();
    let mut used = [false; 256];
    for (_, i) in placed {
        used[*i as usize] = true;
    }
    let fresh = world.read().solid_count() == 0;
    let mut map = [0u8; 256];
    let mut created: HashMap<Material, u8> = HashMap::new();
    let mut params = ParamSlots::default();
    let mut notes = BTreeMap::<String, usize>::new();
    for i in (0..256).filter(|&i| used[i]) {
        let props = matl.get(&(i as u32 + 1)).copied();
        let colour = colour_of(i as u8)?;
        let m = material_from_matl(world, colour, props, &mut params, &mut notes)?;
        let existing = {
            let table = world.materials();
            (0..table.len())
                .find(|&k| table.get(k as u8).ok() == Some(m))
                .map(|k| k as u8)
        };
        let index = match (created.get(&m), existing) {
            (Some(&idx), _) => idx,
            (None, Some(idx)) if !fresh || idx != 0 || !created.is_empty() => idx,
            // In a new scene the default material 0 is replaced by the first one imported.
            (None, _) if fresh && created.is_empty() => {
                world.set_material(0, m).map_err(|e| e.to_string())?;
                0
            }
            (None, _) => world.push_material(m).map_err(|e| e.to_string())?,
        };
        created.insert(m, index);
        map[i] = index;
    }
    report.materials = created.len();
    for (note, n) in notes {
        report.dropped.push(if n > 1 {
            format!("{note} (×{n})")
        } else {
            note
        });
    }
    Ok(map)
}

/// Parameter-table slots handed out during one import (slot 0 of each table stays the
/// default; values already present are reused).
#[derive(Default)]
struct ParamSlots {
    next: HashMap<MaterialKind, u8>,
}

impl ParamSlots {
    fn slot(&mut self, world: &World, kind: MaterialKind, value: f32) -> Result<u8, String> {
        let table = world.materials();
        for i in 0..brickmap::material::PARAMS as u8 {
            if (table.param(kind, i).map_err(|e| e.to_string())? - value).abs() < 1e-4 {
                return Ok(i);
            }
        }
        drop(table);
        let next = self.next.entry(kind).or_insert(2);
        if *next as usize >= brickmap::material::PARAMS {
            return Err(format!(
                "more than {} distinct {kind:?} parameters",
                brickmap::material::PARAMS - 2
            ));
        }
        let i = *next;
        *next += 1;
        world.set_param(kind, i, value).map_err(|e| e.to_string())?;
        Ok(i)
    }
}

fn material_from_matl(
    world: &World,
    colour: u8,
    props: Option<&dot_vox::Dict>,
    params: &mut ParamSlots,
    notes: &mut BTreeMap<String, usize>,
) -> Result<Material, String> {
    let lambertian = Material::lambertian(colour);
    let Some(props) = props else {
        return Ok(lambertian);
    };
    let num = |key: &str| {
        props
            .get(key)
            .and_then(|v| v.trim().parse::<f32>().ok())
            .filter(|v| v.is_finite())
    };
    match props.get("_type").map(String::as_str) {
        None | Some("_diffuse") => Ok(lambertian),
        Some("_metal") => {
            let rough = num("_rough").unwrap_or(0.0).clamp(0.0, 1.0);
            let param = (rough * 63.0).round() as u8; // the roughness table is i/63
            Ok(Material {
                kind: MaterialKind::Metal,
                param,
                colour,
            })
        }
        Some("_glass") => {
            let ior = match (num("_ri"), num("_ior")) {
                (Some(ri), _) => ri,
                // MagicaVoxel 0.99+ stores ior − 1; older files the index itself.
                (None, Some(v)) if v < 1.0 => v + 1.0,
                (None, Some(v)) => v,
                (None, None) => 1.5,
            };
            let param = params.slot(world, MaterialKind::Dielectric, ior.clamp(1.0, 4.0))?;
            Ok(Material {
                kind: MaterialKind::Dielectric,
                param,
                colour,
            })
        }
        Some("_emit") => {
            let strength = num("_emit").unwrap_or(1.0).max(0.0)
                * 2f32.powf(num("_flux").unwrap_or(0.0).clamp(0.0, 16.0));
            let param = params.slot(world, MaterialKind::Emissive, strength.min(1e6))?;
            Ok(Material {
                kind: MaterialKind::Emissive,
                param,
                colour,
            })
        }
        Some(other) => {
            *notes
                .entry(format!("material type {other} imported as lambertian"))
                .or_default() += 1;
            Ok(lambertian)
        }
    }
}

/// Top-level chunks inside MAIN that `dot_vox` does not map, as report lines.
fn unmapped_chunks(bytes: &[u8]) -> BTreeMap<String, usize> {
    const KNOWN: [&[u8; 4]; 10] = [
        b"SIZE", b"XYZI", b"RGBA", b"MATL", b"nTRN", b"nGRP", b"nSHP", b"LAYR", b"IMAP", b"PACK",
    ];
    let mut counts = BTreeMap::<String, usize>::new();
    let u32_at = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    // "VOX " version, then MAIN: id, content size, children size.
    let mut at = 8 + 12 + u32_at(12).unwrap_or(0);
    while let (Some(id), Some(n), Some(m)) = (bytes.get(at..at + 4), u32_at(at + 4), u32_at(at + 8))
    {
        if !KNOWN.iter().any(|k| k.as_slice() == id) {
            *counts
                .entry(String::from_utf8_lossy(id).into_owned())
                .or_default() += 1;
        }
        let Some(next) = at
            .checked_add(12)
            .and_then(|a| a.checked_add(n))
            .and_then(|a| a.checked_add(m))
        else {
            break;
        };
        at = next;
    }
    counts
}

/// What a chunk that may hold a model's voxels is, for the error when a shape's model is
/// missing.
fn describe_chunk(id: &str) -> String {
    match id {
        "TDCZ" => "TDCZ (Teardown's compressed voxel data)".into(),
        other => other.to_string(),
    }
}

/// The `.vox` data of a scene: ≤ 256³ models under one group, a palette slot per used
/// material (at most 255), MATL for each.
pub fn export_data(world: &World) -> Result<DotVoxData, String> {
    let view = world.read();
    let table = view.materials();
    let mut slot_of = [u8::MAX; 256];
    let mut used: Vec<u8> = Vec::new();
    let mut chunks: BTreeMap<(i32, i32, i32), Vec<Voxel>> = BTreeMap::new();
    let mut failure = None;
    view.for_each_brick(|b, mask, mats| {
        let base = b.as_ivec3() * 8;
        for (k, bit) in mask.ones().enumerate() {
            let m = match mats {
                BrickMaterials::Uniform(m) => m,
                BrickMaterials::PerVoxel(v) => v[k],
            };
            if slot_of[m as usize] == u8::MAX {
                if used.len() == 255 {
                    failure.get_or_insert_with(|| {
                        "the scene uses more than 255 materials; .vox holds at most 255".to_string()
                    });
                    return;
                }
                slot_of[m as usize] = used.len() as u8;
                used.push(m);
            }
            let p = base + IVec3::new((bit % 8) as i32, (bit / 8 % 8) as i32, (bit / 64) as i32);
            let vox = IVec3::new(p.x, -p.z - 1, p.y);
            let chunk = (
                vox.x.div_euclid(256),
                vox.y.div_euclid(256),
                vox.z.div_euclid(256),
            );
            let local = vox - IVec3::new(chunk.0, chunk.1, chunk.2) * 256;
            chunks.entry(chunk).or_default().push(Voxel {
                x: local.x as u8,
                y: local.y as u8,
                z: local.z as u8,
                i: slot_of[m as usize],
            });
        }
    });
    if let Some(f) = failure {
        return Err(f);
    }
    let mut palette = dot_vox::DEFAULT_PALETTE.to_vec();
    let mut materials = Vec::new();
    for (slot, &m) in used.iter().enumerate() {
        let mat = table.get(m).map_err(|e| e.to_string())?;
        let [r, g, b] = table.colour(mat.colour);
        palette[slot] = Color { r, g, b, a: 255 };
        let param = table
            .param(mat.kind, mat.param)
            .map_err(|e| e.to_string())?;
        let mut props = dot_vox::Dict::new();
        let mut set = |k: &str, v: String| {
            props.insert(k.to_string(), v);
        };
        match mat.kind {
            MaterialKind::Lambertian => set("_type", "_diffuse".into()),
            MaterialKind::Metal => {
                set("_type", "_metal".into());
                set("_metal", "1".into());
                set("_rough", format!("{param}"));
            }
            MaterialKind::Dielectric => {
                set("_type", "_glass".into());
                set("_trans", "1".into());
                set("_ior", format!("{}", param - 1.0));
                set("_ri", format!("{param}"));
            }
            MaterialKind::Emissive => {
                set("_type", "_emit".into());
                let emit = param.min(1.0);
                let flux = if param > 1.0 { param.log2() } else { 0.0 };
                set("_emit", format!("{emit}"));
                set("_flux", format!("{flux}"));
            }
        }
        materials.push(dot_vox::Material {
            id: slot as u32 + 1,
            properties: props,
        });
    }
    // Scene graph: 0 root transform → 1 group → (transform → shape) per model.
    let mut scenes = vec![
        SceneNode::Transform {
            attributes: Default::default(),
            frames: vec![dot_vox::Frame::new(Default::default())],
            child: 1,
            layer_id: u32::MAX,
        },
        SceneNode::Group {
            attributes: Default::default(),
            children: Vec::new(),
        },
    ];
    let mut models = Vec::new();
    for ((cx, cy, cz), voxels) in chunks {
        let size = voxels.iter().fold(IVec3::ONE, |s, v| {
            s.max(IVec3::new(v.x as i32, v.y as i32, v.z as i32) + 1)
        });
        let t = IVec3::new(cx, cy, cz) * 256 + size / 2;
        let transform_id = scenes.len() as u32;
        let mut frame = dot_vox::Dict::new();
        frame.insert("_t".into(), format!("{} {} {}", t.x, t.y, t.z));
        scenes.push(SceneNode::Transform {
            attributes: Default::default(),
            frames: vec![dot_vox::Frame::new(frame)],
            child: transform_id + 1,
            layer_id: 0,
        });
        scenes.push(SceneNode::Shape {
            attributes: Default::default(),
            models: vec![dot_vox::ShapeModel {
                model_id: models.len() as u32,
                attributes: Default::default(),
            }],
        });
        if let SceneNode::Group { children, .. } = &mut scenes[1] {
            children.push(transform_id);
        }
        models.push(Model {
            size: Size {
                x: size.x as u32,
                y: size.y as u32,
                z: size.z as u32,
            },
            voxels,
        });
    }
    let mut layer = dot_vox::Dict::new();
    layer.insert("_name".into(), "voxbrick".into());
    Ok(DotVoxData {
        version: 150,
        index_map: dot_vox::DEFAULT_INDEX_MAP.to_vec(),
        models,
        palette,
        materials,
        scenes,
        layers: vec![dot_vox::Layer { attributes: layer }],
    })
}

/// Exports a scene to a `.vox` file, atomically.
pub fn export_file(scene: &Scene, path: &Path) -> Result<ExportReport, FormatError> {
    let data = export_data(&scene.world).map_err(|m| FormatError::invalid(path, m))?;
    let mut bytes = Vec::new();
    data.write_vox(&mut bytes)
        .map_err(|e| FormatError::io(path, e))?;
    crate::atomic::write_atomic(path, |w| w.write_all(&bytes))
        .map_err(|e| FormatError::io(path, e))?;
    Ok(ExportReport {
        models: data.models.len(),
        voxels: data.models.iter().map(|m| m.voxels.len() as u64).sum(),
        materials: data.materials.len(),
        bytes: bytes.len() as u64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_bytes_decode_to_signed_permutations() {
        assert_eq!(decode_rotation(0b0000100), Some(IMat3::IDENTITY));
        let mut valid = 0;
        for b in 0..=127u8 {
            if let Some(m) = decode_rotation(b) {
                valid += 1;
                assert!(m.det() == 1 || m.det() == -1, "{b}: {m:?}");
            }
        }
        assert_eq!(valid, 48, "6 permutations × 8 sign patterns");
        assert_eq!(decode_rotation(0b0000011), None);
        assert_eq!(decode_rotation(0b0000000), None);
    }
}
