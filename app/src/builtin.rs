//! The built-in scenes: the editor's default scene (terrain, a metal sphere, a glass block, a
//! lamp and MagicaVoxel's statue) and the thesis benchmark scene, and the terrain materials
//! both share with the Terrain window.

use crate::formats;
use crate::scene::Scene;
use anyhow::{Context, Result};
use brickmap::{
    EditOp, GridDims, Material, MaterialKind, Mode, Shape, World, WorldConfig, terrain,
};
use glam::{DVec3, IVec3, UVec3};

/// Size presets for the default scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SceneSize {
    /// 512 × 256 × 512 voxels (the thesis benchmark size).
    Full,
    /// 128 × 64 × 128 voxels (quick checks).
    Small,
}

/// The built-in default scene: rolling terrain with grass, dirt, rock and sand, plus a metal
/// sphere, a glass block and an emissive lamp, so every material type is present.
pub fn default_scene(size: SceneSize, workers: usize) -> Result<Scene> {
    let dims = match size {
        SceneSize::Full => GridDims::new(64, 32, 64),
        SceneSize::Small => GridDims::new(16, 8, 16),
    }?;
    let owned = World::new(dims, WorldConfig::with_workers(workers))?;
    let world = &owned;
    // Colours 200.. of the table are the scene's own. Terrain materials must be 0..=3 (grass,
    // dirt, rock, sand: the indices terrain::rolling_hills uses); then metal, glass, lamp.
    let colours = [
        [86, 152, 58],
        [121, 85, 58],
        [128, 128, 128],
        [219, 202, 146],
        [230, 200, 120],
        [235, 245, 255],
        [255, 220, 170],
    ];
    for (i, rgb) in colours.into_iter().enumerate() {
        world.set_colour(200 + i as u8, rgb);
    }
    world.set_material(0, Material::lambertian(200))?;
    for colour in 201..=203 {
        world.push_material(Material::lambertian(colour))?;
    }
    let gold = world.push_material(Material {
        kind: MaterialKind::Metal,
        param: 8,
        colour: 204,
    })?;
    let glass = world.push_material(Material {
        kind: MaterialKind::Dielectric,
        param: 0,
        colour: 205,
    })?;
    world.set_param(MaterialKind::Emissive, 1, 8.0)?;
    let lamp = world.push_material(Material {
        kind: MaterialKind::Emissive,
        param: 1,
        colour: 206,
    })?;

    world
        .apply_unrecorded(terrain::rolling_hills(dims))
        .context("building the terrain")?;
    let size = dims.voxels().as_dvec3();
    let unit = size.x / 512.0;
    let centre = DVec3::new(size.x * 0.5, size.y * 0.75, size.z * 0.5);
    let metal = Shape::Sphere {
        centre,
        radius: 24.0 * unit,
    };
    world.apply(EditOp::Shape {
        shape: metal,
        mode: Mode::Add(gold),
    })?;
    let block_min = (centre + DVec3::new(40.0, -10.0, 0.0) * unit).as_ivec3();
    let block = Shape::Box {
        min: block_min,
        max: block_min + (IVec3::splat(20).as_dvec3() * unit).as_ivec3(),
    };
    world.apply(EditOp::Shape {
        shape: block,
        mode: Mode::Add(glass),
    })?;
    let pole = Shape::Cylinder {
        a: centre + DVec3::new(-40.0, -30.0, 0.0) * unit,
        b: centre + DVec3::new(-40.0, 10.0, 0.0) * unit,
        radius: 2.0 * unit.max(0.5),
    };
    world.apply(EditOp::Shape {
        shape: pole,
        mode: Mode::Add(lamp),
    })?;
    Ok(adopt(owned))
}

/// A scene of a world just built here: one object, framed by the default camera.
fn adopt(world: World) -> Scene {
    world.take_dirty();
    let params = render::SceneParams::framing(world.dims().voxels().as_dvec3());
    Scene::new(world, params)
}

/// The statue placed in metal in the thesis scene: "Mini Mike's Metro Minis" by Mike Judge,
/// CC BY 4.0 (assets/vox/SOURCES.md).
pub const STATUE_VOX: &[u8] = include_bytes!("../../assets/vox/mmmm_obj_statue3.vox");

/// Terrain parameters of the thesis benchmark scene for a grid height.
pub fn thesis_terrain(materials: terrain::TerrainMaterials, height: u32) -> terrain::TerrainParams {
    let h = height as f64;
    terrain::TerrainParams {
        seed: 2022,
        noise: terrain::NoiseKind::Perlin,
        scale: 180.0 * h / 256.0,
        octaves: 5,
        height_range: ((h * 0.16) as u32, (h * 0.78) as u32),
        water_level: (h * 0.375) as u32,
        rock_line: 0.62,
        snow_line: 0.86,
        soil_depth: 3,
        materials,
    }
}

/// Adds the terrain palette to a world: grass, dirt, rock with colour variants, sand, snow,
/// and water (a blue-tinted dielectric, IOR 1.333). A material already in the table with the
/// same kind, parameter and colour is reused, so generating terrain again adds nothing.
pub fn terrain_materials(world: &World) -> brickmap::Result<terrain::TerrainMaterials> {
    // Colours are taken from the top of the table down; a fresh table's placeholder
    // material 0 is replaced by the first terrain material.
    let fresh = world.read().solid_count() == 0 && world.materials().len() == 1;
    let mut next_colour = 255u8;
    let mut first = fresh;
    let mut add = |rgb: [u8; 3], kind: MaterialKind, param: u8| -> brickmap::Result<u8> {
        let colour = next_colour;
        next_colour -= 1;
        if !first {
            let table = world.materials();
            let equal = (0..table.len()).find(|&k| {
                table.get(k as u8).is_ok_and(|m| {
                    m.kind == kind && m.param == param && table.colour(m.colour) == rgb
                })
            });
            if let Some(k) = equal {
                return Ok(k as u8);
            }
        }
        world.set_colour(colour, rgb);
        let m = Material {
            kind,
            param,
            colour,
        };
        if std::mem::take(&mut first) {
            world.set_material(0, m)?;
            return Ok(0);
        }
        world.push_material(m)
    };
    let l = MaterialKind::Lambertian;
    let grass = vec![
        add([88, 150, 60], l, 0)?,
        add([98, 162, 66], l, 0)?,
        add([78, 138, 54], l, 0)?,
    ];
    let dirt = vec![add([120, 86, 58], l, 0)?, add([108, 78, 52], l, 0)?];
    let rock = vec![add([126, 126, 122], l, 0)?, add([112, 112, 110], l, 0)?];
    let sand = vec![add([218, 202, 150], l, 0)?];
    let snow = vec![add([240, 244, 250], l, 0)?];
    // Dielectric parameter 1 of the default table is water's IOR, 1.333.
    let water = add([190, 220, 240], MaterialKind::Dielectric, 1)?;
    Ok(terrain::TerrainMaterials {
        grass,
        dirt,
        rock,
        sand,
        snow,
        water,
    })
}

/// A new scene of a heightmap image's terrain (`formats::heightmap`), `height` voxels tall at
/// white: the grid is the image's size (rounded up to whole bricks) by `height`; the columns
/// are painted as the terrain generator paints — the top voxel grass, rock above three
/// quarters of the height and snow above nine tenths, three voxels of dirt under grass, rock
/// below.
pub fn heightmap_scene(
    path: &std::path::Path,
    height: u32,
    workers: usize,
) -> Result<Scene, formats::FormatError> {
    use formats::FormatError;
    let heights = formats::heightmap::read(path)?;
    let tallest = brickmap::grid::MAX_BRICKS_Y * 8;
    if !(1..=tallest).contains(&height) {
        return Err(FormatError::invalid(
            path,
            format!("the terrain's height {height} must lie in 1..={tallest} voxels"),
        ));
    }
    let dims = GridDims::from_voxels(UVec3::new(heights.width, height, heights.depth))
        .map_err(|e| FormatError::world(path, e))?;
    let world = World::new(dims, WorldConfig::with_workers(workers))
        .map_err(|e| FormatError::world(path, e))?;
    let m = terrain_materials(&world).map_err(|e| FormatError::world(path, e))?;
    let size = dims.voxels();
    let mut columns = vec![0i32; (size.x * size.z) as usize];
    for z in 0..heights.depth as usize {
        for x in 0..heights.width as usize {
            let v = heights.values[z * heights.width as usize + x];
            columns[x + z * size.x as usize] =
                formats::heightmap::column_height(v, heights.max, height);
        }
    }
    let h = height as f64;
    let edit = terrain::heightfield(dims, &columns, |v: IVec3, top: i32| {
        let depth = top - 1 - v.y;
        let high = f64::from(top) > 0.75 * h;
        match depth {
            0 if f64::from(top) > 0.9 * h => m.snow[0],
            0 if high => m.rock[0],
            0 => m.grass[0],
            1..=3 if !high => m.dirt[0],
            _ => m.rock[0],
        }
    });
    world
        .apply_unrecorded(edit)
        .map_err(|e| FormatError::world(path, e))?;
    world.take_dirty();
    let params = render::SceneParams::framing(size.as_dvec3());
    Ok(Scene::new(world, params))
}

/// The thesis benchmark scene: 512 × 256 × 512 noise terrain with water, and a statue in
/// polished gold standing on the ground at the centre.
pub fn thesis_scene(workers: usize) -> Result<Scene> {
    let dims = GridDims::new(64, 32, 64)?;
    let owned = World::new(dims, WorldConfig::with_workers(workers))?;
    let world = &owned;
    let materials = terrain_materials(world)?;
    let params = thesis_terrain(materials, dims.voxels().y as u32);
    world
        .apply_unrecorded(terrain::NoiseTerrain::new(params, dims)?.edit())
        .context("generating the terrain")?;
    place_statue(world)?;
    Ok(adopt(owned))
}

/// Places the CC-BY statue in gold on the ground (or water) at the centre of the grid.
fn place_statue(world: &World) -> Result<()> {
    world.set_colour(64, [232, 196, 110]);
    let gold = world.push_material(Material {
        kind: MaterialKind::Metal,
        param: 6,
        colour: 64,
    })?;
    let size = formats::vox::extent(STATUE_VOX)?;
    let v = world.dims().voxels();
    let centre = DVec3::new(
        v.x as f64 / 2.0 + 0.5,
        v.y as f64 + 1.0,
        v.z as f64 / 2.0 + 0.5,
    );
    let ground = world
        .read()
        .ray_cast(
            &brickmap::Ray {
                origin: centre,
                dir: DVec3::NEG_Y,
            },
            f64::INFINITY,
        )?
        .map_or(0, |(hit, _)| hit.voxel.y + 1);
    let offset = IVec3::new(v.x / 2 - size.x / 2, ground, v.z / 2 - size.z / 2);
    let options = formats::vox::ImportOptions {
        offset,
        ..Default::default()
    };
    let (_, edit) = formats::vox::import_into(world, STATUE_VOX, &options, Some(gold))?;
    world.apply(edit)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terrain_generated_twice_reuses_its_materials() {
        let scene = Scene::empty(GridDims::new(2, 2, 2).unwrap(), 1).unwrap();
        let first = terrain_materials(&scene.world).unwrap();
        let count = scene.world.materials().len();
        assert_eq!(count, 10, "grass 3, dirt 2, rock 2, sand, snow, water");
        let second = terrain_materials(&scene.world).unwrap();
        assert_eq!(scene.world.materials().len(), count, "no duplicates");
        assert_eq!(
            (second.grass, second.rock, second.water),
            (first.grass, first.rock, first.water)
        );
    }
}
