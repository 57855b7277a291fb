//! Heightfield terrain as whole bricks: each brick column is built once (a full mask for the
//! solid interior, per-voxel materials only where they differ) and written with one bulk
//! edit. The scene issue's noise-driven generator builds on this.

use crate::brick::{Mask, voxel_bit};
use crate::edit::{BrickUndo, EditInverse, EditOp, PriorMaterials};
use crate::grid::GridDims;
use glam::{IVec3, UVec3};

/// A bulk write of whole bricks: each listed brick's content becomes exactly `mask` with
/// `materials` (one per set bit in popcount order, or one for all). It is a restore whose
/// every voxel is touched, so it returns the usual inverse.
pub fn set_bricks(contents: impl IntoIterator<Item = (UVec3, Mask, PriorMaterials)>) -> EditOp {
    EditOp::Restore(EditInverse {
        bricks: contents
            .into_iter()
            .map(|(brick, mask, prior)| BrickUndo {
                brick,
                prior_mask: mask,
                touched: Mask::FULL,
                prior,
            })
            .collect(),
    })
}

/// Builds the bricks of a heightfield: column (x, z) is solid for `0 ≤ y < heights[x + z·W]`
/// (W = grid width in voxels), and solid voxel (x, y, z) gets `material(x, y, z, height)`.
/// Work is spread over the available cores.
pub fn heightfield(
    dims: GridDims,
    heights: &[i32],
    material: impl Fn(IVec3, i32) -> u8 + Sync,
) -> EditOp {
    let size = dims.voxels();
    assert_eq!(
        heights.len(),
        (size.x * size.z) as usize,
        "one height per column"
    );
    let columns: Vec<UVec3> = (0..dims.bricks().z)
        .flat_map(|z| (0..dims.bricks().x).map(move |x| UVec3::new(x, 0, z)))
        .collect();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let per = columns.len().div_ceil(threads).max(1);
    let material = &material;
    let parts: Vec<Vec<(UVec3, Mask, PriorMaterials)>> = std::thread::scope(|s| {
        let handles: Vec<_> = columns
            .chunks(per)
            .map(|chunk| {
                s.spawn(move || {
                    chunk
                        .iter()
                        .flat_map(|c| column(dims, heights, *c, material))
                        .collect()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("terrain worker panicked"))
            .collect()
    });
    set_bricks(parts.into_iter().flatten())
}

fn column(
    dims: GridDims,
    heights: &[i32],
    c: UVec3,
    material: &(impl Fn(IVec3, i32) -> u8 + Sync),
) -> Vec<(UVec3, Mask, PriorMaterials)> {
    let width = dims.voxels().x;
    let base = IVec3::new(c.x as i32 * 8, 0, c.z as i32 * 8);
    let mut h = [0i32; 64];
    for z in 0..8 {
        for x in 0..8 {
            h[(x + 8 * z) as usize] = heights[((base.x + x) + (base.z + z) * width) as usize];
        }
    }
    let top = h.iter().copied().max().unwrap_or(0).min(dims.voxels().y);
    let mut out = Vec::new();
    let mut bytes = Vec::with_capacity(512);
    for by in 0..(top + 7) / 8 {
        let mut mask = Mask::EMPTY;
        bytes.clear();
        for z in 0..8 {
            for y in 0..8 {
                for x in 0..8 {
                    let height = h[(x + 8 * z) as usize];
                    let wy = by * 8 + y;
                    if wy < height {
                        mask.set(voxel_bit(x, y, z));
                    }
                }
            }
        }
        // Materials in popcount order (x fastest, then y, then z).
        for bit in mask.ones() {
            let (x, y, z) = ((bit % 8) as i32, (bit / 8 % 8) as i32, (bit / 64) as i32);
            let height = h[(x + 8 * z) as usize];
            bytes.push(material(base + IVec3::new(x, by * 8 + y, z), height));
        }
        if mask.is_empty() {
            continue;
        }
        let prior = if bytes.iter().all(|&m| m == bytes[0]) {
            PriorMaterials::Uniform(bytes[0])
        } else {
            PriorMaterials::PerVoxel(bytes.clone())
        };
        out.push((UVec3::new(c.x, by as u32, c.z), mask, prior));
    }
    out
}

/// A deterministic rolling test terrain (sums of sines) filling about half the grid height,
/// with four materials by depth below the surface: 0 grass (top voxel), 1 dirt (next 3),
/// 2 rock, 3 sand (surface below a shore line).
pub fn rolling_hills(dims: GridDims) -> EditOp {
    let size = dims.voxels();
    let (w, d, top) = (size.x, size.z, size.y as f64);
    let mut heights = vec![0i32; (w * d) as usize];
    for z in 0..d {
        for x in 0..w {
            let (fx, fz) = (x as f64, z as f64);
            let n = (fx * 0.021).sin() * 0.5
                + (fz * 0.017 + 1.3).sin() * 0.35
                + ((fx + fz) * 0.043).sin() * 0.15
                + ((fx - 2.0 * fz) * 0.11).sin() * 0.05;
            heights[(x + z * w) as usize] = (top * (0.5 + 0.3 * n)).clamp(1.0, top) as i32;
        }
    }
    let shore = (top * 0.42) as i32;
    heightfield(dims, &heights, move |p, h| {
        let depth = h - 1 - p.y;
        if h <= shore && depth < 3 {
            3
        } else if depth == 0 {
            0
        } else if depth < 4 {
            1
        } else {
            2
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{World, WorldConfig};

    #[test]
    fn heightfield_matches_columns() {
        let dims = GridDims::new(4, 3, 2).unwrap();
        let size = dims.voxels();
        let heights: Vec<i32> = (0..size.x * size.z).map(|i| (i * 7) % 25).collect();
        let world = World::new(dims, WorldConfig::with_workers(2)).unwrap();
        for _ in 0..3 {
            world.push_material(crate::Material::lambertian(3)).unwrap();
        }
        world
            .apply(heightfield(dims, &heights, |p, h| ((h - p.y) % 3) as u8))
            .unwrap();
        let v = world.read();
        v.validate().unwrap();
        for z in 0..size.z {
            for x in 0..size.x {
                let h = heights[(x + z * size.x) as usize];
                for y in 0..size.y {
                    let want = (y < h).then(|| ((h - y) % 3) as u8);
                    assert_eq!(v.voxel(IVec3::new(x, y, z)).unwrap(), want);
                }
            }
        }
    }
}
