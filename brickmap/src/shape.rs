//! Brush shapes and how they cover bricks. A voxel belongs to a shape when its centre
//! (v + 0.5) lies inside the closed shape. Every shape here is convex or a union of convex
//! pieces, so a brick whose eight corner voxel centres lie inside one piece lies inside it
//! entirely: such a brick is edited with one whole-mask write.

use crate::brick::{Mask, voxel_bit};
use crate::error::{BrickmapError, Result};
use crate::voxel_set::VoxelSet;
use glam::{DVec3, IVec3};
use std::sync::Arc;

/// A region of voxels an edit applies to.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// One voxel.
    Voxel(IVec3),
    /// Voxel centres within `radius` of `centre`.
    Sphere {
        /// Centre, in voxel units.
        centre: DVec3,
        /// Radius, > 0.
        radius: f64,
    },
    /// Voxels with `min ≤ v ≤ max` on every axis (inclusive corners).
    Box {
        /// Inclusive minimum corner.
        min: IVec3,
        /// Inclusive maximum corner.
        max: IVec3,
    },
    /// A solid cylinder of any orientation: centres within `radius` of the segment `a`–`b`
    /// whose projection falls between the two end caps.
    Cylinder {
        /// Centre of one cap.
        a: DVec3,
        /// Centre of the other cap (≠ a).
        b: DVec3,
        /// Radius, > 0.
        radius: f64,
    },
    /// Line segments through `points` swept by a ball of `radius` (capsules); one point is a
    /// sphere.
    Line {
        /// Polyline vertices (at least one).
        points: Vec<DVec3>,
        /// Radius, > 0.
        radius: f64,
    },
    /// Exactly the voxels of a set (a selection).
    Set(Arc<VoxelSet>),
    /// The voxels of a shape that also lie in a set (a tool limited to the selection).
    Within {
        /// The shape.
        shape: Box<Shape>,
        /// The voxels it is limited to.
        set: Arc<VoxelSet>,
    },
}

/// How a brick relates to a shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coverage {
    /// No voxel of the brick is inside.
    Outside,
    /// Every voxel of the brick is inside.
    Inside,
    /// Some voxels are inside.
    Partial,
}

fn finite(v: f64, what: &'static str) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(BrickmapError::NotFinite(what))
    }
}
fn finite3(v: DVec3, what: &'static str) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(BrickmapError::NotFinite(what))
    }
}
fn positive(v: f64, what: &'static str) -> Result<()> {
    finite(v, what)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(BrickmapError::NonPositive { what, value: v })
    }
}

/// Squared distance from `p` to the segment `a`–`b`.
fn segment_dist2(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * s)).length_squared()
}

impl Shape {
    /// Checks parameters: finite, positive sizes, non-empty boxes, distinct cylinder caps.
    pub fn validate(&self) -> Result<()> {
        match self {
            Shape::Voxel(_) => Ok(()),
            Shape::Sphere { centre, radius } => {
                finite3(*centre, "sphere centre")?;
                positive(*radius, "sphere radius")
            }
            Shape::Box { min, max } => {
                if min.cmple(*max).all() {
                    Ok(())
                } else {
                    Err(BrickmapError::EmptyBox {
                        min: *min,
                        max: *max,
                    })
                }
            }
            Shape::Cylinder { a, b, radius } => {
                finite3(*a, "cylinder end")?;
                finite3(*b, "cylinder end")?;
                positive(*radius, "cylinder radius")?;
                positive((*b - *a).length(), "cylinder length")
            }
            Shape::Line { points, radius } => {
                if points.is_empty() {
                    return Err(BrickmapError::NoPoints("line"));
                }
                for p in points {
                    finite3(*p, "line point")?;
                }
                positive(*radius, "line radius")
            }
            Shape::Set(_) => Ok(()),
            Shape::Within { shape, .. } => shape.validate(),
        }
    }

    /// Whether the voxel centre `c` (= v + 0.5) is inside.
    pub fn contains_centre(&self, c: DVec3) -> bool {
        match self {
            Shape::Voxel(v) => c.floor().as_ivec3() == *v,
            Shape::Sphere { centre, radius } => (c - *centre).length_squared() <= radius * radius,
            Shape::Box { min, max } => {
                let v = c.floor();
                v.cmpge(min.as_dvec3()).all() && v.cmple(max.as_dvec3()).all()
            }
            Shape::Cylinder { a, b, radius } => {
                let ab = *b - *a;
                let s = (c - *a).dot(ab) / ab.length_squared();
                (0.0..=1.0).contains(&s) && (c - (*a + ab * s)).length_squared() <= radius * radius
            }
            Shape::Line { points, radius } => {
                let r2 = radius * radius;
                if points.len() == 1 {
                    return (c - points[0]).length_squared() <= r2;
                }
                points
                    .windows(2)
                    .any(|w| segment_dist2(c, w[0], w[1]) <= r2)
            }
            Shape::Set(set) => set.contains(c.floor().as_ivec3()),
            Shape::Within { shape, set } => {
                set.contains(c.floor().as_ivec3()) && shape.contains_centre(c)
            }
        }
    }

    /// Whether voxel `v` is inside.
    pub fn contains(&self, v: IVec3) -> bool {
        self.contains_centre(v.as_dvec3() + 0.5)
    }

    /// Inclusive voxel bounds that contain every inside voxel, before clipping to a grid.
    /// Floats are clamped into i32 range, so huge shapes stay representable.
    pub fn voxel_bounds(&self) -> (IVec3, IVec3) {
        let around = |lo: DVec3, hi: DVec3| {
            let clamp = |v: DVec3| v.clamp(DVec3::splat(-1e9), DVec3::splat(1e9));
            (
                (clamp(lo) - 0.5).floor().as_ivec3(),
                (clamp(hi) - 0.5).ceil().as_ivec3(),
            )
        };
        match self {
            Shape::Voxel(v) => (*v, *v),
            Shape::Box { min, max } => (*min, *max),
            Shape::Sphere { centre, radius } => around(*centre - *radius, *centre + *radius),
            Shape::Cylinder { a, b, radius } => around(a.min(*b) - *radius, a.max(*b) + *radius),
            Shape::Line { points, radius } => {
                let lo = points.iter().fold(DVec3::INFINITY, |m, p| m.min(*p));
                let hi = points.iter().fold(DVec3::NEG_INFINITY, |m, p| m.max(*p));
                around(lo - *radius, hi + *radius)
            }
            // An empty set: bounds no voxel lies in (min above max).
            Shape::Set(set) => set
                .bounds()
                .unwrap_or((IVec3::splat(i32::MAX), IVec3::splat(i32::MIN))),
            Shape::Within { shape, set } => {
                let (lo, hi) = shape.voxel_bounds();
                match set.bounds() {
                    Some((a, b)) if a.cmple(hi).all() && lo.cmple(b).all() => {
                        (lo.max(a), hi.min(b))
                    }
                    _ => (IVec3::splat(i32::MAX), IVec3::splat(i32::MIN)),
                }
            }
        }
    }

    /// How the brick whose minimum voxel is `min` relates to the shape.
    pub fn coverage(&self, min: IVec3) -> Coverage {
        let lo = min.as_dvec3() + 0.5;
        let hi = lo + 7.0;
        let corners_in = |inside: &dyn Fn(DVec3) -> bool| {
            (0..8).all(|i| {
                let pick = |bit: i32, l: f64, h: f64| if i & bit != 0 { h } else { l };
                inside(DVec3::new(
                    pick(1, lo.x, hi.x),
                    pick(2, lo.y, hi.y),
                    pick(4, lo.z, hi.z),
                ))
            })
        };
        match self {
            Shape::Voxel(v) => {
                if (*v - min).cmpge(IVec3::ZERO).all() && (*v - min).cmplt(IVec3::splat(8)).all() {
                    Coverage::Partial
                } else {
                    Coverage::Outside
                }
            }
            Shape::Box {
                min: bmin,
                max: bmax,
            } => {
                let bhi = min + 7;
                if bhi.cmplt(*bmin).any() || min.cmpgt(*bmax).any() {
                    Coverage::Outside
                } else if min.cmpge(*bmin).all() && bhi.cmple(*bmax).all() {
                    Coverage::Inside
                } else {
                    Coverage::Partial
                }
            }
            Shape::Sphere { centre, radius } => {
                let nearest = centre.clamp(lo, hi);
                if (nearest - *centre).length_squared() > radius * radius {
                    Coverage::Outside
                } else if corners_in(&|c| self.contains_centre(c)) {
                    Coverage::Inside
                } else {
                    Coverage::Partial
                }
            }
            Shape::Cylinder { .. } => {
                if corners_in(&|c| self.contains_centre(c)) {
                    Coverage::Inside
                } else {
                    Coverage::Partial
                }
            }
            Shape::Line { points, radius } => {
                let r2 = radius * radius;
                let pieces: Vec<(DVec3, DVec3)> = if points.len() == 1 {
                    vec![(points[0], points[0])]
                } else {
                    points.windows(2).map(|w| (w[0], w[1])).collect()
                };
                // A ball of the brick's half-diagonal around its centre bounds every centre.
                let centre = (lo + hi) * 0.5;
                let reach = radius + (hi - centre).length();
                if pieces
                    .iter()
                    .all(|&(a, b)| segment_dist2(centre, a, b) > reach * reach)
                {
                    Coverage::Outside
                } else if pieces
                    .iter()
                    .any(|&(a, b)| corners_in(&|c| segment_dist2(c, a, b) <= r2))
                {
                    Coverage::Inside
                } else {
                    Coverage::Partial
                }
            }
            Shape::Set(set) => set_coverage(set, min),
            Shape::Within { shape, set } => match (shape.coverage(min), set_coverage(set, min)) {
                (Coverage::Outside, _) | (_, Coverage::Outside) => Coverage::Outside,
                (Coverage::Inside, Coverage::Inside) => Coverage::Inside,
                _ => Coverage::Partial,
            },
        }
    }

    /// The inside voxels that lie in a grid of `voxels` voxels, as a set (brick by brick from
    /// the coverage and the mask).
    pub fn voxels(&self, voxels: IVec3) -> VoxelSet {
        let mut set = VoxelSet::new();
        let (lo, hi) = self.voxel_bounds();
        let (lo, hi) = (lo.max(IVec3::ZERO), hi.min(voxels - 1));
        if lo.cmpgt(hi).any() {
            return set;
        }
        let (blo, bhi) = (lo / 8, hi / 8);
        for x in blo.x..=bhi.x {
            for y in blo.y..=bhi.y {
                for z in blo.z..=bhi.z {
                    let b = IVec3::new(x, y, z);
                    let inside = match self.coverage(b * 8) {
                        Coverage::Outside => continue,
                        Coverage::Inside => Mask::FULL,
                        Coverage::Partial => self.mask(b * 8),
                    };
                    let grid = crate::voxel_set::box_mask(b * 8, IVec3::ZERO, voxels - 1);
                    set.set_brick(b.as_uvec3(), inside.and(&grid));
                }
            }
        }
        set
    }

    /// The voxels of the brick at `min` that are inside, as a mask.
    pub fn mask(&self, min: IVec3) -> Mask {
        let mut m = Mask::EMPTY;
        match self {
            Shape::Set(set) => return set_brick(set, min),
            Shape::Within { shape, set } => {
                let inner = match shape.coverage(min) {
                    Coverage::Outside => Mask::EMPTY,
                    Coverage::Inside => Mask::FULL,
                    Coverage::Partial => shape.mask(min),
                };
                return inner.and(&set_brick(set, min));
            }
            Shape::Sphere { centre, radius } => {
                // Row spans: solve (x + 0.5 - cx)² ≤ r² − dy² − dz² per row.
                for z in 0..8 {
                    let dz = (min.z + z) as f64 + 0.5 - centre.z;
                    for y in 0..8 {
                        let dy = (min.y + y) as f64 + 0.5 - centre.y;
                        let rest = radius * radius - dy * dy - dz * dz;
                        if rest < 0.0 {
                            continue;
                        }
                        for x in 0..8 {
                            let dx = (min.x + x) as f64 + 0.5 - centre.x;
                            if dx * dx <= rest {
                                m.set(voxel_bit(x, y, z));
                            }
                        }
                    }
                }
            }
            _ => {
                for z in 0..8 {
                    for y in 0..8 {
                        for x in 0..8 {
                            if self.contains(min + IVec3::new(x, y, z)) {
                                m.set(voxel_bit(x, y, z));
                            }
                        }
                    }
                }
            }
        }
        m
    }
}

/// The set's voxels in the brick whose minimum voxel is `min` (none outside the grid).
fn set_brick(set: &VoxelSet, min: IVec3) -> Mask {
    if min.cmplt(IVec3::ZERO).any() {
        return Mask::EMPTY;
    }
    set.brick((min / 8).as_uvec3())
}

fn set_coverage(set: &VoxelSet, min: IVec3) -> Coverage {
    let m = set_brick(set, min);
    if m.is_empty() {
        Coverage::Outside
    } else if m.is_full() {
        Coverage::Inside
    } else {
        Coverage::Partial
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shapes() -> Vec<Shape> {
        vec![
            Shape::Sphere {
                centre: DVec3::new(10.3, 9.0, 11.7),
                radius: 9.2,
            },
            Shape::Box {
                min: IVec3::new(3, 1, 5),
                max: IVec3::new(20, 17, 9),
            },
            Shape::Cylinder {
                a: DVec3::new(2.0, 3.0, 4.0),
                b: DVec3::new(19.0, 15.0, 8.0),
                radius: 5.5,
            },
            Shape::Line {
                points: vec![
                    DVec3::new(1.0, 1.0, 1.0),
                    DVec3::new(20.0, 4.0, 9.0),
                    DVec3::new(5.0, 20.0, 20.0),
                ],
                radius: 3.2,
            },
            Shape::Voxel(IVec3::new(9, 8, 7)),
            Shape::Set(Arc::new(test_set())),
            Shape::Within {
                shape: Box::new(Shape::Sphere {
                    centre: DVec3::new(10.3, 9.0, 11.7),
                    radius: 9.2,
                }),
                set: Arc::new(test_set()),
            },
        ]
    }

    /// Voxels of two overlapping boxes, one brick fully inside.
    fn test_set() -> VoxelSet {
        let mut s = VoxelSet::new();
        let grid = IVec3::splat(64);
        s.apply_box(IVec3::new(4, 0, 3), IVec3::new(17, 15, 16), grid, false);
        s.apply_box(IVec3::new(9, 5, 0), IVec3::new(12, 30, 30), grid, true);
        s
    }

    #[test]
    fn coverage_and_mask_agree_with_per_voxel_test() {
        for s in shapes() {
            let (lo, hi) = s.voxel_bounds();
            for bz in -1..4 {
                for by in -1..4 {
                    for bx in -1..4 {
                        let min = IVec3::new(bx, by, bz) * 8;
                        let mut want = Mask::EMPTY;
                        for i in 0..512 {
                            let v = min + IVec3::new(i % 8, i / 8 % 8, i / 64);
                            if s.contains(v) {
                                assert!(
                                    v.cmpge(lo).all() && v.cmple(hi).all(),
                                    "{s:?} bounds miss {v}"
                                );
                                want.set(i as usize);
                            }
                        }
                        assert_eq!(s.mask(min), want, "{s:?} at {min}");
                        match s.coverage(min) {
                            Coverage::Outside => assert!(want.is_empty(), "{s:?} {min}"),
                            Coverage::Inside => assert!(want.is_full(), "{s:?} {min}"),
                            Coverage::Partial => {}
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_shapes_voxel_set_is_its_inside_voxels_within_the_grid() {
        let grid = IVec3::new(19, 14, 24);
        for shape in shapes() {
            let set = shape.voxels(grid);
            let mut n = 0;
            for x in -2..grid.x + 2 {
                for y in -2..grid.y + 2 {
                    for z in -2..grid.z + 2 {
                        let v = IVec3::new(x, y, z);
                        let inside = v.cmpge(IVec3::ZERO).all() && v.cmplt(grid).all();
                        let want = inside && shape.contains(v);
                        assert_eq!(set.contains(v), want, "{shape:?} at {v}");
                        n += want as u64;
                    }
                }
            }
            assert!(n > 0, "{shape:?} has voxels in the grid");
            assert_eq!(set.count(), n);
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        let bad = [
            Shape::Sphere {
                centre: DVec3::ZERO,
                radius: 0.0,
            },
            Shape::Sphere {
                centre: DVec3::ZERO,
                radius: -1.0,
            },
            Shape::Sphere {
                centre: DVec3::new(f64::NAN, 0.0, 0.0),
                radius: 1.0,
            },
            Shape::Sphere {
                centre: DVec3::ZERO,
                radius: f64::INFINITY,
            },
            Shape::Box {
                min: IVec3::new(1, 0, 0),
                max: IVec3::ZERO,
            },
            Shape::Cylinder {
                a: DVec3::ONE,
                b: DVec3::ONE,
                radius: 1.0,
            },
            Shape::Line {
                points: vec![],
                radius: 1.0,
            },
            Shape::Line {
                points: vec![DVec3::ZERO],
                radius: f64::NAN,
            },
        ];
        for s in bad {
            assert!(s.validate().is_err(), "{s:?}");
        }
        for s in shapes() {
            s.validate().unwrap();
        }
    }
}
