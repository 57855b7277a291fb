//! An object's model as a whole: its canvas (fit, crop, resize) and its scale (× 2, × ½),
//! on the objects of a MagicaVoxel scene.

use super::*;

/// The canvas of every object of a MagicaVoxel scene (many turned): fit to content, crop
/// to a box, resize with each anchor; the world keeps its voxels (a crop drops exactly what
/// lies outside), the composite stays exact, and undo gives the tree and the world back.
#[test]
fn canvas_fit_crop_and_resize_keep_the_world_and_undo_exactly() {
    use app::editor::canvas::Canvas;
    let scene = app::formats::load(&asset("ogt_test_multiple_model_scene.vox"), 2).unwrap();
    let mut doc = Document::new(scene, History::default());
    let objects = objects_in_order(&doc);
    let start = (outline(&doc), doc.scene.world.read().content_hash());
    let world = |doc: &Document| reference(&doc.scene.objects());
    let mut done = 0;
    for (k, node) in objects.iter().enumerate().take(12) {
        let (lo, hi) = {
            let o = doc.scene.objects();
            let tree = o.tree();
            let m = match tree.node(*node).unwrap().kind {
                NodeKind::Object { model, .. } => o.model(model).unwrap().size(),
                NodeKind::Group { .. } => unreachable!(),
            };
            tree.world_placement(*node).unwrap().bounds(m)
        };
        let before = (outline(&doc), world(&doc));
        let hows = [
            Canvas::Resize {
                size: hi - lo + IVec3::new(3, 2, 5),
                anchor: IVec3::new(-1, 0, 1),
            },
            Canvas::Resize {
                size: (hi - lo - 1).max(IVec3::ONE),
                anchor: IVec3::new(1, -1, 0),
            },
            Canvas::Fit,
            Canvas::Crop {
                min: lo + 1,
                max: hi - 2,
            },
        ];
        let how = hows[k % hows.len()];
        match doc.execute(Command::Object(ObjectCommand::Canvas { node: *node, how })) {
            Ok(_) => done += 1,
            // An object already tight refuses Fit, a crop inside nothing refuses.
            Err(e) => {
                assert_eq!((outline(&doc), world(&doc)), before, "{how:?}: {e}");
                continue;
            }
        }
        assert_composite(&doc, &format!("{how:?} of #{}", node.0));
        let after = world(&doc);
        // Every voxel left is where and what it was (a crop or a shrink only drops some).
        for (v, m) in &after {
            assert_eq!(before.1.get(v), Some(m), "{how:?}: a voxel appeared at {v}");
        }
        let grows = matches!(how, Canvas::Resize { anchor, .. } if anchor == IVec3::new(-1, 0, 1));
        if matches!(how, Canvas::Fit) || grows {
            assert_eq!(after.len(), before.1.len(), "{how:?} keeps every voxel");
        }
        doc.undo().unwrap();
        assert_eq!((outline(&doc), world(&doc)), before, "undo of {how:?}");
        assert_composite(&doc, "undone");
    }
    assert!(done >= 8, "only {done} of 12 canvas changes applied");
    assert_eq!(
        (outline(&doc), doc.scene.world.read().content_hash()),
        start
    );
}

/// The voxels of `node`'s model, by model coordinate.
fn model_voxels(doc: &Document, node: NodeId) -> (IVec3, HashMap<IVec3, u8>) {
    let o = doc.scene.objects();
    let NodeKind::Object { model, .. } = o.tree().node(node).unwrap().kind else {
        unreachable!()
    };
    let m = o.model(model).unwrap();
    let s = m.size();
    let mut out = HashMap::new();
    for x in 0..s.x {
        for y in 0..s.y {
            for z in 0..s.z {
                let v = IVec3::new(x, y, z);
                if let Some(k) = m.voxel(v) {
                    out.insert(v, k);
                }
            }
        }
    }
    (s, out)
}

/// × 2 makes each voxel of an object's model a 2³ block (voxel v of the new model is voxel
/// ⌊v/2⌋ of the old), the object keeps its placement, the composite stays exact; × ½ then
/// gives the model and the world back exactly, and undo the tree.
#[test]
fn an_object_scales_twice_and_back_to_itself() {
    use app::selection_scale::ScaleStep;
    let scene = app::formats::load(&asset("ogt_test_multiple_model_scene.vox"), 2).unwrap();
    let mut doc = Document::new(scene, History::default());
    let objects = objects_in_order(&doc);
    let world = |doc: &Document| reference(&doc.scene.objects());
    let mut done = 0;
    for node in objects.iter().take(10) {
        let before = (outline(&doc), world(&doc));
        let (size, old) = model_voxels(&doc, *node);
        let scale = |doc: &mut Document, step| {
            doc.execute(Command::Object(ObjectCommand::Scale { node: *node, step }))
        };
        if let Err(e) = scale(&mut doc, ScaleStep::Double) {
            // Twice the size may not fit the grid: refused, nothing changed.
            assert_eq!((outline(&doc), world(&doc)), before, "{e}");
            continue;
        }
        done += 1;
        assert_composite(&doc, &format!("× 2 of #{}", node.0));
        let (size2, new) = model_voxels(&doc, *node);
        assert_eq!(size2, size * 2);
        assert_eq!(new.len(), old.len() * 8);
        for (v, m) in &new {
            assert_eq!(old.get(&v.div_euclid(IVec3::splat(2))), Some(m), "at {v}");
        }
        scale(&mut doc, ScaleStep::Halve).unwrap();
        assert_composite(&doc, &format!("× ½ of #{}", node.0));
        assert_eq!(
            model_voxels(&doc, *node),
            (size, old.clone()),
            "× 2 then × ½"
        );
        assert_eq!(world(&doc), before.1, "the world is back");
        doc.undo().unwrap();
        doc.undo().unwrap();
        assert_eq!((outline(&doc), world(&doc)), before, "undone");
    }
    assert!(done >= 5, "only {done} of 10 objects scaled");
}
