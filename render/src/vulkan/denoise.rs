//! The viewport's edge-aware denoiser: guides from the first surface each pixel's centre ray
//! meets past mirrors and glass (`shaders/guides.comp`: hit point, footprint, albedo, material
//! kind and face), then an à-trous wavelet filter with a variance-guided luminance weight on
//! the accumulation's mean divided by the albedo (`shaders/denoise.comp`). Its luminance
//! weight is measured in standard deviations of each pixel's mean, estimated from the
//! accumulation's batches (one per frame, `record_batch` after each); its last step gives way
//! to the raw mean between 8 and 64 spp, where its bias would outweigh the noise it removes
//! (measured by `voxbrick bench-error`, choice "denoised"). Never used by reference renders.

use super::barrier::between_passes;
use super::buffer::{Binding, HostBuffer};
use super::pass::{ComputePass, Dispatch, SetCache};
use super::world::GpuWorld;
use super::{GpuContext, GpuError};
use ash::vk;
use gpu_allocator::MemoryLocation;

const GUIDES: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/guides.comp.spv"));
const FILTER: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/denoise.comp.spv"));

/// À-trous steps (1, 2, 4, 8, 16 pixels apart: a 125-pixel-wide kernel at most).
pub const ITERATIONS: u32 = 5;
// Prepare writes ping and the steps alternate, so an odd count ends in pong.
const _: () = assert!(ITERATIONS % 2 == 1);

/// Push constants. Keep in sync with `Push` in shaders/denoise.comp.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    size: [u32; 2],
    mode: u32,
    step: u32,
    flags: u32,
    fade: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<Push>() == 28);

/// The sample counts between which the filtered image gives way to the raw mean (linear in
/// log₂ of the count): the filter's bias outweighs the noise it removes beyond them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fade {
    /// Samples where the raw mean starts to show.
    pub from: f32,
    /// Samples from which only the raw mean shows.
    pub to: f32,
}

impl Fade {
    /// The filter at every sample count (benchmarks: its bias measured).
    pub const NEVER: Fade = Fade { from: 0.0, to: 0.0 };

    /// The fade for a picture of `size` pixels: 8 to 64 samples up to 512 × 288 pixels; beyond,
    /// its end scales with the picture's linear size k and its start with √k. The filter's
    /// reach is fixed in pixels, so a larger picture's filter averages over less of the scene
    /// and its bias stays below the noise longer: measured on the H100 (BENCHMARKS.md "The
    /// denoiser's fade and the picture size"), the filter alone stops paying at about 34, 66
    /// and 115 spp at 512 × 288, 1024 × 576 and 1920 × 1080, in proportion to the height. A
    /// start scaled with k too came too late (at 1024 × 576, 16 spp: 2.60× less error than
    /// the raw mean against 3.02× with the start at 8√k; 32 and 64 spp within 6 %).
    pub fn for_picture(size: (u32, u32)) -> Fade {
        let pixels = size.0 as f32 * size.1 as f32;
        let k = (pixels / (512.0 * 288.0)).sqrt().max(1.0);
        Fade {
            from: 8.0 * k.sqrt(),
            to: 64.0 * k,
        }
    }

    /// This fade, moved earlier (its shape kept) so that it ends by `samples` when that is
    /// more than 64: a viewport that stops at `samples` shows the unbiased mean there.
    pub fn ending_by(self, samples: u32) -> Fade {
        let end = (samples as f32).max(64.0);
        if self.to <= end {
            return self;
        }
        Fade {
            from: self.from * end / self.to,
            to: end,
        }
    }
}

const MOMENTS: u32 = 0;
const PREPARE: u32 = 1;
const FILTER_STEP: u32 = 2;
const RESTART: u32 = 1;
const LAST: u32 = 2;

/// The buffers of one image size.
struct Buffers {
    size: (u32, u32),
    /// Two vec4 per pixel (shaders/guides.comp).
    guides: HostBuffer,
    /// One vec4 per pixel: the first surface (shaders/guides.comp `primary`).
    primary: HostBuffer,
    /// Per pixel: previous luminance sum and count, Σ S²/k, batches.
    moments: HostBuffer,
    ping: HostBuffer,
    /// The last step's output: remodulated radiance, count 1 (what the display reads).
    pong: HostBuffer,
}

impl Buffers {
    fn new(ctx: &GpuContext, size: (u32, u32)) -> Result<Self, GpuError> {
        ctx.limits.check_image("the denoiser's guides", size, 32)?;
        let pixels = size.0 as u64 * size.1 as u64;
        let make = |name, bytes| HostBuffer::new(ctx, name, bytes, MemoryLocation::GpuOnly);
        let guides = make("denoise guides", pixels * 32)?;
        let primary = match make("denoise first surfaces", pixels * 16) {
            Ok(b) => b,
            Err(e) => {
                guides.destroy(ctx);
                return Err(e);
            }
        };
        let rest = (|| {
            let moments = make("denoise moments", pixels * 16)?;
            let ping = match make("denoise ping", pixels * 16) {
                Ok(b) => b,
                Err(e) => {
                    moments.destroy(ctx);
                    return Err(e);
                }
            };
            match make("denoise pong", pixels * 16) {
                Ok(pong) => Ok((moments, ping, pong)),
                Err(e) => {
                    moments.destroy(ctx);
                    ping.destroy(ctx);
                    Err(e)
                }
            }
        })();
        match rest {
            Ok((moments, ping, pong)) => Ok(Self {
                size,
                guides,
                primary,
                moments,
                ping,
                pong,
            }),
            Err(e) => {
                guides.destroy(ctx);
                primary.destroy(ctx);
                Err(e)
            }
        }
    }

    fn destroy(self, ctx: &GpuContext) {
        for b in [
            self.guides,
            self.primary,
            self.moments,
            self.ping,
            self.pong,
        ] {
            b.destroy(ctx);
        }
    }
}

/// The descriptor sets of one filter: (accum, guides, moments, pong → ping) and
/// (…, ping → pong).
#[derive(Clone, Copy, Debug)]
pub struct FilterSets {
    to_ping: vk::DescriptorSet,
    to_pong: vk::DescriptorSet,
}

/// The denoiser's pipelines and the buffers of the size it last ran at.
pub struct Denoiser {
    guides: ComputePass,
    filter: ComputePass,
    buffers: Option<Buffers>,
    /// The guides and moments describe the current accumulation.
    current: bool,
    /// The output holds the filter of the accumulation's latest batch.
    filtered: bool,
    /// The next filter reads a moving camera's temporal history (no fade to the raw mean).
    temporal_input: bool,
    /// The fade to the raw mean of the next filters.
    fade: Fade,
}

impl Denoiser {
    /// Builds the pipelines (buffers come with the first size).
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let guides = ComputePass::new(ctx, GUIDES, 8, 0)?;
        let filter = match ComputePass::new(ctx, FILTER, 5, std::mem::size_of::<Push>() as u32) {
            Ok(f) => f,
            Err(e) => {
                guides.destroy(ctx);
                return Err(e);
            }
        };
        Ok(Self {
            guides,
            filter,
            buffers: None,
            current: false,
            filtered: false,
            temporal_input: false,
            fade: Fade::for_picture((0, 0)),
        })
    }

    /// The fade to the raw mean of the next filters.
    pub fn set_fade(&mut self, fade: Fade) {
        self.fade = fade;
    }

    /// Forgets the guides and moments: the next [`Denoiser::record_batch`] starts them over
    /// (a restarted accumulation, a new one, or the denoiser switched back on).
    pub fn invalidate(&mut self) {
        self.current = false;
        self.filtered = false;
    }

    /// Buffers for `size` (the caller made sure no submission still uses the old ones).
    fn ensure(&mut self, ctx: &GpuContext, size: (u32, u32)) -> Result<&Buffers, GpuError> {
        if self.buffers.as_ref().is_none_or(|b| b.size != size) {
            if let Some(old) = self.buffers.take() {
                old.destroy(ctx);
            }
            self.buffers = Some(Buffers::new(ctx, size)?);
            self.invalidate();
        }
        Ok(self.buffers.as_ref().expect("made above"))
    }

    /// Whether buffers of `size` exist (a new size waits for the GPU first).
    pub fn has_size(&self, size: (u32, u32)) -> bool {
        self.buffers.as_ref().is_some_and(|b| b.size == size)
    }

    /// Records what follows a batch of samples added to `accum` (size `size`): new guides
    /// (from `params`, the batch's [`super::trace::TraceParams`]) when the accumulation
    /// restarted or they are not current, then the batch's moments. `restarted`: this batch
    /// started the accumulation. Orders its writes before later compute passes.
    #[allow(clippy::too_many_arguments)]
    pub fn record_batch(
        &mut self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        sets: &mut SetCache,
        world: &GpuWorld,
        params: Binding,
        accum: Binding,
        size: (u32, u32),
        restarted: bool,
    ) -> Result<(), GpuError> {
        let fresh = restarted || !self.current || !self.has_size(size);
        self.ensure(ctx, size)?;
        let b = self.buffers.as_ref().expect("ensured");
        if fresh {
            let mut bound = world.bindings();
            bound.extend([params, b.guides.binding(), b.primary.binding()]);
            let set = sets.get(ctx, &self.guides, &bound)?;
            self.guides.record(
                ctx,
                cmd,
                set,
                &[],
                Dispatch::Groups(size.0.div_ceil(8), size.1.div_ceil(8), 1),
            );
            // SAFETY: recording.
            unsafe { between_passes(ctx, cmd) };
        }
        let set = self.filter_set(ctx, sets, accum, false)?;
        let push = Push {
            size: [size.0, size.1],
            mode: MOMENTS,
            step: 0,
            flags: if fresh { RESTART } else { 0 },
            fade: [self.fade.from, self.fade.to],
        };
        self.record_filter_pass(ctx, cmd, set, push);
        // SAFETY: recording.
        unsafe { between_passes(ctx, cmd) };
        self.current = true;
        self.filtered = false;
        Ok(())
    }

    /// The guides and the moments of the current size, if buffers exist (temporal
    /// reprojection reads the first and writes the second).
    pub fn guides_and_moments(&self) -> Option<(Binding, Binding)> {
        self.buffers
            .as_ref()
            .map(|b| (b.guides.binding(), b.moments.binding()))
    }

    /// The first surfaces of the current size (one vec4 per pixel: point, 8 · kind + face or
    /// −1), if buffers exist.
    pub fn first_surfaces(&self) -> Option<Binding> {
        self.buffers.as_ref().map(|b| b.primary.binding())
    }

    /// Whether the next filter's source is a moving camera's temporal history (its counts are
    /// frames blended, not unbiased samples: the last step then does not fade to it).
    pub fn set_temporal_input(&mut self, on: bool) {
        self.temporal_input = on;
    }

    /// The last filter's output (radiance, count 1 per pixel), if buffers exist.
    pub fn output(&self) -> Option<Binding> {
        self.buffers.as_ref().map(|b| b.pong.binding())
    }

    /// Whether the guides and moments describe the accumulation the last batch went to.
    pub fn is_current(&self) -> bool {
        self.current
    }

    /// The output, when it holds the filter of the current accumulation's latest batch (what a
    /// frame that adds no samples displays again).
    pub fn filtered_output(&self) -> Option<Binding> {
        if self.current && self.filtered {
            self.output()
        } else {
            None
        }
    }

    /// Records the filter of `accum` (its guides and moments recorded by
    /// [`Denoiser::record_batch`]); returns the denoised image (radiance, count 1 per pixel)
    /// for the display pass, its writes ordered before later compute passes.
    pub fn record_filter(
        &mut self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        sets: &mut SetCache,
        accum: Binding,
    ) -> Result<Binding, GpuError> {
        let filter_sets = self.filter_sets(ctx, sets, accum)?;
        let out = self.record_filter_sets(ctx, cmd, filter_sets);
        self.filtered = true;
        Ok(out)
    }

    /// The two sets [`Denoiser::record_filter_sets`] binds (fetched first by callers that
    /// record the filter in a closure).
    pub fn filter_sets(
        &self,
        ctx: &GpuContext,
        sets: &mut SetCache,
        accum: Binding,
    ) -> Result<FilterSets, GpuError> {
        Ok(FilterSets {
            to_ping: self.filter_set(ctx, sets, accum, false)?,
            to_pong: self.filter_set(ctx, sets, accum, true)?,
        })
    }

    /// [`Denoiser::record_filter`] with its sets fetched.
    pub fn record_filter_sets(
        &self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        sets: FilterSets,
    ) -> Binding {
        let b = self.buffers.as_ref().expect("recorded after a batch");
        // A moving camera's history counts frames blended, not unbiased samples: no fade.
        let fade = if self.temporal_input {
            Fade::NEVER
        } else {
            self.fade
        };
        let push = |mode, step, flags| Push {
            size: [b.size.0, b.size.1],
            mode,
            step,
            flags,
            fade: [fade.from, fade.to],
        };
        // Prepare writes ping; the steps alternate ping → pong → ping …, ending in pong.
        self.record_filter_pass(ctx, cmd, sets.to_ping, push(PREPARE, 0, 0));
        for step in 0..ITERATIONS {
            // SAFETY: recording.
            unsafe { between_passes(ctx, cmd) };
            let last = step + 1 == ITERATIONS;
            let set = if step % 2 == 0 {
                sets.to_pong
            } else {
                sets.to_ping
            };
            self.record_filter_pass(
                ctx,
                cmd,
                set,
                push(FILTER_STEP, step, if last { LAST } else { 0 }),
            );
        }
        // SAFETY: recording.
        unsafe { between_passes(ctx, cmd) };
        b.pong.binding()
    }

    /// The set binding (accum, guides, moments, src, dst): dst = pong when `to_pong`, else ping.
    fn filter_set(
        &self,
        ctx: &GpuContext,
        sets: &mut SetCache,
        accum: Binding,
        to_pong: bool,
    ) -> Result<vk::DescriptorSet, GpuError> {
        let b = self.buffers.as_ref().expect("ensured by record_batch");
        let (src, dst) = if to_pong {
            (b.ping.binding(), b.pong.binding())
        } else {
            (b.pong.binding(), b.ping.binding())
        };
        sets.get(
            ctx,
            &self.filter,
            &[accum, b.guides.binding(), b.moments.binding(), src, dst],
        )
    }

    fn record_filter_pass(
        &self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        push: Push,
    ) {
        self.filter.record(
            ctx,
            cmd,
            set,
            bytemuck::bytes_of(&push),
            Dispatch::Groups(push.size[0].div_ceil(8), push.size[1].div_ceil(8), 1),
        );
    }

    /// Destroys the pipelines and buffers (the device is idle).
    pub fn destroy(self, ctx: &GpuContext) {
        if let Some(b) = self.buffers {
            b.destroy(ctx);
        }
        self.guides.destroy(ctx);
        self.filter.destroy(ctx);
    }
}

#[cfg(test)]
mod tests {
    use super::Fade;

    #[test]
    fn larger_pictures_end_their_fade_in_proportion_to_their_linear_size() {
        let small = Fade::for_picture((512, 288));
        assert_eq!((small.from, small.to), (8.0, 64.0));
        assert_eq!(Fade::for_picture((64, 36)), small);
        assert_eq!(Fade::for_picture((0, 0)), small);
        for (w, h) in [(1024, 576), (1920, 1080), (3840, 2160)] {
            let f = Fade::for_picture((w, h));
            let k = h as f32 / 288.0;
            assert!(
                (f.from / small.from - k.sqrt()).abs() < 1e-3 * k,
                "{w}x{h}: {f:?}"
            );
            assert!((f.to / small.to - k).abs() < 1e-3 * k, "{w}x{h}: {f:?}");
            // A viewport converging at 256 spp shows the unbiased mean there, the fade's
            // shape (the ratio of its ends) kept.
            let v = f.ending_by(256);
            assert!(
                v.to <= 256.0 && (v.to / v.from - f.to / f.from).abs() < 1e-3,
                "{v:?}"
            );
            assert_eq!(f.ending_by(100_000), f);
        }
        assert_eq!(small.ending_by(16), small);
    }
}
