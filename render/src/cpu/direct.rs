//! Next-event estimation at a surface vertex (docs/DESIGN.md "Emissive voxels as lights"): one
//! light per vertex. Where light faces can be sampled (a scene with them, a vertex in air) the
//! sun and the faces are chosen between by their estimated contributions (the sun's disc
//! bounds, the light tree's root importance), each kept at least 10 %; a face is then drawn
//! from the light tree by importance (`Lights::sample_from`). Elsewhere the sun alone is
//! sampled, as before light faces existed. shaders/trace.comp does the same; keep in step.

use super::{CpuScene, Frame, Shading, eval_bsdf, face_point, power_heuristic};
use crate::params::SunDisc;
use brickmap::Lights;
use brickmap::lights::FACE_NORMALS;
use glam::{DVec3, IVec3};
use std::f64::consts::PI;

/// The least share of each of the sun and the light faces when both may light a vertex.
pub const LEAST_SHARE: f64 = 0.1;

/// What a vertex sampled, to weigh a BSDF ray's hit on a light against it.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Sampled {
    /// The probability the sun was chosen (0: it was not sampled).
    pub sun: f64,
    /// The probability the light faces were chosen (0: they were not sampled).
    pub faces: f64,
    /// The vertex and its normal (a face's probability in the tree depends on them).
    pub p: DVec3,
    pub n: IVec3,
}

/// The sun's share of a vertex's light sample, from the estimates of what the sun and the
/// light faces may give there: 1 without faces, 0 without the sun, else the sun's fraction
/// kept within [LEAST_SHARE, 1 − LEAST_SHARE].
pub fn sun_share(sun: f64, faces: f64) -> f64 {
    if faces <= 0.0 {
        return 1.0;
    }
    if sun <= 0.0 {
        return 0.0;
    }
    LEAST_SHARE + (1.0 - 2.0 * LEAST_SHARE) * sun / (sun + faces)
}

/// cos(max(0, θ − β)) for cos θ = `c` and sin β = `sin_b` (≤ 0 when no direction within β of
/// the axis is above the plane).
fn widened(c: f64, sin_b: f64) -> f64 {
    let cos_b = (1.0 - sin_b * sin_b).max(0.0).sqrt();
    if c >= cos_b {
        return 1.0;
    }
    c * cos_b + (1.0 - c * c).max(0.0).sqrt() * sin_b
}

impl SunDisc {
    /// What the disc may give a point `p` with normal `n`: radiance (r + g + b) × solid angle
    /// × bounds of both cosines over the disc; 0 exactly when no point of it can light p.
    pub fn estimate(&self, p: DVec3, n: IVec3) -> f64 {
        let to = self.centre - p;
        let d2 = to.length_squared();
        let d = d2.sqrt();
        if d <= self.radius {
            return 0.0; // inside the sun: nothing defined, nothing sampled
        }
        let w = to / d;
        let sin_b = self.radius / d;
        let cos_r = widened(w.dot(n.as_dvec3()), sin_b);
        let cos_l = widened(-w.dot(self.normal), sin_b);
        if cos_r <= 0.0 || cos_l <= 0.0 {
            return 0.0;
        }
        self.radiance.element_sum() * self.area() * cos_l * cos_r / d2
    }
}

/// The index in `FACE_NORMALS` of an axis normal.
pub(super) fn face_of(n: IVec3) -> u8 {
    FACE_NORMALS.iter().position(|&f| f == n).unwrap_or(0) as u8
}

/// The solid-angle probability with which a vertex that `sampled` would have chosen the light
/// face (`voxel`, `normal`) seen at distance `t` under cosine `cos_l`: 0 when it sampled no
/// light face (then a BSDF hit on it takes full weight).
pub(super) fn face_pdf(
    lights: &Lights,
    sampled: &Sampled,
    voxel: IVec3,
    normal: IVec3,
    t: f64,
    cos_l: f64,
) -> f64 {
    if sampled.faces <= 0.0 {
        return 0.0;
    }
    let Some(slot) = lights.slot_of(voxel, face_of(normal)) else {
        return 0.0;
    };
    sampled.faces * lights.probability_from(slot, sampled.p, sampled.n) * t * t / cos_l
}

/// A shading point joined to a point on a light (next-event estimation).
pub(super) struct Connection {
    /// Unit direction to the light point, and its distance.
    pub w: DVec3,
    pub dist: f64,
    /// Cosine at the light (its outward normal against −w).
    pub cos_l: f64,
    /// Cosine at the surface, BSDF value and the pdf BSDF sampling would choose w with.
    cos_s: f64,
    f: DVec3,
    pdf_bsdf: f64,
}

impl Connection {
    /// None when the light faces away, the point lies below the surface or the BSDF is 0.
    pub fn new(
        s: Shading,
        frame: &Frame,
        wo: DVec3,
        p: DVec3,
        y: DVec3,
        n_l: DVec3,
    ) -> Option<Self> {
        let to = y - p;
        let dist = to.length();
        let w = to / dist;
        let cos_l = -w.dot(n_l);
        let wi = frame.to_local(w);
        if !(cos_l > 0.0 && wi.z > 0.0) {
            return None;
        }
        let (f, pdf_bsdf) = eval_bsdf(s, wo, wi);
        (f != DVec3::ZERO).then_some(Self {
            w,
            dist,
            cos_l,
            cos_s: wi.z,
            f,
            pdf_bsdf,
        })
    }
    /// The light's contribution when unblocked: radiance `l` sampled with solid-angle pdf
    /// `pdf_light`, weighted against BSDF sampling by the power heuristic.
    pub fn light(&self, l: DVec3, pdf_light: f64) -> DVec3 {
        self.f * self.cos_s * l * power_heuristic(pdf_light, self.pdf_bsdf) / pdf_light
    }
}

/// A surface vertex: its material, frame, outgoing direction, point, the cell in front of it
/// (where its shadow rays start) and whether it lies in air (light faces are sampled only
/// there).
pub(super) struct Vertex<'a> {
    pub s: Shading,
    pub frame: &'a Frame,
    pub wo: DVec3,
    pub p: DVec3,
    pub n: IVec3,
    pub front: IVec3,
    pub in_air: bool,
}

impl CpuScene<'_, '_> {
    /// Direct light at a non-delta surface vertex (one light sampled), and what was sampled.
    pub(super) fn direct(&self, v: &Vertex, rng: &mut super::Pcg32) -> (DVec3, Sampled) {
        let mut sampled = Sampled {
            p: v.p,
            n: v.n,
            ..Sampled::default()
        };
        let lights = self.lights.filter(|_| v.in_air);
        let Some(lights) = lights else {
            let Some(sun) = &self.sun else {
                return (DVec3::ZERO, sampled);
            };
            sampled.sun = 1.0;
            return (self.sample_sun(sun, 1.0, v, rng), sampled);
        };
        let faces = lights.root_importance(v.p, v.n);
        let sun = self.sun.as_ref().map_or(0.0, |s| s.estimate(v.p, v.n));
        let share = if self.sun.is_some() {
            sun_share(sun, faces)
        } else {
            0.0
        };
        sampled.sun = share;
        sampled.faces = if faces > 0.0 { 1.0 - share } else { 0.0 };
        let u = rng.next_f64();
        let l = if u < share {
            let sun = self.sun.as_ref().expect("a share only with a sun");
            self.sample_sun(sun, share, v, rng)
        } else if sampled.faces > 0.0 {
            let u = ((u - share) / (1.0 - share)).min(1.0 - f64::EPSILON);
            self.sample_face(lights, sampled.faces, u, v, rng)
        } else {
            DVec3::ZERO
        };
        (l, sampled)
    }

    /// The sun chosen with probability `share`: a point uniform on its disc.
    fn sample_sun(&self, sun: &SunDisc, share: f64, v: &Vertex, rng: &mut super::Pcg32) -> DVec3 {
        let r = sun.radius * rng.next_f64().sqrt();
        let phi = 2.0 * PI * rng.next_f64();
        let y = sun.centre + (sun.e1 * phi.cos() + sun.e2 * phi.sin()) * r;
        let Some(c) = Connection::new(v.s, v.frame, v.wo, v.p, y, sun.normal) else {
            return DVec3::ZERO;
        };
        if self.occluded(v.p, c.w, v.front, c.dist) {
            return DVec3::ZERO;
        }
        c.light(
            sun.radiance,
            share * c.dist * c.dist / (c.cos_l * sun.area()),
        )
    }

    /// The light faces chosen with probability `share`: a face from the tree by importance
    /// (with `u`), a point uniform on it. The shadow ray may end in the light's voxel and
    /// nowhere before it.
    fn sample_face(
        &self,
        lights: &Lights,
        share: f64,
        u: f64,
        v: &Vertex,
        rng: &mut super::Pcg32,
    ) -> DVec3 {
        let Some((slot, prob)) = lights.sample_from(u, v.p, v.n) else {
            return DVec3::ZERO;
        };
        let face = lights.face(slot);
        let y = face_point(face.voxel, face.face, rng.next_f64(), rng.next_f64());
        let Some(c) = Connection::new(v.s, v.frame, v.wo, v.p, y, face.normal().as_dvec3()) else {
            return DVec3::ZERO;
        };
        self.count_ray();
        let ray = brickmap::Ray {
            origin: v.p,
            dir: c.w,
        };
        let blocker = brickmap::cast_from_cell(self.view, &ray, v.front, c.dist);
        if blocker
            .ok()
            .flatten()
            .is_some_and(|h| h.voxel != face.voxel)
        {
            return DVec3::ZERO;
        }
        let e = self.materials[face.material as usize];
        c.light(e.albedo * e.param, share * prob * c.dist * c.dist / c.cos_l)
    }
}
