//! The modelling tools driven as a user does: the Stamp tool along a drag, the brush's
//! colour modes chosen in the Tools panel.

use super::session::Session;
use app::editor::command::{Command, PaintMode};
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

fn last_command(s: &Session) -> Option<(String, Command)> {
    let doc = s.ed.document();
    let d = doc.read().unwrap();
    d.history
        .undo_steps()
        .last()
        .map(|st| (st.label.clone(), st.command.clone()))
}

fn tap(s: &mut Session, code: KeyCode) {
    s.key(code, true);
    s.key(code, false);
    s.quiet();
}

/// Copy a small box of the terrain, J, H (a quarter turn), a drag across the terrain: one
/// step with a stamp every stamp's width, nothing before the release, undone exactly.
pub fn the_stamp_puts_the_clipboard_down_along_a_drag(s: &mut Session) {
    s.quiet();
    let before = s.state();
    tap(s, KeyCode::KeyM);
    let at = s.on_the_terrain();
    s.to(at);
    s.frame();
    s.left(true);
    s.to((at.0 + 6.0, at.1 + 4.0));
    s.frame();
    s.left(false);
    s.quiet();
    s.ctrl(KeyCode::KeyC);
    s.quiet();
    let clip = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        d.scene.clipboard.as_ref().map(|c| c.size)
    };
    let size = clip.expect("the box was copied");
    tap(s, KeyCode::KeyJ);
    assert_eq!(s.ed.brush().tool, app::ui::tools::Tool::Stamp);
    tap(s, KeyCode::KeyH);
    assert_eq!(s.ed.brush().stamp_quarters, 1);
    s.to(at);
    s.quiet();
    assert!(
        s.ed.paste_preview_faces() > 0,
        "the stamp shows under the cursor"
    );
    s.left(true);
    for k in 1..=10 {
        s.to((at.0 + 12.0 * f64::from(k), at.1 + 2.0 * f64::from(k)));
        s.frame();
    }
    assert_eq!(s.state().0, before.0, "nothing changes before the release");
    s.left(false);
    s.quiet();
    let (label, command) = last_command(s).expect("a step");
    let Command::Stamp {
        at: places,
        quarters,
    } = command
    else {
        panic!("{label}: not a stamp");
    };
    assert_eq!(quarters, 1);
    assert!(places.len() >= 2, "{label} (a clip of {size})");
    let turned = app::editor::stamp::turned_size(size, 1);
    for w in places.windows(2) {
        assert!(
            (w[1] - w[0]).abs().cmpge(turned).any(),
            "{places:?} overlap"
        );
    }
    assert_ne!(s.state().0, before.0);
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state().0, before.0, "undone");
    s.chord(false, true, false, KeyCode::KeyH);
    assert_eq!(s.ed.brush().stamp_quarters, 0, "Shift + H turns back");
    s.ctrl(KeyCode::KeyD);
    tap(s, KeyCode::KeyT);
}

/// P, then "random" and a second material in the Tools panel: a stroke paints the terrain in
/// both (its command says so); "darken" then repaints with the darker neighbours.
pub fn the_colour_modes_are_chosen_in_the_tools_panel(s: &mut Session) {
    s.quiet();
    let before = s.state();
    tap(s, KeyCode::KeyP);
    s.click_on("random", MouseButton::Left);
    let material = s.ed.brush().material;
    let other = if material == 1 { 2 } else { 1 };
    let name = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        let m = d.scene.world.materials().get(other).unwrap();
        format!(
            "random among {other}: {}",
            app::ui::swatch::kind_name(m.kind)
        )
    };
    s.click_on(&name, MouseButton::Left);
    match &s.ed.brush().paint {
        PaintMode::Random { among, .. } => assert_eq!(among.len(), 2, "{among:?}"),
        other => panic!("{other:?}"),
    }
    let at = s.on_the_terrain();
    s.to(at);
    s.frame();
    s.left(true);
    s.to((at.0 + 20.0, at.1));
    s.frame();
    s.left(false);
    s.quiet();
    let (label, command) = last_command(s).expect("a step");
    let Command::Stroke(stroke) = command else {
        panic!("{label}: not a stroke");
    };
    assert!(
        matches!(&stroke.paint, PaintMode::Random { among, .. } if among.len() == 2),
        "{:?}",
        stroke.paint
    );
    assert_ne!(s.state().0, before.0);
    s.click_on("darken", MouseButton::Left);
    assert_eq!(s.ed.brush().paint, PaintMode::Darken);
    s.click_on("solid", MouseButton::Left);
    assert_eq!(s.ed.brush().paint, PaintMode::Solid);
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state().0, before.0, "undone");
    tap(s, KeyCode::KeyT);
}
