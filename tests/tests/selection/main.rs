//! Selection: every operation (select, delete, fill, paint, move, copy, cut, paste, a tool
//! limited to the selection) against a voxel-by-voxel reference of what it should do, undo
//! and redo of each to the exact content hash and selection, moves and pastes over the grid's
//! edges, and the refusals that change nothing.

use app::builtin::{SceneSize, default_scene};
use app::editor::Document;
use app::editor::command::{BrushMode, BrushShape, Command, Mirror, Stroke};
use app::editor::history::History;
use app::selection::SelectOp;
use app::selection_transform::SelectionTransform;
use brickmap::objects::{Axis, Orientation};
use glam::{DVec3, IVec3};

mod sets;
mod transforms;

fn document() -> Document {
    Document::new(
        default_scene(SceneSize::Small, 2).unwrap(),
        History::default(),
    )
}

/// Every voxel of the grid (x slowest, then y, then z).
fn snapshot(doc: &Document) -> Vec<Option<u8>> {
    let view = doc.scene.world.read();
    let d = view.dims().voxels();
    let mut out = Vec::with_capacity((d.x * d.y * d.z) as usize);
    for x in 0..d.x {
        for y in 0..d.y {
            for z in 0..d.z {
                out.push(view.voxel(IVec3::new(x, y, z)).unwrap());
            }
        }
    }
    out
}

/// Content hash, tables and the selection (its boxes and voxel count).
fn state(doc: &Document) -> (u64, String) {
    let view = doc.scene.world.read();
    let selection = doc
        .scene
        .selection
        .as_ref()
        .map(|s| (s.region.clone(), s.voxels.count()));
    (
        view.content_hash(),
        format!("{:?} {selection:?}", view.materials().logical_bytes()),
    )
}

/// A box minus a smaller box, over the terrain's surface (128 × 64 × 128).
fn select_region(doc: &mut Document) -> (IVec3, IVec3, IVec3, IVec3) {
    let (a, b) = (IVec3::new(20, 10, 30), IVec3::new(60, 40, 70));
    let (c, d) = (IVec3::new(30, 0, 40), IVec3::new(40, 63, 50));
    doc.execute(Command::Select(SelectOp::Replace { min: b, max: a }))
        .unwrap();
    doc.execute(Command::Select(SelectOp::Subtract { min: c, max: d }))
        .unwrap();
    (a, b, c, d)
}

fn selected(v: IVec3, (a, b, c, d): (IVec3, IVec3, IVec3, IVec3)) -> bool {
    let inside = |lo: IVec3, hi: IVec3| v.cmpge(lo).all() && v.cmple(hi).all();
    inside(a, b) && !inside(c, d)
}

fn sphere(mode: BrushMode, centre: DVec3, radius: f64, in_selection: bool) -> Command {
    Command::Stroke(Stroke {
        mode,
        shape: BrushShape::Sphere,
        size: radius,
        material: 2,
        mirror: Mirror::default(),
        points: vec![centre],
        axis: Default::default(),
        in_selection,
        paint: Default::default(),
    })
}

/// The small default scene's grid.
const DIMS: IVec3 = IVec3::new(128, 64, 128);

fn index(v: IVec3) -> usize {
    (v.x * DIMS.y * DIMS.z + v.y * DIMS.z + v.z) as usize
}

fn inside(v: IVec3) -> bool {
    v.cmpge(IVec3::ZERO).all() && v.cmplt(DIMS).all()
}

/// What each operation must do to every voxel, given the voxel before (`old` by index) and
/// whether it is selected.
#[test]
fn operations_match_a_voxel_by_voxel_reference() {
    let voxel = |i: usize| {
        let (i, d) = (i as i32, DIMS);
        IVec3::new(i / (d.y * d.z), i / d.z % d.y, i % d.z)
    };
    type Rule = Box<dyn Fn(&[Option<u8>], bool, IVec3) -> Option<u8>>;
    let moved = |offset: IVec3, boxes| -> Rule {
        Box::new(move |old: &[Option<u8>], sel: bool, v: IVec3| {
            // Voxels arriving from the selection win; the rest of the selection empties.
            let from = v - offset;
            if inside(from) && selected(from, boxes) && old[index(from)].is_some() {
                return old[index(from)];
            }
            if sel { None } else { old[index(v)] }
        })
    };
    let centre = DVec3::new(50.0, 36.0, 60.0);
    let sphere_has = move |v: IVec3| (v.as_dvec3() + 0.5 - centre).length_squared() <= 14.0 * 14.0;
    let mut probe = document();
    let boxes = select_region(&mut probe);
    // The material most of the selected voxels have (replaced by 3 below).
    let mut counts = [0u64; 256];
    for (i, m) in snapshot(&probe).iter().enumerate() {
        if let Some(m) = m
            && selected(voxel(i), boxes)
        {
            counts[*m as usize] += 1;
        }
    }
    let common = (0..=255u8).max_by_key(|m| counts[*m as usize]).unwrap();
    assert_ne!(common, 3);
    let cases: Vec<(Command, Rule)> = vec![
        (
            Command::ReplaceMaterial {
                from: common,
                to: 3,
            },
            Box::new(move |old, sel, v| match old[index(v)] {
                Some(m) if sel && m == common => Some(3),
                other => other,
            }),
        ),
        (
            Command::DeleteSelection,
            Box::new(|old, sel, v| if sel { None } else { old[index(v)] }),
        ),
        (
            Command::FillSelection(3),
            Box::new(|old, sel, v| if sel { Some(3) } else { old[index(v)] }),
        ),
        (
            Command::PaintSelection(3),
            Box::new(|old, sel, v| old[index(v)].map(|m| if sel { 3 } else { m })),
        ),
        (
            Command::MoveSelection(IVec3::new(7, -3, 11)),
            moved(IVec3::new(7, -3, 11), boxes),
        ),
        // Past the grid's low x edge and its top: what leaves the grid is gone.
        (
            Command::MoveSelection(IVec3::new(-45, 30, 0)),
            moved(IVec3::new(-45, 30, 0), boxes),
        ),
        (
            sphere(BrushMode::Attach, centre, 14.0, true),
            Box::new(move |old, sel, v| {
                if sel && sphere_has(v) {
                    Some(2)
                } else {
                    old[index(v)]
                }
            }),
        ),
        (
            sphere(BrushMode::Erase, centre, 14.0, true),
            Box::new(move |old, sel, v| {
                if sel && sphere_has(v) {
                    None
                } else {
                    old[index(v)]
                }
            }),
        ),
    ];
    for (command, rule) in cases {
        let mut doc = document();
        select_region(&mut doc);
        let old = snapshot(&doc);
        doc.execute(command.clone())
            .unwrap_or_else(|e| panic!("{command:?}: {e}"));
        let new = snapshot(&doc);
        let mut changed = 0;
        for (i, got) in new.iter().enumerate() {
            let v = voxel(i);
            let want = rule(&old, selected(v, boxes), v);
            assert_eq!(*got, want, "{command:?} at {v}");
            changed += (want != old[i]) as u64;
        }
        assert!(
            changed > 1000,
            "{command:?} changes enough to mean something"
        );
        assert_eq!(
            doc.history.undo_steps().last().map(|s| s.changed_voxels),
            Some(changed),
            "{command:?} counts what it changed"
        );
        doc.scene.world.read().validate().unwrap();
    }
}

/// Without a selection, a replacement covers the whole object; a material no voxel has, or
/// a material replaced by itself, is refused and changes nothing; undo is exact.
#[test]
fn a_material_is_replaced_across_the_object_and_refusals_change_nothing() {
    let mut doc = document();
    let old = snapshot(&doc);
    let used = old.iter().flatten().copied().max().unwrap();
    let before = state(&doc);
    doc.execute(Command::ReplaceMaterial { from: used, to: 3 })
        .unwrap();
    let new = snapshot(&doc);
    for (o, n) in old.iter().zip(&new) {
        assert_eq!(*n, o.map(|m| if m == used { 3 } else { m }));
    }
    doc.undo().unwrap();
    assert_eq!(state(&doc), before);
    let count = doc.scene.world.materials().len() as u8;
    let unused = (0..count)
        .find(|m| !old.contains(&Some(*m)))
        .expect("the scene leaves a material of its table unused");
    for (from, to) in [(unused, 3), (3, 3)] {
        let steps = doc.history.undo_len();
        assert!(doc.execute(Command::ReplaceMaterial { from, to }).is_err());
        assert_eq!(
            (state(&doc), doc.history.undo_len()),
            (before.clone(), steps)
        );
    }
}

#[test]
fn paste_puts_the_copy_down_over_what_is_there_and_selects_it() {
    let dims = DIMS;
    let mut doc = document();
    let boxes = select_region(&mut doc);
    let old = snapshot(&doc);
    doc.execute(Command::Copy).unwrap();
    let origin = doc.scene.clipboard.as_ref().unwrap().origin;
    assert_eq!(
        origin, boxes.0,
        "the copy's origin is the selection's minimum corner"
    );
    // At the far corner: most of it lands outside the grid.
    for at in [IVec3::new(70, 20, 5), IVec3::new(100, 50, 110)] {
        let before = state(&doc);
        doc.execute(Command::Paste { at }).unwrap();
        let new = snapshot(&doc);
        let mut i = 0;
        for x in 0..dims.x {
            for y in 0..dims.y {
                for z in 0..dims.z {
                    let v = IVec3::new(x, y, z);
                    let from = v - at + origin;
                    let want =
                        if inside(from) && selected(from, boxes) && old[index(from)].is_some() {
                            old[index(from)]
                        } else {
                            old[i]
                        };
                    assert_eq!(new[i], want, "paste at {at}: {v}");
                    i += 1;
                }
            }
        }
        let sel = doc.scene.selection.as_ref().expect("the paste is selected");
        assert!(sel.voxels.contains(at) && !sel.voxels.contains(at - 1));
        assert_eq!(sel.voxels.bounds().unwrap().0, at);
        doc.undo().unwrap();
        assert_eq!(state(&doc), before, "undo of the paste at {at}");
    }
}

#[test]
fn every_selection_operation_undoes_and_redoes_exactly() {
    let commands = [
        Command::Select(SelectOp::Replace {
            min: IVec3::new(1, 2, 3),
            max: IVec3::new(9, 9, 9),
        }),
        Command::Select(SelectOp::Add {
            min: IVec3::new(100, 0, 100),
            max: IVec3::new(127, 63, 127),
        }),
        Command::Select(SelectOp::Subtract {
            min: IVec3::new(25, 0, 35),
            max: IVec3::new(30, 63, 40),
        }),
        Command::Select(SelectOp::All),
        Command::Select(SelectOp::None),
        Command::DeleteSelection,
        Command::FillSelection(1),
        Command::PaintSelection(1),
        Command::MoveSelection(IVec3::new(3, 1, -2)),
        Command::MoveSelection(IVec3::new(0, 0, 90)),
        Command::Cut,
        Command::Paste {
            at: IVec3::new(90, 30, 90),
        },
        sphere(BrushMode::Paint, DVec3::new(40.0, 30.0, 50.0), 20.0, true),
        Command::TransformSelection(SelectionTransform::Turn {
            axis: Axis::Y,
            quarters: 1,
        }),
        Command::TransformSelection(SelectionTransform::Flip(Axis::Z)),
    ];
    for command in commands {
        let mut doc = document();
        select_region(&mut doc);
        doc.execute(Command::Copy).unwrap();
        let steps = doc.history.undo_len();
        let before = state(&doc);
        doc.execute(command.clone())
            .unwrap_or_else(|e| panic!("{command:?}: {e}"));
        assert_eq!(doc.history.undo_len(), steps + 1, "{command:?} is one step");
        let after = state(&doc);
        assert_ne!(before, after, "{command:?} changed nothing");
        doc.undo().unwrap();
        assert_eq!(state(&doc), before, "undo of {command:?}");
        doc.redo().unwrap();
        assert_eq!(state(&doc), after, "redo of {command:?}");
        doc.undo().unwrap();
        assert_eq!(state(&doc), before, "second undo of {command:?}");
        doc.scene.world.read().validate().unwrap();
    }
}

#[test]
fn without_a_selection_or_a_copy_the_operations_are_refused_and_change_nothing() {
    let mut doc = document();
    let before = state(&doc);
    for command in [
        Command::DeleteSelection,
        Command::FillSelection(1),
        Command::PaintSelection(1),
        Command::MoveSelection(IVec3::X),
        Command::Copy,
        Command::Cut,
        Command::Paste { at: IVec3::ZERO },
    ] {
        let err = doc.execute(command.clone()).unwrap_err();
        assert!(
            err.to_string().contains("selected") || err.to_string().contains("clipboard"),
            "{command:?}: {err}"
        );
        assert_eq!(state(&doc), before, "{command:?}");
        assert_eq!(doc.history.undo_len(), 0, "{command:?}");
    }
    // A selection entirely outside the grid selects nothing.
    doc.execute(Command::Select(SelectOp::Replace {
        min: IVec3::splat(500),
        max: IVec3::splat(600),
    }))
    .unwrap();
    assert!(doc.scene.selection.is_none());
    // A bad material is refused with the selection in place.
    select_region(&mut doc);
    let before = state(&doc);
    let steps = doc.history.undo_len();
    assert!(doc.execute(Command::FillSelection(250)).is_err());
    assert_eq!((state(&doc), doc.history.undo_len()), (before, steps));
    // A copy is no step and leaves the document clean.
    doc.dirty = false;
    doc.execute(Command::Copy).unwrap();
    assert_eq!(doc.history.undo_len(), steps);
    assert!(!doc.dirty);
    // A tool limited to the selection with nothing selected works everywhere.
    doc.execute(Command::Select(SelectOp::None)).unwrap();
    let before = snapshot(&doc);
    doc.execute(sphere(
        BrushMode::Erase,
        DVec3::new(10.0, 20.0, 10.0),
        6.0,
        true,
    ))
    .unwrap();
    assert_ne!(snapshot(&doc), before);
}

#[test]
fn a_cylinder_follows_its_axis() {
    for (axis, long) in [
        (app::editor::command::Axis::X, 0),
        (app::editor::command::Axis::Y, 1),
        (app::editor::command::Axis::Z, 2),
    ] {
        let mut doc = Document::new(
            app::Scene::empty(brickmap::GridDims::new(8, 8, 8).unwrap(), 1).unwrap(),
            History::default(),
        );
        doc.execute(Command::Stroke(Stroke {
            mode: BrushMode::Attach,
            shape: BrushShape::Cylinder,
            size: 4.0,
            material: 0,
            mirror: Mirror::default(),
            points: vec![DVec3::splat(32.0)],
            axis,
            in_selection: false,
            paint: Default::default(),
        }))
        .unwrap();
        let view = doc.scene.world.read();
        let mut ext = [0i32; 3];
        for a in 0..3 {
            let mut p = IVec3::splat(32);
            while view.voxel(p).unwrap().is_some() {
                p[a] += 1;
            }
            ext[a] = p[a] - 32;
        }
        // Radius 4 across (centres within 4), half-length 4 along (caps at ±4 from 32).
        assert_eq!(ext, [4, 4, 4], "{axis:?}");
        // Which axis: 3 voxels out on two axes, the centre is 3.5 · √2 ≈ 4.95 from the
        // middle across (outside the radius) but 3.5 from the axis when one of the two is
        // the axis (inside).
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let mut v = IVec3::splat(32);
            (v[p], v[q]) = (35, 35);
            let along = p == long || q == long;
            assert_eq!(view.voxel(v).unwrap().is_some(), along, "{axis:?} at {v}");
        }
        let count = view.solid_count();
        drop(view);
        assert!(count > 300, "{axis:?}");
    }
}

#[test]
fn the_preview_of_a_brush_limited_to_the_selection_is_what_it_changes() {
    for mode in [BrushMode::Attach, BrushMode::Erase, BrushMode::Paint] {
        let mut doc = document();
        select_region(&mut doc);
        let command = sphere(mode, DVec3::new(35.0, 36.0, 45.0), 12.0, true);
        let Command::Stroke(stroke) = &command else {
            unreachable!()
        };
        let preview = {
            let view = doc.scene.world.read();
            app::editor::command::preview(&view, stroke, doc.scene.selection.as_ref())
                .unwrap()
                .unwrap()
        };
        let before = snapshot(&doc);
        doc.execute(command.clone()).unwrap();
        let after = snapshot(&doc);
        let changed: Vec<IVec3> = (0..before.len())
            .filter(|&i| before[i] != after[i])
            .map(|i| {
                let (i, d) = (i as i32, DIMS);
                IVec3::new(i / (d.y * d.z), i / d.z % d.y, i % d.z)
            })
            .collect();
        assert!(!changed.is_empty(), "{mode:?}");
        assert_eq!(preview, changed, "{mode:?}");
    }
}
