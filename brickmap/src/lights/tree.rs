//! The light tree: the sum tree's nodes also carry the bounds of the faces below them (a box
//! of voxels and which of the six face directions occur), so a shading point descends it by
//! each child's *importance* — an estimate of the light it can receive from the child's faces
//! — instead of by weight alone. shaders/lights.glsl computes the same in f32; keep the two
//! in step.
//!
//! The importance of a node from point p with axis-aligned shading normal n is
//! W · cos_l · cos_r / max(d², r²) (after Conty Estevez and Kulla 2018, with the six face
//! directions in place of an orientation cone): W its weight, d the distance from its box's
//! centre, r the box's half-diagonal, cos_r and cos_l the receiver's and the best emitting
//! direction's cosines towards the centre, each widened by r / d (an estimate of their best
//! over the box's bounding sphere; it need not bound them). It is 0 exactly when no face
//! below can light p: none of its directions can face p (a +x face lies on a plane x = v + 1
//! with v ≥ lo.x, so p must lie beyond lo.x + 1) or the box lies wholly behind the shading
//! plane. Those two tests are exact for a single face, and a parent's box and directions are
//! the union of its children's, so every face that can light p has positive probability
//! along its whole path: sampling is unbiased.

use super::{FACE_NORMALS, LightFace, Lights};
use glam::{DVec3, IVec3};

/// Levels of the binary tree the descent takes a step: 3, an 8-wide tree over the same nodes
/// (BENCHMARKS.md "The renderer, round 7": at equal samples 53 / 11 / 30 % less error than
/// the binary descent in the lamp room / the thesis scene with lamps / the city at night).
pub const DESCENT_LEVELS: u32 = 3;

/// Bounds words of an empty node (no face below it).
pub(crate) const EMPTY_BOUNDS: [u32; 4] = [0, 0, 0, 0];

/// The least cosine estimate of a node that passed the exact tests (keeps its importance
/// positive).
const COS_FLOOR: f64 = 1e-4;

/// A single face's bounds: its voxel (as lo = hi) and its direction.
pub(crate) fn leaf_bounds(face: LightFace) -> [u32; 4] {
    let v = face.voxel.as_uvec3();
    [
        v.x | v.x << 16,
        v.y | v.y << 16,
        v.z | v.z << 16,
        1 << face.face,
    ]
}

/// The union of two nodes' bounds.
pub(crate) fn union(a: [u32; 4], b: [u32; 4]) -> [u32; 4] {
    if a[3] == 0 {
        return b;
    }
    if b[3] == 0 {
        return a;
    }
    let mut out = [0; 4];
    for k in 0..3 {
        let lo = (a[k] & 0xFFFF).min(b[k] & 0xFFFF);
        let hi = (a[k] >> 16).max(b[k] >> 16);
        out[k] = lo | hi << 16;
    }
    out[3] = a[3] | b[3];
    out
}

/// The box of a node's bounds, in world units: [lo, hi + 1).
fn bounds_box(b: [u32; 4]) -> (DVec3, DVec3) {
    let lo = DVec3::new(
        (b[0] & 0xFFFF) as f64,
        (b[1] & 0xFFFF) as f64,
        (b[2] & 0xFFFF) as f64,
    );
    let hi = DVec3::new(
        (b[0] >> 16) as f64,
        (b[1] >> 16) as f64,
        (b[2] >> 16) as f64,
    ) + 1.0;
    (lo, hi)
}

/// cos θ widened by the bounding sphere's angular radius: cos θ + r / d, within
/// [`COS_FLOOR`, 1] — a linear stand-in for cos(max(0, θ − β)), sin β = r / d (two special
/// functions per node instead of seven; measured on the H100: 2–8 % less time per sample in
/// the light scenes for at most 1.4 % more error, BENCHMARKS.md "The renderer, round 4").
fn widened(cos_t: f64, r_over_d: f64) -> f64 {
    (cos_t + r_over_d).clamp(COS_FLOOR, 1.0)
}

/// The importance of a node of weight `w` and bounds `b` from point `p` with unit axis
/// normal `n` (0 when none of its faces can light p).
pub fn importance(w: f64, b: [u32; 4], p: DVec3, n: IVec3) -> f64 {
    if b[3] == 0 || w <= 0.0 {
        return 0.0;
    }
    let (lo, hi) = bounds_box(b);
    let c = (lo + hi) * 0.5;
    let v = p - c;
    let mut best = f64::NEG_INFINITY;
    for (dir, normal) in FACE_NORMALS.iter().enumerate() {
        if b[3] & (1 << dir) == 0 {
            continue;
        }
        let axis = dir >> 1;
        let faces_p = if dir & 1 == 1 {
            p[axis] > lo[axis] + 1.0
        } else {
            p[axis] < hi[axis] - 1.0
        };
        if faces_p {
            best = best.max(v.dot(normal.as_dvec3()));
        }
    }
    if best == f64::NEG_INFINITY {
        return 0.0;
    }
    let axis = if n.x != 0 {
        0
    } else if n.y != 0 {
        1
    } else {
        2
    };
    let in_front = if n[axis] > 0 {
        hi[axis] > p[axis]
    } else {
        lo[axis] < p[axis]
    };
    if !in_front {
        return 0.0;
    }
    let e = hi - lo;
    let r2 = e.dot(e) * 0.25;
    let d2 = v.dot(v);
    let inv_d = 1.0 / d2.max(1e-20).sqrt();
    let rd = 0.5 * e.length() * inv_d;
    let cos_l = widened(best * inv_d, rd);
    let cos_r = widened(-v.dot(n.as_dvec3()) * inv_d, rd);
    w * cos_l * cos_r / d2.max(r2)
}

impl Lights {
    fn node_importance(&self, i: usize, p: DVec3, n: IVec3) -> f64 {
        importance(self.nodes[i] as f64, self.bounds[i], p, n)
    }

    /// The root's importance from `p` with normal `n`: what all light faces together may
    /// give there (0: none can light p).
    pub fn root_importance(&self, p: DVec3, n: IVec3) -> f64 {
        self.node_importance(1, p, n)
    }

    /// A slot chosen for point `p` with normal `n` by descending the tree by importance with
    /// `u` ∈ [0, 1) (rescaled at each step), [`DESCENT_LEVELS`] levels a step, and its
    /// probability; None when no face can light p. The GPU descends the same way
    /// (shaders/lights.glsl `sample_light`).
    pub fn sample_from(&self, u: f64, p: DVec3, n: IVec3) -> Option<(u32, f64)> {
        self.sample_stepping(u, p, n, DESCENT_LEVELS)
    }

    /// The probability that [`Lights::sample_from`] at `p` with normal `n` chooses `slot`.
    pub fn probability_from(&self, slot: u32, p: DVec3, n: IVec3) -> f64 {
        self.probability_stepping(slot, p, n, DESCENT_LEVELS)
    }

    /// [`Lights::sample_from`] taking `levels` (1 ..= 3) levels of the binary tree a step: a
    /// node's 2^levels descendants that many levels down are chosen among by their own
    /// importance, as in a 2^levels-wide tree over the same nodes (the levels between are not
    /// read). shaders/lights.glsl's `LIGHT_LEVELS`.
    pub fn sample_stepping(&self, u: f64, p: DVec3, n: IVec3, levels: u32) -> Option<(u32, f64)> {
        let c = self.capacity as usize;
        if self.root_importance(p, n) <= 0.0 {
            return None;
        }
        let depth = c.trailing_zeros();
        let (mut i, mut u, mut prob, mut d) = (1usize, u, 1.0, 0);
        while d < depth {
            let s = levels.clamp(1, 3).min(depth - d);
            let first = i << s;
            let imp: Vec<f64> = (first..first + (1 << s))
                .map(|j| self.node_importance(j, p, n))
                .collect();
            let sum: f64 = imp.iter().sum();
            if sum <= 0.0 {
                return None;
            }
            // The child whose share of [0, sum) holds u · sum: the last of positive importance
            // whose share starts at or below it.
            let target = u * sum;
            let (mut below, mut pick, mut below_pick) = (0.0, 0, 0.0);
            for (j, &x) in imp.iter().enumerate() {
                if x > 0.0 && below <= target {
                    pick = j;
                    below_pick = below;
                }
                below += x;
            }
            u = ((target - below_pick) / imp[pick]).clamp(0.0, 1.0 - f64::EPSILON);
            prob *= imp[pick] / sum;
            i = first + pick;
            d += s;
        }
        Some(((i - c) as u32, prob))
    }

    /// The probability that [`Lights::sample_stepping`] with `levels` chooses `slot`.
    pub fn probability_stepping(&self, slot: u32, p: DVec3, n: IVec3, levels: u32) -> f64 {
        let c = self.capacity as usize;
        let leaf = c + slot as usize;
        if self.root_importance(p, n) <= 0.0 {
            return 0.0;
        }
        let depth = c.trailing_zeros();
        let (mut prob, mut d) = (1.0, 0);
        while d < depth {
            let s = levels.clamp(1, 3).min(depth - d);
            let first = (leaf >> (depth - d)) << s;
            let on = leaf >> (depth - d - s);
            let (mut sum, mut w) = (0.0, 0.0);
            for j in first..first + (1 << s) {
                let x = self.node_importance(j, p, n);
                sum += x;
                if j == on {
                    w = x;
                }
            }
            if sum <= 0.0 {
                return 0.0;
            }
            prob *= w / sum;
            d += s;
        }
        prob
    }
}

/// Morton code of a brick coordinate (bits interleaved x, y, z), the order new light faces
/// take slots in so that subtrees gather nearby faces.
pub(crate) fn morton(b: glam::UVec3) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut x = v as u64 & 0x1F_FFFF;
        x = (x | x << 32) & 0x1F_0000_0000_FFFF;
        x = (x | x << 16) & 0x1F_0000_FF00_00FF;
        x = (x | x << 8) & 0x100F_00F0_0F00_F00F;
        x = (x | x << 4) & 0x10C3_0C30_C30C_30C3;
        x = (x | x << 2) & 0x1249_2492_4924_9249;
        x
    }
    spread(b.x) | spread(b.y) << 1 | spread(b.z) << 2
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face(v: [i32; 3], f: u8) -> [u32; 4] {
        leaf_bounds(LightFace {
            voxel: IVec3::from(v),
            face: f,
            material: 1,
        })
    }

    #[test]
    fn a_face_lights_exactly_the_points_in_front_of_it_and_of_the_receiver() {
        // The +y face of voxel (4, 2, 4) lies on y = 3 over x, z ∈ [4, 5].
        let b = face([4, 2, 4], 3);
        let up = IVec3::Y;
        let down = IVec3::NEG_Y;
        assert!(importance(1.0, b, DVec3::new(4.5, 3.5, 4.5), down) > 0.0);
        assert_eq!(importance(1.0, b, DVec3::new(4.5, 3.0, 4.5), down), 0.0); // on its plane
        assert_eq!(importance(1.0, b, DVec3::new(4.5, 2.5, 9.0), up), 0.0); // behind it
        // A floor point in front of the face but facing away from it (the face is below).
        assert_eq!(importance(1.0, b, DVec3::new(10.0, 3.5, 4.5), up), 0.0);
        // A wall facing −x at x = 10 sees it.
        assert!(importance(1.0, b, DVec3::new(10.0, 3.5, 4.5), IVec3::NEG_X) > 0.0);
        // Nearer is more important, and it is 0 for an empty node.
        let near = importance(1.0, b, DVec3::new(4.5, 5.0, 4.5), down);
        let far = importance(1.0, b, DVec3::new(4.5, 50.0, 4.5), down);
        assert!(near > 10.0 * far);
        assert_eq!(importance(1.0, EMPTY_BOUNDS, DVec3::ZERO, up), 0.0);
    }

    #[test]
    fn a_union_covers_both_and_its_importance_is_positive_where_a_childs_is() {
        let a = face([4, 2, 4], 3);
        let b = face([40, 7, 1], 0);
        let u = union(a, b);
        assert_eq!(u, [4 | 40 << 16, 2 | 7 << 16, 1 | 4 << 16, 1 << 3 | 1]);
        for p in [[4.5, 9.0, 4.5], [30.0, 7.5, 1.5], [20.0, 3.5, 2.0]] {
            for n in FACE_NORMALS {
                let p = DVec3::from(p);
                if importance(1.0, a, p, n) > 0.0 || importance(1.0, b, p, n) > 0.0 {
                    assert!(importance(1.0, u, p, n) > 0.0, "{p} {n}");
                }
            }
        }
    }

    #[test]
    fn morton_codes_interleave_the_axes() {
        assert_eq!(morton(glam::UVec3::new(1, 0, 0)), 1);
        assert_eq!(morton(glam::UVec3::new(0, 1, 0)), 2);
        assert_eq!(morton(glam::UVec3::new(0, 0, 1)), 4);
        assert_eq!(morton(glam::UVec3::new(3, 3, 3)), 63);
        assert_eq!(morton(glam::UVec3::new(1 << 20, 0, 0)), 1 << 60);
    }
}
