//! Selections, pastes and materials: a paste's preview, a dielectric's bounces, the selection operations, the magic wand, extrude and plane fill.

use super::session::Session;
use app::ui::Input;
use glam::IVec3;
use std::time::{Duration, Instant};
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

/// A paste being placed shows the voxels it will put down, not only a box.
pub fn a_paste_being_placed_shows_its_voxels(s: &mut Session) {
    s.ctrl(KeyCode::KeyA);
    s.ctrl(KeyCode::KeyC);
    s.quiet();
    assert_eq!(s.ed.paste_preview_faces(), 0, "nothing is being pasted yet");
    s.ctrl(KeyCode::KeyV);
    let terrain = s.on_the_terrain();
    s.to(terrain);
    s.quiet();
    let faces = s.ed.paste_preview_faces();
    assert!(faces > 1000, "the whole terrain's copy shows {faces} faces");
    s.key(KeyCode::Escape, true);
    s.key(KeyCode::Escape, false);
    s.quiet();
    assert_eq!(s.ed.paste_preview_faces(), 0, "Esc put the paste away");
}

/// A glass or water swatch looks like glass (the swatch test in `ui/swatch.rs`),
/// and with a dielectric picked while the scene has too few bounces for light to pass
/// through it, the panel says so and its button sets enough (one undo step).
pub fn a_dielectric_asks_for_the_bounces_it_needs(s: &mut Session) {
    s.quiet();
    let water = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        let table = d.scene.world.materials();
        (0..table.len() as u8)
            .find(|&i| table.get(i).unwrap().kind == brickmap::MaterialKind::Dielectric)
            .expect("the terrain has water")
    };
    let before = s.bounces();
    assert!(before < 5, "the scene starts with {before} bounces");
    let hint = "use 5 bounces";
    s.click_on(&format!("material {water}: dielectric"), MouseButton::Left);
    assert_eq!(s.ed.brush().material, water, "the swatch picked the water");
    let steps = s.state().1;
    s.click_on(hint, MouseButton::Left);
    assert_eq!(s.bounces(), 5);
    // the change showed at once (its first batch of samples); while the pointer
    // goes on moving over the panels refinement waits (frames are the UI's), and left
    // alone it resumes (the target is 8 samples).
    let first = s.ed.samples();
    assert!(
        (1..8).contains(&first),
        "the change's first batch: {first} samples"
    );
    let (gx, gy, gw, _) = s.ed.palette_grid().expect("the palette is docked");
    // (The frame budget may still change the traced size, which restarts the image with
    // one batch: samples may drop, never grow.)
    let mut last = first;
    for k in 0..6 {
        s.to((gx + gw * (0.2 + 0.1 * f64::from(k)), gy + 4.0));
        // Time for the last frame to leave the GPU, so this one is drawn.
        std::thread::sleep(Duration::from_millis(40));
        s.frame();
        let now = s.ed.samples();
        assert!(
            now <= last,
            "refining while the UI is used: {last} → {now} samples"
        );
        last = now;
    }
    let first = last;
    std::thread::sleep(Duration::from_millis(400));
    let left = Instant::now();
    while s.ed.samples() <= first {
        assert!(
            left.elapsed() < Duration::from_secs(60),
            "refinement never resumed"
        );
        // (A frame while the last is still on the GPU is not drawn: give it time.)
        std::thread::sleep(Duration::from_millis(5));
        s.frame();
    }
    assert_eq!(s.state().1, steps + 1, "one step in the history");
    assert!(
        s.ed.widget(hint).is_none(),
        "the hint goes once it is answered"
    );
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.bounces(), before);
    assert!(s.ed.widget(hint).is_some(), "and comes back with the undo");
}

/// Each selection operation says on the status line what it did; "make a
/// new one for the selection" paints the selected voxels with a copy of the material (two
/// steps); a right-click on a palette colour picks it for editing without changing the
/// brush.
pub fn selection_operations_land_and_a_selection_gets_a_material_of_its_own(s: &mut Session) {
    s.ctrl(KeyCode::KeyA);
    s.quiet();
    let (solid, selected) = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        let selection = d.scene.selection.as_ref().expect("a selection");
        (d.scene.world.read().solid_count(), selection.voxels.count())
    };
    assert_eq!(selected, 48 * 24 * 48, "all of the grid");
    assert_eq!(
        s.ed.notice(),
        Some(format!("Select all: {selected} voxels selected").as_str())
    );
    s.ctrl(KeyCode::KeyC);
    s.quiet();
    assert_eq!(
        s.ed.notice(),
        Some(format!("Copied {solid} voxels to the clipboard").as_str())
    );
    let (len, steps) = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        (d.scene.world.materials().len(), d.history.undo_len())
    };
    s.click_on("make a new one for the selection", MouseButton::Left);
    let doc = s.ed.document();
    {
        let d = doc.read().unwrap();
        let table = d.scene.world.materials();
        assert_eq!(table.len(), len + 1, "a new material");
        assert_eq!(d.history.undo_len(), steps + 2, "added, then painted");
        assert_eq!(usize::from(s.ed.brush().material), len);
        let view = d.scene.world.read();
        let top = (0..24)
            .rev()
            .find_map(|y| view.voxel(IVec3::new(24, y, 24)).ok().flatten())
            .expect("a solid column");
        assert_eq!(
            usize::from(top),
            len,
            "the selected voxels have the new material"
        );
    }
    assert!(
        s.ed.notice()
            .is_some_and(|n| n.starts_with("Paint selection")),
        "{:?}",
        s.ed.notice()
    );
    for _ in 0..2 {
        s.ctrl(KeyCode::KeyZ);
        s.quiet();
    }
    assert_eq!(doc.read().unwrap().scene.world.materials().len(), len);
    // A right-click on a colour picks it for editing; the brush keeps its material.
    let material = s.ed.brush().material;
    let (gx, gy, gw, gh) = s.ed.palette_grid().expect("the palette is docked");
    let (row, col) = (3.0, 7.0);
    s.to((gx + (col + 0.5) * gw / 16.0, gy + (row + 0.5) * gh / 16.0));
    s.frame();
    for pressed in [true, false] {
        s.ed.input(Input::Button {
            button: MouseButton::Right,
            pressed,
        });
    }
    s.quiet();
    assert!(
        s.ed.widget("colour 55").is_some(),
        "colour 55 is up for editing"
    );
    assert_eq!(s.ed.brush().material, material);
    s.ctrl(KeyCode::KeyD);
    s.quiet();
    assert_eq!(s.ed.notice(), Some("Select none: nothing selected"));
}

/// The selection tool's magic wand: a click on the terrain selects the connected voxels of
/// its material (one step, named in the History); Shift + Ctrl + click intersects; back to
/// boxes.
pub fn the_magic_wand_selects_with_a_click(s: &mut Session) {
    let count = |s: &Session| {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        d.scene.selection.as_ref().map_or(0, |s| s.voxels.count())
    };
    s.quiet();
    s.key(KeyCode::KeyM, true);
    s.key(KeyCode::KeyM, false);
    s.quiet();
    s.click_on("wand: colour", MouseButton::Left);
    let at = s.on_the_terrain();
    s.to(at);
    s.frame();
    s.left(true);
    s.left(false);
    s.quiet();
    let picked = count(s);
    assert!(picked > 0, "the wand selected nothing");
    let label = s.last_command().map(|(l, _)| l);
    assert!(label.is_some_and(|l| l.starts_with("Magic wand at")));
    // The same click intersected with itself keeps it all.
    s.ed.input(Input::Modifiers(app::ui::input::Mods {
        ctrl: true,
        shift: true,
        alt: false,
    }));
    s.left(true);
    s.left(false);
    s.ed.input(Input::Modifiers(Default::default()));
    s.quiet();
    assert_eq!(count(s), picked);
    s.ctrl(KeyCode::KeyD);
    s.quiet();
    assert_eq!(count(s), 0);
    s.click_on("box", MouseButton::Left);
    assert_eq!(s.ed.brush().select_mode, app::ui::tools::SelectMode::Box);
    s.key(KeyCode::KeyT, true);
    s.key(KeyCode::KeyT, false);
    s.quiet();
}

/// The Extrude tool: U, a press on the terrain's top and a drag up grows its face region by
/// the distance dragged (one step, undone exactly); Shift + click in attach mode fills the
/// plane in front of the face.
pub fn extrude_drags_a_face_and_shift_click_fills_a_plane(s: &mut Session) {
    s.quiet();
    let before = s.state();
    s.key(KeyCode::KeyU, true);
    s.key(KeyCode::KeyU, false);
    s.quiet();
    let at = s.on_the_terrain();
    s.to(at);
    s.frame();
    s.left(true);
    for k in 1..=6 {
        s.to((at.0, at.1 - 12.0 * f64::from(k)));
        s.frame();
    }
    assert_eq!(s.state(), before, "nothing changes before the release");
    s.left(false);
    s.quiet();
    let label = |s: &Session| s.last_command().map(|(l, _)| l);
    assert_eq!(s.state().1, before.1 + 1, "one step");
    assert_ne!(s.state().0, before.0);
    assert!(label(s).is_some_and(|l| l.starts_with("Extrude the face at")));
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state().0, before.0);
    // Attach mode: Shift + click fills the plane in front of the clicked face.
    s.key(KeyCode::KeyT, true);
    s.key(KeyCode::KeyT, false);
    s.to(at);
    s.frame();
    s.ed.input(Input::Modifiers(app::ui::input::Mods {
        shift: true,
        ..Default::default()
    }));
    s.left(true);
    s.left(false);
    s.ed.input(Input::Modifiers(Default::default()));
    s.quiet();
    assert!(label(s).is_some_and(|l| l.starts_with("Fill the plane at")));
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state().0, before.0);
}
