//! Scenes and helpers shared by the CPU reference and Vulkan tests, so both backends are
//! checked against the same closed forms.
#![allow(dead_code)] // each test file uses part of it

use brickmap::{EditOp, GridDims, Material, MaterialKind, Mode, Shape, World, WorldConfig};
use glam::{DVec3, IVec3};
use render::{Camera, RenderSettings, SceneParams, Sky, Sun};

pub fn params(camera: Camera, sky: Sky, sun: Option<Sun>, bounces: u32) -> SceneParams {
    SceneParams {
        camera,
        sun: sun.unwrap_or(Sun {
            enabled: false,
            position: DVec3::new(0.0, 1000.0, 0.0),
            radius: 1.0,
            colour: [1.0; 3],
            intensity: 0.0,
            animate: false,
            speed_deg_per_s: 0.0,
        }),
        sky,
        settings: RenderSettings {
            samples_per_pixel: 1,
            max_bounces: bounces,
            internal_resolution: (32, 32),
            exposure: 0.0,
        },
    }
}

pub fn world(bricks: (u32, u32, u32)) -> World {
    World::new(
        GridDims::new(bricks.0, bricks.1, bricks.2).unwrap(),
        WorldConfig::with_workers(2),
    )
    .unwrap()
}

pub fn add_material(w: &World, kind: MaterialKind, param: u8, rgb: [u8; 3]) -> u8 {
    let colour = 250 - w.materials().len() as u8;
    w.set_colour(colour, rgb);
    w.push_material(Material {
        kind,
        param,
        colour,
    })
    .unwrap()
}

/// A white floor lit only by a sun disc straight above: the floor's radiance is
/// albedo · L · R² / (R² + D²) (the irradiance of a facing disc on its axis, over π).
pub fn sun_floor() -> (World, SceneParams, f64) {
    let w = world((8, 2, 8)); // 64 × 16 × 64
    let m = add_material(&w, MaterialKind::Lambertian, 0, [200, 200, 200]);
    w.apply(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::ZERO,
            max: IVec3::new(63, 3, 63),
        },
        mode: Mode::Add(m),
    })
    .unwrap();
    let (r, d, l) = (6.0, 30.0, 5.0);
    let floor_y = 4.0;
    let sun = Sun {
        enabled: true,
        // Straight above the grid centre (32, ·, 32): it faces the centre, i.e. straight down.
        position: DVec3::new(32.0, floor_y + d, 32.0),
        radius: r,
        colour: [1.0; 3],
        intensity: l as f32,
        animate: false,
        speed_deg_per_s: 0.0,
    };
    let cam = Camera {
        position: DVec3::new(32.0, floor_y + 3.0, 32.0),
        yaw_deg: 0.0,
        pitch_deg: -89.0,
        fov_y_deg: 0.5,
    };
    let albedo = render::cpu::srgb_to_linear(200);
    let expected = albedo * l * r * r / (r * r + d * d);
    (
        w,
        params(cam, Sky::Uniform { colour: [0.0; 3] }, Some(sun), 1),
        expected,
    )
}
