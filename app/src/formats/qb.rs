//! Qubicle binary (`.qb`): a list of named matrices, each a box of true-colour voxels at an
//! integer position. Imported as a scene of objects (a matrix an object, its model the
//! matrix's voxels, placed where the file puts it) and exported from the drawn objects (each
//! written as it shows: turned, at its place).
//!
//! The format (Minddesk's specification): a header of six little-endian u32 — version
//! (1.1.0.0), colour format (0 RGBA, 1 BGRA), z-axis orientation (0 left-handed, 1 right-handed),
//! compression (0 none, 1 run-length per z slice), whether alpha encodes face visibility, the
//! matrix count — then per matrix a name (u8 length + bytes), its size (3 × u32), its position
//! (3 × i32) and its voxels: z slices of y rows of x, a u32 colour each (alpha 0: empty), or
//! per slice runs (`2, count, colour`) and single colours up to the slice's end mark `6`.
//!
//! Axes: a left-handed file's x, y, z are voxbrick's (y up); a right-handed file has x and z
//! swapped (sizes, positions and the order of the voxels), as vengi reads it. Exports are
//! left-handed, RGBA, run-length coded. Colours beyond 256 are reduced (the most used kept,
//! the others mapped to their nearest: the report says how many); every material is
//! lambertian (the format has colour only: an export reports the other kinds it wrote as
//! their colour).

use super::FormatError;
use super::table::{TableBuilder, reduce_colours};
use crate::scene::Scene;
use brickmap::objects::{
    LayerId, Model as VoxelModel, ModelId, NewNode, ObjectTree, Objects, Placement,
};
use brickmap::{GridDims, MaterialKind, World};
use glam::IVec3;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// The most cells (solid or not) a file's matrices may hold together.
pub const MAX_CELLS: u64 = 1 << 28;
/// The longest matrix side.
pub const MAX_SIDE: u32 = 4096;
/// The farthest a matrix's corner may lie from the origin on an axis (the largest grid is
/// far smaller; this keeps every sum of positions and sizes inside i32).
pub const MAX_POSITION: u32 = 1 << 24;

const RLE: u32 = 2;
const NEXT_SLICE: u32 = 6;

/// A matrix as read: its name, size and position in voxbrick's axes, its solid voxels
/// (position in the matrix, sRGB colour).
#[derive(Clone, Debug, PartialEq)]
pub struct Matrix {
    /// Its name.
    pub name: String,
    /// Its size.
    pub size: IVec3,
    /// Its lowest corner's place.
    pub position: IVec3,
    /// Its solid voxels.
    pub voxels: Vec<(IVec3, [u8; 3])>,
}

/// What an import read and changed, or what an export wrote.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct QbReport {
    /// Matrices.
    pub matrices: usize,
    /// Solid voxels.
    pub voxels: u64,
    /// Distinct colours in the file (import) or written (export).
    pub colours: usize,
    /// Colours merged into their nearest kept one (import: beyond 256).
    pub merged_colours: usize,
    /// Export: materials of other kinds than lambertian written as their colour.
    pub as_colour: usize,
    /// Export: hidden objects left out.
    pub hidden: usize,
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b = self.bytes.get(self.at..self.at + 4).ok_or_else(|| {
            format!(
                "the file ends at byte {} inside {what} (truncated)",
                self.bytes.len()
            )
        })?;
        self.at += 4;
        Ok(u32::from_le_bytes(b.try_into().expect("four bytes")))
    }
}

/// Reads the matrices of a `.qb` file, all or nothing; errors name what is wrong and where.
pub fn parse(bytes: &[u8]) -> Result<Vec<Matrix>, String> {
    let mut r = Reader { bytes, at: 0 };
    // The version (1.1.0.0 from Qubicle, others from other tools) says nothing of the layout.
    let _version = r.u32("the header")?;
    let bgra = match r.u32("the header")? {
        0 => false,
        1 => true,
        f => {
            return Err(format!(
                "not a Qubicle binary file: colour format {f} (0 RGBA or 1 BGRA expected)"
            ));
        }
    };
    let right_handed = match r.u32("the header")? {
        0 => false,
        1 => true,
        o => return Err(format!("z-axis orientation {o} (0 or 1 expected)")),
    };
    let compressed = match r.u32("the header")? {
        0 => false,
        1 => true,
        c => return Err(format!("compression {c} (0 or 1 expected)")),
    };
    let _visibility = r.u32("the header")?;
    let count = r.u32("the header")?;
    let mut cells = 0u64;
    let mut out = Vec::new();
    for k in 0..count {
        let start = r.at;
        let len = *bytes
            .get(r.at)
            .ok_or_else(|| format!("the file ends before matrix {k} of {count} (truncated)"))?
            as usize;
        let name = bytes
            .get(r.at + 1..r.at + 1 + len)
            .ok_or_else(|| format!("the file ends inside matrix {k}'s name (truncated)"))?;
        let name = String::from_utf8_lossy(name).into_owned();
        r.at += 1 + len;
        let what = format!("matrix {k} ({name:?}, byte {start})");
        let mut size = [0u32; 3];
        for s in &mut size {
            *s = r.u32(&what)?;
        }
        let mut pos = [0i32; 3];
        for p in &mut pos {
            *p = r.u32(&what)? as i32;
        }
        if pos.iter().any(|p| p.unsigned_abs() > MAX_POSITION) {
            return Err(format!(
                "{what} lies at ({}, {}, {}), beyond ±{MAX_POSITION} voxels",
                pos[0], pos[1], pos[2]
            ));
        }
        if size.iter().any(|&s| s == 0 || s > MAX_SIDE) {
            return Err(format!(
                "{what} declares a {} × {} × {} matrix (each side 1..={MAX_SIDE})",
                size[0], size[1], size[2]
            ));
        }
        cells += size.iter().map(|&s| s as u64).product::<u64>();
        if cells > MAX_CELLS {
            return Err(format!(
                "{what}: the matrices hold more than {MAX_CELLS} cells together"
            ));
        }
        let (sx, sy, sz) = (size[0], size[1], size[2]);
        let mut voxels = Vec::new();
        let mut put = |x: u32, y: u32, z: u32, c: u32| {
            let [a, b, cc, alpha] = c.to_le_bytes();
            if alpha == 0 {
                return;
            }
            let rgb = if bgra { [cc, b, a] } else { [a, b, cc] };
            voxels.push((IVec3::new(x as i32, y as i32, z as i32), rgb));
        };
        if compressed {
            for z in 0..sz {
                let slice = sx as u64 * sy as u64;
                let mut index = 0u64;
                loop {
                    let data = r.u32(&what)?;
                    if data == NEXT_SLICE {
                        break;
                    }
                    let (n, colour) = if data == RLE {
                        (r.u32(&what)? as u64, r.u32(&what)?)
                    } else {
                        (1, data)
                    };
                    if index + n > slice {
                        return Err(format!(
                            "{what}: slice {z} runs past its {sx} × {sy} voxels (at byte {})",
                            r.at
                        ));
                    }
                    if colour.to_le_bytes()[3] != 0 {
                        for i in index..index + n {
                            put((i % sx as u64) as u32, (i / sx as u64) as u32, z, colour);
                        }
                    }
                    index += n;
                }
            }
        } else {
            let need = sx as u64 * sy as u64 * sz as u64 * 4;
            if ((bytes.len() - r.at) as u64) < need {
                return Err(format!(
                    "{what} needs {need} bytes of voxels; the file holds {} more (truncated)",
                    bytes.len() - r.at
                ));
            }
            for z in 0..sz {
                for y in 0..sy {
                    for x in 0..sx {
                        let c = r.u32(&what)?;
                        put(x, y, z, c);
                    }
                }
            }
        }
        let swap = |v: IVec3| {
            if right_handed {
                IVec3::new(v.z, v.y, v.x)
            } else {
                v
            }
        };
        out.push(Matrix {
            name,
            size: swap(IVec3::new(sx as i32, sy as i32, sz as i32)),
            position: swap(IVec3::from(pos)),
            voxels: voxels.into_iter().map(|(v, c)| (swap(v), c)).collect(),
        });
    }
    if r.at != bytes.len() {
        return Err(format!(
            "{} bytes follow the last matrix (byte {})",
            bytes.len() - r.at,
            r.at
        ));
    }
    Ok(out)
}

/// Imports `.qb` bytes as a new scene of objects (`path` only names the file in errors).
pub fn import(bytes: &[u8], path: &Path, workers: usize) -> Result<(Scene, QbReport), FormatError> {
    let invalid = |m: String| FormatError::invalid(path, m);
    let matrices = parse(bytes).map_err(invalid)?;
    if matrices.is_empty() {
        return Err(invalid("the file holds no matrix".into()));
    }
    let mut counts = HashMap::<[u8; 3], u64>::new();
    for m in &matrices {
        for (_, c) in &m.voxels {
            *counts.entry(*c).or_default() += 1;
        }
    }
    let (colour_map, merged) = reduce_colours(&counts, 256);
    let lo = matrices
        .iter()
        .map(|m| m.position)
        .reduce(IVec3::min)
        .expect("a matrix");
    let hi = matrices
        .iter()
        .map(|m| m.position + m.size)
        .reduce(IVec3::max)
        .expect("a matrix");
    let dims = GridDims::from_voxels((hi - lo).as_uvec3())
        .map_err(|e| invalid(format!("the matrices span {} voxels: {e}", hi - lo)))?;
    let world = World::new(dims, brickmap::WorldConfig::with_workers(workers))
        .map_err(|e| FormatError::world(path, e))?;
    let mut table = TableBuilder::new(&world);
    let mut tree = ObjectTree::new();
    let mut models = BTreeMap::new();
    let mut report = QbReport {
        matrices: matrices.len(),
        colours: counts.len(),
        merged_colours: merged,
        ..Default::default()
    };
    for (k, m) in matrices.iter().enumerate() {
        let mut voxels = Vec::with_capacity(m.voxels.len());
        for (v, c) in &m.voxels {
            let material = table
                .material(MaterialKind::Lambertian, 0.0, colour_map[c])
                .map_err(invalid)?;
            voxels.push((*v, material));
        }
        report.voxels += voxels.len() as u64;
        let model = VoxelModel::from_voxels(m.size, voxels, &world.materials())
            .map_err(|e| FormatError::world(path, e))?;
        let id = ModelId(k as u32);
        models.insert(id, model);
        // The pivot rule: a model's corner p lands at p − ⌊s/2⌋ + t.
        let t = m.position - lo + m.size / 2;
        tree.add(
            ObjectTree::ROOT,
            None,
            m.name.clone(),
            Placement::at(t),
            NewNode::Object {
                model: id,
                layer: LayerId(0),
            },
        )
        .map_err(|e| invalid(format!("matrix {k}: {e}")))?;
    }
    let objects = Objects::new(tree, models, &world)
        .map_err(|e| invalid(format!("the matrices do not fit together: {e}")))?;
    Ok((Scene::imported(world, objects), report))
}

/// The scene's drawn objects as matrices (each as it shows: turned, at its place relative
/// to the scene's lowest), and the report's counts.
pub fn matrices_of(scene: &Scene) -> (Vec<Matrix>, QbReport) {
    let objects = scene.objects();
    let tree = objects.tree();
    let view = scene.world.read();
    let table = view.materials();
    let mut report = QbReport::default();
    let mut out = Vec::new();
    let mut colours = std::collections::HashSet::new();
    let mut other_kinds = std::collections::HashSet::new();
    for d in tree.drawn() {
        let Some(model) = objects.model(d.model) else {
            continue;
        };
        let size = model.size();
        let (lo, hi) = d.placement.bounds(size);
        let mut voxels = Vec::new();
        for z in 0..size.z {
            for y in 0..size.y {
                for x in 0..size.x {
                    let v = IVec3::new(x, y, z);
                    let Some(m) = model.voxel(v) else { continue };
                    let Ok(material) = table.get(m) else { continue };
                    if material.kind != MaterialKind::Lambertian {
                        other_kinds.insert(m);
                    }
                    let rgb = table.colour(material.colour);
                    colours.insert(rgb);
                    voxels.push((d.placement.place(v, size) - lo, rgb));
                }
            }
        }
        report.voxels += voxels.len() as u64;
        let name = tree
            .node(d.node)
            .map(|n| n.name.clone())
            .unwrap_or_default();
        out.push(Matrix {
            name,
            size: hi - lo,
            position: lo,
            voxels,
        });
    }
    report.hidden = tree
        .subtree(ObjectTree::ROOT)
        .map(|ids| {
            ids.iter()
                .filter(|id| {
                    matches!(
                        tree.node(**id).map(|n| &n.kind),
                        Ok(brickmap::objects::NodeKind::Object { .. })
                    )
                })
                .count()
        })
        .unwrap_or(0)
        .saturating_sub(out.len());
    report.matrices = out.len();
    report.colours = colours.len();
    report.as_colour = other_kinds.len();
    (out, report)
}

/// The bytes of a `.qb` file holding `matrices` (left-handed, RGBA, run-length coded).
pub fn write(matrices: &[Matrix]) -> Vec<u8> {
    let mut out = Vec::new();
    let u32s = |out: &mut Vec<u8>, v: u32| out.extend_from_slice(&v.to_le_bytes());
    for h in [0x0000_0101, 0, 0, 1, 0, matrices.len() as u32] {
        u32s(&mut out, h);
    }
    for m in matrices {
        let mut name = m.name.as_str();
        while name.len() > 255 {
            let mut end = 255;
            while !name.is_char_boundary(end) {
                end -= 1;
            }
            name = &name[..end];
        }
        out.push(name.len() as u8);
        out.extend_from_slice(name.as_bytes());
        for s in m.size.to_array() {
            u32s(&mut out, s as u32);
        }
        for p in m.position.to_array() {
            u32s(&mut out, p as u32);
        }
        let (sx, sy, sz) = (m.size.x as usize, m.size.y as usize, m.size.z as usize);
        let mut slices = vec![vec![0u32; sx * sy]; sz];
        for (v, c) in &m.voxels {
            slices[v.z as usize][v.y as usize * sx + v.x as usize] =
                u32::from_le_bytes([c[0], c[1], c[2], 255]);
        }
        for slice in slices {
            let mut i = 0;
            while i < slice.len() {
                let c = slice[i];
                let run = slice[i..].iter().take_while(|&&d| d == c).count();
                if run > 2 {
                    for w in [RLE, run as u32, c] {
                        u32s(&mut out, w);
                    }
                } else {
                    for _ in 0..run {
                        u32s(&mut out, c);
                    }
                }
                i += run;
            }
            u32s(&mut out, NEXT_SLICE);
        }
    }
    out
}

/// Exports the scene's drawn objects as a `.qb` file, atomically.
pub fn export(scene: &Scene, path: &Path) -> Result<QbReport, FormatError> {
    let (matrices, report) = matrices_of(scene);
    if matrices.is_empty() {
        return Err(FormatError::invalid(
            path,
            "no object is drawn: nothing to export",
        ));
    }
    let bytes = write(&matrices);
    crate::atomic::write_atomic(path, |w| w.write_all(&bytes))
        .map_err(|e| FormatError::io(path, e))?;
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_matrices_read_back_and_damage_is_named() {
        let m = Matrix {
            name: "box".into(),
            size: IVec3::new(3, 2, 4),
            position: IVec3::new(-2, 5, 7),
            voxels: vec![
                (IVec3::new(0, 0, 0), [255, 0, 0]),
                (IVec3::new(1, 0, 0), [255, 0, 0]),
                (IVec3::new(2, 0, 0), [255, 0, 0]),
                (IVec3::new(2, 1, 3), [0, 10, 200]),
            ],
        };
        let bytes = write(std::slice::from_ref(&m));
        assert_eq!(parse(&bytes).unwrap(), vec![m]);
        let e = parse(&bytes[..bytes.len() - 3]).unwrap_err();
        assert!(e.contains("truncated") && e.contains("\"box\""), "{e}");
        let mut huge = bytes.clone();
        huge[28..32].copy_from_slice(&100_000u32.to_le_bytes());
        assert!(parse(&huge).unwrap_err().contains("100000 × 2 × 4"));
        assert!(
            parse(b"PK\x03\x04\x07\0\0\0")
                .unwrap_err()
                .contains("not a Qubicle")
        );
    }
}
