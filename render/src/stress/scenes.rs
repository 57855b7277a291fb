//! The stress suite's worlds: two for the ray traversal (a dense jumble and the largest grid)
//! and the adversarial image scenes, white furnaces among them.

use super::Rng;
use crate::{Camera, RenderSettings, SceneParams, Sequence, Sky, Sun};
use brickmap::{
    EditOp, GridDims, Material, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp, World, WorldConfig,
};
use glam::{DVec3, IVec3};

/// A world for ray traversal and solid voxels known to be in it.
pub struct RayWorld {
    /// Name in reports.
    pub name: &'static str,
    /// The world.
    pub world: World,
    /// Some of its solid voxels (origins inside voxels start in these).
    pub solid: Vec<IVec3>,
}

fn world(bricks: (u32, u32, u32)) -> World {
    World::new(
        GridDims::new(bricks.0, bricks.1, bricks.2).expect("valid grid"),
        WorldConfig::default(),
    )
    .expect("a world")
}

fn material(w: &World, kind: MaterialKind, param: u8, rgb: [u8; 3]) -> u8 {
    let colour = 250 - w.materials().len() as u8;
    w.set_colour(colour, rgb);
    w.push_material(Material {
        kind,
        param,
        colour,
    })
    .expect("room for a material")
}

fn add(w: &World, shape: Shape, m: u8) {
    w.apply(EditOp::Shape {
        shape,
        mode: Mode::Add(m),
    })
    .expect("a valid shape");
}

fn erase(w: &World, shape: Shape) {
    w.apply(EditOp::Shape {
        shape,
        mode: Mode::Remove,
    })
    .expect("a valid shape");
}

fn cube(min: IVec3, max: IVec3) -> Shape {
    Shape::Box { min, max }
}

fn ball(centre: DVec3, radius: f64) -> Shape {
    Shape::Sphere { centre, radius }
}

/// Random single voxels within `min..min+extent`, set to `m`; returns them.
fn scatter(w: &World, rng: &mut Rng, n: usize, min: IVec3, extent: IVec3, m: u8) -> Vec<IVec3> {
    let voxels: Vec<IVec3> = (0..n)
        .map(|_| {
            min + IVec3::new(
                rng.below(extent.x as u64) as i32,
                rng.below(extent.y as u64) as i32,
                rng.below(extent.z as u64) as i32,
            )
        })
        .collect();
    w.apply(EditOp::Voxels(
        voxels
            .iter()
            .map(|&pos| VoxelEdit {
                pos,
                op: VoxelOp::Set(m),
            })
            .collect(),
    ))
    .expect("voxels inside the grid");
    voxels
}

/// 256 × 128 × 256 voxels: random boxes and spheres (some aligned to bricks, so full cells),
/// a checkerboard slab (every other voxel: no empty 2³ block to skip), a brick-aligned solid
/// block, and 20 000 single voxels.
pub fn dense() -> RayWorld {
    let w = world((32, 16, 32));
    let m = material(&w, MaterialKind::Lambertian, 0, [180, 180, 180]);
    let mut rng = Rng::new(7);
    for _ in 0..40 {
        let min = IVec3::new(
            rng.below(240) as i32,
            rng.below(112) as i32,
            rng.below(240) as i32,
        );
        let extent = IVec3::new(
            1 + rng.below(24) as i32,
            1 + rng.below(24) as i32,
            1 + rng.below(24) as i32,
        );
        add(
            &w,
            cube(min, (min + extent).min(IVec3::new(255, 127, 255))),
            m,
        );
    }
    for _ in 0..25 {
        let c = DVec3::new(
            rng.unit_f64() * 256.0,
            rng.unit_f64() * 128.0,
            rng.unit_f64() * 256.0,
        );
        add(&w, ball(c, 1.0 + rng.unit_f64() * 12.0), m);
    }
    add(&w, cube(IVec3::new(64, 0, 64), IVec3::new(127, 31, 127)), m);
    let checker: Vec<VoxelEdit> = (0..32)
        .flat_map(|x| (0..8).flat_map(move |y| (0..32).map(move |z| IVec3::new(x, y, z))))
        .filter(|v| (v.x + v.y + v.z) % 2 == 0)
        .map(|v| VoxelEdit {
            pos: v + IVec3::new(160, 40, 160),
            op: VoxelOp::Set(m),
        })
        .collect();
    w.apply(EditOp::Voxels(checker)).expect("inside the grid");
    let solid = scatter(
        &w,
        &mut rng,
        20_000,
        IVec3::ZERO,
        IVec3::new(256, 128, 256),
        m,
    );
    RayWorld {
        name: "dense 256×128×256",
        world: w,
        solid,
    }
}

/// The largest grid (4096 × 1024 × 4096 voxels): boxes and scattered voxels at each of its
/// eight corners and a sphere in the middle, where f32 coordinates are coarsest.
pub fn largest() -> RayWorld {
    let w = world((512, 128, 512));
    let m = material(&w, MaterialKind::Lambertian, 0, [180, 180, 180]);
    let mut rng = Rng::new(11);
    let size = IVec3::new(4096, 1024, 4096);
    let mut solid = Vec::new();
    for k in 0..8 {
        let corner = IVec3::new(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        let near = corner * (size - 24);
        add(&w, cube(near + 4, near + 10), m);
        solid.extend(scatter(&w, &mut rng, 500, near, IVec3::splat(24), m));
    }
    add(&w, ball(size.as_dvec3() * 0.5, 40.0), m);
    RayWorld {
        name: "largest 4096×1024×4096",
        world: w,
        solid,
    }
}

/// An adversarial image scene.
pub struct ImageScene {
    /// Name in reports.
    pub name: &'static str,
    /// The world.
    pub world: World,
    /// Its views.
    pub views: Vec<SceneParams>,
    /// A white furnace or closed emitter: every pixel's expected radiance (channel 0), and
    /// whether the estimator conserves energy exactly there (false: single-scattering GGX
    /// loses some by design).
    pub expected: Option<(f64, bool)>,
}

fn no_sun() -> Sun {
    Sun {
        enabled: false,
        position: DVec3::new(0.0, 1000.0, 0.0),
        radius: 1.0,
        colour: [1.0; 3],
        intensity: 0.0,
        animate: false,
        speed_deg_per_s: 0.0,
    }
}

fn sun(position: DVec3, radius: f64, intensity: f32) -> Sun {
    Sun {
        enabled: true,
        position,
        radius,
        colour: [1.0, 0.95, 0.9],
        intensity,
        animate: false,
        speed_deg_per_s: 0.0,
    }
}

fn gradient() -> Sky {
    Sky::Gradient {
        horizon: [0.9, 0.9, 1.0],
        zenith: [0.2, 0.4, 0.9],
    }
}

fn params(camera: Camera, sky: Sky, sun: Sun, bounces: u32) -> SceneParams {
    SceneParams {
        camera,
        sun,
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

fn look(eye: (f64, f64, f64), target: (f64, f64, f64), fov: f64) -> Camera {
    Camera::looking_at(DVec3::from(eye), DVec3::from(target), fov)
}

/// The furnace sky.
const SKY: [f32; 3] = [0.7, 0.5, 0.3];

/// A white 12³ block in a uniform sky seen from a corner and from a face: the image is the
/// sky everywhere when the material conserves energy.
fn furnace(
    name: &'static str,
    kind: MaterialKind,
    roughness: Option<f32>,
    bounces: u32,
) -> ImageScene {
    let w = world((4, 4, 4));
    if let Some(r) = roughness {
        w.set_param(kind, 1, r).expect("a valid roughness");
    }
    let param = u8::from(roughness.is_some());
    let m = material(&w, kind, param, [255, 255, 255]);
    add(&w, cube(IVec3::splat(10), IVec3::splat(21)), m);
    let views = [
        look((-6.0, 40.0, -8.0), (16.0, 16.0, 16.0), 40.0),
        look((16.0, 16.0, 2.0), (16.0, 16.0, 16.0), 70.0),
    ]
    .into_iter()
    .map(|c| params(c, Sky::Uniform { colour: SKY }, no_sun(), bounces))
    .collect();
    ImageScene {
        name,
        world: w,
        views,
        expected: Some((SKY[0] as f64, roughness.is_none())),
    }
}

/// A floor with lambertian and mirror bumps.
fn bumpy_floor() -> World {
    let w = world((8, 4, 8));
    let floor = material(&w, MaterialKind::Lambertian, 0, [160, 150, 130]);
    let metal = material(&w, MaterialKind::Metal, 0, [230, 200, 120]);
    add(&w, cube(IVec3::ZERO, IVec3::new(63, 4, 63)), floor);
    let mut rng = Rng::new(5);
    for _ in 0..30 {
        let c = DVec3::new(rng.unit_f64() * 64.0, 5.0, rng.unit_f64() * 64.0);
        let m = if rng.below(3) == 0 { metal } else { floor };
        add(&w, ball(c, 1.0 + rng.unit_f64() * 5.0), m);
    }
    w
}

/// Every adversarial scene.
pub fn all() -> Vec<ImageScene> {
    let mut scenes = vec![
        furnace("furnace: lambertian", MaterialKind::Lambertian, None, 8),
        furnace("furnace: mirror", MaterialKind::Metal, None, 8),
        furnace("furnace: glass", MaterialKind::Dielectric, None, 64),
        furnace(
            "furnace: rough metal r = 0.5",
            MaterialKind::Metal,
            Some(0.5),
            16,
        ),
    ];
    // A closed box of emissive walls seen from inside: every sample is the emission.
    {
        let w = world((4, 4, 4));
        w.set_param(MaterialKind::Emissive, 1, 2.5)
            .expect("a valid strength");
        let lamp = material(&w, MaterialKind::Emissive, 1, [255, 255, 255]);
        add(&w, cube(IVec3::ZERO, IVec3::splat(31)), lamp);
        erase(&w, cube(IVec3::ONE, IVec3::splat(30)));
        let views = [
            look((16.0, 16.0, 16.0), (30.0, 20.0, 25.0), 90.0),
            look((1.0, 1.0, 1.0), (31.0, 31.0, 31.0), 120.0),
        ]
        .into_iter()
        .map(|c| params(c, Sky::Uniform { colour: [0.0; 3] }, no_sun(), 8))
        .collect();
        scenes.push(ImageScene {
            name: "emissive only (closed lamp box)",
            world: w,
            views,
            expected: Some((2.5, true)),
        });
    }
    // Glass around water around glass around an air bubble, on a floor, in the sun.
    {
        let w = world((8, 8, 8));
        let floor = material(&w, MaterialKind::Lambertian, 0, [150, 150, 150]);
        let glass = material(&w, MaterialKind::Dielectric, 0, [240, 250, 255]);
        let water = material(&w, MaterialKind::Dielectric, 1, [200, 230, 255]);
        add(&w, cube(IVec3::ZERO, IVec3::new(63, 3, 63)), floor);
        add(&w, cube(IVec3::new(8, 4, 8), IVec3::new(55, 51, 55)), glass);
        add(
            &w,
            cube(IVec3::new(16, 12, 16), IVec3::new(47, 43, 47)),
            water,
        );
        add(&w, ball(DVec3::splat(32.0), 10.0), glass);
        erase(&w, ball(DVec3::splat(32.0), 4.0));
        let s = sun(DVec3::new(120.0, 160.0, 90.0), 8.0, 30.0);
        let views = [
            look((-20.0, 70.0, -30.0), (32.0, 28.0, 32.0), 50.0),
            look((32.0, 32.0, 32.0), (60.0, 40.0, 10.0), 90.0),
            look((20.0, 20.0, 20.0), (40.0, 60.0, 40.0), 90.0),
        ]
        .into_iter()
        .map(|c| params(c, gradient(), s.clone(), 32))
        .collect();
        scenes.push(ImageScene {
            name: "nested glass",
            world: w,
            views,
            expected: None,
        });
    }
    // Inside a glass slab looking at its top face beyond the critical angle.
    {
        let w = world((8, 4, 8));
        let glass = material(&w, MaterialKind::Dielectric, 0, [250, 250, 250]);
        add(&w, cube(IVec3::ZERO, IVec3::new(63, 23, 63)), glass);
        let s = sun(DVec3::new(200.0, 100.0, 32.0), 10.0, 20.0);
        let views = [
            look((4.0, 12.0, 32.0), (60.0, 23.5, 32.0), 30.0),
            look((32.0, 1.0, 32.0), (63.0, 23.0, 40.0), 60.0),
        ]
        .into_iter()
        .map(|c| params(c, gradient(), s.clone(), 64))
        .collect();
        scenes.push(ImageScene {
            name: "total internal reflection",
            world: w,
            views,
            expected: None,
        });
    }
    // Two parallel mirrors and a lamp at the end of the corridor, 64 bounces.
    {
        let w = world((8, 8, 8));
        let mirror = material(&w, MaterialKind::Metal, 0, [250, 250, 250]);
        let floor = material(&w, MaterialKind::Lambertian, 0, [120, 120, 120]);
        w.set_param(MaterialKind::Emissive, 1, 8.0)
            .expect("a valid strength");
        let lamp = material(&w, MaterialKind::Emissive, 1, [255, 230, 200]);
        add(&w, cube(IVec3::ZERO, IVec3::new(63, 0, 63)), floor);
        add(
            &w,
            cube(IVec3::new(20, 1, 0), IVec3::new(20, 40, 63)),
            mirror,
        );
        add(
            &w,
            cube(IVec3::new(43, 1, 0), IVec3::new(43, 40, 63)),
            mirror,
        );
        add(
            &w,
            cube(IVec3::new(28, 10, 63), IVec3::new(35, 17, 63)),
            lamp,
        );
        let views = [
            look((30.0, 12.0, 2.0), (43.0, 14.0, 30.0), 60.0),
            look((32.0, 20.0, 10.0), (20.0, 20.0, 10.5), 20.0),
        ]
        .into_iter()
        .map(|c| params(c, Sky::Uniform { colour: [0.05; 3] }, no_sun(), 64))
        .collect();
        scenes.push(ImageScene {
            name: "mirror corridor",
            world: w,
            views,
            expected: None,
        });
    }
    // A bumpy floor under three suns: on the horizon, tiny and bright, and huge and close.
    let cams = [
        look((-10.0, 20.0, -10.0), (32.0, 5.0, 32.0), 60.0),
        look((32.0, 6.0, 32.0), (100.0, 5.5, 32.0), 90.0),
    ];
    for (name, s) in [
        (
            "sun at the horizon",
            sun(DVec3::new(10_032.0, 5.0, 32.0), 200.0, 20.0),
        ),
        (
            "sun of radius 0.001",
            sun(DVec3::new(100.0, 200.0, 60.0), 1e-3, 1e9),
        ),
        (
            "sun of radius 10⁵ at 10³",
            sun(DVec3::new(32.0, 1000.0, 32.0), 1e5, 0.5),
        ),
    ] {
        scenes.push(ImageScene {
            name,
            world: bumpy_floor(),
            views: cams
                .iter()
                .map(|c| params(c.clone(), gradient(), s.clone(), 4))
                .collect(),
            expected: None,
        });
    }
    // A closed white room with one lamp: paths run to 64 bounces.
    {
        let w = world((4, 4, 4));
        let white = material(&w, MaterialKind::Lambertian, 0, [255, 255, 255]);
        let lamp = material(&w, MaterialKind::Emissive, 0, [255, 255, 255]);
        add(&w, cube(IVec3::ZERO, IVec3::splat(31)), white);
        erase(&w, cube(IVec3::ONE, IVec3::splat(30)));
        add(
            &w,
            cube(IVec3::new(15, 30, 15), IVec3::new(16, 30, 16)),
            lamp,
        );
        let views = vec![params(
            look((4.0, 4.0, 4.0), (28.0, 20.0, 28.0), 90.0),
            Sky::Uniform { colour: [0.0; 3] },
            no_sun(),
            64,
        )];
        scenes.push(ImageScene {
            name: "maximum bounces (closed white room)",
            world: w,
            views,
            expected: None,
        });
    }
    // The largest grid with glass, metal and a lamp at its far corner.
    {
        let w = world((512, 128, 512));
        let floor = material(&w, MaterialKind::Lambertian, 0, [150, 150, 150]);
        let glass = material(&w, MaterialKind::Dielectric, 0, [240, 250, 255]);
        let metal = material(&w, MaterialKind::Metal, 0, [230, 200, 120]);
        let lamp = material(&w, MaterialKind::Emissive, 0, [255, 255, 255]);
        add(
            &w,
            cube(IVec3::new(4000, 990, 4000), IVec3::new(4095, 1000, 4095)),
            floor,
        );
        add(
            &w,
            cube(IVec3::new(4080, 1001, 4080), IVec3::new(4095, 1010, 4095)),
            glass,
        );
        add(&w, ball(DVec3::new(4060.0, 1010.0, 4060.0), 6.0), metal);
        add(
            &w,
            cube(IVec3::new(4090, 1020, 4090), IVec3::new(4090, 1020, 4090)),
            lamp,
        );
        let s = sun(DVec3::new(4300.0, 1400.0, 4200.0), 20.0, 20.0);
        let views = [
            look((4050.0, 1020.0, 4050.0), (4095.0, 1000.0, 4093.3), 70.0),
            look((5000.0, 1500.0, 5000.0), (4050.0, 995.0, 4047.7), 70.0),
            look((4088.5, 1005.5, 4088.5), (5000.0, 1005.5, 4088.5), 70.0),
            look((4096.0, 1024.0, 4096.0), (4000.0, 990.0, 4000.0), 70.0),
        ]
        .into_iter()
        .map(|c| params(c, gradient(), s.clone(), 8))
        .collect();
        scenes.push(ImageScene {
            name: "largest grid, far corner",
            world: w,
            views,
            expected: None,
        });
    }
    scenes
}
