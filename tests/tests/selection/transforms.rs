//! Turns, mirrors and scaling of the selection against voxel-by-voxel references.

use super::*;

/// Turns and mirrors of the selection about its centre (the region's box is 41 × 31 × 41:
/// its centre is a voxel's, so every turn is exact) against a voxel-by-voxel reference; four
/// quarter turns, a turn and its reverse, and two mirrors of a cube give back the scene and
/// the region.
#[test]
fn turns_and_mirrors_of_the_selection_match_a_voxel_by_voxel_reference() {
    let voxel = |i: usize| {
        let (i, d) = (i as i32, DIMS);
        IVec3::new(i / (d.y * d.z), i / d.z % d.y, i % d.z)
    };
    let centre = IVec3::new(40, 25, 50);
    let turn = |axis, quarters| SelectionTransform::Turn { axis, quarters };
    for t in [
        turn(Axis::Y, 1),
        turn(Axis::X, -1),
        turn(Axis::Z, 2),
        SelectionTransform::Flip(Axis::X),
    ] {
        let back: Orientation = t.orientation().inverse();
        let mut doc = document();
        let boxes = select_region(&mut doc);
        let old = snapshot(&doc);
        doc.execute(Command::TransformSelection(t)).unwrap();
        let new = snapshot(&doc);
        let mut changed = 0;
        for (i, got) in new.iter().enumerate() {
            let v = voxel(i);
            let from = centre + back.apply(v - centre);
            let want = if inside(from) && selected(from, boxes) && old[index(from)].is_some() {
                old[index(from)]
            } else if selected(v, boxes) {
                None
            } else {
                old[i]
            };
            assert_eq!(*got, want, "{t:?} at {v}");
            changed += (want != old[i]) as u64;
        }
        assert!(changed > 1000, "{t:?} changes {changed}");
        assert_eq!(
            doc.history.undo_steps().last().map(|s| s.changed_voxels),
            Some(changed)
        );
        doc.scene.world.read().validate().unwrap();
    }
    for steps in [
        vec![turn(Axis::Y, 1); 4],
        vec![turn(Axis::X, 1), turn(Axis::X, -1)],
        vec![SelectionTransform::Flip(Axis::Z); 2],
    ] {
        // A cube, whose turned self is itself (a region with a hole turns its voxels over
        // what lay outside it: those are overwritten, as a move overwrites).
        let mut doc = document();
        doc.execute(Command::Select(SelectOp::Replace {
            min: IVec3::new(20, 10, 30),
            max: IVec3::new(50, 40, 60),
        }))
        .unwrap();
        let before = state(&doc);
        for t in &steps {
            doc.execute(Command::TransformSelection(*t)).unwrap();
        }
        assert_eq!(state(&doc), before, "{steps:?}");
    }
}

/// Scaling × 2 (each voxel a 2³ block about the box's centre) and × ½ (the majority of each
/// 2³ block, at least 4 of 8 solid, the lowest material among equals) against voxel-by-voxel
/// references; × 2 then × ½ gives the selection's voxels and region back.
#[test]
fn scaling_the_selection_matches_voxel_by_voxel_references() {
    use app::selection_scale::ScaleStep;
    let (lo, hi) = (IVec3::new(40, 20, 40), IVec3::new(45, 40, 52));
    let select = |doc: &mut Document| {
        doc.execute(Command::Select(SelectOp::Replace { min: lo, max: hi }))
            .unwrap();
    };
    let in_box = |v: IVec3, a: IVec3, b: IVec3| v.cmpge(a).all() && v.cmple(b).all();
    let size = hi - lo + 1;
    // × 2.
    let mut doc = document();
    select(&mut doc);
    let old = snapshot(&doc);
    doc.execute(Command::ScaleSelection(ScaleStep::Double))
        .unwrap();
    let new = snapshot(&doc);
    let to = lo - size / 2;
    for (i, got) in new.iter().enumerate() {
        let i = i as i32;
        let w = IVec3::new(i / (DIMS.y * DIMS.z), i / DIMS.z % DIMS.y, i % DIMS.z);
        let from = lo + (w - to).div_euclid(IVec3::splat(2));
        let doubled = in_box(w, to, to + 2 * size - 1);
        let want = if doubled && old[index(from)].is_some() {
            old[index(from)]
        } else if in_box(w, lo, hi) {
            None
        } else {
            old[index(w)]
        };
        assert_eq!(*got, want, "× 2 at {w}");
    }
    // × ½ of what × 2 made: the original voxels and region.
    doc.execute(Command::ScaleSelection(ScaleStep::Halve))
        .unwrap();
    let back = snapshot(&doc);
    for x in lo.x..=hi.x {
        for y in lo.y..=hi.y {
            for z in lo.z..=hi.z {
                let v = IVec3::new(x, y, z);
                assert_eq!(back[index(v)], old[index(v)], "× 2 then × ½ at {v}");
            }
        }
    }
    let region = doc.scene.selection.as_ref().unwrap().region.clone();
    assert_eq!(region.boxes.len(), 1);
    assert_eq!((region.boxes[0].min, region.boxes[0].max), (lo, hi));
    // × ½ alone against the majority rule.
    let mut doc = document();
    select(&mut doc);
    doc.execute(Command::ScaleSelection(ScaleStep::Halve))
        .unwrap();
    let new = snapshot(&doc);
    let half = (size + 1) / 2;
    let to = lo + (size - half) / 2;
    for x in 0..half.x {
        for y in 0..half.y {
            for z in 0..half.z {
                let u = IVec3::new(x, y, z);
                let mut counts = [0u32; 256];
                let mut n = 0;
                for k in 0..8 {
                    let v = lo + 2 * u + IVec3::new(k & 1, k >> 1 & 1, k >> 2);
                    if in_box(v, lo, hi)
                        && let Some(m) = old[index(v)]
                    {
                        counts[m as usize] += 1;
                        n += 1;
                    }
                }
                let best = (0..=255u8).max_by_key(|m| (counts[*m as usize], std::cmp::Reverse(*m)));
                let want = (n >= 4).then(|| best.unwrap());
                assert_eq!(new[index(to + u)], want, "× ½ at {}", to + u);
            }
        }
    }
}
