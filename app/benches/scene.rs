//! Scene benchmarks on the thesis scene (512 × 256 × 512 terrain, water, metal statue):
//! generation, project save and load, .vox export. Before the timings it prints the project
//! size against the .vox export size.
//!
//! Run: `cargo bench -p app --bench scene`.

use app::builtin::thesis_scene;
use app::formats::{project, vox};
use divan::Bencher;
use std::path::Path;

fn main() {
    let scene = thesis_scene(0).unwrap();
    let ron = project::to_string(&scene);
    let data = vox::export_data(&scene.world).unwrap();
    let mut vox_bytes = Vec::new();
    data.write_vox(&mut vox_bytes).unwrap();
    let view = scene.world.read();
    println!(
        "thesis scene: {} solid voxels; project {} bytes, .vox export {} bytes ({} models): project/.vox = {:.4}",
        view.solid_count(),
        ron.len(),
        vox_bytes.len(),
        data.models.len(),
        ron.len() as f64 / vox_bytes.len() as f64
    );
    drop(view);
    divan::main();
}

#[divan::bench(sample_count = 20, sample_size = 1)]
fn generate_thesis_scene() -> app::Scene {
    thesis_scene(0).unwrap()
}

#[divan::bench(sample_count = 20, sample_size = 1)]
fn save_project(bencher: Bencher) {
    let scene = thesis_scene(0).unwrap();
    let dir = std::env::temp_dir().join(format!("voxbrick-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("thesis.ron");
    bencher.bench_local(|| project::save(&scene, &path).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}

#[divan::bench(sample_count = 20, sample_size = 1)]
fn load_project(bencher: Bencher) {
    let text = project::to_string(&thesis_scene(0).unwrap());
    bencher
        .bench_local(|| project::from_bytes(text.as_bytes(), Path::new("thesis.ron"), 0).unwrap());
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn export_vox(bencher: Bencher) {
    let scene = thesis_scene(0).unwrap();
    bencher.bench_local(|| {
        let data = vox::export_data(&scene.world).unwrap();
        let mut bytes = Vec::new();
        data.write_vox(&mut bytes).unwrap();
        bytes.len()
    });
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn import_vox(bencher: Bencher) {
    let scene = thesis_scene(0).unwrap();
    let mut bytes = Vec::new();
    vox::export_data(&scene.world)
        .unwrap()
        .write_vox(&mut bytes)
        .unwrap();
    bencher.bench_local(|| {
        vox::import_bytes(
            &bytes,
            Path::new("thesis.vox"),
            &vox::ImportOptions::default(),
            0,
        )
        .unwrap()
    });
}
