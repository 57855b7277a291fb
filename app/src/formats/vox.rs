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

mod check;
mod error;
mod export;
mod graph;
mod materials;
mod objects;

pub use error::VoxError;
pub use export::*;
use graph::*;
use materials::*;
pub use objects::{
    ObjectImport, ObjectsInto, export_objects, export_objects_data, import_objects, objects_into,
};

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
pub fn parse(bytes: &[u8]) -> Result<DotVoxData, VoxError> {
    if let Some((x, y, z)) = slab6_dims(bytes) {
        return Err(VoxError::Slab6(x, y, z));
    }
    check::check(bytes)?;
    let parsed = std::panic::catch_unwind(|| dot_vox::load_bytes(bytes));
    match parsed {
        Ok(Ok(data)) => Ok(data),
        Ok(Err(e)) => Err(VoxError::Malformed(e.to_string())),
        Err(_) => Err(VoxError::Malformed(
            "the parser failed on malformed data".into(),
        )),
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
    let invalid = |e: VoxError| FormatError::vox(path, e);
    let (data, placed, mut report) = prepare(bytes, options).map_err(invalid)?;
    let top = bounds(&placed).map_or(IVec3::ZERO, |b| b.1);
    let dims = GridDims::from_voxels((top + 1).max(IVec3::ONE).as_uvec3())
        .map_err(|_| invalid(VoxError::TooLarge(top + 1)))?;
    let world_error = |e| FormatError::world(path, e);
    let world =
        World::new(dims, brickmap::WorldConfig::with_workers(workers)).map_err(world_error)?;
    let mut params = render::SceneParams::framing(dims.voxels().as_dvec3());
    if let Some((lo, hi)) = bounds(&placed) {
        // Framed whole (the default camera's direction), as the editor's "frame the scene".
        params.camera = params.camera.framing(lo.as_dvec3(), (hi + 1).as_dvec3()).0;
    }
    // A new scene takes the file's palette as its colour table, index for index.
    let palette = palette_of(&data);
    for (i, c) in palette.iter().enumerate() {
        world.set_colour(i as u8, [c.r, c.g, c.b]);
    }
    let map = install_materials(&world, &data, &placed, &mut report, Ok).map_err(invalid)?;
    world
        .apply_unrecorded(voxels_edit(&placed, |i| map[i as usize], &mut report))
        .map_err(world_error)?;
    world.take_dirty();
    Ok((Scene::new(world, params), report))
}

/// Imports `.vox` bytes into an existing world. With `material`, every voxel gets that
/// material; otherwise colours are merged into the colour table (an identical colour is
/// reused, else a slot no material uses) and identical materials are reused. Voxels that
/// land outside the grid are dropped and reported. Returns the one voxel edit that writes
/// the voxels, for the caller to apply (the editor: to its active object); colours and
/// materials it added stay.
pub fn import_into(
    world: &World,
    bytes: &[u8],
    options: &ImportOptions,
    material: Option<u8>,
) -> Result<(ImportReport, brickmap::EditOp), VoxError> {
    let (data, mut placed, mut report) = prepare(bytes, options)?;
    let dims = world.dims();
    let before = placed.len();
    placed.retain(|(p, _)| dims.contains_voxel(*p));
    if placed.is_empty() && before > 0 {
        return Err(VoxError::OutsideGrid {
            voxels: before,
            grid: dims.voxels(),
        });
    }
    if placed.len() < before {
        report.dropped.push(format!(
            "{} voxels outside the grid dropped",
            before - placed.len()
        ));
    }
    let map = match material {
        Some(m) => {
            world.materials().check(m as u32)?;
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
    let edit = voxels_edit(&placed, |i| map[i as usize], &mut report);
    Ok((report, edit))
}

/// The size in voxels (voxbrick axes) of what importing `bytes` would place.
pub fn extent(bytes: &[u8]) -> Result<IVec3, VoxError> {
    let (_, placed, _) = prepare(bytes, &ImportOptions::default())?;
    Ok(bounds(&placed).map_or(IVec3::ZERO, |(lo, hi)| hi - lo + 1))
}

/// A parsed file, its placed voxels (grid coordinates, 0-based palette index), the report.
impl ImportReport {
    /// Adds what was dropped, each note once with how often it happened.
    fn add_dropped(&mut self, notes: BTreeMap<String, usize>) {
        for (note, n) in notes {
            self.dropped.push(if n > 1 {
                format!("{note} (×{n})")
            } else {
                note
            });
        }
    }
}

type Prepared = (DotVoxData, Vec<(IVec3, u8)>, ImportReport);

/// Parses, places every instance and shifts into the grid (see the module docs).
fn prepare(bytes: &[u8], options: &ImportOptions) -> Result<Prepared, VoxError> {
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
    let mut placed = place_instances(&data, options, &mut report).map_err(|e| match e {
        // A shape whose model is not in SIZE/XYZI chunks: its voxels are elsewhere.
        VoxError::MissingModel { model, .. } => VoxError::MissingModel {
            model,
            unread: unmapped.keys().map(|id| describe_chunk(id)).collect(),
        },
        e => e,
    })?;
    let declared: u64 = data.models.iter().map(|m| m.voxels.len() as u64).sum();
    if placed.is_empty() && declared > 0 {
        // Never less than the file declares without saying so: nothing placed is an error.
        let why = if report.dropped.is_empty() {
            "no model is placed by the scene graph".to_string()
        } else {
            report.dropped.join("; ")
        };
        return Err(VoxError::NothingPlaced {
            models: data.models.len(),
            voxels: declared,
            why,
        });
    }
    if let Some((lo, _)) = bounds(&placed) {
        let shift = (-lo).max(IVec3::ZERO) + options.offset;
        if (lo + shift).cmplt(IVec3::ZERO).any() {
            return Err(VoxError::BelowOrigin(options.offset));
        }
        for (p, _) in &mut placed {
            *p += shift;
        }
    }
    Ok((data, placed, report))
}

/// The edit that writes the placed voxels as whole bricks: one restore per touched brick
/// whose touched mask is exactly the imported voxels (other voxels keep what they hold; a
/// later voxel at the same position wins). Much cheaper than single-voxel writes for large
/// models.
fn voxels_edit(
    placed: &[(IVec3, u8)],
    material: impl Fn(u8) -> u8,
    report: &mut ImportReport,
) -> brickmap::EditOp {
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
    brickmap::EditOp::Restore(brickmap::EditInverse { bricks: list })
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
) -> Result<u8, VoxError> {
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
    let slot = free.ok_or(VoxError::NoFreeColour)?;
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
