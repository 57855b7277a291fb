//! The interactive editor: a winit window whose viewport is the live path tracer, with egui
//! panels on top. `run` owns the event loop; [`Editor`] is the application handler: input →
//! view camera or actions, the document shared with the file worker, one frame per redraw
//! through the GPU session ([`Viewport`]) and the window's [`Presenter`]. Progressive
//! refinement adds samples until the target, then the loop waits for events.
//!
//! In detail:
//! the editor: `run` owns the winit 0.30 event loop; `Editor` (ApplicationHandler) holds its
//! options and the session's end, and owned parts with narrow methods: `docs::Docs` (the
//! document as `Arc<RwLock<Document>>`, shared with the edit thread and the file worker;
//! every edit goes through `Docs::submit` to `jobs::EditQueue`, every save through
//! `Docs::save_to`), `controls::Controls` (key map, pointer, preview, fly keys, motion, the
//! input backlog, the UI's last use), `screen::Screen` (`Gfx`: presenter, viewport, `Host`;
//! the frames; egui), the panels and view settings, and `viewing::Viewing` (camera, stored
//! views, window and viewport area). Window events become `Input`s and go to `handle.rs`.
//! Refines until the target spp, then `ControlFlow::Wait`; internal resolution ×
//! `moving_scale` while a stroke is drawn and for 150 ms after a camera move or a stroke.
//! `--script` runs `ScriptRun` steps live and captures the presented frame at
//! `--capture-spp`. A GPU error mid-session: unsaved work to the recovery file at once, then a
//! native dialog (tested with `VOXBRICK_TEST_GPU_FAILURE_AT_FRAME`).

mod actions;
mod arranging;
mod browser;
mod budget;
pub mod camera;
mod controls;
mod dialog_tools;
mod docs;
mod document;
mod editing;
pub mod event;
mod extruding;
pub mod files;
mod flight;
mod frame;
mod handle;
mod headless;
mod host;
pub mod input;
mod intent;
pub mod jobs;
pub mod keymap;
mod measure;
mod motion;
mod object_menu;
pub mod outliner;
mod pacing;
mod paint_panel;
pub mod panels;
mod pending;
mod pointer;
mod preview;
pub mod progress;
pub mod purpose;
mod recording;
mod rect_selecting;
pub mod render_image;
pub mod report;
mod saves;
mod screen;
mod selecting;
mod selection_panel;
mod stamping;
mod status;
pub mod swatch;
pub mod tools;
mod viewing;

use crate::Scene;
use crate::editor::Document;
use crate::editor::history::{DEFAULT_BUDGET, History};
use crate::editor::script::{self, ReplayOptions, Script, ScriptRun};
use anyhow::{Context, Result, anyhow};
use camera::ViewCamera;
pub use event::Input;
use files::{ConfigDir, FileWorker};
use glam::DVec3;
use host::Host;
use jobs::EditQueue;
use panels::{PanelState, ViewSettings};
use screen::Gfx;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::WindowId;

/// How the editor starts.
#[derive(Clone, Debug, Default)]
pub struct EditorOptions {
    /// A file to open (.ron, .vox, .qb, .schem); None: the built-in default scene.
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
    /// Enable the validation layer (the editor exits non-zero on any validation error).
    pub validation: bool,
    /// Record the session's edits as a replay script starting from `file`, written here on
    /// exit (each file opened later is copied beside it and opened by an `Open` step).
    pub record: Option<PathBuf>,
    /// The configuration folder (settings, key map, recent files, recovery); None: from the
    /// environment (`ConfigDir::from_env`).
    pub config: Option<PathBuf>,
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
    let wake: Arc<dyn Fn() + Send + Sync> = Arc::new(move || {
        let _ = proxy.send_event(Wake);
    });
    let mut editor = Editor::new(options, wake, false)?;
    event_loop
        .run_app(&mut editor)
        .map_err(|e| anyhow!("event loop: {e}"))?;
    std::mem::replace(&mut editor.outcome, Ok(()))
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

/// The application handler: the session's options and lifecycle, and its owned parts.
pub struct Editor {
    options: EditorOptions,
    config: ConfigDir,
    /// The document, the edit queue, the file worker, saves and the long file jobs.
    docs: docs::Docs,
    /// The key map, the pointer, previews, fly keys, motion, input waiting for an edit.
    controls: controls::Controls,
    /// The GPU session and its host, the frames, egui.
    screen: screen::Screen,
    settings: ViewSettings,
    panels: PanelState,
    /// The view camera, the stored views, the window's size and the viewport's area.
    viewing: viewing::Viewing,
    script: Option<LiveScript>,
    quitting: bool,
    outcome: Result<()>,
    /// The handshake log (`VOXBRICK_REPORT`).
    report: report::Report,
    /// The editor asked to stop (the window loop exits; a headless driver is told).
    exit: bool,
}

impl Editor {
    fn new(
        options: EditorOptions,
        wake: Arc<dyn Fn() + Send + Sync>,
        headless: bool,
    ) -> Result<Self> {
        let recording =
            recording::Recording::start(options.record.as_deref(), options.file.as_deref())?;
        let mut files = FileWorker::new(wake.clone());
        files.dialogs = !headless;
        let wake_preview = wake.clone();
        let edits = EditQueue::new(wake);
        let config = options
            .config
            .clone()
            .map_or_else(ConfigDir::from_env, ConfigDir);
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
            docs: docs::Docs::new(doc, files, edits, recording),
            controls: controls::Controls::new(headless, wake_preview),
            screen: screen::Screen::new(headless),
            viewing: viewing::Viewing::new(view),
            quitting: false,
            outcome: Ok(()),
            report: report::Report::from_env(),
            script: script_run,
            options,
            exit: false,
        };
        editor.panels.errors.extend(settings_error);
        if editor.script.is_none() {
            editor.load_keys();
        }
        if editor.script.is_some() {
            // A script run is reproducible: the defaults, whatever the user saved.
            editor.settings = ViewSettings {
                target_spp: editor.options.capture_spp.max(1),
                ..ViewSettings::default()
            };
        } else {
            if let Some(recovery) = editor.config.pending_recovery() {
                editor
                    .report
                    .line(format_args!("offered recovery {}", recovery.display()));
                editor.panels.recovery = Some(recovery);
            }
            match editor.options.file.clone() {
                Some(f) => editor.docs.files.load(f, editor.options.workers),
                None => {
                    editor.docs.waits.building();
                    editor.docs.files.build_default(editor.options.workers);
                }
            }
        }
        Ok(editor)
    }

    fn moved(&mut self) {
        self.controls.motion.moved();
        self.request_redraw();
    }

    fn request_redraw(&mut self) {
        self.screen.request_redraw();
    }

    /// The viewport's aspect ratio.
    fn aspect(&self) -> f64 {
        self.viewing.aspect()
    }

    /// Normalized device coordinates of the cursor in the viewport (v up).
    fn cursor_ndc(&self) -> (f64, f64) {
        self.ndc(self.controls.pointer.cursor)
    }

    /// Normalized device coordinates of a window point in the viewport (v up).
    fn ndc(&self, p: (f64, f64)) -> (f64, f64) {
        self.viewing.ndc(p)
    }

    /// The cursor's ray.
    /// The key map: the settings' preset under keys.ron; the Shortcuts window lists it.
    fn load_keys(&mut self) {
        let (keymap, error) = self.config.keymap(self.settings.key_preset);
        self.controls.keymap = keymap;
        self.panels.errors.extend(error);
        self.panels.keys = self
            .controls
            .keymap
            .bindings()
            .iter()
            .map(|b| (b.keys.clone(), format!("{:?}", b.action)))
            .collect();
    }

    fn cursor_ray(&self) -> (DVec3, DVec3) {
        self.viewing.ray_at(self.controls.pointer.cursor)
    }
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

impl ApplicationHandler<Wake> for Editor {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.screen.gfx.is_none()
            && let Err(e) = self.create_gfx(event_loop)
        {
            self.outcome = Err(e);
            event_loop.exit();
            return;
        }
        self.request_redraw();
    }

    fn user_event(&mut self, _event_loop: &ActiveEventLoop, _event: Wake) {
        self.request_redraw();
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match &event {
            WindowEvent::RedrawRequested => {
                let began = Instant::now();
                if let Err(e) = self.redraw() {
                    self.gpu_failed(e);
                }
                if let Some(Gfx {
                    host: Host::Window { clock, .. },
                    ..
                }) = &mut self.screen.gfx
                {
                    clock.frame_ran(began);
                }
            }
            WindowEvent::ScaleFactorChanged { .. } => self.request_redraw(),
            _ => {
                let input = Input::from_window_event(&event);
                let tab = input
                    .as_ref()
                    .is_some_and(|i| i.kept_from(&self.screen.egui));
                let consumed = match &mut self.screen.gfx {
                    _ if tab => false,
                    Some(Gfx {
                        host:
                            Host::Window {
                                egui_state, window, ..
                            },
                        ..
                    }) => {
                        let response = egui_state.on_window_event(window, &event);
                        if response.repaint {
                            window.request_redraw();
                        }
                        response.consumed
                    }
                    _ => false,
                };
                if let Some(input) = input {
                    self.input_with(input, consumed);
                }
            }
        }
        if self.exit {
            event_loop.exit();
        }
    }

    fn new_events(&mut self, _event_loop: &ActiveEventLoop, cause: winit::event::StartCause) {
        // A long edit's progress, or refinement that waited while the UI was used.
        if matches!(cause, winit::event::StartCause::ResumeTimeReached { .. })
            && (self.docs.progress().is_some() || self.controls.ui_waiting())
        {
            self.request_redraw();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.exit {
            event_loop.exit();
        }
        event_loop.set_control_flow(ControlFlow::Wait);
        if self.docs.busy() {
            // An edit is running: look at a long one's progress ten times a second.
            event_loop.set_control_flow(ControlFlow::WaitUntil(
                Instant::now() + Duration::from_millis(100),
            ));
            return;
        }
        let mut wake: Option<Instant> = None;
        if self.script.is_none() {
            wake = self.docs.saves.next_autosave(self.settings.autosave_secs);
        }
        // Refinement resumes when the UI has been left alone for `UI_FIRST`.
        match self.controls.ui_wait(Instant::now()) {
            controls::UiWait::None => {}
            controls::UiWait::Until(resume) => wake = Some(wake.map_or(resume, |w| w.min(resume))),
            controls::UiWait::Ended => self.request_redraw(),
        }
        // A trace job in flight: look for its end soon (its image, or the next job).
        if let Some(t) = self.screen.frames.pump_at {
            if t <= Instant::now()
                && let Err(e) = self.pump_trace()
            {
                self.gpu_failed(e);
            }
            if let Some(t) = self.screen.frames.pump_at {
                wake = Some(wake.map_or(t, |w| w.min(t)));
            }
        }
        if let Some(w) = wake {
            event_loop.set_control_flow(ControlFlow::WaitUntil(w));
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.finish();
    }
}

impl Editor {
    /// The session ends: validation errors become the outcome, the GPU objects go before
    /// the window, the recording is written.
    fn finish(&mut self) {
        let errors = self.screen.validation_errors();
        if errors > 0 && self.outcome.is_ok() {
            self.outcome = Err(anyhow!("{errors} Vulkan validation errors"));
        }
        self.screen.release();
        if let Err(e) = self.write_recording() {
            eprintln!("voxbrick: {e:#}");
            if self.outcome.is_ok() {
                self.outcome = Err(e);
            }
        }
    }
}

impl Drop for Editor {
    fn drop(&mut self) {
        self.screen.release();
    }
}
