//! The editor's window handlers driven with the events a window gives them (a headless
//! editor: egui, the key map, picking and the tools as in the window, frames drawn offscreen
//! on the machine's Vulkan device with the validation layer): input lands where the user saw
//! the UI, fly keys follow time, harmless no-ops and saves are said on the status line. One
//! editor (one GPU context) runs every scenario in turn. Without a Vulkan driver it skips,
//! saying so, unless VOXBRICK_REQUIRE_GPU=1 makes that a failure.

mod window;

use app::ui::panels::ViewSettings;
use app::ui::{Editor, EditorOptions, Input};
use glam::{DVec3, IVec3};
use std::time::{Duration, Instant};
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

/// The window the issue was found at: both docks and a viewport of 488 × 494.
const SIZE: (u32, u32) = (960, 540);

struct Session {
    ed: Editor,
}

impl Session {
    fn start(dir: &std::path::Path) -> Option<Self> {
        let config = dir.join("config");
        std::fs::create_dir_all(&config).unwrap();
        app::ui::files::ConfigDir(config.clone())
            .save_settings(&ViewSettings {
                internal_scale: 0.25,
                target_spp: 2,
                autosave_secs: 0,
                ..Default::default()
            })
            .unwrap();
        let file = dir.join("terrain.ron");
        app::ui::files::new_scene((48, 24, 48), true, 2)
            .unwrap()
            .save(&file)
            .unwrap();
        let ed = match Editor::headless(
            EditorOptions {
                file: Some(file),
                config: Some(config),
                workers: 2,
                device: "gpu".into(),
                validation: true,
                ..Default::default()
            },
            SIZE,
        ) {
            Ok(ed) => ed,
            Err(e) => {
                window::skip(&format!("no Vulkan device: {e:#}"));
                return None;
            }
        };
        let mut s = Self { ed };
        let started = Instant::now();
        while s.ed.generation() == 0 {
            assert!(started.elapsed() < Duration::from_secs(120), "never opened");
            s.settle();
            s.frame();
        }
        s.frame();
        Some(s)
    }

    /// Until every edit and file job is done.
    fn settle(&mut self) {
        let started = Instant::now();
        loop {
            self.ed.pump();
            if self.ed.settled() {
                return;
            }
            assert!(self.ed.edit_thread_alive(), "the edit thread died");
            assert!(
                started.elapsed() < Duration::from_secs(120),
                "never settled"
            );
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    fn frame(&mut self) {
        self.ed.frame().expect("a frame");
        assert_eq!(self.ed.validation_errors(), 0, "validation messages");
    }

    /// Edits done and two frames drawn (egui's layers and its idea of the pointer current).
    fn quiet(&mut self) {
        self.settle();
        self.frame();
        self.settle();
        self.frame();
    }

    fn to(&mut self, (x, y): (f64, f64)) {
        self.ed.input(Input::Moved { x, y });
    }

    fn left(&mut self, pressed: bool) {
        self.ed.input(Input::Button {
            button: MouseButton::Left,
            pressed,
        });
    }

    fn key(&mut self, code: KeyCode, pressed: bool) {
        self.ed.input(Input::Key {
            code,
            pressed,
            repeat: false,
        });
    }

    fn ctrl(&mut self, code: KeyCode) {
        let ctrl = app::ui::input::Mods {
            ctrl: true,
            ..Default::default()
        };
        self.ed.input(Input::Modifiers(ctrl));
        self.key(code, true);
        self.key(code, false);
        self.ed.input(Input::Modifiers(Default::default()));
    }

    /// (content hash, undo steps)
    fn state(&self) -> (u64, usize) {
        let doc = self.ed.document();
        let d = doc.read().unwrap();
        (d.scene.world.read().content_hash(), d.history.undo_len())
    }

    /// A point on a window (not a bar: away from the top and bottom edges) with the
    /// terrain behind it, where a press the viewport took would start a stroke.
    fn on_a_window(&self) -> (f64, f64) {
        let (w, h) = (f64::from(SIZE.0), f64::from(SIZE.1));
        let mut y = h * 0.25;
        while y < h * 0.75 {
            let mut x = 4.0;
            while x < w {
                if self.ed.on_ui_at(x, y) && self.terrain_behind((x, y)) {
                    return (x, y);
                }
                x += 8.0;
            }
            y += 8.0;
        }
        panic!("no window over the terrain (the Tools window is open by default)")
    }

    /// Whether the view's ray through the window point hits the scene.
    fn terrain_behind(&self, (x, y): (f64, f64)) -> bool {
        let (origin, dir) = self.ed.ray_at(x, y);
        let doc = self.ed.document();
        let d = doc.read().unwrap();
        let hit = d
            .scene
            .world
            .read()
            .ray_cast(&brickmap::Ray { origin, dir }, f64::INFINITY);
        matches!(hit, Ok(Some(_)))
    }

    /// Where the terrain's surface shows in the viewport, free of every panel.
    fn on_the_terrain(&self) -> (f64, f64) {
        let doc = self.ed.document();
        let d = doc.read().unwrap();
        let view = d.scene.world.read();
        let dims = view.dims().voxels();
        for (x, z) in (8..dims.x - 8).flat_map(|x| (8..dims.z - 8).map(move |z| (x, z))) {
            let Some(top) = (0..dims.y)
                .rev()
                .find(|&y| matches!(view.voxel(IVec3::new(x, y, z)), Ok(Some(_))))
            else {
                continue;
            };
            let p = DVec3::new(f64::from(x) + 0.5, f64::from(top) + 1.0, f64::from(z) + 0.5);
            if let Some(at) = self.ed.aim(p) {
                return at;
            }
        }
        panic!("the terrain shows nowhere in the viewport")
    }
}

/// Item 1: a press within a frame of moving from a window into the viewport is the
/// viewport's (egui's own idea of the pointer is still over the window then).
fn a_press_right_after_leaving_a_window_draws(s: &mut Session) {
    let (window, terrain) = (s.on_a_window(), s.on_the_terrain());
    s.to(window);
    s.quiet();
    let before = s.state();
    // Into the viewport and press at once, no frame between; release a little further on.
    s.to(terrain);
    s.left(true);
    s.to((terrain.0 + 3.0, terrain.1));
    s.left(false);
    s.quiet();
    let after = s.state();
    assert_eq!(
        after.1,
        before.1 + 1,
        "the press right after leaving the window drew no stroke"
    );
    assert_ne!(after.0, before.0, "the stroke changed nothing");
}

/// Item 2: a drag that starts on a window belongs to it until the release, even when egui
/// still thinks the pointer is over the viewport and the drag ends there.
fn a_drag_from_a_window_into_the_viewport_edits_nothing(s: &mut Session) {
    let (window, terrain) = (s.on_a_window(), s.on_the_terrain());
    s.to(terrain);
    s.quiet();
    let before = s.state();
    // Onto the window and press at once, then drag out over the terrain and release.
    s.to(window);
    s.left(true);
    for k in 1..=8 {
        let t = f64::from(k) / 8.0;
        s.to((
            window.0 + (terrain.0 - window.0) * t,
            window.1 + (terrain.1 - window.1) * t,
        ));
    }
    s.left(false);
    s.quiet();
    assert_eq!(
        s.state(),
        before,
        "a drag that started on a window edited the scene"
    );
}

/// Item 11: a held fly key moves the camera by the time it was held, whatever the frames
/// (one frame in 0.4 s here).
fn a_held_fly_key_moves_by_the_time_held(s: &mut Session) {
    s.ed.fly_in_real_time();
    s.quiet();
    let (start, distance) = (s.ed.view().camera.position, s.ed.view().distance);
    let speed = distance.max(8.0) * 0.5;
    let began = Instant::now();
    s.key(KeyCode::KeyW, true);
    std::thread::sleep(Duration::from_millis(400));
    s.frame();
    std::thread::sleep(Duration::from_millis(100));
    s.key(KeyCode::KeyW, false);
    let held = began.elapsed().as_secs_f64();
    let moved = (s.ed.view().camera.position - start).length();
    assert!(
        moved >= speed * 0.5 * 0.95 && moved <= speed * held * 1.05,
        "held {held:.2} s at {speed:.1} voxels/s, moved {moved:.2} voxels"
    );
    s.quiet();
}

/// Item 16: an undo with nothing to undo (a key burst's) is a passing status-line message,
/// not an error; item 6: a save says so on the status line.
fn no_ops_and_saves_are_said_on_the_status_line(s: &mut Session) {
    while s.state().1 > 0 {
        s.ctrl(KeyCode::KeyZ);
        s.quiet();
    }
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.ed.take_errors(), Vec::<String>::new());
    assert_eq!(s.ed.notice(), Some("Nothing to undo"));
    // A copy without a selection: said, not shown as an error.
    s.ctrl(KeyCode::KeyC);
    s.quiet();
    assert_eq!(s.ed.take_errors(), Vec::<String>::new());
    assert!(
        s.ed.notice()
            .is_some_and(|n| n.contains("nothing is selected")),
        "{:?}",
        s.ed.notice()
    );
    s.ctrl(KeyCode::KeyS);
    s.quiet();
    let notice = s.ed.notice().unwrap_or_default().to_string();
    assert!(
        notice.starts_with("Saved ") && notice.ends_with("terrain.ron"),
        "{notice:?}"
    );
}

/// Items 12 and 13: the docks (Tools left, the 256 colours right) leave the viewport a
/// rectangle of its own; F frames the scene inside it; a click on a colour paints with it.
fn the_docks_leave_the_viewport_framing_fits_it_and_the_palette_paints(s: &mut Session) {
    s.quiet();
    let (x0, y0, w, h) = s.ed.view_area();
    assert!(
        x0 > 0 && x0 + w < SIZE.0 && w > SIZE.0 / 4,
        "the viewport {:?} in a {SIZE:?} window",
        s.ed.view_area()
    );
    let mid = f64::from(y0 + h / 2);
    assert!(s.ed.on_ui_at(f64::from(x0) - 4.0, mid), "the left dock");
    assert!(
        s.ed.on_ui_at(f64::from(x0 + w) + 4.0, mid),
        "the right dock"
    );
    s.key(KeyCode::KeyF, true);
    s.key(KeyCode::KeyF, false);
    s.quiet();
    let (lo, hi) = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        let b = d.scene.world.read().occupied_bounds().expect("terrain");
        (b.0.as_dvec3(), b.1.as_dvec3())
    };
    for k in 0..8 {
        let corner = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        assert!(
            s.ed.aim(corner).is_some(),
            "after F the corner {corner} of the scene is not in the viewport {:?}",
            s.ed.view_area()
        );
    }
    let (gx, gy, gw, gh) = s.ed.palette_grid().expect("the palette is docked");
    assert!(gx >= f64::from(x0 + w) && gy + gh <= f64::from(SIZE.1));
    let (row, col) = (2.0, 5.0);
    s.to((gx + (col + 0.5) * gw / 16.0, gy + (row + 0.5) * gh / 16.0));
    s.left(true);
    s.left(false);
    s.quiet();
    let colour = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        d.scene
            .world
            .materials()
            .get(s.ed.brush().material)
            .unwrap()
            .colour
    };
    assert_eq!(colour, 37, "the brush paints with the clicked colour");
}

/// Items 4 and 5: without a native dialog (a headless editor has none, as a desktop
/// without a portal, zenity or kdialog) Save As and Open ask in the in-app browser: nothing
/// is written until a path is confirmed there; a typed name saves beside the scene, a typed
/// path opens.
fn without_a_dialog_save_as_and_open_ask_in_the_browser(s: &mut Session, dir: &std::path::Path) {
    let config = dir.join("config");
    let before: Vec<_> = std::fs::read_dir(&config)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    let shift_ctrl = app::ui::input::Mods {
        ctrl: true,
        shift: true,
        alt: false,
    };
    s.ed.input(Input::Modifiers(shift_ctrl));
    s.key(KeyCode::KeyS, true);
    s.key(KeyCode::KeyS, false);
    s.ed.input(Input::Modifiers(Default::default()));
    s.quiet();
    assert!(
        s.ed.browser_open(),
        "Save As without a dialog opens the browser"
    );
    let after: Vec<_> = std::fs::read_dir(&config)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(
        before, after,
        "nothing was written to a place the user did not see"
    );
    assert!(!dir.join("scene.ron").exists());
    // The name field has the focus: replace the suggested name, Enter.
    s.ctrl(KeyCode::KeyA);
    s.ed.input(Input::Text("mine".into()));
    s.key(KeyCode::Enter, true);
    s.key(KeyCode::Enter, false);
    s.quiet();
    s.quiet();
    let saved = dir.join("mine.ron");
    assert!(
        saved.exists(),
        "saved as the typed name, with the project extension"
    );
    assert!(!s.ed.browser_open());
    let path = s.ed.document().read().unwrap().path.clone();
    assert_eq!(
        path.as_deref(),
        Some(saved.as_path()),
        "the document's file now"
    );
    // Open: a whole path typed in the name field.
    let generation = s.ed.generation();
    s.ctrl(KeyCode::KeyO);
    s.quiet();
    assert!(
        s.ed.browser_open(),
        "Open without a dialog opens the browser"
    );
    s.ed.input(Input::Text(dir.join("terrain.ron").display().to_string()));
    s.key(KeyCode::Enter, true);
    s.key(KeyCode::Enter, false);
    s.quiet();
    s.settle();
    s.quiet();
    assert!(s.ed.generation() > generation, "the typed file was opened");
    let path = s.ed.document().read().unwrap().path.clone();
    assert_eq!(path, Some(dir.join("terrain.ron")));
    // Esc closes it without a choice.
    s.ctrl(KeyCode::KeyO);
    s.quiet();
    assert!(s.ed.browser_open());
    s.key(KeyCode::Escape, true);
    s.key(KeyCode::Escape, false);
    s.quiet();
    assert!(!s.ed.browser_open(), "Esc closes the browser");
}

/// Item 14: a new empty scene has a floor to aim at: the first click attaches on it.
fn the_first_click_on_an_empty_scene_attaches_on_the_floor(s: &mut Session, dir: &std::path::Path) {
    let empty = dir.join("empty.ron");
    app::ui::files::new_scene((32, 16, 32), false, 1)
        .unwrap()
        .save(&empty)
        .unwrap();
    let generation = s.ed.generation();
    s.ed.input(Input::Dropped(empty));
    s.quiet();
    s.settle();
    s.quiet();
    assert!(s.ed.generation() > generation, "the empty scene was opened");
    let (x, y, w, h) = s.ed.view_area();
    let centre = (f64::from(x + w / 2), f64::from(y + h / 2));
    s.to(centre);
    s.quiet();
    s.left(true);
    s.left(false);
    s.quiet();
    let doc = s.ed.document();
    let d = doc.read().unwrap();
    let view = d.scene.world.read();
    let solid: Vec<IVec3> = (0..32)
        .flat_map(|x| (0..16).flat_map(move |y| (0..32).map(move |z| IVec3::new(x, y, z))))
        .filter(|v| matches!(view.voxel(*v), Ok(Some(_))))
        .collect();
    assert!(!solid.is_empty(), "the click placed nothing");
    assert_eq!(solid.iter().map(|v| v.y).min(), Some(0), "on the floor");
}

/// Item 15: a small window folds the docks so the viewport keeps its room; back at full
/// size they are as they were.
fn a_small_window_folds_the_docks_and_a_large_one_brings_them_back(s: &mut Session) {
    s.quiet();
    let wide = s.ed.view_area();
    s.ed.input(Input::Resized(420, 300));
    s.quiet();
    let (_, _, w, _) = s.ed.view_area();
    assert!(w >= 300, "a 420 px window leaves the viewport {w} px");
    assert!(s.ed.palette_grid().is_none(), "the palette folded");
    s.ed.input(Input::Resized(SIZE.0, SIZE.1));
    s.quiet();
    assert_eq!(s.ed.view_area(), wide, "the docks came back as they were");
    assert!(s.ed.palette_grid().is_some());
}

/// Item 8: a paste being placed shows the voxels it will put down, not only a box.
fn a_paste_being_placed_shows_its_voxels(s: &mut Session) {
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

#[test]
fn the_window_handlers_take_input_as_the_user_saw_the_ui() {
    let dir = window::scratch("editor-handlers");
    let Some(mut s) = Session::start(&dir) else {
        return;
    };
    a_press_right_after_leaving_a_window_draws(&mut s);
    a_drag_from_a_window_into_the_viewport_edits_nothing(&mut s);
    a_held_fly_key_moves_by_the_time_held(&mut s);
    no_ops_and_saves_are_said_on_the_status_line(&mut s);
    a_paste_being_placed_shows_its_voxels(&mut s);
    the_docks_leave_the_viewport_framing_fits_it_and_the_palette_paints(&mut s);
    without_a_dialog_save_as_and_open_ask_in_the_browser(&mut s, &dir);
    the_first_click_on_an_empty_scene_attaches_on_the_floor(&mut s, &dir);
    a_small_window_folds_the_docks_and_a_large_one_brings_them_back(&mut s);
    assert!(s.ed.take_errors().is_empty());
    s.ed.close().expect("a clean session");
}
