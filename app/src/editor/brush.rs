//! Brush strokes: modes, shapes, mirror symmetry, and the world edits a stroke makes.
//!
//! A stroke is one connected piece at any mouse speed: consecutive points are joined by the
//! brush's shape swept from one to the other. The sphere sweeps to capsules (exact); the
//! voxel, cube and cylinder are stamped at [`sweep_points`], steps of at most one voxel along
//! every axis, so consecutive stamps' voxels touch (the voxel brush draws a 26-connected 3D
//! line, the cube a swept box). The line brush was capsules already; the box brush is its
//! first and last points.

use super::error::{EditError, Result, invalid};
pub use super::paint::PaintMode;
use super::paint::{Image, coloured_edits};
use crate::selection::Selection;
use brickmap::{EditOp, Mode, Shape};
use glam::{DVec3, IVec3};
use serde::{Deserialize, Serialize};

/// What a brush does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BrushMode {
    /// Add solid voxels with the material.
    Attach,
    /// Remove voxels.
    Erase,
    /// Repaint solid voxels, keeping the shape.
    Paint,
}

/// The brush's shape at each stroke point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BrushShape {
    /// The voxel under the point.
    Voxel,
    /// A ball of radius `size` (swept to capsules between the stroke's points).
    Sphere,
    /// A cube of half-size `size` (edge 2·size + 1 voxels) centred on the point's voxel.
    Cube,
    /// A cylinder of radius and half-height `size` along the stroke's axis.
    Cylinder,
    /// Capsules of radius `size` along the stroke's points.
    Line,
    /// The box spanned by the stroke's first and last points.
    Box,
}

/// The axis of a cylinder brush.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Axis {
    /// Along x.
    X,
    /// Upright.
    #[default]
    Y,
    /// Along z.
    Z,
}

impl Axis {
    /// The unit vector.
    pub fn vector(self) -> DVec3 {
        match self {
            Axis::X => DVec3::X,
            Axis::Y => DVec3::Y,
            Axis::Z => DVec3::Z,
        }
    }
}

/// Mirror symmetry about planes through `centre`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mirror {
    /// Mirror across x = centre.x.
    pub x: bool,
    /// Mirror across y = centre.y.
    pub y: bool,
    /// Mirror across z = centre.z.
    pub z: bool,
    /// The point the mirror planes go through.
    pub centre: DVec3,
}

/// A brush stroke: one undo step however many points it has.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stroke {
    /// Attach, erase or paint.
    pub mode: BrushMode,
    /// Shape at each point.
    pub shape: BrushShape,
    /// Radius or half-size, > 0 (ignored for Voxel and Box).
    pub size: f64,
    /// Material for attach and paint.
    pub material: u8,
    /// Symmetry.
    #[serde(default)]
    pub mirror: Mirror,
    /// Points, in voxel coordinates.
    pub points: Vec<DVec3>,
    /// The cylinder's axis.
    #[serde(default)]
    pub axis: Axis,
    /// Change only selected voxels (when something is selected).
    #[serde(default)]
    pub in_selection: bool,
    /// How the covered voxels are coloured (the brush's material, a gradient, random
    /// entries, darker or brighter neighbours).
    #[serde(default)]
    pub paint: PaintMode,
}

/// The most stamps one segment of a stroke takes (points farther apart than this many voxels
/// are refused: no grid is that large).
pub const MAX_SEGMENT_STEPS: f64 = 65_536.0;

/// Where a brush is stamped between two consecutive stroke points: `a`, `b` and points between
/// them at most one voxel apart along every axis (⌈largest axis distance⌉ equal steps), so
/// the voxels under consecutive stamps are 26-neighbours or the same.
pub fn sweep_points(a: DVec3, b: DVec3) -> Vec<DVec3> {
    let n = (b - a).abs().max_element().ceil().max(1.0) as usize;
    (0..=n)
        .map(|k| {
            if k == n {
                b
            } else {
                a + (b - a) * (k as f64 / n as f64)
            }
        })
        .collect()
}

/// Every stamp of a stroke through `points` ([`sweep_points`] of each consecutive pair; one
/// point is one stamp).
fn stamps(points: &[DVec3]) -> Result<Vec<DVec3>> {
    if points.len() == 1 {
        return Ok(points.to_vec());
    }
    let mut out = vec![points[0]];
    for w in points.windows(2) {
        if (w[1] - w[0]).abs().max_element() > MAX_SEGMENT_STEPS {
            return Err(invalid(format!(
                "stroke points {} and {} are more than {MAX_SEGMENT_STEPS} voxels apart",
                w[0], w[1]
            )));
        }
        out.extend(sweep_points(w[0], w[1]).into_iter().skip(1));
    }
    Ok(out)
}

/// The voxels of boxes ⌊p⌋ − h ..= ⌊p⌋ + h for every stamp p, as one set (a swept cube; a
/// swept voxel for h = 0). Voxels outside the largest grid are left out (no world has them).
fn swept_boxes(stamps: &[DVec3], h: i32) -> Shape {
    let most = glam::UVec3::new(
        brickmap::grid::MAX_BRICKS_X,
        brickmap::grid::MAX_BRICKS_Y,
        brickmap::grid::MAX_BRICKS_Z,
    )
    .as_ivec3()
        * 8;
    let mut set = brickmap::VoxelSet::new();
    let mut last = None;
    for p in stamps {
        let c = p.floor().as_ivec3();
        if last != Some(c) {
            set.apply_box(c - h, c + h, most, false);
            last = Some(c);
        }
    }
    Shape::Set(std::sync::Arc::new(set))
}

/// The world edits of a stroke, mirror images included, validated before any is applied;
/// a stroke `in_selection` changes only voxels of `selection` (all, when none). A stroke
/// with a colour mode ([`PaintMode`]) reads `view` (its grid; darken and brighten its
/// materials) and leaves out the voxels of `done` (a live stroke's earlier segments).
pub fn stroke_edits(
    s: &Stroke,
    selection: Option<&Selection>,
    view: &brickmap::WorldView<'_>,
    done: Option<&brickmap::VoxelSet>,
) -> Result<Vec<EditOp>> {
    let images = image_shapes(s)?;
    let within = selection.filter(|_| s.in_selection);
    if s.paint != PaintMode::Solid {
        let dims = view.dims().voxels();
        let images = images
            .into_iter()
            .map(|(points, shapes)| {
                let mut voxels = brickmap::VoxelSet::new();
                for shape in shapes {
                    voxels = voxels.union(&shape.voxels(dims));
                }
                if let Some(sel) = within {
                    voxels = voxels.intersection(&sel.voxels);
                }
                Image { points, voxels }
            })
            .collect();
        if s.mode == BrushMode::Erase {
            return Err(invalid("erasing has no colour mode"));
        }
        let attach = s.mode == BrushMode::Attach;
        return coloured_edits(&s.paint, attach, s.material, images, view, done);
    }
    let mode = match s.mode {
        BrushMode::Attach => Mode::Add(s.material),
        BrushMode::Erase => Mode::Remove,
        BrushMode::Paint => Mode::Paint(s.material),
    };
    let mut edits = Vec::new();
    for (_, shapes) in images {
        for shape in shapes {
            let shape = match within {
                Some(sel) => Shape::Within {
                    shape: Box::new(shape),
                    set: sel.voxels.clone(),
                },
                None => shape,
            };
            edits.push(EditOp::Shape { shape, mode });
        }
    }
    Ok(edits)
}

/// The brush's shapes in each mirror image of the stroke (up to 8), with the image's points;
/// every shape validated.
fn image_shapes(s: &Stroke) -> Result<Vec<(Vec<DVec3>, Vec<Shape>)>> {
    if s.points.is_empty() {
        return Err(invalid("a stroke needs at least one point"));
    }
    if !s.points.iter().all(|p| p.is_finite()) {
        return Err(invalid("stroke points must be finite"));
    }
    let sized = !matches!(s.shape, BrushShape::Voxel | BrushShape::Box);
    if sized && !(s.size.is_finite() && s.size > 0.0) {
        return Err(invalid(format!("brush size {} must be positive", s.size)));
    }
    // Every combination of reflections across the enabled mirror planes (up to 8 images).
    let m = &s.mirror;
    let axes: Vec<usize> = [(0, m.x), (1, m.y), (2, m.z)]
        .into_iter()
        .filter(|a| a.1)
        .map(|a| a.0)
        .collect();
    let reflect = |p: DVec3, combo: usize| {
        let mut q = p;
        for (k, &axis) in axes.iter().enumerate() {
            if combo >> k & 1 == 1 {
                q[axis] = 2.0 * m.centre[axis] - q[axis];
            }
        }
        q
    };
    let mut images = Vec::new();
    for combo in 0..1usize << axes.len() {
        let pts: Vec<DVec3> = s.points.iter().map(|p| reflect(*p, combo)).collect();
        let shapes: Vec<Shape> = match s.shape {
            BrushShape::Line | BrushShape::Sphere => vec![Shape::Line {
                points: pts.clone(),
                radius: s.size,
            }],
            BrushShape::Box => {
                let (a, b) = (
                    pts[0].floor().as_ivec3(),
                    pts[pts.len() - 1].floor().as_ivec3(),
                );
                vec![Shape::Box {
                    min: a.min(b),
                    max: a.max(b),
                }]
            }
            BrushShape::Voxel if pts.len() == 1 => vec![Shape::Voxel(pts[0].floor().as_ivec3())],
            BrushShape::Voxel => vec![swept_boxes(&stamps(&pts)?, 0)],
            BrushShape::Cube => {
                let h = s.size.round().clamp(0.0, 4096.0) as i32;
                match pts.as_slice() {
                    [p] => {
                        let c = p.floor().as_ivec3();
                        vec![Shape::Box {
                            min: c - h,
                            max: c + h,
                        }]
                    }
                    _ => vec![swept_boxes(&stamps(&pts)?, h)],
                }
            }
            BrushShape::Cylinder => stamps(&pts)?
                .iter()
                .map(|p| Shape::Cylinder {
                    a: *p - s.axis.vector() * s.size,
                    b: *p + s.axis.vector() * s.size,
                    radius: s.size,
                })
                .collect(),
        };
        for shape in &shapes {
            shape.validate().map_err(EditError::World)?;
        }
        images.push((pts, shapes));
    }
    Ok(images)
}

/// The most voxels a preview examines; a larger brush previews nothing (its outline is
/// drawn instead).
pub const PREVIEW_LIMIT: u64 = 4 << 20;

/// Exactly the voxels `stroke` would change in the world as it is now, sorted by x, then y,
/// then z (the brush preview); None when the brush covers more than [`PREVIEW_LIMIT`] voxels.
/// Examined a brick at a time: the shape's coverage skips bricks outside it, its mask and
/// the brick's voxels give the changed ones by mask operations.
pub fn preview(
    view: &brickmap::WorldView<'_>,
    stroke: &Stroke,
    selection: Option<&Selection>,
) -> Result<Option<Vec<IVec3>>> {
    let Some(bricks) = preview_bricks(view, stroke, selection)? else {
        return Ok(None);
    };
    // In x, y, z order: for each x, the rows of each brick row.
    let mut out = Vec::new();
    for slab in bricks.chunk_by(|a, b| a.0.x == b.0.x) {
        let bx = slab[0].0.x;
        for x in 0..8 {
            for column in slab.chunk_by(|a, b| a.0.y == b.0.y) {
                let by = column[0].0.y;
                for y in 0..8 {
                    let base = (x + 8 * y) as usize;
                    for (b, m) in column {
                        for z in 0..8 {
                            if m.get(base + 64 * z) {
                                out.push(IVec3::new(bx * 8 + x, by * 8 + y, b.z * 8 + z as i32));
                            }
                        }
                    }
                }
            }
        }
    }
    Ok(Some(out))
}

/// [`preview`] as brick coordinates and the masks of their changed voxels, sorted by brick
/// (x, then y, then z).
pub fn preview_bricks(
    view: &brickmap::WorldView<'_>,
    stroke: &Stroke,
    selection: Option<&Selection>,
) -> Result<Option<Vec<(IVec3, brickmap::Mask)>>> {
    use brickmap::shape::Coverage;
    let edits = stroke_edits(stroke, selection, view, None)?;
    let dims = view.dims().voxels();
    let mut examined = 0u64;
    // The changed voxels by brick (mirror images may lie far apart: sparse).
    let mut changed: std::collections::HashMap<(i32, i32, i32), brickmap::Mask> =
        Default::default();
    for edit in &edits {
        let EditOp::Shape { shape, mode } = edit else {
            continue;
        };
        let (lo, hi) = shape.voxel_bounds();
        let (lo, hi) = (lo.max(IVec3::ZERO), hi.min(dims - 1));
        if lo.cmpgt(hi).any() {
            continue;
        }
        let n = (hi - lo + 1).as_u64vec3();
        examined += n.x * n.y * n.z;
        if examined > PREVIEW_LIMIT {
            return Ok(None);
        }
        let (blo, bhi) = (lo / 8, hi / 8);
        for bx in blo.x..=bhi.x {
            for by in blo.y..=bhi.y {
                for bz in blo.z..=bhi.z {
                    let b = IVec3::new(bx, by, bz);
                    let region = match shape.coverage(b * 8) {
                        Coverage::Outside => continue,
                        Coverage::Inside => brickmap::Mask::FULL,
                        Coverage::Partial => shape.mask(b * 8),
                    };
                    if region.is_empty() {
                        continue;
                    }
                    let (solid, mats) = view.brick_voxels(b.as_uvec3());
                    let with = |m: u8| {
                        let mut same = brickmap::Mask::EMPTY;
                        for bit in solid.and(&region).ones() {
                            if mats[bit] == m {
                                same.set(bit);
                            }
                        }
                        same
                    };
                    let mask = match mode {
                        Mode::Add(m) => region.and_not(&with(*m)),
                        Mode::Remove => region.and(&solid),
                        Mode::Paint(m) => region.and(&solid).and_not(&with(*m)),
                    };
                    if !mask.is_empty() {
                        let e = changed.entry((bx, by, bz)).or_default();
                        *e = e.or(&mask);
                    }
                }
            }
        }
    }
    let mut bricks: Vec<(IVec3, brickmap::Mask)> = changed
        .into_iter()
        .map(|((x, y, z), m)| (IVec3::new(x, y, z), m))
        .collect();
    bricks.sort_unstable_by_key(|(b, _)| (b.x, b.y, b.z));
    Ok(Some(bricks))
}
