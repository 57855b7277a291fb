//! What commands carry besides coordinates: a terrain's parameters (`TerrainSpec`, its
//! material `Bands`) and a material (`MaterialSpec`, `KindSpec`), as scripts write them.

use brickmap::terrain::NoiseKind;
use brickmap::{Material, MaterialKind};
use serde::{Deserialize, Serialize};

/// Terrain parameters a command carries (materials are added by the command).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TerrainSpec {
    /// Seed.
    pub seed: u32,
    /// Wavelength of the first octave in voxels.
    pub scale: f64,
    /// Octaves.
    pub octaves: u32,
    /// Surface height range.
    pub height_range: (u32, u32),
    /// Water level (0: none).
    pub water_level: u32,
    /// Noise function (Perlin when absent).
    #[serde(default)]
    pub noise: NoiseKind,
    /// Where each material goes (the thesis scene's bands when absent).
    #[serde(default)]
    pub bands: Bands,
}

/// The terrain's material bands: sand at the water's edge, grass over dirt, then rock, then
/// snow over rock, by surface height; rock below the soil everywhere.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bands {
    /// Surfaces above this fraction of the height range are rock (0..=1).
    pub rock_line: f64,
    /// Surfaces above this fraction are snow (rock_line..=1).
    pub snow_line: f64,
    /// Voxels of grass and dirt over the rock.
    pub soil_depth: u32,
}

impl Default for Bands {
    fn default() -> Self {
        Bands {
            rock_line: 0.62,
            snow_line: 0.86,
            soil_depth: 3,
        }
    }
}

impl TerrainSpec {
    /// The defaults for a grid of `size` voxels (New scene, the terrain panel): hills over
    /// the lower five eighths of the height, water at a quarter.
    pub fn for_size(size: (u32, u32, u32)) -> Self {
        TerrainSpec {
            seed: 2022,
            scale: size.0.max(size.2) as f64 / 2.0,
            octaves: 5,
            height_range: (size.1 / 8, size.1 * 5 / 8),
            water_level: size.1 / 4,
            noise: NoiseKind::Perlin,
            bands: Bands::default(),
        }
    }
}

/// Every change a document can undergo.
/// A material in commands and scripts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialSpec {
    /// Type.
    pub kind: KindSpec,
    /// Parameter-table index.
    pub param: u8,
    /// Colour index.
    pub colour: u8,
}

/// Material types in commands and scripts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum KindSpec {
    /// Lambertian.
    Lambertian,
    /// Metal.
    Metal,
    /// Dielectric.
    Dielectric,
    /// Emissive.
    Emissive,
}

impl From<KindSpec> for MaterialKind {
    fn from(k: KindSpec) -> Self {
        match k {
            KindSpec::Lambertian => MaterialKind::Lambertian,
            KindSpec::Metal => MaterialKind::Metal,
            KindSpec::Dielectric => MaterialKind::Dielectric,
            KindSpec::Emissive => MaterialKind::Emissive,
        }
    }
}

impl From<MaterialKind> for KindSpec {
    fn from(k: MaterialKind) -> Self {
        match k {
            MaterialKind::Lambertian => KindSpec::Lambertian,
            MaterialKind::Metal => KindSpec::Metal,
            MaterialKind::Dielectric => KindSpec::Dielectric,
            MaterialKind::Emissive => KindSpec::Emissive,
        }
    }
}

impl From<Material> for MaterialSpec {
    fn from(m: Material) -> Self {
        MaterialSpec {
            kind: m.kind.into(),
            param: m.param,
            colour: m.colour,
        }
    }
}

impl From<MaterialSpec> for Material {
    fn from(m: MaterialSpec) -> Self {
        Material {
            kind: m.kind.into(),
            param: m.param,
            colour: m.colour,
        }
    }
}
