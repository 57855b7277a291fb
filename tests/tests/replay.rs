//! The replay scripts in tests/scripts: each runs with 1 and with 4 workers and must give
//! the same content hash and the same saved files, byte for byte. Failing steps name the
//! step and what differed; a recorded session replays to the same content.

use app::editor::Document;
use app::editor::command::{BrushMode, BrushShape, Command, Mirror, Stroke};
use app::editor::history::History;
use app::editor::script::{self, Recorder, ReplayOptions, Start};
use app::scene::Scene;
use std::path::{Path, PathBuf};

fn scripts() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts");
    let mut all: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    all.sort();
    all
}

/// A scratch folder for this test, removed when it passes.
fn scratch(name: &str) -> app::scratch::Scratch {
    app::scratch::Scratch::new(&format!("replay-{name}"))
}

fn options(workers: usize, out: &Path) -> ReplayOptions {
    ReplayOptions {
        workers: Some(workers),
        out_dir: Some(out.to_path_buf()),
        device: "cpu".into(),
        history_budget: None,
    }
}

#[test]
fn every_script_passes_and_is_deterministic_across_worker_counts() {
    let all = scripts();
    assert!(all.len() >= 6, "{all:?}");
    for path in all {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let mut hashes = Vec::new();
        let mut outs = Vec::new();
        for workers in [1, 4] {
            let out = scratch(&format!("{name}-{workers}"));
            let mut lines = Vec::new();
            let replayed = script::replay_file(&path, &options(workers, &out), &mut |l| {
                lines.push(l.to_string())
            })
            .unwrap_or_else(|e| {
                panic!("{name} with {workers} workers: {e:#}\n{}", lines.join("\n"))
            });
            assert_eq!(lines.len(), replayed.steps, "one report line per step");
            hashes.push(replayed.document.scene.world.read().content_hash());
            outs.push(out);
        }
        assert_eq!(
            hashes[0], hashes[1],
            "{name}: content differs between 1 and 4 workers"
        );
        // Every project file written is the same, byte for byte.
        for entry in std::fs::read_dir(&outs[0]).into_iter().flatten() {
            let file = entry.unwrap().path();
            if file.extension().is_some_and(|e| e == "ron") {
                let other = outs[1].join(file.file_name().unwrap());
                assert_eq!(
                    std::fs::read(&file).unwrap(),
                    std::fs::read(&other).unwrap(),
                    "{name}: {} differs",
                    file.display()
                );
            }
        }
    }
}

fn replay_text(text: &str, out: &Path) -> Result<usize, String> {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts");
    let parsed = script::parse(text).map_err(|e| format!("{e:#}"))?;
    script::replay(&parsed, &folder, &options(2, out), &mut |_| {})
        .map(|r| r.steps)
        .map_err(|e| format!("{e:#}"))
}

#[test]
fn failures_name_the_step_and_what_differed() {
    let out = scratch("failures");
    let head = "(format_version: 1, start: New(size: (32, 32, 32)), steps: [";
    let sphere = "Do(Stroke((mode: Attach, shape: Sphere, size: 4.0, material: 0, points: [(16.0, 16.0, 16.0)])))";
    let cases = [
        (
            format!("{head} {sphere}, Save(\"kept.ron\"), ExpectSolidCount(5) ])"),
            "step 3 (ExpectSolidCount)",
            "expected 5",
        ),
        (
            format!("{head} {sphere}, ExpectVoxel(at: (0, 0, 0), material: Some(0)) ])"),
            "step 2",
            "voxel [0, 0, 0] is None",
        ),
        (
            format!("{head} Undo ])"),
            "step 1 (Undo)",
            "nothing to undo",
        ),
        (
            format!(
                "{head} Do(Stroke((mode: Attach, shape: Sphere, size: 4.0, material: 9, points: [(1.0, 1.0, 1.0)]))) ])"
            ),
            "step 1",
            "beyond the material table",
        ),
        (
            format!("{head} Do(ImportVox(path: \"missing.vox\", offset: (0, 0, 0))) ])"),
            "step 1",
            "missing.vox",
        ),
        (
            format!("{head} ExpectHashOf(\"nowhere\") ])"),
            "step 1",
            "no mark",
        ),
        (
            format!(
                "{head} Render((spp: 1, width: 4, height: 4, mean_min: Some((5.0, 5.0, 5.0)))) ])"
            ),
            "step 1 (Render)",
            "below",
        ),
        (
            "(format_version: 2, start: New(size: (8, 8, 8)), steps: [])".to_string(),
            "",
            "version 2",
        ),
    ];
    for (text, step, what) in cases {
        let err = replay_text(&text, &out).expect_err(&text);
        assert!(err.contains(step) && err.contains(what), "{err}");
    }
    // The project saved before the failing step is complete.
    let kept = app::formats::project::load(&out.join("kept.ron"), 1).unwrap();
    assert!(kept.world.read().solid_count() > 0);
    // Rendering on a device that does not exist is refused, naming the CPU alternative.
    let parsed =
        script::parse(&format!("{head} Render((spp: 1, width: 4, height: 4)) ])")).unwrap();
    let gpu = ReplayOptions {
        device: "no such gpu 9000".into(),
        ..options(1, &out)
    };
    let err = format!(
        "{:#}",
        script::replay(&parsed, &out, &gpu, &mut |_| {})
            .err()
            .unwrap()
    );
    assert!(err.contains("--device cpu"), "{err}");
}

/// The session `doc` recorded (it started as an empty 64 × 32 × 64 grid), as script text and
/// replayed headlessly.
fn replay_recording(doc: &Document, name: &str) -> (String, Document) {
    let text = doc.recorder.as_ref().unwrap().to_ron(
        Start::New {
            size: (64, 32, 64),
            terrain: None,
        },
        Some(2),
    );
    let parsed = script::parse(&text).unwrap();
    let out = scratch(name);
    let replayed = script::replay(&parsed, &out, &options(1, &out), &mut |_| {}).unwrap();
    (text, replayed.document)
}

#[test]
fn a_recorded_session_replays_to_the_same_content() {
    let dims = brickmap::GridDims::new(8, 4, 8).unwrap();
    let mut doc = Document::new(Scene::empty(dims, 2).unwrap(), History::default());
    doc.recorder = Some(Recorder::default());
    let stroke = |x: f64, mode| {
        Command::Stroke(Stroke {
            mode,
            shape: BrushShape::Sphere,
            size: 5.0,
            material: 0,
            mirror: Mirror {
                z: true,
                centre: glam::DVec3::splat(32.0),
                ..Default::default()
            },
            points: vec![glam::DVec3::new(x, 16.0, 20.0)],
            axis: Default::default(),
            in_selection: false,
            paint: Default::default(),
        })
    };
    doc.execute(stroke(20.0, BrushMode::Attach)).unwrap();
    doc.execute(stroke(40.0, BrushMode::Attach)).unwrap();
    doc.execute(stroke(30.0, BrushMode::Erase)).unwrap();
    doc.undo().unwrap();
    doc.execute(Command::SetColour {
        index: 3,
        rgb: [9, 8, 7],
    })
    .unwrap();
    doc.undo().unwrap();
    doc.redo().unwrap();
    let want = doc.scene.world.read().content_hash();
    let (text, replayed) = replay_recording(&doc, "recorded");
    assert_eq!(
        text.matches("\n        ").count(),
        7,
        "one line per step:\n{text}"
    );
    assert_eq!(replayed.scene.world.read().content_hash(), want);
}

#[test]
fn a_recorded_selection_session_replays_to_the_same_content() {
    use app::selection::SelectOp;
    use glam::IVec3;
    let dims = brickmap::GridDims::new(8, 4, 8).unwrap();
    let mut doc = Document::new(Scene::empty(dims, 2).unwrap(), History::default());
    doc.recorder = Some(Recorder::default());
    let box_at = |min: IVec3, max: IVec3| SelectOp::Replace { min, max };
    doc.execute(Command::Select(box_at(
        IVec3::new(4, 0, 4),
        IVec3::new(30, 12, 30),
    )))
    .unwrap();
    doc.execute(Command::FillSelection(0)).unwrap();
    doc.execute(Command::Select(SelectOp::Subtract {
        min: IVec3::new(10, 0, 10),
        max: IVec3::new(20, 31, 20),
    }))
    .unwrap();
    doc.execute(Command::Copy).unwrap();
    doc.execute(Command::MoveSelection(IVec3::new(20, 3, -9)))
        .unwrap();
    doc.execute(Command::Paste {
        at: IVec3::new(40, 0, 40),
    })
    .unwrap();
    doc.execute(Command::PaintSelection(0)).unwrap();
    doc.undo().unwrap();
    doc.execute(Command::Cut).unwrap();
    doc.execute(Command::Paste {
        at: IVec3::new(0, 20, 0),
    })
    .unwrap();
    let want = doc.scene.world.read().content_hash();
    let (_, replayed) = replay_recording(&doc, "recorded-selection");
    assert_eq!(replayed.scene.world.read().content_hash(), want);
    assert_eq!(
        replayed.scene.selection.map(|s| s.region),
        doc.scene.selection.map(|s| s.region)
    );
}

#[test]
fn the_readme_example_is_a_tested_script() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("../README.md")).unwrap();
    let section = &readme[readme
        .find("## Replay scripts")
        .expect("README has the section")..];
    let start = section.find("```ron\n").unwrap() + "```ron\n".len();
    let block = &section[start..start + section[start..].find("```").unwrap()];
    let file = std::fs::read_to_string(root.join("scripts/readme_example.ron")).unwrap();
    assert_eq!(
        block, file,
        "README's example must be tests/scripts/readme_example.ron"
    );
}

#[test]
fn gpu_renders_in_scripts_match_the_cpu_reference() {
    // Needs a Vulkan driver (lavapipe in CI); skips, saying so, only where there is none and
    // VOXBRICK_REQUIRE_GPU is not set.
    if render::vulkan::GpuContext::new(&Default::default()).is_err() {
        assert_ne!(
            std::env::var("VOXBRICK_REQUIRE_GPU").as_deref(),
            Ok("1"),
            "no Vulkan device, and VOXBRICK_REQUIRE_GPU=1"
        );
        eprintln!("SKIPPED: no Vulkan driver on this machine");
        return;
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/gpu/gpu_vs_cpu.ron");
    let out = scratch("gpu");
    let gpu = ReplayOptions {
        device: "gpu".into(),
        ..options(2, &out)
    };
    let mut lines = Vec::new();
    script::replay_file(&path, &gpu, &mut |l| lines.push(l.to_string()))
        .unwrap_or_else(|e| panic!("{e:#}\n{}", lines.join("\n")));
    let compared = lines
        .iter()
        .filter(|l| l.contains("matches the CPU reference"))
        .count();
    assert_eq!(compared, 2, "{lines:#?}");
    // The same script on the CPU refuses compare_cpu by name rather than comparing nothing.
    let err = format!(
        "{:#}",
        script::replay_file(&path, &options(2, &out), &mut |_| {})
            .err()
            .unwrap()
    );
    assert!(err.contains("compare_cpu needs a GPU"), "{err}");
}

/// The modelling tools recorded and replayed: terrain, a live gradient stroke, random and
/// darken strokes, the face wand, a screen rectangle, a copy stamped twice turned, an
/// extrude, a turn of the selection — the same content and selection after replay.
#[test]
fn a_recorded_modelling_session_replays_to_the_same_content() {
    use app::editor::command::{PaintMode, TerrainSpec};
    use app::selection::SelectOp;
    use app::wand::Combine;
    use glam::{DVec3, IVec3};
    let dims = brickmap::GridDims::new(8, 4, 8).unwrap();
    let mut doc = Document::new(Scene::empty(dims, 2).unwrap(), History::default());
    doc.recorder = Some(Recorder::default());
    doc.execute(Command::GenerateTerrain(TerrainSpec::for_size((
        64, 32, 64,
    ))))
    .unwrap();
    let stroke = |mode, paint, points: Vec<DVec3>| Stroke {
        mode,
        shape: BrushShape::Sphere,
        size: 4.0,
        material: 1,
        mirror: Mirror::default(),
        points,
        axis: Default::default(),
        in_selection: false,
        paint,
    };
    let drag: Vec<DVec3> = (0..8)
        .map(|k| DVec3::new(8.0 + 5.0 * k as f64, 14.0, 20.0 + 2.0 * k as f64))
        .collect();
    doc.begin_stroke(stroke(
        BrushMode::Paint,
        PaintMode::Gradient { to: 4 },
        drag[..1].to_vec(),
    ))
    .unwrap();
    for p in &drag[1..] {
        doc.extend_stroke(std::slice::from_ref(p)).unwrap();
    }
    doc.end_stroke().unwrap();
    let random = PaintMode::Random {
        among: vec![0, 2, 5],
        seed: 9,
    };
    doc.execute(Command::Stroke(stroke(
        BrushMode::Attach,
        random,
        drag.clone(),
    )))
    .unwrap();
    doc.execute(Command::Stroke(stroke(
        BrushMode::Paint,
        PaintMode::Darken,
        drag,
    )))
    .unwrap();
    let top = {
        let view = doc.scene.world.read();
        (0..32)
            .rev()
            .map(|y| IVec3::new(40, y, 40))
            .find(|v| view.voxel(*v).unwrap().is_some())
            .unwrap()
    };
    doc.execute(Command::Select(SelectOp::Face {
        start: top,
        normal: IVec3::Y,
        by_material: false,
        diagonal: true,
        how: Combine::Replace,
    }))
    .unwrap();
    let camera = doc.scene.params.camera.clone();
    doc.execute(Command::Select(SelectOp::Rect {
        rect: Box::new(app::rect_select::ScreenRect {
            camera,
            aspect: 1.5,
            pixels: (96, 64),
            a: (-0.3, -0.3),
            b: (0.2, 0.25),
            visible_only: true,
        }),
        how: Combine::Add,
    }))
    .unwrap();
    doc.execute(Command::Copy).unwrap();
    doc.execute(Command::Stamp {
        at: vec![IVec3::new(2, 20, 2), IVec3::new(30, 22, 6)],
        quarters: 3,
    })
    .unwrap();
    doc.execute(Command::Extrude {
        voxel: top,
        normal: IVec3::Y,
        distance: 2,
        same_material: false,
    })
    .unwrap();
    doc.execute(Command::TransformSelection(
        app::selection_transform::SelectionTransform::Turn {
            axis: brickmap::objects::Axis::Y,
            quarters: 1,
        },
    ))
    .unwrap();
    let want = doc.scene.world.read().content_hash();
    let (_, replayed) = replay_recording(&doc, "recorded-modelling");
    assert_eq!(replayed.scene.world.read().content_hash(), want);
    assert_eq!(
        replayed.scene.selection.map(|s| s.voxels.count()),
        doc.scene.selection.map(|s| s.voxels.count())
    );
}
