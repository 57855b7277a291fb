//! The soak through the editor itself: a headless [`Editor`] (the window's editor, frames
//! drawn offscreen with egui, validation on) fed seeded random input events — cursor moves,
//! button presses and releases, keys with modifiers, the wheel, resizes, dropped files —
//! through the same handlers a window's events reach: egui first, then the key map, picking,
//! strokes of every mode and shape, selections, the clipboard, the eyedropper, flood fills,
//! view drags, fly keys, undo / redo bursts, saves and re-opens, and clicks anywhere on the
//! panels (menus, sliders, palette, history).
//!
//! The driver waits for the editor to settle after each input (edits and file jobs done), so
//! a session is a function of its seed (egui's clock is the frame count). After every input:
//! the edit thread is alive, validation is silent, and an input whose every edit was refused
//! changed neither the content nor the history (a refused stroke: back to before it began).
//! At every check: Ctrl+Z as often as the history is long gives the opening hash, Ctrl+Shift+Z
//! as often gives the latest, Ctrl+S and a reload of the file give the same hash, the history
//! and the process's memory stay within their bounds. The session's recording (`--record`, on
//! across re-opens) is the failing prefix's replay script.

use super::{Rng, SoakOptions, SoakReport, rss};
use crate::editor::history::DEFAULT_BUDGET;
use crate::ui::input::Mods;
use crate::ui::{Editor, EditorOptions, Input};
use anyhow::{Context, Result, anyhow, bail, ensure};
use std::time::{Duration, Instant};
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

/// One soak session through a headless editor.
pub(super) struct EditorSession {
    opts: SoakOptions,
    rng: Rng,
    editor: Option<Editor>,
    report: SoakReport,
    opening: u64,
    generation: u64,
    baseline_rss: u64,
    inputs_since_frame: u64,
    mods: Mods,
    /// The state before the stroke being drawn began (a refused segment goes back to it).
    stroke_start: Option<(u64, usize, usize)>,
}

const NO_KEYS: Mods = Mods {
    ctrl: false,
    shift: false,
    alt: false,
};

impl EditorSession {
    pub(super) fn start(opts: &SoakOptions) -> Result<Self> {
        let dir = &opts.out_dir;
        let config = dir.join("config");
        let _ = std::fs::remove_dir_all(&config);
        std::fs::create_dir_all(&config).context("the soak's config folder")?;
        // Small internal images: the soak is about the editor, not about tracing.
        crate::ui::files::ConfigDir(config.clone()).save_settings(
            &crate::ui::panels::ViewSettings {
                internal_scale: 0.25,
                target_spp: 4,
                autosave_secs: 1,
                ..Default::default()
            },
        )?;
        let file = dir.join(format!("soak-editor-{}.ron", opts.seed));
        let (scene, _) = super::start_scene(opts)?;
        crate::formats::save(&scene, &file).context("the soak's start file")?;
        let device = opts.device.clone().unwrap_or_else(|| "gpu".into());
        let editor = Editor::headless(
            EditorOptions {
                file: Some(file),
                record: Some(dir.join(format!("soak-editor-{}-session.ron", opts.seed))),
                config: Some(config),
                workers: opts.workers,
                device,
                validation: true,
                capture_spp: 1,
                ..Default::default()
            },
            opts.window,
        )?;
        let mut s = Self {
            rng: Rng(opts.seed ^ 0xED17_0450),
            editor: Some(editor),
            report: SoakReport::default(),
            opening: 0,
            generation: 0,
            baseline_rss: rss(),
            inputs_since_frame: 0,
            mods: NO_KEYS,
            stroke_start: None,
            opts: opts.clone(),
        };
        s.settle()?;
        s.frame()?;
        s.opening = s.hash();
        s.generation = s.ed().generation();
        ensure!(s.generation > 0, "the start file was not opened");
        Ok(s)
    }

    fn ed(&mut self) -> &mut Editor {
        self.editor.as_mut().expect("alive until the end")
    }

    fn doc_state(&mut self) -> (u64, usize, usize) {
        let doc = self.ed().document();
        let d = doc.read().unwrap_or_else(|p| p.into_inner());
        (
            d.scene.world.read().content_hash(),
            d.history.undo_len(),
            d.history.redo_len(),
        )
    }

    fn hash(&mut self) -> u64 {
        self.doc_state().0
    }

    /// Until every edit and file job asked for is done (frames drawn meanwhile as the
    /// window's loop would).
    fn settle(&mut self) -> Result<()> {
        let started = Instant::now();
        loop {
            self.ed().pump();
            if self.ed().settled() {
                return Ok(());
            }
            ensure!(
                self.ed().edit_thread_alive(),
                "the edit thread died (a panic)"
            );
            ensure!(
                started.elapsed() < Duration::from_secs(300),
                "the editor did not settle in 300 s (a hung edit or file job)"
            );
            std::thread::sleep(Duration::from_micros(300));
        }
    }

    fn frame(&mut self) -> Result<()> {
        self.ed().frame()?;
        self.report.frames += 1;
        self.inputs_since_frame = 0;
        let errors = self.ed().validation_errors();
        ensure!(errors == 0, "{errors} Vulkan validation errors");
        Ok(())
    }

    /// One input, handled and settled, then the per-input checks.
    fn send(&mut self, input: Input) -> Result<()> {
        let before = self.doc_state();
        if let Input::Modifiers(m) = &input {
            self.mods = *m;
        }
        let pressed_left = matches!(
            input,
            Input::Button {
                button: MouseButton::Left,
                pressed: true
            }
        );
        if pressed_left {
            self.stroke_start = Some(before);
        }
        self.report.inputs += 1;
        self.ed().input(input);
        self.settle()?;
        self.inputs_since_frame += 1;
        if self.inputs_since_frame >= self.opts.frame_every.max(1) {
            self.frame()?;
            self.settle()?;
        }
        if self.ed().wants_exit() {
            // Quit from a menu or a key: the driver starts it again, as a user would.
            *self.report.kinds.entry("quit asked").or_default() += 1;
            self.ed().keep_running();
        }
        let lines = self.ed().take_report();
        self.ed().take_errors();
        let edited: Vec<&String> = lines.iter().filter(|l| l.starts_with("edited")).collect();
        let refused = edited.iter().filter(|l| l.contains(": error")).count();
        let stroke_refused = edited.iter().any(|l| l.starts_with("edited stroke: error"));
        self.report.refused += refused as u64;
        if self.ed().generation() != self.generation {
            // A new document (opened, built, recovered): its history starts here.
            self.generation = self.ed().generation();
            self.opening = self.hash();
            *self.report.kinds.entry("document replaced").or_default() += 1;
        } else if stroke_refused {
            let start = self.stroke_start.unwrap_or(before);
            ensure!(
                self.doc_state() == start,
                "a refused stroke left part of itself: {lines:?}"
            );
        } else if !edited.is_empty() && refused == edited.len() {
            ensure!(
                self.doc_state() == before,
                "a refused edit changed the document: {lines:?}"
            );
        }
        Ok(())
    }

    fn key(&mut self, code: KeyCode, mods: Mods) -> Result<()> {
        if mods != self.mods {
            self.send(Input::Modifiers(mods))?;
        }
        self.send(Input::Key {
            code,
            pressed: true,
            repeat: false,
        })?;
        self.send(Input::Key {
            code,
            pressed: false,
            repeat: false,
        })?;
        if mods != NO_KEYS {
            self.send(Input::Modifiers(NO_KEYS))?;
        }
        Ok(())
    }

    fn ctrl(&mut self, code: KeyCode, shift: bool) -> Result<()> {
        self.key(
            code,
            Mods {
                ctrl: true,
                shift,
                alt: false,
            },
        )
    }

    /// A point in the window. `viewport`: where the scene shows, aimed as a user aims — the
    /// top of a random column of the world (its floor where the column is empty), where no
    /// panel covers it (else a random point right of the Tools window's usual place).
    fn point(&mut self, viewport: bool) -> (f64, f64) {
        let (w, h) = self.ed().size();
        let (w, h) = (f64::from(w), f64::from(h));
        if !viewport {
            return (w * self.rng.unit(), h * self.rng.unit());
        }
        for _ in 0..12 {
            let target = self.column_top();
            if let Some(at) = self.ed().aim(target) {
                return at;
            }
        }
        (
            w * (0.55 + 0.42 * self.rng.unit()),
            h * (0.15 + 0.75 * self.rng.unit()),
        )
    }

    /// The top face's centre of a random column's highest solid voxel (the floor's point
    /// where the column is empty).
    fn column_top(&mut self) -> glam::DVec3 {
        let doc = self.ed().document();
        let d = doc.read().unwrap_or_else(|p| p.into_inner());
        let view = d.scene.world.read();
        let dims = view.dims().voxels();
        let x = self.rng.below(dims.x as u64) as i32;
        let z = self.rng.below(dims.z as u64) as i32;
        let top = (0..dims.y)
            .rev()
            .find(|&y| matches!(view.voxel(glam::IVec3::new(x, y, z)), Ok(Some(_))))
            .map_or(0.0, |y| f64::from(y) + 1.0);
        glam::DVec3::new(f64::from(x) + 0.5, top, f64::from(z) + 0.5)
    }

    /// A drag with `button`: press at a point, moves (mostly small, now and then a leap, as
    /// a fast hand on a slow frame makes), release — or Esc before it (a cancel).
    fn drag(&mut self, button: MouseButton, mods: Mods, viewport: bool) -> Result<()> {
        let (mut x, mut y) = self.point(viewport);
        if mods != self.mods {
            self.send(Input::Modifiers(mods))?;
        }
        self.send(Input::Moved { x, y })?;
        self.send(Input::Button {
            button,
            pressed: true,
        })?;
        let (w, h) = self.ed().size();
        for _ in 0..self.rng.below(16) {
            let step = if self.rng.chance(0.15) { 120.0 } else { 8.0 };
            x = (x + (self.rng.unit() - 0.5) * step).clamp(0.0, f64::from(w) - 1.0);
            y = (y + (self.rng.unit() - 0.5) * step).clamp(0.0, f64::from(h) - 1.0);
            self.send(Input::Moved { x, y })?;
        }
        if button == MouseButton::Left && self.rng.chance(0.08) {
            *self.report.kinds.entry("drag cancelled").or_default() += 1;
            self.key(KeyCode::Escape, self.mods)?;
        }
        self.send(Input::Button {
            button,
            pressed: false,
        })?;
        if mods != NO_KEYS {
            self.send(Input::Modifiers(NO_KEYS))?;
        }
        Ok(())
    }

    fn count(&mut self, kind: &'static str) {
        *self.report.kinds.entry(kind).or_default() += 1;
    }

    fn event(&mut self) -> Result<()> {
        match self.rng.below(100) {
            0..=29 => {
                self.count("stroke");
                let selecting = self.ed().brush().tool == crate::ui::tools::Tool::Select;
                if selecting || self.rng.chance(0.4) {
                    let mode = self
                        .rng
                        .pick(&[KeyCode::KeyT, KeyCode::KeyX, KeyCode::KeyP]);
                    self.key(mode, NO_KEYS)?;
                }
                if self.rng.chance(0.4) {
                    let shape = self.rng.pick(&[
                        KeyCode::KeyV,
                        KeyCode::KeyB,
                        KeyCode::KeyC,
                        KeyCode::KeyY,
                        KeyCode::KeyL,
                        KeyCode::KeyR,
                    ]);
                    self.key(shape, NO_KEYS)?;
                }
                for _ in 0..self.rng.below(3) {
                    let k = self
                        .rng
                        .pick(&[KeyCode::BracketLeft, KeyCode::BracketRight]);
                    self.key(k, NO_KEYS)?;
                }
                self.drag(MouseButton::Left, NO_KEYS, true)?;
            }
            30..=39 => {
                self.count("view drag, wheel, frame, projection, slots");
                match self.rng.below(6) {
                    0 => self.drag(MouseButton::Right, NO_KEYS, true)?,
                    1 => self.drag(MouseButton::Middle, NO_KEYS, true)?,
                    2 => {
                        let (x, y) = self.point(true);
                        self.send(Input::Moved { x, y })?;
                        let lines = (self.rng.unit() - 0.5) * 6.0;
                        self.send(Input::Wheel(lines))?;
                    }
                    3 => {
                        let k = self.rng.pick(&[KeyCode::KeyF, KeyCode::KeyO]);
                        self.key(k, NO_KEYS)?;
                    }
                    _ => {
                        let slot = self.rng.pick(&[KeyCode::Digit1, KeyCode::Digit2]);
                        let store = self.rng.chance(0.5);
                        self.key(
                            slot,
                            Mods {
                                ctrl: store,
                                ..NO_KEYS
                            },
                        )?;
                    }
                }
            }
            40..=42 => {
                self.count("fly");
                let k = self.rng.pick(&[
                    KeyCode::KeyW,
                    KeyCode::KeyA,
                    KeyCode::KeyS,
                    KeyCode::KeyD,
                    KeyCode::KeyQ,
                    KeyCode::KeyE,
                ]);
                self.send(Input::Key {
                    code: k,
                    pressed: true,
                    repeat: false,
                })?;
                for _ in 0..self.rng.range(1, 4) {
                    self.frame()?;
                }
                self.send(Input::Key {
                    code: k,
                    pressed: false,
                    repeat: false,
                })?;
            }
            43..=51 => {
                self.count("select");
                self.key(KeyCode::KeyM, NO_KEYS)?;
                let mods = Mods {
                    shift: self.rng.chance(0.3),
                    ctrl: self.rng.chance(0.2),
                    alt: false,
                };
                self.drag(MouseButton::Left, mods, true)?;
            }
            52..=61 => {
                self.count("selection operation");
                let (code, ctrl, shift) = self.rng.pick(&[
                    (KeyCode::KeyA, true, false),
                    (KeyCode::KeyD, true, false),
                    (KeyCode::Delete, false, false),
                    (KeyCode::KeyF, true, false),
                    (KeyCode::KeyP, true, false),
                    (KeyCode::KeyC, true, false),
                    (KeyCode::KeyX, true, false),
                    (KeyCode::ArrowLeft, false, false),
                    (KeyCode::ArrowUp, false, true),
                    (KeyCode::PageUp, false, false),
                    (KeyCode::PageDown, false, true),
                ]);
                self.key(
                    code,
                    Mods {
                        ctrl,
                        shift,
                        alt: false,
                    },
                )?;
            }
            62..=64 => {
                self.count("paste");
                self.ctrl(KeyCode::KeyV, false)?;
                let (x, y) = self.point(true);
                self.send(Input::Moved { x, y })?;
                if self.rng.chance(0.2) {
                    self.key(KeyCode::Escape, NO_KEYS)?;
                } else {
                    self.send(Input::Button {
                        button: MouseButton::Left,
                        pressed: true,
                    })?;
                    self.send(Input::Button {
                        button: MouseButton::Left,
                        pressed: false,
                    })?;
                }
            }
            65..=67 => {
                self.count("eyedropper, flood fill");
                let alt = self.rng.chance(0.5);
                if !alt {
                    self.key(KeyCode::KeyP, NO_KEYS)?;
                }
                let mods = Mods {
                    alt,
                    shift: !alt,
                    ctrl: false,
                };
                let (x, y) = self.point(true);
                self.send(Input::Moved { x, y })?;
                self.send(Input::Modifiers(mods))?;
                self.send(Input::Button {
                    button: MouseButton::Left,
                    pressed: true,
                })?;
                self.send(Input::Button {
                    button: MouseButton::Left,
                    pressed: false,
                })?;
                self.send(Input::Modifiers(NO_KEYS))?;
            }
            68..=77 => {
                self.count("undo / redo burst");
                for _ in 0..self.rng.range(1, 12) {
                    match self.rng.below(5) {
                        0..=2 => self.ctrl(KeyCode::KeyZ, false)?,
                        3 => self.ctrl(KeyCode::KeyZ, true)?,
                        _ => self.ctrl(KeyCode::KeyY, false)?,
                    }
                }
            }
            78..=79 => {
                self.count("resize");
                let (w, h) = self.opts.window;
                let size = (
                    self.rng.range(i64::from(w / 2), i64::from(w)) as u32,
                    self.rng.range(i64::from(h / 2), i64::from(h)) as u32,
                );
                self.send(Input::Resized(size.0, size.1))?;
                self.frame()?;
            }
            80 => {
                self.count("save and reopen");
                let reopen = self.rng.chance(0.5);
                self.save_and_reload(reopen)?;
            }
            81 => {
                self.count("bad file dropped");
                let bad = self.opts.out_dir.join("not-a-scene.ron");
                std::fs::write(&bad, "(format_version: 1, this is not a project")?;
                // What egui still has queued (a panel click's edit) lands first, or the
                // comparison below would blame the drop for it.
                self.frame()?;
                self.settle()?;
                let before = self.doc_state();
                let generation = self.ed().generation();
                self.send(Input::Dropped(bad))?;
                self.frame()?;
                self.settle()?;
                ensure!(
                    self.ed().generation() == generation && self.doc_state() == before,
                    "a broken file dropped on the window changed the document"
                );
            }
            82..=96 => {
                self.count("panel click or drag");
                if self.rng.chance(0.7) {
                    let (x, y) = self.point(false);
                    self.send(Input::Moved { x, y })?;
                    self.send(Input::Button {
                        button: MouseButton::Left,
                        pressed: true,
                    })?;
                    self.send(Input::Button {
                        button: MouseButton::Left,
                        pressed: false,
                    })?;
                } else {
                    self.drag(MouseButton::Left, NO_KEYS, false)?;
                }
                self.frame()?;
            }
            _ => {
                self.count("window keys");
                let k = self.rng.pick(&[
                    KeyCode::F1,
                    KeyCode::Escape,
                    KeyCode::Enter,
                    KeyCode::Tab,
                    KeyCode::Digit5,
                ]);
                self.key(k, NO_KEYS)?;
            }
        }
        Ok(())
    }

    /// Keys reach the key map only while egui wants no keyboard (a text field clicked by a
    /// panel click has it): Esc gives it back, as a user would press it.
    fn release_keyboard(&mut self) -> Result<()> {
        self.key(KeyCode::Escape, NO_KEYS)?;
        self.frame()?;
        // What egui did in that frame (a panel click it had queued: a palette swatch's new
        // material) is an edit on its way: done before anything is compared.
        self.settle()
    }

    /// Ctrl+S, then the file read back: the same content hash. With `reopen`, the file is
    /// dropped on the window (the document replaced by it).
    fn save_and_reload(&mut self, reopen: bool) -> Result<()> {
        self.release_keyboard()?;
        let doc = self.ed().document();
        let path = doc
            .read()
            .unwrap_or_else(|p| p.into_inner())
            .path
            .clone()
            .ok_or_else(|| anyhow!("the document has no file to save to"))?;
        let now = self.hash();
        self.ctrl(KeyCode::KeyS, false)?;
        self.frame()?;
        self.settle()?;
        let dirty = doc.read().unwrap_or_else(|p| p.into_inner()).dirty;
        ensure!(!dirty, "Ctrl+S left the document unsaved");
        let loaded = crate::formats::load(&path, self.opts.workers)
            .context("reloading the save")?
            .world
            .read()
            .content_hash();
        ensure!(
            loaded == now,
            "the saved file's hash {loaded:016x} is not the document's {now:016x}"
        );
        if reopen {
            self.send(Input::Dropped(path))?;
            self.frame()?;
            self.settle()?;
            ensure!(
                self.hash() == now,
                "the re-opened file is not what was saved"
            );
        }
        Ok(())
    }

    /// The whole history undone and redone by keys, a save and reload, the bounds.
    fn check(&mut self) -> Result<()> {
        self.release_keyboard()?;
        let now = self.hash();
        let (undo, dropped) = {
            let doc = self.ed().document();
            let d = doc.read().unwrap_or_else(|p| p.into_inner());
            (d.history.undo_len(), d.history.dropped())
        };
        for _ in 0..undo {
            self.ctrl(KeyCode::KeyZ, false)?;
        }
        let (back, left, _) = self.doc_state();
        ensure!(left == 0, "{undo} × Ctrl+Z left {left} steps to undo");
        if dropped == 0 {
            ensure!(
                back == self.opening,
                "undo of all {undo} steps gives {back:016x}, not the opening {:016x}",
                self.opening
            );
        }
        for _ in 0..undo {
            self.ctrl(KeyCode::KeyZ, true)?;
        }
        let again = self.hash();
        ensure!(
            again == now,
            "redo of all {undo} steps gives {again:016x}, not {now:016x}"
        );
        self.save_and_reload(false)?;
        let (history, world) = {
            let doc = self.ed().document();
            let d = doc.read().unwrap_or_else(|p| p.into_inner());
            let m = d.scene.world.read().memory();
            (d.history.bytes(), m.gpu_reserved() + m.cpu_only)
        };
        ensure!(
            history <= DEFAULT_BUDGET,
            "the history holds {history} bytes, over its bound {DEFAULT_BUDGET}"
        );
        let resident = rss();
        self.report.peak_history = self.report.peak_history.max(history);
        self.report.peak_rss = self.report.peak_rss.max(resident);
        let allowed = self.baseline_rss + DEFAULT_BUDGET as u64 + 4 * world + (512 << 20);
        ensure!(
            resident == 0 || resident <= allowed,
            "resident memory {resident} bytes, over the history bound + the world + 512 MiB ({allowed})"
        );
        self.report.checks += 1;
        Ok(())
    }
}

impl super::Driver for EditorSession {
    fn start(opts: &SoakOptions) -> Result<Self> {
        Self::start(opts)
    }

    fn event(&mut self, _n: u64) -> Result<()> {
        self.event()
    }

    fn check(&mut self) -> Result<()> {
        self.check()
    }

    fn report(&mut self) -> &mut SoakReport {
        &mut self.report
    }

    fn script(&self) -> String {
        self.editor
            .as_ref()
            .and_then(Editor::recording)
            .unwrap_or_default()
    }

    fn finish(&mut self) -> Result<()> {
        match self.editor.take() {
            Some(e) => e.close(),
            None => bail!("the editor is gone"),
        }
    }
}
