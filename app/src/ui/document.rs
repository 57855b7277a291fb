//! The editor's document side: edits queued on the edit thread and what they report, files
//! (open, save, save as, new, import, export, autosave, recovery) and their results, the
//! unsaved-changes question, quitting, and a GPU failure's rescue of unsaved work.

use super::files::Done;
use super::jobs::{Edit, Edited};
use super::pending::Pending;
use super::purpose::Purpose;
use super::{Editor, scene_view};
use crate::Scene;
use crate::editor::Document;
use crate::editor::command::Command;
use crate::editor::history::{DEFAULT_BUDGET, History};
use crate::editor::script;
use anyhow::{Result, anyhow};
use std::path::{Path, PathBuf};

impl Editor {
    pub(super) fn read(&self) -> std::sync::RwLockReadGuard<'_, Document> {
        self.docs.read()
    }

    /// Queues a command on the edit thread (the UI never waits for the world's workers).
    pub(super) fn execute(&mut self, command: Command) {
        self.docs.submit(Edit::Command(command));
    }

    /// What an edit on the edit thread did. A failed script step ends the run (non-zero,
    /// naming the step).
    pub(super) fn edited(&mut self, edited: Edited) {
        self.docs.edits.finished();
        match edited {
            Edited::Command(label, result, said) => {
                let outcome = match &result {
                    Ok(_) => "ok".to_string(),
                    Err(e) => format!("error {e}"),
                };
                self.report
                    .line(format_args!("edited command {label}: {outcome}"));
                match result {
                    Err(e) if e.is_no_op() => self.panels.notify(format!("{label}: {e}")),
                    Err(e) => self.panels.errors.push(format!("{label}: {e}")),
                    Ok(_) => {
                        if let Some(text) = said {
                            self.panels.notify(text);
                        }
                    }
                }
            }
            Edited::Undo(result) => self.history_done("Undid", result),
            Edited::Redo(result) => self.history_done("Redid", result),
            // A segment: the statistics (a walk over every cell) wait for the stroke's end.
            Edited::Stroke(Ok(None)) => {
                self.report.line(format_args!("edited stroke segment: ok"));
                return;
            }
            Edited::Stroke(Ok(Some(_))) => {
                self.report.line(format_args!("edited stroke end: ok"));
            }
            Edited::Stroke(Err(e)) => {
                self.report.line(format_args!("edited stroke: error {e}"));
                // The stroke is undone and closed: stop sending it segments.
                self.controls.pointer.drawing = None;
                self.panels.errors.push(format!("stroke: {e}"));
            }
            Edited::ScriptStep {
                run,
                result,
                camera_changed,
            } => {
                if camera_changed {
                    let view = scene_view(&self.read().scene);
                    self.viewing.camera = view;
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

    /// An undo or a redo done: said on the status line, as is one with nothing to do.
    fn history_done(&mut self, what: &str, result: Result<String, crate::editor::EditError>) {
        let outcome = match &result {
            Ok(label) => format!("ok {label}"),
            Err(e) => format!("error {e}"),
        };
        self.report.line(format_args!("edited history: {outcome}"));
        match result {
            Ok(label) => self.panels.notify(format!("{what} {label}")),
            Err(e) if e.is_no_op() => self.panels.notify(capitalized(&e.to_string())),
            Err(e) => self.panels.errors.push(e.to_string()),
        }
    }

    pub(super) fn refresh_stats(&mut self) {
        let text = scene_statistics(&self.read());
        self.panels.stats = text;
    }

    pub(super) fn replace_document(&mut self, mut scene: Scene, path: Option<PathBuf>) {
        // The clipboard outlives the document: copy in one scene, paste in the next.
        scene.clipboard = self.read().scene.clipboard.clone();
        self.controls.pointer.cancel_placing();
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
        if self.docs.recording.on() {
            doc.recorder = self.carry_recording(path.as_deref());
        }
        doc.path = path.filter(|_| is_project);
        self.viewing.camera = scene_view(&doc.scene);
        self.docs.replace(doc);
        self.refresh_stats();
    }

    /// The recorder for the next document (see [`recording::Recording::carry`]).
    fn carry_recording(&mut self, path: Option<&Path>) -> Option<script::Recorder> {
        let previous = (self.docs.generation() > 0).then(|| self.docs.write().recorder.take());
        self.docs
            .recording
            .carry(previous, path)
            .unwrap_or_else(|message| {
                self.panels.errors.push(message);
                None
            })
    }

    /// The session's recording so far (the document's, or the one a built scene ended).
    pub(super) fn recording_text(&self) -> Option<String> {
        self.docs.recording.text(self.read().recorder.as_ref())
    }

    /// Runs `then` now, or asks about unsaved changes first.
    pub(super) fn guard_unsaved(&mut self, then: Pending) {
        if self.read().dirty && self.script.is_none() {
            self.docs.waits.ask(then);
            self.panels.asking_unsaved = true;
        } else {
            self.proceed(then);
        }
    }

    pub(super) fn proceed(&mut self, then: Pending) {
        match then {
            Pending::Quit => self.quit_now(),
            Pending::Open(Some(p)) => self.docs.files.load(p, self.options.workers),
            Pending::Open(None) => self.docs.files.pick(Purpose::Open, self.folder(), None),
            Pending::New { size, terrain } => self.new_scene(size, terrain),
            Pending::Heightmap => self
                .docs
                .files
                .pick(Purpose::Heightmap, self.folder(), None),
        }
    }

    pub(super) fn new_scene(&mut self, size: (u32, u32, u32), terrain: bool) {
        // Built on a worker; it replaces the document like a default-scene build.
        self.docs.waits.building();
        self.docs
            .files
            .build_new(size, terrain, self.options.workers);
    }

    pub(super) fn folder(&self) -> Option<PathBuf> {
        self.read()
            .path
            .as_ref()
            .and_then(|p| p.parent())
            .map(Path::to_path_buf)
    }

    pub(super) fn save(&mut self, as_new: bool) {
        let path = self.read().path.clone();
        match path.filter(|_| !as_new) {
            Some(p) => self.docs.save_to(p, false),
            None => self
                .docs
                .files
                .pick(Purpose::SaveAs, self.folder(), Some("scene.ron".into())),
        }
    }

    pub(super) fn quit_now(&mut self) {
        self.config.remove_recovery();
        if self.script.is_none()
            && let Err(e) = self.config.save_settings(&self.settings)
        {
            eprintln!("voxbrick: {e:#}");
        }
        self.quitting = true;
    }

    /// A path the user chose (in a native dialog or the in-app browser) for `purpose`.
    pub(super) fn picked(&mut self, purpose: Purpose, path: PathBuf) {
        match purpose {
            Purpose::Open => self.docs.files.load(path, self.options.workers),
            Purpose::Heightmap => {
                // Built on a worker; it replaces the document like New.
                self.docs.waits.building();
                self.docs.files.load_heightmap(path, self.options.workers);
            }
            Purpose::SaveAs | Purpose::Export => {
                let path = if purpose == Purpose::SaveAs && path.extension().is_none() {
                    path.with_extension("ron")
                } else {
                    path
                };
                self.docs.save_to(path, false)
            }
            Purpose::ExportMesh => {
                let path = if path.extension().is_none() {
                    path.with_extension("glb")
                } else {
                    path
                };
                let options = self.settings.mesh_export.clone();
                let progress = std::sync::Arc::new(super::progress::TaskProgress::waking(
                    self.docs.files.waker(),
                ));
                self.docs.mesh_task = Some((path.clone(), progress.clone()));
                self.docs.export_mesh(path, options, progress)
            }
            // Asks for the offset first (the import dialog), then `ImportVox`.
            Purpose::Import => self.panels.import = Some((path, [0, 0, 0])),
            Purpose::LoadPalette => self.docs.files.load_palette(path),
            Purpose::RenderImage => self.start_render(path),
            Purpose::SavePalette => {
                let path = if path.extension().is_none() {
                    path.with_extension("png")
                } else {
                    path
                };
                let colours = {
                    let doc = self.read();
                    let table = doc.scene.world.materials();
                    (0..=255u8).map(|i| table.colour(i)).collect()
                };
                self.docs.files.save_palette(colours, path);
            }
        }
    }

    /// Starts File → Render image…'s job writing `path` (its extension made the format's).
    fn start_render(&mut self, path: PathBuf) {
        let format = self.settings.render_image.format;
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        let path = if ext.eq_ignore_ascii_case(format.extension()) {
            path
        } else {
            path.with_extension(format.extension())
        };
        let text = crate::formats::project::to_string(&self.read().scene);
        let device = self
            .screen
            .gfx
            .as_ref()
            .map_or_else(|| "gpu".to_string(), |g| g.viewport.ctx().name.clone());
        self.report
            .line(format_args!("rendering image {}", path.display()));
        self.docs.render_task = Some(super::render_image::RenderTask::start(
            text,
            self.viewing.camera.camera.clone(),
            &self.settings.render_image,
            path,
            device,
            self.docs.files.waker(),
        ));
    }

    /// Takes File → Render image…'s outcome once its job ended.
    pub(super) fn render_finished(&mut self) {
        let Some(outcome) = self
            .docs
            .render_task
            .as_ref()
            .and_then(|t| t.take_outcome())
        else {
            return;
        };
        let task = self.docs.render_task.take().expect("a task");
        let path = task.path;
        if outcome.is_err() && task.progress.cancelled() {
            self.report
                .line(format_args!("render cancelled {}", path.display()));
            self.panels
                .notify(format!("Render cancelled: {} not written", path.display()));
            return;
        }
        match outcome {
            Ok(done) => {
                self.report
                    .line(format_args!("rendered image {}", path.display()));
                let spp = done.first().map_or(0, |r| r.samples.1);
                let what = match done.len() {
                    1 => path.display().to_string(),
                    n => format!("{n} pictures from {}", path.display()),
                };
                self.panels.notify(format!("Rendered {what} ({spp} spp)"));
            }
            Err(e) => {
                self.report
                    .line(format_args!("render failed {}: {e}", path.display()));
                self.panels
                    .errors
                    .push(format!("Rendering {}: {e}", path.display()));
            }
        }
    }

    pub(super) fn file_done(&mut self, done: Done) {
        self.docs.files.finished();
        match done {
            Done::Picked(purpose, Some(path)) => self.picked(purpose, path),
            Done::Palette(Ok(colours)) => self.execute(Command::SetPalette(colours)),
            Done::Palette(Err(e)) => self.panels.errors.push(format!("{e:#}")),
            Done::PaletteSaved(_, Ok(())) => {}
            Done::MeshExported(path, Err(e))
                if matches!(
                    e.downcast_ref::<crate::formats::FormatError>(),
                    Some(crate::formats::FormatError::Cancelled { .. })
                ) =>
            {
                self.docs.mesh_task = None;
                self.report
                    .line(format_args!("mesh export cancelled {}", path.display()));
                self.panels.notify(format!(
                    "Mesh export cancelled: {} not written",
                    path.display()
                ));
            }
            Done::MeshExported(path, Ok(stats)) => {
                self.docs.mesh_task = None;
                self.report
                    .line(format_args!("exported mesh {}", path.display()));
                self.panels.notify(format!(
                    "Exported {} triangles ({} parts) to {}",
                    stats.triangles,
                    stats.parts,
                    path.display()
                ));
            }
            Done::MeshExported(_, Err(e)) => {
                self.docs.mesh_task = None;
                self.panels.errors.push(format!("Could not export {e:#}"))
            }
            Done::PaletteSaved(path, Err(e)) => self
                .panels
                .errors
                .push(format!("writing {}: {e:#}", path.display())),
            Done::Picked(_, None) => self.docs.waits.save_abandoned(),
            // No native dialog: the in-app browser asks (nothing is written meanwhile).
            Done::NoDialog {
                purpose,
                folder,
                name,
            } => {
                let places = {
                    let doc = self.read();
                    let folder = doc
                        .path
                        .as_ref()
                        .and_then(|p| p.parent())
                        .map(Path::to_path_buf);
                    super::browser::places(folder.as_deref(), &self.panels.recent)
                };
                let browser = super::browser::Browser::new(purpose, folder, name);
                self.panels.browser = Some((browser, places));
            }
            Done::Loaded(path, loaded) => match *loaded {
                Ok(scene) => {
                    // A file opened while the default scene was building wins.
                    let Some(recovered) = self.docs.waits.arrived(path.is_some()) else {
                        return;
                    };
                    if self.report.on() {
                        let what = match (&path, recovered) {
                            (Some(_), true) => "recovery".to_string(),
                            (Some(p), false) => p.display().to_string(),
                            (None, _) => "default scene".to_string(),
                        };
                        let hash = scene.world.read().content_hash();
                        self.report
                            .line(format_args!("loaded {what} hash {hash:016x}"));
                    }
                    self.replace_document(scene, path.filter(|_| !recovered));
                    if recovered {
                        self.docs.write().dirty = true;
                        self.config.remove_recovery();
                    }
                }
                Err(e) => {
                    self.docs.waits.load_failed();
                    self.panels.errors.push(format!("{e:#}"));
                }
            },
            Done::Saved {
                path,
                autosave,
                revision,
                result,
            } => match result {
                Ok(()) if autosave => {
                    self.report
                        .line(format_args!("autosaved {}", path.display()));
                }
                Ok(()) => {
                    self.report.line(format_args!("saved {}", path.display()));
                    self.panels.notify(format!("Saved {}", path.display()));
                    self.docs.saves.finished(path.clone(), revision);
                    self.docs.mark_saved();
                    let _ = self.config.add_recent(&path);
                    self.panels.recent = self.config.recent();
                    if let Some(then) = self.docs.waits.saved() {
                        self.proceed(then);
                    }
                }
                Err(e) => {
                    self.docs.waits.save_abandoned();
                    self.panels.errors.push(format!("{e:#}"));
                }
            },
        }
    }

    pub(super) fn autosave(&mut self) {
        if self.script.is_some() || !self.docs.saves.autosave_due(self.settings.autosave_secs) {
            return;
        }
        if self.read().dirty {
            let recovery = self.config.recovery_file();
            self.docs.save_to(recovery, true);
        }
    }

    /// A GPU error mid-session: say so; unsaved work goes to the recovery file at once
    /// (offered on the next start), then a dialog offers to save it as a project too (not
    /// in a script run: nobody is there to answer).
    pub(super) fn gpu_failed(&mut self, e: anyhow::Error) {
        // The message itself is the run's error, printed once at exit.
        let message = format!("{e:#}");
        self.screen.gfx = None;
        if self.read().dirty {
            let recovery = self.config.recovery_file();
            match std::fs::create_dir_all(self.config.0.as_path())
                .map_err(anyhow::Error::from)
                .and_then(|()| Ok(crate::formats::save(&self.read().scene, &recovery)?))
            {
                Ok(()) => eprintln!(
                    "voxbrick: unsaved work is in {} (offered on the next start)",
                    recovery.display()
                ),
                Err(e) => eprintln!("voxbrick: writing {} failed: {e:#}", recovery.display()),
            }
            if self.script.is_none() && !self.screen.headless() {
                self.offer_save(&message);
            }
        } else if self.script.is_none() && !self.screen.headless() {
            rfd::MessageDialog::new()
                .set_level(rfd::MessageLevel::Error)
                .set_title("voxbrick: the GPU failed")
                .set_description(format!("{message}\n\nThe scene has no unsaved changes."))
                .set_buttons(rfd::MessageButtons::Ok)
                .show();
        }
        self.outcome = Err(anyhow!("the GPU failed: {message}"));
        self.exit = true;
    }

    /// After a GPU failure: "save the scene?", to its file or one the user picks.
    pub(super) fn offer_save(&mut self, message: &str) {
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
            match crate::formats::save(&self.read().scene, &path) {
                Ok(()) => eprintln!("voxbrick: saved {}", path.display()),
                Err(e) => eprintln!("voxbrick: saving {} failed: {e}", path.display()),
            }
        }
    }

    /// With `--record`: the session's script, starting from the file opened (atomic write).
    pub(super) fn write_recording(&mut self) -> Result<()> {
        self.docs.recording.write(self.read().recorder.as_ref())
    }
}

/// The statistics panel's text.
pub(super) fn scene_statistics(doc: &Document) -> String {
    let view = doc.scene.world.read();
    let m = view.memory();
    let dims = doc.scene.world.dims().voxels();
    let solid = view.solid_count();
    let mut s = format!(
        "size         {} x {} x {} voxels\nsolid        {solid} voxels\nbricks       {} stored, {} full cells\nmaterials    {}\nlights       {} emissive faces\n\
         GPU memory   {:.1} MiB used\n  brick index {:.2} MiB\n  bricks      {:.2} MiB\n  coarse grid {:.2} MiB\n  materials   {:.2} MiB\n  tables      {} B\n  lights      {} B\n",
        dims.x,
        dims.y,
        dims.z,
        view.brick_count(),
        m.full_cells,
        view.materials().len(),
        view.lights().len(),
        m.gpu_used() as f64 / 1048576.0,
        m.brick_index as f64 / 1048576.0,
        m.bricks_used as f64 / 1048576.0,
        m.coarse as f64 / 1048576.0,
        m.material_used as f64 / 1048576.0,
        m.tables,
        m.lights
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

/// `text` with its first letter a capital (an error's text as a sentence).
fn capitalized(text: &str) -> String {
    let mut c = text.chars();
    c.next()
        .map_or_else(String::new, |f| f.to_uppercase().chain(c).collect())
}
