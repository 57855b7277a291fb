//! Objects benchmarks: compositing a whole 512 × 256 × 512 terrain model into an empty world
//! (brick-aligned at identity, the copy path, and turned 90° about y, the per-voxel path), a
//! sphere edit of that model followed by its re-composite, and 10,000 small objects: building
//! the composite and updating it after one object moved.
//!
//! Run: `cargo bench -p brickmap --bench objects` (set BRICKMAP_WORKERS to pin workers).

use brickmap::objects::{
    Axis, Composite, LayerId, Model, ModelId, NewNode, ObjectTree, Orientation, Placement,
};
use brickmap::{EditOp, GridDims, Mode, Shape, World, WorldConfig, terrain};
use divan::Bencher;
use glam::{DVec3, IVec3};
use std::collections::BTreeMap;

fn workers() -> usize {
    std::env::var("BRICKMAP_WORKERS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

fn dims() -> GridDims {
    GridDims::new(64, 32, 64).unwrap() // 512 × 256 × 512 voxels
}

fn world() -> World {
    world_of(dims())
}

fn world_of(grid: GridDims) -> World {
    let w = World::new(grid, WorldConfig::with_workers(workers())).unwrap();
    for c in [2, 3, 4] {
        w.push_material(brickmap::Material::lambertian(c)).unwrap();
    }
    w
}

/// The rolling-hills terrain as one model of the whole grid.
fn terrain_model() -> (Model, World) {
    let source = world();
    source.apply(terrain::rolling_hills(dims())).unwrap();
    (Model::from_world(&source).unwrap(), source)
}

fn one_object(rot: Orientation, size: IVec3) -> ObjectTree {
    let mut tree = ObjectTree::new();
    tree.add(
        ObjectTree::ROOT,
        None,
        "terrain",
        Placement { rot, t: size / 2 },
        NewNode::Object {
            model: ModelId(0),
            layer: LayerId(0),
        },
    )
    .unwrap();
    tree
}

/// The benchmark's brush: a sphere in the terrain's middle, added or removed in turn.
fn brush(radius: f64, add: bool) -> EditOp {
    EditOp::Shape {
        shape: Shape::Sphere {
            centre: DVec3::new(256.0, 100.0, 256.0),
            radius,
        },
        mode: if add { Mode::Add(1) } else { Mode::Remove },
    }
}

fn main() {
    let (model, source) = terrain_model();
    let bricks = model.bricks().count();
    println!(
        "terrain model {:?}: {} solid voxels in {bricks} bricks, {} bytes of bricks \
         (the world: {} stored bricks, {} GPU bytes used)",
        model.size(),
        model.solid_count(),
        model.brick_bytes(),
        source.read().brick_count(),
        source.read().memory().gpu_used()
    );
    divan::main();
}

/// The whole terrain composited into an empty world (every brick written): placed at the
/// origin, turned a quarter about y, or moved one voxel along x (a world a brick wider).
#[divan::bench(args = ["identity", "turned", "shifted"], sample_count = 5, sample_size = 1)]
fn composite_terrain(bencher: Bencher, how: &str) {
    let (model, _) = terrain_model();
    let size = model.size();
    // Turned about y, the model's x and z swap: a square model still fits the grid.
    let rot = match how {
        "turned" => Orientation::quarter_turn(Axis::Y, 1),
        _ => Orientation::IDENTITY,
    };
    let mut tree = one_object(rot, size);
    let mut grid = dims();
    if how == "shifted" {
        let node = tree.node(ObjectTree::ROOT).unwrap().children()[0];
        tree.node_mut(node).unwrap().placement.t += IVec3::X;
        let b = grid.bricks();
        grid = GridDims::new(b.x + 1, b.y, b.z).unwrap();
    }
    let models = BTreeMap::from([(ModelId(0), model)]);
    let composite = Composite::new(&tree, &models, grid.voxels()).unwrap();
    let all = composite.all_bricks();
    bencher
        .with_inputs(|| world_of(grid))
        .bench_local_values(|w| {
            composite.write(&w, &all, &models).unwrap();
            w
        });
}

/// A sphere brush in the terrain model, then its re-composite (what a stroke segment costs
/// in edit mode).
#[divan::bench(
    args = [(16.0, "identity"), (64.0, "identity"), (16.0, "turned"), (64.0, "turned")],
    sample_count = 20,
    sample_size = 1
)]
fn model_edit_then_composite(bencher: Bencher, (radius, how): (f64, &str)) {
    let (model, source) = terrain_model();
    let table = source.materials().clone();
    let size = model.size();
    let rot = match how {
        "identity" => Orientation::IDENTITY,
        _ => Orientation::quarter_turn(Axis::Y, 1),
    };
    let tree = one_object(rot, size);
    let mut models = BTreeMap::from([(ModelId(0), model)]);
    let composite = Composite::new(&tree, &models, dims().voxels()).unwrap();
    let w = world();
    composite
        .write(&w, &composite.all_bricks(), &models)
        .unwrap();
    let mut add = true;
    bencher.bench_local(|| {
        let op = brush(radius, add);
        add = !add;
        let m = models.get_mut(&ModelId(0)).unwrap();
        let out = m.apply(&op, &table).unwrap();
        composite
            .model_edited(&w, &models, ModelId(0), &out.inverse)
            .unwrap();
        w.take_dirty();
    });
}

/// 10,000 objects (100 models of 8 × 8 × 8, each placed 100 times, in 100 groups).
fn many() -> (ObjectTree, BTreeMap<ModelId, Model>) {
    let table = world().materials().clone();
    let mut models = BTreeMap::new();
    for m in 0..100u32 {
        let mut model = Model::new(IVec3::splat(8)).unwrap();
        let op = EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::splat(4.0),
                radius: 2.0 + (m % 3) as f64,
            },
            mode: Mode::Add((m % 3 + 1) as u8),
        };
        model.apply(&op, &table).unwrap();
        models.insert(ModelId(m), model);
    }
    let mut tree = ObjectTree::new();
    for g in 0..100 {
        let group = tree
            .add(
                ObjectTree::ROOT,
                None,
                format!("row {g}"),
                Placement::IDENTITY,
                NewNode::Group,
            )
            .unwrap();
        for i in 0..100 {
            let t = IVec3::new(
                8 + (i % 50) * 10,
                8 + (g % 20) * 12,
                8 + (g / 20) * 100 + (i / 50) * 40,
            );
            let new = NewNode::Object {
                model: ModelId(((g * 100 + i) % 100) as u32),
                layer: LayerId(0),
            };
            let rot = Orientation::all().nth(((g + i) % 48) as usize).unwrap();
            tree.add(group, None, format!("o{i}"), Placement { rot, t }, new)
                .unwrap();
        }
    }
    (tree, models)
}

/// Building the composite of 10,000 objects (the drawn list, boxes, index) and writing it.
#[divan::bench(sample_count = 5, sample_size = 1)]
fn ten_thousand_objects_build(bencher: Bencher) {
    let (tree, models) = many();
    bencher.with_inputs(world).bench_local_values(|w| {
        let c = Composite::new(&tree, &models, dims().voxels()).unwrap();
        c.write(&w, &c.all_bricks(), &models).unwrap();
        w
    });
}

/// One of 10,000 objects moved: the composite updated (the whole tree walked again, two
/// small boxes rewritten).
#[divan::bench(sample_count = 20, sample_size = 1)]
fn ten_thousand_objects_move_one(bencher: Bencher) {
    let (mut tree, models) = many();
    let mut c = Composite::new(&tree, &models, dims().voxels()).unwrap();
    let w = world();
    c.write(&w, &c.all_bricks(), &models).unwrap();
    let node = tree.node(ObjectTree::ROOT).unwrap().children()[50];
    let node = tree.node(node).unwrap().children()[7];
    let mut step = 0;
    bencher.bench_local(|| {
        step += 1;
        tree.node_mut(node).unwrap().placement.t.x = 20 + (step % 2) * 3;
        c.update(&w, &tree, &models, &[]).unwrap();
        w.take_dirty();
    });
}

/// The model edit alone (no composite): how much of an edit through a model is the model's.
#[divan::bench(args = [16.0, 64.0], sample_count = 20, sample_size = 1)]
fn model_edit_alone(bencher: Bencher, radius: f64) {
    let (mut model, source) = terrain_model();
    let table = source.materials().clone();
    let mut add = true;
    bencher.bench_local(|| {
        let op = brush(radius, add);
        add = !add;
        model.apply(&op, &table).unwrap()
    });
}

/// Noise terrain (the editor's Terrain window, 5 octaves of Perlin) generated into the
/// 512 × 256 × 512 world and into a model of that size: what the Terrain window will cost
/// once it generates into the active object.
#[divan::bench(args = ["world", "model"], sample_count = 5, sample_size = 1)]
fn noise_terrain(bencher: Bencher, into: &str) {
    let w = world();
    let materials = brickmap::terrain::TerrainMaterials {
        grass: vec![1],
        dirt: vec![2],
        rock: vec![3],
        sand: vec![2],
        snow: vec![1],
        water: 0,
    };
    let params = brickmap::terrain::TerrainParams {
        seed: 2022,
        noise: brickmap::terrain::NoiseKind::Perlin,
        scale: 180.0,
        octaves: 5,
        height_range: (40, 200),
        water_level: 0,
        rock_line: 0.62,
        snow_line: 0.86,
        soil_depth: 3,
        materials,
    };
    let table = w.materials().clone();
    match into {
        "world" => bencher.bench_local(|| {
            let op = brickmap::terrain::NoiseTerrain::new(params.clone(), dims())
                .unwrap()
                .edit();
            w.apply(op).unwrap()
        }),
        _ => {
            let mut m = Model::new(dims().voxels()).unwrap();
            bencher.bench_local(|| {
                let op = brickmap::terrain::NoiseTerrain::new(params.clone(), dims())
                    .unwrap()
                    .edit();
                m.apply(&op, &table).unwrap()
            })
        }
    }
}
