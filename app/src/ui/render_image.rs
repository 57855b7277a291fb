//! File → Render image…: the finished render's options (kept in the view settings), the
//! job that renders on a thread of its own while the editor stays usable, and its progress
//! window with the time left and Cancel.
//!
//! The job copies the scene when it starts (the project text, read under the document's
//! read lock as a save reads it) and renders the copy on a GPU session of its own on the
//! editor's device (`app::gpu::session`: its own queue, so the viewport's frames and the
//! render's batches never share one); edits made meanwhile are not in the picture.

use super::intent::UiEvent;
use super::progress::TaskProgress;
use crate::formats::picture::PictureFormat;
use crate::picture::{Preset, Rendered, Shot, content_bounds, render_shots};
use render::finished::{Finish, Stop};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// The options of File → Render image….
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct RenderImageOptions {
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Samples per pixel (with a noise target: the most).
    pub samples: u32,
    /// Stop at a relative noise (else at the sample count).
    pub stop_at_noise: bool,
    /// The relative noise asked for.
    pub noise: f64,
    /// Filter the noise.
    pub denoise: bool,
    /// A transparent background (alpha = coverage).
    pub alpha: bool,
    /// The view.
    pub preset: Preset,
    /// The file's format.
    pub format: PictureFormat,
    /// A turntable of this many frames about the content's centre (0: one picture); the
    /// files are numbered from the chosen name.
    pub turntable: u32,
}

impl Default for RenderImageOptions {
    fn default() -> Self {
        Self {
            size: (1920, 1080),
            samples: 256,
            stop_at_noise: false,
            noise: 0.02,
            denoise: false,
            alpha: false,
            preset: Preset::Scene,
            format: PictureFormat::Png8,
            turntable: 0,
        }
    }
}

impl RenderImageOptions {
    /// The render these options ask for.
    pub fn finish(&self) -> Finish {
        Finish {
            size: self.size,
            stop: if self.stop_at_noise {
                Stop::Noise {
                    target: self.noise,
                    max: self.samples.max(2),
                }
            } else {
                Stop::Samples(self.samples)
            },
            denoise: self.denoise,
            alpha: self.alpha && self.format != PictureFormat::Pfm,
            seed: 1,
            tile: 2048,
        }
    }
}

/// How a render ended: the pictures written, or why not.
pub type Outcome = Result<Vec<Rendered>, String>;

/// A render under way.
pub struct RenderTask {
    /// The file it writes.
    pub path: PathBuf,
    /// Its progress and Cancel.
    pub progress: Arc<TaskProgress>,
    outcome: Arc<Mutex<Option<Outcome>>>,
}

impl RenderTask {
    /// Starts rendering `scene_text` (a project's text) through `camera` with `options`
    /// to `path` on the device named `device`.
    pub fn start(
        scene_text: String,
        camera: render::Camera,
        options: &RenderImageOptions,
        path: PathBuf,
        device: String,
        wake: Arc<dyn Fn() + Send + Sync>,
    ) -> Self {
        let progress = Arc::new(TaskProgress::waking(wake));
        let outcome = Arc::new(Mutex::new(None));
        let (p, out, o, file) = (
            progress.clone(),
            outcome.clone(),
            options.clone(),
            path.clone(),
        );
        std::thread::spawn(move || {
            let result = run(&scene_text, camera, &o, &file, &device, &p);
            if let Ok(mut slot) = out.lock() {
                *slot = Some(result);
            }
            p.wake();
        });
        Self {
            path,
            progress,
            outcome,
        }
    }

    /// The outcome once the job ended (taken once).
    pub fn take_outcome(&self) -> Option<Outcome> {
        self.outcome.lock().ok()?.take()
    }
}

fn run(
    scene_text: &str,
    camera: render::Camera,
    o: &RenderImageOptions,
    path: &std::path::Path,
    device: &str,
    progress: &TaskProgress,
) -> Result<Vec<Rendered>, String> {
    let finish = o.finish();
    finish.validate().map_err(|e| e.to_string())?;
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get().min(4));
    let scene = crate::formats::project::from_bytes(scene_text.as_bytes(), path, workers)
        .map_err(|e| e.to_string())?;
    let view = scene.world.read();
    let mut params = scene.params.clone();
    let aspect = o.size.0 as f64 / o.size.1 as f64;
    let bounds = content_bounds(&view);
    params.camera = o.preset.camera(&camera, bounds, aspect);
    let mut session = crate::gpu::session(device, &view).map_err(|e| format!("{e:#}"))?;
    let shots = match o.turntable {
        0 => vec![Shot {
            params,
            out: path.to_path_buf(),
        }],
        n => crate::picture::turntable(&params, (bounds.0 + bounds.1) * 0.5, n as usize, path),
    };
    render_shots(&mut session, &view, &shots, &finish, o.format, &mut |p| {
        progress.set(p.done)
    })
    .map_err(|e| e.to_string())
}

/// The Render image window (options, and Render… which asks where to write) and, while a
/// job runs, its progress with Cancel.
pub fn window(
    ctx: &egui::Context,
    open: &mut bool,
    o: &mut RenderImageOptions,
    task: Option<&RenderTask>,
) -> Option<UiEvent> {
    let mut event = None;
    if let Some(t) = task {
        super::progress::window(ctx, "Rendering", &t.path.display().to_string(), &t.progress);
    }
    if !*open {
        return None;
    }
    egui::Window::new("Render image")
        .open(open)
        .resizable(false)
        .show(ctx, |ui| {
            egui::Grid::new("render image")
                .num_columns(2)
                .show(ui, |ui| {
                    ui.label("size");
                    ui.horizontal(|ui| {
                        ui.add(egui::DragValue::new(&mut o.size.0).range(1..=16384));
                        ui.label("×");
                        ui.add(egui::DragValue::new(&mut o.size.1).range(1..=16384));
                    });
                    ui.end_row();
                    ui.label("view");
                    egui::ComboBox::from_id_salt("render view")
                        .selected_text(o.preset.name())
                        .show_ui(ui, |ui| {
                            for p in Preset::ALL {
                                ui.selectable_value(&mut o.preset, p, p.name());
                            }
                        });
                    ui.end_row();
                    ui.label("samples per pixel");
                    ui.add(egui::DragValue::new(&mut o.samples).range(1..=65536));
                    ui.end_row();
                    ui.checkbox(&mut o.stop_at_noise, "stop at noise");
                    ui.add_enabled(
                        o.stop_at_noise,
                        egui::DragValue::new(&mut o.noise)
                            .range(0.001..=0.5)
                            .speed(0.001),
                    )
                    .on_hover_text(
                        "relative noise of each tile (0.02: 2 %); the samples above are the most",
                    );
                    ui.end_row();
                    ui.checkbox(&mut o.denoise, "denoise");
                    ui.checkbox(&mut o.alpha, "transparent background");
                    ui.end_row();
                    ui.label("turntable frames");
                    ui.add(egui::DragValue::new(&mut o.turntable).range(0..=3600))
                        .on_hover_text("0: one picture; N: N pictures turning once about the content, numbered name_0000…");
                    ui.end_row();
                    ui.label("format");
                    egui::ComboBox::from_id_salt("render format")
                        .selected_text(o.format.label())
                        .show_ui(ui, |ui| {
                            for f in PictureFormat::ALL {
                                ui.selectable_value(&mut o.format, f, f.label());
                            }
                        });
                    ui.end_row();
                });
            if ui
                .add_enabled(task.is_none(), egui::Button::new("Render…"))
                .clicked()
            {
                event = Some(UiEvent::RenderImage);
            }
        });
    event
}
