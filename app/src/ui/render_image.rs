//! File → Render image…: the finished render's options (kept in the view settings), the
//! job that renders on a thread of its own while the editor stays usable, and its progress
//! window with the time left and Cancel.
//!
//! The job copies the scene when it starts (the project text, read under the document's
//! read lock as a save reads it) and renders the copy on a GPU session of its own on the
//! editor's device (`app::gpu::session`: its own queue, so the viewport's frames and the
//! render's batches never share one); edits made meanwhile are not in the picture.

use super::intent::UiEvent;
use crate::formats::picture::PictureFormat;
use crate::picture::{Preset, Rendered, Shot, content_bounds, render_shots};
use render::finished::{Finish, Stop};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
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

/// What the job's thread shares with the editor.
#[derive(Default)]
struct Shared {
    /// Part done and seconds left.
    progress: (f64, Option<f64>),
    /// The outcome, once there is one.
    outcome: Option<Result<Vec<Rendered>, String>>,
}

/// A render under way.
pub struct RenderTask {
    /// The file it writes.
    pub path: PathBuf,
    shared: Arc<Mutex<Shared>>,
    cancel: Arc<AtomicBool>,
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
    ) -> Self {
        let shared = Arc::new(Mutex::new(Shared::default()));
        let cancel = Arc::new(AtomicBool::new(false));
        let (s, c, o, p) = (
            shared.clone(),
            cancel.clone(),
            options.clone(),
            path.clone(),
        );
        std::thread::spawn(move || {
            let outcome = run(&scene_text, camera, &o, &p, &device, &s, &c);
            s.lock().expect("render job state").outcome = Some(outcome);
        });
        Self {
            path,
            shared,
            cancel,
        }
    }

    /// Asks the job to stop (it ends at its next batch; nothing is written).
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// Part done (0..1) and seconds left.
    pub fn progress(&self) -> (f64, Option<f64>) {
        self.shared.lock().map_or((0.0, None), |s| s.progress)
    }

    /// The outcome once the job ended (taken once).
    pub fn take_outcome(&self) -> Option<Result<Vec<Rendered>, String>> {
        self.shared.lock().ok()?.outcome.take()
    }
}

fn run(
    scene_text: &str,
    camera: render::Camera,
    o: &RenderImageOptions,
    path: &std::path::Path,
    device: &str,
    shared: &Mutex<Shared>,
    cancel: &AtomicBool,
) -> Result<Vec<Rendered>, String> {
    let finish = o.finish();
    finish.validate().map_err(|e| e.to_string())?;
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get().min(4));
    let scene = crate::formats::project::from_bytes(scene_text.as_bytes(), path, workers)
        .map_err(|e| e.to_string())?;
    let view = scene.world.read();
    let mut params = scene.params.clone();
    let aspect = o.size.0 as f64 / o.size.1 as f64;
    params.camera = o.preset.camera(&camera, content_bounds(&view), aspect);
    let mut session = crate::gpu::session(device, &view).map_err(|e| format!("{e:#}"))?;
    let shots = [Shot {
        params,
        out: path.to_path_buf(),
    }];
    render_shots(&mut session, &view, &shots, &finish, o.format, &mut |p| {
        if let Ok(mut s) = shared.lock() {
            s.progress = (p.done, p.remaining());
        }
        !cancel.load(Ordering::Relaxed)
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
        let (done, left) = t.progress();
        egui::Window::new("Rendering")
            .collapsible(false)
            .resizable(false)
            .show(ctx, |ui| {
                ui.label(format!("{}", t.path.display()));
                ui.add(egui::ProgressBar::new(done as f32).show_percentage());
                ui.label(left.map_or("estimating the time left…".to_string(), |s| {
                    format!("about {} left", seconds(s))
                }));
                if ui.button("Cancel").clicked() {
                    t.cancel();
                }
            });
        ctx.request_repaint_after(std::time::Duration::from_millis(250));
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

/// Seconds as `1 h 2 min`, `3 min 4 s` or `5 s`.
fn seconds(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {} s", s / 60, s % 60),
        _ => format!("{} h {} min", s / 3600, s % 3600 / 60),
    }
}
