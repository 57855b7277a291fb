//! The numerical stress suite (`voxbrick stress`; a smaller run in CI): millions of random
//! and adversarial rays through the GPU traversal judged against the exact CPU ray cast
//! ([`rays`]), and whole images of adversarial scenes on the GPU and the CPU reference
//! counted for NaN, infinite and negative samples, energy lost in white furnaces and
//! iteration caps hit ([`scenes`]). Every count is expected to be zero.

pub mod rays;
pub mod scenes;

use crate::cpu::{CpuScene, RenderJob};
use crate::image::Image;
use crate::viewport::{RenderHow, Viewport};
use crate::vulkan::{GpuContext, GpuError};
use glam::IVec3;
use rays::{RayClass, RayTally};
use std::sync::Arc;

/// SplitMix64: the suite's own deterministic numbers.
pub struct Rng(u64);

impl Rng {
    /// A stream from `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in [0, 1), in f64.
    pub fn unit_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [−1, 1).
    pub fn signed(&mut self) -> f32 {
        self.unit() * 2.0 - 1.0
    }

    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }
}

/// How much to try.
#[derive(Clone, Copy, Debug)]
pub struct StressConfig {
    /// Rays per class and ray world.
    pub rays_per_class: usize,
    /// GPU images: width and height.
    pub gpu_size: u32,
    /// GPU images: one-sample renders per view.
    pub gpu_renders: u32,
    /// CPU reference images: width and height.
    pub cpu_size: u32,
    /// CPU reference images: one-sample renders per view.
    pub cpu_renders: u32,
    /// Seed of everything random.
    pub seed: u64,
}

/// One class of rays in one world.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RayRow {
    /// The world.
    pub world: String,
    /// The class.
    pub class: String,
    /// What came of it.
    pub tally: RayTally,
}

/// One adversarial scene on one renderer.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ImageRow {
    /// The scene.
    pub scene: String,
    /// "GPU" or "CPU".
    pub renderer: String,
    /// Samples tried (pixels × one-sample renders × views).
    pub samples: u64,
    /// Samples with a NaN channel.
    pub nan: u64,
    /// Samples with an infinite channel (and no NaN).
    pub inf: u64,
    /// Samples with a negative channel (finite).
    pub negative: u64,
    /// GPU traversal iteration caps hit (None on the CPU, whose exact cast has none).
    pub caps_hit: Option<u64>,
    /// Mean of channel 0 over all samples and its standard error.
    pub mean: f64,
    /// Standard error of `mean`.
    pub standard_error: f64,
    /// A furnace's or closed emitter's expected mean.
    pub expected: Option<f64>,
    /// Relative energy lost, 1 − mean / expected.
    pub energy_lost: Option<f64>,
    /// Whether the loss is as the estimator must give: zero within 4 standard errors where it
    /// conserves energy; never a gain where it does not (single-scattering GGX).
    pub energy_ok: Option<bool>,
}

impl ImageRow {
    /// Whether every count is zero and the energy is as expected.
    pub fn clean(&self) -> bool {
        self.nan == 0
            && self.inf == 0
            && self.negative == 0
            && self.caps_hit.unwrap_or(0) == 0
            && self.energy_ok.unwrap_or(true)
    }
}

/// Sums per sample over many one-sample images.
#[derive(Default)]
struct SampleCounts {
    n: u64,
    nan: u64,
    inf: u64,
    negative: u64,
    sum: f64,
    sum_sq: f64,
}

impl SampleCounts {
    fn add(&mut self, img: &Image) {
        for px in &img.pixels {
            self.n += 1;
            if px.iter().any(|c| c.is_nan()) {
                self.nan += 1;
            } else if px.iter().any(|c| c.is_infinite()) {
                self.inf += 1;
            } else {
                if px.iter().any(|&c| c < 0.0) {
                    self.negative += 1;
                }
                let v = px[0] as f64;
                self.sum += v;
                self.sum_sq += v * v;
            }
        }
    }

    fn row(
        &self,
        scene: &str,
        renderer: &str,
        caps: Option<u64>,
        expected: Option<(f64, bool)>,
    ) -> ImageRow {
        let finite = (self.n - self.nan - self.inf).max(1) as f64;
        let mean = self.sum / finite;
        let var = (self.sum_sq / finite - mean * mean).max(0.0) * finite / (finite - 1.0).max(1.0);
        let se = (var / finite).sqrt();
        let (lost, ok) = match expected {
            Some((e, conserving)) => {
                let lost = 1.0 - mean / e;
                let slack = 4.0 * se / e + 1e-4;
                (
                    Some(lost),
                    Some(if conserving {
                        lost.abs() <= slack
                    } else {
                        lost >= -slack
                    }),
                )
            }
            None => (None, None),
        };
        ImageRow {
            scene: scene.to_string(),
            renderer: renderer.to_string(),
            samples: self.n,
            nan: self.nan,
            inf: self.inf,
            negative: self.negative,
            caps_hit: caps,
            mean,
            standard_error: se,
            expected: expected.map(|e| e.0),
            energy_lost: lost,
            energy_ok: ok,
        }
    }
}

/// Every ray class through both ray worlds on the GPU, judged against the CPU cast.
/// `progress` hears each row as it is done.
pub fn ray_suite(
    ctx: &Arc<GpuContext>,
    cfg: &StressConfig,
    mut progress: impl FnMut(&RayRow),
) -> Result<Vec<RayRow>, GpuError> {
    let mut rows = Vec::new();
    for rw in [scenes::dense(), scenes::largest()] {
        let view = rw.world.read();
        let mut session = Viewport::new(ctx.clone(), &view)?;
        let size = view.dims().voxels().as_vec3();
        for class in RayClass::ALL {
            let mut pick = |rng: &mut Rng| -> Option<IVec3> {
                (!rw.solid.is_empty()).then(|| rw.solid[rng.below(rw.solid.len() as u64) as usize])
            };
            let rays = rays::generate(class, cfg.rays_per_class, size, cfg.seed, &mut pick);
            let (hits, caps) = session.first_hits(&rays, None)?;
            let row = RayRow {
                world: rw.name.to_string(),
                class: class.name().to_string(),
                tally: rays::tally(&view, &rays, &hits, caps),
            };
            progress(&row);
            rows.push(row);
        }
    }
    Ok(rows)
}

/// Every adversarial scene on the GPU (when `ctx` is given) and on the CPU reference, one
/// sample per pixel per render, every sample counted.
pub fn image_suite(
    ctx: Option<&Arc<GpuContext>>,
    cfg: &StressConfig,
    mut progress: impl FnMut(&ImageRow),
) -> Result<Vec<ImageRow>, GpuError> {
    let mut rows = Vec::new();
    for scene in scenes::all() {
        let view = scene.world.read();
        if let Some(ctx) = ctx {
            let mut session = Viewport::new(ctx.clone(), &view)?;
            let (mut counts, mut caps) = (SampleCounts::default(), 0);
            for (v, p) in scene.views.iter().enumerate() {
                for k in 0..cfg.gpu_renders {
                    let job = RenderJob {
                        width: cfg.gpu_size,
                        height: cfg.gpu_size,
                        spp: 1,
                        seed: cfg.seed + 1000 * v as u64 + k as u64,
                    };
                    let r = session.render(&view, p, &job, RenderHow::SCENE.counted())?;
                    counts.add(&r.image);
                    caps += r.rays.expect("counted").capped;
                }
            }
            let row = counts.row(scene.name, "GPU", Some(caps), scene.expected);
            progress(&row);
            rows.push(row);
        }
        let mut counts = SampleCounts::default();
        for (v, p) in scene.views.iter().enumerate() {
            let cpu = CpuScene::new(&view, p);
            for k in 0..cfg.cpu_renders {
                counts.add(&cpu.render(&RenderJob {
                    width: cfg.cpu_size,
                    height: cfg.cpu_size,
                    spp: 1,
                    seed: cfg.seed + 1000 * v as u64 + k as u64,
                }));
            }
        }
        let row = counts.row(scene.name, "CPU", None, scene.expected);
        progress(&row);
        rows.push(row);
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_samples_are_counted_once_each() {
        let img = Image {
            width: 5,
            height: 1,
            pixels: vec![
                [1.0, 2.0, 3.0],
                [f32::NAN, f32::INFINITY, -1.0],
                [f32::INFINITY, -1.0, 0.0],
                [0.5, -0.5, 0.0],
                [-0.0, 0.0, 0.0],
            ],
        };
        let mut c = SampleCounts::default();
        c.add(&img);
        let row = c.row("s", "CPU", None, Some((0.5, true)));
        assert_eq!((row.samples, row.nan, row.inf, row.negative), (5, 1, 1, 1));
        assert_eq!(row.mean, 0.5, "the finite samples' mean");
        assert!(!row.clean());
        assert_eq!(row.energy_lost, Some(0.0));
        // A loss beyond the noise fails a conserving furnace, a gain fails any.
        let mut f = SampleCounts::default();
        f.add(&Image {
            width: 2,
            height: 1,
            pixels: vec![[0.4; 3], [0.4; 3]],
        });
        assert_eq!(
            f.row("f", "GPU", Some(0), Some((0.5, true))).energy_ok,
            Some(false)
        );
        assert_eq!(
            f.row("f", "GPU", Some(0), Some((0.5, false))).energy_ok,
            Some(true)
        );
        assert_eq!(
            f.row("f", "GPU", Some(0), Some((0.3, false))).energy_ok,
            Some(false)
        );
        assert!(!f.row("f", "GPU", Some(1), None).clean(), "a cap hit fails");
    }
}
