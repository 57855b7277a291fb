//! Brickmap benchmarks: brush edits (with dirty-range recording and draining), whole-brick
//! box fill, random single-voxel inserts, and CPU primary rays over a terrain. Before the
//! timings it prints the memory the terrain takes (bytes per solid voxel).
//!
//! Run: `cargo bench -p brickmap --bench brickmap` (set BRICKMAP_WORKERS to pin workers).

use brickmap::{
    EditOp, GridDims, Mode, Ray, Shape, VoxelEdit, VoxelOp, World, WorldConfig, terrain,
};
use divan::Bencher;
use glam::{DVec3, IVec3};

fn workers() -> usize {
    std::env::var("BRICKMAP_WORKERS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

fn thesis_dims() -> GridDims {
    GridDims::new(64, 32, 64).unwrap() // 512 × 256 × 512 voxels
}

fn empty_world() -> World {
    World::new(thesis_dims(), WorldConfig::with_workers(workers())).unwrap()
}

fn terrain_world() -> World {
    let world = empty_world();
    for c in [2, 3, 4] {
        world
            .push_material(brickmap::Material::lambertian(c))
            .unwrap();
    }
    world.apply(terrain::rolling_hills(thesis_dims())).unwrap();
    world.take_dirty();
    world
}

fn main() {
    let world = terrain_world();
    let view = world.read();
    let m = view.memory();
    let solid = view.solid_count();
    println!(
        "terrain 512x256x512, 4 materials, {} workers: {solid} solid voxels, {} bricks; GPU bytes used {} \
         (index {}, bricks {}, coarse {}, material {} holding {} payload, tables {}) = {:.4} B/solid voxel; \
         reserved {:.4} B/voxel; {} uniform bricks",
        world.workers(),
        view.brick_count(),
        m.gpu_used(),
        m.brick_index,
        m.bricks_used,
        m.coarse,
        m.material_used,
        m.material_payload,
        m.tables,
        m.gpu_used() as f64 / solid as f64,
        m.gpu_reserved() as f64 / solid as f64,
        m.uniform_bricks,
    );
    drop(view);
    drop(world);
    divan::main();
}

/// One brush edit per iteration at the terrain surface, alternating add and remove at the
/// same spot so every iteration changes the full sphere; the renderer's drain is included.
#[divan::bench(args = [16.0, 64.0], sample_count = 40, sample_size = 1)]
fn sphere_brush(bencher: Bencher, radius: f64) {
    let world = terrain_world();
    let centre = DVec3::new(200.5, 128.0, 300.5);
    let mut add = true;
    let mut changed = 0u64;
    bencher.bench_local(|| {
        let mode = if add { Mode::Add(1) } else { Mode::Remove };
        add = !add;
        let out = world
            .apply(EditOp::Shape {
                shape: Shape::Sphere { centre, radius },
                mode,
            })
            .unwrap();
        changed = out.changed_voxels;
        divan::black_box(world.take_dirty());
    });
    divan::black_box(changed);
}

/// Fills the whole 512 × 256 × 512 grid (67 M voxels) with one box edit.
#[divan::bench(sample_count = 10, sample_size = 1)]
fn box_fill_512x256x512(bencher: Bencher) {
    bencher.with_inputs(empty_world).bench_local_refs(|world| {
        let max = world.dims().voxels() - 1;
        world
            .apply(EditOp::Shape {
                shape: Shape::Box {
                    min: IVec3::ZERO,
                    max,
                },
                mode: Mode::Add(0),
            })
            .unwrap()
    });
}

/// One million single-voxel sets at random positions of the whole 512 × 256 × 512 grid
/// (bricks are created, turn from uniform to per-voxel and change buckets); and the same
/// count packed into a 128³ region (bricks fill up, so every insert shifts bytes).
#[divan::bench(args = [512, 128], sample_count = 10, sample_size = 1)]
fn random_inserts_1m(bencher: Bencher, extent: i32) {
    let mut s = 0x2545F4914F6CDD1Du64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let edits: Vec<VoxelEdit> = (0..1_000_000)
        .map(|_| {
            let r = next();
            let pos = IVec3::new(
                (r & 511) as i32 % extent,
                (r >> 9 & 255) as i32 % extent,
                (r >> 17 & 511) as i32 % extent,
            );
            VoxelEdit {
                pos,
                op: VoxelOp::Set((r >> 26 & 1) as u8),
            }
        })
        .collect();
    bencher
        .with_inputs(|| {
            let w = empty_world();
            w.push_material(brickmap::Material::lambertian(5)).unwrap();
            (w, edits.clone())
        })
        .bench_local_refs(|(world, edits)| {
            world.apply(EditOp::Voxels(std::mem::take(edits))).unwrap()
        });
}

/// Builds the 512 × 256 × 512 test terrain (heights, bricks and the bulk write).
#[divan::bench(sample_count = 5, sample_size = 1)]
fn terrain_build(bencher: Bencher) {
    bencher.with_inputs(empty_world).bench_local_refs(|world| {
        for c in [2, 3, 4] {
            world
                .push_material(brickmap::Material::lambertian(c))
                .unwrap();
        }
        world.apply(terrain::rolling_hills(thesis_dims())).unwrap()
    });
}

/// 1024 × 576 primary rays from a camera above the terrain looking across it, split over the
/// available cores: 589,824 rays per iteration.
#[divan::bench(sample_count = 10, sample_size = 1)]
fn primary_rays_1024x576(bencher: Bencher) {
    let world = terrain_world();
    let view = world.read();
    let (w, h) = (1024usize, 576usize);
    let eye = DVec3::new(-20.0, 230.0, -20.0);
    let forward = (DVec3::new(256.0, 100.0, 256.0) - eye).normalize();
    let right = forward.cross(DVec3::Y).normalize();
    let up = right.cross(forward);
    let tan = (60f64.to_radians() / 2.0).tan();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    bencher.bench_local(|| {
        std::thread::scope(|s| {
            let view = &view;
            let handles: Vec<_> = (0..threads)
                .map(|t| {
                    s.spawn(move || {
                        let mut hits = 0u32;
                        for y in (t..h).step_by(threads) {
                            for x in 0..w {
                                let u = (2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * tan * w as f64
                                    / h as f64;
                                let v = (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * tan;
                                let dir = forward + right * u + up * v;
                                hits += view
                                    .ray_cast(&Ray { origin: eye, dir }, f64::INFINITY)
                                    .unwrap()
                                    .is_some() as u32;
                            }
                        }
                        hits
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).sum::<u32>()
        })
    });
}
