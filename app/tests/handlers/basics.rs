//! The viewport and the windows: presses and drags at a window's edge, fly keys, stored views, status-line notices, the docks, the browser, an empty scene's floor, a small window.

use super::session::{SIZE, Session};
use app::ui::Input;
use glam::{DVec3, IVec3};
use std::time::{Duration, Instant};
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

/// A press within a frame of moving from a window into the viewport is the
/// viewport's (egui's own idea of the pointer is still over the window then).
pub fn a_press_right_after_leaving_a_window_draws(s: &mut Session) {
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

/// A brush drag pressed on the sky draws from where its path first meets the scene: one fast
/// move from the sky onto the terrain (a single event, as a quick flick gives) begins the
/// stroke at the first point of the path with terrain behind it, one undo step.
pub fn a_drag_pressed_on_the_sky_draws_from_where_it_meets_the_ground(s: &mut Session) {
    let (sky, terrain) = (s.on_the_sky(), s.on_the_terrain());
    s.key(KeyCode::KeyT, true); // attach
    s.key(KeyCode::KeyT, false);
    s.to(sky);
    s.quiet();
    let before = s.state();
    // The first point of the path whose ray meets the scene, and the voxel attach fills there.
    let first = (1..=2000)
        .map(|i| {
            let f = f64::from(i) / 2000.0;
            (
                sky.0 + (terrain.0 - sky.0) * f,
                sky.1 + (terrain.1 - sky.1) * f,
            )
        })
        .find(|p| s.terrain_behind(*p))
        .expect("the path reaches the terrain");
    let target = {
        let h = s.hit_at(first).expect("terrain behind");
        h.voxel + h.normal
    };
    let filled = |s: &Session| {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        matches!(d.scene.world.read().voxel(target), Ok(Some(_)))
    };
    assert!(
        !filled(s),
        "the voxel in front of the crossing starts empty"
    );
    s.left(true);
    s.to(terrain);
    s.left(false);
    s.quiet();
    let after = s.state();
    assert_eq!(
        after.1,
        before.1 + 1,
        "the drag off the sky drew one stroke"
    );
    assert!(
        filled(s),
        "the stroke begins where the path crossed onto the scene ({first:?}), not at the event"
    );
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state().0, before.0, "undone exactly");
}

/// A drag that starts on a window belongs to it until the release, even when egui
/// still thinks the pointer is over the viewport and the drag ends there.
pub fn a_drag_from_a_window_into_the_viewport_edits_nothing(s: &mut Session) {
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
pub fn a_held_fly_key_moves_by_the_time_held(s: &mut Session) {
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
pub fn a_stored_view_comes_back(s: &mut Session) {
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
pub fn no_ops_and_saves_are_said_on_the_status_line(s: &mut Session) {
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
pub fn the_docks_leave_the_viewport_framing_fits_it_and_the_palette_paints(s: &mut Session) {
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
pub fn without_a_dialog_save_as_and_open_ask_in_the_browser(
    s: &mut Session,
    dir: &std::path::Path,
) {
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
pub fn the_first_click_on_an_empty_scene_attaches_on_the_floor(
    s: &mut Session,
    dir: &std::path::Path,
) {
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
pub fn a_small_window_folds_the_docks_and_a_large_one_brings_them_back(s: &mut Session) {
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

/// The panel windows are as tall as what they hold: Scene statistics, a few lines, opens
/// far shorter than egui's 420-point default, and as wide as it opens.
pub fn a_short_window_is_as_tall_as_what_it_holds(s: &mut Session) {
    s.click_on("View", MouseButton::Left);
    s.click_on("Scene statistics", MouseButton::Left);
    s.quiet();
    let (_, _, w, h) =
        s.ed.window_rect("Scene statistics")
            .expect("the statistics window opened");
    assert!(h < 300.0, "a window of a few lines is {h} pixels tall");
    assert!(w < 600.0, "it opens {w} pixels wide");
    // Closed again from the menu.
    s.click_on("View", MouseButton::Left);
    s.click_on("Scene statistics", MouseButton::Left);
    s.quiet();
    assert!(s.ed.window_rect("Scene statistics").is_none(), "closed");
}
