//! Random and adversarial rays for the GPU traversal, and their verdict against the exact f64
//! CPU ray cast of the same (f32) ray.
//!
//! A ray's verdict is *exact* (same first voxel, same entry face, hit points within the
//! tolerance, or both miss), an *edge face* (same voxel and hit point, which lies on an edge
//! or corner of the voxel, and another of that edge's faces named), an *f32 tie* (the answers differ, but only where the ray passes
//! within the tolerance of a voxel's boundary: a crossing the f32 traversal and the f64 cast
//! may order either way), or a *mismatch* (anything else: a bug). The tolerance is positional:
//! [`tolerance`] = 4 ulps of f32 at the largest coordinate involved (the ray's origin unless
//! it is farther than [`FAR_ORIGIN`] outside, the hit points, the grid's far corner), compared
//! with distances to voxel boxes in the max norm; hit parameters are compared as |Δt| ·
//! max|dᵢ| with 4 ulps of t (and f32's least normal, a t that small may be flushed) added.
//! Direction components below f32's least normal are zero for both ([`flush_denormals`]).

use super::Rng;
use brickmap::{Ray, RayHit, WorldView};
use glam::{DVec3, IVec3, Vec3};

use crate::vulkan::primary::GpuHit;

/// The kinds of rays tried.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayClass {
    /// Uniform origins in and around the grid, uniform directions.
    Random,
    /// One axis ±1, the other components +0.0 or −0.0.
    AxisParallel,
    /// Face and space diagonals from integer and half-integer points (exact crossing ties).
    Diagonal,
    /// Origins on a voxel face plane.
    OnFace,
    /// Origins on a voxel edge, half of them moving along it or in one of its faces.
    OnEdge,
    /// Origins on voxel corners.
    OnCorner,
    /// Origins inside solid voxels (strictly inside, or on their corner).
    InsideSolid,
    /// Origins on a face plane, moving off it by a tiny component (2⁻¹⁰ … 2⁻¹²⁰).
    Grazing,
    /// One or two components denormal (at least one normal component left).
    Denormal,
    /// Components scaled up to 2¹²⁷, mixed with ordinary ones.
    Huge,
    /// Origins within 8 voxels of the grid's eight corners.
    GridCorners,
    /// Origins 10³ … 10⁷ voxels outside the grid, aimed at points in it.
    FarOutside,
}

impl RayClass {
    /// Every class.
    pub const ALL: [RayClass; 12] = [
        RayClass::Random,
        RayClass::AxisParallel,
        RayClass::Diagonal,
        RayClass::OnFace,
        RayClass::OnEdge,
        RayClass::OnCorner,
        RayClass::InsideSolid,
        RayClass::Grazing,
        RayClass::Denormal,
        RayClass::Huge,
        RayClass::GridCorners,
        RayClass::FarOutside,
    ];

    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            RayClass::Random => "random",
            RayClass::AxisParallel => "axis-parallel (±0.0)",
            RayClass::Diagonal => "diagonals",
            RayClass::OnFace => "from faces",
            RayClass::OnEdge => "from and along edges",
            RayClass::OnCorner => "from corners",
            RayClass::InsideSolid => "from inside voxels",
            RayClass::Grazing => "grazing",
            RayClass::Denormal => "denormal components",
            RayClass::Huge => "huge components",
            RayClass::GridCorners => "grid corners",
            RayClass::FarOutside => "origins far outside",
        }
    }
}

/// A uniform direction.
fn sphere(rng: &mut Rng) -> Vec3 {
    loop {
        let v = Vec3::new(rng.signed(), rng.signed(), rng.signed());
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// ±0.0 with a random sign.
fn signed_zero(rng: &mut Rng) -> f32 {
    if rng.below(2) == 0 { 0.0 } else { -0.0 }
}

fn with(v: Vec3, axis: usize, x: f32) -> Vec3 {
    let mut a = v.to_array();
    a[axis] = x;
    Vec3::from_array(a)
}

fn at(v: Vec3, axis: usize) -> f32 {
    v.to_array()[axis]
}

/// `n` rays of `class` for a grid of `size` voxels; `solid` finds solid voxels (None when it
/// gives up: the scene has too few).
pub fn generate(
    class: RayClass,
    n: usize,
    size: Vec3,
    seed: u64,
    mut solid: impl FnMut(&mut Rng) -> Option<IVec3>,
) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng::new(seed ^ (class as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mut rays = Vec::with_capacity(n);
    let point = |rng: &mut Rng| Vec3::new(rng.unit(), rng.unit(), rng.unit()) * size;
    let lattice = |rng: &mut Rng| point(rng).floor();
    while rays.len() < n {
        let ray = match class {
            RayClass::Random => {
                let o = point(&mut rng) * 1.5 - size * 0.25;
                (o, sphere(&mut rng))
            }
            RayClass::AxisParallel => {
                let mut o = point(&mut rng);
                if rng.below(2) == 0 {
                    o = o.floor();
                }
                let axis = rng.below(3) as usize;
                let mut d = Vec3::new(
                    signed_zero(&mut rng),
                    signed_zero(&mut rng),
                    signed_zero(&mut rng),
                );
                d = with(d, axis, if rng.below(2) == 0 { 1.0 } else { -1.0 });
                (o, d)
            }
            RayClass::Diagonal => {
                let o = lattice(&mut rng) + Vec3::splat(if rng.below(2) == 0 { 0.0 } else { 0.5 });
                let s = |rng: &mut Rng| if rng.below(2) == 0 { 1.0 } else { -1.0 };
                let mut d = Vec3::new(s(&mut rng), s(&mut rng), s(&mut rng));
                if rng.below(2) == 0 {
                    d = with(d, rng.below(3) as usize, signed_zero(&mut rng));
                }
                (o, d)
            }
            RayClass::OnFace => {
                let axis = rng.below(3) as usize;
                let o = point(&mut rng);
                (with(o, axis, at(o, axis).floor()), sphere(&mut rng))
            }
            RayClass::OnEdge => {
                let free = rng.below(3) as usize;
                let o = with(lattice(&mut rng), free, at(point(&mut rng), free));
                let d = match rng.below(3) {
                    0 => with(Vec3::ZERO, free, if rng.below(2) == 0 { 1.0 } else { -1.0 }),
                    1 => {
                        let inplane = (free + 1 + rng.below(2) as usize) % 3;
                        with(sphere(&mut rng), 3 - free - inplane, signed_zero(&mut rng))
                    }
                    _ => sphere(&mut rng),
                };
                (o, d)
            }
            RayClass::OnCorner => {
                let o = lattice(&mut rng);
                let d = if rng.below(2) == 0 {
                    sphere(&mut rng)
                } else {
                    Vec3::new(rng.signed(), rng.signed(), rng.signed()).signum()
                };
                (o, d)
            }
            RayClass::InsideSolid => {
                let Some(v) = solid(&mut rng) else {
                    break;
                };
                let f = if rng.below(4) == 0 {
                    Vec3::ZERO
                } else {
                    Vec3::new(rng.unit(), rng.unit(), rng.unit())
                };
                (v.as_vec3() + f, sphere(&mut rng))
            }
            RayClass::Grazing => {
                let axis = rng.below(3) as usize;
                let o = point(&mut rng);
                let tiny = (-(10.0 + rng.unit() * 110.0)).exp2();
                let tiny = if rng.below(2) == 0 { tiny } else { -tiny };
                let d = with(sphere(&mut rng), axis, tiny);
                (with(o, axis, at(o, axis).floor()), d)
            }
            RayClass::Denormal => {
                let mut d = sphere(&mut rng);
                let k = 1 + rng.below(2) as usize;
                let first = rng.below(3) as usize;
                for j in 0..k {
                    let bits = 1 + rng.below(0x7F_FFFF) as u32;
                    let x = f32::from_bits(bits | if rng.below(2) == 0 { 0 } else { 1 << 31 });
                    d = with(d, (first + j) % 3, x);
                }
                let mut o = point(&mut rng);
                if rng.below(2) == 0 {
                    o = o.floor();
                }
                (o, d)
            }
            RayClass::Huge => {
                let mut d = sphere(&mut rng);
                let scale = (60.0 + rng.unit() * 66.0).exp2();
                if rng.below(2) == 0 {
                    d *= scale;
                } else {
                    let axis = rng.below(3) as usize;
                    d = with(d, axis, at(d, axis) * scale);
                }
                if !d.is_finite() {
                    continue;
                }
                (point(&mut rng), d)
            }
            RayClass::GridCorners => {
                let corner = Vec3::new(
                    rng.below(2) as f32,
                    rng.below(2) as f32,
                    rng.below(2) as f32,
                ) * size;
                let jitter = Vec3::new(rng.signed(), rng.signed(), rng.signed()) * 8.0;
                let o = if rng.below(4) == 0 {
                    corner
                } else {
                    corner + jitter
                };
                let d = if rng.below(3) == 0 {
                    with(
                        Vec3::new(
                            signed_zero(&mut rng),
                            signed_zero(&mut rng),
                            signed_zero(&mut rng),
                        ),
                        rng.below(3) as usize,
                        if rng.below(2) == 0 { 1.0 } else { -1.0 },
                    )
                } else {
                    sphere(&mut rng)
                };
                (o, d)
            }
            RayClass::FarOutside => {
                let distance = 10f32.powf(3.0 + rng.unit() * 4.0);
                let o = size * 0.5 + sphere(&mut rng) * distance;
                let target = point(&mut rng);
                (o, (target - o).normalize())
            }
        };
        if ray.1 != Vec3::ZERO && ray.0.is_finite() && ray.1.is_finite() {
            rays.push(ray);
        }
    }
    rays
}

/// What one class of rays came to.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RayTally {
    /// Rays tried.
    pub tried: u64,
    /// Rays the CPU cast found a voxel for.
    pub hits: u64,
    /// Same voxel, face and hit point (or both miss).
    pub exact: u64,
    /// Same voxel and hit point on an edge or corner, another face of it named.
    pub edge_faces: u64,
    /// Different answers within the f32 tolerance of a voxel boundary.
    pub f32_ties: u64,
    /// Anything else: expected zero.
    pub mismatches: u64,
    /// GPU traversal iteration caps hit: expected zero.
    pub caps_hit: u64,
    /// Rays the CPU cast refused (none are generated invalid): expected zero.
    pub cpu_errors: u64,
    /// Up to four mismatches, described.
    pub examples: Vec<String>,
    /// Up to two ties, described.
    pub tie_examples: Vec<String>,
}

impl RayTally {
    /// Adds another tally.
    pub fn add(&mut self, o: &RayTally) {
        self.tried += o.tried;
        self.hits += o.hits;
        self.exact += o.exact;
        self.edge_faces += o.edge_faces;
        self.f32_ties += o.f32_ties;
        self.mismatches += o.mismatches;
        self.caps_hit += o.caps_hit;
        self.cpu_errors += o.cpu_errors;
        for e in &o.examples {
            if self.examples.len() < 4 {
                self.examples.push(e.clone());
            }
        }
        for e in &o.tie_examples {
            if self.tie_examples.len() < 2 {
                self.tie_examples.push(e.clone());
            }
        }
    }
}

/// Origins farther than this outside the grid are first moved to just before it by the GPU
/// traversal (`FAR_ORIGIN` in shaders/brickmap.glsl).
pub const FAR_ORIGIN: f64 = 1024.0;

/// 4 ulps of f32 at the largest of `coords` (and 1).
pub fn tolerance(coords: &[f64]) -> f64 {
    let m = coords.iter().fold(1.0f64, |m, c| m.max(c.abs()));
    4.0 * (m.log2().floor() - 23.0).exp2()
}

/// The parameter interval of the ray inside the box [lo, hi] (t ≥ 0), if it meets it.
fn slab(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
        } else {
            let (x, y) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
            t0 = t0.max(x.min(y));
            t1 = t1.min(x.max(y));
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

/// Max-norm distance from `p` to the unit box of voxel `v`.
fn box_distance(p: DVec3, v: IVec3) -> f64 {
    let lo = v.as_dvec3();
    let outside = (lo - p).max(p - (lo + 1.0)).max(DVec3::ZERO);
    outside.max_element()
}

/// Whether the ray only grazes voxel `v`: it never comes deeper than `eps` inside.
fn grazes(o: DVec3, d: DVec3, v: IVec3, eps: f64) -> bool {
    if eps >= 0.5 {
        return true;
    }
    let lo = v.as_dvec3() + eps;
    slab(o, d, lo, lo + (1.0 - 2.0 * eps)).is_none()
}

/// The verdict on one ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Same answer.
    Exact,
    /// Same voxel and hit point, which lies on an edge or corner of the voxel: the two
    /// walks name different faces of that edge (a block skip and a voxel step order
    /// simultaneous crossings differently).
    Edge,
    /// Different, explained by f32 resolution at a voxel boundary.
    Tie,
    /// Wrong.
    Mismatch,
}

/// Judges the GPU's answer `gpu` for ray (o, d) against the CPU's `cpu`; `solid` tells
/// whether a voxel is solid.
pub fn judge(
    o: DVec3,
    d: DVec3,
    size: DVec3,
    cpu: Option<RayHit>,
    gpu: Option<GpuHit>,
    solid: impl Fn(IVec3) -> bool,
) -> Verdict {
    let dmax = d.abs().max_element();
    let t_of = |t: f64| o + d * t;
    // An origin farther out than the GPU's FAR_ORIGIN is first moved to just before the grid
    // (exactly, up to the rounding there), so its magnitude does not count.
    let outside = (-o).max(o - size).max_element();
    let mut coords = vec![size.max_element()];
    if outside <= FAR_ORIGIN {
        coords.push(o.abs().max_element());
    }
    if let Some(c) = cpu {
        coords.push(t_of(c.t).abs().max_element());
    }
    if let Some(g) = gpu {
        coords.push(t_of(g.t as f64).abs().max_element());
    }
    let eps = tolerance(&coords);
    // Hit parameters also carry f32 rounding of t itself (a far origin's t is large).
    let t_scale = cpu
        .map_or(0.0, |c| c.t)
        .max(gpu.map_or(0.0, |g| g.t as f64));
    // A t below f32's least normal may come back as 0 (flushed).
    let eps_t = eps + (tolerance(&[t_scale]) + f32::MIN_POSITIVE as f64) * dmax;
    match (cpu, gpu) {
        (None, None) => return Verdict::Exact,
        (Some(c), Some(g))
            if c.voxel == g.voxel
                && c.normal == g.normal
                && (c.t - g.t as f64).abs() * dmax <= eps_t =>
        {
            return Verdict::Exact;
        }
        _ => {}
    }
    // The GPU's voxel must be solid and touched by the ray where the GPU says.
    if let Some(g) = gpu {
        let p = t_of(g.t as f64);
        if !solid(g.voxel) || box_distance(p, g.voxel) > eps_t {
            return Verdict::Mismatch;
        }
    }
    let close = |a: f64, b: f64| (a - b).abs() * dmax <= eps_t;
    let ok = match (cpu, gpu) {
        (Some(c), Some(g)) => {
            let tg = g.t as f64;
            if close(c.t, tg) {
                if c.voxel == g.voxel {
                    // Same voxel, other face: the hit point lies on the edge of both.
                    let axis = g.normal.abs().to_array().iter().position(|&x| x == 1);
                    let on_edge = axis.is_some_and(|a| {
                        let plane = g.voxel[a] as f64 + if g.normal[a] > 0 { 1.0 } else { 0.0 };
                        (t_of(c.t)[a] - plane).abs() <= eps
                    });
                    return if on_edge {
                        Verdict::Edge
                    } else {
                        Verdict::Mismatch
                    };
                }
                true
            } else if tg > c.t {
                // The GPU went past the CPU's voxel: only if the ray just grazes it.
                grazes(o, d, c.voxel, eps)
            } else {
                // The GPU stopped at a voxel the CPU went past: only a grazed one.
                grazes(o, d, g.voxel, eps)
            }
        }
        (Some(c), None) => grazes(o, d, c.voxel, eps),
        (None, Some(g)) => grazes(o, d, g.voxel, eps),
        (None, None) => true,
    };
    if ok { Verdict::Tie } else { Verdict::Mismatch }
}

/// The direction the GPU traverses: components below f32's least normal are zero
/// (`LEAST_NORMAL` in shaders/brickmap.glsl; Vulkan lets devices flush denormals, so the
/// traversal does it on every device).
pub fn flush_denormals(d: Vec3) -> Vec3 {
    Vec3::from_array(
        d.to_array()
            .map(|c| if c.abs() < f32::MIN_POSITIVE { 0.0 } else { c }),
    )
}

/// One ray and both answers, with the exact bits of the ray.
fn describe(o: Vec3, d: Vec3, cpu: Option<RayHit>, gpu: Option<GpuHit>) -> String {
    format!(
        "origin {:?} dir {:?} (bits {:x?} / {:x?}): CPU {:?}, GPU {:?}",
        o.to_array(),
        d.to_array(),
        o.to_array().map(f32::to_bits),
        d.to_array().map(f32::to_bits),
        cpu.map(|c| (c.voxel.to_array(), c.normal.to_array(), c.t)),
        gpu.map(|g| (g.voxel.to_array(), g.normal.to_array(), g.t)),
    )
}

/// Casts every ray on the CPU (f64, on all cores) and judges the GPU's answers.
pub fn tally(
    view: &WorldView<'_>,
    rays: &[(Vec3, Vec3)],
    gpu: &[Option<GpuHit>],
    caps_hit: u64,
) -> RayTally {
    let size = view.dims().voxels().as_dvec3();
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let chunk = rays.len().div_ceil(threads).max(1);
    let parts: Vec<RayTally> = std::thread::scope(|s| {
        let handles: Vec<_> = rays
            .chunks(chunk)
            .zip(gpu.chunks(chunk))
            .map(|(rays, gpu)| {
                s.spawn(move || {
                    let mut t = RayTally::default();
                    for (&(o, d), &g) in rays.iter().zip(gpu) {
                        t.tried += 1;
                        let ray = Ray {
                            origin: o.as_dvec3(),
                            dir: flush_denormals(d).as_dvec3(),
                        };
                        let cpu = match brickmap::cast(view, &ray, f64::INFINITY) {
                            Ok(c) => c,
                            Err(_) => {
                                t.cpu_errors += 1;
                                continue;
                            }
                        };
                        t.hits += u64::from(cpu.is_some());
                        let solid = |v: IVec3| view.voxel(v).ok().flatten().is_some();
                        match judge(ray.origin, ray.dir, size, cpu, g, solid) {
                            Verdict::Exact => t.exact += 1,
                            Verdict::Edge => {
                                t.edge_faces += 1;
                                if t.tie_examples.len() < 2 {
                                    t.tie_examples.push(describe(o, d, cpu, g));
                                }
                            }
                            Verdict::Tie => {
                                t.f32_ties += 1;
                                if t.tie_examples.len() < 2 {
                                    t.tie_examples.push(describe(o, d, cpu, g));
                                }
                            }
                            Verdict::Mismatch => {
                                t.mismatches += 1;
                                if t.examples.len() < 4 {
                                    t.examples.push(describe(o, d, cpu, g));
                                }
                            }
                        }
                    }
                    t
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a CPU cast thread panicked"))
            .collect()
    });
    let mut total = RayTally {
        caps_hit,
        ..Default::default()
    };
    for p in &parts {
        total.add(p);
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(voxel: IVec3, normal: IVec3, t: f64) -> RayHit {
        RayHit { voxel, normal, t }
    }

    fn ghit(voxel: IVec3, normal: IVec3, t: f32) -> GpuHit {
        GpuHit { voxel, t, normal }
    }

    #[test]
    fn judging_tells_ties_from_mismatches() {
        let size = DVec3::splat(64.0);
        let all = |_| true;
        let o = DVec3::new(0.5, 0.5, 0.25);
        let d = DVec3::X;
        let c = hit(IVec3::new(3, 0, 0), IVec3::NEG_X, 2.5);
        let same = ghit(IVec3::new(3, 0, 0), IVec3::NEG_X, 2.5);
        assert_eq!(judge(o, d, size, Some(c), Some(same), all), Verdict::Exact);
        // A voxel further on, through the middle of the CPU's: the GPU skipped a voxel.
        let past = ghit(IVec3::new(5, 0, 0), IVec3::NEG_X, 4.5);
        assert_eq!(
            judge(o, d, size, Some(c), Some(past), all),
            Verdict::Mismatch
        );
        assert_eq!(judge(o, d, size, Some(c), None, all), Verdict::Mismatch);
        // An empty voxel reported as a hit.
        assert_eq!(
            judge(o, d, size, None, Some(same), |v: IVec3| v.x != 3),
            Verdict::Mismatch
        );
        // A ray along y = 1 exactly (the boundary between rows 0 and 1): either row is right.
        let o = DVec3::new(0.5, 1.0, 0.5);
        let c = hit(IVec3::new(3, 1, 0), IVec3::NEG_X, 2.5);
        let other = ghit(IVec3::new(3, 0, 0), IVec3::NEG_X, 2.5);
        assert_eq!(judge(o, d, size, Some(c), Some(other), all), Verdict::Tie);
        assert_eq!(judge(o, d, size, None, Some(other), all), Verdict::Tie);
        // Same voxel, other face, at an edge only.
        let diag = DVec3::new(1.0, 1.0, 0.0);
        let o = DVec3::new(0.0, 0.0, 0.5);
        let c = hit(IVec3::new(2, 2, 0), IVec3::NEG_X, 2.0);
        let g = ghit(IVec3::new(2, 2, 0), IVec3::NEG_Y, 2.0);
        assert_eq!(judge(o, diag, size, Some(c), Some(g), all), Verdict::Edge);
        let o = DVec3::new(0.0, 0.5, 0.5);
        let c = hit(IVec3::new(2, 2, 0), IVec3::NEG_X, 2.0);
        let g = ghit(IVec3::new(2, 2, 0), IVec3::NEG_Y, 2.0);
        assert_eq!(
            judge(o, diag, size, Some(c), Some(g), all),
            Verdict::Mismatch
        );
    }

    #[test]
    fn tolerance_scales_with_the_coordinates() {
        assert_eq!(tolerance(&[0.5]), 4.0 * 2f64.powi(-23));
        assert_eq!(tolerance(&[4096.0, 3.0]), 4.0 * 2f64.powi(12 - 23));
    }

    #[test]
    fn every_class_makes_valid_rays() {
        for class in RayClass::ALL {
            let rays = generate(class, 500, Vec3::new(64.0, 32.0, 64.0), 3, |rng| {
                Some(IVec3::new(rng.below(64) as i32, 0, rng.below(64) as i32))
            });
            assert_eq!(rays.len(), 500, "{class:?}");
            assert!(
                rays.iter()
                    .all(|(o, d)| o.is_finite() && d.is_finite() && *d != Vec3::ZERO),
                "{class:?}"
            );
        }
        // The classes are what they say.
        let size = Vec3::splat(64.0);
        let axis = generate(RayClass::AxisParallel, 200, size, 1, |_| None);
        assert!(axis.iter().all(|(_, d)| d.abs().element_sum() == 1.0));
        assert!(
            axis.iter()
                .any(|(_, d)| d.to_array().iter().any(|c| c.to_bits() == 1 << 31)),
            "some −0.0"
        );
        let den = generate(RayClass::Denormal, 200, size, 1, |_| None);
        assert!(
            den.iter()
                .all(|(_, d)| d.to_array().iter().any(|c| c.is_subnormal()))
        );
        assert!(
            den.iter()
                .all(|(_, d)| d.to_array().iter().any(|c| c.is_normal()))
        );
    }
}
