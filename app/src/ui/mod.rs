//! The interactive editor: a winit window whose viewport is the live path tracer, with egui
//! panels on top. `run` owns the event loop; [`Editor`] is the application handler: input →
//! view camera or actions, the document shared with the file worker, one frame per redraw
//! through the GPU session ([`Viewport`]) and the window's [`Presenter`]. Progressive
//! refinement adds samples until the target, then the loop waits for events.

pub mod camera;
pub mod files;
pub mod input;
pub mod jobs;
pub mod panels;

use crate::Scene;
use crate::editor::Document;
use crate::editor::command::Command;
use crate::editor::history::{DEFAULT_BUDGET, History};
use crate::editor::script::{self, ReplayOptions, Script, ScriptRun};
use anyhow::{Context, Result, anyhow};
use camera::ViewCamera;
use files::{ConfigDir, Done, FileWorker, Purpose, SharedDocument};
use glam::DVec3;
use input::{Action, Drag, Mods};
use jobs::{Edit, EditQueue, Edited};
use panels::{PanelState, UiEvent, UnsavedAnswer, ViewSettings};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use render::present::{EguiFrame, Presented, Presenter};
use render::viewport::{FrameRequest, Viewport};
use render::vulkan::{ContextOptions, GpuContext, WindowHandles};
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::{Arc, RwLock};
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// How the editor starts.
#[derive(Clone, Debug, Default)]
pub struct EditorOptions {
    /// A file to open (.ron or .vox); None: the built-in default scene.
    pub file: Option<PathBuf>,
    /// Run a replay script's steps through the live editor, capture and exit.
    pub script: Option<PathBuf>,
    /// Where a script run writes the captured frame (PNG).
    pub capture: Option<PathBuf>,
    /// Samples per pixel before a script run captures.
    pub capture_spp: u32,
    /// Keep the window open this long after the capture (for screenshots).
    pub linger: Duration,
    /// Initial window size in physical pixels.
    pub size: (u32, u32),
    /// Worker threads (0: one per core).
    pub workers: usize,
    /// Vulkan device choice ("gpu" or part of a name).
    pub device: String,
    /// Enable the validation layer (a script run fails on any validation error).
    pub validation: bool,
}

/// Wakes the event loop from other threads (file work finished).
#[derive(Debug, Clone, Copy)]
pub struct Wake;

/// Runs the editor until the window closes.
pub fn run(options: EditorOptions) -> Result<()> {
    let event_loop = EventLoop::<Wake>::with_user_event().build().map_err(|e| {
        anyhow!("cannot open a window: {e} (no display? set DISPLAY or WAYLAND_DISPLAY)")
    })?;
    let proxy = event_loop.create_proxy();
    let mut editor = Editor::new(options, proxy)?;
    event_loop
        .run_app(&mut editor)
        .map_err(|e| anyhow!("event loop: {e}"))?;
    std::mem::replace(&mut editor.outcome, Ok(()))
}

/// What the GPU and the window are, once the window exists. Field order is drop order:
/// the presenter and the session go before the window their surface belongs to.
struct Gfx {
    presenter: Presenter,
    viewport: Viewport,
    egui_state: egui_winit::State,
    window: Arc<Window>,
}

/// A script run through the live editor.
struct LiveScript {
    script: Arc<Script>,
    /// None while its next step runs on the edit thread.
    run: Option<Box<ScriptRun>>,
    /// Every step ran.
    finished: bool,
    capture: Option<PathBuf>,
    captured_at: Option<Instant>,
}

/// What to do once the unsaved-changes question is answered.
#[derive(Clone, Debug)]
enum Pending {
    Quit,
    Open(Option<PathBuf>),
    New {
        size: (u32, u32, u32),
        terrain: bool,
    },
}

/// The application handler.
pub struct Editor {
    options: EditorOptions,
    config: ConfigDir,
    gfx: Option<Gfx>,
    egui: egui::Context,
    doc: SharedDocument,
    /// Bumped whenever the document is replaced (the GPU world is then rebuilt).
    generation: u64,
    gpu_generation: u64,
    files: FileWorker,
    edits: EditQueue,
    /// Input that arrived while an edit held the frame gate, handled (in order) once it is
    /// free: a keystroke during a long undo is late, never lost.
    backlog: Vec<WindowEvent>,
    /// Saves asked for while edits were queued: they start once those are applied.
    saves_waiting: Vec<(PathBuf, bool)>,
    /// Finished saves (file, revision written) whose bookkeeping is not yet on the document.
    saved: Vec<(PathBuf, u64)>,
    view: ViewCamera,
    slots: [Option<ViewCamera>; 9],
    settings: ViewSettings,
    panels: PanelState,
    mods: Mods,
    drag: Option<(Drag, (f64, f64))>,
    cursor: (f64, f64),
    flying: HashSet<KeyCode>,
    last_tick: Instant,
    moving_until: Instant,
    spp_per_frame: u32,
    /// Samples per pixel the last shown frame added (0 once converged).
    last_added: u32,
    pending: Option<Pending>,
    save_then: Option<Pending>,
    last_autosave: Instant,
    script: Option<LiveScript>,
    /// A built scene (the default one, or New) is on its way: a `Loaded` without a path replaces
    /// the document only then.
    awaiting_built_scene: bool,
    pending_textures: egui::TexturesDelta,
    /// The window title last set.
    title: String,
    recovering: bool,
    quitting: bool,
    outcome: Result<()>,
    /// Input event time of the latest camera move not yet on screen (input-to-photon).
    move_event: Option<Instant>,
    /// Frames and time of the latest move's first frame (for the status line).
    latency: Option<Duration>,
    /// Frames drawn.
    frames: u64,
    /// Tests only: the frame that fails as if the device were lost
    /// (`VOXBRICK_TEST_GPU_FAILURE_AT_FRAME`), to check nothing is lost when the GPU fails.
    fail_at_frame: Option<u64>,
}

impl Editor {
    fn new(options: EditorOptions, proxy: EventLoopProxy<Wake>) -> Result<Self> {
        let wake_proxy = proxy.clone();
        let wake: Arc<dyn Fn() + Send + Sync> = Arc::new(move || {
            let _ = wake_proxy.send_event(Wake);
        });
        let files = FileWorker::new(wake.clone());
        let edits = EditQueue::new(wake);
        let config = ConfigDir::from_env();
        // Until the first real scene arrives the editor shows an empty one-brick grid.
        let placeholder = Scene::empty(brickmap::GridDims::new(1, 1, 1)?, 1)?;
        let mut doc = Document::new(placeholder, History::with_budget(DEFAULT_BUDGET));
        let mut script_run = None;
        if let Some(path) = &options.script {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            let script = script::parse(&text).with_context(|| path.display().to_string())?;
            let folder = path.parent().map(Path::to_path_buf).unwrap_or_default();
            let (run, document) = ScriptRun::start(
                &script,
                &folder,
                &ReplayOptions {
                    workers: (options.workers > 0).then_some(options.workers),
                    out_dir: options
                        .capture
                        .as_ref()
                        .and_then(|c| c.parent())
                        .filter(|p| !p.as_os_str().is_empty())
                        .map(Path::to_path_buf),
                    device: options.device.clone(),
                    ..Default::default()
                },
            )?;
            doc = document;
            script_run = Some(LiveScript {
                script: Arc::new(script),
                run: Some(Box::new(run)),
                finished: false,
                capture: options.capture.clone(),
                captured_at: None,
            });
        }
        let view = scene_view(&doc.scene);
        let (settings, settings_error) = match config.settings::<ViewSettings>() {
            Ok(s) => (s, None),
            Err(e) => (
                ViewSettings::default(),
                Some(format!("{e:#}; using the defaults")),
            ),
        };
        let mut editor = Self {
            settings,
            panels: PanelState {
                recent: config.recent(),
                ..Default::default()
            },
            config,
            gfx: None,
            egui: egui::Context::default(),
            doc: Arc::new(RwLock::new(doc)),
            generation: 0,
            gpu_generation: 0,
            files,
            edits,
            backlog: Vec::new(),
            saves_waiting: Vec::new(),
            saved: Vec::new(),
            view,
            slots: Default::default(),
            mods: Mods::default(),
            drag: None,
            cursor: (0.0, 0.0),
            flying: HashSet::new(),
            last_tick: Instant::now(),
            moving_until: Instant::now(),
            spp_per_frame: 1,
            last_added: 0,
            pending: None,
            save_then: None,
            last_autosave: Instant::now(),
            awaiting_built_scene: false,
            pending_textures: Default::default(),
            title: String::new(),
            recovering: false,
            quitting: false,
            outcome: Ok(()),
            move_event: None,
            latency: None,
            frames: 0,
            fail_at_frame: std::env::var("VOXBRICK_TEST_GPU_FAILURE_AT_FRAME")
                .ok()
                .and_then(|v| v.parse().ok()),
            script: script_run,
            options,
        };
        editor.panels.errors.extend(settings_error);
        if editor.script.is_some() {
            // A script run is reproducible: the defaults, whatever the user saved.
            editor.settings = ViewSettings {
                target_spp: editor.options.capture_spp.max(1),
                ..ViewSettings::default()
            };
        } else {
            if let Some(recovery) = editor.config.pending_recovery() {
                editor.panels.recovery = Some(recovery);
            }
            match editor.options.file.clone() {
                Some(f) => editor.files.load(f, editor.options.workers),
                None => {
                    editor.awaiting_built_scene = true;
                    editor.files.build_default(editor.options.workers);
                }
            }
        }
        Ok(editor)
    }

    fn read(&self) -> std::sync::RwLockReadGuard<'_, Document> {
        self.doc.read().unwrap_or_else(|p| p.into_inner())
    }

    /// Saves on the file worker once the edits asked for before are applied (Ctrl+Z then
    /// Ctrl+S saves the undone scene).
    fn save_to(&mut self, path: PathBuf, autosave: bool) {
        if self.edits.busy() {
            self.saves_waiting.push((path, autosave));
        } else {
            self.files.save(&self.doc, path, autosave);
        }
    }

    /// Applies finished saves' bookkeeping (file, clean flag) to the document, unless
    /// another save is reading it right now (then next frame: the UI never waits).
    fn mark_saved(&mut self) {
        if self.saved.is_empty() {
            return;
        }
        let mut d = match self.doc.try_write() {
            Ok(d) => d,
            Err(std::sync::TryLockError::Poisoned(p)) => p.into_inner(),
            Err(std::sync::TryLockError::WouldBlock) => return,
        };
        for (path, revision) in self.saved.drain(..) {
            d.mark_saved(&path, revision);
        }
    }

    /// Queues a command on the edit thread (the UI never waits for the world's workers).
    fn execute(&mut self, command: Command) {
        self.edits.submit(&self.doc, Edit::Command(command));
    }

    /// What an edit on the edit thread did. A failed script step ends the run (non-zero,
    /// naming the step).
    fn edited(&mut self, edited: Edited) {
        self.edits.finished();
        match edited {
            Edited::Command(label, result) => {
                if let Err(e) = result {
                    self.panels.errors.push(format!("{label}: {e}"));
                }
            }
            Edited::Undo(result) | Edited::Redo(result) => {
                if let Err(e) = result {
                    self.panels.errors.push(e.to_string());
                }
            }
            Edited::ScriptStep {
                run,
                result,
                camera_changed,
            } => {
                if camera_changed {
                    let view = scene_view(&self.read().scene);
                    self.view = view;
                }
                if let Some(s) = &mut self.script {
                    s.run = Some(run);
                    match result {
                        Ok(Some(line)) => println!("{line}"),
                        Ok(None) => s.finished = true,
                        Err(e) => {
                            s.finished = true;
                            self.outcome = Err(e);
                            self.quitting = true;
                        }
                    }
                }
            }
        }
        self.refresh_stats();
    }

    fn refresh_stats(&mut self) {
        let text = scene_statistics(&self.read());
        self.panels.stats = text;
    }

    fn replace_document(&mut self, scene: Scene, path: Option<PathBuf>) {
        let mut doc = Document::new(scene, History::with_budget(DEFAULT_BUDGET));
        doc.folder = path
            .as_ref()
            .and_then(|p| p.parent())
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        let is_project = path.as_ref().is_some_and(|p| {
            crate::formats::Format::of(p).ok() == Some(crate::formats::Format::Project)
        });
        if let Some(p) = &path {
            let _ = self.config.add_recent(p);
            self.panels.recent = self.config.recent();
        }
        doc.path = path.filter(|_| is_project);
        self.view = scene_view(&doc.scene);
        self.doc = Arc::new(RwLock::new(doc));
        self.generation += 1;
        self.refresh_stats();
    }

    /// Runs `then` now, or asks about unsaved changes first.
    fn guard_unsaved(&mut self, then: Pending) {
        if self.read().dirty && self.script.is_none() {
            self.pending = Some(then);
            self.panels.asking_unsaved = true;
        } else {
            self.proceed(then);
        }
    }

    fn proceed(&mut self, then: Pending) {
        match then {
            Pending::Quit => self.quit_now(),
            Pending::Open(Some(p)) => self.files.load(p, self.options.workers),
            Pending::Open(None) => self.files.pick(Purpose::Open, self.folder(), None),
            Pending::New { size, terrain } => self.new_scene(size, terrain),
        }
    }

    fn new_scene(&mut self, size: (u32, u32, u32), terrain: bool) {
        // Built on a worker; it replaces the document like a default-scene build.
        self.awaiting_built_scene = true;
        self.files.build_new(size, terrain, self.options.workers);
    }

    fn folder(&self) -> Option<PathBuf> {
        self.read()
            .path
            .as_ref()
            .and_then(|p| p.parent())
            .map(Path::to_path_buf)
    }

    fn save(&mut self, as_new: bool) {
        let path = self.read().path.clone();
        match path.filter(|_| !as_new) {
            Some(p) => self.save_to(p, false),
            None => self
                .files
                .pick(Purpose::SaveAs, self.folder(), Some("scene.ron".into())),
        }
    }

    fn quit_now(&mut self) {
        self.config.remove_recovery();
        if self.script.is_none()
            && let Err(e) = self.config.save_settings(&self.settings)
        {
            eprintln!("voxbrick: {e:#}");
        }
        self.quitting = true;
    }

    fn action(&mut self, action: Action) {
        match action {
            Action::Undo => self.edits.submit(&self.doc, Edit::Undo),
            Action::Redo => self.edits.submit(&self.doc, Edit::Redo),
            Action::New => self.panels.new_open = true,
            Action::Open => self.guard_unsaved(Pending::Open(None)),
            Action::Save => self.save(false),
            Action::SaveAs => self.save(true),
            Action::Import => self.files.pick(Purpose::Import, self.folder(), None),
            Action::Export => {
                self.files
                    .pick(Purpose::Export, self.folder(), Some("scene.vox".into()))
            }
            Action::Frame => {
                let (min, max) = content_bounds(&self.read().scene);
                self.view.frame(min, max);
                self.moved();
            }
            Action::ToggleProjection => {
                let size = self.read().scene.world.dims().voxels().as_dvec3();
                self.view.toggle_projection(DVec3::ZERO, size);
                self.moved();
            }
            Action::StoreView(n) => self.slots[n as usize - 1] = Some(self.view.clone()),
            Action::RecallView(n) => {
                if let Some(v) = self.slots[n as usize - 1].clone() {
                    self.view = v;
                    self.moved();
                }
            }
            Action::Help => self.panels.help_open = !self.panels.help_open,
            Action::Quit => self.guard_unsaved(Pending::Quit),
        }
    }

    fn ui_event(&mut self, e: UiEvent) {
        match e {
            UiEvent::Action(a) => self.action(a),
            UiEvent::OpenRecent(p) => self.guard_unsaved(Pending::Open(Some(p))),
            UiEvent::SetSun(s) => self.execute(Command::SetSun(s)),
            UiEvent::SetSky(s) => self.execute(Command::SetSky(s)),
            UiEvent::SetSettings(s) => self.execute(Command::SetSettings(s)),
            // Reading and merging a file can take a while: on the worker.
            UiEvent::Import { path, offset } => self.execute(Command::ImportVox {
                path: path.display().to_string(),
                offset: glam::IVec3::from_array(offset),
            }),
            UiEvent::UseViewAsSceneCamera => {
                self.execute(Command::SetCamera(self.view.camera.clone()))
            }
            UiEvent::NewScene { size, terrain } => {
                self.guard_unsaved(Pending::New { size, terrain })
            }
            UiEvent::Unsaved(answer) => {
                self.panels.asking_unsaved = false;
                let Some(then) = self.pending.take() else {
                    return;
                };
                match answer {
                    UnsavedAnswer::Cancel => {}
                    UnsavedAnswer::Discard => self.proceed(then),
                    UnsavedAnswer::Save => {
                        self.save_then = Some(then);
                        self.save(false);
                    }
                }
            }
            UiEvent::Recover(yes) => {
                if let Some(p) = self.panels.recovery.take() {
                    if yes {
                        self.awaiting_built_scene = false;
                        self.files.load(p, self.options.workers);
                        self.recovering = true;
                    } else {
                        self.config.remove_recovery();
                    }
                }
            }
        }
    }

    fn file_done(&mut self, done: Done) {
        self.files.finished();
        match done {
            Done::Picked(purpose, Ok(Some(path))) => match purpose {
                Purpose::Open => self.files.load(path, self.options.workers),
                Purpose::SaveAs | Purpose::Export => {
                    let path = if purpose == Purpose::SaveAs && path.extension().is_none() {
                        path.with_extension("ron")
                    } else {
                        path
                    };
                    self.save_to(path, false)
                }
                // Asks for the offset first (the import dialog), then `ImportVox`.
                Purpose::Import => self.panels.import = Some((path, [0, 0, 0])),
            },
            Done::Picked(_, Ok(None)) => self.save_then = None,
            Done::Picked(Purpose::SaveAs, Err(e)) => {
                // Nothing is lost for want of a dialog: save beside the home folder.
                let home =
                    std::env::var_os("HOME").map_or_else(|| PathBuf::from("."), PathBuf::from);
                let path = files::fallback_path(&home, "voxbrick-untitled", "ron");
                self.panels
                    .errors
                    .push(format!("{e}; saving to {} instead", path.display()));
                self.save_to(path, false);
            }
            Done::Picked(_, Err(e)) => {
                self.save_then = None;
                self.panels.errors.push(format!(
                    "{e}; open a file by dropping it onto the window or naming it on the command line"
                ));
            }
            Done::Loaded(path, loaded) => match *loaded {
                Ok(scene) => {
                    if self.awaiting_built_scene && path.is_some() {
                        // A file opened while the default scene was building wins.
                        self.awaiting_built_scene = false;
                    }
                    if path.is_none() && !self.awaiting_built_scene {
                        return;
                    }
                    self.awaiting_built_scene = false;
                    let recovered = std::mem::take(&mut self.recovering);
                    self.replace_document(scene, path.filter(|_| !recovered));
                    if recovered {
                        if let Ok(mut d) = self.doc.write() {
                            d.dirty = true;
                        }
                        self.config.remove_recovery();
                    }
                }
                Err(e) => {
                    self.awaiting_built_scene = false;
                    self.panels.errors.push(format!("{e:#}"));
                }
            },
            Done::Saved {
                path,
                autosave,
                revision,
                result,
            } => match result {
                Ok(()) if autosave => {}
                Ok(()) => {
                    self.saved.push((path.clone(), revision));
                    self.mark_saved();
                    let _ = self.config.add_recent(&path);
                    self.panels.recent = self.config.recent();
                    if let Some(then) = self.save_then.take() {
                        self.proceed(then);
                    }
                }
                Err(e) => {
                    self.save_then = None;
                    self.panels.errors.push(format!("{e:#}"));
                }
            },
        }
    }

    fn moved(&mut self) {
        self.moving_until = Instant::now() + Duration::from_millis(150);
        self.move_event.get_or_insert_with(Instant::now);
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }

    fn aspect(&self) -> f64 {
        self.gfx.as_ref().map_or(16.0 / 9.0, |g| {
            let s = g.window.inner_size();
            s.width.max(1) as f64 / s.height.max(1) as f64
        })
    }

    /// Normalized device coordinates of the cursor (v up).
    fn cursor_ndc(&self) -> (f64, f64) {
        let Some(g) = &self.gfx else {
            return (0.0, 0.0);
        };
        let s = g.window.inner_size();
        (
            2.0 * self.cursor.0 / s.width.max(1) as f64 - 1.0,
            1.0 - 2.0 * self.cursor.1 / s.height.max(1) as f64,
        )
    }

    fn zoom(&mut self, steps: f64) {
        let aspect = self.aspect();
        let (u, v) = self.cursor_ndc();
        let (origin, dir) = self.view.ray(u, v, aspect);
        let ray = brickmap::Ray { origin, dir };
        // The surface under the cursor (exact CPU cast), else the pivot plane.
        let hit = self
            .read()
            .scene
            .world
            .read()
            .ray_cast(&ray, f64::INFINITY)
            .ok()
            .flatten();
        let target = match hit {
            Some((h, _)) => ray.origin + dir * h.t,
            None => self.view.pivot_plane_point(u, v, aspect),
        };
        self.view.zoom_towards(target, 0.85f64.powf(steps));
        self.moved();
    }

    fn tick_fly(&mut self) {
        let now = Instant::now();
        let dt = (now - self.last_tick).as_secs_f64().min(0.1);
        self.last_tick = now;
        if self.flying.is_empty() {
            return;
        }
        let dir: DVec3 = self.flying.iter().filter_map(|k| input::fly_axis(*k)).sum();
        let speed = self.view.distance.max(8.0) * if self.mods.shift { 2.0 } else { 0.5 };
        self.view.fly(dir * speed * dt);
        self.moved();
    }

    fn create_gfx(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let (w, h) = self.options.size;
        let attrs = Window::default_attributes()
            .with_title("voxbrick")
            .with_inner_size(winit::dpi::PhysicalSize::new(w.max(64), h.max(64)));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .context("creating the window")?,
        );
        let handles = WindowHandles {
            display: window.display_handle().context("display handle")?.as_raw(),
            window: window.window_handle().context("window handle")?.as_raw(),
        };
        let ctx = GpuContext::new(&ContextOptions {
            device: crate::gpu::device_choice(&self.options.device),
            validation: self.options.validation,
            window: Some(handles),
            draw_ui: true,
        })
        .context("no Vulkan device can draw this window")?;
        let ctx = Arc::new(ctx);
        let size = window.inner_size();
        let presenter = Presenter::new(ctx.clone(), (size.width, size.height))?;
        let viewport = {
            let doc = self.read();
            let view = doc.scene.world.read();
            Viewport::new(ctx, &view)?
        };
        self.gpu_generation = self.generation;
        let egui_state = egui_winit::State::new(
            self.egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        self.gfx = Some(Gfx {
            presenter,
            viewport,
            egui_state,
            window,
        });
        self.refresh_stats();
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.outcome = Err(e);
        event_loop.exit();
    }

    /// One frame: script step, file results, egui, trace, present. Skipped (not waited
    /// for) while a command runs on the worker; its completion wakes the loop.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let gate = self.edits.gate.clone();
        let Ok(_frame) = gate.try_lock() else {
            return Ok(());
        };
        while let Ok(done) = self.files.done.try_recv() {
            self.file_done(done);
        }
        while let Ok(edited) = self.edits.done.try_recv() {
            self.edited(edited);
        }
        if !self.edits.busy() {
            for (path, autosave) in std::mem::take(&mut self.saves_waiting) {
                self.files.save(&self.doc, path, autosave);
            }
        }
        self.mark_saved();
        for event in std::mem::take(&mut self.backlog) {
            self.handle_window_event(event_loop, event);
        }
        self.tick_fly();
        self.step_script();
        self.autosave();
        let Some(mut gfx) = self.gfx.take() else {
            return Ok(());
        };
        let result = self.draw(&mut gfx, event_loop);
        self.gfx = Some(gfx);
        result
    }

    fn draw(&mut self, gfx: &mut Gfx, event_loop: &ActiveEventLoop) -> Result<()> {
        self.frames += 1;
        if self.fail_at_frame == Some(self.frames) {
            return Err(render::vulkan::GpuError::Vk {
                call: "vkQueueSubmit (simulated: VOXBRICK_TEST_GPU_FAILURE_AT_FRAME)",
                result: ash::vk::Result::ERROR_DEVICE_LOST,
            }
            .into());
        }
        if self.gpu_generation != self.generation {
            // A new document: a new GPU world on the same device (the old one goes first).
            let ctx = gfx.viewport.ctx().clone();
            let next = {
                let doc = self.read();
                let view = doc.scene.world.read();
                Viewport::new(ctx, &view)?
            };
            gfx.viewport = next;
            self.gpu_generation = self.generation;
        }
        let capture_now = self
            .script
            .as_ref()
            .is_some_and(|s| s.captured_at.is_none() && s.finished)
            && gfx.viewport.samples() >= self.settings.target_spp;
        // The status line and the panels.
        self.panels.busy = self.files.running.clone();
        self.panels.busy.extend(self.edits.pending.iter().cloned());
        let samples = gfx.viewport.samples();
        let gpu_ms = gfx.viewport.last_gpu_seconds().map_or(0.0, |s| s * 1e3);
        let size = gfx.window.inner_size();
        let internal = self.internal_size((size.width, size.height));
        let paths = internal.0 as f64 * internal.1 as f64 * self.last_added as f64;
        self.panels.status = format!(
            "{samples}/{} spp · GPU {gpu_ms:.2} ms/frame · {:.1} Mpaths/s · internal {}x{}{} · {}{}",
            self.settings.target_spp,
            if gpu_ms > 0.0 {
                paths / gpu_ms / 1e3
            } else {
                0.0
            },
            internal.0,
            internal.1,
            if self.view.camera.is_orthographic() {
                " · orthographic"
            } else {
                ""
            },
            gfx.viewport.ctx().name,
            self.latency.map_or_else(String::new, |l| format!(
                " · input to photon {:.1} ms",
                l.as_secs_f64() * 1e3
            )),
        );
        // The title only when it changes (each set is a round trip to the window system).
        let title = files::title(&self.read());
        if title != self.title {
            gfx.window.set_title(&title);
            self.title = title;
        }
        let raw = gfx.egui_state.take_egui_input(&gfx.window);
        let egui_ctx = self.egui.clone();
        let mut events = Vec::new();
        let output = {
            let doc = self.doc.clone();
            let doc = doc.read().unwrap_or_else(|p| p.into_inner());
            egui_ctx.run_ui(raw, |ui| {
                events = panels::draw(ui, &mut self.panels, &doc, &mut self.settings);
            })
        };
        for e in events {
            self.ui_event(e);
        }
        let egui::FullOutput {
            platform_output,
            textures_delta,
            shapes,
            pixels_per_point,
            viewport_output,
        } = output;
        gfx.egui_state
            .handle_platform_output(&gfx.window, platform_output);
        // Texture changes wait here until a frame with the UI applies them.
        self.pending_textures.append(textures_delta);
        let primitives = egui_ctx.tessellate(shapes, pixels_per_point);
        let moving = Instant::now() < self.moving_until;
        let internal = if moving {
            scaled(
                (size.width, size.height),
                self.settings.moving_scale.min(self.settings.internal_scale),
            )
        } else {
            internal
        };
        let doc = self.doc.clone();
        let doc = doc.read().unwrap_or_else(|p| p.into_inner());
        let mut params = doc.scene.params.clone();
        params.camera = self.view.camera.clone();
        let request = FrameRequest {
            params: &params,
            internal,
            output: (size.width, size.height),
            spp: self.spp_per_frame,
            target_spp: self.settings.target_spp,
            exposure: doc.scene.params.settings.exposure + self.settings.exposure,
            bgra: false,
        };
        let ui = (!capture_now).then(|| EguiFrame {
            primitives: &primitives,
            pixels_per_point,
            textures: &self.pending_textures,
        });
        let (presented, captured) = gfx.presenter.frame(
            &mut gfx.viewport,
            &doc.scene.world,
            &request,
            ui,
            capture_now,
        )?;
        drop(doc);
        match &presented {
            Presented::Shown(status) => {
                if !capture_now {
                    self.pending_textures.clear();
                }
                self.last_added = status.added;
                if let Some(t) = self.move_event.take() {
                    self.latency = Some(t.elapsed());
                }
                self.adapt_samples(gfx.viewport.last_gpu_seconds());
            }
            Presented::NotReady | Presented::Recreated => gfx.window.request_redraw(),
        }
        if let Some(c) = captured {
            self.finish_capture(gfx, c)?;
        }
        if let Some(s) = &self.script
            && let Some(at) = s.captured_at
            && at.elapsed() >= self.options.linger
        {
            let errors = gfx.viewport.ctx().validation_errors();
            if errors > 0 {
                anyhow::bail!("{errors} Vulkan validation errors");
            }
            event_loop.exit();
        }
        if self.quitting {
            event_loop.exit();
        }
        // Keep drawing while refining, moving, running a script or waiting for files.
        let busy = gfx.viewport.samples() < self.settings.target_spp
            || moving
            || !self.flying.is_empty()
            || self.script.is_some()
            || !self.files.running.is_empty()
            || self.edits.busy()
            || !self.saves_waiting.is_empty()
            || !self.saved.is_empty()
            || viewport_output.values().any(|v| v.repaint_delay.is_zero());
        if busy {
            gfx.window.request_redraw();
        }
        Ok(())
    }

    fn internal_size(&self, size: (u32, u32)) -> (u32, u32) {
        scaled(size, self.settings.internal_scale)
    }

    /// Samples per frame follow the GPU time: about 16 ms of tracing per frame.
    fn adapt_samples(&mut self, gpu: Option<f64>) {
        let Some(t) = gpu else { return };
        if t < 0.008 && self.spp_per_frame < 16 {
            self.spp_per_frame *= 2;
        } else if t > 0.033 && self.spp_per_frame > 1 {
            self.spp_per_frame /= 2;
        }
    }

    /// Runs the script's next step, one per frame, so the viewport shows each edit; a camera
    /// step resets the view to the scene camera (what the capture is compared against).
    /// Queues the script's next step on the edit thread (the same path as the UI's own
    /// edits), one at a time: the frame after a step shows it.
    fn step_script(&mut self) {
        let Some(s) = &mut self.script else {
            return;
        };
        if s.finished {
            return;
        }
        if let Some(run) = s.run.take() {
            self.edits
                .submit(&self.doc, Edit::ScriptStep(s.script.clone(), run));
        }
    }

    fn finish_capture(&mut self, gfx: &Gfx, c: render::present::Capture) -> Result<()> {
        let Some(s) = &mut self.script else {
            return Ok(());
        };
        s.captured_at = Some(Instant::now());
        if let Some(path) = &s.capture {
            let bytes: Vec<u8> = c.rgb.iter().flatten().copied().collect();
            crate::atomic::write_atomic(path, |w| {
                render::image::write_png_rgb8(w, c.width, c.height, &bytes)
            })
            .with_context(|| format!("writing {}", path.display()))?;
            println!(
                "captured {}x{} at {} spp to {}",
                c.width,
                c.height,
                gfx.viewport.samples(),
                path.display()
            );
        }
        Ok(())
    }

    fn autosave(&mut self) {
        let secs = self.settings.autosave_secs;
        if secs == 0
            || self.script.is_some()
            || self.last_autosave.elapsed() < Duration::from_secs(secs)
        {
            return;
        }
        self.last_autosave = Instant::now();
        if self.read().dirty {
            let recovery = self.config.recovery_file();
            self.save_to(recovery, true);
        }
    }
}

fn scaled((w, h): (u32, u32), f: f32) -> (u32, u32) {
    let f = f.clamp(0.05, 1.0) as f64;
    (
        ((w as f64 * f).ceil() as u32).max(1),
        ((h as f64 * f).ceil() as u32).max(1),
    )
}

/// The view of a scene: its camera exactly, orbiting the grid centre's depth.
fn scene_view(scene: &Scene) -> ViewCamera {
    let centre = scene.world.dims().voxels().as_dvec3() * 0.5;
    ViewCamera::for_scene(scene.params.camera.clone(), centre)
}

/// The box of the scene's solid content (the whole grid when empty).
fn content_bounds(scene: &Scene) -> (DVec3, DVec3) {
    let view = scene.world.read();
    match view.occupied_bounds() {
        Some((min, max)) => (min.as_dvec3(), max.as_dvec3()),
        None => (DVec3::ZERO, scene.world.dims().voxels().as_dvec3()),
    }
}

/// The statistics panel's text.
fn scene_statistics(doc: &Document) -> String {
    let view = doc.scene.world.read();
    let m = view.memory();
    let dims = doc.scene.world.dims().voxels();
    let solid = view.solid_count();
    let mut s = format!(
        "size         {} x {} x {} voxels\nsolid        {solid} voxels\nbricks       {} stored, {} full cells\nmaterials    {}\n\
         GPU memory   {:.1} MiB used\n  brick index {:.2} MiB\n  bricks      {:.2} MiB\n  coarse grid {:.2} MiB\n  materials   {:.2} MiB\n  tables      {} B\n",
        dims.x,
        dims.y,
        dims.z,
        view.brick_count(),
        m.full_cells,
        view.materials().len(),
        m.gpu_used() as f64 / 1048576.0,
        m.brick_index as f64 / 1048576.0,
        m.bricks_used as f64 / 1048576.0,
        m.coarse as f64 / 1048576.0,
        m.material_used as f64 / 1048576.0,
        m.tables
    );
    if solid > 0 {
        s += &format!(
            "per voxel    {:.4} B per solid voxel\n",
            m.gpu_used() as f64 / solid as f64
        );
    }
    s += &format!(
        "history      {} steps ({:.1} MiB), {} oldest dropped",
        doc.history.undo_len(),
        doc.history.bytes() as f64 / 1048576.0,
        doc.history.dropped()
    );
    s
}

impl ApplicationHandler<Wake> for Editor {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none()
            && let Err(e) = self.create_gfx(event_loop)
        {
            self.fail(event_loop, e);
            return;
        }
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }

    fn user_event(&mut self, _event_loop: &ActiveEventLoop, _event: Wake) {
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        // While an edit holds the frame gate, input (which may read the document) waits in
        // the backlog, in order, for the next frame; redraws skip themselves (see `redraw`).
        let gate = self.edits.gate.clone();
        let _between_frames = match &event {
            WindowEvent::RedrawRequested | WindowEvent::Resized(_) => None,
            _ => match gate.try_lock() {
                Ok(g) => Some(g),
                Err(_) => {
                    self.backlog.push(event);
                    return;
                }
            },
        };
        if _between_frames.is_some() {
            for earlier in std::mem::take(&mut self.backlog) {
                self.handle_window_event(event_loop, earlier);
            }
        }
        self.handle_window_event(event_loop, event);
    }
    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        event_loop.set_control_flow(ControlFlow::Wait);
        if self.settings.autosave_secs > 0 && self.script.is_none() {
            event_loop.set_control_flow(ControlFlow::WaitUntil(
                self.last_autosave + Duration::from_secs(self.settings.autosave_secs),
            ));
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        // Drop the GPU objects before the window goes.
        self.gfx = None;
    }
}

impl Editor {
    /// One window event, the frame gate held (or not needed: redraw, resize).
    fn handle_window_event(&mut self, event_loop: &ActiveEventLoop, event: WindowEvent) {
        let Some(gfx) = &mut self.gfx else { return };
        let response = gfx.egui_state.on_window_event(&gfx.window, &event);
        // egui-winit asks to repaint after every RedrawRequested too; honouring that would
        // keep a converged editor drawing forever.
        if response.repaint && !matches!(event, WindowEvent::RedrawRequested) {
            gfx.window.request_redraw();
        }
        let consumed = response.consumed;
        match event {
            WindowEvent::CloseRequested => self.action(Action::Quit),
            WindowEvent::Resized(size) => {
                gfx.presenter.resize((size.width, size.height));
                gfx.window.request_redraw();
            }
            WindowEvent::ScaleFactorChanged { .. } => gfx.window.request_redraw(),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.gpu_failed(event_loop, e);
                }
            }
            WindowEvent::DroppedFile(path) => {
                if path
                    .extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("vox") || e.eq_ignore_ascii_case("ron"))
                {
                    self.guard_unsaved(Pending::Open(Some(path)));
                } else {
                    self.panels
                        .errors
                        .push(format!("{} is not a .ron or .vox file", path.display()));
                }
            }
            WindowEvent::ModifiersChanged(m) => {
                let s = m.state();
                self.mods = Mods {
                    ctrl: s.control_key() || s.super_key(),
                    shift: s.shift_key(),
                    alt: s.alt_key(),
                };
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                let pressed = event.state == ElementState::Pressed;
                if !pressed {
                    self.flying.remove(&code);
                    return;
                }
                if consumed || self.egui.egui_wants_keyboard_input() {
                    return;
                }
                if let Some(a) = input::action_for_key(code, self.mods) {
                    if !event.repeat {
                        self.action(a);
                    }
                } else if !self.mods.ctrl && input::fly_axis(code).is_some() {
                    self.last_tick = Instant::now();
                    self.flying.insert(code);
                    self.moved();
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                if state == ElementState::Pressed
                    && !consumed
                    && !self.egui.egui_wants_pointer_input()
                {
                    self.drag = input::drag_for_button(button, self.mods).map(|d| (d, self.cursor));
                } else if state == ElementState::Released {
                    self.drag = None;
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let previous = self.cursor;
                self.cursor = (position.x, position.y);
                if let Some((drag, _)) = self.drag {
                    let h = gfx.window.inner_size().height.max(1) as f64;
                    let (dx, dy) = (self.cursor.0 - previous.0, self.cursor.1 - previous.1);
                    match drag {
                        Drag::Orbit => self.view.orbit(-dx * 0.3, -dy * 0.3),
                        Drag::Pan => {
                            let aspect = self.aspect();
                            self.view.pan(dx / h, -dy / h, aspect)
                        }
                    }
                    self.moved();
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                if consumed || self.egui.egui_wants_pointer_input() {
                    return;
                }
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                self.zoom(steps);
            }
            _ => {}
        }
    }

    /// A GPU error mid-session: say so; unsaved work goes to the recovery file at once
    /// (offered on the next start), then a dialog offers to save it as a project too (not
    /// in a script run: nobody is there to answer).
    fn gpu_failed(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        // The message itself is the run's error, printed once at exit.
        let message = format!("{e:#}");
        self.gfx = None;
        if self.read().dirty {
            let recovery = self.config.recovery_file();
            match std::fs::create_dir_all(self.config.0.as_path())
                .map_err(anyhow::Error::from)
                .and_then(|()| Ok(self.read().scene.save(&recovery)?))
            {
                Ok(()) => eprintln!(
                    "voxbrick: unsaved work is in {} (offered on the next start)",
                    recovery.display()
                ),
                Err(e) => eprintln!("voxbrick: writing {} failed: {e:#}", recovery.display()),
            }
            if self.script.is_none() {
                self.offer_save(&message);
            }
        } else if self.script.is_none() {
            rfd::MessageDialog::new()
                .set_level(rfd::MessageLevel::Error)
                .set_title("voxbrick: the GPU failed")
                .set_description(format!("{message}\n\nThe scene has no unsaved changes."))
                .set_buttons(rfd::MessageButtons::Ok)
                .show();
        }
        self.outcome = Err(anyhow!("the GPU failed: {message}"));
        event_loop.exit();
    }

    /// After a GPU failure: "save the scene?", to its file or one the user picks.
    fn offer_save(&mut self, message: &str) {
        let answer = rfd::MessageDialog::new()
            .set_level(rfd::MessageLevel::Error)
            .set_title("voxbrick: the GPU failed")
            .set_description(format!(
                "{message}\n\nYour work is in the recovery file. Save the scene as well?"
            ))
            .set_buttons(rfd::MessageButtons::YesNo)
            .show();
        if answer != rfd::MessageDialogResult::Yes {
            return;
        }
        let path = self.read().path.clone().or_else(|| {
            rfd::FileDialog::new()
                .add_filter("voxbrick project", &["ron"])
                .save_file()
        });
        if let Some(path) = path {
            match self.read().scene.save(&path) {
                Ok(()) => eprintln!("voxbrick: saved {}", path.display()),
                Err(e) => eprintln!("voxbrick: saving {} failed: {e}", path.display()),
            }
        }
    }
}

impl Drop for Editor {
    fn drop(&mut self) {
        self.gfx = None;
        self.pending_textures.clear();
    }
}
