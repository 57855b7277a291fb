//! CPU ray cast through coarse grid → brick grid → voxels, by an exact integer DDA.
//!
//! Exactness: voxel v fills the half-open box [v, v+1) (docs/DESIGN.md), so the ray point at
//! parameter t belongs to voxel ⌊o + t·d⌋. The crossing time of the plane `b` on axis i is
//! computed as the correctly rounded `(b − oᵢ) / dᵢ` and nothing else (no accumulated
//! increments), so event order, ties at edges and corners included, is decided on the same
//! numbers an independent reference computes. At a tie, positive-direction axes step first
//! (at that instant the point already lies in the next cell along them), negative-direction
//! axes right after; cells the ray touches in a single point are visited, as the half-open
//! convention says. Empty coarse cells (32³ voxels) and empty bricks (8³) are skipped with the
//! same event rule at their boundaries. Steps are bounded by the grid size, so it never loops
//! forever; every returned t is finite.

// The DDA walks three axes over several parallel per-axis arrays; index loops say that best.
#![allow(clippy::needless_range_loop)]

use crate::error::{BrickmapError, Result};
use crate::grid::GridDims;
use glam::{DVec3, IVec3, UVec3};

/// A ray `origin + t·dir`, t ≥ 0. `dir` need not be normalised; t is in its units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point, in voxel units.
    pub origin: DVec3,
    /// Direction (finite, not zero).
    pub dir: DVec3,
}

/// The first solid voxel a ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The voxel.
    pub voxel: IVec3,
    /// Unit normal of the face the ray entered through (for a ray starting inside a solid
    /// voxel: the face it would have entered through, the latest plane crossed behind it).
    pub normal: IVec3,
    /// Ray parameter of the hit (0 when the ray starts inside the voxel).
    pub t: f64,
}

/// What a ray cast needs to know about occupancy.
pub trait Occupancy {
    /// Grid size.
    fn dims(&self) -> GridDims;
    /// Whether the coarse cell (4³ bricks) may hold anything.
    fn coarse_occupied(&self, c: UVec3) -> bool;
    /// Whether the brick holds anything.
    fn brick_occupied(&self, b: UVec3) -> bool;
    /// Whether a voxel inside the grid is solid.
    fn solid(&self, v: IVec3) -> bool;
}

/// Distance outside the grid beyond which a ray's origin is first moved to near the grid
/// (so every crossing time is computed from a nearby origin and keeps full precision).
pub const FAR: f64 = 1_048_576.0;

impl Ray {
    /// Checks the ray: finite origin and direction, direction not zero.
    pub fn validate(&self) -> Result<()> {
        if !self.origin.is_finite() {
            return Err(BrickmapError::InvalidRay("origin is not finite"));
        }
        if !self.dir.is_finite() {
            return Err(BrickmapError::InvalidRay("direction is not finite"));
        }
        if self.dir == DVec3::ZERO {
            return Err(BrickmapError::InvalidRay("direction is zero"));
        }
        Ok(())
    }

    /// The crossing time of plane `b` on `axis`.
    #[inline]
    pub fn plane_time(&self, axis: usize, b: f64) -> f64 {
        (b - self.origin[axis]) / self.dir[axis]
    }

    /// For an origin farther than [`FAR`] from the grid, the same ray started near the grid
    /// and the parameter offset to add back; otherwise the ray itself and 0.
    pub fn near_grid(&self, dims: &GridDims) -> (Ray, f64) {
        let size = dims.voxels().as_dvec3();
        let outside = (-self.origin).max(self.origin - size).max_element();
        if outside <= FAR {
            return (*self, 0.0);
        }
        // Advance to the earliest crossing of the grid box's planes, less a margin.
        let mut enter = 0.0f64;
        for i in 0..3 {
            if self.dir[i] != 0.0 {
                let (near, _) = if self.dir[i] > 0.0 {
                    (0.0, size[i])
                } else {
                    (size[i], 0.0)
                };
                enter = enter.max(self.plane_time(i, near));
            }
        }
        let shift = (enter - 2.0 / self.dir.abs().max_element()).max(0.0);
        (
            Ray {
                origin: self.origin + self.dir * shift,
                dir: self.dir,
            },
            shift,
        )
    }
}

/// Casts a ray for the first solid voxel with hit parameter ≤ `t_max`.
pub fn cast(grid: &impl Occupancy, ray: &Ray, t_max: f64) -> Result<Option<RayHit>> {
    ray.validate()?;
    if t_max.is_nan() {
        return Err(BrickmapError::InvalidRay("t_max is NaN"));
    }
    let dims = grid.dims();
    let (near, shift) = ray.near_grid(&dims);
    Ok(Dda::new(&near, &dims)
        .and_then(|mut dda| dda.run(grid, t_max - shift))
        .map(|mut hit| {
            hit.t += shift;
            hit
        }))
}

/// Casts a ray that leaves a surface from a known cell: `cell` is the voxel the ray starts
/// in (for a reflection, the empty cell in front of the face; for a refraction, the voxel
/// behind it), `ray.origin` the point on the face. Because the start cell is given, no epsilon
/// offset is needed at any coordinate. The start cell itself is tested first (a hit there has
/// t = 0). Origins must lie within the grid's box (surface points do).
pub fn cast_from_cell(
    grid: &impl Occupancy,
    ray: &Ray,
    cell: IVec3,
    t_max: f64,
) -> Result<Option<RayHit>> {
    ray.validate()?;
    if t_max.is_nan() {
        return Err(BrickmapError::InvalidRay("t_max is NaN"));
    }
    Ok(Dda::at_cell(ray, &grid.dims(), cell).and_then(|mut dda| dda.run(grid, t_max)))
}

struct Dda<'r> {
    ray: &'r Ray,
    size: [i64; 3],
    sign: [i8; 3],
    cell: [i64; 3],
    t: f64,
    normal_axis: usize,
}

impl<'r> Dda<'r> {
    /// A walker for a ray before its start cell is known (None for a zero direction).
    fn blank(ray: &'r Ray, dims: &GridDims) -> Option<Self> {
        let sign: [i8; 3] = std::array::from_fn(|i| {
            let d = ray.dir[i];
            if d > 0.0 {
                1
            } else if d < 0.0 {
                -1
            } else {
                0
            }
        });
        // Start from an axis the ray moves along: with denormal components every entry
        // time can be −∞, and the normal must still name a real face.
        let normal_axis = (0..3).find(|&i| sign[i] != 0)?;
        let size = dims.voxels().as_i64vec3().to_array();
        Some(Dda {
            ray,
            size,
            sign,
            cell: [0; 3],
            t: 0.0,
            normal_axis,
        })
    }

    /// The face entered last: the latest plane crossed into the current cell.
    fn set_entry_axis(&mut self) {
        let mut latest = f64::NEG_INFINITY;
        for i in 0..3 {
            let e = match self.sign[i] {
                0 => continue,
                1 => self.ray.plane_time(i, self.cell[i] as f64),
                _ => self.ray.plane_time(i, (self.cell[i] + 1) as f64),
            };
            if e > latest {
                latest = e;
                self.normal_axis = i;
            }
        }
    }

    /// A walker for a ray from anywhere: finds the first cell inside the grid.
    fn new(ray: &'r Ray, dims: &GridDims) -> Option<Self> {
        let mut dda = Self::blank(ray, dims)?;
        // Earliest time the ray can be in the grid; t stays ≥ 0.
        let mut t0 = 0.0f64;
        for i in 0..3 {
            match dda.sign[i] {
                0 => {
                    let o = ray.origin[i];
                    if !(o >= 0.0 && o < dda.size[i] as f64) {
                        return None;
                    }
                }
                1 => t0 = t0.max(ray.plane_time(i, 0.0)),
                _ => t0 = t0.max(ray.plane_time(i, dda.size[i] as f64)),
            }
        }
        if !t0.is_finite() {
            return None;
        }
        dda.t = if t0 == 0.0 { 0.0 } else { t0 };
        for i in 0..3 {
            dda.cell[i] = dda.cell_at(i, dda.t, false);
        }
        dda.set_entry_axis();
        Some(dda)
    }

    /// A walker for a ray leaving a surface from a known cell.
    fn at_cell(ray: &'r Ray, dims: &GridDims, cell: IVec3) -> Option<Self> {
        let mut dda = Self::blank(ray, dims)?;
        dda.cell = cell.as_i64vec3().to_array();
        dda.set_entry_axis();
        Some(dda)
    }

    /// The cell along `axis` holding the ray point at time `t` (or, with `after`, just after
    /// `t`), by the half-open rule.
    fn cell_at(&self, axis: usize, t: f64, after: bool) -> i64 {
        let o = self.ray.origin[axis];
        let n = self.size[axis];
        let guess = ((o + t * self.ray.dir[axis]).floor() as i64).clamp(-1, n);
        let time = |b: i64| self.ray.plane_time(axis, b as f64);
        let mut c = guess;
        match self.sign[axis] {
            0 => o.floor() as i64,
            1 => {
                // Largest c with time(c) ≤ t.
                while c < n && time(c + 1) <= t {
                    c += 1;
                }
                while c > -1 && time(c) > t {
                    c -= 1;
                }
                c
            }
            _ => {
                // Largest c with time(c) ≥ t (at t) or time(c) > t (just after t).
                let reached = |c: i64| if after { time(c) > t } else { time(c) >= t };
                while c < n && reached(c + 1) {
                    c += 1;
                }
                while c > -1 && !reached(c) {
                    c -= 1;
                }
                c
            }
        }
    }

    fn inside(&self) -> bool {
        (0..3).all(|i| self.cell[i] >= 0 && self.cell[i] < self.size[i])
    }

    fn leaving(&self) -> bool {
        (0..3).any(|i| {
            (self.sign[i] > 0 && self.cell[i] >= self.size[i])
                || (self.sign[i] < 0 && self.cell[i] < 0)
        })
    }

    /// Advances to the next cell outside the current aligned block of `block` voxels (1: the
    /// next voxel). Returns false when no further event exists.
    fn step(&mut self, block: i64) -> bool {
        let mut bound = [0i64; 3];
        let mut times = [f64::INFINITY; 3];
        let mut t_next = f64::INFINITY;
        for i in 0..3 {
            let s = self.sign[i];
            if s == 0 {
                continue;
            }
            let base = self.cell[i].div_euclid(block) * block;
            bound[i] = if s > 0 { base + block } else { base };
            times[i] = self.ray.plane_time(i, bound[i] as f64);
            t_next = t_next.min(times[i]);
        }
        if !t_next.is_finite() {
            return false;
        }
        let positive_tie = (0..3).any(|i| self.sign[i] > 0 && times[i] == t_next);
        let mut stepped = [false; 3];
        for i in 0..3 {
            if times[i] == t_next && (self.sign[i] > 0) == positive_tie {
                stepped[i] = true;
                self.cell[i] = if self.sign[i] > 0 {
                    bound[i]
                } else {
                    bound[i] - 1
                };
                self.normal_axis = i;
            }
        }
        if block > 1 {
            // Positive steps land at the instant t_next itself; negative steps just after it,
            // when every other negative axis crossing at t_next has crossed too.
            for i in 0..3 {
                if !stepped[i] && self.sign[i] != 0 {
                    self.cell[i] = self.cell_at(i, t_next, !positive_tie);
                }
            }
        }
        self.t = t_next;
        true
    }

    fn run(&mut self, grid: &impl Occupancy, t_max: f64) -> Option<RayHit> {
        let budget = 3 * (self.size.iter().sum::<i64>() + 8);
        for _ in 0..budget {
            if self.leaving() || self.t > t_max {
                return None;
            }
            let block = if self.inside() {
                let v = IVec3::new(
                    self.cell[0] as i32,
                    self.cell[1] as i32,
                    self.cell[2] as i32,
                );
                let u = v.as_uvec3();
                if !grid.coarse_occupied(u / 32) {
                    32
                } else if !grid.brick_occupied(u / 8) {
                    8
                } else if grid.solid(v) {
                    let mut normal = IVec3::ZERO;
                    normal[self.normal_axis] = -self.sign[self.normal_axis] as i32;
                    return Some(RayHit {
                        voxel: v,
                        normal,
                        t: self.t,
                    });
                } else {
                    1
                }
            } else {
                1
            };
            if !self.step(block) {
                return None;
            }
        }
        None
    }
}

impl Occupancy for crate::world::WorldView<'_> {
    fn dims(&self) -> GridDims {
        crate::world::WorldView::dims(self)
    }
    fn coarse_occupied(&self, c: UVec3) -> bool {
        self.slab_for_brick_x(c.x * crate::grid::COARSE_BRICKS)
            .coarse_occupied(c)
    }
    fn brick_occupied(&self, b: UVec3) -> bool {
        crate::world::WorldView::brick_occupied(self, b)
    }
    fn solid(&self, v: IVec3) -> bool {
        self.solid_at(v)
    }
}

impl crate::world::WorldView<'_> {
    /// The first solid voxel along a ray with t ≤ `t_max`, and its material.
    pub fn ray_cast(&self, ray: &Ray, t_max: f64) -> Result<Option<(RayHit, u8)>> {
        Ok(cast(self, ray, t_max)?.map(|hit| {
            let m = self.voxel(hit.voxel).ok().flatten().unwrap_or(0);
            (hit, m)
        }))
    }
}
