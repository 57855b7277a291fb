//! The headless editor session every scenario drives: start (a small terrain, the validation
//! layer), settle, frames, input and the points of the window the scenarios aim at.

use app::ui::panels::ViewSettings;
use app::ui::{Editor, EditorOptions, Input};
use glam::{DVec3, IVec3};
use std::time::{Duration, Instant};
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

/// The window size the problems were found at by hand: both docks and a viewport of 488 × 494.
pub const SIZE: (u32, u32) = (960, 540);

pub struct Session {
    pub ed: Editor,
}

impl Session {
    pub fn start(dir: &std::path::Path) -> Option<Self> {
        let config = dir.join("config");
        std::fs::create_dir_all(&config).unwrap();
        app::ui::files::ConfigDir(config.clone())
            .save_settings(&ViewSettings {
                internal_scale: 0.25,
                target_spp: 8,
                autosave_secs: 0,
                render_image: app::ui::render_image::RenderImageOptions {
                    size: (40, 30),
                    samples: 4,
                    alpha: true,
                    ..Default::default()
                },
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
                crate::window::skip(&format!("no Vulkan device: {e:#}"));
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

    /// The last undo step's label and command.
    pub fn last_command(&self) -> Option<(String, app::editor::command::Command)> {
        let doc = self.ed.document();
        let d = doc.read().unwrap();
        d.history
            .undo_steps()
            .last()
            .map(|st| (st.label.clone(), st.command.clone()))
    }

    /// Until every edit and file job is done.
    pub fn settle(&mut self) {
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

    pub fn frame(&mut self) {
        self.ed.frame().expect("a frame");
        assert_eq!(self.ed.validation_errors(), 0, "validation messages");
    }

    /// Edits done and two frames drawn (egui's layers and its idea of the pointer current).
    pub fn quiet(&mut self) {
        self.settle();
        self.frame();
        self.settle();
        self.frame();
    }

    pub fn to(&mut self, (x, y): (f64, f64)) {
        self.ed.input(Input::Moved { x, y });
    }

    pub fn left(&mut self, pressed: bool) {
        self.ed.input(Input::Button {
            button: MouseButton::Left,
            pressed,
        });
    }

    pub fn key(&mut self, code: KeyCode, pressed: bool) {
        self.ed.input(Input::Key {
            code,
            pressed,
            repeat: false,
        });
    }

    pub fn ctrl(&mut self, code: KeyCode) {
        self.chord(true, false, false, code);
    }

    /// Tab into arrange mode and a click on the terrain (picking its object); the point.
    pub fn arrange_and_pick_the_terrain(&mut self) -> (f64, f64) {
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
    pub fn chord(&mut self, ctrl: bool, shift: bool, alt: bool, code: KeyCode) {
        let mods = app::ui::input::Mods { ctrl, shift, alt };
        self.ed.input(Input::Modifiers(mods));
        self.key(code, true);
        self.key(code, false);
        self.ed.input(Input::Modifiers(Default::default()));
    }

    /// A click (left or right) on the widget that says `label`, as last drawn; then the
    /// edits it asked for done.
    pub fn click_on(&mut self, label: &str, button: MouseButton) {
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

    pub fn bounces(&self) -> u32 {
        let doc = self.ed.document();
        let d = doc.read().unwrap();
        d.scene.params.settings.max_bounces
    }

    /// (content hash, undo steps)
    pub fn state(&self) -> (u64, usize) {
        let doc = self.ed.document();
        let d = doc.read().unwrap();
        (d.scene.world.read().content_hash(), d.history.undo_len())
    }

    /// A point on a window (not a bar: away from the top and bottom edges) with the
    /// terrain behind it, where a press the viewport took would start a stroke.
    pub fn on_a_window(&self) -> (f64, f64) {
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
    pub fn terrain_behind(&self, at: (f64, f64)) -> bool {
        self.hit_at(at).is_some()
    }

    /// What the view's ray through the window point hits first (the exact CPU cast).
    pub fn hit_at(&self, (x, y): (f64, f64)) -> Option<brickmap::RayHit> {
        let (origin, dir) = self.ed.ray_at(x, y);
        let doc = self.ed.document();
        let d = doc.read().unwrap();
        let hit = d
            .scene
            .world
            .read()
            .ray_cast(&brickmap::Ray { origin, dir }, f64::INFINITY);
        hit.ok().flatten().map(|(h, _)| h)
    }

    /// A point of the viewport, free of every panel, with nothing of the scene behind it.
    pub fn on_the_sky(&self) -> (f64, f64) {
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
    pub fn on_the_terrain(&self) -> (f64, f64) {
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
