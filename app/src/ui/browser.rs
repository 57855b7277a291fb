//! The in-app file browser: what Open, Save As, Import, Export and the palette's files use
//! when no native dialog can be shown (no xdg-desktop-portal, no zenity or kdialog, or a
//! headless editor). A folder field, the places (home, the document's folder, recent files'
//! folders, the root), the folder's subfolders and its files of the purpose's extensions (or
//! all files), and a name field that also takes a whole path. Enter or the button confirms;
//! a save over an existing file asks first; nothing is written until the user confirms a
//! path they can see.

use super::purpose::Purpose;
use std::path::{Path, PathBuf};

/// The browser's state while it is open.
pub struct Browser {
    /// What the chosen path is for.
    pub purpose: Purpose,
    folder: PathBuf,
    /// The folder field's text (applied with Enter or Go).
    folder_text: String,
    /// The file name (or a whole path).
    name: String,
    /// Subfolders and files of `folder` (names; folders first, then files, each sorted).
    entries: Vec<(String, bool)>,
    /// The folder could not be read: why.
    error: Option<String>,
    /// Every file, not only the purpose's extensions.
    all_files: bool,
    /// A save would replace this existing file: asked first.
    confirm: Option<PathBuf>,
    /// Focus the name field on the first frame.
    focus: bool,
}

/// What the user did with the browser this frame.
#[derive(Debug, PartialEq, Eq)]
pub enum Answer {
    /// Still choosing.
    Open,
    /// Closed without a choice.
    Cancelled,
    /// This path, confirmed.
    Chosen(PathBuf),
}

impl Browser {
    /// A browser in `folder` (else the working folder) with `name` filled in.
    pub fn new(purpose: Purpose, folder: Option<PathBuf>, name: Option<String>) -> Self {
        let folder = folder
            .filter(|f| f.is_dir())
            .or_else(|| std::env::current_dir().ok())
            .unwrap_or_else(|| PathBuf::from("/"));
        let mut b = Self {
            purpose,
            folder_text: folder.display().to_string(),
            folder,
            name: name.unwrap_or_default(),
            entries: Vec::new(),
            error: None,
            all_files: false,
            confirm: None,
            focus: true,
        };
        b.read_folder();
        b
    }

    /// The folder shown.
    pub fn folder(&self) -> &Path {
        &self.folder
    }

    /// Goes to `folder` (an unreadable one is said, and the entries emptied).
    pub fn go(&mut self, folder: PathBuf) {
        self.folder_text = folder.display().to_string();
        self.folder = folder;
        self.confirm = None;
        self.read_folder();
    }

    fn read_folder(&mut self) {
        let (_, exts) = self.purpose.filter();
        self.entries.clear();
        self.error = None;
        let read = match std::fs::read_dir(&self.folder) {
            Ok(r) => r,
            Err(e) => {
                self.error = Some(format!("cannot read this folder: {e}"));
                return;
            }
        };
        for entry in read.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue;
            }
            let dir = entry.path().is_dir();
            let wanted = dir
                || self.all_files
                || Path::new(&name)
                    .extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| exts.iter().any(|x| e.eq_ignore_ascii_case(x)));
            if wanted {
                self.entries.push((name, dir));
            }
        }
        self.entries
            .sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
    }

    /// The path the name field names: a whole path as typed, else the name in the folder;
    /// for a save without an extension, the purpose's first one.
    pub fn target(&self) -> Option<PathBuf> {
        let path = self.typed()?;
        let (_, exts) = self.purpose.filter();
        Some(if self.purpose.saves() && path.extension().is_none() {
            path.with_extension(exts[0])
        } else {
            path
        })
    }

    /// The path the name field names as typed: a whole path, else the name in the folder.
    fn typed(&self) -> Option<PathBuf> {
        let name = self.name.trim();
        if name.is_empty() {
            return None;
        }
        let typed = Path::new(name);
        Some(if typed.is_absolute() {
            typed.to_path_buf()
        } else {
            self.folder.join(typed)
        })
    }

    /// Confirms the name field: a folder is entered; a file to read must exist; a save over
    /// an existing file asks first.
    fn confirm_name(&mut self) -> Answer {
        if let Some(folder) = self.typed().filter(|p| p.is_dir()) {
            self.name.clear();
            self.go(folder);
            return Answer::Open;
        }
        let Some(path) = self.target() else {
            return Answer::Open;
        };
        if self.purpose.saves() {
            if path.exists() && self.confirm.as_ref() != Some(&path) {
                self.confirm = Some(path);
                return Answer::Open;
            }
            if !path.parent().is_some_and(Path::is_dir) {
                self.error = Some(format!(
                    "no folder {}",
                    path.parent().unwrap_or(&path).display()
                ));
                return Answer::Open;
            }
            return Answer::Chosen(path);
        }
        if path.is_file() {
            Answer::Chosen(path)
        } else {
            self.error = Some(format!("there is no file {}", path.display()));
            Answer::Open
        }
    }

    /// Draws the browser inside `area`; `places` are (label, folder) buttons.
    pub fn draw(
        &mut self,
        ctx: &egui::Context,
        area: egui::Rect,
        places: &[(String, PathBuf)],
    ) -> Answer {
        let mut answer = Answer::Open;
        let mut open = true;
        let (what, exts) = self.purpose.filter();
        egui::Window::new(self.purpose.title())
            .id(egui::Id::new("file browser"))
            .open(&mut open)
            .collapsible(false)
            .constrain_to(area)
            .default_width(560.0_f32.min(area.width() - 16.0))
            .pivot(egui::Align2::CENTER_CENTER)
            .default_pos(area.center())
            .show(ctx, |ui| {
                ui.horizontal(|ui| {
                    ui.label("Folder");
                    let field = ui.add(
                        egui::TextEdit::singleline(&mut self.folder_text).desired_width(300.0),
                    );
                    let entered =
                        field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                    if entered || ui.button("Go").clicked() {
                        self.go(PathBuf::from(self.folder_text.trim()));
                    }
                    if ui.button("Up").clicked()
                        && let Some(p) = self.folder.parent()
                    {
                        self.go(p.to_path_buf());
                    }
                });
                ui.separator();
                ui.horizontal_top(|ui| {
                    ui.vertical(|ui| {
                        ui.set_width(120.0);
                        for (label, folder) in places {
                            if ui
                                .selectable_label(&self.folder == folder, label)
                                .on_hover_text(folder.display().to_string())
                                .clicked()
                            {
                                self.go(folder.clone());
                            }
                        }
                    });
                    ui.vertical(|ui| {
                        // What the rest of the browser leaves of the area's height.
                        egui::ScrollArea::vertical()
                            .max_height((area.height() - 190.0).clamp(60.0, 320.0))
                            .auto_shrink([false, false])
                            .show(ui, |ui| {
                                if let Some(e) = &self.error {
                                    ui.colored_label(egui::Color32::LIGHT_RED, e);
                                }
                                let mut enter = None;
                                for (name, dir) in &self.entries {
                                    let label = if *dir {
                                        format!("🗀 {name}/")
                                    } else {
                                        name.clone()
                                    };
                                    let r = ui.selectable_label(!dir && &self.name == name, label);
                                    if r.clicked() {
                                        if *dir {
                                            enter = Some(self.folder.join(name));
                                        } else {
                                            self.name = name.clone();
                                            self.confirm = None;
                                        }
                                    }
                                    if r.double_clicked() && !dir {
                                        answer = Answer::Chosen(self.folder.join(name));
                                    }
                                }
                                if self.entries.is_empty() && self.error.is_none() {
                                    ui.weak("(no folders or matching files here)");
                                }
                                if let Some(f) = enter {
                                    self.go(f);
                                }
                            });
                    });
                });
                ui.separator();
                ui.horizontal(|ui| {
                    ui.label("Name");
                    let field = ui.add(
                        egui::TextEdit::singleline(&mut self.name)
                            .desired_width(300.0)
                            .hint_text("a file name, or a whole path"),
                    );
                    if std::mem::take(&mut self.focus) {
                        field.request_focus();
                    }
                    if field.changed() {
                        self.confirm = None;
                    }
                    if field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
                        answer = self.confirm_name();
                    }
                });
                ui.horizontal(|ui| {
                    if ui
                        .checkbox(&mut self.all_files, "all files")
                        .on_hover_text(format!("{what}: *.{}", exts.join(", *.")))
                        .changed()
                    {
                        self.read_folder();
                    }
                    ui.weak(format!("{what} (*.{})", exts.join(", *.")));
                });
                if let Some(p) = &self.confirm {
                    ui.colored_label(
                        egui::Color32::YELLOW,
                        format!(
                            "{} exists: press Replace (or Enter) to write over it",
                            p.display()
                        ),
                    );
                }
                ui.horizontal(|ui| {
                    let verb = match (self.purpose.saves(), self.confirm.is_some()) {
                        (true, true) => "Replace",
                        (true, false) => "Save",
                        (false, _) => "Open",
                    };
                    if ui
                        .add_enabled(self.target().is_some(), egui::Button::new(verb))
                        .clicked()
                    {
                        answer = self.confirm_name();
                    }
                    if ui.button("Cancel").clicked() {
                        answer = Answer::Cancelled;
                    }
                    if let Some(t) = self.target() {
                        ui.weak(t.display().to_string());
                    }
                });
            });
        if !open || ctx.input(|i| i.key_pressed(egui::Key::Escape)) {
            return Answer::Cancelled;
        }
        answer
    }
}

/// The browser's places: home, the document's folder, recent files' folders, the root.
pub fn places(document_folder: Option<&Path>, recent: &[PathBuf]) -> Vec<(String, PathBuf)> {
    let mut out: Vec<(String, PathBuf)> = Vec::new();
    let mut add = |label: String, p: PathBuf| {
        if p.is_dir() && !out.iter().any(|(_, q)| *q == p) {
            out.push((label, p));
        }
    };
    if let Some(home) = std::env::var_os("HOME") {
        add("Home".into(), PathBuf::from(home));
    }
    if let Some(f) = document_folder {
        add("This scene's folder".into(), f.to_path_buf());
    }
    for r in recent {
        if let Some(f) = r.parent() {
            let name = f.file_name().map_or_else(
                || f.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            add(name, f.to_path_buf());
        }
    }
    add("/".into(), PathBuf::from("/"));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(tag: &str) -> crate::scratch::Scratch {
        let d = crate::scratch::Scratch::new(&format!("browser-{tag}"));
        std::fs::create_dir_all(d.join("sub")).unwrap();
        for f in ["b.ron", "a.vox", "notes.txt", ".hidden.ron"] {
            std::fs::write(d.join(f), "x").unwrap();
        }
        d
    }

    #[test]
    fn a_folder_lists_subfolders_then_the_purposes_files() {
        let d = folder("list");
        let mut b = Browser::new(Purpose::Open, Some(d.to_path_buf()), None);
        let names: Vec<&str> = b.entries.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["sub", "a.vox", "b.ron"]);
        b.all_files = true;
        b.read_folder();
        assert_eq!(b.entries.len(), 4, "notes.txt too, never the hidden file");
        let b = Browser::new(Purpose::Import, Some(d.to_path_buf()), None);
        let names: Vec<&str> = b.entries.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["sub", "a.vox"]);
    }

    #[test]
    fn the_name_field_takes_a_name_a_path_or_a_folder() {
        let d = folder("name");
        let mut b = Browser::new(Purpose::SaveAs, Some(d.to_path_buf()), Some("new".into()));
        assert_eq!(
            b.target(),
            Some(d.join("new.ron")),
            "a save gets its extension"
        );
        assert_eq!(b.confirm_name(), Answer::Chosen(d.join("new.ron")));
        // An existing file: asked first, then replaced.
        b.name = "b.ron".into();
        assert_eq!(b.confirm_name(), Answer::Open);
        assert_eq!(b.confirm, Some(d.join("b.ron")));
        assert_eq!(b.confirm_name(), Answer::Chosen(d.join("b.ron")));
        // A folder typed as the name is entered.
        b.name = "sub".into();
        assert_eq!(b.confirm_name(), Answer::Open);
        assert_eq!(b.folder(), d.join("sub"));
        // A whole path; a save into a folder that does not exist is refused.
        b.name = d.join("a.vox").display().to_string();
        assert_eq!(b.target(), Some(d.join("a.vox")));
        b.name = d.join("none/x.ron").display().to_string();
        assert_eq!(b.confirm_name(), Answer::Open);
        assert!(b.error.as_deref().is_some_and(|e| e.contains("no folder")));
        // Opening needs an existing file.
        let mut o = Browser::new(
            Purpose::Open,
            Some(d.to_path_buf()),
            Some("missing.ron".into()),
        );
        assert_eq!(o.confirm_name(), Answer::Open);
        o.name = "b.ron".into();
        assert_eq!(o.confirm_name(), Answer::Chosen(d.join("b.ron")));
    }

    #[test]
    fn an_unreadable_folder_is_said() {
        let mut b = Browser::new(Purpose::Open, None, None);
        b.go(PathBuf::from("/no/such/folder"));
        assert!(
            b.error
                .as_deref()
                .is_some_and(|e| e.starts_with("cannot read"))
        );
        assert!(b.entries.is_empty());
    }
}
