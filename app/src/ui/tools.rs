//! The editor's tools: the brush settings (mode, shape, size, material, mirror), picking what
//! is under the cursor with the brickmap's exact CPU ray cast, and where a stroke's next
//! point goes. Attach strokes and boxes stay on the plane of the face first clicked (so a
//! drag paints a layer instead of climbing towards the camera); erase and paint follow the
//! surface under the cursor. Pure functions of the world and the ray, tested here.

use crate::editor::command::{Axis, BrushMode, BrushShape, Mirror, PaintMode, Stroke};
use brickmap::{Ray, WorldView};
use glam::{DVec3, IVec3};
use serde::{Deserialize, Serialize};

/// The brush as the tools panel sets it (view state, kept in settings.ron).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Brush {
    /// Attach, erase or paint.
    pub mode: BrushMode,
    /// The shape at each point.
    pub shape: BrushShape,
    /// Radius or half-size in voxels (1..=64).
    pub size: f64,
    /// Material index for attach and paint.
    pub material: u8,
    /// Mirror across x, y, z.
    pub mirror: [bool; 3],
    /// The mirror planes' point (None: the grid's centre).
    pub mirror_centre: Option<DVec3>,
    /// The cylinder's axis.
    pub axis: Axis,
    /// Change only selected voxels (when something is selected).
    pub in_selection: bool,
    /// The brush or the selection tool.
    pub tool: Tool,
    /// How deep a selection box goes into the surface, in voxels.
    pub select_depth: i32,
    /// An attach stroke follows the surface under the cursor (each point on the face it
    /// hits) instead of keeping to the first face's layer.
    pub follow_surface: bool,
    /// How the selection tool selects.
    pub select_mode: SelectMode,
    /// The magic wand joins voxels through edges and corners too (26), not only faces (6).
    pub wand_diagonal: bool,
    /// The Extrude tool takes only the clicked voxel's material.
    pub extrude_same_material: bool,
    /// How attach and paint strokes colour the voxels (solid, gradient, random, darken,
    /// brighten).
    pub paint: PaintMode,
    /// The Stamp tool's quarter turns about the vertical (0..4).
    pub stamp_quarters: i32,
}

/// How the selection tool selects.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum SelectMode {
    /// A box dragged on a face.
    #[default]
    Box,
    /// A click: the connected voxels of the clicked one's material.
    WandColour,
    /// A click: the connected solid voxels.
    WandSolid,
    /// A click on a face: its connected coplanar exposed region.
    WandFace,
    /// A rectangle dragged on the screen: every solid voxel inside, through all depth.
    Rect,
    /// A rectangle dragged on the screen: the voxels it shows.
    RectVisible,
}

impl SelectMode {
    /// Shift + M: the next mode.
    pub fn next(self) -> Self {
        match self {
            SelectMode::Box => SelectMode::WandColour,
            SelectMode::WandColour => SelectMode::WandSolid,
            SelectMode::WandSolid => SelectMode::WandFace,
            SelectMode::WandFace => SelectMode::Rect,
            SelectMode::Rect => SelectMode::RectVisible,
            SelectMode::RectVisible => SelectMode::Box,
        }
    }
}

/// What the left button does in the viewport.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Tool {
    /// Draw with the brush.
    #[default]
    Brush,
    /// Drag selection boxes.
    Select,
    /// Pick and move objects (arrange mode).
    Arrange,
    /// Measure between two voxels (the ruler).
    Measure,
    /// Drag a face along its normal (extrude, push-pull).
    Extrude,
    /// Stamp the clipboard along a drag.
    Stamp,
}

impl Default for Brush {
    fn default() -> Self {
        Self {
            mode: BrushMode::Attach,
            shape: BrushShape::Sphere,
            size: 3.0,
            material: 0,
            mirror: [false; 3],
            mirror_centre: None,
            axis: Axis::Y,
            in_selection: false,
            tool: Tool::Brush,
            select_depth: 16,
            follow_surface: false,
            select_mode: SelectMode::Box,
            wand_diagonal: false,
            extrude_same_material: false,
            paint: PaintMode::Solid,
            stamp_quarters: 0,
        }
    }
}

/// Largest brush size.
pub const MAX_SIZE: f64 = 64.0;

impl Brush {
    /// A stroke of this brush through `points` (voxel centres) in a grid of `dims` voxels.
    pub fn stroke(&self, points: Vec<DVec3>, dims: IVec3) -> Stroke {
        Stroke {
            mode: self.mode,
            shape: self.shape,
            size: self.size,
            material: self.material,
            mirror: Mirror {
                x: self.mirror[0],
                y: self.mirror[1],
                z: self.mirror[2],
                centre: self.centre(dims),
            },
            points,
            axis: self.axis,
            in_selection: self.in_selection,
            paint: match (self.mode, &self.paint) {
                (BrushMode::Erase, _) => PaintMode::Solid,
                (BrushMode::Attach, PaintMode::Darken | PaintMode::Brighten) => PaintMode::Solid,
                (_, p) => p.clone(),
            },
        }
    }

    /// The mirror planes' point.
    pub fn centre(&self, dims: IVec3) -> DVec3 {
        self.mirror_centre.unwrap_or(dims.as_dvec3() * 0.5)
    }

    /// N: the next colour mode (darken and brighten only while painting); a gradient starts
    /// and ends at the current material, random picks among it alone, until chosen.
    pub fn next_colour_mode(&mut self) {
        let paint = self.mode == BrushMode::Paint;
        self.paint = match self.paint {
            PaintMode::Solid => PaintMode::Gradient { to: self.material },
            PaintMode::Gradient { .. } => PaintMode::Random {
                among: vec![self.material],
                seed: 1,
            },
            PaintMode::Random { .. } if paint => PaintMode::Darken,
            PaintMode::Darken => PaintMode::Brighten,
            _ => PaintMode::Solid,
        };
    }

    /// `[` / `]`: one smaller or larger, within 1..=[`MAX_SIZE`].
    pub fn resize(&mut self, by: f64) {
        self.size = (self.size.round() + by).clamp(1.0, MAX_SIZE);
    }
}

/// What the cursor's ray hits: the solid voxel and the face it entered through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Hit {
    /// The solid voxel.
    pub voxel: IVec3,
    /// Unit normal of the face (towards the camera).
    pub normal: IVec3,
}

/// The exact CPU ray cast of the cursor's ray.
pub fn pick(view: &WorldView<'_>, origin: DVec3, dir: DVec3) -> Option<(Hit, u8)> {
    let (hit, material) = view
        .ray_cast(&Ray { origin, dir }, f64::INFINITY)
        .ok()
        .flatten()?;
    Some((
        Hit {
            voxel: hit.voxel,
            normal: hit.normal,
        },
        material,
    ))
}

/// The plane a stroke keeps to: voxels whose coordinate on `axis` is `layer`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layer {
    /// 0, 1 or 2.
    pub axis: usize,
    /// The voxel coordinate on that axis.
    pub layer: i32,
}

/// Where a click starts a stroke: the empty voxel in front of the face (attach) or the
/// voxel itself (erase, paint), and the layer later points keep to (attach and boxes).
/// Attach on empty space starts on the grid's floor (y = 0) where the ray meets it.
pub fn start(
    view: &WorldView<'_>,
    mode: BrushMode,
    origin: DVec3,
    dir: DVec3,
) -> Option<(IVec3, Layer)> {
    let dims = view.dims().voxels();
    match (pick(view, origin, dir), mode) {
        (Some((hit, _)), BrushMode::Attach) => {
            let v = hit.voxel + hit.normal;
            let axis = axis_of(hit.normal);
            (view.dims().contains_voxel(v)).then_some((
                v,
                Layer {
                    axis,
                    layer: v[axis],
                },
            ))
        }
        (Some((hit, _)), _) => {
            let axis = axis_of(hit.normal);
            Some((
                hit.voxel,
                Layer {
                    axis,
                    layer: hit.voxel[axis],
                },
            ))
        }
        (None, BrushMode::Attach) => {
            let floor = Layer { axis: 1, layer: 0 };
            on_layer(floor, origin, dir, dims).map(|v| (v, floor))
        }
        (None, _) => None,
    }
}

/// The next point of a stroke under the cursor: on the stroke's layer for attach strokes
/// and boxes (an attach stroke that follows the surface: in front of the face under the
/// cursor), else the voxel under the cursor (None: the cursor is off the scene).
pub fn next(
    view: &WorldView<'_>,
    brush: &Brush,
    layer: Layer,
    origin: DVec3,
    dir: DVec3,
) -> Option<IVec3> {
    if brush.mode == BrushMode::Attach && brush.follow_surface && brush.shape != BrushShape::Box {
        start(view, BrushMode::Attach, origin, dir).map(|(v, _)| v)
    } else if brush.mode == BrushMode::Attach || brush.shape == BrushShape::Box {
        on_layer(layer, origin, dir, view.dims().voxels())
    } else {
        pick(view, origin, dir).map(|(hit, _)| hit.voxel)
    }
}

/// The voxel of `layer` the ray passes through at the layer's mid-plane, if it is in the grid.
pub fn on_layer(layer: Layer, origin: DVec3, dir: DVec3, dims: IVec3) -> Option<IVec3> {
    let a = layer.axis;
    if dir[a].abs() < 1e-9 {
        return None;
    }
    let t = (layer.layer as f64 + 0.5 - origin[a]) / dir[a];
    if t <= 0.0 {
        return None;
    }
    let mut v = (origin + dir * t).floor().as_ivec3();
    v[a] = layer.layer;
    (v.cmpge(IVec3::ZERO).all() && v.cmplt(dims).all()).then_some(v)
}

fn axis_of(normal: IVec3) -> usize {
    if normal.x != 0 {
        0
    } else if normal.y != 0 {
        1
    } else {
        2
    }
}

/// A voxel's centre: the point a stroke passes through.
pub fn centre(v: IVec3) -> DVec3 {
    v.as_dvec3() + 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use brickmap::{EditOp, GridDims, Mode, Shape, World, WorldConfig};

    /// A 32³ grid with a floor (y 0..=3) and a pillar at x, z 10..=12 up to y 10.
    fn world() -> World {
        let w = World::new(
            GridDims::new(4, 4, 4).unwrap(),
            WorldConfig::with_workers(1),
        )
        .unwrap();
        for (min, max) in [
            (IVec3::ZERO, IVec3::new(31, 3, 31)),
            (IVec3::new(10, 4, 10), IVec3::new(12, 10, 12)),
        ] {
            w.apply(EditOp::Shape {
                shape: Shape::Box { min, max },
                mode: Mode::Add(0),
            })
            .unwrap();
        }
        w
    }

    #[test]
    fn an_attach_stroke_that_follows_the_surface_climbs_onto_the_pillar() {
        let w = world();
        let view = w.read();
        let down = DVec3::NEG_Y;
        let (_, layer) =
            start(&view, BrushMode::Attach, DVec3::new(20.5, 40.0, 20.5), down).unwrap();
        let brush = Brush {
            follow_surface: true,
            ..Brush::default()
        };
        let over = next(&view, &brush, layer, DVec3::new(11.5, 40.0, 11.5), down);
        assert_eq!(over, Some(IVec3::new(11, 11, 11)), "on top of the pillar");
        // Boxes keep to their layer whatever the option says.
        let boxed = Brush {
            shape: BrushShape::Box,
            ..brush
        };
        let over = next(&view, &boxed, layer, DVec3::new(11.5, 40.0, 11.5), down);
        assert_eq!(over, Some(IVec3::new(11, 4, 11)));
    }

    #[test]
    fn attach_starts_in_front_of_the_face_and_keeps_to_its_layer() {
        let w = world();
        let view = w.read();
        // Straight down onto the floor at (20, *, 20): the voxel above it, layer y = 4.
        let down = DVec3::NEG_Y;
        let (v, layer) =
            start(&view, BrushMode::Attach, DVec3::new(20.5, 40.0, 20.5), down).unwrap();
        assert_eq!(v, IVec3::new(20, 4, 20));
        assert_eq!(layer, Layer { axis: 1, layer: 4 });
        // Dragging over the pillar stays on y = 4 (the pillar is not climbed).
        let brush = Brush::default();
        let over = next(&view, &brush, layer, DVec3::new(11.5, 40.0, 11.5), down);
        assert_eq!(over, Some(IVec3::new(11, 4, 11)));
        // The pillar's side: attach in front of the +x face, layer x = 13.
        let (v, layer) = start(
            &view,
            BrushMode::Attach,
            DVec3::new(30.0, 7.5, 11.5),
            DVec3::NEG_X,
        )
        .unwrap();
        assert_eq!(v, IVec3::new(13, 7, 11));
        assert_eq!(layer, Layer { axis: 0, layer: 13 });
    }

    #[test]
    fn erase_and_paint_follow_the_surface_and_a_miss_attaches_to_the_floor() {
        let w = world();
        let view = w.read();
        let down = DVec3::NEG_Y;
        let (v, _) = start(&view, BrushMode::Erase, DVec3::new(11.5, 40.0, 11.5), down).unwrap();
        assert_eq!(v, IVec3::new(11, 10, 11), "the pillar's top");
        let brush = Brush {
            mode: BrushMode::Paint,
            ..Brush::default()
        };
        let layer = Layer { axis: 1, layer: 10 };
        assert_eq!(
            next(&view, &brush, layer, DVec3::new(20.5, 40.0, 20.5), down),
            Some(IVec3::new(20, 3, 20)),
            "paint follows the floor"
        );
        // Into the sky: erase finds nothing; attach lands on the floor plane where the ray
        // crosses y = 0.5 (here an empty grid, so the ray reaches it).
        assert_eq!(
            start(
                &view,
                BrushMode::Erase,
                DVec3::new(5.0, 40.0, 5.0),
                DVec3::Y
            ),
            None
        );
        let empty = World::new(
            GridDims::new(2, 2, 2).unwrap(),
            WorldConfig::with_workers(1),
        )
        .unwrap();
        let (v, layer) = start(
            &empty.read(),
            BrushMode::Attach,
            DVec3::new(3.5, 10.5, 3.5),
            DVec3::new(1.0, -1.0, 0.0).normalize(),
        )
        .unwrap();
        assert_eq!(
            (v, layer),
            (IVec3::new(13, 0, 3), Layer { axis: 1, layer: 0 })
        );
    }

    #[test]
    fn a_layer_parallel_to_the_ray_or_behind_it_gives_nothing() {
        let dims = IVec3::splat(32);
        let l = Layer { axis: 1, layer: 4 };
        assert_eq!(
            on_layer(l, DVec3::new(5.0, 10.0, 5.0), DVec3::X, dims),
            None
        );
        assert_eq!(
            on_layer(l, DVec3::new(5.0, 10.0, 5.0), DVec3::Y, dims),
            None
        );
        assert_eq!(
            on_layer(
                l,
                DVec3::new(40.0, 10.0, 5.0),
                DVec3::new(0.0, -1.0, 0.0),
                dims
            ),
            None,
            "outside the grid"
        );
    }

    #[test]
    fn the_colour_and_select_modes_cycle_back_to_the_start() {
        let mut b = Brush {
            mode: BrushMode::Paint,
            material: 3,
            ..Brush::default()
        };
        let mut seen = Vec::new();
        for _ in 0..5 {
            b.next_colour_mode();
            seen.push(std::mem::discriminant(&b.paint));
        }
        assert_eq!(b.paint, PaintMode::Solid, "five steps while painting");
        seen.dedup();
        assert_eq!(seen.len(), 5);
        b.mode = BrushMode::Attach;
        for _ in 0..3 {
            b.next_colour_mode();
        }
        assert_eq!(b.paint, PaintMode::Solid, "three while attaching");
        let mut m = SelectMode::Box;
        for _ in 0..6 {
            m = m.next();
        }
        assert_eq!(m, SelectMode::Box);
    }

    #[test]
    fn brush_sizes_stay_in_range_and_strokes_carry_the_mirror() {
        let mut b = Brush::default();
        for _ in 0..100 {
            b.resize(1.0);
        }
        assert_eq!(b.size, MAX_SIZE);
        for _ in 0..100 {
            b.resize(-1.0);
        }
        assert_eq!(b.size, 1.0);
        b.mirror = [true, false, true];
        let s = b.stroke(vec![DVec3::ONE], IVec3::new(64, 32, 16));
        assert!(s.mirror.x && !s.mirror.y && s.mirror.z);
        assert_eq!(s.mirror.centre, DVec3::new(32.0, 16.0, 8.0));
    }
}
