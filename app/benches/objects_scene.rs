//! A scene of over 1,000 objects: every readable `.vox` in `assets/vox` imported side by side,
//! round after round (each import a group of the file's objects, with models of its own),
//! into a new empty scene whose grid grows to hold them. Printed once: how long the imports
//! took, the objects, models and bytes, the saved project's size. Timed: opening the saved
//! project (parse, models, composite), moving one object by a voxel and hiding one (each
//! with its undo), and the whole composite rebuilt (every object written into an empty
//! world of the grid's size).
//!
//! Run: `cargo bench -p app --bench objects_scene`. With `VOXBRICK_BENCH_OUT=DIR` the
//! project goes there, with the replay script that builds it from `assets/vox` (`DIR` one
//! folder below the repository's root: `voxbrick replay DIR/objects-scene.ron --save …`
//! on another machine).

use app::editor::Document;
use app::editor::command::Command;
use app::editor::history::History;
use app::editor::objects::ObjectCommand;
use app::scene::Scene;
use brickmap::objects::{NodeId, NodeKind, ObjectTree, Objects};
use brickmap::{GridDims, World, WorldConfig};
use divan::Bencher;
use glam::IVec3;
use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Instant;

/// Objects the scene holds at least.
const OBJECTS: usize = 1000;

fn main() {
    let (doc, file) = scene();
    let objects = doc.scene.objects();
    let (models, index) = objects.bytes();
    let dims = doc.scene.world.dims().voxels();
    println!(
        "{} objects, {} models, grid {}x{}x{}, {} solid voxels shown; models {:.1} MB, tree + \
         composite index {:.2} MB; the world on the GPU {:.1} MB; project {:.1} MB",
        count(&objects),
        objects.models().len(),
        dims.x,
        dims.y,
        dims.z,
        doc.scene.world.read().solid_count(),
        models as f64 / 1e6,
        index as f64 / 1e6,
        doc.scene.world.read().memory().gpu_used() as f64 / 1e6,
        std::fs::metadata(file).map_or(0, |m| m.len()) as f64 / 1e6,
    );
    drop(objects);
    divan::main();
}

/// The objects (not groups) of the tree.
fn count(objects: &Objects) -> usize {
    let tree = objects.tree();
    tree.subtree(ObjectTree::ROOT)
        .unwrap()
        .into_iter()
        .filter(|n| matches!(tree.node(*n).unwrap().kind, NodeKind::Object { .. }))
        .count()
}

/// The readable `.vox` files of `assets/vox` with their extents (the box their objects
/// cover, from the origin).
fn files() -> Vec<(PathBuf, IVec3)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/vox");
    let mut out = Vec::new();
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "vox"))
        .collect();
    paths.sort();
    for p in paths {
        if let Ok(scene) = app::formats::load(&p, 2) {
            out.push((p, scene.world.dims().voxels()));
        }
    }
    out
}

/// The scene built once, and the project it was saved to.
fn scene() -> &'static (Document, PathBuf) {
    static SCENE: OnceLock<(Document, PathBuf)> = OnceLock::new();
    SCENE.get_or_init(|| {
        let files = files();
        let scene = Scene::empty(
            GridDims::from_voxels(glam::UVec3::new(1024, 128, 1024)).unwrap(),
            0,
        )
        .unwrap();
        let mut doc = Document::new(scene, History::default());
        let started = Instant::now();
        // Rows along x, 8 voxels apart, a new row past 2048; a new layer of rows past
        // 2048 in z.
        let (mut x, mut z, mut y, mut row_depth, mut layer_height) = (0, 0, 0, 0, 0);
        let mut imports = 0;
        let mut script = String::from(
            "// 1,000 objects: every readable .vox of assets/vox imported side by side, round\n\
             // after round (written by app/benches/objects_scene.rs).\n\
             (format_version: 1, start: New(size: (1024, 128, 1024)), workers: None, steps: [\n",
        );
        while count(&doc.scene.objects()) < OBJECTS {
            for (path, size) in &files {
                if x + size.x > 2048 {
                    x = 0;
                    z += row_depth + 8;
                    row_depth = 0;
                }
                if z + size.z > 2048 {
                    z = 0;
                    y += layer_height + 8;
                    layer_height = 0;
                }
                doc.execute(Command::ImportVox {
                    path: path.display().to_string(),
                    offset: IVec3::new(x, y, z),
                })
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                let name = path.file_name().unwrap().to_string_lossy();
                script += &format!(
                    "    Do(ImportVox(path: \"../assets/vox/{name}\", offset: ({x}, {y}, {z}))),\n"
                );
                imports += 1;
                x += size.x + 8;
                row_depth = row_depth.max(size.z);
                layer_height = layer_height.max(size.y);
            }
        }
        println!(
            "{imports} imports in {:.1} s",
            started.elapsed().as_secs_f64()
        );
        let dir = std::env::var_os("VOXBRICK_BENCH_OUT")
            .map(PathBuf::from)
            .unwrap_or_else(std::env::temp_dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("objects-scene.ron"), script + "])\n").unwrap();
        let file = dir.join("objects-scene-project.ron");
        doc.save(&file).unwrap();
        (doc, file)
    })
}

/// The `k`-th object of the drawing order.
fn object(doc: &Document, k: usize) -> NodeId {
    let objects = doc.scene.objects();
    let tree = objects.tree();
    tree.subtree(ObjectTree::ROOT)
        .unwrap()
        .into_iter()
        .filter(|n| matches!(tree.node(*n).unwrap().kind, NodeKind::Object { .. }))
        .nth(k)
        .unwrap()
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn open_the_project(bencher: Bencher) {
    let (_, file) = scene();
    bencher.bench(|| app::formats::load(file, 0).unwrap());
}

#[divan::bench(sample_count = 3, sample_size = 1)]
fn composite_every_object(bencher: Bencher) {
    let (doc, _) = scene();
    let objects = doc.scene.objects();
    let dims = doc.scene.world.dims();
    let table = doc.scene.world.materials().clone();
    bencher.bench(|| {
        let world = World::new(dims, WorldConfig::with_workers(0)).unwrap();
        world.replace_materials(table.clone()).unwrap();
        Objects::new(objects.tree().clone(), objects.models().clone(), &world).unwrap()
    });
}

#[divan::bench(args = ["move by a voxel", "hide"], sample_count = 20, sample_size = 1)]
fn one_object_of_many_and_its_undo(bencher: Bencher, what: &str) {
    let (_, file) = scene();
    let scene = app::formats::load(file, 0).unwrap();
    let mut doc = Document::new(scene, History::default());
    let n = object(&doc, OBJECTS / 2);
    let command = match what {
        "hide" => ObjectCommand::Show {
            node: n,
            visible: false,
        },
        _ => ObjectCommand::Translate {
            nodes: vec![n],
            by: IVec3::X,
        },
    };
    bencher.bench_local(|| {
        doc.execute(Command::Object(command.clone())).unwrap();
        doc.undo().unwrap();
    });
}
