//! The editor's egui panels: menu bar, status bar, render settings, sun and sky, scene
//! statistics, the shortcut list, and the dialogs (unsaved changes, recovery, errors). They
//! read the state and return what the user asked for as [`UiEvent`]s; the frame loop applies
//! them (scene settings as undoable commands, view settings directly).
//!
//! In detail:
//! egui: menus, status bar (with a passing notice, 4 s: a save done, an undo or redo, a no-op),
//! the docks, then the viewport's rectangle (what the bars and docks leave; windows are kept
//! inside it), render settings (view: target spp, internal scale, exposure, denoise, autosave;
//! scene: bounces as `SetSettings`), sun and sky (`SetSun`/`SetSky`, coalesced per drag),
//! statistics, shortcuts, new scene, the unsaved-changes and recovery questions, errors.
//! Returns `UiEvent`s the loop applies.

use super::editing::window;
use super::input::SHORTCUTS;
use super::intent::Action;
pub use super::intent::{UiEvent, UnsavedAnswer};
use crate::editor::Document;
use render::Sky;
use std::path::PathBuf;

/// View settings: not part of the scene, not in the history; kept in the config folder.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct ViewSettings {
    /// Samples per pixel at which the viewport stops (converged).
    pub target_spp: u32,
    /// Internal resolution as a fraction of the window.
    pub internal_scale: f32,
    /// Internal resolution while the camera moves.
    pub moving_scale: f32,
    /// Display exposure in stops.
    pub exposure: f32,
    /// Show the viewport denoised (edge-aware, guided by the first hit; it gives way to the
    /// raw image between 8 and 64 spp). Renders and exports never are.
    pub denoise: bool,
    /// With `denoise`: while the camera moves, reuse earlier frames where they saw the same
    /// surfaces (a clean image while orbiting; the still image is unchanged).
    pub reproject: bool,
    /// Outside arrange mode, darken what lies outside the edited object's box.
    pub dim_others: bool,
    /// The ground grid on the scene's floor (G).
    pub grid: bool,
    /// Its lines' spacing in voxels.
    pub grid_spacing: u32,
    /// The key map's preset (keys.ron's bindings win over it).
    pub key_preset: super::intent::KeyPreset,
    /// Autosave period in seconds (0: off).
    pub autosave_secs: u64,
    /// The brush.
    pub brush: super::tools::Brush,
    /// How File → Export mesh makes the mesh.
    pub mesh_export: crate::formats::mesh::MeshOptions,
    /// File → Render image…'s options.
    pub render_image: super::render_image::RenderImageOptions,
}

impl Default for ViewSettings {
    fn default() -> Self {
        Self {
            target_spp: 256,
            internal_scale: 1.0,
            moving_scale: 0.5,
            exposure: 0.0,
            denoise: false,
            reproject: true,
            dim_others: false,
            grid: true,
            grid_spacing: 8,
            key_preset: Default::default(),
            autosave_secs: 180,
            brush: Default::default(),
            mesh_export: Default::default(),
            render_image: Default::default(),
        }
    }
}

/// What the panels show besides the document.
#[derive(Default)]
pub struct PanelState {
    /// Render settings window open.
    pub render_open: bool,
    /// File → Render image… open.
    pub render_image_open: bool,
    /// Sun and sky window open.
    pub sun_open: bool,
    /// Statistics window open.
    pub stats_open: bool,
    /// Shortcut list open.
    pub help_open: bool,
    /// New-scene dialog open, with its fields.
    pub new_open: bool,
    /// New-scene size.
    pub new_size: (u32, u32, u32),
    /// New scene gets terrain.
    pub new_terrain: bool,
    /// A picked .vox waiting for its import offset.
    pub import: Option<(PathBuf, [i32; 3])>,
    /// "Save changes?" is being asked (for what comes next).
    pub asking_unsaved: bool,
    /// A recovery file to offer.
    pub recovery: Option<PathBuf>,
    /// Errors to show (newest last).
    pub errors: Vec<String>,
    /// Recent files.
    pub recent: Vec<PathBuf>,
    /// Status line: device, samples, timings.
    pub status: String,
    /// The in-app file browser (no native dialog could be shown), with its places.
    pub browser: Option<(super::browser::Browser, Vec<(String, PathBuf)>)>,
    /// A passing message on the status line (a save done, an undo with nothing to undo)
    /// and when it was given; shown for [`NOTICE_SECS`].
    pub notice: Option<(String, std::time::Instant)>,
    /// Scene statistics text (refreshed when the scene changes).
    pub stats: String,
    /// Background jobs running.
    pub busy: Vec<String>,
    /// The editing windows (tools, palette, history).
    pub editing: super::editing::EditingState,
    /// The Objects window.
    pub outliner: super::outliner::OutlinerState,
    /// The key map's bindings (chord, action) for the shortcut list.
    pub keys: Vec<(String, String)>,
    /// The Object menu's Resize canvas fields.
    pub canvas: super::object_menu::CanvasForm,
    /// The viewport's rectangle: what the menu bar, the status line and the docked panels
    /// leave of the window, in points (last frame).
    pub viewport: Option<egui::Rect>,
}

/// How long a status-line notice stays.
pub const NOTICE_SECS: f32 = 4.0;

impl PanelState {
    /// A passing message on the status line (replacing the one before).
    pub fn notify(&mut self, text: impl Into<String>) {
        self.notice = Some((text.into(), std::time::Instant::now()));
    }
}

/// Draws the panels; returns what the user asked for.
pub fn draw(
    root: &mut egui::Ui,
    state: &mut PanelState,
    doc: &Document,
    view: &mut ViewSettings,
) -> Vec<UiEvent> {
    let mut out = Vec::new();
    let ctx = &root.ctx().clone();
    egui::Panel::top("menu").show(root, |ui| {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("New…").clicked() {
                    state.new_open = true;
                    if state.new_size == (0, 0, 0) {
                        state.new_size = (256, 128, 256);
                    }
                }
                for (label, action) in [
                    ("New from a heightmap…", Action::NewFromHeightmap),
                    ("Open…  Ctrl+O", Action::Open),
                    ("Save  Ctrl+S", Action::Save),
                    ("Save As…  Ctrl+Shift+S", Action::SaveAs),
                    ("Import .vox…  Ctrl+I", Action::Import),
                    ("Export .vox / .qb / .schem…  Ctrl+E", Action::Export),
                    ("Export mesh…  Ctrl+Shift+E", Action::ExportMesh),
                ] {
                    if ui.button(label).clicked() {
                        out.push(UiEvent::Action(action));
                    }
                }
                if ui.button("Render image…").clicked() {
                    state.render_image_open = true;
                }
                ui.separator();
                ui.label("mesh export options");
                {
                    let m = &mut view.mesh_export;
                    ui.checkbox(&mut m.per_object, "one part per object")
                        .on_hover_text("named; glTF nodes under their groups; else the scene as shown");
                    ui.add_enabled(
                        m.per_object,
                        egui::Checkbox::new(&mut m.keep_transforms, "keep placements (glTF)"),
                    )
                    .on_hover_text("each object's turn and position as its node's matrix, its mesh in its own frame; else applied");
                    let mut faces = !m.greedy;
                    if ui
                        .checkbox(&mut faces, "one quad per voxel face (watertight)")
                        .on_hover_text("else coplanar faces of one material merged into rectangles, which meet at T-junctions")
                        .changed()
                    {
                        m.greedy = !faces;
                    }
                    ui.horizontal(|ui| {
                        ui.add(
                            egui::DragValue::new(&mut m.voxel_size)
                                .speed(0.01)
                                .range(0.001..=1000.0),
                        );
                        ui.label("units per voxel (glTF: metres)");
                    });
                }
                ui.separator();
                ui.menu_button("Recent", |ui| {
                    if state.recent.is_empty() {
                        ui.label("(none)");
                    }
                    for p in &state.recent {
                        if ui.button(p.display().to_string()).clicked() {
                            out.push(UiEvent::OpenRecent(p.clone()));
                        }
                    }
                });
                ui.separator();
                if ui.button("Quit  Ctrl+Q").clicked() {
                    out.push(UiEvent::Action(Action::Quit));
                }
            });
            ui.menu_button("Edit", |ui| {
                if ui
                    .add_enabled(
                        doc.history.undo_len() > 0,
                        egui::Button::new("Undo  Ctrl+Z"),
                    )
                    .clicked()
                {
                    out.push(UiEvent::Action(Action::Undo));
                }
                if ui
                    .add_enabled(
                        doc.history.redo_len() > 0,
                        egui::Button::new("Redo  Ctrl+Y"),
                    )
                    .clicked()
                {
                    out.push(UiEvent::Action(Action::Redo));
                }
                ui.separator();
                let selected = doc.scene.selection.is_some();
                for (enabled, name, action) in [
                    (selected, "Cut  Ctrl+X", Action::Cut),
                    (selected, "Copy  Ctrl+C", Action::Copy),
                    (
                        doc.scene.clipboard.is_some(),
                        "Paste  Ctrl+V",
                        Action::Paste,
                    ),
                    (
                        selected,
                        "Delete selection  Delete",
                        Action::DeleteSelection,
                    ),
                    (selected, "Fill selection  Ctrl+F", Action::FillSelection),
                    (selected, "Paint selection  Ctrl+P", Action::PaintSelection),
                    (true, "Select all  Ctrl+A", Action::SelectAll),
                    (selected, "Select none  Ctrl+D", Action::SelectNone),
                ] {
                    if ui.add_enabled(enabled, egui::Button::new(name)).clicked() {
                        out.push(UiEvent::Action(action));
                    }
                }
                ui.menu_button("Replace by the current material", |ui| {
                    ui.label(if selected {
                        "in the selection:"
                    } else {
                        "in the edited object:"
                    });
                    let count = doc.scene.world.materials().len();
                    for from in (0..count as u8).filter(|m| *m != view.brush.material) {
                        if ui.button(format!("material {from}")).clicked() {
                            out.push(UiEvent::ReplaceMaterial { from });
                        }
                    }
                });
            });
            ui.menu_button("View", |ui| {
                if ui.button("Frame the scene  F").clicked() {
                    out.push(UiEvent::Action(Action::Frame));
                }
                if ui.button("Perspective / orthographic  O").clicked() {
                    out.push(UiEvent::Action(Action::ToggleProjection));
                }
                ui.checkbox(&mut view.grid, "Ground grid  G");
                if ui.button("Use this view as the scene camera").clicked() {
                    out.push(UiEvent::UseViewAsSceneCamera);
                }
                ui.checkbox(&mut state.render_open, "Render settings");
                ui.checkbox(&mut state.sun_open, "Sun and sky");
                ui.checkbox(&mut state.stats_open, "Scene statistics");
                ui.checkbox(&mut state.help_open, "Shortcuts  F1");
                ui.separator();
                let mut tools = !state.editing.tools_hidden;
                ui.checkbox(&mut tools, "Tools");
                state.editing.tools_hidden = !tools;
                let mut palette = !state.editing.palette_hidden;
                ui.checkbox(&mut palette, "Palette and materials");
                state.editing.palette_hidden = !palette;
                ui.checkbox(&mut state.editing.history_open, "History");
                ui.checkbox(&mut state.outliner.open, "Objects");
                if ui.button("Terrain and water…").clicked() {
                    let d = doc.scene.world.dims().voxels();
                    state.editing.terrain = Some(crate::editor::command::TerrainSpec::for_size((
                        d.x as u32, d.y as u32, d.z as u32,
                    )));
                }
            });
            ui.menu_button("Object", |ui| {
                super::object_menu::menu(
                    ui,
                    doc,
                    view.brush.tool,
                    &mut view.dim_others,
                    &mut state.canvas,
                    &mut out,
                )
            });
            if !state.busy.is_empty() {
                ui.separator();
                ui.add(egui::Spinner::new());
                ui.label(state.busy.join(", "));
            }
        });
    });
    egui::Panel::bottom("status").show(root, |ui| {
        ui.horizontal(|ui| {
            if let Some((text, at)) = &state.notice {
                let left = NOTICE_SECS - at.elapsed().as_secs_f32();
                if left > 0.0 {
                    ui.strong(text);
                    ui.separator();
                    ctx.request_repaint_after(std::time::Duration::from_secs_f32(left));
                } else {
                    state.notice = None;
                }
            }
            ui.label(&state.status);
        });
    });
    // The file browser may use the whole width between the bars (it asks before anything
    // else goes on); the other windows stay in the viewport.
    let between_bars = root.available_rect_before_wrap();
    super::editing::docks(root, &mut state.editing, doc, &mut view.brush, &mut out);
    // The viewport is what the bars and the docks leave; windows stay inside it (in a small
    // window egui would otherwise push a tall one up over the menus).
    let area = root.available_rect_before_wrap();
    state.viewport = Some(area);
    super::editing::draw(ctx, area, &mut state.editing, doc, &mut out);
    super::outliner::draw(ctx, area, &mut state.outliner, doc, &mut out);
    if let Some((browser, places)) = &mut state.browser {
        match browser.draw(ctx, between_bars, places) {
            super::browser::Answer::Open => {}
            super::browser::Answer::Cancelled => {
                state.browser = None;
                out.push(UiEvent::PickCancelled);
            }
            super::browser::Answer::Chosen(path) => {
                out.push(UiEvent::Picked(browser.purpose, path));
                state.browser = None;
            }
        }
    }
    if state.render_open {
        let mut open = true;
        window(area, "Render settings")
            .open(&mut open)
            .show(ctx, |ui| {
                ui.add(
                    egui::Slider::new(&mut view.target_spp, 1..=4096)
                        .logarithmic(true)
                        .text("target spp"),
                );
                ui.add(
                    egui::Slider::new(&mut view.internal_scale, 0.125..=1.0)
                        .text("internal resolution"),
                );
                ui.add(egui::Slider::new(&mut view.moving_scale, 0.125..=1.0).text("while moving"));
                ui.add(egui::Slider::new(&mut view.exposure, -8.0..=8.0).text("exposure (stops)"));
                ui.horizontal(|ui| {
                    ui.checkbox(&mut view.grid, "ground grid  G");
                    ui.add(
                        egui::DragValue::new(&mut view.grid_spacing)
                            .range(1..=256)
                            .suffix(" voxels"),
                    );
                });
                ui.checkbox(&mut view.denoise, "denoise the viewport")
                    .on_hover_text("Edge-aware filter guided by the first hit's normal, albedo and depth; between 8 and 64 samples it gives way to the path-traced image. Renders and exports are never denoised.");
                ui.add_enabled(view.denoise, egui::Checkbox::new(&mut view.reproject, "reuse earlier frames while moving"))
                    .on_hover_text("While the camera moves, blend in the previous frames where they saw the same surfaces; once it stops, the path-traced image takes over within 16 samples.");
                let mut settings = doc.scene.params.settings.clone();
                if ui
                    .add(
                        egui::Slider::new(&mut settings.max_bounces, 1..=16)
                            .text("bounces (scene)"),
                    )
                    .changed()
                {
                    out.push(UiEvent::SetSettings(settings.clone()));
                }
                let before = settings.sequence;
                egui::ComboBox::from_label("sample numbers (scene)")
                    .selected_text(sequence_name(before))
                    .show_ui(ui, |ui| {
                        for q in [render::Sequence::Sobol, render::Sequence::Independent] {
                            ui.selectable_value(&mut settings.sequence, q, sequence_name(q));
                        }
                    });
                if settings.sequence != before {
                    out.push(UiEvent::SetSettings(settings));
                }
                ui.add(
                    egui::Slider::new(&mut view.autosave_secs, 0..=1800)
                        .text("autosave every (s, 0 off)"),
                );
            });
        state.render_open = open;
    }
    if state.sun_open {
        let mut open = true;
        window(area, "Sun and sky").open(&mut open).show(ctx, |ui| {
            sun_and_sky(ui, doc, &mut out);
        });
        state.sun_open = open;
    }
    if state.stats_open {
        let mut open = true;
        window(area, "Scene statistics")
            .open(&mut open)
            .show(ctx, |ui| {
                ui.monospace(&state.stats);
            });
        state.stats_open = open;
    }
    if state.help_open {
        let mut open = true;
        // As wide as the viewport allows; the descriptions wrap rather than clip.
        let width = (area.width() - 24.0).clamp(200.0, 720.0);
        window(area, "Shortcuts")
            .open(&mut open)
            .default_width(width)
            .show(ctx, |ui| {
                ui.horizontal(|ui| {
                    ui.label("key map");
                    for p in super::intent::KeyPreset::ALL {
                        if ui
                            .selectable_label(view.key_preset == p, p.name())
                            .clicked()
                            && view.key_preset != p
                        {
                            out.push(UiEvent::KeyPreset(p));
                        }
                    }
                });
                ui.separator();
                // Scrolls when the window is short (or the UI scale large).
                egui::ScrollArea::vertical().show(ui, |ui| {
                    // A row per shortcut: the keys in a column of their own, the description
                    // wrapped in what is left.
                    for (keys, what) in SHORTCUTS {
                        ui.horizontal_top(|ui| {
                            ui.allocate_ui_with_layout(
                                egui::vec2(210.0, 0.0),
                                egui::Layout::top_down(egui::Align::Min),
                                |ui| {
                                    ui.set_width(210.0);
                                    ui.monospace(*keys);
                                },
                            );
                            ui.add(egui::Label::new(*what).wrap());
                        });
                    }
                    if !state.keys.is_empty() {
                        ui.separator();
                        ui.label("The key map in force (keys.ron in the config folder):");
                        egui::Grid::new("keymap").striped(true).show(ui, |ui| {
                            for (keys, action) in &state.keys {
                                ui.monospace(keys);
                                ui.label(action);
                                ui.end_row();
                            }
                        });
                    }
                });
            });
        state.help_open = open;
    }
    if state.new_open {
        let mut open = true;
        window(area, "New scene").open(&mut open).show(ctx, |ui| {
            let (x, y, z) = &mut state.new_size;
            ui.horizontal(|ui| {
                ui.add(egui::DragValue::new(x).range(8..=4096).prefix("x "));
                ui.add(egui::DragValue::new(y).range(8..=1024).prefix("y "));
                ui.add(egui::DragValue::new(z).range(8..=4096).prefix("z "));
            });
            ui.checkbox(&mut state.new_terrain, "noise terrain with water");
            if ui.button("Create").clicked() {
                out.push(UiEvent::NewScene {
                    size: state.new_size,
                    terrain: state.new_terrain,
                });
                state.new_open = false;
            }
        });
        state.new_open &= open;
    }
    if let Some((path, offset)) = &mut state.import {
        let mut go = None;
        modal(ctx, "Import .vox", |ui| {
            ui.label(path.display().to_string());
            ui.horizontal(|ui| {
                for (v, axis) in offset.iter_mut().zip(["x ", "y ", "z "]) {
                    ui.add(egui::DragValue::new(v).range(-4096..=4096).prefix(axis));
                }
            });
            ui.label("offset in voxels, added after the model is shifted into the grid");
            ui.horizontal(|ui| {
                if ui.button("Import").clicked() {
                    go = Some(true);
                }
                if ui.button("Cancel").clicked() {
                    go = Some(false);
                }
            });
        });
        match go {
            Some(true) => {
                out.push(UiEvent::Import {
                    path: path.clone(),
                    offset: *offset,
                });
                state.import = None;
            }
            Some(false) => state.import = None,
            None => {}
        }
    }
    if state.asking_unsaved {
        modal(ctx, "Unsaved changes", |ui| {
            ui.label("The scene has unsaved changes.");
            ui.horizontal(|ui| {
                for (label, a) in [
                    ("Save", UnsavedAnswer::Save),
                    ("Discard", UnsavedAnswer::Discard),
                    ("Cancel", UnsavedAnswer::Cancel),
                ] {
                    if ui.button(label).clicked() {
                        out.push(UiEvent::Unsaved(a));
                    }
                }
            });
        });
    }
    if let Some(path) = &state.recovery {
        let text = format!(
            "voxbrick did not exit cleanly last time. Recover the autosaved scene ({})?",
            path.display()
        );
        // Enter recovers (the default answer), Escape discards.
        let (enter, escape) = ctx.input(|i| {
            (
                i.key_pressed(egui::Key::Enter),
                i.key_pressed(egui::Key::Escape),
            )
        });
        modal(ctx, "Recover unsaved work", |ui| {
            ui.label(text);
            ui.horizontal(|ui| {
                if ui.button("Recover (Enter)").clicked() || enter {
                    out.push(UiEvent::Recover(true));
                }
                if ui.button("Discard (Esc)").clicked() || escape {
                    out.push(UiEvent::Recover(false));
                }
            });
        });
    }
    if !state.errors.is_empty() {
        let mut dismiss = false;
        // As tall as its messages (a resizable window with a scroll area keeps egui's
        // 420-pixel default height, most of it empty), scrolling past the viewport's height.
        egui::Window::new("Error")
            .constrain_to(area)
            .collapsible(false)
            .resizable(false)
            .default_width(360.0)
            .show(ctx, |ui| {
                egui::ScrollArea::vertical()
                    .max_height((area.height() - 120.0).max(60.0))
                    .auto_shrink([false, true])
                    .show(ui, |ui| {
                        for e in &state.errors {
                            ui.colored_label(egui::Color32::LIGHT_RED, e);
                        }
                    });
                dismiss = ui.button("OK").clicked();
            });
        if dismiss {
            state.errors.clear();
        }
    }
    out
}

fn modal(ctx: &egui::Context, title: &str, body: impl FnOnce(&mut egui::Ui)) {
    egui::Window::new(title)
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
        .show(ctx, body);
}

fn sun_and_sky(ui: &mut egui::Ui, doc: &Document, out: &mut Vec<UiEvent>) {
    let mut sun = doc.scene.params.sun.clone();
    let centre = doc.scene.world.dims().voxels().as_dvec3() * 0.5;
    // Azimuth and elevation of the sun about the grid centre, at its distance.
    let rel = sun.position - centre;
    let distance = rel.length().max(1.0);
    let mut elevation = (rel.y / distance).clamp(-1.0, 1.0).asin().to_degrees();
    let mut azimuth = rel.z.atan2(rel.x).to_degrees();
    let mut changed = ui.checkbox(&mut sun.enabled, "sun").changed();
    changed |= ui
        .add(egui::Slider::new(&mut azimuth, -180.0..=180.0).text("azimuth°"))
        .changed();
    changed |= ui
        .add(egui::Slider::new(&mut elevation, -10.0..=90.0).text("elevation°"))
        .changed();
    changed |= ui
        .add(
            egui::Slider::new(&mut sun.radius, 1.0..=distance * 0.5)
                .logarithmic(true)
                .text("radius"),
        )
        .changed();
    changed |= ui
        .add(
            egui::Slider::new(&mut sun.intensity, 0.0..=1000.0)
                .logarithmic(true)
                .text("intensity"),
        )
        .changed();
    changed |= ui.color_edit_button_rgb(&mut sun.colour).changed();
    changed |= ui.checkbox(&mut sun.animate, "animate").changed();
    if changed {
        let (a, e) = (azimuth.to_radians(), elevation.to_radians());
        sun.position =
            centre + glam::DVec3::new(a.cos() * e.cos(), e.sin(), a.sin() * e.cos()) * distance;
        if sun.validate().is_ok() {
            out.push(UiEvent::SetSun(sun));
        }
    }
    ui.separator();
    let mut sky = doc.scene.params.sky.clone();
    let sky_changed = match &mut sky {
        Sky::Uniform { colour } => {
            ui.label("sky (uniform)");
            ui.color_edit_button_rgb(colour).changed()
        }
        Sky::Gradient { horizon, zenith } => {
            ui.label("sky: horizon, zenith");
            ui.color_edit_button_rgb(horizon).changed() | ui.color_edit_button_rgb(zenith).changed()
        }
    };
    if sky_changed && sky.validate().is_ok() {
        out.push(UiEvent::SetSky(sky));
    }
}

/// What the render settings call a sample sequence.
fn sequence_name(q: render::Sequence) -> &'static str {
    match q {
        render::Sequence::Sobol => "scrambled Sobol",
        render::Sequence::Independent => "independent random",
    }
}
