//! The key map: which key chord does which [`Action`]. The defaults follow MagicaVoxel where
//! it has a shortcut; `keys.ron` in the config folder (written with the defaults on the
//! first start, so there is a file to edit) replaces them. A chord is written as in menus:
//! `"Ctrl+Shift+Z"`, `"F"`, `"["`, `"Numpad5"`, `"F1"`; actions the file leaves out keep
//! their default chords where the file does not use them. A file that does not parse, or
//! names a key that does not exist, is an error naming the binding; the defaults are used
//! and the file is left as it is. Flying (W A S D, Q / E, held) is not an action and not
//! remapped; a preset that binds one of those keys takes it.
//!
//! Two presets: MagicaVoxel's (the default) and a Blender-like one (`KeyPreset`, chosen in
//! the Shortcuts window). keys.ron's bindings win over either; with the Blender-like preset
//! the file's lines that are MagicaVoxel defaults (as the first start wrote them) give way.

pub use super::intent::KeyPreset;
use super::intent::{Action, Mods, Nudge};
use crate::editor::command::{BrushMode, BrushShape};
use brickmap::objects::Axis;
use serde::{Deserialize, Serialize};
use winit::keyboard::KeyCode;

/// One line of keys.ron.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Binding {
    /// The chord, e.g. "Ctrl+Shift+Z".
    pub keys: String,
    /// What it does.
    pub action: Action,
}

/// A key with the modifiers that must be held (exactly).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Chord {
    key: KeyCode,
    mods: Mods,
}

/// The bindings in force.
#[derive(Clone, Debug)]
pub struct KeyMap {
    chords: Vec<(Chord, Action)>,
    bindings: Vec<Binding>,
}

impl Default for KeyMap {
    fn default() -> Self {
        Self::from_bindings(&default_bindings()).expect("the default bindings parse")
    }
}

/// Why a key map cannot be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum KeyMapError {
    /// keys.ron is not a list of bindings.
    #[error("{0}")]
    Syntax(String),
    /// A chord without a key ("Ctrl+").
    #[error("\"{0}\": no key")]
    NoKey(String),
    /// A modifier that is not Ctrl, Shift or Alt.
    #[error("\"{chord}\": \"{modifier}\" is not Ctrl, Shift or Alt")]
    Modifier {
        /// The chord as written.
        chord: String,
        /// The word that is not a modifier.
        modifier: String,
    },
    /// A key name that names no key.
    #[error("\"{chord}\": no key is called \"{key}\"")]
    UnknownKey {
        /// The chord as written.
        chord: String,
        /// The name.
        key: String,
    },
}

impl KeyPreset {
    /// Both, for a chooser.
    pub const ALL: [KeyPreset; 2] = [KeyPreset::MagicaVoxel, KeyPreset::Blender];

    /// Its name in the Shortcuts window.
    pub fn name(self) -> &'static str {
        match self {
            KeyPreset::MagicaVoxel => "MagicaVoxel",
            KeyPreset::Blender => "Blender-like",
        }
    }

    /// Its bindings.
    pub fn bindings(self) -> Vec<Binding> {
        match self {
            KeyPreset::MagicaVoxel => default_bindings(),
            KeyPreset::Blender => blender_bindings(),
        }
    }
}

/// Blender's chords for the actions it has, then MagicaVoxel's defaults whose chord and action
/// those leave free.
fn blender_bindings() -> Vec<Binding> {
    let own = [
        ("A", Action::SelectAll),
        ("Alt+A", Action::SelectNone),
        ("X", Action::DeleteSelection),
        ("Delete", Action::DeleteSelection),
        ("Shift+D", Action::DuplicateObject),
        ("Alt+D", Action::InstanceObject),
        ("P", Action::SplitSelection),
        ("B", Action::SelectTool),
        ("Shift+B", Action::Shape(BrushShape::Sphere)),
        ("Shift+X", Action::Mode(BrushMode::Erase)),
        ("Home", Action::Frame),
        ("NumpadDecimal", Action::Frame),
    ];
    let mut out: Vec<Binding> = own
        .iter()
        .map(|(k, a)| Binding {
            keys: k.to_string(),
            action: *a,
        })
        .collect();
    for d in default_bindings() {
        let chord = parse_chord(&d.keys).expect("the defaults parse");
        let taken = own
            .iter()
            .any(|(k, a)| *a == d.action || parse_chord(k).is_ok_and(|c| c == chord));
        if !taken {
            out.push(d);
        }
    }
    out
}

impl KeyMap {
    /// A preset's map.
    pub fn of(preset: KeyPreset) -> Self {
        Self::from_bindings(&preset.bindings()).expect("the presets parse")
    }

    /// The map of these bindings; an error names the first bad chord.
    pub fn from_bindings(bindings: &[Binding]) -> Result<Self, KeyMapError> {
        let chords = bindings
            .iter()
            .map(|b| parse_chord(&b.keys).map(|c| (c, b.action)))
            .collect::<Result<_, _>>()?;
        Ok(Self {
            chords,
            bindings: bindings.to_vec(),
        })
    }

    /// The action of a key pressed with modifiers (the first binding that matches).
    pub fn action(&self, key: KeyCode, mods: Mods) -> Option<Action> {
        self.chords
            .iter()
            .find(|(c, _)| c.key == key && c.mods == mods)
            .map(|(_, a)| *a)
    }

    /// The bindings, as written (for the help window).
    pub fn bindings(&self) -> &[Binding] {
        &self.bindings
    }

    /// keys.ron's text for these bindings: a header, then one binding per line.
    pub fn to_ron(bindings: &[Binding]) -> String {
        let mut text = String::from(
            "// voxbrick key map: each line binds a chord (\"Ctrl+Shift+Z\", \"F\", \"[\",\n\
             // \"Numpad5\", \"F1\") to an action. Edit and restart the editor; delete the\n\
             // file to get the defaults back.\n[\n",
        );
        for b in bindings {
            let line = ron::to_string(b).expect("a binding serializes");
            text += &format!("    {line},\n");
        }
        text + "]\n"
    }

    /// Parses keys.ron's text. An action the file does not bind keeps its default chord when
    /// the file does not use that chord for something else (a file written by an older
    /// version still gets the shortcuts added since).
    pub fn parse(text: &str, preset: KeyPreset) -> Result<Self, KeyMapError> {
        let mut bindings: Vec<Binding> =
            ron::from_str(text).map_err(|e| KeyMapError::Syntax(e.to_string()))?;
        if preset != KeyPreset::MagicaVoxel {
            // The defaults the first start wrote are not the user's choice.
            let defaults = default_bindings();
            bindings.retain(|b| !defaults.contains(b));
        }
        let user = Self::from_bindings(&bindings)?;
        for d in preset.bindings() {
            let chord = parse_chord(&d.keys)?;
            let taken = user.chords.iter().any(|(c, _)| *c == chord);
            if !taken && !bindings.iter().any(|b| b.action == d.action) {
                bindings.push(d);
            }
        }
        Self::from_bindings(&bindings)
    }
}

/// The default bindings.
pub fn default_bindings() -> Vec<Binding> {
    let mut b: Vec<(String, Action)> = [
        ("Ctrl+Z", Action::Undo),
        ("Ctrl+Shift+Z", Action::Redo),
        ("Ctrl+Y", Action::Redo),
        ("Ctrl+N", Action::New),
        ("Ctrl+O", Action::Open),
        ("Ctrl+S", Action::Save),
        ("Ctrl+Shift+S", Action::SaveAs),
        ("Ctrl+I", Action::Import),
        ("Ctrl+E", Action::Export),
        ("Ctrl+Shift+E", Action::ExportMesh),
        ("Ctrl+Q", Action::Quit),
        ("F", Action::Frame),
        ("O", Action::ToggleProjection),
        ("Numpad5", Action::ToggleProjection),
        ("[", Action::BrushSmaller),
        ("]", Action::BrushLarger),
        ("T", Action::Mode(BrushMode::Attach)),
        ("X", Action::Mode(BrushMode::Erase)),
        ("P", Action::Mode(BrushMode::Paint)),
        ("V", Action::Shape(BrushShape::Voxel)),
        ("B", Action::Shape(BrushShape::Sphere)),
        ("C", Action::Shape(BrushShape::Cube)),
        ("Y", Action::Shape(BrushShape::Cylinder)),
        ("L", Action::Shape(BrushShape::Line)),
        ("R", Action::Shape(BrushShape::Box)),
        ("M", Action::SelectTool),
        ("Tab", Action::ArrangeTool),
        ("K", Action::MeasureTool),
        ("U", Action::ExtrudeTool),
        ("J", Action::StampTool),
        ("H", Action::StampTurn),
        ("Shift+H", Action::StampTurnBack),
        ("N", Action::NextColourMode),
        ("Shift+M", Action::NextSelectMode),
        ("G", Action::ToggleGrid),
        ("Ctrl+A", Action::SelectAll),
        ("Ctrl+D", Action::SelectNone),
        ("Delete", Action::DeleteSelection),
        ("Ctrl+F", Action::FillSelection),
        ("Ctrl+P", Action::PaintSelection),
        ("Ctrl+C", Action::Copy),
        ("Ctrl+X", Action::Cut),
        ("Ctrl+V", Action::Paste),
        ("Ctrl+Shift+D", Action::DuplicateObject),
        ("Ctrl+Shift+I", Action::InstanceObject),
        ("Ctrl+U", Action::MakeUnique),
        ("Ctrl+G", Action::GroupObjects),
        ("Ctrl+Shift+G", Action::Ungroup),
        ("Ctrl+J", Action::MergeObjects),
        ("Ctrl+Shift+N", Action::SplitSelection),
        ("F1", Action::Help),
    ]
    .into_iter()
    .map(|(k, a)| (k.to_string(), a))
    .collect();
    for (key, n) in [
        ("ArrowLeft", Nudge::Left),
        ("ArrowRight", Nudge::Right),
        ("ArrowUp", Nudge::Away),
        ("ArrowDown", Nudge::Towards),
        ("PageUp", Nudge::Up),
        ("PageDown", Nudge::Down),
    ] {
        b.push((key.to_string(), Action::Nudge(n)));
        b.push((format!("Shift+{key}"), Action::Nudge(n)));
    }
    for (key, axis) in [("X", Axis::X), ("Y", Axis::Y), ("Z", Axis::Z)] {
        b.push((format!("Alt+{key}"), Action::Turn(axis)));
        b.push((format!("Alt+Shift+{key}"), Action::TurnBack(axis)));
        b.push((format!("Ctrl+Alt+{key}"), Action::Flip(axis)));
    }
    for n in 1..=9u8 {
        b.push((format!("Ctrl+{n}"), Action::StoreView(n)));
        b.push((format!("{n}"), Action::RecallView(n)));
    }
    b.into_iter()
        .map(|(keys, action)| Binding { keys, action })
        .collect()
}

fn parse_chord(s: &str) -> Result<Chord, KeyMapError> {
    let mut mods = Mods::default();
    let parts: Vec<&str> = s.split('+').map(str::trim).collect();
    // "Ctrl++" would be Ctrl and "+"; no default uses it, and "+" alone is allowed.
    let (key, held) = match parts.split_last() {
        Some((k, held)) if !k.is_empty() => (*k, held),
        _ => return Err(KeyMapError::NoKey(s.to_string())),
    };
    for m in held {
        match m.to_ascii_lowercase().as_str() {
            "ctrl" | "control" | "cmd" => mods.ctrl = true,
            "shift" => mods.shift = true,
            "alt" => mods.alt = true,
            other => {
                return Err(KeyMapError::Modifier {
                    chord: s.to_string(),
                    modifier: other.to_string(),
                });
            }
        }
    }
    let key = key_code(key).ok_or_else(|| KeyMapError::UnknownKey {
        chord: s.to_string(),
        key: key.to_string(),
    })?;
    Ok(Chord { key, mods })
}

/// A key by the name a user writes: a letter, a digit, F1..F12, a few symbols, or winit's
/// own names for the rest ("Numpad5", "ArrowUp", "Delete").
fn key_code(name: &str) -> Option<KeyCode> {
    use KeyCode::*;
    let letters = [
        KeyA, KeyB, KeyC, KeyD, KeyE, KeyF, KeyG, KeyH, KeyI, KeyJ, KeyK, KeyL, KeyM, KeyN, KeyO,
        KeyP, KeyQ, KeyR, KeyS, KeyT, KeyU, KeyV, KeyW, KeyX, KeyY, KeyZ,
    ];
    let digits = [
        Digit0, Digit1, Digit2, Digit3, Digit4, Digit5, Digit6, Digit7, Digit8, Digit9,
    ];
    let mut chars = name.chars();
    if let (Some(c), None) = (chars.next(), chars.next()) {
        return match c {
            'a'..='z' | 'A'..='Z' => Some(letters[(c.to_ascii_uppercase() as u8 - b'A') as usize]),
            '0'..='9' => Some(digits[(c as u8 - b'0') as usize]),
            '[' => Some(BracketLeft),
            ']' => Some(BracketRight),
            '-' => Some(Minus),
            '=' => Some(Equal),
            ',' => Some(Comma),
            '.' => Some(Period),
            '/' => Some(Slash),
            ';' => Some(Semicolon),
            _ => None,
        };
    }
    let named = [
        F1,
        F2,
        F3,
        F4,
        F5,
        F6,
        F7,
        F8,
        F9,
        F10,
        F11,
        F12,
        Numpad0,
        Numpad1,
        Numpad2,
        Numpad3,
        Numpad4,
        Numpad5,
        Numpad6,
        Numpad7,
        Numpad8,
        Numpad9,
        NumpadAdd,
        NumpadSubtract,
        NumpadDecimal,
        Escape,
        Space,
        Tab,
        Enter,
        Backspace,
        Delete,
        Insert,
        Home,
        End,
        PageUp,
        PageDown,
        ArrowUp,
        ArrowDown,
        ArrowLeft,
        ArrowRight,
    ];
    let lower = name.to_ascii_lowercase();
    let alias = match lower.as_str() {
        "esc" => Some(Escape),
        "del" => Some(Delete),
        "up" => Some(ArrowUp),
        "down" => Some(ArrowDown),
        "left" => Some(ArrowLeft),
        "right" => Some(ArrowRight),
        _ => None,
    };
    alias.or_else(|| {
        named
            .into_iter()
            .find(|k| format!("{k:?}").eq_ignore_ascii_case(name))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const CTRL: Mods = Mods {
        ctrl: true,
        shift: false,
        alt: false,
    };

    #[test]
    fn the_blender_preset_binds_its_own_keys_and_the_written_defaults_give_way() {
        let map = KeyMap::of(KeyPreset::Blender);
        let none = Mods::default();
        let alt = Mods { alt: true, ..none };
        let shift = Mods {
            shift: true,
            ..none
        };
        assert_eq!(map.action(KeyCode::KeyA, none), Some(Action::SelectAll));
        assert_eq!(map.action(KeyCode::KeyA, alt), Some(Action::SelectNone));
        assert_eq!(
            map.action(KeyCode::KeyD, shift),
            Some(Action::DuplicateObject)
        );
        assert_eq!(
            map.action(KeyCode::KeyX, none),
            Some(Action::DeleteSelection)
        );
        assert_eq!(
            map.action(KeyCode::KeyX, shift),
            Some(Action::Mode(BrushMode::Erase))
        );
        assert_eq!(
            map.action(KeyCode::NumpadDecimal, none),
            Some(Action::Frame)
        );
        // MagicaVoxel's chords it does not take stay; those of actions it moved are free.
        assert_eq!(map.action(KeyCode::KeyZ, CTRL), Some(Action::Undo));
        assert_eq!(map.action(KeyCode::KeyM, none), None);
        assert_eq!(map.action(KeyCode::KeyF, none), None);
        // No chord is bound twice.
        let chords: Vec<_> = map.chords.iter().map(|(c, _)| *c).collect();
        for (i, c) in chords.iter().enumerate() {
            assert!(!chords[i + 1..].contains(c), "{c:?} twice");
        }
        // keys.ron as the first start wrote it (the MagicaVoxel defaults) and one line the
        // user changed: the preset's keys, and the user's.
        let mut written = default_bindings();
        written.push(Binding {
            keys: "Ctrl+K".into(),
            action: Action::Copy,
        });
        let text = KeyMap::to_ron(&written);
        let map = KeyMap::parse(&text, KeyPreset::Blender).unwrap();
        assert_eq!(map.action(KeyCode::KeyA, none), Some(Action::SelectAll));
        assert_eq!(map.action(KeyCode::KeyK, CTRL), Some(Action::Copy));
        let map = KeyMap::parse(&text, KeyPreset::MagicaVoxel).unwrap();
        assert_eq!(map.action(KeyCode::KeyA, CTRL), Some(Action::SelectAll));
        assert_eq!(map.action(KeyCode::KeyA, none), None);
    }

    #[test]
    fn the_default_file_round_trips_and_means_the_defaults() {
        let text = KeyMap::to_ron(&default_bindings());
        let map = KeyMap::parse(&text, KeyPreset::MagicaVoxel).unwrap();
        assert_eq!(map.bindings(), default_bindings().as_slice());
        assert_eq!(map.action(KeyCode::KeyZ, CTRL), Some(Action::Undo));
        assert_eq!(
            map.action(KeyCode::BracketRight, Mods::default()),
            Some(Action::BrushLarger)
        );
        assert_eq!(
            map.action(KeyCode::Numpad5, Mods::default()),
            Some(Action::ToggleProjection)
        );
        assert_eq!(
            map.action(KeyCode::Digit7, CTRL),
            Some(Action::StoreView(7))
        );
        assert_eq!(map.action(KeyCode::KeyZ, Mods::default()), None);
        // No chord does two things.
        let chords: Vec<Chord> = map.chords.iter().map(|(c, _)| *c).collect();
        for (i, c) in chords.iter().enumerate() {
            assert!(
                !chords[..i].contains(c),
                "{:?} bound twice",
                map.bindings()[i]
            );
        }
    }

    #[test]
    fn an_older_file_keeps_its_bindings_and_gets_the_new_defaults() {
        // Binds Copy elsewhere and takes Ctrl+V for Undo: neither default comes back.
        let map = KeyMap::parse(
            r#"[(keys: "Ctrl+K", action: Copy), (keys: "Ctrl+V", action: Undo)]"#,
            KeyPreset::MagicaVoxel,
        )
        .unwrap();
        assert_eq!(map.action(KeyCode::KeyK, CTRL), Some(Action::Copy));
        assert_eq!(map.action(KeyCode::KeyC, CTRL), None);
        assert_eq!(map.action(KeyCode::KeyV, CTRL), Some(Action::Undo));
        assert_eq!(map.action(KeyCode::KeyZ, CTRL), None, "Undo is the file's");
        // Left out: the default.
        assert_eq!(map.action(KeyCode::KeyA, CTRL), Some(Action::SelectAll));
        assert_eq!(
            map.action(KeyCode::KeyM, Mods::default()),
            Some(Action::SelectTool)
        );
    }

    #[test]
    fn a_user_binding_replaces_the_defaults_and_bad_ones_are_named() {
        let map = KeyMap::parse(
            r#"[(keys: "Alt+U", action: Undo), (keys: "shift+f", action: Frame)]"#,
            KeyPreset::MagicaVoxel,
        )
        .unwrap();
        let alt = Mods {
            alt: true,
            ..Mods::default()
        };
        let shift = Mods {
            shift: true,
            ..Mods::default()
        };
        assert_eq!(map.action(KeyCode::KeyU, alt), Some(Action::Undo));
        assert_eq!(map.action(KeyCode::KeyF, shift), Some(Action::Frame));
        assert_eq!(
            map.action(KeyCode::KeyZ, CTRL),
            None,
            "the defaults are replaced"
        );
        let err = KeyMap::parse(
            r#"[(keys: "Ctrl+Banana", action: Undo)]"#,
            KeyPreset::MagicaVoxel,
        )
        .unwrap_err();
        assert_eq!(
            err,
            KeyMapError::UnknownKey {
                chord: "Ctrl+Banana".into(),
                key: "Banana".into()
            }
        );
        assert!(
            err.to_string().contains("no key is called \"Banana\""),
            "{err}"
        );
        let err = KeyMap::parse(
            r#"[(keys: "Hyper+Z", action: Undo)]"#,
            KeyPreset::MagicaVoxel,
        )
        .unwrap_err();
        assert!(
            matches!(err, KeyMapError::Modifier { ref modifier, .. } if modifier == "hyper"),
            "{err}"
        );
        assert!(matches!(
            KeyMap::parse(r#"[(keys: "Z", action: Fly)]"#, KeyPreset::MagicaVoxel),
            Err(KeyMapError::Syntax(_))
        ));
        assert!(matches!(
            KeyMap::parse(r#"[(keys: "Ctrl+", action: Undo)]"#, KeyPreset::MagicaVoxel),
            Err(KeyMapError::NoKey(_))
        ));
    }
}
