//! `.vox` materials in: one voxbrick material per used palette entry from its MATL chunk
//! (diffuse, metal with roughness, glass with IOR, emission `_emit · 2^_flux`), reusing equal
//! entries, with the parameter slots they need.

use super::*;

/// Creates (or reuses) one material per used palette entry from its MATL chunk, with the
/// colour index `colour_of(palette index)` gives; returns palette index → material index.
pub(super) fn install_materials(
    world: &World,
    data: &DotVoxData,
    placed: &[(IVec3, u8)],
    report: &mut ImportReport,
    mut colour_of: impl FnMut(u8) -> Result<u8, VoxError>,
) -> Result<[u8; 256], VoxError> {
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
                world.set_material(0, m)?;
                0
            }
            (None, _) => world.push_material(m)?,
        };
        created.insert(m, index);
        map[i] = index;
    }
    report.materials = created.len();
    report.add_dropped(notes);
    Ok(map)
}

/// Parameter-table slots handed out during one import (slot 0 of each table stays the
/// default; values already present are reused).
#[derive(Default)]
pub(super) struct ParamSlots {
    next: HashMap<MaterialKind, u8>,
}

impl ParamSlots {
    fn slot(&mut self, world: &World, kind: MaterialKind, value: f32) -> Result<u8, VoxError> {
        let table = world.materials();
        for i in 0..brickmap::material::PARAMS as u8 {
            if (table.param(kind, i)? - value).abs() < 1e-4 {
                return Ok(i);
            }
        }
        drop(table);
        let next = self.next.entry(kind).or_insert(2);
        if *next as usize >= brickmap::material::PARAMS {
            return Err(VoxError::TooManyParameters {
                kind,
                max: brickmap::material::PARAMS - 2,
            });
        }
        let i = *next;
        *next += 1;
        world.set_param(kind, i, value)?;
        Ok(i)
    }
}

pub(super) fn material_from_matl(
    world: &World,
    colour: u8,
    props: Option<&dot_vox::Dict>,
    params: &mut ParamSlots,
    notes: &mut BTreeMap<String, usize>,
) -> Result<Material, VoxError> {
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
