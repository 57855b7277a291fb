//! The editing panels: tools (mode, shape, size, mirror symmetry, the current material),
//! palette and materials (the 256-colour table and the material list, edited live: each
//! slider drag is one undo step, and only the material tables are uploaded), and the
//! history list (every step with the voxels it changed; click one to go back or forward to
//! it; how many of the oldest steps the memory budget dropped).
//!
//! In detail:
//! the docks (`docks`): Tools on the left (with its Selection section: what is selected, box
//! depth, "brush only inside the selection", the operations as buttons), on the right the 256
//! colours always shown (click: paint with the colour — the first material of it, lambertian
//! first, else a new lambertian one; right-click: edit it), the current material (a dielectric
//! with too few scene bounces says so and offers `DIELECTRIC_BOUNCES`) and a History section
//! (click a step to undo / redo to it; the dropped count); each collapses to a strip, and a
//! window too narrow for both docks and a 240-point viewport folds the palette's, then the
//! tools' (the user's choice returns when it is wide again). The Terrain window floats over the
//! viewport.

use super::intent::{Action, UiEvent};
use super::swatch::{DIELECTRIC_BOUNCES, kind_name, rgb, swatch};
use super::tools::{Brush, MAX_SIZE, Tool};
use crate::editor::Document;
use crate::editor::command::{
    Axis, BrushMode, BrushShape, KindSpec, MaterialSpec, NoiseKind, TerrainSpec,
};
use brickmap::{MaterialKind, MaterialTable};

/// Which editing windows are shown, and the palette's selected colour.
#[derive(Default)]
pub struct EditingState {
    /// The tools window is hidden (shown by default).
    pub tools_hidden: bool,
    /// The palette dock is collapsed (shown by default).
    pub palette_hidden: bool,
    /// The history section of the palette dock is open.
    pub history_open: bool,
    /// The colour selected in the palette grid.
    pub colour: u8,
    /// Where the palette's 16 × 16 grid of colours was drawn (points, last frame; None
    /// while its dock is collapsed).
    pub palette_grid: Option<egui::Rect>,
    /// The terrain window, with its parameters.
    pub terrain: Option<TerrainSpec>,
}

/// The docks' width in points: the palette's 16 columns of swatches and the tools' rows.
const DOCK_WIDTH: f32 = 236.0;
/// The narrowest viewport the docks leave; a narrower window folds them.
const MIN_VIEWPORT: f32 = 240.0;

/// The docked panels, at the window's sides: Tools on the left; the 256 colours, the
/// current material and the history on the right. Each collapses to a strip with the button
/// that brings it back; the viewport is what they leave.
pub fn docks(
    root: &mut egui::Ui,
    state: &mut EditingState,
    doc: &Document,
    brush: &mut Brush,
    out: &mut Vec<UiEvent>,
) {
    let table = doc.scene.world.materials();
    // The table can shrink (an undone addition, unused materials removed): the current
    // material stays an entry of it.
    brush.material = brush.material.min((table.len() - 1) as u8);
    // A narrow window keeps a usable viewport: the palette's dock folds first, then the
    // tools' (the user's choice comes back when the window is wide again).
    let width = root.available_rect_before_wrap().width();
    let show_tools = !state.tools_hidden && width >= DOCK_WIDTH + MIN_VIEWPORT;
    let docks = if show_tools { 2.0 } else { 1.0 };
    let show_palette = !state.palette_hidden && width >= docks * DOCK_WIDTH + MIN_VIEWPORT;
    let tools_toggled = dock(root, "tools", true, "Tools", show_tools, |ui| {
        tools(ui, brush, &table, doc, out)
    });
    if let Some(hidden) = tools_toggled {
        state.tools_hidden = hidden;
    }
    if !show_palette {
        state.palette_grid = None;
    }
    let selected = doc.scene.selection.is_some();
    let palette_toggled = dock(
        root,
        "palette",
        false,
        "Palette and materials",
        show_palette,
        |ui| {
            palette(
                ui,
                state,
                brush,
                &table,
                selected,
                &doc.scene.params.settings,
                out,
            );
            ui.separator();
            let header = egui::CollapsingHeader::new("History")
                .open(Some(state.history_open))
                .show(ui, |ui| history(ui, doc, out));
            if header.header_response.clicked() {
                state.history_open = !state.history_open;
            }
        },
    );
    if let Some(hidden) = palette_toggled {
        state.palette_hidden = hidden;
    }
}

/// A dock at the window's left or right side: `title` with a hide button over `content`
/// (scrolling), or — when not `shown` (hidden, or no room) — a strip whose button shows
/// it. Some(hidden) when the user clicked either button.
fn dock(
    root: &mut egui::Ui,
    id: &str,
    left: bool,
    title: &str,
    shown: bool,
    content: impl FnOnce(&mut egui::Ui),
) -> Option<bool> {
    let side = |id: String| {
        if left {
            egui::Panel::left(id)
        } else {
            egui::Panel::right(id)
        }
        .resizable(false)
    };
    // Arrows point where the dock goes: towards its side to hide, away to show.
    let (hide, show) = if left { ("⏴", "⏵") } else { ("⏵", "⏴") };
    if !shown {
        let label = format!("Show {title} (a narrow window folds it)");
        let clicked = side(format!("{id} strip"))
            .exact_size(24.0)
            .show(root, |ui| ui.button(show).on_hover_text(label).clicked())
            .inner;
        return clicked.then_some(false);
    }
    side(id.to_string())
        .exact_size(DOCK_WIDTH)
        .show(root, |ui| {
            // The hide button at the dock's outer edge, the title beside it.
            let hidden = ui
                .horizontal(|ui| {
                    if left {
                        ui.strong(title);
                        ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                            ui.small_button(hide).on_hover_text("Hide").clicked()
                        })
                        .inner
                    } else {
                        let clicked = ui.small_button(hide).on_hover_text("Hide").clicked();
                        ui.strong(title);
                        clicked
                    }
                })
                .inner;
            egui::ScrollArea::vertical().show(ui, content);
            hidden.then_some(true)
        })
        .inner
}

/// Draws the editing windows that float over the viewport (terrain).
pub fn draw(
    ctx: &egui::Context,
    area: egui::Rect,
    state: &mut EditingState,
    doc: &Document,
    out: &mut Vec<UiEvent>,
) {
    if let Some(spec) = &mut state.terrain {
        let mut open = true;
        // The terrain fills the object brushes edit.
        let height = doc.scene.active_size().map_or(0, |s| s.y as u32);
        window(area, "Terrain and water")
            .open(&mut open)
            .show(ctx, |ui| terrain(ui, spec, height, out));
        if !open {
            state.terrain = None;
        }
    }
}

fn tools(
    ui: &mut egui::Ui,
    brush: &mut Brush,
    table: &MaterialTable,
    doc: &Document,
    out: &mut Vec<UiEvent>,
) {
    ui.horizontal_wrapped(|ui| {
        for (m, name) in [
            (BrushMode::Attach, "Attach  T"),
            (BrushMode::Erase, "Erase  X"),
            (BrushMode::Paint, "Paint  P"),
        ] {
            let on = brush.tool == Tool::Brush && brush.mode == m;
            if ui.selectable_label(on, name).clicked() {
                brush.mode = m;
                brush.tool = Tool::Brush;
            }
        }
        ui.selectable_value(&mut brush.tool, Tool::Select, "Select  M");
        ui.selectable_value(&mut brush.tool, Tool::Arrange, "Arrange  Tab");
        ui.selectable_value(&mut brush.tool, Tool::Measure, "Measure  K");
        ui.selectable_value(&mut brush.tool, Tool::Extrude, "Extrude  U");
        ui.selectable_value(&mut brush.tool, Tool::Stamp, "Stamp  J");
    });
    ui.horizontal_wrapped(|ui| {
        for (s, name) in [
            (BrushShape::Voxel, "Voxel V"),
            (BrushShape::Sphere, "Sphere B"),
            (BrushShape::Cube, "Cube C"),
            (BrushShape::Cylinder, "Cylinder Y"),
            (BrushShape::Line, "Line L"),
            (BrushShape::Box, "Box R"),
        ] {
            ui.selectable_value(&mut brush.shape, s, name);
        }
    });
    ui.add(
        egui::Slider::new(&mut brush.size, 1.0..=MAX_SIZE)
            .step_by(1.0)
            .text("size  [ ]"),
    );
    if brush.shape == BrushShape::Cylinder {
        ui.horizontal_wrapped(|ui| {
            ui.label("cylinder axis");
            for (a, name) in [(Axis::X, "X"), (Axis::Y, "Y"), (Axis::Z, "Z")] {
                ui.selectable_value(&mut brush.axis, a, name);
            }
        });
    }
    if brush.mode == BrushMode::Attach && brush.shape != BrushShape::Box {
        ui.checkbox(&mut brush.follow_surface, "follow the surface")
            .on_hover_text(
                "on: each point of a stroke attaches to the face under the cursor;
 off: the stroke keeps to the first face's layer (shown while drawing)",
            );
    }
    if brush.tool == Tool::Stamp {
        ui.horizontal_wrapped(|ui| {
            ui.label(format!("stamp turned {}°", brush.stamp_quarters * 90));
            if ui.button("turn  H").clicked() {
                brush.stamp_quarters = (brush.stamp_quarters + 1).rem_euclid(4);
            }
        });
        if doc.scene.clipboard.is_none() {
            ui.label("the stamp is the clipboard: select, then Ctrl + C");
        }
    }
    if brush.tool == Tool::Extrude {
        ui.checkbox(
            &mut brush.extrude_same_material,
            "extrude: same material only",
        );
    }
    ui.horizontal_wrapped(|ui| {
        ui.label("mirror");
        ui.checkbox(&mut brush.mirror[0], "X");
        ui.checkbox(&mut brush.mirror[1], "Y");
        ui.checkbox(&mut brush.mirror[2], "Z");
    });
    if brush.mirror.iter().any(|m| *m) {
        let dims = doc.scene.world.dims().voxels();
        let mut c = brush.centre(dims);
        ui.horizontal_wrapped(|ui| {
            ui.label("centre");
            let mut changed = false;
            for k in 0..3 {
                changed |= ui
                    .add(
                        egui::DragValue::new(&mut c[k])
                            .speed(0.5)
                            .range(0.0..=dims[k] as f64),
                    )
                    .changed();
            }
            if changed {
                brush.mirror_centre = Some(c);
            }
            if ui.button("scene centre").clicked() {
                brush.mirror_centre = None;
            }
        });
    }
    ui.separator();
    super::paint_panel::material(ui, brush, table);
    ui.separator();
    super::selection_panel::selection(ui, brush, doc, out);
}

fn palette(
    ui: &mut egui::Ui,
    state: &mut EditingState,
    brush: &mut Brush,
    table: &MaterialTable,
    selected: bool,
    settings: &render::RenderSettings,
    out: &mut Vec<UiEvent>,
) {
    let current = table.get(brush.material).map(|m| m.colour).ok();
    let grid = egui::Grid::new("palette")
        .spacing(egui::vec2(1.0, 1.0))
        .min_col_width(12.5)
        .min_row_height(12.5)
        .show(ui, |ui| {
            for row in 0..16u8 {
                for col in 0..16u8 {
                    let i = row * 16 + col;
                    let r = swatch(ui, rgb(table, i), None, current == Some(i), 12.5)
                        .on_hover_text(format!(
                            "colour {i} · click: paint with it · right-click: edit it"
                        ));
                    if r.clicked() {
                        paint_with_colour(i, state, brush, table, out);
                    }
                    if r.secondary_clicked() {
                        state.colour = i;
                    }
                }
                ui.end_row();
            }
        });
    state.palette_grid = Some(grid.response.rect);
    ui.horizontal_wrapped(|ui| {
        let mut c = table.colour(state.colour);
        ui.label(format!("colour {}", state.colour));
        if ui.color_edit_button_srgb(&mut c).changed() {
            out.push(UiEvent::SetColour {
                index: state.colour,
                rgb: c,
            });
        }
        ui.menu_button("palette file", |ui| {
            if ui
                .button("Load palette…")
                .on_hover_text("a 256 × 1 PNG strip or a .vox file")
                .clicked()
            {
                out.push(UiEvent::PaletteFile { save: false });
            }
            if ui.button("Save palette as PNG…").clicked() {
                out.push(UiEvent::PaletteFile { save: true });
            }
        });
    });
    ui.separator();
    let Ok(m) = table.get(brush.material) else {
        return;
    };
    ui.label(format!(
        "material {} ({} of 256)",
        brush.material,
        table.len()
    ))
    .on_hover_text("an edit here changes every voxel of this material");
    if m.kind == MaterialKind::Dielectric && settings.max_bounces < DIELECTRIC_BOUNCES {
        // Paths end inside the glass: it shows dark until light can pass through it.
        ui.colored_label(
            ui.visuals().warn_fg_color,
            format!("shows dark at {} bounces", settings.max_bounces),
        )
        .on_hover_text(format!(
            "light needs {DIELECTRIC_BOUNCES} bounces to pass through glass or water"
        ));
        if ui
            .button(format!("use {DIELECTRIC_BOUNCES} bounces"))
            .on_hover_text("the scene's bounces (Render settings; one step in the history)")
            .clicked()
        {
            let mut more = settings.clone();
            more.max_bounces = DIELECTRIC_BOUNCES;
            out.push(UiEvent::SetSettings(more));
        }
    }
    ui.weak("changes every voxel of this material");
    let mut spec: MaterialSpec = m.into();
    let before = spec;
    egui::ComboBox::from_label("type")
        .selected_text(kind_name(m.kind))
        .show_ui(ui, |ui| {
            for k in [
                KindSpec::Lambertian,
                KindSpec::Metal,
                KindSpec::Dielectric,
                KindSpec::Emissive,
            ] {
                ui.selectable_value(&mut spec.kind, k, kind_name(k.into()));
            }
        });
    if m.kind != MaterialKind::Lambertian {
        // Names above their sliders: beside them they would pass the dock's width.
        egui::CollapsingHeader::new("parameter slot")
            .id_salt("material slot")
            .show(ui, |ui| {
                ui.weak("materials of a kind that share a slot share its value");
                ui.add(egui::Slider::new(&mut spec.param, 0..=63));
            });
        let (name, lo, hi) = match m.kind {
            MaterialKind::Metal => ("roughness", 0.0, 1.0),
            MaterialKind::Dielectric => ("index of refraction", 1.0, 4.0),
            _ => ("strength", 0.0, 100.0),
        };
        ui.label(name);
        if let Ok(mut value) = table.param(m.kind, m.param)
            && ui.add(egui::Slider::new(&mut value, lo..=hi)).changed()
        {
            out.push(UiEvent::SetParam {
                kind: spec.kind,
                index: m.param,
                value,
            });
        }
    }
    ui.horizontal_wrapped(|ui| {
        swatch(ui, rgb(table, m.colour), Some(m.kind), false, 16.0);
        ui.label(format!("colour {}", m.colour));
        if m.colour != state.colour
            && ui
                .button(format!("use {}", state.colour))
                .on_hover_text("the colour selected in the palette")
                .clicked()
        {
            spec.colour = state.colour;
        }
    });
    if spec != before {
        out.push(UiEvent::SetMaterial {
            index: brush.material,
            material: spec,
        });
    }
    ui.horizontal_wrapped(|ui| {
        if table.len() < 256
            && ui
                .button("duplicate")
                .on_hover_text("a new material, a copy of this one, for the brush")
                .clicked()
        {
            out.push(UiEvent::AddMaterial(spec));
            brush.material = table.len() as u8;
        }
        if table.len() > 1
            && ui
                .button("remove unused")
                .on_hover_text("drop the materials no voxel uses; later ones move down")
                .clicked()
        {
            out.push(UiEvent::Action(Action::RemoveUnusedMaterials));
        }
        // The selected voxels get a material of their own, to edit apart from the rest.
        if table.len() < 256
            && selected
            && ui
                .button("make a new one for the selection")
                .on_hover_text("a copy of this material, painted on the selected voxels (two steps in the history)")
                .clicked()
        {
            // The paint reads the brush's material when the events are applied: the new one.
            brush.material = table.len() as u8;
            out.push(UiEvent::AddMaterial(spec));
            out.push(UiEvent::Action(Action::PaintSelection));
        }
    });
}

/// A palette click: the brush paints with colour `i` — the first material of that colour
/// (a lambertian one first), else a new lambertian material of it.
fn paint_with_colour(
    i: u8,
    state: &mut EditingState,
    brush: &mut Brush,
    table: &MaterialTable,
    out: &mut Vec<UiEvent>,
) {
    state.colour = i;
    brush.tool = Tool::Brush;
    let of_colour = |lambertian: bool| {
        (0..table.len()).find(|&k| {
            table
                .get(k as u8)
                .is_ok_and(|m| m.colour == i && (!lambertian || m.kind == MaterialKind::Lambertian))
        })
    };
    match of_colour(true).or_else(|| of_colour(false)) {
        Some(k) => brush.material = k as u8,
        None if table.len() < 256 => {
            out.push(UiEvent::AddMaterial(MaterialSpec {
                kind: KindSpec::Lambertian,
                param: 0,
                colour: i,
            }));
            brush.material = table.len() as u8;
        }
        None => {}
    }
}

fn history(ui: &mut egui::Ui, doc: &Document, out: &mut Vec<UiEvent>) {
    let h = &doc.history;
    ui.label(format!(
        "{} steps, {:.1} MiB{}",
        h.undo_len() + h.redo_len(),
        h.bytes() as f64 / (1 << 20) as f64,
        if h.dropped() > 0 {
            format!(
                "; the {} oldest dropped to stay within the memory budget",
                h.dropped()
            )
        } else {
            String::new()
        }
    ));
    egui::ScrollArea::vertical()
        .max_height(320.0)
        .show(ui, |ui| {
            let undo: Vec<_> = h.undo_steps().collect();
            let n = undo.len();
            for (k, step) in undo.iter().enumerate() {
                let text = format!("{}  ({} voxels)", step.label, step.changed_voxels);
                let current = k + 1 == n;
                if ui.selectable_label(current, text).clicked() && !current {
                    out.push(UiEvent::Jump {
                        undo: n - 1 - k,
                        redo: 0,
                    });
                }
            }
            for (j, step) in h.redo_steps().enumerate() {
                let text = egui::RichText::new(format!(
                    "{}  ({} voxels)",
                    step.label, step.changed_voxels
                ))
                .weak();
                if ui.selectable_label(false, text).clicked() {
                    out.push(UiEvent::Jump {
                        undo: 0,
                        redo: j + 1,
                    });
                }
            }
        });
}

fn terrain(ui: &mut egui::Ui, spec: &mut TerrainSpec, height: u32, out: &mut Vec<UiEvent>) {
    egui::ComboBox::from_label("noise")
        .selected_text(format!("{:?}", spec.noise))
        .show_ui(ui, |ui| {
            for n in [
                NoiseKind::Perlin,
                NoiseKind::OpenSimplex,
                NoiseKind::SuperSimplex,
                NoiseKind::Value,
            ] {
                ui.selectable_value(&mut spec.noise, n, format!("{n:?}"));
            }
        });
    ui.add(egui::DragValue::new(&mut spec.seed).prefix("seed "));
    ui.add(
        egui::Slider::new(&mut spec.scale, 4.0..=4096.0)
            .logarithmic(true)
            .text("scale (voxels)"),
    );
    ui.add(egui::Slider::new(&mut spec.octaves, 1..=10).text("octaves"));
    let top = height.saturating_sub(1);
    ui.add(egui::Slider::new(&mut spec.height_range.0, 0..=top).text("lowest ground"));
    ui.add(egui::Slider::new(&mut spec.height_range.1, 0..=top).text("highest ground"));
    spec.height_range.1 = spec.height_range.1.max(spec.height_range.0);
    ui.add(egui::Slider::new(&mut spec.water_level, 0..=top).text("water level (0: none)"));
    ui.label("material bands (by surface height, from lowest to highest ground)");
    let b = &mut spec.bands;
    ui.add(egui::Slider::new(&mut b.rock_line, 0.0..=1.0).text("rock above"));
    ui.add(egui::Slider::new(&mut b.snow_line, 0.0..=1.0).text("snow above"));
    b.snow_line = b.snow_line.max(b.rock_line);
    ui.add(egui::Slider::new(&mut b.soil_depth, 0..=32).text("soil depth (grass, dirt)"));
    ui.label("Sand lines the water; colours are in the palette after generating.");
    ui.label(
        "Replaces every voxel of the object brushes edit, filling its box (one undoable step).",
    );
    if ui.button("Generate").clicked() {
        out.push(UiEvent::Generate(spec.clone()));
    }
}

/// The egui id of the panel window titled `title` (where it is, as last drawn, is kept under
/// it).
pub(super) fn window_id(title: &str) -> egui::Id {
    egui::Id::new(("panel window", title))
}

/// The width a panel window opens with (the user may widen or narrow it).
pub(super) const WINDOW_WIDTH: f32 = 340.0;

/// A window kept inside `area` (the viewport between the panels): as tall as what it holds,
/// scrolling past the area's height, as wide as [`WINDOW_WIDTH`] until the user drags its
/// side. (egui's default window is resizable both ways with a scroll area that never
/// shrinks: 420 points tall whatever it holds.)
pub(super) fn window(area: egui::Rect, title: &str) -> egui::Window<'_> {
    egui::Window::new(title)
        .id(window_id(title))
        .constrain_to(area)
        .auto_sized()
        .vscroll(true)
        .default_width(WINDOW_WIDTH)
        .resizable([true, false])
        .max_height(area.height() - 40.0)
}
