//! The editor's input events, independent of the window: what [`super::Editor::input`]
//! handles. A window's winit events are translated into them (`from_window_event`); a
//! headless driver (the soak test) makes them directly, so both reach the same handlers. For
//! a headless editor they are also translated into egui's events (`to_egui`), the way
//! egui-winit does for a window, with the same rule for which of them egui keeps to itself.

use super::input::Mods;
use std::path::PathBuf;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{KeyCode, PhysicalKey};

/// One input event, in the window's physical pixels.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// The cursor moved to (x, y).
    Moved {
        /// Pixels from the left.
        x: f64,
        /// Pixels from the top.
        y: f64,
    },
    /// A mouse button went down or up.
    Button {
        /// Which.
        button: MouseButton,
        /// Down (true) or up.
        pressed: bool,
    },
    /// A key went down or up.
    Key {
        /// The physical key.
        code: KeyCode,
        /// Down (true) or up.
        pressed: bool,
        /// A key held down, repeating.
        repeat: bool,
    },
    /// The modifier keys held changed.
    Modifiers(Mods),
    /// Text typed (egui's alone: a window's egui-winit takes it from the key events itself).
    Text(String),
    /// The wheel turned, in lines (up positive).
    Wheel(f64),
    /// The window's inner size changed, in physical pixels.
    Resized(u32, u32),
    /// A file was dropped on the window.
    Dropped(PathBuf),
    /// The window's close button.
    Close,
}

impl Input {
    /// The editor's input for a window event (None: not one the editor handles, or a key
    /// without a physical key code).
    pub fn from_window_event(event: &WindowEvent) -> Option<Self> {
        Some(match event {
            WindowEvent::CursorMoved { position, .. } => Self::Moved {
                x: position.x,
                y: position.y,
            },
            WindowEvent::MouseInput { state, button, .. } => Self::Button {
                button: *button,
                pressed: *state == ElementState::Pressed,
            },
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return None;
                };
                Self::Key {
                    code,
                    pressed: event.state == ElementState::Pressed,
                    repeat: event.repeat,
                }
            }
            WindowEvent::ModifiersChanged(m) => {
                let s = m.state();
                Self::Modifiers(Mods {
                    ctrl: s.control_key() || s.super_key(),
                    shift: s.shift_key(),
                    alt: s.alt_key(),
                })
            }
            WindowEvent::MouseWheel { delta, .. } => Self::Wheel(match delta {
                MouseScrollDelta::LineDelta(_, y) => *y as f64,
                MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
            }),
            WindowEvent::Resized(size) => Self::Resized(size.width, size.height),
            WindowEvent::DroppedFile(path) => Self::Dropped(path.clone()),
            WindowEvent::CloseRequested => Self::Close,
            _ => return None,
        })
    }

    /// How the event appears in the handshake log (`input …`; None: not logged).
    pub fn report_line(&self) -> Option<String> {
        Some(match self {
            Self::Moved { x, y } => format!("move {x} {y}"),
            Self::Button { button, pressed } => {
                format!("{} {button:?}", if *pressed { "press" } else { "release" })
            }
            Self::Key { code, pressed, .. } => format!(
                "key {:?} {}",
                PhysicalKey::Code(*code),
                if *pressed { "down" } else { "up" }
            ),
            Self::Wheel(_) => "wheel".into(),
            Self::Resized(w, h) => format!("resized {w} {h}"),
            _ => return None,
        })
    }

    /// Whether the event goes through the frame gate (it may read the document); resizes
    /// never wait.
    pub fn gated(&self) -> bool {
        !matches!(self, Self::Resized(..))
    }

    /// egui's events for this input in a headless editor (one pixel per point), given the
    /// cursor's last position and the modifiers held.
    pub fn to_egui(&self, cursor: (f64, f64), mods: Mods) -> Vec<egui::Event> {
        let modifiers = egui_modifiers(mods);
        let at = egui::pos2(cursor.0 as f32, cursor.1 as f32);
        match self {
            Self::Moved { x, y } => {
                vec![egui::Event::PointerMoved(egui::pos2(*x as f32, *y as f32))]
            }
            Self::Button { button, pressed } => {
                let button = match button {
                    MouseButton::Left => egui::PointerButton::Primary,
                    MouseButton::Right => egui::PointerButton::Secondary,
                    MouseButton::Middle => egui::PointerButton::Middle,
                    MouseButton::Back => egui::PointerButton::Extra1,
                    MouseButton::Forward => egui::PointerButton::Extra2,
                    MouseButton::Other(_) => return Vec::new(),
                };
                vec![egui::Event::PointerButton {
                    pos: at,
                    button,
                    pressed: *pressed,
                    modifiers,
                }]
            }
            Self::Key {
                code,
                pressed,
                repeat,
            } => egui_key(*code)
                .map(|key| egui::Event::Key {
                    key,
                    physical_key: Some(key),
                    pressed: *pressed,
                    repeat: *repeat,
                    modifiers,
                })
                .into_iter()
                .collect(),
            Self::Wheel(lines) => vec![egui::Event::MouseWheel {
                unit: egui::MouseWheelUnit::Line,
                delta: egui::vec2(0.0, *lines as f32),
                phase: egui::TouchPhase::Move,
                modifiers,
            }],
            Self::Text(text) => vec![egui::Event::Text(text.clone())],
            Self::Modifiers(_) | Self::Resized(..) | Self::Dropped(_) | Self::Close => Vec::new(),
        }
    }

    /// Whether egui keeps the event to itself (egui-winit's rule: pointer events while egui
    /// wants the pointer — a move only while it is using it —, keys while it wants the
    /// keyboard).
    /// Whether egui is kept from seeing this input: Tab is arrange mode's key, which egui
    /// would take for moving its focus (and keep the arrows after), unless a text field has
    /// the focus.
    pub fn kept_from(&self, egui: &egui::Context) -> bool {
        matches!(
            self,
            Self::Key {
                code: winit::keyboard::KeyCode::Tab,
                ..
            }
        ) && !egui.egui_wants_keyboard_input()
    }

    pub fn consumed_by(&self, egui: &egui::Context) -> bool {
        match self {
            Self::Moved { .. } => egui.egui_is_using_pointer(),
            Self::Button { .. } | Self::Wheel(_) => egui.egui_wants_pointer_input(),
            Self::Key { .. } => egui.egui_wants_keyboard_input(),
            _ => false,
        }
    }
}

/// egui's modifiers for ours (Ctrl is egui's command key too).
pub fn egui_modifiers(m: Mods) -> egui::Modifiers {
    egui::Modifiers {
        alt: m.alt,
        ctrl: m.ctrl,
        shift: m.shift,
        mac_cmd: false,
        command: m.ctrl,
    }
}

/// egui's key for a physical key: egui knows winit's names ("KeyA", "Digit1", "BracketLeft",
/// "ArrowUp", "F1", …).
fn egui_key(code: KeyCode) -> Option<egui::Key> {
    egui::Key::from_name(&format!("{code:?}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_reach_egui_under_their_names() {
        assert_eq!(egui_key(KeyCode::KeyZ), Some(egui::Key::Z));
        assert_eq!(egui_key(KeyCode::Digit3), Some(egui::Key::Num3));
        assert_eq!(egui_key(KeyCode::Escape), Some(egui::Key::Escape));
        assert_eq!(egui_key(KeyCode::ArrowLeft), Some(egui::Key::ArrowLeft));
        assert_eq!(egui_key(KeyCode::F1), Some(egui::Key::F1));
        assert_eq!(egui_key(KeyCode::BracketLeft), Some(egui::Key::OpenBracket));
    }

    #[test]
    fn a_press_goes_to_egui_where_the_cursor_is() {
        let e = Input::Button {
            button: MouseButton::Left,
            pressed: true,
        }
        .to_egui((12.0, 34.0), Mods::default());
        assert!(
            matches!(e.as_slice(), [egui::Event::PointerButton { pos, pressed: true, .. }] if *pos == egui::pos2(12.0, 34.0)),
            "{e:?}"
        );
    }
}
