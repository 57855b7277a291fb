//! The compact voxel payload inside a project file ("VXB1", stored base64-encoded).
//!
//! Layout (all integers unsigned LEB128 varints unless marked):
//! ```text
//! "VXB1"                      4 bytes magic
//! N                           number of records
//! N records, one per non-empty brick cell, cells strictly ascending in the order
//! (bx·Z + bz)·Y + by (Z, Y: grid size in bricks):
//!   gap                       cell − previous cell − 1 (previous starts at −1)
//!   kind: u8                  0 full cell · 1 uniform brick · 2 per-voxel brick
//!   kind 0: material: u8      all 512 voxels solid with this material
//!   kind 1: mask[64], material: u8
//!   kind 2: mask[64], runs    (length ≥ 1, material: u8) pairs covering exactly
//!                             popcount(mask) voxels in popcount order
//! ```
//! Mask bytes are the brick's 16 little-endian u32 words (bit of voxel (x,y,z) = x+8y+64z).
//! A full cell costs about 3 bytes, so solid interiors are nearly free; surface bricks cost
//! their 64-byte mask plus their material runs.

use brickmap::{BrickMaterials, GridDims, Mask, PriorMaterials, WorldView};
use glam::UVec3;

const MAGIC: &[u8; 4] = b"VXB1";

/// Encodes every non-empty brick of a world.
pub fn encode(view: &WorldView<'_>) -> Vec<u8> {
    encode_bricks(&view.dims(), |f| view.for_each_brick(f))
}

/// Encodes the non-empty bricks `each` visits, in ascending cell order of `dims` (a world's
/// grid, or a model's grid of bricks).
pub fn encode_bricks(
    dims: &GridDims,
    each: impl FnOnce(&mut dyn FnMut(UVec3, &Mask, BrickMaterials<'_>)),
) -> Vec<u8> {
    let mut records = Vec::new();
    let mut count = 0u64;
    let mut previous: i64 = -1;
    each(&mut |b, mask, mats| {
        let cell = dims.cell_index(b) as i64;
        debug_assert!(cell > previous, "bricks in ascending cell order");
        put_varint(&mut records, (cell - previous - 1) as u64);
        previous = cell;
        count += 1;
        match mats {
            BrickMaterials::Uniform(m) if mask.is_full() => records.extend_from_slice(&[0, m]),
            BrickMaterials::Uniform(m) => {
                records.push(1);
                records.extend_from_slice(bytemuck::bytes_of(mask));
                records.push(m);
            }
            BrickMaterials::PerVoxel(v) => {
                records.push(2);
                records.extend_from_slice(bytemuck::bytes_of(mask));
                let mut i = 0;
                while i < v.len() {
                    let run = v[i..].iter().take_while(|&&m| m == v[i]).count();
                    put_varint(&mut records, run as u64);
                    records.push(v[i]);
                    i += run;
                }
            }
        }
    });
    let mut out = MAGIC.to_vec();
    put_varint(&mut out, count);
    out.extend_from_slice(&records);
    out
}

/// Why a voxel payload cannot be decoded; byte offsets are into the payload.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PayloadError {
    /// The first four bytes are not the magic.
    #[error("voxel payload does not start with VXB1")]
    NoMagic,
    /// The payload ends inside a record (its length).
    #[error("voxel payload truncated at byte {0}")]
    Truncated(usize),
    /// More bricks declared than the bytes can hold.
    #[error("voxel payload declares {declared} bricks but holds at most {most}")]
    TooManyBricks {
        /// Bricks declared.
        declared: u64,
        /// The most the payload's length allows.
        most: usize,
    },
    /// A brick's cell lies outside the grid.
    #[error("brick cell beyond the {}×{}×{} grid at payload byte {at}", bricks.x, bricks.y, bricks.z)]
    CellBeyondGrid {
        /// The grid in bricks.
        bricks: UVec3,
        /// Where.
        at: usize,
    },
    /// A brick record's kind byte is unknown.
    #[error("unknown brick kind {kind} at payload byte {at}")]
    UnknownKind {
        /// The kind byte.
        kind: u8,
        /// Where.
        at: usize,
    },
    /// A brick's mask is empty (such bricks are not stored).
    #[error("empty brick mask at payload byte {0}")]
    EmptyMask(usize),
    /// A material index beyond the scene's table.
    #[error("material {material} at payload byte {at} is beyond the table ({entries} entries)")]
    MaterialBeyondTable {
        /// The index.
        material: u8,
        /// Where.
        at: usize,
        /// Entries in the table.
        entries: usize,
    },
    /// A run of materials longer than the voxels left in its brick (or empty).
    #[error("material run of {run} at payload byte {at} does not fit the brick's {voxels} voxels")]
    RunTooLong {
        /// The run's length.
        run: u64,
        /// Where.
        at: usize,
        /// Voxels in the brick.
        voxels: usize,
    },
    /// A varint of more than 64 bits.
    #[error("varint too long at payload byte {0}")]
    VarintTooLong(usize),
    /// Bytes after the last brick.
    #[error("{0} unexpected bytes after the last brick")]
    TrailingBytes(usize),
}

/// Decodes a payload for a grid and a table of `materials` entries, checking everything:
/// on success every brick is in the grid, every material in the table, every mask matches
/// its materials. Allocation is bounded by the input length.
pub fn decode(
    bytes: &[u8],
    dims: &GridDims,
    materials: usize,
) -> Result<Vec<(UVec3, Mask, PriorMaterials)>, PayloadError> {
    let mut r = Reader { bytes, at: 0 };
    if r.take(4)? != MAGIC {
        return Err(PayloadError::NoMagic);
    }
    let n = r.varint()?;
    // Every record takes at least two bytes: a count beyond that is a lie, not a reason to
    // reserve memory.
    if n > (bytes.len() as u64) / 2 {
        return Err(PayloadError::TooManyBricks {
            declared: n,
            most: bytes.len() / 2,
        });
    }
    let cells = dims.brick_cells() as u64;
    let check = |m: u8, at: usize| {
        if (m as usize) < materials {
            Ok(m)
        } else {
            Err(PayloadError::MaterialBeyondTable {
                material: m,
                at,
                entries: materials,
            })
        }
    };
    let mut out = Vec::with_capacity(n as usize);
    let mut previous: u64 = u64::MAX; // −1
    for _ in 0..n {
        let gap = r.varint()?;
        let cell = previous
            .wrapping_add(1)
            .checked_add(gap)
            .filter(|c| *c < cells)
            .ok_or(PayloadError::CellBeyondGrid {
                bricks: dims.bricks(),
                at: r.at,
            })?;
        previous = cell;
        let brick = dims.cell_coord(cell as usize);
        let kind_at = r.at;
        match r.byte()? {
            0 => {
                let m = check(r.byte()?, r.at - 1)?;
                out.push((brick, Mask::FULL, PriorMaterials::Uniform(m)));
            }
            1 => {
                let mask = r.mask()?;
                let m = check(r.byte()?, r.at - 1)?;
                out.push((brick, mask, PriorMaterials::Uniform(m)));
            }
            2 => {
                let mask = r.mask()?;
                let want = mask.count() as usize;
                let mut mats = Vec::with_capacity(want);
                while mats.len() < want {
                    let run = r.varint()?;
                    let m = check(r.byte()?, r.at - 1)?;
                    if run == 0 || run > (want - mats.len()) as u64 {
                        return Err(PayloadError::RunTooLong {
                            run,
                            at: r.at,
                            voxels: want,
                        });
                    }
                    mats.resize(mats.len() + run as usize, m);
                }
                out.push((brick, mask, PriorMaterials::PerVoxel(mats)));
            }
            k => {
                return Err(PayloadError::UnknownKind {
                    kind: k,
                    at: kind_at,
                });
            }
        }
    }
    if r.at != bytes.len() {
        return Err(PayloadError::TrailingBytes(bytes.len() - r.at));
    }
    Ok(out)
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], PayloadError> {
        let end = self.at.checked_add(n).filter(|e| *e <= self.bytes.len());
        let end = end.ok_or(PayloadError::Truncated(self.bytes.len()))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn byte(&mut self) -> Result<u8, PayloadError> {
        Ok(self.take(1)?[0])
    }
    fn mask(&mut self) -> Result<Mask, PayloadError> {
        let at = self.at;
        let mask: Mask = bytemuck::pod_read_unaligned(self.take(64)?);
        if mask.is_empty() {
            return Err(PayloadError::EmptyMask(at));
        }
        Ok(mask)
    }
    fn varint(&mut self) -> Result<u64, PayloadError> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = self.byte()?;
            v |= ((b & 0x7f) as u64) << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(PayloadError::VarintTooLong(self.at))
    }
}

fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

#[cfg(test)]
mod tests {
    use super::*;
    use brickmap::{EditOp, Mode, Shape, World, WorldConfig, terrain};
    use glam::DVec3;

    fn world() -> World {
        let w = World::new(
            GridDims::new(6, 4, 6).unwrap(),
            WorldConfig::with_workers(2),
        )
        .unwrap();
        for c in 0..3 {
            w.push_material(brickmap::Material::lambertian(c)).unwrap();
        }
        w.apply(terrain::rolling_hills(w.dims())).unwrap();
        let sphere = Shape::Sphere {
            centre: DVec3::splat(20.0),
            radius: 9.0,
        };
        w.apply(EditOp::Shape {
            shape: sphere,
            mode: Mode::Add(2),
        })
        .unwrap();
        w
    }

    #[test]
    fn round_trips_every_kind() {
        let w = world();
        let bytes = encode(&w.read());
        let bricks = decode(&bytes, &w.dims(), 4).unwrap();
        let kinds =
            |k: fn(&(UVec3, Mask, PriorMaterials)) -> bool| bricks.iter().filter(|b| k(b)).count();
        assert!(kinds(|b| b.1.is_full()) > 0);
        assert!(kinds(|b| matches!(b.2, PriorMaterials::PerVoxel(_))) > 0);
        let copy = World::new(w.dims(), WorldConfig::with_workers(3)).unwrap();
        copy.replace_materials(w.materials().clone()).unwrap();
        copy.apply(terrain::set_bricks(bricks)).unwrap();
        assert_eq!(copy.read().content_hash(), w.read().content_hash());
        assert_eq!(encode(&copy.read()), bytes, "the encoding is canonical");
    }

    #[test]
    fn every_truncation_and_corruption_is_an_error() {
        let w = world();
        let bytes = encode(&w.read());
        for cut in 0..bytes.len() {
            assert!(
                decode(&bytes[..cut], &w.dims(), 4).is_err(),
                "truncated at {cut}"
            );
        }
        // Flip bytes: either an error or a valid decode, never a panic; materials stay in range.
        for i in (0..bytes.len()).step_by(7) {
            let mut bad = bytes.clone();
            bad[i] ^= 0x5A;
            if let Ok(bricks) = decode(&bad, &w.dims(), 4) {
                for (_, mask, mats) in bricks {
                    if let PriorMaterials::PerVoxel(v) = mats {
                        assert_eq!(v.len(), mask.count() as usize);
                    }
                }
            }
        }
        assert!(matches!(
            decode(&bytes, &w.dims(), 2).unwrap_err(),
            PayloadError::MaterialBeyondTable { entries: 2, .. }
        ));
        let small = GridDims::new(2, 2, 2).unwrap();
        let e = decode(&bytes, &small, 4).unwrap_err();
        assert!(matches!(e, PayloadError::CellBeyondGrid { .. }), "{e}");
        assert!(e.to_string().contains("beyond the 2×2×2 grid"), "{e}");
    }

    #[test]
    fn hostile_counts_do_not_allocate() {
        let mut bytes = MAGIC.to_vec();
        put_varint(&mut bytes, u64::MAX / 3);
        let err = decode(&bytes, &GridDims::new(1, 1, 1).unwrap(), 1).unwrap_err();
        assert!(matches!(err, PayloadError::TooManyBricks { .. }), "{err}");
        let mut runs = MAGIC.to_vec();
        put_varint(&mut runs, 1);
        runs.extend_from_slice(&[0, 2]);
        runs.extend_from_slice(&[0xFF; 64]);
        put_varint(&mut runs, 1 << 40);
        runs.push(0);
        assert!(matches!(
            decode(&runs, &GridDims::new(1, 1, 1).unwrap(), 1).unwrap_err(),
            PayloadError::RunTooLong { run, voxels: 512, .. } if run == 1 << 40
        ));
    }
}
