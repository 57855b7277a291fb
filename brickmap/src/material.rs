//! The scene material table (≤ 256 packed 16-bit entries), the 256-entry colour table and
//! the per-type parameter tables, laid out exactly as the GPU reads them.
//!
//! Entry layout (16 bits): bits 0–1 type (0 lambertian, 1 metal, 2 dielectric, 3 emissive),
//! bits 2–7 index into that type's parameter table (metal roughness, dielectric IOR, emissive
//! strength; unused for lambertian), bits 8–15 colour index.

use crate::dirty::DirtyRanges;
use crate::error::{BrickmapError, Result};
use bytemuck::{Pod, Zeroable};

/// Entries in each parameter table.
pub const PARAMS: usize = 64;

/// How a material scatters light (see docs/DESIGN.md's light-transport specification).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MaterialKind {
    /// Ideal diffuse, albedo = colour.
    Lambertian = 0,
    /// Conductor: mirror at roughness 0, GGX above; reflectance = colour.
    Metal = 1,
    /// Smooth dielectric with an IOR; transmission tinted by colour.
    Dielectric = 2,
    /// Emits colour × strength from every face, reflects nothing.
    Emissive = 3,
}

/// One material: its kind, its parameter-table index and its colour index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Material {
    /// How it scatters.
    pub kind: MaterialKind,
    /// Index into the parameter table of `kind` (0..64; ignored for lambertian).
    pub param: u8,
    /// Index into the colour table.
    pub colour: u8,
}

impl Material {
    /// A lambertian material of a colour.
    pub fn lambertian(colour: u8) -> Self {
        Self {
            kind: MaterialKind::Lambertian,
            param: 0,
            colour,
        }
    }
    /// The packed 16-bit form the GPU reads.
    pub fn pack(self) -> u16 {
        self.kind as u16 | (self.param as u16 & 63) << 2 | (self.colour as u16) << 8
    }
    /// Unpacks the 16-bit form.
    pub fn unpack(v: u16) -> Self {
        let kind = match v & 3 {
            0 => MaterialKind::Lambertian,
            1 => MaterialKind::Metal,
            2 => MaterialKind::Dielectric,
            _ => MaterialKind::Emissive,
        };
        Self {
            kind,
            param: (v >> 2 & 63) as u8,
            colour: (v >> 8) as u8,
        }
    }
}

/// Every table as the GPU reads it (2304 bytes). Keep in sync with `MaterialTables` in
/// `shaders/brickmap.glsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug, PartialEq)]
pub struct MaterialTablesGpu {
    /// Packed entries, two per word (entry 2i in the low half of word i).
    pub materials: [u32; 128],
    /// Colours as RGBA8 (alpha unused, 255), red in the low byte.
    pub colours: [u32; 256],
    /// Metal roughness in [0, 1].
    pub roughness: [f32; PARAMS],
    /// Dielectric index of refraction in [1, 4].
    pub ior: [f32; PARAMS],
    /// Emissive strength, finite and ≥ 0.
    pub strength: [f32; PARAMS],
}
const _: () = assert!(std::mem::size_of::<MaterialTablesGpu>() == 2304);

/// The table of a scene: entries, colours and parameters, with change tracking.
#[derive(Clone, Debug)]
pub struct MaterialTable {
    len: usize,
    gpu: MaterialTablesGpu,
    dirty: DirtyRanges,
}

impl Default for MaterialTable {
    /// One lambertian material (colour 1, light grey); a grey ramp and hue wheel as colours;
    /// roughness i/63; IOR 1.5 (entry 1: water, 1.333); strength 1.
    fn default() -> Self {
        let mut colours = [0u32; 256];
        for (i, c) in colours.iter_mut().enumerate() {
            let rgb = if i < 32 {
                let g = 255 - (i as u32 * 255 / 31);
                [g, g, g]
            } else {
                hue(i as f32 / 224.0)
            };
            *c = rgb[0] | rgb[1] << 8 | rgb[2] << 16 | 255 << 24;
        }
        let mut ior = [1.5; PARAMS];
        ior[1] = 1.333;
        let mut gpu = MaterialTablesGpu {
            materials: [0; 128],
            colours,
            roughness: std::array::from_fn(|i| i as f32 / 63.0),
            ior,
            strength: [1.0; PARAMS],
        };
        gpu.materials[0] = Material::lambertian(1).pack() as u32;
        let mut dirty = DirtyRanges::default();
        dirty.record(0..std::mem::size_of::<MaterialTablesGpu>() as u64);
        Self { len: 1, gpu, dirty }
    }
}

fn hue(h: f32) -> [u32; 3] {
    let f = |n: f32| {
        let k = (n + h * 6.0) % 6.0;
        let v = 1.0 - (k.min(4.0 - k).clamp(0.0, 1.0)) * 0.75;
        (v * 255.0).round() as u32
    };
    [f(5.0), f(3.0), f(1.0)]
}

impl MaterialTable {
    /// Entries in the table.
    pub fn len(&self) -> usize {
        self.len
    }
    /// Always false: a table holds at least one material.
    pub fn is_empty(&self) -> bool {
        false
    }
    /// A material entry.
    pub fn get(&self, index: u8) -> Result<Material> {
        self.check(index as u32)?;
        Ok(Material::unpack(
            (self.gpu.materials[index as usize / 2] >> (16 * (index % 2))) as u16,
        ))
    }
    /// Whether `index` names an entry.
    pub fn check(&self, index: u32) -> Result<()> {
        if (index as usize) < self.len {
            Ok(())
        } else {
            Err(BrickmapError::MaterialIndex {
                index,
                len: self.len,
            })
        }
    }
    /// The table of only the entries `keep` marks (at least one), in order, with the same
    /// colours and parameters; entry i of the result is the i-th kept one.
    pub fn retain(&self, keep: &[bool; 256]) -> Result<MaterialTable> {
        let mut out = self.clone();
        out.gpu.materials = [0; 128];
        out.len = 0;
        for i in (0..self.len).filter(|&i| keep[i]) {
            out.len += 1;
            out.write_entry((out.len - 1) as u8, self.get(i as u8)?)?;
        }
        if out.len == 0 {
            return Err(BrickmapError::EmptyTable);
        }
        out.mark_all_dirty();
        Ok(out)
    }

    /// Appends a material, returning its index.
    pub fn push(&mut self, m: Material) -> Result<u8> {
        if self.len == 256 {
            return Err(BrickmapError::MaterialTableFull);
        }
        self.len += 1;
        let index = (self.len - 1) as u8;
        self.write_entry(index, m)?;
        Ok(index)
    }
    /// Replaces an entry, returning the previous one.
    pub fn set(&mut self, index: u8, m: Material) -> Result<Material> {
        let old = self.get(index)?;
        self.write_entry(index, m)?;
        Ok(old)
    }
    fn write_entry(&mut self, index: u8, m: Material) -> Result<()> {
        if m.param as usize >= PARAMS {
            return Err(BrickmapError::ParamIndex(m.param as u32));
        }
        let word = &mut self.gpu.materials[index as usize / 2];
        let shift = 16 * (index as u32 % 2);
        *word = (*word & !(0xFFFF << shift)) | (m.pack() as u32) << shift;
        self.dirty.record(offset_of_word(0, index as usize / 2));
        Ok(())
    }
    /// A colour as RGB.
    pub fn colour(&self, index: u8) -> [u8; 3] {
        let c = self.gpu.colours[index as usize];
        [c as u8, (c >> 8) as u8, (c >> 16) as u8]
    }
    /// Replaces a colour, returning the previous one.
    pub fn set_colour(&mut self, index: u8, rgb: [u8; 3]) -> [u8; 3] {
        let old = self.colour(index);
        self.gpu.colours[index as usize] =
            rgb[0] as u32 | (rgb[1] as u32) << 8 | (rgb[2] as u32) << 16 | 255 << 24;
        self.dirty.record(offset_of_word(512, index as usize));
        old
    }
    /// A parameter of a kind's table (lambertian has none: 0).
    pub fn param(&self, kind: MaterialKind, index: u8) -> Result<f32> {
        let i = index as usize;
        if i >= PARAMS {
            return Err(BrickmapError::ParamIndex(index as u32));
        }
        Ok(match kind {
            MaterialKind::Lambertian => 0.0,
            MaterialKind::Metal => self.gpu.roughness[i],
            MaterialKind::Dielectric => self.gpu.ior[i],
            MaterialKind::Emissive => self.gpu.strength[i],
        })
    }
    /// Sets a parameter, returning the previous value. Roughness must lie in [0, 1], IOR in
    /// [1, 4], strength be finite and ≥ 0.
    pub fn set_param(&mut self, kind: MaterialKind, index: u8, value: f32) -> Result<f32> {
        let old = self.param(kind, index)?;
        let i = index as usize;
        let (table, base, range, lo, hi) = match kind {
            MaterialKind::Lambertian => {
                return Err(BrickmapError::Config(
                    "lambertian materials have no parameter".into(),
                ));
            }
            MaterialKind::Metal => (&mut self.gpu.roughness, 1536, "[0, 1]", 0.0, 1.0),
            MaterialKind::Dielectric => (&mut self.gpu.ior, 1792, "[1, 4]", 1.0, 4.0),
            MaterialKind::Emissive => (&mut self.gpu.strength, 2048, "[0, 1e6]", 0.0, 1e6),
        };
        if !(lo..=hi).contains(&value) {
            return Err(BrickmapError::ParamRange {
                what: "material parameter",
                value,
                range,
            });
        }
        table[i] = value;
        self.dirty.record(offset_of_word(base, i));
        Ok(old)
    }
    /// The tables exactly as uploaded.
    pub fn gpu(&self) -> &MaterialTablesGpu {
        &self.gpu
    }
    /// Marks the whole table changed (after it replaced another).
    pub fn mark_all_dirty(&mut self) {
        self.dirty
            .record(0..std::mem::size_of::<MaterialTablesGpu>() as u64);
    }
    /// Byte ranges of [`MaterialTablesGpu`] changed since the last drain.
    pub fn take_dirty(&mut self) -> Vec<std::ops::Range<u64>> {
        self.dirty.take()
    }
    /// Bytes that define the logical content (for the content hash).
    pub fn logical_bytes(&self) -> Vec<u8> {
        let mut out = (self.len as u32).to_le_bytes().to_vec();
        let entries: &[u8] = bytemuck::cast_slice(&self.gpu.materials);
        out.extend_from_slice(&entries[..self.len * 2]);
        out.extend_from_slice(bytemuck::cast_slice(&self.gpu.colours));
        out.extend_from_slice(bytemuck::cast_slice(&self.gpu.roughness));
        out.extend_from_slice(bytemuck::cast_slice(&self.gpu.ior));
        out.extend_from_slice(bytemuck::cast_slice(&self.gpu.strength));
        out
    }
}

fn offset_of_word(base: u64, word: usize) -> std::ops::Range<u64> {
    let s = base + 4 * word as u64;
    s..s + 4
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pack_round_trips() {
        for kind in [
            MaterialKind::Lambertian,
            MaterialKind::Metal,
            MaterialKind::Dielectric,
            MaterialKind::Emissive,
        ] {
            let m = Material {
                kind,
                param: 37,
                colour: 201,
            };
            assert_eq!(Material::unpack(m.pack()), m);
        }
    }

    #[test]
    fn table_limits_and_dirty() {
        let mut t = MaterialTable::default();
        t.take_dirty();
        assert!(t.get(1).is_err());
        for i in 1..256 {
            assert_eq!(t.push(Material::lambertian(i as u8)).unwrap(), i as u8);
        }
        assert_eq!(
            t.push(Material::lambertian(0)),
            Err(BrickmapError::MaterialTableFull)
        );
        assert_eq!(t.get(255).unwrap().colour, 255);
        t.take_dirty();
        t.set_param(MaterialKind::Dielectric, 3, 1.33).unwrap();
        assert_eq!(t.take_dirty(), vec![1792 + 12..1792 + 16]);
        assert!(t.set_param(MaterialKind::Metal, 0, 1.5).is_err());
        assert!(t.set_param(MaterialKind::Metal, 0, f32::NAN).is_err());
        t.set_colour(7, [1, 2, 3]);
        assert_eq!(t.colour(7), [1, 2, 3]);
        assert_eq!(t.take_dirty(), vec![512 + 28..512 + 32]);
    }
}
