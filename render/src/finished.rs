//! Finished renders: a picture of any size up to 16384 × 16384 rendered in tiles on the GPU
//! session, each tile stopping at a sample count or at a target relative noise, optionally
//! denoised, with an alpha channel (the coverage of the camera rays by voxels), reporting its
//! progress and stopping when asked to.
//!
//! A tile is a window of the picture ([`Window`]): its pixels, random numbers included, are
//! the picture's pixels there, so a tiled picture equals the untiled one. The noise of a tile
//! is estimated from two independent halves of its samples (the same pixels, two seeds): for
//! the mean M = (A + B) / 2 of halves A and B, Var M ≈ (A − B)² / 4 per pixel, and the tile's
//! relative noise is `relative_noise` below (a relMSE's square root, luminance, ε = 0.01).
//! Alpha is a second pass of the tile's camera rays (the first half's, the same numbers) with
//! the coverage variant: 1 per ray that hits a voxel, 0 per ray that does not; so alpha is 0
//! exactly where every camera ray misses and 1 exactly where every one hits. With alpha the
//! background is transparent: camera rays that miss add nothing to the colour (the sky and
//! the sun still light the voxels), so the colour is premultiplied by the alpha.
//! Denoised tiles are rendered with a margin the filter's reach wide and cropped (the filter
//! sees the picture's neighbours at a tile's edge); with a noise target the denoised tile is
//! rendered again at the sample count the target needed (the filter's moments are kept per
//! batch of its own accumulation), which costs that tile twice.

use crate::cpu::RenderJob;
use crate::image::Image;
use crate::params::SceneParams;
use crate::viewport::Viewport;
use crate::vulkan::progressive::Progressive;
use crate::vulkan::trace::{Variant, Window};
use crate::vulkan::{GpuContext, GpuError};
use brickmap::WorldView;
use std::sync::Arc;
use std::time::Instant;

/// The largest picture side.
pub const MAX_SIDE: u32 = 16384;

/// Pixels on each side of a denoised tile that are rendered and filtered but not kept: the
/// à-trous filter's reach (2 · (1 + 2 + 4 + 8 + 16) pixels) and the variance's 3 × 3 blurs.
pub const DENOISE_MARGIN: u32 = 66;

/// When a tile stops sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stop {
    /// After this many samples per pixel.
    Samples(u32),
    /// When its relative noise is at most `target` (e.g. 0.02), or at `max` samples per
    /// pixel, whichever comes first.
    Noise {
        /// The relative noise asked for.
        target: f64,
        /// The most samples per pixel.
        max: u32,
    },
}

/// What a finished render makes.
#[derive(Clone, Debug, PartialEq)]
pub struct Finish {
    /// The picture's width and height (each 1..=[`MAX_SIDE`]).
    pub size: (u32, u32),
    /// When each tile stops.
    pub stop: Stop,
    /// Filter the noise (the viewport's denoiser).
    pub denoise: bool,
    /// Make an alpha channel (the coverage of the camera rays by voxels).
    pub alpha: bool,
    /// The picture's random seed.
    pub seed: u64,
    /// A tile's side, pixels (smaller where the device's limits want).
    pub tile: u32,
}

/// A finished picture.
#[derive(Clone, Debug, PartialEq)]
pub struct Picture {
    /// The linear image (denoised when asked); with alpha, premultiplied by it (camera rays
    /// that miss every voxel add nothing).
    pub image: Image,
    /// Coverage per pixel, 0..=1, when asked.
    pub alpha: Option<Vec<f32>>,
    /// The fewest and most samples per pixel a tile took.
    pub samples: (u32, u32),
    /// The largest relative noise a tile ended with (of the image before denoising; with a
    /// noise target only).
    pub noise: Option<f64>,
    /// Tiles rendered.
    pub tiles: usize,
    /// GPU time spent (timestamp queries; None when the queue cannot time).
    pub gpu_seconds: Option<f64>,
}

/// Where a finished render is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// The part done, 0..=1 (pixels done, the current tile's counted by its samples).
    pub done: f64,
    /// The tile being rendered (0-based) and the tile count.
    pub tile: (usize, usize),
    /// Seconds since the render started.
    pub elapsed: f64,
}

impl Progress {
    /// Seconds left at the pace so far (None before anything is done).
    pub fn remaining(&self) -> Option<f64> {
        (self.done > 0.0).then(|| self.elapsed * (1.0 - self.done) / self.done)
    }
}

/// Why a finished render did not finish.
#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    /// The asked render makes no sense.
    #[error("{0}")]
    Invalid(String),
    /// The caller said stop.
    #[error("the render was cancelled")]
    Cancelled,
    /// The GPU failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl Finish {
    /// Checks the sizes and the stop rule.
    pub fn validate(&self) -> Result<(), PictureError> {
        let (w, h) = self.size;
        let bad = |s: String| Err(PictureError::Invalid(s));
        if !(1..=MAX_SIDE).contains(&w) || !(1..=MAX_SIDE).contains(&h) {
            return bad(format!(
                "a picture of {w} × {h}: each side is 1..={MAX_SIDE}"
            ));
        }
        if self.tile < 8 {
            return bad(format!("tiles of {} pixels: at least 8", self.tile));
        }
        match self.stop {
            Stop::Samples(n) if !(1..=1 << 20).contains(&n) => {
                bad(format!("{n} samples per pixel: 1..=1048576"))
            }
            Stop::Noise { target, max } if !(target > 0.0 && target < 1.0) || max < 2 => {
                bad(format!(
                    "a noise target of {target} up to {max} samples: the target is in (0, 1), at least 2 samples"
                ))
            }
            _ => Ok(()),
        }
    }

    /// The tiles: (top left pixel, size) of at most `side` × `side` each, covering the
    /// picture, rows first.
    pub fn tiles(&self, side: u32) -> Vec<((u32, u32), (u32, u32))> {
        let (w, h) = self.size;
        let mut out = Vec::new();
        for y in (0..h).step_by(side as usize) {
            for x in (0..w).step_by(side as usize) {
                out.push(((x, y), (side.min(w - x), side.min(h - y))));
            }
        }
        out
    }
}

/// √(mean over pixel pairs of `term(L1, L2)`), L the luminance of each image's pixel.
fn luminance_rms(a: &Image, b: &Image, term: impl Fn(f64, f64) -> f64) -> f64 {
    let lum = |p: &[f32; 3]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    let n = a.pixels.len().max(1) as f64;
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| term(lum(p), lum(q)))
        .sum();
    (sum / n).sqrt()
}

/// The relative noise of the mean of halves `a` and `b` (the same pixels, independent
/// samples): √(mean over pixels of ((La − Lb) / 2)² / (Lm² + 0.01)), L the luminance and Lm
/// that of the mean.
pub fn relative_noise(a: &Image, b: &Image) -> f64 {
    luminance_rms(a, b, |la, lb| {
        let (m, d) = (0.5 * (la + lb), 0.5 * (la - lb));
        d * d / (m * m + 0.01)
    })
}

/// The relative error of `image` against `reference`, the way [`relative_noise`] measures
/// noise: √(mean over pixels of (L − Lr)² / (Lr² + 0.01)).
pub fn relative_error(image: &Image, reference: &Image) -> f64 {
    luminance_rms(image, reference, |l, lr| {
        (l - lr) * (l - lr) / (lr * lr + 0.01)
    })
}

/// The second half's seed.
fn other_seed(seed: u64) -> u64 {
    seed ^ 0x9e37_79b9_7f4a_7c15
}

/// A tile's accumulation, freed when dropped.
struct Acc {
    acc: Option<Progressive>,
    ctx: Arc<GpuContext>,
}

impl Viewport {
    /// Renders `finish`'s picture of the scene in `view` with `params`, tile by tile,
    /// calling `progress` after every batch of samples; it returns false to cancel (the
    /// buffers are freed and [`PictureError::Cancelled`] comes back).
    pub fn render_picture(
        &mut self,
        view: &WorldView<'_>,
        params: &SceneParams,
        finish: &Finish,
        progress: &mut dyn FnMut(Progress) -> bool,
    ) -> Result<Picture, PictureError> {
        finish.validate()?;
        let started = Instant::now();
        let margin = if finish.denoise { DENOISE_MARGIN } else { 0 };
        let limits = self.ctx().limits;
        let mut side = finish.tile.min(MAX_SIDE);
        let fits = |s: u32| {
            let s = s + 2 * margin;
            limits.check_image("a tile", (s, s), 32).is_ok()
        };
        while side > 8 && !fits(side) {
            side /= 2;
        }
        let tiles = finish.tiles(side);
        let (w, h) = finish.size;
        let total = w as f64 * h as f64;
        let mut picture = Picture {
            image: Image {
                width: w,
                height: h,
                pixels: vec![[0.0; 3]; w as usize * h as usize],
            },
            alpha: finish.alpha.then(|| vec![0.0f32; w as usize * h as usize]),
            samples: (u32::MAX, 0),
            noise: None,
            tiles: tiles.len(),
            gpu_seconds: Some(0.0),
        };
        let mut done_pixels = 0.0;
        for (k, &(origin, size)) in tiles.iter().enumerate() {
            let tile_pixels = size.0 as f64 * size.1 as f64;
            let mut report = |part: f64| {
                progress(Progress {
                    done: ((done_pixels + tile_pixels * part.clamp(0.0, 1.0)) / total).min(1.0),
                    tile: (k, tiles.len()),
                    elapsed: started.elapsed().as_secs_f64(),
                })
            };
            let tile = self.render_tile(view, params, finish, origin, size, margin, &mut report)?;
            picture.samples.0 = picture.samples.0.min(tile.samples);
            picture.samples.1 = picture.samples.1.max(tile.samples);
            if let Some(n) = tile.noise {
                picture.noise = Some(picture.noise.unwrap_or(0.0).max(n));
            }
            picture.gpu_seconds = picture.gpu_seconds.zip(tile.gpu).map(|(a, b)| a + b);
            for row in 0..size.1 {
                let from = (row * size.0) as usize;
                let to = ((origin.1 + row) * w + origin.0) as usize;
                picture.image.pixels[to..to + size.0 as usize]
                    .copy_from_slice(&tile.image.pixels[from..from + size.0 as usize]);
                if let (Some(alpha), Some(cov)) = (&mut picture.alpha, &tile.alpha) {
                    alpha[to..to + size.0 as usize]
                        .copy_from_slice(&cov[from..from + size.0 as usize]);
                }
            }
            done_pixels += tile_pixels;
            if !report_done(
                &mut *progress,
                done_pixels / total,
                (k, tiles.len()),
                started,
            ) {
                return Err(PictureError::Cancelled);
            }
        }
        Ok(picture)
    }

    /// One tile: `size` pixels at `origin` of the picture.
    #[allow(clippy::too_many_arguments)]
    fn render_tile(
        &mut self,
        view: &WorldView<'_>,
        params: &SceneParams,
        finish: &Finish,
        origin: (u32, u32),
        size: (u32, u32),
        margin: u32,
        report: &mut dyn FnMut(f64) -> bool,
    ) -> Result<Tile, PictureError> {
        let variant = Variant {
            transparent: finish.alpha,
            ..Variant::for_scene(view, params)
        };
        let window = Window {
            origin,
            picture: finish.size,
        };
        let mut gpu = Some(0.0);
        let mut add = |g: Option<f64>| gpu = gpu.zip(g).map(|(a, b)| a + b);
        let mut a = Acc::new(self, size, window, finish.seed)?;
        let (image, samples, noise) = match finish.stop {
            Stop::Samples(n) => {
                let mut left = n;
                while left > 0 {
                    let batch = left.min(batch_spp(finish.tile));
                    add(a.add(self, view, params, variant, batch)?);
                    left -= batch;
                    if !report(f64::from(n - left) / f64::from(n)) {
                        return Err(PictureError::Cancelled);
                    }
                }
                (a.hdr()?, n, None)
            }
            Stop::Noise { target, max } => {
                let mut b = Acc::new(self, size, window, other_seed(finish.seed))?;
                noise_loop(
                    self,
                    view,
                    params,
                    variant,
                    (&mut a, &mut b),
                    (target, max, finish.tile),
                    &mut add,
                    report,
                )?
            }
        };
        let alpha = if finish.alpha {
            // The first half's camera rays again (the same seed and sample indices).
            let half = match finish.stop {
                Stop::Samples(n) => n,
                Stop::Noise { .. } => samples / 2,
            };
            let mut c = Acc::new(self, size, window, finish.seed)?;
            let coverage = Variant::coverage(variant.sequence);
            add(c.add(self, view, params, coverage, half.max(1))?);
            Some(c.hdr()?.pixels.iter().map(|p| p[0]).collect())
        } else {
            None
        };
        drop(a);
        let image = if finish.denoise {
            let (x0, y0) = (
                origin.0.saturating_sub(margin),
                origin.1.saturating_sub(margin),
            );
            let x1 = (origin.0 + size.0 + margin).min(finish.size.0);
            let y1 = (origin.1 + size.1 + margin).min(finish.size.1);
            let job = RenderJob {
                width: x1 - x0,
                height: y1 - y0,
                spp: samples,
                seed: finish.seed,
            };
            let window = Window {
                origin: (x0, y0),
                picture: finish.size,
            };
            let d = self.render_denoised_in(view, params, &job, variant, 0, window)?;
            add(d.trace_seconds);
            crop(&d.denoised, (origin.0 - x0, origin.1 - y0), size)
        } else {
            image
        };
        Ok(Tile {
            image,
            alpha,
            samples,
            noise,
            gpu,
        })
    }
}

/// Samples per pixel between two progress reports (and cancel checks): about 2 M paths for
/// a full tile of `side`², 1 to 16. The same for every tile of a picture, so tiles add their
/// samples in the batches the untiled picture does when the tile side is the same.
fn batch_spp(side: u32) -> u32 {
    ((1u64 << 21) / (side as u64 * side as u64).max(1)).clamp(1, 16) as u32
}

/// Calls `progress` with the part done; false: cancel.
fn report_done(
    progress: &mut dyn FnMut(Progress) -> bool,
    done: f64,
    tile: (usize, usize),
    started: Instant,
) -> bool {
    progress(Progress {
        done: done.min(1.0),
        tile,
        elapsed: started.elapsed().as_secs_f64(),
    })
}

/// Adds samples to both halves until their mean's noise reaches `target` or `max` samples
/// per pixel are taken: first 8 per half, then as many as the noise so far says are needed
/// (noise falls as 1/√n), at least twice as many, at most `max` in all.
#[allow(clippy::too_many_arguments)]
fn noise_loop(
    vp: &mut Viewport,
    view: &WorldView<'_>,
    params: &SceneParams,
    variant: Variant,
    (a, b): (&mut Acc, &mut Acc),
    (target, max, tile): (f64, u32, u32),
    add: &mut dyn FnMut(Option<f64>),
    report: &mut dyn FnMut(f64) -> bool,
) -> Result<(Image, u32, Option<f64>), PictureError> {
    let half_max = (max / 2).max(1);
    let mut half = 0u32;
    let mut want = 8.min(half_max);
    loop {
        while half < want {
            let batch = (want - half).min(batch_spp(tile));
            add(a.add(vp, view, params, variant, batch)?);
            add(b.add(vp, view, params, variant, batch)?);
            half += batch;
            if !report(f64::from(half) / f64::from(want.max(1)) * 0.99) {
                return Err(PictureError::Cancelled);
            }
        }
        let (ia, ib) = (a.hdr()?, b.hdr()?);
        let noise = relative_noise(&ia, &ib);
        if noise <= target || half >= half_max {
            let mean = Image {
                width: ia.width,
                height: ia.height,
                pixels: ia
                    .pixels
                    .iter()
                    .zip(&ib.pixels)
                    .map(|(p, q)| std::array::from_fn(|c| 0.5 * (p[c] + q[c])))
                    .collect(),
            };
            return Ok((mean, 2 * half, Some(noise)));
        }
        let needed = (f64::from(half) * (noise / target).powi(2) * 1.05).ceil();
        want = (needed.min(f64::from(half_max)) as u32)
            .max(2 * half)
            .min(half_max);
    }
}

/// A rendered tile.
struct Tile {
    image: Image,
    alpha: Option<Vec<f32>>,
    samples: u32,
    noise: Option<f64>,
    gpu: Option<f64>,
}

impl Acc {
    /// `size` pixels at `window` of the picture, numbers from `seed`.
    fn new(
        vp: &mut Viewport,
        size: (u32, u32),
        window: Window,
        seed: u64,
    ) -> Result<Self, PictureError> {
        let ctx = vp.ctx().clone();
        let mut acc = Progressive::new(&ctx, size, size, seed)?;
        acc.set_window(window);
        Ok(Self {
            acc: Some(acc),
            ctx,
        })
    }

    /// Adds `spp` samples per pixel with `variant`; the GPU time.
    fn add(
        &mut self,
        vp: &mut Viewport,
        view: &WorldView<'_>,
        params: &SceneParams,
        variant: Variant,
        spp: u32,
    ) -> Result<Option<f64>, PictureError> {
        let (ctx, tracer, world) = vp.parts();
        let acc = self.acc.as_mut().expect("kept until dropped");
        let (gpu, _) = acc.accumulate(ctx, tracer, world, view, params, variant, spp)?;
        Ok(gpu)
    }

    /// The mean so far.
    fn hdr(&self) -> Result<Image, PictureError> {
        Ok(self
            .acc
            .as_ref()
            .expect("kept until dropped")
            .hdr(&self.ctx)?)
    }
}

impl Drop for Acc {
    fn drop(&mut self) {
        if let Some(acc) = self.acc.take() {
            acc.destroy(&self.ctx);
        }
    }
}

/// The `size` pixels of `image` at `at`.
fn crop(image: &Image, at: (u32, u32), size: (u32, u32)) -> Image {
    let mut pixels = Vec::with_capacity(size.0 as usize * size.1 as usize);
    for y in at.1..at.1 + size.1 {
        let row = (y * image.width + at.0) as usize;
        pixels.extend_from_slice(&image.pixels[row..row + size.0 as usize]);
    }
    Image {
        width: size.0,
        height: size.1,
        pixels,
    }
}
