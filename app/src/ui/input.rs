//! Input → action: the editor's shortcuts (MagicaVoxel's where it has one) and the mouse
//! buttons that move the view. Pure functions of keys and modifiers, so they are tested
//! without a window.

pub use super::intent::{Action, Mods};
use glam::DVec3;
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

/// The shortcut for a key pressed with modifiers, in the default key map (the editor uses
/// the user's, see `keymap`).
pub fn action_for_key(key: KeyCode, m: Mods) -> Option<Action> {
    super::keymap::KeyMap::default().action(key, m)
}

/// How a mouse drag moves the view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drag {
    /// Rotate about the pivot.
    Orbit,
    /// Move in the view plane.
    Pan,
}

/// The drag a button starts: right orbits (Shift + right pans), middle pans.
pub fn drag_for_button(button: MouseButton, m: Mods) -> Option<Drag> {
    match button {
        MouseButton::Right if m.shift => Some(Drag::Pan),
        MouseButton::Right => Some(Drag::Orbit),
        MouseButton::Middle => Some(Drag::Pan),
        _ => None,
    }
}

/// Fly direction (right, up, forward) of a held movement key: W A S D, Q down, E up.
pub fn fly_axis(key: KeyCode) -> Option<DVec3> {
    Some(match key {
        KeyCode::KeyW => DVec3::Z,
        KeyCode::KeyS => DVec3::NEG_Z,
        KeyCode::KeyA => DVec3::NEG_X,
        KeyCode::KeyD => DVec3::X,
        KeyCode::KeyE => DVec3::Y,
        KeyCode::KeyQ => DVec3::NEG_Y,
        _ => return None,
    })
}

/// Every shortcut, for the help window: (keys, what it does).
pub const SHORTCUTS: &[(&str, &str)] = &[
    ("Left drag", "draw with the brush (one undo step per drag)"),
    ("Alt + click", "pick the material under the cursor"),
    (
        "Shift + click (paint)",
        "flood-fill the connected surface of that material",
    ),
    (
        "Shift + click (attach)",
        "fill the empty plane in front of the clicked face (within the edited object)",
    ),
    (
        "U, then drag a face",
        "extrude: the face's connected region grows (or, dragged inward, sinks) by the distance dragged",
    ),
    (
        "N",
        "the brush's next colour mode: solid, gradient, random (paint: darken, brighten)",
    ),
    (
        "Shift + M",
        "the selection tool's next mode: box, wand by colour, solid, face, rectangle, visible",
    ),
    (
        "J, then drag (H / Shift + H turn)",
        "stamp the clipboard along the drag, a stamp every stamp's width",
    ),
    ("Esc (while drawing)", "cancel the stroke"),
    (
        "M",
        "selection tool (drag a box on a face; Shift adds, Ctrl subtracts)",
    ),
    (
        "Tab",
        "arrange mode (again: the brush): click picks an object, Shift adds, Ctrl takes away, a drag from nothing picks those in its box; drag or arrows move the picked ones, Delete deletes them, F frames them",
    ),
    (
        "Alt + X / Y / Z (Shift: back), Ctrl + Alt + X / Y / Z",
        "turn a quarter about / flip along an axis: the picked objects (arrange mode) or the edited one",
    ),
    (
        "Ctrl + Shift + D / Ctrl + Shift + I, Ctrl + U",
        "duplicate / instance the picked or edited object (a copy of its model / the same model), make its model its own",
    ),
    (
        "Ctrl + G / Ctrl + Shift + G, Ctrl + J",
        "group / ungroup the picked nodes, merge the picked objects into one",
    ),
    ("Ctrl + Shift + N", "the selected voxels into a new object"),
    (
        "K",
        "measure: click two voxels for the distance along each axis and in all (Esc ends it)",
    ),
    ("Ctrl+A / Ctrl+D", "select all / nothing"),
    (
        "Delete, Ctrl+F, Ctrl+P",
        "delete / fill / paint the selection",
    ),
    (
        "Ctrl+C / Ctrl+X / Ctrl+V",
        "copy / cut / paste (click to put the paste down)",
    ),
    (
        "Arrows, Page Up / Down",
        "move the selection (Shift: by a brick)",
    ),
    ("T / X / P", "attach / erase / paint"),
    (
        "V / B / C / Y / L / R",
        "voxel / sphere / cube / cylinder / line / box brush",
    ),
    ("[ / ]", "brush smaller / larger"),
    ("Right drag", "orbit about the pivot"),
    ("Middle drag, Shift + right drag", "pan"),
    ("Wheel", "zoom to the cursor"),
    ("W A S D, Q / E", "fly (Shift: faster)"),
    ("F", "frame the scene"),
    ("O, Numpad 5", "perspective / orthographic"),
    (
        "G",
        "the ground grid on and off (its spacing: Render settings)",
    ),
    ("Ctrl + 1..9 / 1..9", "store / recall a camera slot"),
    ("Ctrl + Z", "undo"),
    ("Ctrl + Shift + Z, Ctrl + Y", "redo"),
    ("Ctrl + N", "new scene"),
    ("Ctrl + O", "open"),
    ("Ctrl + S / Ctrl + Shift + S", "save / save as"),
    ("Ctrl + I", "import .vox into the scene"),
    ("Ctrl + E", "export .vox"),
    (
        "Ctrl + Shift + E",
        "export a mesh (.glb, .gltf, .obj, .ply)",
    ),
    ("F1", "this list"),
    ("Ctrl + Q", "quit"),
];

#[cfg(test)]
mod tests {
    use super::*;

    const CTRL: Mods = Mods {
        ctrl: true,
        shift: false,
        alt: false,
    };
    const CTRL_SHIFT: Mods = Mods {
        ctrl: true,
        shift: true,
        alt: false,
    };

    #[test]
    fn shortcuts_follow_the_usual_editor_keys() {
        assert_eq!(action_for_key(KeyCode::KeyZ, CTRL), Some(Action::Undo));
        assert_eq!(
            action_for_key(KeyCode::KeyZ, CTRL_SHIFT),
            Some(Action::Redo)
        );
        assert_eq!(action_for_key(KeyCode::KeyY, CTRL), Some(Action::Redo));
        assert_eq!(action_for_key(KeyCode::KeyS, CTRL), Some(Action::Save));
        assert_eq!(
            action_for_key(KeyCode::KeyS, CTRL_SHIFT),
            Some(Action::SaveAs)
        );
        assert_eq!(action_for_key(KeyCode::KeyO, CTRL), Some(Action::Open));
        assert_eq!(
            action_for_key(KeyCode::KeyF, Mods::default()),
            Some(Action::Frame)
        );
        assert_eq!(
            action_for_key(KeyCode::Digit3, CTRL),
            Some(Action::StoreView(3))
        );
        assert_eq!(
            action_for_key(KeyCode::Digit3, Mods::default()),
            Some(Action::RecallView(3))
        );
    }

    #[test]
    fn movement_keys_are_not_shortcuts_and_plain_letters_do_not_save() {
        for key in [KeyCode::KeyW, KeyCode::KeyA, KeyCode::KeyS, KeyCode::KeyD] {
            assert_eq!(action_for_key(key, Mods::default()), None, "{key:?}");
            assert!(fly_axis(key).is_some());
        }
        assert_eq!(action_for_key(KeyCode::KeyZ, Mods::default()), None);
        assert_eq!(fly_axis(KeyCode::KeyZ), None);
        assert_eq!(fly_axis(KeyCode::KeyE), Some(DVec3::Y));
    }

    #[test]
    fn buttons_start_the_right_drags() {
        assert_eq!(
            drag_for_button(MouseButton::Right, Mods::default()),
            Some(Drag::Orbit)
        );
        let shift = Mods {
            shift: true,
            ..Mods::default()
        };
        assert_eq!(drag_for_button(MouseButton::Right, shift), Some(Drag::Pan));
        assert_eq!(
            drag_for_button(MouseButton::Middle, Mods::default()),
            Some(Drag::Pan)
        );
        assert_eq!(drag_for_button(MouseButton::Left, Mods::default()), None);
    }
}
