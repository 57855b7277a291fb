//! The editor on objects, end to end: a MagicaVoxel scene of many objects opened as a
//! document; object commands (turn, move, flip, duplicate, instance, hide, lock, group,
//! ungroup, merge, make unique, delete, split) and brush strokes on the active object. After
//! every step the world is the composite of the visible objects, computed here voxel by
//! voxel from the tree and the models (forward placement, later objects win); undoing every
//! step gives back the first tree and world exactly, redoing them the last; the document
//! saved as a version 2 project opens with the same tree and voxels.

use app::editor::Document;
use app::editor::command::{Axis as BrushAxis, BrushMode, BrushShape, Command, Mirror, Stroke};
use app::editor::history::History;
use app::editor::objects::ObjectCommand;
use brickmap::objects::{Axis, LayerId, NodeId, NodeKind, ObjectTree, Objects};
use glam::{DVec3, IVec3};
use std::collections::HashMap;
use std::path::PathBuf;

mod canvas;

fn asset(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../assets/vox")
        .join(name)
}

/// Every solid world voxel the visible objects put there: each drawn object's model voxels
/// placed forward, in drawing order (a later object's voxel replaces an earlier one's).
fn reference(objects: &Objects) -> HashMap<IVec3, u8> {
    let mut out = HashMap::new();
    for d in objects.tree().drawn() {
        let m = objects.model(d.model).expect("a drawn object's model");
        for (b, brick) in m.bricks() {
            for bit in brick.mask.ones() {
                let v = b.as_ivec3() * 8
                    + IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6);
                out.insert(d.placement.place(v, m.size()), brick.material(bit));
            }
        }
    }
    out
}

fn assert_composite(doc: &Document, what: &str) {
    let want = reference(&doc.scene.objects());
    let view = doc.scene.world.read();
    assert_eq!(
        view.solid_count(),
        want.len() as u64,
        "{what}: solid voxels"
    );
    for (v, m) in &want {
        assert_eq!(view.voxel(*v).unwrap(), Some(*m), "{what}: voxel {v}");
    }
}

/// The tree as text (ids, names, kinds, flags, placements) to compare two states.
fn outline(doc: &Document) -> String {
    let objects = doc.scene.objects();
    let tree = objects.tree();
    let mut s = String::new();
    for id in tree.subtree(ObjectTree::ROOT).unwrap() {
        let n = tree.node(id).unwrap();
        s += &format!(
            "{} {} {:?} {} {} {:?}\n",
            id.0, n.name, n.kind, n.visible, n.locked, n.placement
        );
    }
    s += &format!("models {:?}\n", objects.models().keys().collect::<Vec<_>>());
    s
}

/// The tree as saved files keep it (ids are renumbered in pre-order on load): each node's
/// depth, name, flags, world placement and its model's content.
fn content_outline(doc: &Document) -> Vec<String> {
    let objects = doc.scene.objects();
    objects.outline(false, |_, m| format!("{:x}", m.content_hash()))
}

fn objects_in_order(doc: &Document) -> Vec<NodeId> {
    let objects = doc.scene.objects();
    let tree = objects.tree();
    tree.subtree(ObjectTree::ROOT)
        .unwrap()
        .into_iter()
        .filter(|id| matches!(tree.node(*id).unwrap().kind, NodeKind::Object { .. }))
        .collect()
}

fn sphere(at: DVec3, mode: BrushMode) -> Command {
    Command::Stroke(Stroke {
        mode,
        shape: BrushShape::Sphere,
        size: 5.0,
        material: 0,
        mirror: Mirror::default(),
        points: vec![at],
        axis: BrushAxis::Y,
        in_selection: false,
        paint: Default::default(),
    })
}

#[test]
fn object_commands_and_edits_keep_the_composite_and_undo_and_redo_exactly() {
    let path = asset("ogt_test_multiple_model_scene.vox");
    let scene = app::formats::load(&path, 2).unwrap();
    let mut doc = Document::new(scene, History::default());
    assert_composite(&doc, "opened");
    let (first_tree, first_hash) = (outline(&doc), doc.scene.world.read().content_hash());
    let ids = objects_in_order(&doc);
    assert!(ids.len() > 10, "a scene of many objects");
    let (a, b, c, d) = (ids[0], ids[1], ids[2], ids[3]);
    assert_eq!(
        doc.scene.active(),
        Some(a),
        "the first object is edited first"
    );
    let centre = |doc: &Document, n: NodeId| {
        let objects = doc.scene.objects();
        let node = objects.tree().node(n).unwrap();
        let NodeKind::Object { model, .. } = node.kind else {
            panic!("an object")
        };
        let size = objects.model(model).unwrap().size();
        let (lo, hi) = objects.tree().world_placement(n).unwrap().bounds(size);
        (lo + hi).as_dvec3() / 2.0
    };
    let mut steps = 0;
    let mut run = |doc: &mut Document, c: Command| {
        let what = c.label();
        doc.execute(c).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_composite(doc, &what);
        steps += 1;
    };
    run(
        &mut doc,
        Command::Object(ObjectCommand::Turn {
            nodes: vec![a],
            axis: Axis::Y,
            quarters: 1,
        }),
    );
    run(
        &mut doc,
        Command::Object(ObjectCommand::Flip {
            nodes: vec![a],
            axis: Axis::X,
        }),
    );
    run(
        &mut doc,
        Command::Object(ObjectCommand::Translate {
            nodes: vec![b],
            by: IVec3::new(3, 1, -2),
        }),
    );
    run(
        &mut doc,
        Command::Object(ObjectCommand::Instance {
            node: a,
            offset: IVec3::new(2, 0, 3),
        }),
    );
    // A brush on the turned object: its new instance shows the same change.
    let at = centre(&doc, a);
    run(&mut doc, sphere(at, BrushMode::Erase));
    run(
        &mut doc,
        Command::Object(ObjectCommand::Duplicate {
            node: c,
            offset: IVec3::new(-2, 0, 1),
        }),
    );
    run(
        &mut doc,
        Command::Object(ObjectCommand::Show {
            node: d,
            visible: false,
        }),
    );
    run(
        &mut doc,
        Command::Object(ObjectCommand::Group {
            nodes: vec![b, c],
            name: "pair".into(),
        }),
    );
    let group = doc
        .scene
        .objects()
        .tree()
        .node(b)
        .unwrap()
        .parent()
        .unwrap();
    run(
        &mut doc,
        Command::Object(ObjectCommand::Translate {
            nodes: vec![group],
            by: IVec3::new(1, 0, 1),
        }),
    );
    // Another object dragged into the group (before b): it stays where it was; the group's
    // objects on a new layer, hidden with it and shown again.
    let e = ids[4];
    let e_at = centre(&doc, e);
    run(
        &mut doc,
        Command::Object(ObjectCommand::Reparent {
            nodes: vec![e],
            parent: group,
            before: Some(b),
        }),
    );
    assert_eq!(centre(&doc, e), e_at, "a node moved into a group stays put");
    assert_eq!(
        doc.scene.objects().tree().node(group).unwrap().children(),
        &[e, b, c]
    );
    run(
        &mut doc,
        Command::Object(ObjectCommand::AddLayer("extra".into())),
    );
    let layer = LayerId(doc.scene.objects().tree().layers().len() as u8 - 1);
    run(
        &mut doc,
        Command::Object(ObjectCommand::SetLayer {
            nodes: vec![group],
            layer,
        }),
    );
    let shown = doc.scene.world.read().solid_count();
    run(
        &mut doc,
        Command::Object(ObjectCommand::ShowLayer {
            layer,
            visible: false,
        }),
    );
    assert!(
        doc.scene.world.read().solid_count() < shown,
        "the layer hides"
    );
    run(
        &mut doc,
        Command::Object(ObjectCommand::ShowLayer {
            layer,
            visible: true,
        }),
    );
    run(&mut doc, Command::Object(ObjectCommand::Ungroup(group)));
    run(
        &mut doc,
        Command::Object(ObjectCommand::Merge {
            nodes: vec![b, c],
            name: "merged".into(),
        }),
    );
    // The active object deleted: the first one left becomes active; undo brings it back.
    run(&mut doc, Command::Object(ObjectCommand::Delete(vec![a])));
    assert_ne!(doc.scene.active(), Some(a));
    let active = doc.scene.active().unwrap();
    let at = centre(&doc, active);
    run(&mut doc, sphere(at, BrushMode::Attach));
    // A locked object refuses a move, and nothing changes.
    run(
        &mut doc,
        Command::Object(ObjectCommand::Lock {
            node: active,
            locked: true,
        }),
    );
    let before = (outline(&doc), doc.scene.world.read().content_hash());
    let refused = doc.execute(Command::Object(ObjectCommand::Translate {
        nodes: vec![active],
        by: IVec3::X,
    }));
    assert!(refused.is_err());
    assert_eq!(
        (outline(&doc), doc.scene.world.read().content_hash()),
        before
    );
    let (last_tree, last_hash) = (outline(&doc), doc.scene.world.read().content_hash());
    for _ in 0..steps {
        doc.undo().unwrap();
    }
    assert_eq!(outline(&doc), first_tree);
    assert_eq!(doc.scene.world.read().content_hash(), first_hash);
    assert_eq!(doc.scene.active(), Some(a));
    assert_composite(&doc, "undone");
    for _ in 0..steps {
        doc.redo().unwrap();
    }
    assert_eq!(outline(&doc), last_tree);
    assert_eq!(doc.scene.world.read().content_hash(), last_hash);
    // Saved and opened again: the same tree and voxels.
    let dir = std::env::temp_dir().join(format!("voxbrick-objects-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scene.ron");
    doc.save(&file).unwrap();
    let back = Document::new(app::formats::load(&file, 1).unwrap(), History::default());
    assert_eq!(content_outline(&back), content_outline(&doc));
    assert_eq!(back.scene.world.read().content_hash(), last_hash);
    std::fs::remove_dir_all(&dir).ok();
}

/// The small default scene (one terrain object) and a selection of its corner column.
fn small_default() -> (Document, app::selection::SelectOp) {
    let scene = app::builtin::default_scene(app::builtin::SceneSize::Small, 2).unwrap();
    let corner = app::selection::SelectOp::Replace {
        min: IVec3::new(0, 0, 0),
        max: IVec3::new(31, 63, 31),
    };
    (Document::new(scene, History::default()), corner)
}

#[test]
fn a_selection_splits_into_a_new_object_that_edits_apart() {
    let (mut doc, corner) = small_default();
    let terrain = doc.scene.active().unwrap();
    doc.execute(Command::Select(corner)).unwrap();
    let hash = doc.scene.world.read().content_hash();
    doc.execute(Command::Object(ObjectCommand::SplitSelection))
        .unwrap();
    // The voxels moved to another object: the world shows the same.
    assert_eq!(doc.scene.world.read().content_hash(), hash);
    let ids = objects_in_order(&doc);
    assert_eq!(ids.len(), 2);
    let split = *ids.iter().find(|n| **n != terrain).unwrap();
    let solid = |doc: &Document, n: NodeId| {
        let o = doc.scene.objects();
        let NodeKind::Object { model, .. } = o.tree().node(n).unwrap().kind else {
            unreachable!()
        };
        o.model(model).unwrap().solid_count()
    };
    assert!(solid(&doc, split) > 0);
    // A brush on the split object changes its model; the terrain's is untouched.
    doc.execute(Command::Object(ObjectCommand::Activate(Some(split))))
        .unwrap();
    let (before, ground) = (solid(&doc, split), solid(&doc, terrain));
    doc.execute(sphere(DVec3::new(16.0, 40.0, 16.0), BrushMode::Attach))
        .unwrap();
    assert!(solid(&doc, split) > before);
    assert_eq!(solid(&doc, terrain), ground);
    assert_composite(&doc, "split and painted");
    // Its model is the selected voxels' box: it moves within the grid.
    let translate = |node, by: IVec3| {
        Command::Object(ObjectCommand::Translate {
            nodes: vec![node],
            by,
        })
    };
    doc.execute(translate(split, IVec3::new(40, 0, 40)))
        .unwrap();
    assert_composite(&doc, "moved");
    // Past the grid's far side and past the origin, the grid grows (by whole bricks, the
    // scene moved with the camera where it passed the origin); undo shrinks it back.
    let (grid, hash, camera) = (
        doc.scene.world.dims(),
        doc.scene.world.read().content_hash(),
        doc.scene.params.camera.position,
    );
    doc.execute(translate(split, IVec3::new(200, 0, 0)))
        .unwrap();
    assert_eq!(
        doc.scene.world.dims().voxels().x,
        272,
        "40 + 200 + 32 voxels, in bricks"
    );
    assert_composite(&doc, "past the far side");
    doc.execute(translate(split, IVec3::new(-260, 0, 0)))
        .unwrap();
    assert_eq!(
        doc.scene.shifted(),
        IVec3::new(24, 0, 0),
        "−20 rounded to whole bricks"
    );
    assert_eq!(
        doc.scene.params.camera.position,
        camera + DVec3::new(24.0, 0.0, 0.0)
    );
    assert_composite(&doc, "past the origin");
    doc.undo().unwrap();
    doc.undo().unwrap();
    assert_eq!(doc.scene.world.dims(), grid);
    assert_eq!(doc.scene.world.read().content_hash(), hash);
    assert_eq!(doc.scene.params.camera.position, camera);
    doc.redo().unwrap();
    doc.redo().unwrap();
    assert_composite(&doc, "redone");
    doc.undo().unwrap();
    doc.undo().unwrap();
    // Past the largest grid: refused, naming it; nothing changed.
    let far = doc.execute(translate(split, IVec3::new(5000, 0, 0)));
    let e = far.unwrap_err().to_string();
    assert!(e.contains("largest, 4096×1024×4096"), "{e}");
    assert_eq!(doc.scene.world.dims(), grid);
    assert_eq!(doc.scene.world.read().content_hash(), hash);
    // Hiding the terrain leaves the split voxels alone in the world.
    doc.execute(Command::Object(ObjectCommand::Show {
        node: terrain,
        visible: false,
    }))
    .unwrap();
    assert_eq!(doc.scene.world.read().solid_count(), solid(&doc, split));
    // Activating a group is refused.
    assert!(
        doc.execute(Command::Object(ObjectCommand::Activate(Some(
            ObjectTree::ROOT
        ))))
        .is_err()
    );
}

/// In a scene of several objects, the selection's reads see the active object alone: a move
/// of a box where only another object shows moves nothing; made active, that object moves.
#[test]
fn selection_moves_read_the_active_object_alone() {
    let (mut doc, corner) = small_default();
    let terrain = doc.scene.active().unwrap();
    doc.execute(Command::Select(corner.clone())).unwrap();
    doc.execute(Command::Object(ObjectCommand::SplitSelection))
        .unwrap();
    let part = *objects_in_order(&doc)
        .iter()
        .find(|n| **n != terrain)
        .unwrap();
    doc.execute(Command::Select(corner)).unwrap();
    let hash = doc.scene.world.read().content_hash();
    // The terrain is active: it holds nothing in the box, so nothing moves (the part's
    // voxels, which show there, are not copied into the terrain).
    doc.execute(Command::MoveSelection(IVec3::new(40, 0, 40)))
        .unwrap();
    assert_eq!(doc.scene.world.read().content_hash(), hash);
    assert_composite(&doc, "an empty move");
    doc.undo().unwrap();
    doc.execute(Command::Object(ObjectCommand::Activate(Some(part))))
        .unwrap();
    doc.execute(Command::MoveSelection(IVec3::new(40, 0, 40)))
        .unwrap();
    assert_ne!(doc.scene.world.read().content_hash(), hash);
    assert_composite(&doc, "the part's voxels moved within it");
}

/// Importing a `.vox` file into a scene adds its objects (a group named after the file,
/// its groups, names, hidden parts and shared models) beside what is there; the grid grows
/// to take them; undo takes them and the grid back exactly.
#[test]
fn an_imported_vox_file_joins_the_scene_as_its_objects() {
    let scene = app::builtin::default_scene(app::builtin::SceneSize::Small, 2).unwrap();
    let mut doc = Document::new(scene, History::default());
    let (hash, grid, before) = (
        doc.scene.world.read().content_hash(),
        doc.scene.world.dims(),
        objects_in_order(&doc).len(),
    );
    let park = asset("ogt_test_multiple_model_scene.vox");
    let file = app::formats::load(&park, 1).unwrap();
    doc.execute(Command::ImportVox {
        path: park.to_string_lossy().into_owned(),
        offset: IVec3::new(100, 0, 100),
    })
    .unwrap();
    assert_composite(&doc, "imported");
    let added = objects_in_order(&doc).len() - before;
    assert_eq!(
        added,
        objects_in_order(&Document::new(file, History::default())).len()
    );
    assert_ne!(
        doc.scene.world.dims(),
        grid,
        "the park does not fit beside the terrain"
    );
    {
        let o = doc.scene.objects();
        let group = *o
            .tree()
            .node(ObjectTree::ROOT)
            .unwrap()
            .children()
            .last()
            .unwrap();
        assert_eq!(
            o.tree().node(group).unwrap().name,
            "ogt_test_multiple_model_scene"
        );
    }
    doc.undo().unwrap();
    assert_eq!(doc.scene.world.read().content_hash(), hash);
    assert_eq!(doc.scene.world.dims(), grid);
    assert_eq!(objects_in_order(&doc).len(), before);
}

/// A new empty object away from the origin (its size not whole bricks), then a terrain
/// generated into it: the terrain fills the object's own box, the world shows exactly the
/// objects, and undo takes the terrain and then the object away exactly.
#[test]
fn a_new_object_takes_a_terrain_of_its_own_size_wherever_it_stands() {
    let (mut doc, _) = small_default();
    let first = doc.scene.active().unwrap();
    let hash = doc.scene.world.read().content_hash();
    let (at, size) = (IVec3::new(21, 3, 37), IVec3::new(45, 20, 30));
    doc.execute(Command::Object(ObjectCommand::NewObject {
        name: "hill".into(),
        size,
        at,
    }))
    .unwrap();
    let hill = doc.scene.active().unwrap();
    assert_ne!(hill, first, "the new object is the one brushes edit");
    assert_eq!(doc.scene.world.read().content_hash(), hash, "it is empty");
    doc.execute(Command::GenerateTerrain(
        app::editor::command::TerrainSpec {
            seed: 7,
            scale: 24.0,
            octaves: 3,
            height_range: (2, 18),
            water_level: 0,
            noise: Default::default(),
            bands: Default::default(),
        },
    ))
    .unwrap();
    assert_composite(&doc, "terrain in an object");
    let objects = doc.scene.objects();
    let NodeKind::Object { model, .. } = objects.tree().node(hill).unwrap().kind else {
        panic!("an object")
    };
    let m = objects.model(model).unwrap();
    assert_eq!(m.size(), size);
    assert!(m.solid_count() > 0, "the terrain is in the new object");
    // Its columns stand on the model's floor: the lowest layer is full.
    for (x, z) in [(0, 0), (44, 29), (20, 15)] {
        assert!(m.voxel(IVec3::new(x, 0, z)).is_some(), "column {x}, {z}");
    }
    drop(objects);
    doc.undo().unwrap();
    assert_eq!(doc.scene.world.read().content_hash(), hash);
    doc.undo().unwrap();
    assert_eq!(doc.scene.active(), Some(first));
    assert_eq!(objects_in_order(&doc), vec![first]);
}

/// File → Import of damaged files into a scene of objects: each either refused, the scene,
/// its tree and its history as they were, or imported, and its undo gives the scene back
/// exactly. The damage: the fuzzing seeds, and a multi-object file with bytes changed at
/// random (chunk sizes, ids, transforms, names).
#[test]
fn damaged_files_imported_as_objects_change_nothing_or_undo_exactly() {
    let (mut doc, _) = small_default();
    let dir = std::env::temp_dir().join(format!("voxbrick-import-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let seeds = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../app/fuzz/seeds/vox_import");
    let mut files: Vec<Vec<u8>> = std::fs::read_dir(&seeds)
        .unwrap()
        .map(|e| std::fs::read(e.unwrap().path()).unwrap())
        .collect();
    let good = std::fs::read(asset("ogt_test_multiple_model_scene.vox")).unwrap();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for _ in 0..24 {
        let mut bytes = good.clone();
        for _ in 0..1 + next() % 4 {
            let at = (next() % bytes.len() as u64) as usize;
            bytes[at] = next() as u8;
        }
        files.push(bytes);
    }
    let before = (
        outline(&doc),
        doc.scene.world.read().content_hash(),
        doc.history.undo_len(),
    );
    let (mut refused, mut imported) = (0, 0);
    for (k, bytes) in files.iter().enumerate() {
        let path = dir.join(format!("damaged-{k}.vox"));
        std::fs::write(&path, bytes).unwrap();
        let command = Command::ImportVox {
            path: path.display().to_string(),
            offset: IVec3::new(4, 0, 4),
        };
        match doc.execute(command) {
            Ok(_) => {
                imported += 1;
                assert_composite(&doc, "imported");
                doc.undo().unwrap();
            }
            Err(_) => refused += 1,
        }
        let now = (
            outline(&doc),
            doc.scene.world.read().content_hash(),
            doc.history.undo_len(),
        );
        assert!(now == before, "file {k}: the scene changed");
    }
    assert!(refused >= 6, "the seeds are refused ({refused})");
    assert!(imported > 0, "some damage is harmless ({imported})");
    std::fs::remove_dir_all(&dir).ok();
}
