//! Replay throughput of a long generated sculpting session (2,000 strokes of every mode and
//! shape, with undo/redo chains every 20 strokes) on a 256 × 64 × 256 grid, and the history
//! memory per step. Before the timing it prints voxels changed and history bytes per step
//! from one run.
//!
//! Run: `cargo bench -p app --bench replay`.

use app::editor::Document;
use app::editor::command::{BrushMode, BrushShape, Command, Mirror, Stroke};
use app::editor::history::History;
use app::editor::script::{self, ReplayOptions, Script, Start, Step};
use app::scene::Scene;
use glam::DVec3;

fn session() -> Script {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let mut steps = Vec::new();
    for i in 0..2000 {
        let r = next();
        let mode = match r % 20 {
            0..12 => BrushMode::Attach,
            12..17 => BrushMode::Erase,
            _ => BrushMode::Paint,
        };
        let shape = [
            BrushShape::Sphere,
            BrushShape::Cube,
            BrushShape::Cylinder,
            BrushShape::Line,
        ][(r >> 8) as usize % 4];
        let size = 2.0 + ((r >> 16) % 7) as f64;
        let start = DVec3::new(
            ((r >> 24) % 240) as f64 + 8.0,
            ((r >> 32) % 48) as f64 + 8.0,
            ((r >> 40) % 240) as f64 + 8.0,
        );
        let points = (0..1 + (r >> 48) % 4)
            .map(|k| start + DVec3::new(k as f64 * 6.0, 0.0, k as f64 * 3.0))
            .collect();
        steps.push(Step::Do(Command::Stroke(Stroke {
            mode,
            shape,
            size,
            material: 0,
            mirror: Mirror::default(),
            points,
            axis: Default::default(),
            in_selection: false,
            paint: Default::default(),
        })));
        if i % 20 == 19 {
            steps.extend([Step::Undo, Step::Undo, Step::Undo, Step::Redo, Step::Redo]);
        }
    }
    Script {
        format_version: 1,
        start: Start::New {
            size: (256, 64, 256),
            terrain: None,
        },
        workers: None,
        steps,
    }
}

fn main() {
    let script = session();
    let dims = brickmap::GridDims::new(32, 8, 32).unwrap();
    let mut doc = Document::new(Scene::empty(dims, 0).unwrap(), History::default());
    let (mut changed, mut peak) = (0u64, 0usize);
    for step in &script.steps {
        match step {
            Step::Do(c) => changed += doc.execute(c.clone()).unwrap().changed_voxels,
            Step::Undo => drop(doc.undo().unwrap()),
            Step::Redo => drop(doc.redo().unwrap()),
            _ => unreachable!(),
        }
        peak = peak.max(doc.history.bytes());
    }
    let steps = doc.history.undo_len() + doc.history.redo_len();
    println!(
        "session: {} script steps, {changed} voxels changed by strokes, {} solid at the end; history {} bytes over {steps} steps = {:.0} bytes/step (peak {peak})",
        script.steps.len(),
        doc.scene.world.read().solid_count(),
        doc.history.bytes(),
        doc.history.bytes() as f64 / steps as f64,
    );
    divan::main();
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn replay_sculpt_session(bencher: divan::Bencher) {
    let script = session();
    let out = std::env::temp_dir().join(format!("voxbrick-replay-bench-{}", std::process::id()));
    let options = ReplayOptions {
        out_dir: Some(out),
        device: "cpu".into(),
        ..Default::default()
    };
    bencher.bench_local(|| {
        script::replay(&script, std::path::Path::new("."), &options, &mut |_| {})
            .unwrap()
            .steps
    });
}
