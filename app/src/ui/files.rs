//! Files, with nothing ever lost: the user's config folder (recent files, the recovery
//! file), and file work off the UI thread. Loads build a new scene on a worker thread and
//! hand it back; saves read the shared document under a read lock while the UI keeps
//! drawing (edits wait for the save); every write is atomic (temp file + rename), so a
//! failure leaves the file on disk, the scene and the history as they were.

use super::purpose::Purpose;
use crate::Scene;
use crate::editor::Document;
use anyhow::{Context, Result};
use crossbeam_channel::{Receiver, Sender};
use std::path::{Path, PathBuf};
use std::sync::{Arc, RwLock};

/// Recent files kept.
const RECENT: usize = 10;

/// The editor's folder in the user's config directory: `$VOXBRICK_CONFIG_DIR`, else
/// `$XDG_CONFIG_HOME/voxbrick`, else `~/.config/voxbrick`.
#[derive(Clone, Debug)]
pub struct ConfigDir(pub PathBuf);

impl ConfigDir {
    /// The folder from the environment (not created until something is written).
    pub fn from_env() -> Self {
        let env = |k| {
            std::env::var_os(k)
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
        };
        Self(
            env("VOXBRICK_CONFIG_DIR")
                .or_else(|| env("XDG_CONFIG_HOME").map(|p| p.join("voxbrick")))
                .or_else(|| env("HOME").map(|p| p.join(".config/voxbrick")))
                .unwrap_or_else(|| PathBuf::from(".voxbrick")),
        )
    }

    fn recent_file(&self) -> PathBuf {
        self.0.join("recent.ron")
    }

    /// The autosave target; it exists only while a session with unsaved changes runs (or
    /// after one crashed).
    pub fn recovery_file(&self) -> PathBuf {
        self.0.join("recovery.ron")
    }

    /// Recent files, newest first (a missing or unreadable list is empty).
    pub fn recent(&self) -> Vec<PathBuf> {
        std::fs::read_to_string(self.recent_file())
            .ok()
            .and_then(|t| ron::from_str::<Vec<PathBuf>>(&t).ok())
            .unwrap_or_default()
    }

    /// Puts `path` first in the recent list.
    pub fn add_recent(&self, path: &Path) -> Result<()> {
        let path = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        let mut list = self.recent();
        list.retain(|p| p != &path);
        list.insert(0, path);
        list.truncate(RECENT);
        std::fs::create_dir_all(&self.0)
            .with_context(|| format!("creating {}", self.0.display()))?;
        let text = ron::ser::to_string_pretty(&list, Default::default())?;
        crate::atomic::write_atomic(&self.recent_file(), |w| w.write_all(text.as_bytes()))
            .with_context(|| format!("writing {}", self.recent_file().display()))
    }

    fn settings_file(&self) -> PathBuf {
        self.0.join("settings.ron")
    }

    /// The saved view settings; defaults when there are none, and an error naming the file
    /// when it cannot be read (the defaults are then used and the file is left alone).
    pub fn settings<T: serde::de::DeserializeOwned + Default>(&self) -> Result<T> {
        let f = self.settings_file();
        match std::fs::read_to_string(&f) {
            Ok(text) => ron::from_str(&text).with_context(|| format!("reading {}", f.display())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(T::default()),
            Err(e) => Err(e).with_context(|| format!("reading {}", f.display())),
        }
    }

    /// The key map: keys.ron, written with the defaults when there is none (so the user
    /// has a file to edit). A broken file is an error naming it, and the defaults are used
    /// (the file is left alone).
    pub fn keymap(
        &self,
        preset: super::keymap::KeyPreset,
    ) -> (super::keymap::KeyMap, Option<String>) {
        use super::keymap::{KeyMap, default_bindings};
        let f = self.0.join("keys.ron");
        match std::fs::read_to_string(&f) {
            Ok(text) => match KeyMap::parse(&text, preset) {
                Ok(map) => (map, None),
                Err(e) => (
                    KeyMap::of(preset),
                    Some(format!("{}: {e}; using the default keys", f.display())),
                ),
            },
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                let text = KeyMap::to_ron(&default_bindings());
                let written = std::fs::create_dir_all(&self.0).and_then(|()| {
                    crate::atomic::write_atomic(&f, |w| w.write_all(text.as_bytes()))
                        .map_err(std::io::Error::other)
                });
                let note = written
                    .err()
                    .map(|e| format!("writing {}: {e}", f.display()));
                (KeyMap::of(preset), note)
            }
            Err(e) => (
                KeyMap::of(preset),
                Some(format!("reading {}: {e}", f.display())),
            ),
        }
    }

    /// Saves the view settings (atomically).
    pub fn save_settings<T: serde::Serialize>(&self, settings: &T) -> Result<()> {
        std::fs::create_dir_all(&self.0)
            .with_context(|| format!("creating {}", self.0.display()))?;
        let text = ron::ser::to_string_pretty(settings, Default::default())?;
        crate::atomic::write_atomic(&self.settings_file(), |w| w.write_all(text.as_bytes()))
            .with_context(|| format!("writing {}", self.settings_file().display()))
    }

    /// A recovery file left by a session that did not exit cleanly.
    pub fn pending_recovery(&self) -> Option<PathBuf> {
        let f = self.recovery_file();
        f.is_file().then_some(f)
    }

    /// Removes the recovery file (clean exit, or the user discarded it).
    pub fn remove_recovery(&self) {
        let _ = std::fs::remove_file(self.recovery_file());
    }
}

/// The document, shared with the file worker: the UI reads it every frame and writes it
/// for edits; a save reads it on the worker.
pub type SharedDocument = Arc<RwLock<Document>>;

/// A finished piece of background work.
pub enum Done {
    /// A file dialog closed (None: cancelled).
    Picked(Purpose, Option<PathBuf>),
    /// No native dialog could be shown: the in-app browser asks instead, starting in
    /// `folder` with `name` filled in.
    NoDialog {
        /// What the path is for.
        purpose: Purpose,
        /// Where to start.
        folder: Option<PathBuf>,
        /// The suggested file name.
        name: Option<String>,
    },
    /// A scene was loaded (or failed to) from a path, or built (the default scene: None).
    Loaded(Option<PathBuf>, Box<Result<Scene>>),
    /// A palette was read (or failed to).
    Palette(Result<Vec<[u8; 3]>>),
    /// The palette was written (or failed to).
    PaletteSaved(PathBuf, Result<()>),
    /// A mesh was exported (or failed to).
    MeshExported(PathBuf, Result<crate::formats::mesh::MeshStats>),
    /// A save finished; `autosave` saves go to the recovery file and don't clean the document.
    Saved {
        /// Where.
        path: PathBuf,
        /// Recovery autosave (the document stays dirty).
        autosave: bool,
        /// The document's revision that was written.
        revision: u64,
        /// The outcome.
        result: Result<()>,
    },
}

/// Background file work and its results.
pub struct FileWorker {
    done_tx: Sender<Done>,
    /// Results, polled by the frame loop.
    pub done: Receiver<Done>,
    /// Jobs running (for the progress indicator).
    pub running: Vec<String>,
    /// Whether native dialogs may be shown (false: a pick answers at once that no dialog
    /// can be shown, as on a machine without a portal).
    pub dialogs: bool,
    wake: Arc<dyn Fn() + Send + Sync>,
}

impl FileWorker {
    /// What wakes an idle editor (jobs of their own call it when they end).
    pub fn waker(&self) -> Arc<dyn Fn() + Send + Sync> {
        self.wake.clone()
    }

    /// A worker that calls `wake` when a job finishes (to redraw an idle editor).
    pub fn new(wake: Arc<dyn Fn() + Send + Sync>) -> Self {
        let (done_tx, done) = crossbeam_channel::unbounded();
        Self {
            done_tx,
            done,
            running: Vec::new(),
            dialogs: true,
            wake,
        }
    }

    fn spawn(&mut self, what: String, job: impl FnOnce() -> Done + Send + 'static) {
        let (tx, wake) = (self.done_tx.clone(), self.wake.clone());
        self.running.push(what);
        std::thread::spawn(move || {
            let _ = tx.send(job());
            wake();
        });
    }

    /// A native file dialog on its own thread (the frame loop never waits for it).
    pub fn pick(&mut self, purpose: Purpose, folder: Option<PathBuf>, name: Option<String>) {
        let label = format!("{purpose:?} dialog");
        let dialogs = self.dialogs;
        self.spawn(label, move || {
            let no_dialog = |folder, name| Done::NoDialog {
                purpose,
                folder,
                name,
            };
            if !dialogs {
                return no_dialog(folder, name);
            }
            let (what, exts) = purpose.filter();
            let mut d = rfd::FileDialog::new().add_filter(what, exts);
            if let Some(f) = &folder {
                d = d.set_directory(f);
            }
            if let Some(n) = &name {
                d = d.set_file_name(n);
            }
            let started = std::time::Instant::now();
            let saves = purpose.saves();
            let picked = if saves { d.save_file() } else { d.pick_file() };
            // rfd answers "cancelled" at once when no dialog can be shown (no
            // xdg-desktop-portal); nobody cancels a dialog that fast. Then zenity or
            // kdialog where one is installed, else the in-app browser.
            if picked.is_none() && started.elapsed() < std::time::Duration::from_millis(150) {
                return match super::dialog_tools::pick(purpose, folder.as_deref(), name.as_deref())
                {
                    Some(picked) => Done::Picked(purpose, picked),
                    None => no_dialog(folder, name),
                };
            }
            Done::Picked(purpose, picked)
        });
    }

    /// Loads a scene (.ron, .vox, .qb, .schem) on a worker thread.
    pub fn load(&mut self, path: PathBuf, workers: usize) {
        self.spawn(format!("opening {}", path.display()), move || {
            // The format's error names the file already.
            let scene = crate::formats::load(&path, workers)
                .map_err(|e| anyhow::anyhow!("Could not open {e}"));
            Done::Loaded(Some(path), Box::new(scene))
        });
    }

    /// Reads a palette on a worker thread.
    pub fn load_palette(&mut self, path: PathBuf) {
        self.spawn(format!("reading {}", path.display()), move || {
            Done::Palette(crate::formats::palette::load(&path).map_err(Into::into))
        });
    }

    /// Writes a palette on a worker thread.
    pub fn save_palette(&mut self, colours: Vec<[u8; 3]>, path: PathBuf) {
        self.spawn(format!("writing {}", path.display()), move || {
            let result = crate::formats::palette::save_png(&colours, &path).map_err(Into::into);
            Done::PaletteSaved(path, result)
        });
    }

    /// Writes the document's scene as a mesh (the format by the extension) on a worker
    /// thread, reading it under a read lock, telling `progress` how far it is and stopping
    /// (nothing written) when it is cancelled.
    pub fn export_mesh(
        &mut self,
        doc: &SharedDocument,
        path: PathBuf,
        options: crate::formats::mesh::MeshOptions,
        progress: std::sync::Arc<super::progress::TaskProgress>,
    ) {
        let doc = doc.clone();
        self.spawn(format!("exporting {}", path.display()), move || {
            let result = match doc.read() {
                Ok(d) => crate::formats::mesh::export_watched(&d.scene, &path, &options, &|f| {
                    progress.set(f)
                })
                .map_err(anyhow::Error::from),
                Err(_) => Err(anyhow::anyhow!("the document is unavailable")),
            };
            Done::MeshExported(path, result)
        });
    }

    /// Builds a new scene from a heightmap image (white 256 voxels tall) on a worker thread.
    pub fn load_heightmap(&mut self, path: PathBuf, workers: usize) {
        self.spawn(format!("reading {}", path.display()), move || {
            let scene = crate::builtin::heightmap_scene(&path, 256, workers)
                .map_err(|e| anyhow::anyhow!("Could not read the heightmap {e}"));
            Done::Loaded(None, Box::new(scene))
        });
    }

    /// Builds a new scene (`size` voxels, empty or with noise terrain) on a worker thread.
    pub fn build_new(&mut self, size: (u32, u32, u32), terrain: bool, workers: usize) {
        self.spawn(
            format!("building a {}x{}x{} scene", size.0, size.1, size.2),
            move || Done::Loaded(None, Box::new(new_scene(size, terrain, workers))),
        );
    }

    /// Builds the embedded default scene on a worker thread.
    pub fn build_default(&mut self, workers: usize) {
        self.spawn("building the default scene".into(), move || {
            let scene = crate::builtin::default_scene(crate::builtin::SceneSize::Full, workers);
            Done::Loaded(None, Box::new(scene))
        });
    }

    /// Saves the document's scene to `path` (project or .vox by extension) on a worker
    /// thread, reading it under a read lock.
    pub fn save(&mut self, doc: &SharedDocument, path: PathBuf, autosave: bool) {
        let doc = doc.clone();
        let what = if autosave {
            "autosaving".to_string()
        } else {
            format!("saving {}", path.display())
        };
        self.spawn(what, move || {
            let (result, revision) = match doc.read() {
                Ok(d) => (save_scene(&d.scene, &path, autosave), d.revision),
                Err(_) => (Err(anyhow::anyhow!("the document is unavailable")), 0),
            };
            Done::Saved {
                path,
                autosave,
                revision,
                result,
            }
        });
    }

    /// Marks one job finished (the caller got its result).
    pub fn finished(&mut self) {
        if !self.running.is_empty() {
            self.running.remove(0);
        }
    }
}

/// A new scene framed by its camera: empty, or noise terrain with water.
pub fn new_scene(size: (u32, u32, u32), terrain: bool, workers: usize) -> Result<Scene> {
    use crate::editor::command::{Command, TerrainSpec};
    let dims = brickmap::GridDims::from_voxels(glam::UVec3::new(size.0, size.1, size.2))?;
    let mut scene = Scene::empty(dims, workers)?;
    scene.params = render::SceneParams::framing(dims.voxels().as_dvec3());
    if terrain {
        let spec = TerrainSpec::for_size(size);
        Command::GenerateTerrain(spec).apply(&mut scene, Path::new("."))?;
    }
    Ok(scene)
}

fn save_scene(scene: &Scene, path: &Path, autosave: bool) -> Result<()> {
    if autosave && let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    // The format's error names the file already.
    crate::formats::save(scene, path)
        .map_err(|e| anyhow::anyhow!("Could not save {e}; pick another place with Save As"))
}

/// The window title: file name (or "untitled"), an unsaved-changes mark, the program.
pub fn title(doc: &Document) -> String {
    let name = doc.path.as_ref().and_then(|p| p.file_name()).map_or_else(
        || "untitled".to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    format!("{}{name} — voxbrick", if doc.dirty { "● " } else { "" })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::editor::command::Command;
    use crate::editor::history::History;
    use brickmap::GridDims;

    fn temp(name: &str) -> crate::scratch::Scratch {
        crate::scratch::Scratch::new(&format!("ui-{name}"))
    }

    fn doc() -> SharedDocument {
        let scene = Scene::empty(GridDims::new(2, 2, 2).unwrap(), 1).unwrap();
        Arc::new(RwLock::new(Document::new(
            scene,
            History::with_budget(1 << 20),
        )))
    }

    fn wait(w: &mut FileWorker) -> Done {
        let d = w
            .done
            .recv_timeout(std::time::Duration::from_secs(60))
            .unwrap();
        w.finished();
        d
    }

    #[test]
    fn recent_files_are_newest_first_without_duplicates() {
        let scratch = temp("recent");
        let dir = ConfigDir(scratch.to_path_buf());
        assert!(dir.recent().is_empty());
        for n in ["a.ron", "b.ron", "a.ron"] {
            dir.add_recent(&dir.0.join(n)).unwrap();
        }
        let names: Vec<_> = dir
            .recent()
            .iter()
            .map(|p| p.file_name().unwrap().to_owned())
            .collect();
        assert_eq!(names, ["a.ron", "b.ron"]);
    }

    #[test]
    fn view_settings_round_trip_and_a_broken_file_is_an_error_not_a_reset() {
        use crate::ui::panels::ViewSettings;
        let scratch = temp("settings");
        let dir = ConfigDir(scratch.join("config"));
        assert_eq!(
            dir.settings::<ViewSettings>().unwrap(),
            ViewSettings::default()
        );
        let s = ViewSettings {
            target_spp: 64,
            autosave_secs: 0,
            ..ViewSettings::default()
        };
        dir.save_settings(&s).unwrap();
        assert_eq!(dir.settings::<ViewSettings>().unwrap(), s);
        std::fs::write(dir.0.join("settings.ron"), b"(target_spp: \"many\")").unwrap();
        assert!(dir.settings::<ViewSettings>().is_err());
        // Fields missing from an older file take their defaults.
        std::fs::write(dir.0.join("settings.ron"), b"(exposure: 1.5)").unwrap();
        let partial = dir.settings::<ViewSettings>().unwrap();
        assert_eq!(
            (partial.exposure, partial.target_spp),
            (1.5, ViewSettings::default().target_spp)
        );
    }

    #[test]
    fn new_scenes_are_empty_or_terrain_and_framed() {
        let empty = new_scene((64, 32, 64), false, 1).unwrap();
        assert_eq!(empty.world.read().solid_count(), 0);
        let hills = new_scene((64, 32, 64), true, 1).unwrap();
        assert!(hills.world.read().solid_count() > 64 * 64);
        assert!(hills.params.validate().is_ok());
        assert!(new_scene((0, 32, 64), false, 1).is_err());
    }

    #[test]
    fn the_title_marks_unsaved_changes() {
        let d = doc();
        let mut d = d.write().unwrap();
        assert_eq!(title(&d), "untitled — voxbrick");
        d.execute(Command::Clear).unwrap();
        assert!(title(&d).starts_with("● untitled"));
    }

    #[test]
    fn recovery_is_written_offered_and_removed_and_a_save_cleans_the_document() {
        let scratch = temp("recovery");
        let dir = ConfigDir(scratch.join("config"));
        let d = doc();
        d.write().unwrap().execute(Command::Clear).unwrap();
        let mut w = FileWorker::new(Arc::new(|| {}));
        assert!(dir.pending_recovery().is_none());
        w.save(&d, dir.recovery_file(), true);
        let Done::Saved {
            result, autosave, ..
        } = wait(&mut w)
        else {
            panic!()
        };
        result.unwrap();
        assert!(autosave);
        // An autosave does not clean the document; the next start is offered the file.
        assert!(d.read().unwrap().dirty);
        let offered = dir.pending_recovery().expect("recovery offered");
        w.load(offered, 1);
        let Done::Loaded(_, scene) = wait(&mut w) else {
            panic!()
        };
        assert_eq!(
            scene.unwrap().world.read().content_hash(),
            d.read().unwrap().scene.world.read().content_hash()
        );
        dir.remove_recovery();
        assert!(dir.pending_recovery().is_none());
        // A real save, once finished, makes the file the document's and cleans it.
        let target = dir.0.join("scene.ron");
        w.save(&d, target.clone(), false);
        let Done::Saved {
            result,
            path,
            revision,
            ..
        } = wait(&mut w)
        else {
            panic!()
        };
        result.unwrap();
        // A change made after the save read the document keeps it dirty.
        d.write().unwrap().execute(Command::Clear).unwrap();
        d.write().unwrap().mark_saved(&path, revision);
        assert!(d.read().unwrap().dirty);
        let now = d.read().unwrap().revision;
        d.write().unwrap().mark_saved(&path, now);
        assert!(!d.read().unwrap().dirty);
        assert_eq!(d.read().unwrap().path.as_deref(), Some(target.as_path()));
    }

    #[test]
    fn a_failed_save_keeps_the_document_and_the_file_on_disk() {
        let dir = temp("failed");
        let d = doc();
        d.write().unwrap().execute(Command::Clear).unwrap();
        let target = dir.join("keep.ron");
        std::fs::write(&target, b"the user's old bytes").unwrap();
        let mut w = FileWorker::new(Arc::new(|| {}));
        // A folder where the file should go makes the rename fail; an unknown extension
        // is refused before anything is written.
        for bad in [dir.join("sub.ron"), dir.join("scene.txt")] {
            if bad.extension().is_some_and(|e| e == "ron") {
                std::fs::create_dir_all(bad.join("x")).unwrap();
            }
            let hash = d.read().unwrap().scene.world.read().content_hash();
            w.save(&d, bad.clone(), false);
            let Done::Saved { result, .. } = wait(&mut w) else {
                panic!()
            };
            assert!(result.is_err(), "{} should fail", bad.display());
            let doc = d.read().unwrap();
            assert!(doc.dirty && doc.path.is_none());
            assert_eq!(doc.scene.world.read().content_hash(), hash);
            assert_eq!(doc.history.undo_len(), 1);
        }
        assert_eq!(std::fs::read(&target).unwrap(), b"the user's old bytes");
        // Loading a broken file reports it and builds nothing.
        std::fs::write(dir.join("broken.ron"), b"(format_version: 1, garbage").unwrap();
        w.load(dir.join("broken.ron"), 1);
        let Done::Loaded(_, scene) = wait(&mut w) else {
            panic!()
        };
        assert!(scene.is_err());
    }
}
