//! The GPU session: one long-lived owner of the world's GPU mirror, the path tracer, the
//! accumulation and the display pass, used by every caller — the CLI's `render` and
//! `bench-gpu`, replay scripts and the editor's frame loop. Drop releases everything.
//!
//! Headless callers use [`Viewport::render`] and friends (they wait for the GPU). The
//! interactive loop uses frames in flight: [`Viewport::begin_frame`] takes the next slot only
//! if its previous submission finished (it never blocks), [`Viewport::trace_frame`] uploads
//! what the world changed and records one batch of samples plus the display pass,
//! [`Viewport::submit_frame`] submits. World locks are held only while dirty ranges are copied
//! and the frame's parameters are read, never across GPU work.

use crate::cpu::RenderJob;
use crate::image::Image;
use crate::params::SceneParams;
use crate::vulkan::barrier::{Scope, after_earlier_passes, barrier, between_passes};
use crate::vulkan::buffer::{Binding, HostBuffer, read_device};
use crate::vulkan::denoise::{Denoiser, Fade};
use crate::vulkan::frame::{FRAMES_IN_FLIGHT, FrameSlot};
use crate::vulkan::pass::{SetCache, run_batch};
use crate::vulkan::primary::{GpuHit, PrimaryTracer};
use crate::vulkan::progressive::Progressive;
pub use crate::vulkan::progressive::{RenderHow, Rendered};
use crate::vulkan::temporal::Temporal;
use crate::vulkan::tonemap::ToneMapper;
use crate::vulkan::trace::{Band, Dim, PathTracer, TraceParams, Variant, Window};
use crate::vulkan::world::{GpuWorld, UploadReport};
use crate::vulkan::{GpuContext, GpuError};
use ash::vk;
use brickmap::{World, WorldView};
use std::mem::ManuallyDrop;
use std::sync::Arc;

mod denoised;
mod paced;
pub use denoised::DenoisedRender;
pub use paced::{Paced, SLOW_JOB, ShownImage, TracedImage};

/// The most bytes per traced pixel one buffer of a frame holds (the denoiser's guides; the
/// accumulation holds 16): the internal size is fitted so that it stays within the device's
/// limits ([`Viewport::fit_internal`]).
pub const IMAGE_BYTES_PER_PIXEL: u64 = 32;

/// What the interactive loop asks of one frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameRequest<'a> {
    /// The scene's camera, sun, sky and settings.
    pub params: &'a SceneParams,
    /// The traced (internal) resolution.
    pub internal: (u32, u32),
    /// The displayed resolution.
    pub output: (u32, u32),
    /// Samples per pixel to add at most this frame (0: display only).
    pub spp: u32,
    /// Stop adding samples at this many per pixel (the image is converged).
    pub target_spp: u32,
    /// Display exposure in stops.
    pub exposure: f32,
    /// Write the output in B, G, R, A byte order (for a B8G8R8A8 target).
    pub bgra: bool,
    /// Display the denoised accumulation ([`crate::vulkan::denoise`]; a view setting, never
    /// in reference renders).
    pub denoise: bool,
    /// With `denoise`: while the camera moves, reuse the previous frames' radiance where they
    /// saw the same surfaces (temporal reprojection, `vulkan::temporal`).
    pub reproject: bool,
    /// Camera hits outside this box weighted by its factor (a view setting: the editor's
    /// dimming of the objects it is not editing).
    pub dim: Option<Dim>,
    /// A ground grid on the plane y = 0 with lines this many voxels apart (a view setting).
    pub grid: Option<f32>,
}

/// What one interactive frame did.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameStatus {
    /// Samples per pixel accumulated after this frame.
    pub samples: u32,
    /// Samples per pixel this frame added.
    pub added: u32,
    /// Whether this frame restarted the accumulation.
    pub restarted: bool,
    /// What the world upload did.
    pub upload: UploadReport,
}

/// A frame being recorded: the slot's command buffer.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    slot: usize,
    /// The command buffer (recording).
    pub cmd: vk::CommandBuffer,
    /// The slot's swapchain-acquire semaphore.
    pub acquired: vk::Semaphore,
}

/// The GPU session. Fields are released in `Drop`, the context last.
pub struct Viewport {
    world: ManuallyDrop<GpuWorld>,
    tracer: ManuallyDrop<PathTracer>,
    tone: ManuallyDrop<ToneMapper>,
    /// First-hit traversal of given rays (made on first use: `voxbrick stress`).
    primary: Option<PrimaryTracer>,
    /// Interactive accumulation (created at the requested internal size).
    live: Option<Progressive>,
    /// One-shot accumulation kept by benchmarks between calls.
    bench: Option<Progressive>,
    frames: Vec<FrameSlot>,
    next: usize,
    last_gpu_seconds: Option<f64>,
    /// Frames in a row that showed the previous image while an upload was incomplete.
    held: u32,
    /// The edge-aware denoiser (made when first asked for).
    denoiser: Option<Denoiser>,
    /// The denoiser's fade to the raw mean when not the picture size's (benchmarks).
    fade: Option<Fade>,
    /// Its temporal reprojection while the camera moves (made with it).
    temporal: Option<Temporal>,
    /// The last frame's `TraceParams::scene_key` and variant: when a restart keeps it, only
    /// the camera moved (the temporal history stays valid).
    scene_key: Option<u64>,
    /// What the last denoised frame's filter read when it was not the accumulation (the
    /// temporal history or handover).
    filter_input: Option<Binding>,
    /// The interactive loop's jobs and the images they leave ([`Viewport::trace_paced`]).
    pacing: paced::Pacing,
    ctx: Arc<GpuContext>,
}

/// The most frames in a row an incomplete upload holds the previous image (an edit larger
/// than that many staging slots then shows in parts, rather than the view freezing while a
/// long stroke keeps adding to the upload).
pub const MAX_HELD_FRAMES: u32 = 8;

impl Frame {
    /// The frame slot (0..[`FRAMES_IN_FLIGHT`]).
    pub fn slot(&self) -> usize {
        self.slot
    }
}

impl Viewport {
    /// Uploads the world and builds the tracer and the display pass.
    pub fn new(ctx: Arc<GpuContext>, view: &WorldView<'_>) -> Result<Self, GpuError> {
        Self::with_staging(
            ctx,
            view,
            crate::vulkan::world::RING_SLOTS,
            crate::vulkan::world::RING_SLOT_BYTES,
        )
    }

    /// [`Viewport::new`] with `slots` staging buffers of `slot_bytes` (what one frame
    /// uploads at most; tests make edits span frames with a small one).
    pub fn with_staging(
        ctx: Arc<GpuContext>,
        view: &WorldView<'_>,
        slots: usize,
        slot_bytes: u64,
    ) -> Result<Self, GpuError> {
        let world = GpuWorld::with_ring(&ctx, view, slots, slot_bytes)?;
        let tracer = match PathTracer::new(&ctx) {
            Ok(t) => t,
            Err(e) => {
                world.destroy(&ctx);
                return Err(e);
            }
        };
        let tone = match ToneMapper::new(&ctx) {
            Ok(t) => t,
            Err(e) => {
                tracer.destroy(&ctx);
                world.destroy(&ctx);
                return Err(e);
            }
        };
        Ok(Self {
            world: ManuallyDrop::new(world),
            tracer: ManuallyDrop::new(tracer),
            tone: ManuallyDrop::new(tone),
            primary: None,
            live: None,
            bench: None,
            frames: Vec::new(),
            next: 0,
            last_gpu_seconds: None,
            held: 0,
            denoiser: None,
            fade: None,
            temporal: None,
            scene_key: None,
            filter_input: None,
            pacing: Default::default(),
            ctx,
        })
    }

    /// The context.
    pub fn ctx(&self) -> &Arc<GpuContext> {
        &self.ctx
    }

    /// The path tracer (its sampling options).
    pub fn tracer(&mut self) -> &mut PathTracer {
        &mut self.tracer
    }

    /// The context, the tracer and the uploaded world, for one-shot renders elsewhere in
    /// the crate (`finished.rs`).
    pub(crate) fn parts(&mut self) -> (&Arc<GpuContext>, &mut PathTracer, &GpuWorld) {
        (&self.ctx, &mut self.tracer, &self.world)
    }

    /// Renders `job` as `how` says on this session's world and waits
    /// ([`PathTracer::render`]).
    pub fn render(
        &mut self,
        view: &WorldView<'_>,
        params: &SceneParams,
        job: &RenderJob,
        how: RenderHow,
    ) -> Result<Rendered, GpuError> {
        self.tracer
            .render(&self.ctx, &self.world, view, params, job, how)
    }

    /// Benchmarks: GPU times of `count` back-to-back dispatches of `spp` samples per pixel
    /// at `size` with `variant` ([`Progressive::time_repeated`]).
    pub fn time_repeated(
        &mut self,
        view: &WorldView<'_>,
        params: &SceneParams,
        variant: Variant,
        size: (u32, u32),
        spp: u32,
        count: u32,
    ) -> Result<Vec<f64>, GpuError> {
        if self.bench.as_ref().is_none_or(|b| b.internal() != size) {
            if let Some(old) = self.bench.take() {
                old.destroy(&self.ctx);
            }
            self.bench = Some(Progressive::new(&self.ctx, size, size, 1)?);
        }
        let acc = self.bench.as_mut().expect("made above");
        acc.time_repeated(
            &self.ctx,
            &mut self.tracer,
            &self.world,
            view,
            params,
            variant,
            spp,
            count,
        )
    }

    /// The first solid voxel along each ray (origin, direction) in air, or with `medium` the
    /// first voxel that is not that dielectric, by the tracer's own traversal
    /// (`shaders/brickmap.glsl` through `shaders/primary.comp`), and the iteration caps the
    /// traversals hit. The world is the GPU's copy: as uploaded when the session was made and by
    /// each `trace_frame` since.
    pub fn first_hits(
        &mut self,
        rays: &[(glam::Vec3, glam::Vec3)],
        medium: Option<u8>,
    ) -> Result<(Vec<Option<GpuHit>>, u64), GpuError> {
        if self.primary.is_none() {
            self.primary = Some(PrimaryTracer::new(&self.ctx)?);
        }
        let primary = self.primary.as_ref().expect("made above");
        let (mut hits, mut capped) = (Vec::with_capacity(rays.len()), 0);
        // One dispatch covers at most 65 535 workgroups of 64 rays.
        for chunk in rays.chunks(1 << 20) {
            let (h, c) = primary.trace_counted(&self.ctx, &self.world, chunk, medium)?;
            hits.extend(h);
            capped += c;
        }
        Ok((hits, capped))
    }

    /// The driver's statistics of a variant's pipelines.
    pub fn statistics(&mut self, variant: Variant) -> Vec<(String, String)> {
        self.tracer
            .statistics(&self.ctx, variant)
            .unwrap_or_default()
    }

    /// Samples per pixel the interactive accumulation holds.
    pub fn samples(&self) -> u32 {
        self.live.as_ref().map_or(0, |l| l.samples())
    }

    /// GPU time of the last interactive frame that finished (timestamp queries); of a
    /// sample pass traced in bands ([`Viewport::trace_paced`]), the sum of its bands.
    pub fn last_gpu_seconds(&self) -> Option<f64> {
        self.last_gpu_seconds
    }

    /// The linear mean of the interactive accumulation (waits for the GPU; tests).
    pub fn live_hdr(&mut self) -> Result<Option<Image>, GpuError> {
        self.wait_idle()?;
        self.live.as_ref().map(|l| l.hdr(&self.ctx)).transpose()
    }

    /// The denoised image the last frame displayed (linear, internal size), or None when it
    /// displayed the raw accumulation (waits for the GPU; tests).
    pub fn live_denoised(&mut self) -> Result<Option<Image>, GpuError> {
        self.wait_idle()?;
        let (Some(live), Some(d)) = (&self.live, &self.denoiser) else {
            return Ok(None);
        };
        d.filtered_output()
            .map(|out| read_image(&self.ctx, out, live.internal()))
            .transpose()
    }

    /// What the last denoised frame filtered when it was the temporal history (or the
    /// handover after a stop) rather than the accumulation: its mean (waits; tests and
    /// benchmarks).
    pub fn live_filter_input(&mut self) -> Result<Option<Image>, GpuError> {
        self.wait_idle()?;
        let (Some(live), Some(input)) = (&self.live, self.filter_input) else {
            return Ok(None);
        };
        let raw = read_device(&self.ctx, input)?;
        let px: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        let (w, h) = live.internal();
        Ok(Some(Image {
            width: w,
            height: h,
            pixels: px
                .iter()
                .take(w as usize * h as usize)
                .map(|p| {
                    let n = if p[3] > 0.0 { p[3] } else { 1.0 };
                    [p[0] / n, p[1] / n, p[2] / n]
                })
                .collect(),
        }))
    }

    /// The next frame slot, if its previous submission finished; never blocks.
    pub fn begin_frame(&mut self) -> Result<Option<Frame>, GpuError> {
        while self.frames.len() < FRAMES_IN_FLIGHT {
            self.frames.push(FrameSlot::new(&self.ctx)?);
        }
        let slot = self.next;
        let s = &mut self.frames[slot];
        if !s.ready(&self.ctx)? {
            return Ok(None);
        }
        if let Some(t) = s.gpu_seconds(&self.ctx)
            && let Some(pass) = self.pacing.timed(slot, t)
        {
            self.last_gpu_seconds = Some(pass);
        }
        let cmd = s.begin(&self.ctx)?;
        Ok(Some(Frame {
            slot,
            cmd,
            acquired: s.acquired,
        }))
    }

    /// The internal size a frame asked at `size` is traced at: `size` itself, or the largest
    /// of its aspect whose per-pixel buffers (at most [`IMAGE_BYTES_PER_PIXEL`]: the
    /// denoiser's guides) fit the device's limits.
    pub fn fit_internal(&self, size: (u32, u32)) -> (u32, u32) {
        self.ctx
            .limits
            .fit_image((size.0.max(1), size.1.max(1)), IMAGE_BYTES_PER_PIXEL)
    }

    /// Records the frame's GPU work: the world's changed bytes are uploaded (staging ring),
    /// up to `req.spp` samples added (restarting on any change), and the display pass writes
    /// the output buffer ([`Viewport::output`]).
    pub fn trace_frame(
        &mut self,
        frame: &Frame,
        world: &World,
        req: &FrameRequest<'_>,
    ) -> Result<FrameStatus, GpuError> {
        let upload = self.world.update(&self.ctx.clone(), world)?;
        Ok(self.record_frame(frame, world, req, upload, Band::WHOLE)?.0)
    }

    /// [`Viewport::trace_frame`] after the world's upload, tracing `band` of the image's
    /// rows: a band before the last records only its part of the samples (no denoiser, no
    /// display pass). Also returns whether the band was traced (not held by an upload).
    fn record_frame(
        &mut self,
        frame: &Frame,
        world: &World,
        req: &FrameRequest<'_>,
        upload: UploadReport,
        band: Band,
    ) -> Result<(FrameStatus, bool), GpuError> {
        let ctx = self.ctx.clone();
        if upload.grew {
            // The grown world waited for the GPU: every slot's sets may go.
            for s in &mut self.frames {
                s.sets.clear(&ctx);
            }
        }
        let internal = self.fit_internal(req.internal);
        let output = (req.output.0.max(1), req.output.1.max(1));
        let mut recreated = false;
        if self
            .live
            .as_ref()
            .is_none_or(|l| l.internal() != internal || l.output() != output)
        {
            // The other slot may still read the old accumulation.
            self.wait_idle()?;
            if let Some(old) = self.live.take() {
                old.destroy(&ctx);
            }
            for s in &mut self.frames {
                s.sets.clear(&ctx);
            }
            self.live = Some(Progressive::new(&ctx, internal, output, 1)?);
            recreated = true;
            if let Some(d) = &mut self.denoiser {
                d.invalidate();
            }
        }
        let live = self.live.as_mut().expect("made above");
        if upload.changed() {
            live.restart();
        }
        // An edit whose upload spans frames: until the rest is on the GPU the frame shows the
        // previous image (the accumulation is untouched) instead of a half-applied edit.
        let hold = upload.deferred_bytes > 0 && self.held < MAX_HELD_FRAMES && live.has_image();
        self.held = if hold { self.held + 1 } else { 0 };
        // The frame's parameters under a short read lock.
        let (base, variant) = {
            let view = world.read();
            let base = TraceParams::new(&view, req.params, &live.job_of(1))
                .dimmed(req.dim)
                .with_grid(req.grid);
            let variant = Variant {
                dim: req.dim.is_some(),
                grid: req.grid.is_some(),
                ..Variant::for_scene(&view, req.params)
            };
            (base, variant)
        };
        let key = {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            (base.scene_key(), variant).hash(&mut h);
            h.finish()
        };
        let only_camera = !upload.changed() && self.scene_key == Some(key);
        self.scene_key = Some(key);
        let ldr_bytes = output.0 as u64 * output.1 as u64 * 4;
        if self.frames[frame.slot]
            .ldr
            .as_ref()
            .is_some_and(|b| b.size < ldr_bytes)
        {
            paced::idle_for_output(&ctx)?;
        }
        let slot = &mut self.frames[frame.slot];
        slot.ensure_ldr(&ctx, ldr_bytes)?;
        // SAFETY: recording; earlier frames' and the staging ring's writes (same queue,
        // earlier in submission order) come before this frame's reads and writes.
        unsafe { after_earlier_passes(&ctx, frame.cmd) };
        // Reprojection averages a moving camera's frames: they must be independent samples.
        live.set_fresh_restarts(req.denoise && req.reproject);
        let (added, restarted) = if hold {
            (0, false)
        } else {
            live.record_batch(
                &ctx,
                frame.cmd,
                &mut self.tracer,
                &self.world,
                base,
                variant,
                (req.spp, req.target_spp),
                &mut slot.uniforms,
                &mut slot.sets,
                band,
            )?
        };
        if !band.is_last() && !hold {
            // The display pass waits for the pass's last band.
            let status = FrameStatus {
                samples: live.samples(),
                added,
                restarted,
                upload,
            };
            return Ok((status, true));
        }
        // SAFETY: recording: the trace's writes before the display pass reads them.
        unsafe { between_passes(&ctx, frame.cmd) };
        let mut shown = live.accumulation();
        if req.denoise && live.has_image() {
            if self.denoiser.is_none() {
                self.denoiser = Some(Denoiser::new(&ctx)?);
            }
            let d = self.denoiser.as_mut().expect("made above");
            d.set_fade(
                self.fade
                    .unwrap_or(Fade::for_picture(internal).ending_by(req.target_spp)),
            );
            if !d.has_size(internal) {
                // The other slot may still read the old size's buffers.
                for s in &self.frames {
                    s.wait(&ctx)?;
                }
            }
            let slot = &mut self.frames[frame.slot];
            let fresh = !d.is_current() || !d.has_size(internal);
            if added > 0 || (fresh && !hold) {
                if added == 0 {
                    // No batch this frame wrote the slot's parameters (the denoiser was
                    // switched on over a finished image): the guides need the camera.
                    slot.uniforms
                        .write(bytemuck::bytes_of(&base.batch(0, live.samples(), true)));
                }
                d.record_batch(
                    &ctx,
                    frame.cmd,
                    &mut slot.sets,
                    &self.world,
                    slot.uniforms.binding(),
                    live.accumulation(),
                    internal,
                    restarted,
                )?;
                // While the camera moves, the filter reads the reprojected history instead.
                let t = match &mut self.temporal {
                    Some(t) => t,
                    None => self.temporal.insert(Temporal::new(&ctx)?),
                };
                if !only_camera || !req.reproject {
                    t.invalidate();
                }
                let inputs = d.first_surfaces().zip(d.guides_and_moments());
                let source = match inputs.filter(|_| added > 0 && req.reproject) {
                    Some((surfaces, (guides, moments))) => t.record(
                        &ctx,
                        frame.cmd,
                        &mut slot.sets,
                        live.accumulation(),
                        surfaces,
                        guides,
                        moments,
                        base.camera(),
                        internal,
                        live.samples(),
                        restarted,
                        recreated,
                    )?,
                    None => None,
                };
                self.filter_input = source;
                d.set_temporal_input(source.is_some() && restarted);
                let source = source.unwrap_or_else(|| live.accumulation());
                shown = d.record_filter(&ctx, frame.cmd, &mut slot.sets, source)?;
            } else if let Some(out) = d.filtered_output() {
                shown = out;
            }
        } else if let Some(d) = &mut self.denoiser {
            // Batches added meanwhile are not in its moments.
            d.invalidate();
            if let Some(t) = &mut self.temporal {
                t.invalidate();
            }
        }
        let slot = &mut self.frames[frame.slot];
        let ldr = slot.ldr.as_ref().expect("ensured above").binding();
        self.tone.record(
            &ctx,
            frame.cmd,
            &mut slot.sets,
            shown,
            ldr,
            (internal, output),
            req.exposure,
            req.bgra,
        )?;
        // SAFETY: recording: the display output is read by transfers (copy to an image).
        unsafe {
            barrier(&ctx, frame.cmd, Scope::SHADER_WRITE, Scope::TRANSFER_READ);
        }
        self.pacing.recording(frame.slot, output, live.samples());
        let status = FrameStatus {
            samples: live.samples(),
            added,
            restarted,
            upload,
        };
        Ok((status, !hold))
    }

    /// Ends and submits the frame (waiting on `waits`, signalling `signals`); never blocks.
    pub fn submit_frame(
        &mut self,
        frame: Frame,
        waits: &[(vk::Semaphore, vk::PipelineStageFlags)],
        signals: &[vk::Semaphore],
    ) -> Result<(), GpuError> {
        self.frames[frame.slot].submit(&self.ctx, waits, signals)?;
        self.pacing.submitted(frame.slot);
        self.next = (frame.slot + 1) % FRAMES_IN_FLIGHT;
        Ok(())
    }

    /// Waits until every frame in flight finished.
    pub fn wait_idle(&self) -> Result<(), GpuError> {
        for s in &self.frames {
            s.wait(&self.ctx)?;
        }
        Ok(())
    }

    /// A whole frame without a window, if a slot is free: traces `world` as `req` asks and
    /// submits. `None`: both slots are in flight (the window's loop would handle events
    /// meanwhile).
    pub fn try_draw(
        &mut self,
        world: &World,
        req: &FrameRequest<'_>,
    ) -> Result<Option<FrameStatus>, GpuError> {
        let Some(frame) = self.begin_frame()? else {
            return Ok(None);
        };
        let status = self.trace_frame(&frame, world, req)?;
        self.submit_frame(frame, &[], &[])?;
        Ok(Some(status))
    }

    /// [`Viewport::try_draw`], waiting (yielding the thread) until a slot is free.
    pub fn draw(&mut self, world: &World, req: &FrameRequest<'_>) -> Result<FrameStatus, GpuError> {
        loop {
            if let Some(status) = self.try_draw(world, req)? {
                return Ok(status);
            }
            std::thread::yield_now();
        }
    }
}

/// A device buffer of vec4 per pixel (radiance, count 1) as a linear image.
fn read_image(ctx: &GpuContext, buffer: Binding, size: (u32, u32)) -> Result<Image, GpuError> {
    let raw = read_device(ctx, buffer)?;
    let px: &[[f32; 4]] = bytemuck::cast_slice(&raw);
    Ok(Image {
        width: size.0,
        height: size.1,
        pixels: px
            .iter()
            .take(size.0 as usize * size.1 as usize)
            .map(|p| [p[0], p[1], p[2]])
            .collect(),
    })
}

impl Drop for Viewport {
    fn drop(&mut self) {
        // SAFETY: the device is idle after the wait; each field is taken once, here.
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
            for s in self.frames.drain(..) {
                s.destroy(&self.ctx);
            }
            if let Some(l) = self.live.take() {
                l.destroy(&self.ctx);
            }
            if let Some(b) = self.bench.take() {
                b.destroy(&self.ctx);
            }
            if let Some(p) = self.primary.take() {
                p.destroy(&self.ctx);
            }
            if let Some(d) = self.denoiser.take() {
                d.destroy(&self.ctx);
            }
            if let Some(t) = self.temporal.take() {
                t.destroy(&self.ctx);
            }
            ManuallyDrop::take(&mut self.tone).destroy(&self.ctx);
            ManuallyDrop::take(&mut self.tracer).destroy(&self.ctx);
            ManuallyDrop::take(&mut self.world).destroy(&self.ctx);
        }
    }
}
