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

/// The window size the problems were found at by hand: both docks and a viewport of 488 × 494.
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
                target_spp: 8,
                autosave_secs: 0,
                ..Default::default()
            })
            .unwrap();
        let file = dir.join("terrain.ron");
        app::formats::save(
            &app::ui::files::new_scene((48, 24, 48), true, 2).unwrap(),
            &file,
        )
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
        self.chord(true, false, false, code);
    }

    /// Tab into arrange mode and a click on the terrain (picking its object); the point.
    fn arrange_and_pick_the_terrain(&mut self) -> (f64, f64) {
        self.key(KeyCode::Tab, true);
        self.key(KeyCode::Tab, false);
        let at = self.on_the_terrain();
        self.to(at);
        self.frame();
        self.left(true);
        self.left(false);
        self.quiet();
        at
    }

    /// A key pressed and released with the modifiers named (Ctrl, Shift, Alt) held.
    fn chord(&mut self, ctrl: bool, shift: bool, alt: bool, code: KeyCode) {
        let mods = app::ui::input::Mods { ctrl, shift, alt };
        self.ed.input(Input::Modifiers(mods));
        self.key(code, true);
        self.key(code, false);
        self.ed.input(Input::Modifiers(Default::default()));
    }

    /// A click (left or right) on the widget that says `label`, as last drawn; then the
    /// edits it asked for done.
    fn click_on(&mut self, label: &str, button: MouseButton) {
        let at = self
            .ed
            .widget(label)
            .unwrap_or_else(|| panic!("no widget says {label:?}"));
        // The docks end where the viewport does (the status bar is below both).
        let (_, y0, _, h) = self.ed.view_area();
        let inside = at.0 < f64::from(SIZE.0) && at.1 < f64::from(y0 + h);
        assert!(
            inside && self.ed.on_ui_at(at.0, at.1),
            "{label:?} at {at:?} is not on the UI as drawn (scrolled out of its dock?)"
        );
        self.to(at);
        self.frame();
        for pressed in [true, false] {
            self.ed.input(Input::Button { button, pressed });
        }
        self.quiet();
    }

    fn bounces(&self) -> u32 {
        let doc = self.ed.document();
        let d = doc.read().unwrap();
        d.scene.params.settings.max_bounces
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

    /// A point of the viewport, free of every panel, with nothing of the scene behind it.
    fn on_the_sky(&self) -> (f64, f64) {
        let (x0, y0, w, h) = self.ed.view_area();
        let (x0, y0, w, h) = (f64::from(x0), f64::from(y0), f64::from(w), f64::from(h));
        for (fx, fy) in (1..16).flat_map(|j| (1..16).map(move |i| (i, j))) {
            let p = (x0 + w * f64::from(fx) / 16.0, y0 + h * f64::from(fy) / 16.0);
            if !self.ed.on_ui_at(p.0, p.1) && !self.terrain_behind(p) {
                return p;
            }
        }
        panic!("the scene fills the viewport")
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

/// A press within a frame of moving from a window into the viewport is the
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

/// A drag that starts on a window belongs to it until the release, even when egui
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

/// A held fly key moves the camera by the time it was held, whatever the frames
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

/// Ctrl + 3 stores the view; after an orbit, 3 brings it back exactly.
fn a_stored_view_comes_back(s: &mut Session) {
    s.quiet();
    s.ctrl(KeyCode::Digit3);
    let stored = s.ed.view().clone();
    let (x, y, w, h) = s.ed.view_area();
    let centre = (f64::from(x + w / 2), f64::from(y + h / 2));
    s.to(centre);
    s.ed.input(Input::Button {
        button: MouseButton::Right,
        pressed: true,
    });
    s.to((centre.0 + 60.0, centre.1 + 20.0));
    s.ed.input(Input::Button {
        button: MouseButton::Right,
        pressed: false,
    });
    assert_ne!(*s.ed.view(), stored, "the drag orbits");
    s.key(KeyCode::Digit3, true);
    s.key(KeyCode::Digit3, false);
    assert_eq!(*s.ed.view(), stored, "the stored view is back");
    s.quiet();
}

/// An undo with nothing to undo (a key burst's) is a passing status-line message,
/// not an error; a save says so on the status line.
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

/// The docks (Tools left, the 256 colours right) leave the viewport a
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
    assert!(
        gx >= f64::from(x0 + w) && gy + gh <= f64::from(SIZE.1),
        "the palette at {:?}, the viewport {:?}",
        (gx, gy, gw, gh),
        s.ed.view_area()
    );
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

/// Without a native dialog (a headless editor has none, as a desktop
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

/// A new empty scene has a floor to aim at: the first click attaches on it.
fn the_first_click_on_an_empty_scene_attaches_on_the_floor(s: &mut Session, dir: &std::path::Path) {
    let empty = dir.join("empty.ron");
    app::formats::save(
        &app::ui::files::new_scene((32, 16, 32), false, 1).unwrap(),
        &empty,
    )
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

/// A small window folds the docks so the viewport keeps its room; back at full
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

/// A paste being placed shows the voxels it will put down, not only a box.
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

/// A glass or water swatch looks like glass (the swatch test in `ui/swatch.rs`),
/// and with a dielectric picked while the scene has too few bounces for light to pass
/// through it, the panel says so and its button sets enough (one undo step).
fn a_dielectric_asks_for_the_bounces_it_needs(s: &mut Session) {
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
fn selection_operations_land_and_a_selection_gets_a_material_of_its_own(s: &mut Session) {
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

/// Arrange mode: Tab, then a click picks the object under the cursor and an arrow moves it
/// (the scene's one grid-sized object: past the grid's side, so the grid grows and the
/// viewport takes the new world, validated); Ctrl + Z puts it back and the grid with it; a
/// drag from it moves it by one step at the release; a click on the sky un-picks it, a box
/// dragged from the sky over it picks it again, and the turn keys turn it; Tab again is the
/// brush.
fn arrange_mode_picks_and_moves_an_object(s: &mut Session) {
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
fn the_object_keys_and_menu_act_on_the_picked_object(s: &mut Session) {
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
fn the_blender_key_map_is_chosen_in_the_shortcuts_window(s: &mut Session) {
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

/// The selection tool's magic wand: a click on the terrain selects the connected voxels of
/// its material (one step, named in the History); Shift + Ctrl + click intersects; back to
/// boxes.
fn the_magic_wand_selects_with_a_click(s: &mut Session) {
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
    let label = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        d.history.undo_steps().last().map(|st| st.label.clone())
    };
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
fn extrude_drags_a_face_and_shift_click_fills_a_plane(s: &mut Session) {
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
    let label = |s: &Session| {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        d.history.undo_steps().last().map(|st| st.label.clone())
    };
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

#[test]
fn the_window_handlers_take_input_as_the_user_saw_the_ui() {
    let dir = window::scratch("editor-handlers");
    let Some(mut s) = Session::start(&dir) else {
        return;
    };
    a_press_right_after_leaving_a_window_draws(&mut s);
    a_drag_from_a_window_into_the_viewport_edits_nothing(&mut s);
    a_held_fly_key_moves_by_the_time_held(&mut s);
    a_stored_view_comes_back(&mut s);
    no_ops_and_saves_are_said_on_the_status_line(&mut s);
    a_paste_being_placed_shows_its_voxels(&mut s);
    a_dielectric_asks_for_the_bounces_it_needs(&mut s);
    selection_operations_land_and_a_selection_gets_a_material_of_its_own(&mut s);
    arrange_mode_picks_and_moves_an_object(&mut s);
    the_object_keys_and_menu_act_on_the_picked_object(&mut s);
    the_blender_key_map_is_chosen_in_the_shortcuts_window(&mut s);
    the_magic_wand_selects_with_a_click(&mut s);
    extrude_drags_a_face_and_shift_click_fills_a_plane(&mut s);
    the_docks_leave_the_viewport_framing_fits_it_and_the_palette_paints(&mut s);
    without_a_dialog_save_as_and_open_ask_in_the_browser(&mut s, &dir);
    the_first_click_on_an_empty_scene_attaches_on_the_floor(&mut s, &dir);
    a_small_window_folds_the_docks_and_a_large_one_brings_them_back(&mut s);
    assert!(s.ed.take_errors().is_empty());
    s.ed.close().expect("a clean session");
}
