//! Set-based selections (the magic wand, the face wand, by material, a screen rectangle,
//! invert, grow, shrink, box intersections) against voxel-by-voxel references.

use super::*;

/// The selected voxels, as a set.
fn selected_set(doc: &Document) -> std::collections::HashSet<IVec3> {
    doc.scene
        .selection
        .as_ref()
        .map(|s| s.voxels.voxels().collect())
        .unwrap_or_default()
}

/// The small default scene, its voxels and the top voxel of its column at (40, 50).
fn terrain_top() -> (Document, Vec<Option<u8>>, IVec3) {
    let doc = document();
    let old = snapshot(&doc);
    let top = (0..DIMS.y)
        .rev()
        .map(|y| IVec3::new(40, y, 50))
        .find(|v| old[index(*v)].is_some())
        .unwrap();
    (doc, old, top)
}

/// The magic wand (by material and solid, through faces and corners), select by material,
/// invert, grow and shrink, each combined as the modifiers say, against voxel-by-voxel
/// references on the terrain; each is one undoable step.
#[test]
fn set_selections_match_voxel_by_voxel_references() {
    use app::wand::Combine;
    use std::collections::HashSet;
    let (mut doc, old, top) = terrain_top();
    let at = |v: IVec3| inside(v).then(|| old[index(v)]).flatten();
    let reference = |by_material: bool, diagonal: bool| {
        let m = at(top).unwrap();
        let mut seen = HashSet::from([top]);
        let mut stack = vec![top];
        while let Some(v) = stack.pop() {
            for d in 0..27 {
                let d = IVec3::new(d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1);
                if d == IVec3::ZERO || (!diagonal && d.abs().element_sum() != 1) {
                    continue;
                }
                let n = v + d;
                if at(n).is_some_and(|k| !by_material || k == m) && seen.insert(n) {
                    stack.push(n);
                }
            }
        }
        seen
    };
    let the_box = (IVec3::new(30, 0, 40), IVec3::new(50, 63, 60));
    let boxed: HashSet<IVec3> = (the_box.0.x..=the_box.1.x)
        .flat_map(|x| (0..DIMS.y).flat_map(move |y| (40..=60).map(move |z| IVec3::new(x, y, z))))
        .collect();
    for (by_material, diagonal) in [(true, false), (true, true), (false, false)] {
        let want = reference(by_material, diagonal);
        assert!(want.len() > 10, "{} voxels", want.len());
        for how in [
            Combine::Replace,
            Combine::Add,
            Combine::Subtract,
            Combine::Intersect,
        ] {
            doc.execute(Command::Select(SelectOp::Replace {
                min: the_box.0,
                max: the_box.1,
            }))
            .unwrap();
            let before = state(&doc);
            doc.execute(Command::Select(SelectOp::Wand {
                start: top,
                by_material,
                diagonal,
                how,
            }))
            .unwrap();
            let expected: HashSet<IVec3> = match how {
                Combine::Replace => want.clone(),
                Combine::Add => want.union(&boxed).copied().collect(),
                Combine::Subtract => boxed.difference(&want).copied().collect(),
                Combine::Intersect => boxed.intersection(&want).copied().collect(),
            };
            assert_eq!(
                selected_set(&doc),
                expected,
                "{by_material} {diagonal} {how:?}"
            );
            doc.undo().unwrap();
            assert_eq!(state(&doc), before);
        }
    }
    // By material: every voxel of the top's material.
    let m = at(top).unwrap();
    doc.execute(Command::Select(SelectOp::Material {
        material: m,
        how: Combine::Replace,
    }))
    .unwrap();
    let all: HashSet<IVec3> = (0..old.len())
        .filter(|i| old[*i] == Some(m))
        .map(|i| {
            let i = i as i32;
            IVec3::new(i / (DIMS.y * DIMS.z), i / DIMS.z % DIMS.y, i % DIMS.z)
        })
        .collect();
    assert_eq!(selected_set(&doc), all);
    // Grow, shrink, invert of a box inside the grid.
    let (lo, hi) = (IVec3::new(10, 5, 12), IVec3::new(20, 15, 30));
    let boxed: HashSet<IVec3> = (lo.x..=hi.x)
        .flat_map(|x| {
            (lo.y..=hi.y).flat_map(move |y| (lo.z..=hi.z).map(move |z| IVec3::new(x, y, z)))
        })
        .collect();
    doc.execute(Command::Select(SelectOp::Replace { min: lo, max: hi }))
        .unwrap();
    let faces = brickmap::FACES;
    doc.execute(Command::Select(SelectOp::Grow)).unwrap();
    let grown: HashSet<IVec3> = boxed
        .iter()
        .flat_map(|v| faces.iter().map(move |f| *v + *f).chain([*v]))
        .filter(|v| inside(*v))
        .collect();
    assert_eq!(selected_set(&doc), grown);
    doc.execute(Command::Select(SelectOp::Shrink)).unwrap();
    doc.execute(Command::Select(SelectOp::Shrink)).unwrap();
    let shrunk: HashSet<IVec3> = boxed
        .iter()
        .filter(|v| faces.iter().all(|f| boxed.contains(&(**v + *f))))
        .copied()
        .collect();
    assert_eq!(selected_set(&doc), shrunk, "grown then shrunk twice");
    doc.execute(Command::Select(SelectOp::Invert)).unwrap();
    let n = (DIMS.x * DIMS.y * DIMS.z) as usize;
    let selection = selected_set(&doc);
    assert_eq!(selection.len(), n - shrunk.len());
    assert!(shrunk.iter().all(|v| !selection.contains(v)));
}

/// The face wand: from the top face of a terrain column, the voxels of that layer whose top
/// is exposed, joined through edges (or corners too), of the clicked material or any;
/// against a flood written here. Shift + Ctrl on a box drag keeps what both hold.
#[test]
fn the_face_wand_and_box_intersections_match_references() {
    use app::wand::Combine;
    use std::collections::HashSet;
    let (mut doc, old, top) = terrain_top();
    let at = |v: IVec3| inside(v).then(|| old[index(v)]).flatten();
    let m = at(top).unwrap();
    for (by_material, diagonal) in [(false, false), (true, false), (false, true)] {
        let takes = |v: IVec3| {
            v.y == top.y
                && at(v).is_some_and(|k| !by_material || k == m)
                && at(v + IVec3::Y).is_none()
        };
        let mut want = HashSet::from([top]);
        let mut stack = vec![top];
        while let Some(v) = stack.pop() {
            for dx in -1..=1 {
                for dz in -1..=1 {
                    let d = IVec3::new(dx, 0, dz);
                    if d == IVec3::ZERO || (!diagonal && dx != 0 && dz != 0) {
                        continue;
                    }
                    if takes(v + d) && want.insert(v + d) {
                        stack.push(v + d);
                    }
                }
            }
        }
        assert!(want.len() > 3, "{} voxels", want.len());
        let before = state(&doc);
        doc.execute(Command::Select(SelectOp::Face {
            start: top,
            normal: IVec3::Y,
            by_material,
            diagonal,
            how: Combine::Replace,
        }))
        .unwrap();
        assert_eq!(selected_set(&doc), want, "{by_material} {diagonal}");
        doc.undo().unwrap();
        assert_eq!(state(&doc), before);
    }
    // A face that is not exposed (inside the ground) selects nothing: with Replace it
    // empties the selection, one step whose undo brings the selection back.
    doc.execute(Command::Select(SelectOp::Replace {
        min: IVec3::new(1, 1, 1),
        max: IVec3::new(4, 4, 4),
    }))
    .unwrap();
    let boxed = selected_set(&doc);
    assert!(!boxed.is_empty());
    let steps = doc.history.undo_len();
    doc.execute(Command::Select(SelectOp::Face {
        start: top - IVec3::Y * 3,
        normal: IVec3::Y,
        by_material: false,
        diagonal: false,
        how: Combine::Replace,
    }))
    .unwrap();
    assert!(selected_set(&doc).is_empty());
    assert_eq!(doc.history.undo_len(), steps + 1);
    doc.undo().unwrap();
    assert_eq!(selected_set(&doc), boxed);
    // Box ∩ box.
    let (a0, a1) = (IVec3::new(10, 5, 10), IVec3::new(30, 20, 30));
    let (b0, b1) = (IVec3::new(25, 0, 0), IVec3::new(60, 10, 12));
    doc.execute(Command::Select(SelectOp::Replace { min: a0, max: a1 }))
        .unwrap();
    doc.execute(Command::Select(SelectOp::Intersect { min: b1, max: b0 }))
        .unwrap();
    let want: HashSet<IVec3> = (25..=30)
        .flat_map(|x| (5..=10).flat_map(move |y| (10..=12).map(move |z| IVec3::new(x, y, z))))
        .collect();
    assert_eq!(selected_set(&doc), want);
}

/// A screen rectangle through all depth takes exactly the solid voxels whose centres project
/// inside it (brick-level culling against a per-voxel projection); the visible-only mode
/// takes the first voxel of each pixel's ray (every viewport pixel tested here), all of them
/// on the surface and fewer than through all depth.
#[test]
fn a_screen_rectangle_selects_through_all_depth_or_what_shows() {
    use app::rect_select::ScreenRect;
    use app::wand::Combine;
    use std::collections::HashSet;
    let mut doc = document();
    let old = snapshot(&doc);
    let camera = doc.scene.params.camera.clone();
    let (aspect, pixels) = (16.0 / 9.0, (160u32, 90u32));
    let rect = |visible_only| ScreenRect {
        camera: camera.clone(),
        aspect,
        pixels,
        a: (0.3, -0.4),
        b: (-0.25, 0.105),
        visible_only,
    };
    let solid: Vec<IVec3> = (0..old.len())
        .filter(|i| old[*i].is_some())
        .map(|i| {
            let i = i as i32;
            IVec3::new(i / (DIMS.y * DIMS.z), i / DIMS.z % DIMS.y, i % DIMS.z)
        })
        .collect();
    let shows = |v: IVec3| {
        camera
            .project(v.as_dvec3() + 0.5, aspect)
            .is_some_and(|(u, w)| (-0.25..=0.3).contains(&u) && (-0.4..=0.105).contains(&w))
    };
    let all: HashSet<IVec3> = solid.iter().copied().filter(|v| shows(*v)).collect();
    assert!(all.len() > 1000, "{} voxels", all.len());
    // The projection is the camera's: the ray through a voxel's (u, v) passes its centre.
    let v = *all.iter().next().unwrap();
    let (u, w) = camera.project(v.as_dvec3() + 0.5, aspect).unwrap();
    let (o, d) = camera.ray(u, w, aspect);
    let c = v.as_dvec3() + 0.5;
    assert!((c - o - d * (c - o).dot(d)).length() < 1e-6);
    doc.execute(Command::Select(SelectOp::Rect {
        rect: Box::new(rect(false)),
        how: Combine::Replace,
    }))
    .unwrap();
    assert_eq!(selected_set(&doc), all);
    // Visible only: every pixel centre inside, its ray's first voxel.
    let view = doc.scene.world.read();
    let mut seen = HashSet::new();
    for y in 0..pixels.1 {
        for x in 0..pixels.0 {
            let u = (f64::from(x) + 0.5) / f64::from(pixels.0) * 2.0 - 1.0;
            let w = (f64::from(y) + 0.5) / f64::from(pixels.1) * 2.0 - 1.0;
            if !((-0.25..=0.3).contains(&u) && (-0.4..=0.105).contains(&w)) {
                continue;
            }
            let (origin, dir) = camera.ray(u, w, aspect);
            if let Some((hit, _)) = view
                .ray_cast(&brickmap::Ray { origin, dir }, f64::INFINITY)
                .unwrap()
            {
                seen.insert(hit.voxel);
            }
        }
    }
    drop(view);
    doc.execute(Command::Select(SelectOp::Rect {
        rect: Box::new(rect(true)),
        how: Combine::Replace,
    }))
    .unwrap();
    let visible = selected_set(&doc);
    let extra: Vec<_> = visible.difference(&seen).take(5).collect();
    let missing: Vec<_> = seen.difference(&visible).take(5).collect();
    assert!(
        extra.is_empty() && missing.is_empty(),
        "{} selected, {} seen; extra {extra:?}, missing {missing:?}",
        visible.len(),
        seen.len()
    );
    assert!(!visible.is_empty() && visible.len() < all.len() / 4);
    let at = |v: IVec3| inside(v).then(|| old[index(v)]).flatten();
    for v in &visible {
        assert!(at(*v).is_some());
        assert!(
            brickmap::FACES.iter().any(|f| at(*v + *f).is_none()),
            "{v} is buried"
        );
    }
    // Ctrl takes the visible ones away from the all-depth set.
    doc.execute(Command::Select(SelectOp::Rect {
        rect: Box::new(rect(false)),
        how: Combine::Replace,
    }))
    .unwrap();
    doc.execute(Command::Select(SelectOp::Rect {
        rect: Box::new(rect(true)),
        how: Combine::Subtract,
    }))
    .unwrap();
    let rest: HashSet<IVec3> = all.difference(&visible).copied().collect();
    assert_eq!(selected_set(&doc), rest);
}
