//! The CPU reference path tracer: the light transport of docs/DESIGN.md, written for clarity in
//! f64, as the test oracle for the GPU renderer and the `--device cpu` backend.
//!
//! Conventions it fixes (docs/DESIGN.md repeats them for independent checks):
//! - Albedo is the material's colour-table entry decoded from sRGB to linear.
//! - A path carries its medium: a dielectric material it is inside, or air. Inside a medium
//!   the next interaction is the first voxel that is not that medium (air or another
//!   material); a dielectric face between two media is an interface with relative IOR
//!   η_i/η_t, any other solid face is a surface shaded from the medium's side.
//! - At a refraction, transmission is multiplied by the albedo of the dielectric whose face
//!   is crossed (the one entered, or the one left when leaving into air) and by (η_i/η_t)².
//! - Rays leave a surface from a known cell (`brickmap::cast_from_cell`), never from an
//!   epsilon-offset point.

mod direct;
pub mod sampling;

use crate::image::Image;
use crate::params::{SceneParams, Sky, SunDisc};
use brickmap::{Lights, MaterialKind, Occupancy, Ray, RayHit, WorldView};
use glam::{DVec3, IVec3, UVec3};
use sampling::{
    Pcg32, cosine_hemisphere, fresnel_dielectric, ggx_d, ggx_lambda, ggx_sample_visible,
};
use std::f64::consts::PI;

/// A material resolved for shading.
#[derive(Clone, Copy, Debug)]
struct Shading {
    kind: MaterialKind,
    /// Linear albedo (reflectance, transmission tint, or emission colour).
    albedo: DVec3,
    /// Roughness (metal), IOR (dielectric) or strength (emissive).
    param: f64,
}

impl SunDisc {
    fn area(&self) -> f64 {
        PI * self.radius * self.radius
    }
    /// Distance along a unit ray to the disc's front face, if it hits it.
    fn intersect(&self, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
        let denom = d.dot(self.normal);
        if denom >= 0.0 {
            return None; // parallel, or seeing the back (one-sided)
        }
        let t = (self.centre - o).dot(self.normal) / denom;
        if t.is_nan()
            || t <= 0.0
            || (o + d * t - self.centre).length_squared() > self.radius * self.radius
        {
            return None;
        }
        Some((t, -denom))
    }
}

/// sRGB-encoded byte to linear (one definition, shared with the light weights).
pub use brickmap::lights::srgb_to_linear;

/// What to render.
#[derive(Clone, Debug)]
pub struct RenderJob {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of every pixel's random stream.
    pub seed: u64,
}

impl RenderJob {
    /// `spp` samples per pixel of an image of `size` (width, height) with `seed`.
    pub fn sized(size: (u32, u32), spp: u32, seed: u64) -> Self {
        Self {
            width: size.0,
            height: size.1,
            spp,
            seed,
        }
    }
}

/// Occupancy inside a dielectric medium: the next interaction is the first voxel that is not
/// this material (no empty-space skipping: empty space is what ends the medium).
struct InMedium<'a, 'w> {
    view: &'a WorldView<'w>,
    material: u8,
}

impl Occupancy for InMedium<'_, '_> {
    fn dims(&self) -> brickmap::GridDims {
        self.view.dims()
    }
    fn coarse_occupied(&self, _: UVec3) -> bool {
        true
    }
    fn brick_occupied(&self, _: UVec3) -> bool {
        true
    }
    fn solid(&self, v: IVec3) -> bool {
        self.view.voxel(v).ok().flatten() != Some(self.material)
    }
}

/// Where a ray starts: the camera (cell found from the origin) or a known cell.
#[derive(Clone, Copy)]
enum Start {
    Camera,
    Cell(IVec3),
}

/// The scene prepared for tracing.
pub struct CpuScene<'a, 'w> {
    view: &'a WorldView<'w>,
    materials: Vec<Shading>,
    sun: Option<SunDisc>,
    sky: Sky,
    max_bounces: u32,
    camera: crate::params::Camera,
    rays: std::sync::atomic::AtomicU64,
    /// The light faces of emissive voxels, when sampled (None: none, or BSDF rays only).
    lights: Option<&'a Lights>,
}

impl<'a, 'w> CpuScene<'a, 'w> {
    /// Resolves materials, sun and sky of a scene.
    pub fn new(view: &'a WorldView<'w>, params: &SceneParams) -> Self {
        let table = view.materials();
        let materials = (0..table.len())
            .map(|i| {
                let m = table.get(i as u8).expect("index within the table");
                let [r, g, b] = table.colour(m.colour);
                Shading {
                    kind: m.kind,
                    albedo: DVec3::new(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b)),
                    param: table.param(m.kind, m.param).unwrap_or(0.0) as f64,
                }
            })
            .collect();
        let sun = params.sun.disc(view.dims().voxels().as_dvec3() * 0.5);
        Self {
            view,
            materials,
            sun,
            sky: params.sky.clone(),
            max_bounces: params.settings.max_bounces,
            camera: params.camera.clone(),
            rays: std::sync::atomic::AtomicU64::new(0),
            lights: Some(view.lights()).filter(|l| l.total() > 0.0),
        }
    }

    /// Light sampling of emissive voxels on (the default when there are any) or off (they
    /// are then found by BSDF rays only: the same converged image, noisier).
    pub fn with_light_sampling(mut self, on: bool) -> Self {
        self.lights = if on {
            Some(self.view.lights()).filter(|l| l.total() > 0.0)
        } else {
            None
        };
        self
    }

    fn count_ray(&self) {
        self.rays.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }

    /// Rays traced so far (camera, continuation and shadow rays).
    pub fn rays_traced(&self) -> u64 {
        self.rays.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Overrides the bounce count B.
    pub fn with_max_bounces(mut self, b: u32) -> Self {
        self.max_bounces = b.max(1);
        self
    }

    fn sky(&self, d: DVec3) -> DVec3 {
        let c = |v: [f32; 3]| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
        match &self.sky {
            Sky::Uniform { colour } => c(*colour),
            Sky::Gradient { horizon, zenith } => {
                let t = d.y.clamp(0.0, 1.0);
                c(*horizon) * (1.0 - t) + c(*zenith) * t
            }
        }
    }

    fn material_at(&self, v: IVec3) -> Option<Shading> {
        self.view
            .voxel(v)
            .ok()
            .flatten()
            .map(|m| self.materials[m as usize])
    }

    /// The first interaction along a ray in a medium (`None`: air).
    fn trace(&self, o: DVec3, d: DVec3, start: Start, medium: Option<u8>) -> Option<RayHit> {
        self.count_ray();
        let ray = Ray { origin: o, dir: d };
        let inf = f64::INFINITY;
        let hit = match (medium, start) {
            (None, Start::Camera) => brickmap::cast(self.view, &ray, inf),
            (None, Start::Cell(c)) => brickmap::cast_from_cell(self.view, &ray, c, inf),
            (Some(material), Start::Camera) => brickmap::cast(
                &InMedium {
                    view: self.view,
                    material,
                },
                &ray,
                inf,
            ),
            (Some(material), Start::Cell(c)) => brickmap::cast_from_cell(
                &InMedium {
                    view: self.view,
                    material,
                },
                &ray,
                c,
                inf,
            ),
        };
        hit.ok().flatten()
    }

    /// Whether any voxel lies on the segment from a surface (leaving from `cell`) to a point
    /// at distance `dist` (dielectrics block shadow rays too).
    fn occluded(&self, o: DVec3, d: DVec3, cell: IVec3, dist: f64) -> bool {
        self.count_ray();
        brickmap::cast_from_cell(self.view, &Ray { origin: o, dir: d }, cell, dist)
            .ok()
            .flatten()
            .is_some()
    }

    /// The camera ray through image position (x, y) in pixels (fractional: the box filter
    /// comes from jittering within the pixel).
    pub fn camera_ray(&self, x: f64, y: f64, width: u32, height: u32) -> (DVec3, DVec3) {
        let u = 2.0 * x / width as f64 - 1.0;
        let v = 1.0 - 2.0 * y / height as f64;
        self.camera.ray(u, v, width as f64 / height as f64)
    }

    /// One sample of the radiance arriving at `origin` from direction `−dir` (unit `dir`).
    pub fn radiance(&self, origin: DVec3, dir: DVec3, rng: &mut Pcg32) -> DVec3 {
        let mut l = DVec3::ZERO;
        let mut beta = DVec3::ONE;
        let (mut o, mut d) = (origin, dir);
        let mut start = Start::Camera;
        let mut medium = self
            .view
            .voxel(origin.floor().as_ivec3())
            .ok()
            .flatten()
            .filter(|&m| self.materials[m as usize].kind == MaterialKind::Dielectric);
        // Solid-angle pdf of the BSDF sample that made the current ray; None after a delta
        // scattering or at the camera (then a sun hit takes full weight).
        let mut bsdf_pdf: Option<f64> = None;
        // What the vertex the current ray left sampled (a hit on the sun or a light face is
        // weighted against that by the power heuristic).
        let mut sampled = direct::Sampled::default();
        for vertex in 1..=self.max_bounces + 1 {
            let hit = self.trace(o, d, start, medium);
            let t_voxel = hit.map_or(f64::INFINITY, |h| h.t);
            if let Some(sun) = &self.sun
                && let Some((t_sun, cos_l)) = sun.intersect(o, d)
                && t_sun < t_voxel
            {
                let w = bsdf_pdf.map_or(1.0, |p| {
                    power_heuristic(p, sampled.sun * t_sun * t_sun / (cos_l * sun.area()))
                });
                l += beta * sun.radiance * w;
                break;
            }
            let Some(hit) = hit else {
                l += beta * self.sky(d);
                break;
            };
            let p = o + d * hit.t;
            let n = hit.normal.as_dvec3();
            let here = self.material_at(hit.voxel);
            let interface = match (here, medium) {
                (Some(s), _) if s.kind == MaterialKind::Dielectric => true,
                (None, Some(_)) => true, // leaving a medium into air
                _ => false,
            };
            if let Some(s) = here
                && s.kind == MaterialKind::Emissive
            {
                // They reflect nothing. Full weight unless the last vertex sampled them.
                let w = match (bsdf_pdf, self.lights) {
                    (Some(pdf), Some(lights)) => {
                        let cos_l = -d.dot(n);
                        let light =
                            direct::face_pdf(lights, &sampled, hit.voxel, hit.normal, hit.t, cos_l);
                        power_heuristic(pdf, light)
                    }
                    _ => 1.0,
                };
                l += beta * s.albedo * s.param * w;
                break;
            }
            if vertex == self.max_bounces + 1 {
                break; // whatever the B-th continuation ray hit has been counted
            }
            let front = hit.voxel + hit.normal; // the cell the ray arrived from
            if interface {
                let eta_i = medium.map_or(1.0, |m| self.materials[m as usize].param);
                let (eta_t, tint) = match here {
                    Some(s) => (s.param, s.albedo),
                    None => (
                        1.0,
                        self.materials[medium.expect("leaving a medium") as usize].albedo,
                    ),
                };
                let cos_i = -d.dot(n);
                let (f, cos_t) = fresnel_dielectric(cos_i, eta_i, eta_t);
                if rng.next_f64() < f {
                    d = (d + n * (2.0 * cos_i)).normalize();
                    start = Start::Cell(front);
                } else {
                    let eta = eta_i / eta_t;
                    d = (d * eta + n * (eta * cos_i - cos_t)).normalize();
                    start = Start::Cell(hit.voxel);
                    beta *= tint * (eta * eta);
                    medium = here.and_then(|_| self.view.voxel(hit.voxel).ok().flatten());
                }
                bsdf_pdf = None;
                sampled = direct::Sampled::default();
            } else {
                let s = here.expect("a surface interaction has a material");
                let frame = Frame::new(n);
                let wo = frame.to_local(-d);
                // Next-event estimation (the sun or a light face), for non-delta surfaces.
                // Light faces are sampled from vertices in air (from inside a medium every
                // shadow ray is blocked at once: shadow rays stop at any voxel).
                let delta = s.kind == MaterialKind::Metal && s.param <= 0.0;
                sampled = direct::Sampled::default();
                if !delta {
                    let vertex = direct::Vertex {
                        s,
                        frame: &frame,
                        wo,
                        p,
                        n: hit.normal,
                        front,
                        in_air: medium.is_none(),
                    };
                    let (light, what) = self.direct(&vertex, rng);
                    l += beta * light;
                    sampled = what;
                }
                let Some((wi, weight, pdf)) = sample_bsdf(s, wo, rng) else {
                    break;
                };
                beta *= weight;
                bsdf_pdf = pdf;
                d = frame.to_world(wi);
                start = Start::Cell(front);
            }
            o = p;
            // Russian roulette from the 4th vertex on.
            if vertex >= 4 {
                let q = beta.max_element().clamp(0.05, 1.0);
                if rng.next_f64() >= q {
                    break;
                }
                beta /= q;
            }
        }
        l
    }

    /// Renders an image: `spp` samples per pixel, box filter, on every core.
    pub fn render(&self, job: &RenderJob) -> Image {
        let (w, h) = (job.width as usize, job.height as usize);
        let mut pixels = vec![[0f32; 3]; w * h];
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(h.max(1));
        let rows_per = h.div_ceil(threads);
        std::thread::scope(|scope| {
            for (chunk_index, chunk) in pixels.chunks_mut(rows_per * w).enumerate() {
                scope.spawn(move || {
                    for (k, px) in chunk.iter_mut().enumerate() {
                        let index = chunk_index * rows_per * w + k;
                        let (x, y) = ((index % w) as f64, (index / w) as f64);
                        let mut rng = Pcg32::new(job.seed, index as u64);
                        let mut sum = DVec3::ZERO;
                        for _ in 0..job.spp {
                            let (o, d) = self.camera_ray(
                                x + rng.next_f64(),
                                y + rng.next_f64(),
                                job.width,
                                job.height,
                            );
                            sum += self.radiance(o, d, &mut rng);
                        }
                        let mean = sum / job.spp.max(1) as f64;
                        *px = [mean.x as f32, mean.y as f32, mean.z as f32];
                    }
                });
            }
        });
        Image {
            width: job.width,
            height: job.height,
            pixels,
        }
    }
}

/// The point (u1, u2) of a voxel's face (`brickmap::lights::FACE_NORMALS` order), uniform
/// for uniform u.
pub fn face_point(voxel: IVec3, face: u8, u1: f64, u2: f64) -> DVec3 {
    let v = voxel.as_dvec3();
    let high = (face & 1) as f64; // +x, +y, +z faces lie at the voxel's far side
    v + match face / 2 {
        0 => DVec3::new(high, u1, u2),
        1 => DVec3::new(u1, high, u2),
        _ => DVec3::new(u1, u2, high),
    }
}

fn power_heuristic(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// An orthonormal frame around an axis-aligned normal (voxel faces), z = normal.
struct Frame {
    t: DVec3,
    b: DVec3,
    n: DVec3,
}

impl Frame {
    fn new(n: DVec3) -> Self {
        let t = if n.x != 0.0 { DVec3::Y } else { DVec3::X };
        let b = n.cross(t);
        Self { t, b, n }
    }
    fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }
    fn to_world(&self, v: DVec3) -> DVec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// BSDF value and the solid-angle pdf `sample_bsdf` would have chosen `wi` with.
fn eval_bsdf(s: Shading, wo: DVec3, wi: DVec3) -> (DVec3, f64) {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return (DVec3::ZERO, 0.0);
    }
    match s.kind {
        MaterialKind::Lambertian => (s.albedo / PI, wi.z / PI),
        MaterialKind::Metal if s.param > 0.0 => {
            let alpha = s.param * s.param;
            let h = (wo + wi).normalize();
            let d = ggx_d(h, alpha);
            let g2 = 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
            let g1 = 1.0 / (1.0 + ggx_lambda(wo, alpha));
            (
                s.albedo * (d * g2 / (4.0 * wo.z * wi.z)),
                g1 * d / (4.0 * wo.z),
            )
        }
        _ => (DVec3::ZERO, 0.0),
    }
}

/// Samples an incoming direction: (wi, f·cos/pdf, pdf or None for a delta lobe).
fn sample_bsdf(s: Shading, wo: DVec3, rng: &mut Pcg32) -> Option<(DVec3, DVec3, Option<f64>)> {
    match s.kind {
        MaterialKind::Lambertian => {
            let wi = cosine_hemisphere(rng.next_f64(), rng.next_f64());
            (wi.z > 0.0).then_some((wi, s.albedo, Some(wi.z / PI)))
        }
        MaterialKind::Metal if s.param <= 0.0 => {
            Some((DVec3::new(-wo.x, -wo.y, wo.z), s.albedo, None))
        }
        MaterialKind::Metal => {
            let alpha = s.param * s.param;
            if wo.z <= 0.0 {
                return None;
            }
            let h = ggx_sample_visible(wo, alpha, rng.next_f64(), rng.next_f64());
            let wi = h * (2.0 * wo.dot(h)) - wo;
            if wi.z <= 0.0 {
                return None;
            }
            let lo = ggx_lambda(wo, alpha);
            let g2_over_g1 = (1.0 + lo) / (1.0 + lo + ggx_lambda(wi, alpha));
            let pdf = ggx_d(h, alpha) / (4.0 * wo.z * (1.0 + lo));
            Some((wi, s.albedo * g2_over_g1, Some(pdf)))
        }
        // Dielectrics are interfaces and emissive voxels end paths: never sampled here.
        MaterialKind::Dielectric | MaterialKind::Emissive => None,
    }
}
