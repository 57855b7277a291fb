//! Progressive accumulation: samples add up in a device-local HDR buffer at the internal
//! resolution while nothing that changes the image changes (camera, world, materials, sun,
//! sky, settings); any change restarts it. The display pass divides by the sample count,
//! applies exposure, the ACES fitted curve and sRGB, and upscales bilinearly to the output
//! resolution (exposure is display-only: changing it keeps the samples).
//!
//! In detail:
//! `Progressive`: a device-local accumulation buffer (radiance sum + count per pixel) at the
//! internal resolution; `frame` adds samples (batches shaped by `batch_shape`: never more than
//! asked) and restarts when the image key (every trace parameter + variant) changes or the
//! world changed; `record_batch` is the interactive frame's one dispatch (never past the
//! target); `display` = mean → bilinear upscale to the output resolution → exposure → ACES →
//! sRGB (exposure does not restart); `hdr` reads the mean. The one-shot `PathTracer::render`
//! (as `RenderHow` says) lives here too, so trace.rs does not import the accumulation.

use super::buffer::{Binding, HostBuffer, read_device};
use super::pass::SetCache;
use super::tonemap::ToneMapper;
use super::trace::{
    Band, MAX_SAMPLES_PER_DISPATCH, PathTracer, RayCounts, TraceParams, Variant, Window,
};
use super::world::GpuWorld;
use super::{GpuContext, GpuError};
use crate::cpu::RenderJob;
use crate::image::Image;
use crate::params::SceneParams;
use brickmap::WorldView;
use gpu_allocator::MemoryLocation;
use std::hash::{DefaultHasher, Hash, Hasher};

/// What one frame did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// Samples per pixel accumulated so far (after this frame).
    pub samples: u32,
    /// Whether this frame restarted the accumulation.
    pub restarted: bool,
    /// GPU time of this frame's dispatches (None when the queue cannot time).
    pub gpu_seconds: Option<f64>,
}

/// An accumulating frame at an internal resolution, displayed at an output resolution.
pub struct Progressive {
    accum: HostBuffer,
    uniforms: HostBuffer,
    internal: (u32, u32),
    output: (u32, u32),
    key: Option<u64>,
    samples: u32,
    seed: u64,
    /// Where the internal image lies in the picture (the whole picture but for tiles).
    window: Window,
    /// Some batch was recorded into the buffer (it holds an image to display).
    traced: bool,
    /// Accumulations started after the first, counted while `fresh_restarts` is on: each then
    /// takes fresh scrambles, so a moving camera's frames are independent samples, which
    /// temporal reprojection averages. Off, every restart repeats the job's numbers (the
    /// same samples as a one-shot render of the job: tests compare them).
    epoch: u32,
    fresh_restarts: bool,
}

impl Progressive {
    /// Buffers for an `internal` image displayed at `output`; `seed` picks the random
    /// sequence (each restart continues it with fresh samples).
    pub fn new(
        ctx: &GpuContext,
        internal: (u32, u32),
        output: (u32, u32),
        seed: u64,
    ) -> Result<Self, GpuError> {
        let internal = (internal.0.max(1), internal.1.max(1));
        ctx.limits.check_image("the accumulation", internal, 16)?;
        let pixels = internal.0 as u64 * internal.1 as u64;
        let accum = HostBuffer::new(ctx, "accumulation", pixels * 16, MemoryLocation::GpuOnly)?;
        let uniforms = match HostBuffer::new(
            ctx,
            "trace params",
            std::mem::size_of::<TraceParams>() as u64,
            MemoryLocation::CpuToGpu,
        ) {
            Ok(u) => u,
            Err(e) => {
                accum.destroy(ctx);
                return Err(e);
            }
        };
        Ok(Self {
            accum,
            uniforms,
            internal,
            output: (output.0.max(1), output.1.max(1)),
            key: None,
            samples: 0,
            seed,
            window: Window::whole(internal),
            traced: false,
            epoch: 0,
            fresh_restarts: false,
        })
    }

    /// Makes the internal image the part `window` of a larger picture (a tile); restarts.
    pub fn set_window(&mut self, window: Window) {
        self.window = window;
        self.restart();
    }

    /// Samples per pixel accumulated so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Internal (traced) resolution.
    pub fn internal(&self) -> (u32, u32) {
        self.internal
    }

    /// Output (displayed) resolution.
    pub fn output(&self) -> (u32, u32) {
        self.output
    }

    /// Whether the buffer holds an image (a batch was recorded since it was made; a restart
    /// keeps the old samples until the next batch overwrites them).
    pub fn has_image(&self) -> bool {
        self.traced
    }

    /// Whether restarts take fresh random numbers (see `epoch`).
    pub fn set_fresh_restarts(&mut self, on: bool) {
        self.fresh_restarts = on;
    }

    /// Drops the accumulated samples; the next frame starts over.
    pub fn restart(&mut self) {
        self.key = None;
        self.samples = 0;
    }

    /// One frame of `spp` more samples per pixel with the scene's variant. `world_changed`
    /// (from [`GpuWorld::update`]) or any change of the parameters restarts the accumulation.
    #[allow(clippy::too_many_arguments)]
    pub fn frame(
        &mut self,
        ctx: &GpuContext,
        tracer: &mut PathTracer,
        world: &GpuWorld,
        view: &WorldView<'_>,
        params: &SceneParams,
        world_changed: bool,
        spp: u32,
    ) -> Result<FrameReport, GpuError> {
        if world_changed {
            self.restart();
        }
        let variant = Variant::for_scene(view, params);
        let (gpu_seconds, restarted) =
            self.accumulate(ctx, tracer, world, view, params, variant, spp)?;
        Ok(FrameReport {
            samples: self.samples,
            restarted,
            gpu_seconds,
        })
    }

    /// `spp` samples per pixel at the internal resolution with this accumulation's seed.
    fn job(&self, spp: u32) -> RenderJob {
        RenderJob {
            width: self.internal.0,
            height: self.internal.1,
            spp,
            seed: self.seed,
        }
    }

    /// Adds `spp` samples per pixel with `variant`, restarting first if the image key
    /// changed; returns the GPU time of the dispatches and whether it started over.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn accumulate(
        &mut self,
        ctx: &GpuContext,
        tracer: &mut PathTracer,
        world: &GpuWorld,
        view: &WorldView<'_>,
        params: &SceneParams,
        variant: Variant,
        spp: u32,
    ) -> Result<(Option<f64>, bool), GpuError> {
        self.accumulate_with(
            ctx,
            tracer,
            world,
            view,
            params,
            variant,
            spp,
            |_, _| Ok(()),
        )
    }

    /// [`Progressive::accumulate`], calling `after(accumulation, restarted)` once each
    /// dispatch finished (its batch is in the buffer; `restarted`: it was the first).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn accumulate_with(
        &mut self,
        ctx: &GpuContext,
        tracer: &mut PathTracer,
        world: &GpuWorld,
        view: &WorldView<'_>,
        params: &SceneParams,
        variant: Variant,
        spp: u32,
        mut after: impl FnMut(Binding, bool) -> Result<(), GpuError>,
    ) -> Result<(Option<f64>, bool), GpuError> {
        let base = TraceParams::in_window(view, params, &self.job(spp), self.window);
        self.check_key(&base, variant);
        let restarted = self.samples == 0;
        let mut gpu = Some(0.0);
        let mut done = 0;
        let pixels = self.internal.0 as u64 * self.internal.1 as u64;
        let (per_invocation, slices) = (
            tracer.samples_per_dispatch_for(pixels, variant),
            tracer.sample_slices(pixels),
        );
        while done < spp {
            let (per, split) = batch_shape(spp - done, per_invocation, slices);
            let batch = per * split;
            let p = base.batch(per, self.samples, self.samples > 0);
            let t = tracer.dispatch(
                ctx,
                world,
                variant,
                &p,
                split,
                &mut self.uniforms,
                self.accum.binding(),
                true,
            );
            let first = self.samples == 0;
            let t = t.and_then(|t| after(self.accum.binding(), first).map(|_| t));
            let t = match t {
                Ok(t) => t,
                Err(e) => {
                    // The buffer may hold a partial batch: start over next frame.
                    self.restart();
                    return Err(e);
                }
            };
            gpu = gpu.zip(t).map(|(a, b)| a + b);
            self.samples += batch;
            done += batch;
        }
        Ok((gpu, restarted))
    }

    /// Starts over when the image key (every trace parameter and the variant) changed.
    fn check_key(&mut self, base: &TraceParams, variant: Variant) {
        let mut hasher = DefaultHasher::new();
        base.image_key().hash(&mut hasher);
        variant.hash(&mut hasher);
        let key = hasher.finish();
        if self.key != Some(key) {
            self.samples = 0;
            self.key = Some(key);
        }
    }

    /// The interactive frame's trace: records one dispatch of up to `spp` samples per pixel,
    /// never past `target` in all
    /// (fewer when the tracer's batch shape says so) into `cmd` with the frame slot's
    /// parameter buffer and sets, without submitting; restarts on a changed key. Returns
    /// (samples added, whether it restarted). `base` is [`TraceParams::new`] for this
    /// accumulation's size, computed by the caller under a short world read lock. With a
    /// `band` of several, only its rows are traced and the samples count once the last band
    /// is recorded (the caller keeps `spp` for the whole pass).
    #[allow(clippy::too_many_arguments)]
    pub fn record_batch(
        &mut self,
        ctx: &GpuContext,
        cmd: ash::vk::CommandBuffer,
        tracer: &mut PathTracer,
        world: &GpuWorld,
        base: TraceParams,
        variant: Variant,
        (spp, target): (u32, u32),
        uniforms: &mut HostBuffer,
        sets: &mut SetCache,
        band: Band,
    ) -> Result<(u32, bool), GpuError> {
        self.check_key(&base, variant);
        let restarted = self.samples == 0;
        let spp = spp.min(target.saturating_sub(self.samples));
        if spp == 0 {
            return Ok((0, restarted));
        }
        let pixels = self.internal.0 as u64 * self.internal.1 as u64;
        let (per, split) = batch_shape(
            spp,
            tracer.samples_per_dispatch_for(pixels, variant),
            tracer.sample_slices(pixels),
        );
        if restarted && self.traced && self.fresh_restarts && band.index == 0 {
            self.epoch = self.epoch.wrapping_add(1);
        }
        let epoch = if self.fresh_restarts { self.epoch } else { 0 };
        let p = base
            .batch(per, self.samples, self.samples > 0)
            .reseeded(epoch);
        self.traced = true;
        tracer.record(
            ctx,
            cmd,
            world,
            variant,
            &p,
            split,
            uniforms,
            self.accum.binding(),
            sets,
            band,
        )?;
        // A pass in bands has added its samples once its last band is recorded.
        if !band.is_last() {
            return Ok((0, restarted));
        }
        self.samples += per * split;
        Ok((per * split, restarted))
    }

    /// The accumulation buffer (radiance sum and count per pixel).
    pub fn accumulation(&self) -> Binding {
        self.accum.binding()
    }

    /// The job this accumulation traces, `spp` samples per pixel.
    pub fn job_of(&self, spp: u32) -> RenderJob {
        self.job(spp)
    }

    /// Benchmarks: GPU times of `count` back-to-back dispatches of the same first batch of
    /// `spp` (≤ [`MAX_SAMPLES_PER_DISPATCH`]) samples per pixel with `variant`, in one
    /// submission; the samples are split among as many invocations per pixel as the tracer's
    /// [`PathTracer::sample_slices`] allows and divides `spp`.
    /// Leaves the accumulation restarted.
    #[allow(clippy::too_many_arguments)]
    pub fn time_repeated(
        &mut self,
        ctx: &GpuContext,
        tracer: &mut PathTracer,
        world: &GpuWorld,
        view: &WorldView<'_>,
        params: &SceneParams,
        variant: Variant,
        spp: u32,
        count: u32,
    ) -> Result<Vec<f64>, GpuError> {
        let spp = spp.clamp(1, MAX_SAMPLES_PER_DISPATCH);
        let pixels = self.internal.0 as u64 * self.internal.1 as u64;
        let slices = (1..=tracer.sample_slices(pixels).min(spp))
            .rev()
            .find(|s| spp.is_multiple_of(*s))
            .unwrap_or(1);
        let p = TraceParams::new(view, params, &self.job(spp)).batch(spp / slices, 0, false);
        let times = tracer.dispatch_repeated(
            ctx,
            world,
            variant,
            &p,
            slices,
            &mut self.uniforms,
            self.accum.binding(),
            count,
            true,
        );
        self.restart();
        times
    }

    /// The mean radiance so far, at the internal resolution.
    pub fn hdr(&self, ctx: &GpuContext) -> Result<Image, GpuError> {
        let raw = read_device(ctx, self.accum.binding())?;
        let px: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        Ok(Image {
            width: self.internal.0,
            height: self.internal.1,
            pixels: px
                .iter()
                .map(|p| {
                    let n = if p[3] > 0.0 { p[3] } else { 1.0 };
                    [p[0] / n, p[1] / n, p[2] / n]
                })
                .collect(),
        })
    }

    /// The displayed frame: mean → exposure → ACES fitted → sRGB, upscaled bilinearly (in
    /// linear HDR, before the curve) to the output resolution; rows top to bottom.
    pub fn display(
        &self,
        ctx: &GpuContext,
        tone: &ToneMapper,
        exposure: f32,
    ) -> Result<Vec<[u8; 3]>, GpuError> {
        tone.display(
            ctx,
            self.accum.binding(),
            self.internal,
            self.output,
            exposure,
        )
    }

    /// Frees the buffers.
    pub fn destroy(self, ctx: &GpuContext) {
        self.accum.destroy(ctx);
        self.uniforms.destroy(ctx);
    }
}

/// How a one-shot render runs: the scene's pipeline variant or a chosen one (benchmarks
/// compare variants; a variant lacking something the scene has renders it wrongly), and
/// whether rays are counted by kind (the same image, plus one atomic add per pixel and
/// dispatch).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderHow {
    /// The variant (None: `Variant::for_scene`).
    pub variant: Option<Variant>,
    /// Count the rays traced, by kind.
    pub count_rays: bool,
}

impl RenderHow {
    /// The scene's variant, no counting.
    pub const SCENE: RenderHow = RenderHow {
        variant: None,
        count_rays: false,
    };

    /// A chosen variant, no counting.
    pub fn variant(v: Variant) -> Self {
        Self {
            variant: Some(v),
            count_rays: false,
        }
    }

    /// The same, counting rays.
    pub fn counted(self) -> Self {
        Self {
            count_rays: true,
            ..self
        }
    }
}

/// What a one-shot render gives back.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The linear image.
    pub image: Image,
    /// GPU time spent, seconds (timestamp queries summed over the dispatches; None when
    /// the queue cannot time).
    pub gpu_seconds: Option<f64>,
    /// Rays traced by kind, when counted.
    pub rays: Option<RayCounts>,
}

/// One-shot renders (CLI, scripts, tests): an accumulation of the image's size, filled and
/// read back. Here rather than in trace.rs so the tracer does not depend on the accumulation.
impl PathTracer {
    /// Renders `job.spp` samples per pixel as `how` says and waits. Samples accumulate on the
    /// GPU in batches of [`PathTracer::samples_per_dispatch`], at most
    /// [`MAX_SAMPLES_PER_DISPATCH`]: long-running invocations lose samples on lavapipe
    /// (measured: 256 samples per invocation came out 9% dark there, exact on the H100), and
    /// short dispatches are what a viewport does anyway.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        world: &GpuWorld,
        view: &WorldView<'_>,
        params: &SceneParams,
        job: &RenderJob,
        how: RenderHow,
    ) -> Result<Rendered, GpuError> {
        let variant = Variant {
            count_rays: how.count_rays,
            ..how
                .variant
                .unwrap_or_else(|| Variant::for_scene(view, params))
        };
        if how.count_rays {
            self.reset_counters();
        }
        let size = (job.width, job.height);
        let mut acc = Progressive::new(ctx, size, size, job.seed)?;
        let result = acc
            .accumulate(ctx, self, world, view, params, variant, job.spp)
            .and_then(|(gpu, _)| acc.hdr(ctx).map(|img| (img, gpu)));
        acc.destroy(ctx);
        let (image, gpu_seconds) = result?;
        Ok(Rendered {
            image,
            gpu_seconds,
            rays: how.count_rays.then(|| self.read_counters()),
        })
    }
}

/// The next dispatch of `left` samples per pixel: (samples per invocation, invocations per
/// pixel), at most `per` × `slices` and never more than `left` in all.
fn batch_shape(left: u32, per: u32, slices: u32) -> (u32, u32) {
    let split = slices.clamp(1, left.max(1));
    let per = per.clamp(1, (left / split).max(1));
    (per, split)
}

#[cfg(test)]
mod tests {
    use super::batch_shape;

    #[test]
    fn batches_cover_the_samples_exactly_within_the_limits() {
        for per in 1..=16 {
            for slices in 1..=8 {
                for spp in 1..=200 {
                    let (mut left, mut dispatches) = (spp, 0);
                    while left > 0 {
                        let (p, s) = batch_shape(left, per, slices);
                        assert!(p >= 1 && p <= per && s >= 1 && s <= slices);
                        assert!(p * s <= left, "{spp} spp: {p} x {s} of {left}");
                        left -= p * s;
                        dispatches += 1;
                    }
                    // Never more than one short dispatch per shrinking of the split.
                    assert!(
                        dispatches <= spp.div_ceil(per * slices) + slices,
                        "{spp} {per} {slices}: {dispatches}"
                    );
                }
            }
        }
        assert_eq!(batch_shape(64, 4, 4), (4, 4));
        assert_eq!(batch_shape(7, 2, 4), (1, 4));
        assert_eq!(batch_shape(3, 2, 4), (1, 3));
    }
}
