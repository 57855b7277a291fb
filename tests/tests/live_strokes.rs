//! Live strokes: a drag is one undoable step that grows segment by segment. For every shape
//! and mode (and with mirror symmetry), the segments give the content hash of the same stroke
//! applied at once; undo restores the exact hash before the stroke, redo the one after; a
//! segment that fails undoes the whole stroke; the recorder replays the stroke at once to the
//! same hash.

use app::builtin::{SceneSize, default_scene};
use app::editor::Document;
use app::editor::command::{BrushMode, BrushShape, Command, Mirror, Stroke};
use app::editor::history::History;
use app::editor::{EditError, script};
use glam::DVec3;

fn document() -> Document {
    Document::new(
        default_scene(SceneSize::Small, 2).unwrap(),
        History::default(),
    )
}

fn hash(doc: &Document) -> u64 {
    doc.scene.world.read().content_hash()
}

/// A wandering drag over the small default scene's ground (128 × 64 × 128).
fn drag() -> Vec<DVec3> {
    (0..12)
        .map(|i| {
            let t = i as f64;
            DVec3::new(30.0 + 5.0 * t, 34.0 + (t * 0.7).sin() * 6.0, 40.0 + 3.0 * t)
        })
        .collect()
}

fn stroke(mode: BrushMode, shape: BrushShape, mirror: bool) -> Stroke {
    Stroke {
        mode,
        shape,
        size: 3.5,
        material: 4,
        mirror: Mirror {
            x: mirror,
            z: mirror,
            centre: DVec3::new(64.0, 0.0, 64.0),
            ..Mirror::default()
        },
        points: drag(),
        axis: Default::default(),
        in_selection: false,
        paint: Default::default(),
    }
}

#[test]
fn segments_give_the_hash_of_the_stroke_applied_at_once_and_undo_exactly() {
    use BrushShape::*;
    for shape in [Voxel, Sphere, Cube, Cylinder, Line, Box] {
        for mode in [BrushMode::Attach, BrushMode::Erase, BrushMode::Paint] {
            for mirror in [false, true] {
                let what = format!("{shape:?} {mode:?} mirror {mirror}");
                let s = stroke(mode, shape, mirror);
                let mut at_once = document();
                at_once.execute(Command::Stroke(s.clone())).unwrap();
                let mut live = document();
                let before = hash(&live);
                let points = s.points.clone();
                // First two points, then segments of one, three and the rest.
                live.begin_stroke(Stroke {
                    points: points[..2].to_vec(),
                    ..s.clone()
                })
                .unwrap();
                live.extend_stroke(&points[2..3]).unwrap();
                live.extend_stroke(&points[3..6]).unwrap();
                live.extend_stroke(&points[6..]).unwrap();
                assert!(live.live_stroke().is_some());
                let done = live.end_stroke().unwrap().expect("a stroke was open");
                let after = hash(&live);
                assert_eq!(after, hash(&at_once), "{what}");
                if mode != BrushMode::Erase || shape != Voxel {
                    assert_ne!(after, before, "{what}: the stroke changed something");
                    assert!(done.changed_voxels > 0, "{what}");
                }
                assert_eq!(live.history.undo_len(), 1, "{what}: one step");
                live.undo().unwrap();
                assert_eq!(hash(&live), before, "{what}: undo");
                live.redo().unwrap();
                assert_eq!(hash(&live), after, "{what}: redo");
            }
        }
    }
}

#[test]
fn a_box_follows_its_last_corner_and_is_applied_on_release() {
    let mut doc = document();
    let before = hash(&doc);
    let s = Stroke {
        points: vec![DVec3::new(20.0, 40.0, 20.0)],
        ..stroke(BrushMode::Attach, BrushShape::Box, false)
    };
    doc.begin_stroke(s.clone()).unwrap();
    doc.extend_stroke(&[DVec3::new(90.0, 45.0, 90.0)]).unwrap();
    doc.extend_stroke(&[DVec3::new(30.0, 44.0, 35.0)]).unwrap();
    assert_eq!(hash(&doc), before, "nothing until release");
    doc.end_stroke().unwrap();
    let mut at_once = document();
    at_once
        .execute(Command::Stroke(Stroke {
            points: vec![s.points[0], DVec3::new(30.0, 44.0, 35.0)],
            ..s
        }))
        .unwrap();
    assert_eq!(hash(&doc), hash(&at_once));
}

#[test]
fn a_failing_segment_undoes_the_whole_stroke_and_leaves_no_step() {
    let mut doc = document();
    let before = hash(&doc);
    let s = stroke(BrushMode::Attach, BrushShape::Sphere, false);
    doc.begin_stroke(s.clone()).unwrap();
    assert_ne!(hash(&doc), before);
    let err = doc
        .extend_stroke(&[DVec3::new(40.0, f64::NAN, 40.0)])
        .unwrap_err();
    assert!(matches!(err, EditError::Invalid(_)), "{err}");
    assert_eq!(hash(&doc), before, "the stroke so far is undone");
    assert!(doc.live_stroke().is_none());
    assert_eq!(doc.end_stroke().unwrap().map(|e| e.changed_voxels), None);
    assert_eq!(doc.history.undo_len(), 0);
    // A bad material is refused before anything is applied.
    let err = doc
        .begin_stroke(Stroke {
            material: 250,
            ..s.clone()
        })
        .unwrap_err();
    assert!(matches!(err, EditError::World(_)), "{err}");
    assert_eq!(hash(&doc), before);
    // Abort undoes what was applied.
    doc.begin_stroke(s).unwrap();
    doc.abort_stroke().unwrap();
    assert_eq!(hash(&doc), before);
    assert_eq!(doc.history.undo_len(), 0);
}

#[test]
fn a_recorded_live_stroke_replays_to_the_same_hash() {
    let mut doc = document();
    doc.recorder = Some(script::Recorder::default());
    let s = stroke(BrushMode::Attach, BrushShape::Line, true);
    doc.begin_stroke(Stroke {
        points: s.points[..1].to_vec(),
        ..s.clone()
    })
    .unwrap();
    for p in &s.points[1..] {
        doc.extend_stroke(std::slice::from_ref(p)).unwrap();
    }
    // Undo finishes the open stroke first: it is one step, then undone.
    doc.undo().unwrap();
    doc.redo().unwrap();
    let steps = doc
        .recorder
        .take()
        .unwrap()
        .script(
            script::Start::New {
                size: (1, 1, 1),
                terrain: None,
            },
            None,
        )
        .steps;
    assert_eq!(steps.len(), 3, "{steps:?}");
    let mut replayed = document();
    for step in steps {
        match step {
            script::Step::Do(c) => {
                replayed.execute(c).unwrap();
            }
            script::Step::Undo => {
                replayed.undo().unwrap();
            }
            script::Step::Redo => {
                replayed.redo().unwrap();
            }
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(hash(&replayed), hash(&doc));
}

#[test]
fn the_preview_is_exactly_what_the_click_then_changes() {
    use BrushShape::*;
    let doc = document();
    let dims = doc.scene.world.dims().voxels();
    let snapshot = |doc: &Document| {
        let view = doc.scene.world.read();
        let mut all = Vec::with_capacity((dims.x * dims.y * dims.z) as usize);
        for x in 0..dims.x {
            for y in 0..dims.y {
                for z in 0..dims.z {
                    all.push(view.voxel(glam::IVec3::new(x, y, z)).unwrap());
                }
            }
        }
        all
    };
    let before = snapshot(&doc);
    drop(doc);
    for shape in [Voxel, Sphere, Cube, Cylinder, Box] {
        for mode in [BrushMode::Attach, BrushMode::Erase, BrushMode::Paint] {
            let mut doc = document();
            let s = Stroke {
                points: vec![DVec3::new(50.5, 33.5, 60.5), DVec3::new(58.5, 38.5, 66.5)],
                ..stroke(mode, shape, true)
            };
            let preview = {
                let view = doc.scene.world.read();
                app::editor::command::preview(&view, &s, None)
                    .unwrap()
                    .unwrap()
            };
            doc.execute(Command::Stroke(s)).unwrap();
            let after = snapshot(&doc);
            let changed: Vec<glam::IVec3> = (0..before.len())
                .filter(|&i| before[i] != after[i])
                .map(|i| {
                    let i = i as i32;
                    glam::IVec3::new(i / (dims.y * dims.z), i / dims.z % dims.y, i % dims.z)
                })
                .collect();
            let what = format!("{shape:?} {mode:?}");
            assert!(!changed.is_empty(), "{what} changes something");
            assert_eq!(preview, changed, "{what}");
        }
    }
}

/// The colour modes (gradient, random, darken, brighten): live == at once, undo and redo exact, and every voxel of the grid against a
/// voxel-by-voxel reference: covered = within the capsule's radius of the stroke (the voxel
/// centre's distance, computed here), material by the mode's rule.
#[test]
fn colour_modes_match_a_voxel_by_voxel_reference_live_and_at_once() {
    use app::editor::command::PaintMode;
    let modes = [
        (BrushMode::Paint, PaintMode::Gradient { to: 1 }),
        (BrushMode::Attach, PaintMode::Gradient { to: 6 }),
        (
            BrushMode::Paint,
            PaintMode::Random {
                among: vec![1, 3, 5],
                seed: 11,
            },
        ),
        (
            BrushMode::Attach,
            PaintMode::Random {
                among: vec![2, 6],
                seed: 3,
            },
        ),
        (BrushMode::Paint, PaintMode::Darken),
        (BrushMode::Paint, PaintMode::Brighten),
    ];
    // Back and forth over the same voxels: darken must change each once.
    let points: Vec<DVec3> = [30.0, 50.0, 36.0, 56.0, 40.0]
        .iter()
        .enumerate()
        .map(|(i, x)| DVec3::new(*x, 33.0 + i as f64 * 0.5, 44.0 + i as f64))
        .collect();
    let dims = document().scene.world.dims().voxels();
    for (mode, paint) in modes {
        let what = format!("{mode:?} {paint:?}");
        let s = Stroke {
            points: points.clone(),
            size: 4.5,
            material: 4,
            paint: paint.clone(),
            ..stroke(mode, BrushShape::Sphere, false)
        };
        let mut live = document();
        let before = hash(&live);
        let table = live.scene.world.materials().clone();
        let darker = app::editor::command::neighbours(&table, false);
        let brighter = app::editor::command::neighbours(&table, true);
        let old: Vec<Option<u8>> = {
            let view = live.scene.world.read();
            every_voxel(dims).map(|v| view.voxel(v).unwrap()).collect()
        };
        live.begin_stroke(Stroke {
            points: points[..1].to_vec(),
            ..s.clone()
        })
        .unwrap();
        for p in &points[1..] {
            live.extend_stroke(std::slice::from_ref(p)).unwrap();
        }
        let done = live.end_stroke().unwrap().expect("a stroke was open");
        assert!(done.changed_voxels > 0, "{what}");
        let after = hash(&live);
        assert_ne!(after, before, "{what}");
        let mut at_once = document();
        let whole = s.clone();
        at_once.execute(Command::Stroke(whole.clone())).unwrap();
        assert_eq!(hash(&at_once), after, "{what}: live = at once");
        // The reference, voxel by voxel.
        let view = live.scene.world.read();
        let r2 = s.size * s.size;
        let (a, b) = (whole.points[0], whole.points[whole.points.len() - 1]);
        let mut covered_count = 0;
        for (v, was) in every_voxel(dims).zip(&old) {
            let c = v.as_dvec3() + 0.5;
            let covered = whole.points.windows(2).any(|w| {
                let ab = w[1] - w[0];
                let t = ((c - w[0]).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                (c - (w[0] + ab * t)).length_squared() <= r2
            });
            covered_count += covered as u32;
            let want = match (&paint, covered, mode, *was) {
                (_, false, _, was) => was,
                (_, true, BrushMode::Paint, None) => None,
                (PaintMode::Gradient { to }, true, _, _) => {
                    let t = ((c - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
                    Some((4.0 + (t * (*to as f64 - 4.0)).round()) as u8)
                }
                (PaintMode::Random { among, seed }, true, _, _) => {
                    Some(among[app::editor::command::paint_hash(v, *seed) as usize % among.len()])
                }
                (PaintMode::Darken, true, _, Some(m)) => Some(darker[m as usize]),
                (PaintMode::Brighten, true, _, Some(m)) => Some(brighter[m as usize]),
                other => panic!("{other:?}"),
            };
            assert_eq!(view.voxel(v).unwrap(), want, "{what} at {v}");
        }
        assert!(covered_count > 500, "{what}: {covered_count}");
        drop(view);
        live.undo().unwrap();
        assert_eq!(hash(&live), before, "{what}: undo");
        live.redo().unwrap();
        assert_eq!(hash(&live), after, "{what}: redo");
    }
}

#[test]
fn colour_modes_that_cannot_apply_are_refused_and_change_nothing() {
    use app::editor::command::PaintMode;
    let mut doc = document();
    let before = hash(&doc);
    for (mode, paint) in [
        (BrushMode::Attach, PaintMode::Darken),
        (BrushMode::Erase, PaintMode::Brighten),
        (
            BrushMode::Paint,
            PaintMode::Random {
                among: vec![],
                seed: 0,
            },
        ),
        (
            BrushMode::Paint,
            PaintMode::Random {
                among: vec![1, 240],
                seed: 0,
            },
        ),
        (BrushMode::Attach, PaintMode::Gradient { to: 250 }),
    ] {
        let s = Stroke {
            paint: paint.clone(),
            ..stroke(mode, BrushShape::Sphere, false)
        };
        assert!(doc.begin_stroke(s.clone()).is_err(), "{mode:?} {paint:?}");
        assert!(
            doc.execute(Command::Stroke(s)).is_err(),
            "{mode:?} {paint:?}"
        );
        assert_eq!(hash(&doc), before);
        assert_eq!(doc.history.undo_len(), 0);
    }
}

fn every_voxel(dims: glam::IVec3) -> impl Iterator<Item = glam::IVec3> {
    (0..dims.x).flat_map(move |x| {
        (0..dims.y).flat_map(move |y| (0..dims.z).map(move |z| glam::IVec3::new(x, y, z)))
    })
}
