//! The built-in default scene: rolling terrain with grass, dirt, rock and sand, plus a metal
//! sphere, a glass block and an emissive lamp, so every material type is present.

use anyhow::{Context, Result};
use brickmap::{
    EditOp, GridDims, Material, MaterialKind, Mode, Shape, World, WorldConfig, terrain,
};
use glam::{DVec3, IVec3};

/// Size presets for the default scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SceneSize {
    /// 512 × 256 × 512 voxels (the thesis benchmark size).
    Full,
    /// 128 × 64 × 128 voxels (quick checks).
    Small,
}

/// Builds the default scene.
pub fn default_scene(size: SceneSize, workers: usize) -> Result<World> {
    let dims = match size {
        SceneSize::Full => GridDims::new(64, 32, 64),
        SceneSize::Small => GridDims::new(16, 8, 16),
    }?;
    let world = World::new(
        dims,
        WorldConfig {
            workers,
            ..Default::default()
        },
    )?;
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
        .apply(terrain::rolling_hills(dims))
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
    Ok(world)
}
