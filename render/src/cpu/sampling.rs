//! Random numbers and the sampling routines of the integrator: PCG32, cosine-weighted
//! hemisphere, GGX visible-normal sampling (Heitz 2018), the Smith terms, exact unpolarized
//! Fresnel. Vectors are in a local frame whose z axis is the surface normal.

use glam::DVec3;
use std::f64::consts::PI;

/// PCG32 (O'Neill): a small, statistically strong generator; one stream per pixel.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    /// A generator for `(seed, stream)`; different streams are independent sequences.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }
    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(6364136223846793005).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }
    /// Uniform in [0, 1), 53 bits.
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        (hi | lo) as f64 / (1u64 << 53) as f64
    }
}

/// Cosine-weighted direction on the +z hemisphere; pdf = cos θ / π.
pub fn cosine_hemisphere(u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

/// GGX normal distribution D(h) for roughness α.
pub fn ggx_d(h: DVec3, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
    1.0 / (PI * a2 * t * t)
}

/// Smith Λ(w) for GGX.
pub fn ggx_lambda(w: DVec3, alpha: f64) -> f64 {
    let tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
    ((1.0 + alpha * alpha * tan2).sqrt() - 1.0) * 0.5
}

/// A microfacet normal sampled from the GGX distribution of normals visible from `wo`
/// (Heitz 2018); its pdf is G1(wo)·max(0, wo·h)·D(h) / wo.z.
pub fn ggx_sample_visible(wo: DVec3, alpha: f64, u1: f64, u2: f64) -> DVec3 {
    let vh = DVec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        DVec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
    } else {
        DVec3::X
    };
    let t2 = vh.cross(t1);
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// Exact Fresnel reflectance of unpolarized light at a smooth interface, for the cosine of
/// the incident angle and the indices on the incident (`eta_i`) and transmitted side. 1 at
/// total internal reflection. Also returns the transmitted cosine.
pub fn fresnel_dielectric(cos_i: f64, eta_i: f64, eta_t: f64) -> (f64, f64) {
    let eta = eta_i / eta_t;
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    let rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg_is_uniform_enough() {
        let mut r = Pcg32::new(42, 7);
        let n = 200_000;
        let mut bins = [0u32; 10];
        for _ in 0..n {
            bins[(r.next_f64() * 10.0) as usize] += 1;
        }
        for b in bins {
            let expected = n as f64 / 10.0;
            assert!(
                (b as f64 - expected).abs() < 5.0 * expected.sqrt(),
                "{bins:?}"
            );
        }
    }

    #[test]
    fn fresnel_limits() {
        // Normal incidence: ((n1 − n2)/(n1 + n2))².
        let (f, _) = fresnel_dielectric(1.0, 1.0, 1.5);
        assert!((f - 0.04).abs() < 1e-12);
        // Grazing: 1. Beyond the critical angle from inside: total internal reflection.
        assert!((fresnel_dielectric(1e-9, 1.0, 1.5).0 - 1.0).abs() < 1e-6);
        assert_eq!(fresnel_dielectric(0.3, 1.5, 1.0).0, 1.0);
    }

    #[test]
    fn visible_normal_pdf_integrates_to_one() {
        // ∫ D_wo(h) dh over the hemisphere = 1, checked by importance sampling a uniform
        // hemisphere estimate of the density the sampler claims.
        let alpha = 0.3;
        let wo = DVec3::new(0.5, 0.1, 0.86).normalize();
        let g1 = 1.0 / (1.0 + ggx_lambda(wo, alpha));
        let mut r = Pcg32::new(1, 1);
        let n = 400_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let z = r.next_f64();
            let phi = 2.0 * PI * r.next_f64();
            let s = (1.0 - z * z).sqrt();
            let h = DVec3::new(s * phi.cos(), s * phi.sin(), z);
            sum += g1 * wo.dot(h).max(0.0) * ggx_d(h, alpha) / wo.z * 2.0 * PI;
        }
        assert!((sum / n as f64 - 1.0).abs() < 0.02, "{}", sum / n as f64);
    }
}
