//! The scenes `bench-gpu --lights` measures light sampling on: a lamp-lit room, the thesis
//! scene with six lamps and the sun, and a city at night lit by about 10,000 street lamps.

use anyhow::Result;
use app::Scene;
use app::builtin::thesis_scene;
use brickmap::{EditOp, GridDims, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp};
use glam::{DVec3, IVec3};
use render::{Camera, Sky};

pub(crate) fn lamp(scene: &Scene, strength: f32, rgb: [u8; 3]) -> Result<u8> {
    let w = &scene.world;
    let param = 1 + w.materials().len() as u8 % 60;
    w.set_param(MaterialKind::Emissive, param, strength)?;
    let colour = 200 + w.materials().len() as u8 % 50;
    w.set_colour(colour, rgb);
    Ok(w.push_material(brickmap::Material {
        kind: MaterialKind::Emissive,
        param,
        colour,
    })?)
}

pub(crate) fn fill(scene: &Scene, m: u8, min: IVec3, max: IVec3) -> Result<()> {
    scene.edit(EditOp::Shape {
        shape: Shape::Box { min, max },
        mode: Mode::Add(m),
    })?;
    Ok(())
}

/// A 128 × 64 × 128 room (walls of albedo 0.46, a table, a shelf) lit only by a few emissive voxels: a
/// 2 × 1 × 2 ceiling lamp and a 1 × 2 × 1 table lamp; no sun, black sky, 4 bounces.
pub(crate) fn lamp_room(workers: usize) -> Result<Scene> {
    let dims = GridDims::new(16, 8, 16)?;
    let mut scene = Scene::empty(dims, workers)?;
    let v = dims.voxels() - 1;
    // Walls of a mid albedo (sRGB 180: 0.46 linear), as painted interiors have.
    scene.world.set_colour(199, [180, 180, 180]);
    let wall = scene
        .world
        .push_material(brickmap::Material::lambertian(199))?;
    fill(&scene, wall, IVec3::ZERO, v)?;
    scene.edit(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::ONE,
            max: v - 1,
        },
        mode: Mode::Remove,
    })?;
    fill(&scene, wall, IVec3::new(40, 1, 50), IVec3::new(80, 20, 80))?; // table
    fill(&scene, wall, IVec3::new(1, 30, 20), IVec3::new(12, 32, 100))?; // shelf
    let ceiling = lamp(&scene, 300.0, [255, 236, 210])?;
    fill(
        &scene,
        ceiling,
        IVec3::new(63, 62, 63),
        IVec3::new(64, 62, 64),
    )?;
    let table = lamp(&scene, 300.0, [255, 190, 120])?;
    fill(
        &scene,
        table,
        IVec3::new(70, 21, 70),
        IVec3::new(70, 22, 70),
    )?;
    let p = &mut scene.params;
    p.camera = Camera::looking_at(
        DVec3::new(110.0, 40.0, 120.0),
        DVec3::new(55.0, 15.0, 55.0),
        60.0,
    );
    p.sun.enabled = false;
    p.sky = Sky::Uniform { colour: [0.0; 3] };
    p.settings.max_bounces = 4;
    scene.world.take_dirty();
    Ok(scene)
}

/// The thesis scene at complexity 3 (3 bounces, sun) with six 3³ lamps on the ground.
pub(crate) fn thesis_with_lamps(workers: usize) -> Result<Scene> {
    let mut scene = thesis_scene(workers)?;
    scene.params.settings.max_bounces = 3;
    scene.params.sun.enabled = true;
    let m = lamp(&scene, 30.0, [255, 150, 60])?;
    let v = scene.world.dims().voxels();
    for k in 0..6 {
        let x = v.x / 2 - 60 + 24 * k;
        let z = v.z / 2 + 40 - 16 * (k % 3);
        let ground = scene
            .world
            .read()
            .ray_cast(
                &brickmap::Ray {
                    origin: DVec3::new(x as f64 + 0.5, v.y as f64 + 1.0, z as f64 + 0.5),
                    dir: DVec3::NEG_Y,
                },
                f64::INFINITY,
            )?
            .map_or(0, |(hit, _)| hit.voxel.y + 1)
            .min(v.y - 3);
        fill(
            &scene,
            m,
            IVec3::new(x, ground, z),
            IVec3::new(x + 2, ground + 2, z + 2),
        )?;
    }
    scene.world.take_dirty();
    Ok(scene)
}

/// A city at night, 1024 × 64 × 1024: 32 × 32 blocks of buildings 6–45 voxels tall (three
/// greys) between streets 8 voxels wide, lit by street lamps — one emissive voxel (warm,
/// strength 40) on a 4-voxel pole every 9 voxels along both sides of every street, 11,008 of
/// them — under a dark blue sky; no sun, 3 bounces.
pub(crate) fn night_city(workers: usize) -> Result<Scene> {
    let dims = GridDims::new(128, 8, 128)?;
    let mut scene = Scene::empty(dims, workers)?;
    let w = &scene.world;
    w.set_colour(196, [60, 60, 64]);
    w.set_colour(197, [150, 140, 125]);
    w.set_colour(198, [110, 115, 125]);
    w.set_colour(199, [90, 85, 80]);
    let ground = w.push_material(brickmap::Material::lambertian(196))?;
    let walls: Vec<u8> = (197..200)
        .map(|c| w.push_material(brickmap::Material::lambertian(c)))
        .collect::<Result<_, _>>()?;
    let pole = w.push_material(brickmap::Material::lambertian(196))?;
    let light = lamp(&scene, 40.0, [255, 190, 120])?;
    let v = dims.voxels();
    fill(&scene, ground, IVec3::ZERO, IVec3::new(v.x - 1, 0, v.z - 1))?;
    // Blocks of 24 × 24 voxels at a pitch of 32 (streets at 24..32 of each period).
    let hash = |x: i32, z: i32| {
        let mut h = (x as u32).wrapping_mul(0x9e37_79b9) ^ (z as u32).wrapping_mul(0x85eb_ca6b);
        h ^= h >> 15;
        h = h.wrapping_mul(0x2c1b_3c6d);
        h ^ (h >> 12)
    };
    for bx in 0..32 {
        for bz in 0..32 {
            let h = hash(bx, bz);
            let height = 6 + (h % 40) as i32;
            let min = IVec3::new(bx * 32, 1, bz * 32);
            fill(
                &scene,
                walls[(h >> 8) as usize % 3],
                min,
                min + IVec3::new(23, height - 1, 23),
            )?;
        }
    }
    // Lamps 1 voxel in from the kerbs (x or z ≡ 25 or 30 mod 32), every 9 voxels.
    let mut edits = Vec::new();
    let mut put = |p: IVec3| {
        for y in 1..5 {
            edits.push(VoxelEdit {
                pos: IVec3::new(p.x, y, p.z),
                op: VoxelOp::Set(pole),
            });
        }
        edits.push(VoxelEdit {
            pos: IVec3::new(p.x, 5, p.z),
            op: VoxelOp::Set(light),
        });
    };
    for street in 0..32 {
        for side in [25, 30] {
            let across = street * 32 + side;
            for k in 0..v.x / 9 {
                let along = k * 9 + 2;
                if along % 32 >= 24 {
                    continue; // a crossing: the other street's lamps light it
                }
                put(IVec3::new(across, 0, along));
                put(IVec3::new(along, 0, across));
            }
        }
    }
    scene.edit(EditOp::Voxels(edits))?;
    let p = &mut scene.params;
    p.camera = Camera::looking_at(
        DVec3::new(420.0, 140.0, 760.0),
        DVec3::new(520.0, 0.0, 520.0),
        60.0,
    );
    p.sun.enabled = false;
    p.sky = Sky::Uniform {
        colour: [0.004, 0.006, 0.015],
    };
    p.settings.max_bounces = 3;
    scene.world.take_dirty();
    Ok(scene)
}
