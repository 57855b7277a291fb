//! Scenes and helpers shared by the CPU reference and Vulkan tests, so both backends are
//! checked against the same closed forms.
#![allow(dead_code)] // each test file uses part of it

use brickmap::{
    EditOp, GridDims, Material, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp, World, WorldConfig,
};
use glam::{DVec3, IVec3};
use render::{Camera, Image, RenderSettings, SceneParams, Sequence, Sky, Sun};

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
            sequence: Sequence::Independent,
        },
    }
}

/// The furnace sky radiance of [`block_scene`].
pub const SKY: [f32; 3] = [0.7, 0.5, 0.3];

/// A 12³ block of one material (white) in the middle of a 32³ grid under the uniform
/// [`SKY`], seen from a corner, 4 bounces.
pub fn block_scene(kind: MaterialKind, param: u8) -> (World, SceneParams) {
    let w = world((4, 4, 4));
    let m = add_material(&w, kind, param, [255, 255, 255]);
    w.apply(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::splat(10),
            max: IVec3::splat(21),
        },
        mode: Mode::Add(m),
    })
    .unwrap();
    let cam = Camera::looking_at(DVec3::new(-6.0, 40.0, -8.0), DVec3::splat(16.0), 40.0);
    (w, params(cam, Sky::Uniform { colour: SKY }, None, 4))
}

/// Mean of channel 0 over the image and its standard error.
pub fn mean_and_error(img: &Image) -> (f64, f64) {
    let v: Vec<f64> = img.pixels.iter().map(|p| p[0] as f64).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Every pixel finite (no NaN, no infinity) and non-negative.
pub fn assert_finite_and_nonnegative(img: &Image, what: &str) {
    assert!(img.all_finite(), "{what}: {:?}", img.pixels);
    assert!(
        img.pixels.iter().all(|px| px.iter().all(|c| *c >= 0.0)),
        "{what}"
    );
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
        projection: render::Projection::Perspective,
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

/// The largest grid (4096 × 1024 × 4096 voxels) with glass, metal, an emitter and a floor at
/// its far corner, and cameras where f32 coordinates are coarsest: near and on the far
/// corner, on a voxel face, inside glass, along the grid's far edge, and far outside. The
/// first two cameras' centre rays pass no voxel edge (an exactly diagonal ray would, and f32
/// and f64 may then legitimately order the crossings differently).
pub fn far_places() -> (World, Vec<SceneParams>) {
    let w = world((512, 128, 512));
    let floor = add_material(&w, MaterialKind::Lambertian, 0, [150, 150, 150]);
    let glass = add_material(&w, MaterialKind::Dielectric, 0, [240, 250, 255]);
    let metal = add_material(&w, MaterialKind::Metal, 20, [230, 200, 120]);
    let lamp = add_material(&w, MaterialKind::Emissive, 0, [255, 255, 255]);
    for (shape, m) in [
        (
            Shape::Box {
                min: IVec3::new(4000, 990, 4000),
                max: IVec3::new(4095, 1000, 4095),
            },
            floor,
        ),
        (
            Shape::Box {
                min: IVec3::new(4080, 1001, 4080),
                max: IVec3::new(4095, 1010, 4095),
            },
            glass,
        ),
        (
            Shape::Sphere {
                centre: DVec3::new(4060.0, 1010.0, 4060.0),
                radius: 6.0,
            },
            metal,
        ),
    ] {
        w.apply(EditOp::Shape {
            shape,
            mode: Mode::Add(m),
        })
        .unwrap();
    }
    w.apply(EditOp::Voxels(vec![VoxelEdit {
        pos: IVec3::new(4090, 1020, 4090),
        op: VoxelOp::Set(lamp),
    }]))
    .unwrap();
    let sun = Sun {
        enabled: true,
        position: DVec3::new(4300.0, 1400.0, 4200.0),
        radius: 20.0,
        colour: [1.0, 0.9, 0.8],
        intensity: 20.0,
        animate: false,
        speed_deg_per_s: 0.0,
    };
    let sky = Sky::Gradient {
        horizon: [0.9, 0.9, 1.0],
        zenith: [0.2, 0.4, 0.9],
    };
    let cams = [
        ((4050.0, 1020.0, 4050.0), (4095.0, 1000.0, 4093.3)), // looking at the far corner
        ((5000.0, 1500.0, 5000.0), (4050.0, 995.0, 4047.7)),  // far outside, looking in
        ((4090.0, 1001.0, 4070.5), (4095.0, 990.0, 4095.0)),  // on the floor's top face
        ((4088.5, 1005.5, 4088.5), (5000.0, 1005.5, 4088.5)), // inside glass, out through x
        ((4095.999, 1023.999, 0.5), (4095.999, 1023.999, 4096.0)), // along the far edge
        ((4096.0, 1024.0, 4096.0), (4000.0, 990.0, 4000.0)),  // on the far corner itself
    ];
    let views = cams
        .into_iter()
        .map(|(eye, target)| {
            let cam = Camera::looking_at(DVec3::from(eye), DVec3::from(target), 70.0);
            params(cam, sky.clone(), Some(sun.clone()), 6)
        })
        .collect();
    (w, views)
}

/// Every material kind (lambertian floor, glass, water, rough and mirror metal, a lamp),
/// the sun casting shadows and a gradient sky, seen obliquely; 4 bounces.
pub fn showcase() -> (World, SceneParams) {
    let w = World::new(
        GridDims::new(6, 4, 6).unwrap(),
        WorldConfig::with_workers(2),
    )
    .unwrap();
    let floor = add_material(&w, MaterialKind::Lambertian, 0, [150, 140, 120]);
    let glass = add_material(&w, MaterialKind::Dielectric, 0, [240, 250, 255]);
    let water = add_material(&w, MaterialKind::Dielectric, 1, [200, 230, 255]);
    let rough = add_material(&w, MaterialKind::Metal, 30, [230, 200, 120]);
    let mirror = add_material(&w, MaterialKind::Metal, 0, [250, 250, 250]);
    w.set_param(MaterialKind::Emissive, 2, 6.0).unwrap();
    let lamp = add_material(&w, MaterialKind::Emissive, 2, [255, 220, 180]);
    for (shape, m) in [
        (
            Shape::Box {
                min: IVec3::ZERO,
                max: IVec3::new(47, 2, 47),
            },
            floor,
        ),
        (
            Shape::Box {
                min: IVec3::new(0, 3, 28),
                max: IVec3::new(47, 5, 47),
            },
            water,
        ),
        (
            Shape::Box {
                min: IVec3::new(8, 3, 8),
                max: IVec3::new(15, 10, 15),
            },
            glass,
        ),
        (
            Shape::Sphere {
                centre: DVec3::new(30.0, 8.0, 14.0),
                radius: 5.0,
            },
            rough,
        ),
        (
            Shape::Box {
                min: IVec3::new(40, 3, 4),
                max: IVec3::new(41, 14, 20),
            },
            mirror,
        ),
    ] {
        w.apply(EditOp::Shape {
            shape,
            mode: Mode::Add(m),
        })
        .unwrap();
    }
    w.apply(EditOp::Voxels(vec![VoxelEdit {
        pos: IVec3::new(22, 12, 30),
        op: VoxelOp::Set(lamp),
    }]))
    .unwrap();
    let sun = Sun {
        enabled: true,
        position: DVec3::new(80.0, 90.0, 60.0),
        radius: 8.0,
        colour: [1.0, 0.9, 0.8],
        intensity: 15.0,
        animate: false,
        speed_deg_per_s: 0.0,
    };
    let cam = Camera::looking_at(
        DVec3::new(-8.0, 26.0, -8.0),
        DVec3::new(24.0, 6.0, 24.0),
        55.0,
    );
    let p = params(
        cam,
        Sky::Gradient {
            horizon: [0.8, 0.85, 1.0],
            zenith: [0.2, 0.35, 0.8],
        },
        Some(sun),
        4,
    );
    (w, p)
}

/// A square CPU reference render.
pub fn cpu_render(w: &World, p: &SceneParams, size: u32, spp: u32, seed: u64) -> Image {
    let view = w.read();
    render::cpu::CpuScene::new(&view, p).render(&render::cpu::RenderJob {
        width: size,
        height: size,
        spp,
        seed,
    })
}

/// A context on `device` with validation on; None (and a line saying so) on a machine without
/// any Vulkan driver unless VOXBRICK_REQUIRE_GPU=1 (CI) makes that a failure.
pub fn gpu_context(device: render::vulkan::DeviceChoice) -> Option<render::vulkan::GpuContext> {
    use render::vulkan::{ContextOptions, GpuContext, GpuError};
    match GpuContext::new(&ContextOptions {
        device,
        validation: true,
        ..Default::default()
    }) {
        Ok(c) => Some(c),
        Err(e @ GpuError::NoVulkan(_))
            if std::env::var("VOXBRICK_REQUIRE_GPU").as_deref() != Ok("1") =>
        {
            eprintln!(
                "SKIPPED: no Vulkan driver on this machine ({e}); VOXBRICK_REQUIRE_GPU=1 makes this a failure"
            );
            None
        }
        Err(e) => panic!("creating a Vulkan context: {e}"),
    }
}

/// Two emissive rectangles at different depths seen by an orthographic camera looking along
/// −z with one pixel per voxel, and a wall behind the image plane that must not be seen:
/// each pixel is exactly the lamp's radiance where its voxel column meets a rectangle, else
/// black (1 bounce, black sky: zero variance). A perspective camera would show the farther
/// rectangle smaller. Returns the world, the parameters (32 × 32 pixels) and which pixels
/// are lit, row by row from the top.
pub fn orthographic_walls() -> (World, SceneParams, Vec<bool>) {
    let w = world((4, 4, 4));
    let lamp = add_material(&w, MaterialKind::Emissive, 0, [255, 255, 255]);
    let rects = [
        (IVec3::new(4, 4, 10), IVec3::new(11, 11, 10)),
        (IVec3::new(20, 16, 20), IVec3::new(27, 23, 20)),
    ];
    for (min, max) in rects
        .into_iter()
        .chain([(IVec3::new(0, 0, 28), IVec3::new(31, 31, 28))])
    {
        w.apply(EditOp::Shape {
            shape: Shape::Box { min, max },
            mode: Mode::Add(lamp),
        })
        .unwrap();
    }
    let cam = Camera {
        position: DVec3::new(16.0, 16.0, 25.5),
        yaw_deg: 0.0,
        pitch_deg: 0.0,
        fov_y_deg: 50.0,
        projection: render::Projection::Orthographic { height: 32.0 },
    };
    let lit = (0..32 * 32)
        .map(|i| {
            let (x, y) = (i % 32, 31 - i / 32);
            rects
                .iter()
                .any(|(min, max)| (min.x..=max.x).contains(&x) && (min.y..=max.y).contains(&y))
        })
        .collect();
    (
        w,
        params(cam, Sky::Uniform { colour: [0.0; 3] }, None, 1),
        lit,
    )
}

/// Asserts an image of [`orthographic_walls`]: lit pixels all equal and positive, the rest
/// black.
pub fn assert_orthographic_walls(img: &Image, lit: &[bool], what: &str) {
    assert_eq!(img.pixels.len(), lit.len());
    let want = img.pixels[lit.iter().position(|l| *l).unwrap()];
    assert!(want[0] > 0.0, "{what}: {want:?}");
    for (i, (px, l)) in img.pixels.iter().zip(lit).enumerate() {
        for c in 0..3 {
            let expect = if *l { want[c] } else { 0.0 };
            assert!(
                (px[c] - expect).abs() <= 1e-5 * want[c],
                "{what}: pixel ({}, {}) is {px:?}, expected {}",
                i % 32,
                i / 32,
                if *l { "lit" } else { "black" }
            );
        }
    }
}

/// A camera inside a clear glass cube (IOR 1.5) looking out through a face at the uniform
/// [`SKY`], along near-normal directions only (in a cube, directions with every |dᵢ| below
/// cos θc are trapped by total internal reflection forever): the radiance seen is η²·L
/// (L/η² is invariant across the interface), which checks the (η_i/η_t)² factor and the
/// camera's medium. Orthographic: the image plane (4 voxels tall) lies inside the glass, so
/// every ray must start in it. Returns the expected value of channel 0.
pub fn inside_glass(orthographic: bool) -> (World, SceneParams, f64) {
    let w = world((4, 4, 4));
    let glass = add_material(&w, MaterialKind::Dielectric, 0, [255, 255, 255]);
    w.apply(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::splat(2),
            max: IVec3::splat(29),
        },
        mode: Mode::Add(glass),
    })
    .unwrap();
    let mut cam = Camera::looking_at(
        DVec3::new(15.3, 14.7, 16.1),
        DVec3::new(30.0, 14.7, 16.1),
        2.0,
    );
    if orthographic {
        cam.projection = render::Projection::Orthographic { height: 4.0 };
    }
    let p = params(cam, Sky::Uniform { colour: SKY }, None, 64);
    (w, p, 1.5 * 1.5 * SKY[0] as f64)
}

/// Closed rooms under a black sky, no sun, lit only by emissive voxels (the light-sampling cases):
/// one voxel; thousands of voxels (a ceiling panel); voxels of strengths 1 and 1000; a lamp
/// whose light reaches the view through a glass pane, and one sealed in glass. Named, 4
/// bounces. The camera sees no lamp directly (the noise compared is the lighting's, not the
/// pixel filter's at a lamp's edge).
pub fn lamp_rooms() -> Vec<(&'static str, World, SceneParams)> {
    let room = |bricks: (u32, u32, u32)| {
        let w = world(bricks);
        let wall = add_material(&w, MaterialKind::Lambertian, 0, [180, 170, 160]);
        let v = w.dims().voxels() - 1;
        let put = |m, min, max| {
            w.apply(EditOp::Shape {
                shape: Shape::Box { min, max },
                mode: m,
            })
            .unwrap()
        };
        put(Mode::Add(wall), IVec3::ZERO, v);
        put(Mode::Remove, IVec3::ONE, v - 1);
        // A block on the floor, so there are shadows.
        put(
            Mode::Add(wall),
            IVec3::new(v.x / 2 - 3, 1, v.z / 3),
            IVec3::new(v.x / 2 + 3, 6, v.z / 3 + 5),
        );
        w
    };
    let lamp = |w: &World, strength_param: u8, strength: f32, rgb: [u8; 3]| {
        w.set_param(MaterialKind::Emissive, strength_param, strength)
            .unwrap();
        add_material(w, MaterialKind::Emissive, strength_param, rgb)
    };
    let put = |w: &World, m: u8, min: IVec3, max: IVec3| {
        w.apply(EditOp::Shape {
            shape: Shape::Box { min, max },
            mode: Mode::Add(m),
        })
        .unwrap();
    };
    // From near the back wall (z high), looking down the room: the ceiling, the back wall
    // and the side walls near the camera are out of view.
    let camera = |w: &World| {
        let v = w.dims().voxels().as_dvec3();
        Camera::looking_at(
            DVec3::new(v.x * 0.5, v.y * 0.6, v.z - 3.0),
            DVec3::new(v.x * 0.5, 0.0, v.z * 0.5),
            60.0,
        )
    };
    let black = Sky::Uniform { colour: [0.0; 3] };
    let mut out = Vec::new();

    let w = room((4, 2, 4)); // 32 × 16 × 32
    let m = lamp(&w, 1, 60.0, [255, 230, 200]);
    put(&w, m, IVec3::new(20, 9, 30), IVec3::new(20, 9, 30));
    let p = params(camera(&w), black.clone(), None, 4);
    out.push(("one voxel", w, p));

    let w = room((6, 2, 6)); // 48 × 16 × 48
    let m = lamp(&w, 1, 1.5, [255, 255, 255]);
    put(&w, m, IVec3::new(1, 14, 1), IVec3::new(46, 14, 46));
    assert!(w.read().lights().len() >= 2000);
    let p = params(camera(&w), black.clone(), None, 4);
    out.push(("thousands of voxels", w, p));

    let w = room((4, 2, 4));
    let dim = lamp(&w, 1, 1.0, [255, 255, 255]);
    let bright = lamp(&w, 2, 1000.0, [255, 120, 60]);
    put(&w, dim, IVec3::new(2, 12, 30), IVec3::new(29, 13, 30));
    put(&w, bright, IVec3::new(8, 3, 30), IVec3::new(8, 3, 30));
    let p = params(camera(&w), black.clone(), None, 4);
    out.push(("strengths 1 and 1000", w, p));

    let w = room((4, 2, 4));
    let m = lamp(&w, 1, 60.0, [255, 255, 255]);
    let glass = add_material(&w, MaterialKind::Dielectric, 0, [240, 250, 255]);
    put(&w, m, IVec3::new(16, 3, 9), IVec3::new(16, 3, 9)); // hidden behind the block
    put(&w, glass, IVec3::new(2, 1, 18), IVec3::new(29, 14, 18)); // a pane across the room
    put(&w, glass, IVec3::new(2, 3, 27), IVec3::new(4, 5, 29));
    put(&w, m, IVec3::new(3, 4, 28), IVec3::new(3, 4, 28)); // sealed in glass
    let p = params(camera(&w), black.clone(), None, 4);
    out.push(("behind glass", w, p));

    // The sun through a roof open over half the room, and two lamps: each vertex chooses
    // between the sun and the light faces by their estimated contributions.
    let w = room((4, 2, 4));
    let m = lamp(&w, 1, 8.0, [255, 200, 150]);
    put(&w, m, IVec3::new(4, 8, 22), IVec3::new(6, 9, 24));
    put(&w, m, IVec3::new(24, 1, 20), IVec3::new(26, 2, 22));
    w.apply(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::new(1, 15, 1),
            max: IVec3::new(30, 15, 14),
        },
        mode: Mode::Remove,
    })
    .unwrap();
    let sun = Sun {
        enabled: true,
        position: DVec3::new(150.0, 420.0, 40.0),
        radius: 30.0,
        colour: [1.0, 0.95, 0.9],
        intensity: 40.0,
        animate: false,
        speed_deg_per_s: 0.0,
    };
    let p = params(camera(&w), black, Some(sun), 4);
    out.push(("the sun and lamps", w, p));
    out
}

/// Light sampling against BSDF sampling alone, from two independent renders of each
/// (`l1`, `l2` with light sampling, `b1`, `b2` without): for unbiased estimators of the same
/// image, the means L = (L₁ + L₂)/2 and B = (B₁ + B₂)/2 have E[(L − B)²] = E[(L₁ − L₂)²]/4 +
/// E[(B₁ − B₂)²]/4 (symmetric in each pair, so a firefly counts the same in whichever render
/// it lands). Returns that MSE over its expected value (≈ 1; a bias makes it larger) and the
/// image means' difference in standard errors.
pub fn same_image_within_noise(l1: &Image, l2: &Image, b1: &Image, b2: &Image) -> (f64, f64) {
    let px = |img: &Image, i: usize, k: usize| img.pixels[i][k] as f64;
    let (mut mse, mut expected, mut diff) = (0.0, 0.0, 0.0);
    let n = l1.pixels.len();
    for i in 0..n {
        for k in 0..3 {
            let l = 0.5 * (px(l1, i, k) + px(l2, i, k));
            let b = 0.5 * (px(b1, i, k) + px(b2, i, k));
            mse += (l - b).powi(2);
            expected += ((px(l1, i, k) - px(l2, i, k)).powi(2)
                + (px(b1, i, k) - px(b2, i, k)).powi(2))
                / 4.0;
            diff += l - b;
        }
    }
    // The mean over all pixel channels: its variance is the sum of the per-pixel ones / count².
    let count = (3 * n) as f64;
    (
        mse / expected,
        (diff / count).abs() / (expected.sqrt() / count),
    )
}

/// A square GPU render of `size` pixels with the scene's variant changed by `variant`;
/// `queued`: shadow rays go to the shadow pass (where the device can), else are traced where
/// they start.
#[allow(clippy::too_many_arguments)]
pub fn gpu_render_with(
    ctx: &render::vulkan::GpuContext,
    w: &World,
    p: &SceneParams,
    size: u32,
    spp: u32,
    seed: u64,
    variant: impl Fn(render::vulkan::trace::Variant) -> render::vulkan::trace::Variant,
    queued: bool,
) -> Image {
    use render::vulkan::trace::{PathTracer, Variant};
    let view = w.read();
    let world = render::vulkan::world::GpuWorld::upload(ctx, &view).unwrap();
    let mut tracer = PathTracer::new(ctx).unwrap();
    tracer.set_deferred_shadows(ctx, queued);
    let v = variant(Variant::for_scene(&view, p));
    let job = render::cpu::RenderJob {
        width: size,
        height: size,
        spp,
        seed,
    };
    let image = tracer
        .render(
            ctx,
            &world,
            &view,
            p,
            &job,
            render::viewport::RenderHow::variant(v),
        )
        .unwrap()
        .image;
    tracer.destroy(ctx);
    world.destroy(ctx);
    image
}
