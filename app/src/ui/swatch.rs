//! How a material looks in the panels: a square of its colour, drawn so the kind shows —
//! glass and water as a tint over a checkerboard (what shows through them), metal with a
//! highlight, a lamp glowing. A plain square for every kind read as "paint with this
//! colour", and a glass swatch then painted something else.

use brickmap::{MaterialKind, MaterialTable};
use egui::{Color32, Pos2, Rect, Shape, Stroke};

/// How many bounces a path needs before glass and water look like themselves in the
/// viewport: in, out, and the light behind (measured on a glass and a water cube on a
/// floor: black faces at 3 bounces, right from 5).
pub const DIELECTRIC_BOUNCES: u32 = 5;

/// The colour-table entry `colour` as an egui colour.
pub fn rgb(table: &MaterialTable, colour: u8) -> Color32 {
    let [r, g, b] = table.colour(colour);
    Color32::from_rgb(r, g, b)
}

/// A material kind's name, as the panels write it.
pub fn kind_name(k: MaterialKind) -> &'static str {
    match k {
        MaterialKind::Lambertian => "lambertian",
        MaterialKind::Metal => "metal",
        MaterialKind::Dielectric => "dielectric",
        MaterialKind::Emissive => "emissive",
    }
}

/// A square swatch of `colour` drawn as `kind` (None: a palette colour, no material);
/// a white frame when `selected`. Returns its response (clickable).
pub fn swatch(
    ui: &mut egui::Ui,
    colour: Color32,
    kind: Option<MaterialKind>,
    selected: bool,
    size: f32,
) -> egui::Response {
    let (rect, response) = ui.allocate_exact_size(egui::vec2(size, size), egui::Sense::click());
    ui.painter().extend(shapes(rect, colour, kind));
    if selected {
        ui.painter().rect_stroke(
            rect,
            2.0,
            Stroke::new(2.0, Color32::WHITE),
            egui::StrokeKind::Outside,
        );
    }
    response
}

/// The shapes of a swatch in `rect`.
pub fn shapes(rect: Rect, colour: Color32, kind: Option<MaterialKind>) -> Vec<Shape> {
    match kind {
        None | Some(MaterialKind::Lambertian) => vec![Shape::rect_filled(rect, 2.0, colour)],
        Some(MaterialKind::Dielectric) => {
            // A 2 × 2 checkerboard behind a translucent tint, and a glint along the top.
            let mut out = Vec::with_capacity(6);
            let half = rect.size() * 0.5;
            for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let min = rect.min + egui::vec2(i as f32 * half.x, j as f32 * half.y);
                let light = (i + j) % 2 == 0;
                let grey = if light { 215 } else { 95 };
                out.push(Shape::rect_filled(
                    Rect::from_min_size(min, half),
                    0.0,
                    Color32::from_gray(grey),
                ));
            }
            let [r, g, b, _] = colour.to_array();
            out.push(Shape::rect_filled(
                rect,
                2.0,
                Color32::from_rgba_unmultiplied(r, g, b, 150),
            ));
            out.push(glint(rect, Color32::from_white_alpha(200)));
            out
        }
        Some(MaterialKind::Metal) => {
            // Darker body, a lighter upper-left half: a polished sheen.
            let dark = scale(colour, 0.55);
            let light = lerp_white(colour, 0.45);
            vec![
                Shape::rect_filled(rect, 2.0, dark),
                Shape::convex_polygon(
                    vec![rect.left_top(), rect.right_top(), rect.left_bottom()],
                    light,
                    Stroke::NONE,
                ),
                glint(rect, Color32::WHITE),
            ]
        }
        Some(MaterialKind::Emissive) => {
            // A bright core with a ring of the colour: a lamp.
            let core = lerp_white(colour, 0.6);
            vec![
                Shape::rect_filled(rect, 2.0, colour),
                Shape::circle_filled(rect.center(), rect.width() * 0.3, core),
                Shape::circle_stroke(
                    rect.center(),
                    rect.width() * 0.42,
                    Stroke::new(1.0, Color32::from_rgb(255, 244, 200)),
                ),
            ]
        }
    }
}

/// A short light line across the upper-left corner.
fn glint(rect: Rect, colour: Color32) -> Shape {
    let a = rect.min + rect.size() * egui::vec2(0.2, 0.45);
    let b = rect.min + rect.size() * egui::vec2(0.45, 0.2);
    Shape::line_segment(
        [Pos2::new(a.x, a.y), Pos2::new(b.x, b.y)],
        Stroke::new(1.5, colour),
    )
}

fn scale(c: Color32, k: f32) -> Color32 {
    let [r, g, b, _] = c.to_array();
    let f = |v: u8| (f32::from(v) * k).round() as u8;
    Color32::from_rgb(f(r), f(g), f(b))
}

fn lerp_white(c: Color32, t: f32) -> Color32 {
    let [r, g, b, _] = c.to_array();
    let f = |v: u8| (f32::from(v) + (255.0 - f32::from(v)) * t).round() as u8;
    Color32::from_rgb(f(r), f(g), f(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fills(shapes: &[Shape]) -> Vec<Color32> {
        shapes
            .iter()
            .filter_map(|s| match s {
                Shape::Rect(r) => Some(r.fill),
                Shape::Path(p) => Some(p.fill),
                Shape::Circle(c) => Some(c.fill),
                _ => None,
            })
            .filter(|c| *c != Color32::TRANSPARENT)
            .collect()
    }

    #[test]
    fn each_kind_looks_different_from_a_plain_colour() {
        let rect = Rect::from_min_size(Pos2::ZERO, egui::vec2(18.0, 18.0));
        let blue = Color32::from_rgb(40, 90, 220);
        let plain = shapes(rect, blue, Some(MaterialKind::Lambertian));
        assert_eq!(fills(&plain), vec![blue]);
        assert_eq!(fills(&shapes(rect, blue, None)), vec![blue]);
        // Glass: a light and a dark square show through a translucent tint of its colour.
        let glass = fills(&shapes(rect, blue, Some(MaterialKind::Dielectric)));
        assert!(
            glass.contains(&Color32::from_gray(215)) && glass.contains(&Color32::from_gray(95))
        );
        let tint = glass.last().unwrap();
        assert!(
            tint.a() < 255 && tint.a() > 0,
            "the tint is translucent: {tint:?}"
        );
        // Metal: two tones of its colour, neither the plain one.
        let metal = fills(&shapes(rect, blue, Some(MaterialKind::Metal)));
        assert_eq!(metal.len(), 2);
        assert!(!metal.contains(&blue) && metal[0] != metal[1]);
        // A lamp: a core brighter than its colour.
        let lamp = fills(&shapes(rect, blue, Some(MaterialKind::Emissive)));
        let core = lamp[1];
        assert!(core.r() > blue.r() && core.g() > blue.g() && core.b() >= blue.b());
    }
}
