//! Scenes and helpers shared by the CPU reference and Vulkan tests, so both backends are
//! checked against the same closed forms.
#![allow(dead_code)] // each test file uses part of it

use brickmap::{
    EditOp, GridDims, Material, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp, World, WorldConfig,
};
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

/// Glass boxes forcing total internal reflection, water on a floor, rough and mirror metal, an
/// emissive voxel and the sun, with cameras on faces, edges, inside voxels and along axes:
/// every image must be finite and non-negative.
pub fn hard_places() -> (World, Vec<SceneParams>) {
    let w = world((6, 4, 6));
    let glass = add_material(&w, MaterialKind::Dielectric, 0, [240, 250, 255]);
    let water = add_material(&w, MaterialKind::Dielectric, 1, [200, 230, 255]);
    let rough = add_material(&w, MaterialKind::Metal, 30, [230, 200, 120]);
    let mirror = add_material(&w, MaterialKind::Metal, 0, [250, 250, 250]);
    let lamp = add_material(&w, MaterialKind::Emissive, 0, [255, 255, 255]);
    let floor = add_material(&w, MaterialKind::Lambertian, 0, [120, 120, 120]);
    let shapes = [
        (
            Shape::Box {
                min: IVec3::ZERO,
                max: IVec3::new(47, 2, 47),
            },
            floor,
        ),
        (
            Shape::Box {
                min: IVec3::new(0, 3, 0),
                max: IVec3::new(47, 6, 20),
            },
            water,
        ),
        (
            Shape::Box {
                min: IVec3::new(8, 8, 8),
                max: IVec3::new(15, 15, 15),
            },
            glass,
        ),
        (
            Shape::Sphere {
                centre: DVec3::new(30.0, 12.0, 30.0),
                radius: 5.0,
            },
            rough,
        ),
        (
            Shape::Box {
                min: IVec3::new(36, 3, 8),
                max: IVec3::new(37, 20, 20),
            },
            mirror,
        ),
    ];
    for (shape, m) in shapes {
        w.apply(EditOp::Shape {
            shape,
            mode: Mode::Add(m),
        })
        .unwrap();
    }
    w.apply(EditOp::Voxels(vec![VoxelEdit {
        pos: IVec3::new(20, 9, 20),
        op: VoxelOp::Set(lamp),
    }]))
    .unwrap();
    let sun = Sun {
        enabled: true,
        position: DVec3::new(80.0, 90.0, 60.0),
        radius: 6.0,
        colour: [1.0, 0.9, 0.8],
        intensity: 20.0,
        animate: false,
        speed_deg_per_s: 0.0,
    };
    let cams = [
        Camera::looking_at(
            DVec3::new(-10.0, 30.0, -10.0),
            DVec3::new(24.0, 8.0, 24.0),
            60.0,
        ),
        Camera::looking_at(
            DVec3::new(12.0, 12.0, 12.0),
            DVec3::new(12.0, 12.0, 40.0),
            90.0,
        ), // inside glass
        Camera::looking_at(
            DVec3::new(10.0, 4.0, 10.0),
            DVec3::new(30.0, 20.0, 30.0),
            90.0,
        ), // under water
        Camera::looking_at(DVec3::new(8.0, 8.0, 0.0), DVec3::new(8.0, 8.0, 40.0), 60.0), // on brick edges, along z
        Camera::looking_at(
            DVec3::new(30.0, 12.0, 30.0),
            DVec3::new(0.0, 12.0, 0.0),
            60.0,
        ), // inside metal
        Camera::looking_at(
            DVec3::new(16.0, 16.0, 16.0),
            DVec3::new(48.0, 48.0, 48.0),
            60.0,
        ), // diagonal through a corner
    ];
    let sky = Sky::Gradient {
        horizon: [0.9, 0.9, 1.0],
        zenith: [0.2, 0.4, 0.9],
    };
    let views = cams
        .into_iter()
        .map(|cam| params(cam, sky.clone(), Some(sun.clone()), 6))
        .collect();
    (w, views)
}

/// Renders the sun floor at 4, 16 and 64 spp with `render(spp)` and requires the per-pixel
/// RMS error against the closed form to halve with each 4× more samples (no plateau, so no
/// bias), within sampling slack.
pub fn assert_error_halves(mut render: impl FnMut(u32) -> render::Image, expected: f64) {
    let mut rms = |spp: u32| {
        let img = render(spp);
        (img.pixels
            .iter()
            .map(|px| (px[0] as f64 - expected).powi(2))
            .sum::<f64>()
            / img.pixels.len() as f64)
            .sqrt()
    };
    let (e4, e16, e64) = (rms(4), rms(16), rms(64));
    for (a, b) in [(e4, e16), (e16, e64)] {
        assert!(
            (1.6..2.5).contains(&(a / b)),
            "errors {e4} {e16} {e64}: ratio {}",
            a / b
        );
    }
}
