//! Objects and keys: arrange mode, the Object menu's keys, the Blender-like key map.

use super::session::Session;
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

/// Arrange mode: Tab, then a click picks the object under the cursor and an arrow moves it
/// (the scene's one grid-sized object: past the grid's side, so the grid grows and the
/// viewport takes the new world, validated); Ctrl + Z puts it back and the grid with it; a
/// drag from it moves it by one step at the release; a click on the sky un-picks it, a box
/// dragged from the sky over it picks it again, and the turn keys turn it; Tab again is the
/// brush.
pub fn arrange_mode_picks_and_moves_an_object(s: &mut Session) {
    s.quiet();
    let grid = |s: &Session| s.ed.document().read().unwrap().scene.world.dims();
    let (before, dims) = (s.state(), grid(s));
    let at = s.arrange_and_pick_the_terrain();
    assert_eq!(s.state(), before, "a pick changes nothing");
    s.key(KeyCode::ArrowRight, true);
    s.key(KeyCode::ArrowRight, false);
    s.quiet();
    let moved = s.state();
    assert_eq!(moved.1, before.1 + 1, "one step");
    assert_ne!(grid(s), dims, "the object left the grid: it grew");
    for _ in 0..3 {
        s.frame();
    }
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state().0, before.0);
    assert_eq!(grid(s), dims);
    // A drag that starts on the picked object moves it once, at the release.
    s.to(at);
    s.frame();
    s.left(true);
    for k in 1..=8 {
        s.to((at.0 + 8.0 * f64::from(k), at.1 + 3.0 * f64::from(k)));
        s.frame();
    }
    assert_eq!(s.state(), before, "nothing moves before the release");
    s.left(false);
    s.quiet();
    assert_eq!(s.state().1, before.1 + 1, "the drag is one step");
    assert_ne!(s.state().0, before.0);
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state(), before);
    // A click on nothing clears the picked objects: the turn key then turns nothing.
    let sky = s.on_the_sky();
    s.to(sky);
    s.frame();
    s.left(true);
    s.left(false);
    s.quiet();
    let alt = |s: &mut Session, shift: bool| {
        s.chord(false, shift, true, KeyCode::KeyY);
        s.quiet();
    };
    alt(s, false);
    assert_eq!(s.state(), before, "nothing picked, nothing turned");
    // A box dragged from the sky over the object picks it; Alt + Y turns it a quarter,
    // Alt + Shift + Y turns it back (two steps), undo and undo again are where it began.
    s.to(sky);
    s.frame();
    s.left(true);
    for k in 1..=6 {
        let f = f64::from(k) / 6.0;
        s.to((sky.0 + (at.0 - sky.0) * f, sky.1 + (at.1 - sky.1) * f));
        s.frame();
    }
    s.left(false);
    s.quiet();
    alt(s, false);
    let turned = s.state();
    assert_eq!(
        turned.1,
        before.1 + 1,
        "the box picked the object: one turn"
    );
    assert_ne!(turned.0, before.0);
    alt(s, true);
    assert_eq!(s.state(), (before.0, before.1 + 2), "turned back");
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state().0, turned.0);
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state(), before);
    // View → Objects → New object: an empty object (32³: taller than this grid, which grows
    // for it), the one brushes edit; undo removes it and the grid shrinks back.
    let nodes = |s: &Session| s.ed.document().read().unwrap().scene.objects().tree().len();
    let solid = |s: &Session| {
        s.ed.document()
            .read()
            .unwrap()
            .scene
            .world
            .read()
            .solid_count()
    };
    let solid_before = solid(s);
    let (count, active) = (nodes(s), s.ed.document().read().unwrap().scene.active());
    s.click_on("View", MouseButton::Left);
    s.click_on("Objects", MouseButton::Left);
    s.click_on("New object", MouseButton::Left);
    assert_eq!(nodes(s), count + 1, "a new object");
    assert_ne!(s.ed.document().read().unwrap().scene.active(), active);
    assert_eq!(solid(s), solid_before, "it is empty");
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!((nodes(s), s.state()), (count, before));
    s.click_on("View", MouseButton::Left);
    s.click_on("Objects", MouseButton::Left);
    s.key(KeyCode::Tab, true);
    s.key(KeyCode::Tab, false);
    s.quiet();
}

/// The Object menu's keys on the object picked in arrange mode: Ctrl + Shift + D duplicates
/// it (a new model), Ctrl + Shift + I instances it (the same model), Ctrl + U gives it its own
/// copy back, Ctrl + G groups it; what they cannot act on is said on the status line (ungroup
/// of an object, merge of one, split without a selection); undo takes each back. The menu's
/// entry does what its key does, and its dimming toggle is the view setting.
pub fn the_object_keys_and_menu_act_on_the_picked_object(s: &mut Session) {
    s.quiet();
    let counts = |s: &Session| {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        let objects = d.scene.objects();
        (objects.tree().len(), objects.models().len())
    };
    let press = |s: &mut Session, shift: bool, code: KeyCode| {
        s.chord(true, shift, false, code);
        s.quiet();
    };
    let (before, (nodes, models)) = (s.state(), counts(s));
    s.arrange_and_pick_the_terrain();
    for (shift, code, (more_nodes, more_models), what) in [
        (true, KeyCode::KeyD, (1, 1), "a duplicate: its own model"),
        (true, KeyCode::KeyI, (2, 1), "an instance: the same model"),
        (
            false,
            KeyCode::KeyU,
            (2, 2),
            "made unique: a model of its own",
        ),
        (false, KeyCode::KeyG, (3, 2), "a group"),
    ] {
        press(s, shift, code);
        assert_eq!(
            counts(s),
            (nodes + more_nodes, models + more_models),
            "{what}"
        );
    }
    assert_eq!(s.state().1, before.1 + 4, "four steps");
    for (shift, code, says) in [
        (true, KeyCode::KeyG, "pick a group first"),
        (false, KeyCode::KeyJ, "pick two objects or more"),
        (true, KeyCode::KeyN, "select voxels first"),
    ] {
        press(s, shift, code);
        assert!(
            s.ed.notice().is_some_and(|n| n.starts_with(says)),
            "{:?}",
            s.ed.notice()
        );
    }
    assert_eq!(s.state().1, before.1 + 4, "refusals are no steps");
    s.click_on("Object", MouseButton::Left);
    s.click_on("Duplicate  Ctrl+Shift+D", MouseButton::Left);
    s.quiet();
    assert_eq!(counts(s), (nodes + 4, models + 3), "the menu's duplicate");
    assert!(!s.ed.settings().dim_others);
    s.click_on("Object", MouseButton::Left);
    s.click_on("Dim the objects not edited", MouseButton::Left);
    assert!(s.ed.settings().dim_others, "the menu's toggle");
    s.click_on("Object", MouseButton::Left);
    s.click_on("Dim the objects not edited", MouseButton::Left);
    assert!(!s.ed.settings().dim_others);
    // Fit canvas to content: the edited object's model shrinks to its voxels.
    let size = |s: &Session| s.ed.document().read().unwrap().scene.active_size();
    let was = size(s);
    s.click_on("Object", MouseButton::Left);
    s.click_on("Fit canvas to content", MouseButton::Left);
    s.quiet();
    assert_ne!(size(s), was, "fitted to its voxels");
    for _ in 0..6 {
        s.ctrl(KeyCode::KeyZ);
        s.quiet();
    }
    assert_eq!((s.state(), counts(s)), (before, (nodes, models)));
    s.key(KeyCode::Tab, true);
    s.key(KeyCode::Tab, false);
    s.quiet();
    // Back in edit mode with a selection, Alt + Y turns the selection, not the object.
    s.ctrl(KeyCode::KeyA);
    s.quiet();
    let selected = s.state();
    s.chord(false, false, true, KeyCode::KeyY);
    s.quiet();
    let last = |s: &Session| {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        d.history.undo_steps().last().map(|st| st.label.clone())
    };
    assert_eq!(s.state().1, selected.1 + 1);
    assert_eq!(last(s).as_deref(), Some("Turn selection 90° about Y"));
    s.ctrl(KeyCode::KeyZ);
    s.ctrl(KeyCode::KeyD);
    s.quiet();
    assert_eq!(s.state().0, before.0);
}

/// The Shortcuts window (F1) switches to the Blender-like key map: A selects all, Alt + A
/// nothing; and back.
pub fn the_blender_key_map_is_chosen_in_the_shortcuts_window(s: &mut Session) {
    use app::ui::keymap::KeyPreset;
    let selected = |s: &Session| s.ed.document().read().unwrap().scene.selection.is_some();
    s.quiet();
    s.key(KeyCode::F1, true);
    s.key(KeyCode::F1, false);
    s.quiet();
    s.click_on("Blender-like", MouseButton::Left);
    assert_eq!(s.ed.settings().key_preset, KeyPreset::Blender);
    s.key(KeyCode::KeyA, true);
    s.key(KeyCode::KeyA, false);
    s.quiet();
    assert!(selected(s), "A selects all");
    s.chord(false, false, true, KeyCode::KeyA);
    s.quiet();
    assert!(!selected(s), "Alt + A selects nothing");
    s.click_on("MagicaVoxel", MouseButton::Left);
    assert_eq!(s.ed.settings().key_preset, KeyPreset::MagicaVoxel);
    s.key(KeyCode::F1, true);
    s.key(KeyCode::F1, false);
    s.quiet();
}
