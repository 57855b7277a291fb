//! Sponge schematics (`.schem`, versions 1 to 3: Minecraft structures as WorldEdit and its
//! kin write them): a box of blocks named by id (`minecraft:stone[…]`), gzip-compressed NBT.
//! Imported as a scene of one object, each block id made a material through a block table
//! (`assets/schem/blocks.ron`, or an edited copy: [`BlockTable`]); exported (version 2) from
//! the scene as it shows, each material written as a block of the table. Block entities,
//! entities and biomes have no voxbrick counterpart: the import reports what it left out, and
//! blocks missing from the table by name.
//!
//! The format (SpongePowered's specification): `Width`, `Height`, `Length` (unsigned shorts),
//! a `Palette` of block state → index, and the blocks' indices as varints in `BlockData`
//! (versions 1, 2) or `Blocks.Data` (version 3, under a root `Schematic` compound), the block
//! at (x, y, z) the (x + z·Width + y·Width·Length)-th. Minecraft's y is up, as voxbrick's.

mod blocks;
pub mod nbt;

use blocks::Found;
pub use blocks::{BUILTIN_BLOCKS, BlockTable};

use super::FormatError;
use super::table::TableBuilder;
use crate::scene::Scene;
use brickmap::objects::{
    LayerId, Model as VoxelModel, ModelId, NewNode, ObjectTree, Objects, Placement,
};
use brickmap::{GridDims, World};
use glam::IVec3;
use nbt::Tag;
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::Path;

/// The most bytes a decompressed schematic may have.
pub const MAX_NBT_BYTES: u64 = 1 << 30;

/// The Minecraft data version exports declare (1.20.1).
pub const DATA_VERSION: i32 = 3465;

/// What an import read and left out, or what an export wrote.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SchemReport {
    /// The schematic's version.
    pub version: i64,
    /// Width, height, length.
    pub size: IVec3,
    /// Solid voxels.
    pub voxels: u64,
    /// Block ids missing from the table, with their voxel counts (given its unknown material).
    pub unknown: BTreeMap<String, u64>,
    /// Block ids shown as a listed block derived from their name, with that block.
    pub derived: BTreeMap<String, String>,
    /// Block entities left out (chests' contents, signs' text).
    pub block_entities: usize,
    /// Entities left out.
    pub entities: usize,
    /// Whether biomes were left out.
    pub biomes: bool,
    /// Export: materials written as their nearest block (no block of the table has them).
    pub as_nearest: usize,
}

/// Gunzips (or takes as is, when not gzip) at most [`MAX_NBT_BYTES`].
fn inflate(bytes: &[u8]) -> Result<Vec<u8>, String> {
    if !bytes.starts_with(&[0x1f, 0x8b]) {
        return Ok(bytes.to_vec());
    }
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(bytes)
        .take(MAX_NBT_BYTES + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("the gzip stream is damaged: {e}"))?;
    if out.len() as u64 > MAX_NBT_BYTES {
        return Err(format!("it inflates past {MAX_NBT_BYTES} bytes"));
    }
    Ok(out)
}

/// A varint sequence of exactly `count` values, each below `below`.
fn varints(data: &[u8], count: usize, below: usize) -> Result<Vec<u32>, String> {
    let mut out = Vec::with_capacity(count.min(data.len()));
    let mut i = 0;
    while i < data.len() {
        let (mut value, mut shift) = (0u32, 0);
        loop {
            let b = *data
                .get(i)
                .ok_or_else(|| format!("the block data ends inside value {}", out.len()))?;
            i += 1;
            value |= ((b & 0x7f) as u32) << shift;
            if b & 0x80 == 0 {
                break;
            }
            shift += 7;
            if shift > 28 {
                return Err(format!(
                    "value {} of the block data is longer than 5 bytes",
                    out.len()
                ));
            }
        }
        if value as usize >= below {
            return Err(format!(
                "block {} has palette index {value}; the palette has {below}",
                out.len()
            ));
        }
        out.push(value);
        if out.len() > count {
            break;
        }
    }
    if out.len() != count {
        return Err(format!(
            "the block data holds {} blocks; the size says {count}",
            out.len()
        ));
    }
    Ok(out)
}

/// Imports `.schem` bytes as a new scene of one object (`path` only names the file).
pub fn import(
    bytes: &[u8],
    path: &Path,
    table: &BlockTable,
    workers: usize,
) -> Result<(Scene, SchemReport), FormatError> {
    let invalid = |m: String| FormatError::invalid(path, m);
    let raw = inflate(bytes).map_err(invalid)?;
    let (_, root) = nbt::read(&raw).map_err(invalid)?;
    let s = match root.get("Schematic") {
        Some(inner @ Tag::Compound(_)) => inner,
        _ => &root,
    };
    // Version 1 files from some tools omit the tag their specification asks for.
    let version = match s.get("Version").and_then(Tag::int) {
        Some(v) => v,
        None if s.get("BlockData").is_some() && s.get("Palette").is_some() => 1,
        None => return Err(invalid("no Version: not a Sponge schematic".into())),
    };
    if !(1..=3).contains(&version) {
        return Err(invalid(format!(
            "Sponge schematic version {version} (1, 2 or 3 are read)"
        )));
    }
    let side = |name: &str| -> Result<i32, FormatError> {
        match s.get(name) {
            Some(Tag::Short(v)) if *v != 0 => Ok(*v as u16 as i32),
            other => Err(invalid(format!(
                "{name} is {other:?}, not a positive short"
            ))),
        }
    };
    let size = IVec3::new(side("Width")?, side("Height")?, side("Length")?);
    let blocks = if version == 3 {
        s.get("Blocks")
            .ok_or_else(|| invalid("a version 3 schematic without Blocks".into()))?
    } else {
        s
    };
    let (palette, data) = match (
        blocks.get("Palette"),
        blocks.get(if version == 3 { "Data" } else { "BlockData" }),
    ) {
        (Some(Tag::Compound(p)), Some(Tag::ByteArray(d))) => (p, d),
        _ => {
            return Err(invalid(
                "no Palette compound and block data byte array".into(),
            ));
        }
    };
    let mut by_index: Vec<Option<&str>> = vec![None; palette.len()];
    for (state, index) in palette {
        let i = index
            .int()
            .filter(|&i| (0..palette.len() as i64).contains(&i))
            .ok_or_else(|| {
                invalid(format!(
                    "palette entry {state} has index {index:?}; the palette has {}",
                    palette.len()
                ))
            })? as usize;
        if by_index[i].replace(state).is_some() {
            return Err(invalid(format!("palette index {i} is given twice")));
        }
    }
    let count = size.x as usize * size.y as usize * size.z as usize;
    let ids = varints(data, count, palette.len()).map_err(invalid)?;
    let dims = GridDims::from_voxels(size.as_uvec3())
        .map_err(|e| invalid(format!("a {size} schematic: {e}")))?;
    let world = World::new(dims, brickmap::WorldConfig::with_workers(workers))
        .map_err(|e| FormatError::world(path, e))?;
    let mut builder = TableBuilder::new(&world);
    let mut report = SchemReport {
        version,
        size,
        ..Default::default()
    };
    let mut materials: Vec<Option<u8>> = Vec::with_capacity(by_index.len());
    let mut known = Vec::with_capacity(by_index.len());
    for state in &by_index {
        let state = state.unwrap_or("minecraft:air");
        let (spec, found) = table.spec(state);
        if let Found::Derived(base) = &found {
            let id = state.split('[').next().unwrap_or(state).to_string();
            report.derived.insert(id, base.clone());
        }
        known.push(found != Found::Unknown);
        materials.push(match spec {
            None => None,
            Some(s) => Some(
                builder
                    .material(s.kind(), s.value, s.rgb())
                    .map_err(invalid)?,
            ),
        });
    }
    let (w, l) = (size.x as usize, size.z as usize);
    let mut voxels = Vec::new();
    for (i, &id) in ids.iter().enumerate() {
        let Some(m) = materials[id as usize] else {
            continue;
        };
        if !known[id as usize] {
            let name = by_index[id as usize].unwrap_or("?");
            let name = name.split('[').next().unwrap_or(name).to_string();
            *report.unknown.entry(name).or_default() += 1;
        }
        let (x, z, y) = (i % w, (i / w) % l, i / (w * l));
        voxels.push((IVec3::new(x as i32, y as i32, z as i32), m));
    }
    report.voxels = voxels.len() as u64;
    let list_len = |t: Option<&Tag>| match t {
        Some(Tag::List(_, items)) => items.len(),
        _ => 0,
    };
    // Version 1: TileEntities; 2: BlockEntities; 3: Blocks.BlockEntities.
    report.block_entities = list_len(blocks.get("BlockEntities")) + list_len(s.get("TileEntities"));
    report.entities = list_len(s.get("Entities"));
    report.biomes = s.get("Biomes").is_some() || s.get("BiomeData").is_some();
    let model = VoxelModel::from_voxels(size, voxels, &world.materials())
        .map_err(|e| FormatError::world(path, e))?;
    let name = s
        .get("Metadata")
        .and_then(|m| m.get("Name"))
        .and_then(|n| match n {
            Tag::String(s) => Some(s.clone()),
            _ => None,
        })
        .unwrap_or_else(|| "schematic".into());
    let mut tree = ObjectTree::new();
    tree.add(
        ObjectTree::ROOT,
        None,
        name,
        Placement::at(size / 2),
        NewNode::Object {
            model: ModelId(0),
            layer: LayerId(0),
        },
    )
    .map_err(|e| invalid(e.to_string()))?;
    let objects = Objects::new(tree, BTreeMap::from([(ModelId(0), model)]), &world)
        .map_err(|e| invalid(format!("the schematic does not fit: {e}")))?;
    Ok((Scene::imported(world, objects), report))
}

/// The exact box of the solid voxels (None: empty).
fn solid_box(view: &brickmap::WorldView<'_>) -> Option<(IVec3, IVec3)> {
    let (lo, hi) = view.occupied_bounds()?;
    let (mut a, mut b) = (IVec3::MAX, IVec3::MIN);
    for z in lo.z..hi.z {
        for y in lo.y..hi.y {
            for x in lo.x..hi.x {
                let v = IVec3::new(x, y, z);
                if view.voxel(v).ok().flatten().is_some() {
                    a = a.min(v);
                    b = b.max(v + 1);
                }
            }
        }
    }
    (a.x <= b.x).then_some((a, b))
}

/// The scene as it shows as a Sponge schematic (version 2, gzip-compressed NBT).
pub fn write(scene: &Scene, table: &BlockTable) -> Result<(Vec<u8>, SchemReport), String> {
    let view = scene.world.read();
    let (lo, hi) = solid_box(&view).ok_or("the scene has no voxel: nothing to export")?;
    let size = hi - lo;
    if size.max_element() > u16::MAX as i32 {
        return Err(format!(
            "the content is {size} voxels; a schematic's sides are at most {}",
            u16::MAX
        ));
    }
    let materials = view.materials();
    let mut names: Vec<String> = vec!["minecraft:air".into()];
    let mut palette_of: HashMap<u8, u32> = HashMap::new();
    let mut report = SchemReport {
        version: 2,
        size,
        ..Default::default()
    };
    let mut data = Vec::new();
    for y in 0..size.y {
        for z in 0..size.z {
            for x in 0..size.x {
                let m = view.voxel(lo + IVec3::new(x, y, z)).ok().flatten();
                let id = match m {
                    None => 0,
                    Some(m) => {
                        report.voxels += 1;
                        match palette_of.get(&m) {
                            Some(&id) => id,
                            None => {
                                let mat = materials.get(m).map_err(|e| e.to_string())?;
                                let value = materials.param(mat.kind, mat.param).unwrap_or(0.0);
                                let (name, exact) =
                                    table.block_of(mat.kind, value, materials.colour(mat.colour));
                                report.as_nearest += usize::from(!exact);
                                let id = match names.iter().position(|n| n == name) {
                                    Some(k) => k as u32,
                                    None => {
                                        names.push(name.to_string());
                                        names.len() as u32 - 1
                                    }
                                };
                                palette_of.insert(m, id);
                                id
                            }
                        }
                    }
                };
                let mut v = id;
                loop {
                    let b = (v & 0x7f) as u8;
                    v >>= 7;
                    if v == 0 {
                        data.push(b);
                        break;
                    }
                    data.push(b | 0x80);
                }
            }
        }
    }
    let palette: BTreeMap<String, Tag> = names
        .iter()
        .enumerate()
        .map(|(k, n)| (n.clone(), Tag::Int(k as i32)))
        .collect();
    let mut root = BTreeMap::new();
    root.insert("Version".into(), Tag::Int(2));
    root.insert("DataVersion".into(), Tag::Int(DATA_VERSION));
    root.insert("Width".into(), Tag::Short(size.x as u16 as i16));
    root.insert("Height".into(), Tag::Short(size.y as u16 as i16));
    root.insert("Length".into(), Tag::Short(size.z as u16 as i16));
    root.insert("Offset".into(), Tag::IntArray(vec![0, 0, 0]));
    root.insert("PaletteMax".into(), Tag::Int(names.len() as i32));
    root.insert("Palette".into(), Tag::Compound(palette));
    root.insert("BlockData".into(), Tag::ByteArray(data));
    root.insert("BlockEntities".into(), Tag::List(10, Vec::new()));
    let raw = nbt::write("Schematic", &Tag::Compound(root));
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    std::io::Write::write_all(&mut gz, &raw).map_err(|e| e.to_string())?;
    Ok((gz.finish().map_err(|e| e.to_string())?, report))
}

/// Exports the scene as a `.schem`, atomically.
pub fn export(scene: &Scene, path: &Path, table: &BlockTable) -> Result<SchemReport, FormatError> {
    let (bytes, report) = write(scene, table).map_err(|m| FormatError::invalid(path, m))?;
    crate::atomic::write_atomic(path, |w| w.write_all(&bytes))
        .map_err(|e| FormatError::io(path, e))?;
    Ok(report)
}
