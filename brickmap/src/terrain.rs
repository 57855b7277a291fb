//! Heightfield terrain as whole bricks: each brick column is built once (a full mask for the
//! solid interior, per-voxel materials only where they differ) and written with one bulk
//! edit. `NoiseTerrain`, the noise-driven generator, builds on this.

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

/// Noise functions the generator can use (also as commands and scripts name them).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum NoiseKind {
    /// Classic gradient noise.
    #[default]
    Perlin,
    /// OpenSimplex (fewer directional artefacts).
    OpenSimplex,
    /// SuperSimplex.
    SuperSimplex,
    /// Value noise (blockier).
    Value,
}

/// Material indices the generator paints with; each band may list colour variants, which
/// are used in the top layers only (so the solid interior stays uniform and costs nothing).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TerrainMaterials {
    /// Surface of low and middle ground.
    pub grass: Vec<u8>,
    /// Under grass.
    pub dirt: Vec<u8>,
    /// Steep and high ground, and everything deep down (first entry).
    pub rock: Vec<u8>,
    /// Shores: surface at or just above the water level.
    pub sand: Vec<u8>,
    /// The highest ground.
    pub snow: Vec<u8>,
    /// Water (a dielectric) filling empty space below the water level.
    pub water: u8,
}

/// Parameters of the noise terrain generator.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainParams {
    /// Seed; the same seed and parameters give the same terrain.
    pub seed: u32,
    /// Noise function.
    pub noise: NoiseKind,
    /// Wavelength of the first octave, in voxels (> 0).
    pub scale: f64,
    /// Octaves of fractal noise, 1..=12.
    pub octaves: u32,
    /// Lowest and highest surface height, in voxels (min < max ≤ grid height).
    pub height_range: (u32, u32),
    /// Water fills empty voxels below this height (0: no water).
    pub water_level: u32,
    /// Above this fraction of the height range the surface is rock; above `snow_line`, snow.
    pub rock_line: f64,
    /// See `rock_line`.
    pub snow_line: f64,
    /// Depth of the dirt or sand under the surface voxel.
    pub soil_depth: u32,
    /// Materials.
    pub materials: TerrainMaterials,
}

impl TerrainParams {
    /// Checks the parameters against a grid.
    pub fn validate(&self, dims: &GridDims) -> crate::Result<()> {
        use crate::BrickmapError::Config;
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(Config(format!(
                "terrain scale {} must be a positive number",
                self.scale
            )));
        }
        if !(1..=12).contains(&self.octaves) {
            return Err(Config(format!(
                "terrain octaves {} must be 1..=12",
                self.octaves
            )));
        }
        let (lo, hi) = self.height_range;
        if lo >= hi || hi > dims.voxels().y as u32 {
            return Err(Config(format!(
                "terrain height range {lo}..{hi} must be increasing and within the grid height {}",
                dims.voxels().y
            )));
        }
        if self.water_level > dims.voxels().y as u32 {
            return Err(Config(format!(
                "water level {} is above the grid",
                self.water_level
            )));
        }
        let lines_ok =
            (0.0..=1.0).contains(&self.rock_line) && (0.0..=1.0).contains(&self.snow_line);
        if !lines_ok || self.rock_line > self.snow_line {
            return Err(Config(
                "rock and snow lines must be fractions with rock ≤ snow".into(),
            ));
        }
        let m = &self.materials;
        if [&m.grass, &m.dirt, &m.rock, &m.sand, &m.snow]
            .iter()
            .any(|v| v.is_empty())
        {
            return Err(Config(
                "every terrain band needs at least one material".into(),
            ));
        }
        Ok(())
    }
}

/// A [`crate::ColumnSource`] for noise terrain. Build with [`NoiseTerrain::new`] and apply
/// with [`NoiseTerrain::edit`].
pub struct NoiseTerrain {
    params: TerrainParams,
    dims: GridDims,
    noise: Box<dyn noise::NoiseFn<f64, 2> + Send + Sync>,
}

impl NoiseTerrain {
    /// A generator for a grid, after validating the parameters.
    pub fn new(params: TerrainParams, dims: GridDims) -> crate::Result<Self> {
        use noise::{Fbm, MultiFractal, OpenSimplex, Perlin, SuperSimplex, Value};
        params.validate(&dims)?;
        let (seed, octaves) = (params.seed, params.octaves as usize);
        let noise: Box<dyn noise::NoiseFn<f64, 2> + Send + Sync> = match params.noise {
            NoiseKind::Perlin => Box::new(Fbm::<Perlin>::new(seed).set_octaves(octaves)),
            NoiseKind::OpenSimplex => Box::new(Fbm::<OpenSimplex>::new(seed).set_octaves(octaves)),
            NoiseKind::SuperSimplex => {
                Box::new(Fbm::<SuperSimplex>::new(seed).set_octaves(octaves))
            }
            NoiseKind::Value => Box::new(Fbm::<Value>::new(seed).set_octaves(octaves)),
        };
        Ok(Self {
            params,
            dims,
            noise,
        })
    }

    /// The edit that replaces the whole grid by this terrain.
    pub fn edit(self) -> EditOp {
        EditOp::Generate(crate::edit::Generator(std::sync::Arc::new(self)))
    }

    /// Surface height of column (x, z): solid for y < height.
    pub fn height(&self, x: i32, z: i32) -> i32 {
        let p = &self.params;
        let f = 1.0 / p.scale;
        let n = self.noise.get([x as f64 * f, z as f64 * f]);
        let t = (n * 0.5 + 0.5).clamp(0.0, 1.0);
        let (lo, hi) = (p.height_range.0 as f64, p.height_range.1 as f64);
        (lo + t * (hi - lo)).round() as i32
    }

    /// Material of solid voxel `p` in a column of surface height `h`.
    fn material(&self, p: IVec3, h: i32) -> u8 {
        let params = &self.params;
        let m = &params.materials;
        let depth = h - 1 - p.y;
        let soil = params.soil_depth as i32;
        if depth > soil {
            return m.rock[0];
        }
        let (lo, hi) = (params.height_range.0 as f64, params.height_range.1 as f64);
        let level = (h as f64 - lo) / (hi - lo);
        let band = if h <= params.water_level as i32 + 1 {
            &m.sand
        } else if level >= params.snow_line {
            if depth == 0 { &m.snow } else { &m.rock }
        } else if level >= params.rock_line {
            &m.rock
        } else if depth == 0 {
            &m.grass
        } else {
            &m.dirt
        };
        band[variant(params.seed, p) % band.len()]
    }
}

/// A well-mixed hash of a voxel position, for colour variants.
fn variant(seed: u32, p: IVec3) -> usize {
    let mut h = (p.x as u32 as u64) | (p.y as u32 as u64) << 21 | (p.z as u32 as u64) << 42;
    h ^= (seed as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((h ^ (h >> 31)) >> 8) as usize
}

impl crate::edit::ColumnSource for NoiseTerrain {
    fn column(&self, bx: u32, bz: u32, emit: &mut dyn FnMut(u32, Mask, PriorMaterials)) {
        let base = IVec3::new(bx as i32 * 8, 0, bz as i32 * 8);
        let mut h = [0i32; 64];
        for z in 0..8 {
            for x in 0..8 {
                h[(x + 8 * z) as usize] = self.height(base.x + x, base.z + z);
            }
        }
        let (lo, hi) = (*h.iter().min().unwrap_or(&0), *h.iter().max().unwrap_or(&0));
        let water = self.params.water_level as i32;
        let top = hi.max(water).min(self.dims.voxels().y);
        let soil = self.params.soil_depth as i32;
        let mut bytes = Vec::with_capacity(512);
        for by in 0..(top + 7) / 8 {
            let (y0, y1) = (by * 8, by * 8 + 8);
            // Whole-brick fast paths: deep rock, open water.
            if y1 <= lo - 1 - soil {
                emit(
                    by as u32,
                    Mask::FULL,
                    PriorMaterials::Uniform(self.params.materials.rock[0]),
                );
                continue;
            }
            if y0 >= hi && y1 <= water {
                emit(
                    by as u32,
                    Mask::FULL,
                    PriorMaterials::Uniform(self.params.materials.water),
                );
                continue;
            }
            let mut mask = Mask::EMPTY;
            bytes.clear();
            for z in 0..8 {
                for y in 0..8 {
                    for x in 0..8 {
                        let wy = y0 + y;
                        let height = h[(x + 8 * z) as usize];
                        let m = if wy < height {
                            self.material(base + IVec3::new(x, wy, z), height)
                        } else if wy < water {
                            self.params.materials.water
                        } else {
                            continue;
                        };
                        mask.set(voxel_bit(x, y, z));
                        bytes.push(m);
                    }
                }
            }
            if mask.is_empty() {
                continue;
            }
            let mats = if bytes.iter().all(|&m| m == bytes[0]) {
                PriorMaterials::Uniform(bytes[0])
            } else {
                PriorMaterials::PerVoxel(bytes.clone())
            };
            emit(by as u32, mask, mats);
        }
    }

    fn materials(&self) -> Vec<u8> {
        let m = &self.params.materials;
        let mut all: Vec<u8> = [&m.grass, &m.dirt, &m.rock, &m.sand, &m.snow]
            .into_iter()
            .flatten()
            .copied()
            .collect();
        all.push(m.water);
        all
    }
}

#[cfg(test)]
mod generator_tests {
    use super::*;
    use crate::{Material, MaterialKind, World, WorldConfig};

    fn params() -> TerrainParams {
        TerrainParams {
            seed: 7,
            noise: NoiseKind::Perlin,
            scale: 40.0,
            octaves: 4,
            height_range: (6, 40),
            water_level: 18,
            rock_line: 0.7,
            snow_line: 0.9,
            soil_depth: 3,
            materials: TerrainMaterials {
                grass: vec![1, 2],
                dirt: vec![3],
                rock: vec![4, 5],
                sand: vec![6],
                snow: vec![7],
                water: 8,
            },
        }
    }

    fn world(workers: usize) -> World {
        let w = World::new(
            GridDims::new(6, 6, 5).unwrap(),
            WorldConfig::with_workers(workers),
        )
        .unwrap();
        for c in 1..=7 {
            w.push_material(Material::lambertian(c)).unwrap();
        }
        w.push_material(Material {
            kind: MaterialKind::Dielectric,
            param: 1,
            colour: 9,
        })
        .unwrap();
        w
    }

    #[test]
    fn terrain_is_solid_underground_with_water_above() {
        let w = world(2);
        let dims = w.dims();
        let terrain = NoiseTerrain::new(params(), dims).unwrap();
        let heights: Vec<i32> = (0..dims.voxels().z)
            .flat_map(|z| (0..dims.voxels().x).map(move |x| (x, z)))
            .map(|(x, z)| terrain.height(x, z))
            .collect();
        w.apply(terrain.edit()).unwrap();
        let v = w.read();
        v.validate().unwrap();
        let size = dims.voxels();
        let (mut water, mut sand, mut grass) = (0, 0, 0);
        for z in 0..size.z {
            for x in 0..size.x {
                let h = heights[(x + z * size.x) as usize];
                assert!((6..=40).contains(&h));
                for y in 0..size.y {
                    let got = v.voxel(IVec3::new(x, y, z)).unwrap();
                    if y < h {
                        let m = got.expect("solid underground");
                        assert_ne!(m, 8, "no water inside the ground");
                        if h - 1 - y > 3 {
                            assert_eq!(m, 4, "deep voxels are the first rock material");
                        }
                        sand += (m == 6) as u32;
                        grass += (m == 1 || m == 2) as u32;
                    } else if y < 18 {
                        assert_eq!(got, Some(8), "water fills up to the level");
                        water += 1;
                    } else {
                        assert_eq!(got, None);
                    }
                }
            }
        }
        assert!(
            water > 0 && sand > 0 && grass > 0,
            "water {water} sand {sand} grass {grass}"
        );
        // Solid interior costs no stored bricks.
        assert!(v.memory().full_cells > 0);
    }

    #[test]
    fn deterministic_across_worker_counts_and_undoable() {
        let hashes: Vec<u64> = [1, 2, 3]
            .into_iter()
            .map(|n| {
                let w = world(n);
                let terrain = NoiseTerrain::new(params(), w.dims()).unwrap();
                let done = w.apply(terrain.edit()).unwrap();
                let hash = w.read().content_hash();
                w.apply(EditOp::Restore(done.inverse)).unwrap();
                assert_eq!(w.read().solid_count(), 0, "undo removes the terrain");
                hash
            })
            .collect();
        assert!(hashes.windows(2).all(|h| h[0] == h[1]), "{hashes:?}");
        let w = world(2);
        let other = TerrainParams {
            seed: 8,
            ..params()
        };
        w.apply(NoiseTerrain::new(other, w.dims()).unwrap().edit())
            .unwrap();
        assert_ne!(
            w.read().content_hash(),
            hashes[0],
            "another seed, another terrain"
        );
    }

    #[test]
    fn bad_parameters_are_errors() {
        let dims = GridDims::new(6, 6, 5).unwrap();
        let bad = [
            TerrainParams {
                scale: 0.0,
                ..params()
            },
            TerrainParams {
                scale: f64::NAN,
                ..params()
            },
            TerrainParams {
                octaves: 0,
                ..params()
            },
            TerrainParams {
                height_range: (30, 20),
                ..params()
            },
            TerrainParams {
                height_range: (1, 49),
                ..params()
            },
            TerrainParams {
                water_level: 49,
                ..params()
            },
            TerrainParams {
                rock_line: 0.95,
                ..params()
            },
        ];
        for p in bad {
            assert!(NoiseTerrain::new(p.clone(), dims).is_err(), "{p:?}");
        }
        // A material index beyond the table is refused before any worker runs.
        let w = world(2);
        let mut p = params();
        p.materials.water = 200;
        assert!(
            w.apply(NoiseTerrain::new(p, w.dims()).unwrap().edit())
                .is_err()
        );
        assert_eq!(w.read().solid_count(), 0);
    }
}
