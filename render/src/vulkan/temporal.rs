//! Temporal reprojection for the denoised viewport (`shaders/temporal.comp`): while the camera
//! moves, each frame's one batch is blended with the previous frames' radiance reprojected
//! through the first surfaces the denoiser's guides pass finds (same material kind and face,
//! same plane, nearby), and the
//! filter runs on that history instead of the single batch; when the camera stops, the last
//! moving history is handed over to the restarted accumulation, fading out by
//! [`MAX_LEN`] samples, after which the accumulation is shown alone (the unbiased image, as
//! without reprojection). A restart for any other reason (an edit, a setting, the sun)
//! forgets the history. Only the display reads it: no reference render, export or capture
//! of a still image sees it.

use super::barrier::{Scope, barrier, between_passes};
use super::buffer::{Binding, HostBuffer};
use super::pass::{ComputePass, Dispatch, SetCache};
use super::{GpuContext, GpuError};
use ash::vk;
use gpu_allocator::MemoryLocation;

const TEMPORAL: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/temporal.comp.spv"));

/// The longest history, in samples: each new batch weighs at least 1 / MAX_LEN, and a stopped
/// camera's accumulation takes over completely at MAX_LEN samples.
pub const MAX_LEN: u32 = 16;

/// Push constants. Keep in sync with `Push` in shaders/temporal.comp.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    camera: [[f32; 4]; 4],
    size: [u32; 2],
    prev_size: [u32; 2],
    mode: u32,
    flags: u32,
    max_len: f32,
}
const _: () = assert!(std::mem::size_of::<Push>() == 92);

const MOVING: u32 = 0;
const STILL: u32 = 1;

/// A frame's history: its radiance (mean × n, n per pixel), its first surfaces and camera, for
/// images of up to `pixels` pixels (`size` is the one it holds).
struct Kept {
    pixels: u64,
    size: (u32, u32),
    history: HostBuffer,
    surfaces: HostBuffer,
    camera: [[f32; 4]; 4],
}

impl Kept {
    fn new(ctx: &GpuContext, size: (u32, u32)) -> Result<Self, GpuError> {
        ctx.limits.check_image("the temporal history", size, 32)?;
        let pixels = size.0 as u64 * size.1 as u64;
        let make = |name, bytes| HostBuffer::new(ctx, name, bytes, MemoryLocation::GpuOnly);
        let history = make("temporal history", pixels * 32)?;
        match make("temporal first surfaces", pixels * 16) {
            Ok(surfaces) => Ok(Self {
                pixels,
                size,
                history,
                surfaces,
                camera: [[0.0; 4]; 4],
            }),
            Err(e) => {
                history.destroy(ctx);
                Err(e)
            }
        }
    }

    fn destroy(self, ctx: &GpuContext) {
        self.history.destroy(ctx);
        self.surfaces.destroy(ctx);
    }
}

/// The reprojection pass and the histories it keeps.
pub struct Temporal {
    pass: ComputePass,
    /// The last moving frame's history (what the next frame reprojects), if still valid.
    last: Option<Kept>,
    /// Whether `last` describes the scene as it is (only the camera may have moved since).
    valid: bool,
    /// A history buffer set to write the next moving frame into (the one before `last`).
    spare: Option<Kept>,
    /// A stopped camera's display source (radiance sum and count per pixel).
    still: Option<HostBuffer>,
    /// A history too small for the current size, read once more and then retired (freed in
    /// the next safe frame).
    retired: Option<Kept>,
    /// This frame's `last` is too small to be written next: retire it after the frame.
    replace_last: bool,
}

impl Temporal {
    /// Builds the pipeline (buffers come with the first frame).
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            pass: ComputePass::new(ctx, TEMPORAL, 7, std::mem::size_of::<Push>() as u32)?,
            last: None,
            valid: false,
            spare: None,
            still: None,
            retired: None,
            replace_last: false,
        })
    }

    /// Forgets the history: the scene changed, not only the camera.
    pub fn invalidate(&mut self) {
        self.valid = false;
    }

    /// Buffers large enough for `size`: what a frame of that size writes (the next history
    /// when `moving`) and what any later frame of that size writes (the handover buffer, so a
    /// stop never has to grow it). A history kept for reading that is too small to be written
    /// next time is retired after this frame and a new one takes its turn. Buffers are freed
    /// only in `safe` frames — ones that waited for the GPU and dropped their descriptor sets
    /// (the viewport's first frame at a new internal size) — so nothing in flight or cached
    /// uses them: the retired history waits for the next safe frame. Returns false when a
    /// buffer is too small and could only be replaced by freeing one in an unsafe frame.
    fn ensure(
        &mut self,
        ctx: &GpuContext,
        size: (u32, u32),
        moving: bool,
        safe: bool,
    ) -> Result<bool, GpuError> {
        let pixels = size.0 as u64 * size.1 as u64;
        let small_spare = moving && self.spare.as_ref().is_none_or(|k| k.pixels < pixels);
        let small_last = moving && self.last.as_ref().is_some_and(|k| k.pixels < pixels);
        let small_still = self.still.as_ref().is_none_or(|b| b.size < pixels * 16);
        let frees = (small_spare && self.spare.is_some())
            || small_last
            || (small_still && self.still.is_some());
        if frees && !safe {
            return Ok(false);
        }
        if safe && let Some(r) = self.retired.take() {
            r.destroy(ctx);
        }
        if small_spare {
            if let Some(old) = self.spare.take() {
                old.destroy(ctx);
            }
            self.spare = Some(Kept::new(ctx, size)?);
        }
        self.replace_last = small_last;
        if small_still {
            if let Some(old) = self.still.take() {
                old.destroy(ctx);
            }
            self.still = Some(HostBuffer::new(
                ctx,
                "temporal handover",
                pixels * 16,
                MemoryLocation::GpuOnly,
            )?);
        }
        Ok(true)
    }

    /// Records the pass after a batch added to `accum` (of `size`, its first surfaces `surfaces`, made
    /// from `camera`: TraceParams' first four vec4) with `samples` in the accumulation now;
    /// `moving`: this batch restarted the accumulation (the camera moved, or the history was
    /// invalidated); `safe`: the frame may free buffers ([`Temporal::ensure`]). Returns what
    /// the filter should read instead of the accumulation (None: the accumulation itself).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        sets: &mut SetCache,
        accum: Binding,
        surfaces: Binding,
        guides: Binding,
        moments: Binding,
        camera: [[f32; 4]; 4],
        size: (u32, u32),
        samples: u32,
        moving: bool,
        safe: bool,
    ) -> Result<Option<Binding>, GpuError> {
        if !moving && (!self.valid || self.last.is_none() || samples >= MAX_LEN) {
            return Ok(None);
        }
        if !self.ensure(ctx, size, moving, safe)? {
            self.valid = false;
            return Ok(None);
        }
        let groups = Dispatch::Groups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
        if moving {
            let mut out = self.spare.take().expect("ensured");
            let (prev_history, prev_surfaces, prev_camera, prev_size, flags) = match &self.last {
                Some(l) if self.valid => (
                    l.history.binding(),
                    l.surfaces.binding(),
                    l.camera,
                    l.size,
                    1,
                ),
                // Nothing to reproject: any buffers bound, flag 0.
                _ => (
                    out.history.binding(),
                    out.surfaces.binding(),
                    camera,
                    size,
                    0,
                ),
            };
            let set = sets.get(
                ctx,
                &self.pass,
                &[
                    accum,
                    surfaces,
                    prev_surfaces,
                    prev_history,
                    out.history.binding(),
                    guides,
                    moments,
                ],
            )?;
            let push = Push {
                camera: prev_camera,
                size: [size.0, size.1],
                prev_size: [prev_size.0, prev_size.1],
                mode: MOVING,
                flags,
                max_len: MAX_LEN as f32,
            };
            self.pass
                .record(ctx, cmd, set, bytemuck::bytes_of(&push), groups);
            // SAFETY: recording: the guides pass's writes are ordered before this copy (its
            // barrier covers shaders; the copy's own barrier below), the copy's write before
            // the next frame's reads (`after_earlier_passes`).
            unsafe {
                barrier(ctx, cmd, Scope::SHADER_RW, Scope::SHADER_READ_TRANSFER_RW);
                ctx.device.cmd_copy_buffer(
                    cmd,
                    surfaces.buffer,
                    out.surfaces.raw,
                    &[vk::BufferCopy {
                        src_offset: surfaces.offset,
                        dst_offset: 0,
                        size: out.surfaces.size.min(surfaces.range),
                    }],
                );
                barrier(ctx, cmd, Scope::TRANSFER_WRITE, Scope::SHADER_RW);
            }
            out.camera = camera;
            out.size = size;
            let shown = out.history.binding();
            self.spare = self.last.replace(out);
            if std::mem::take(&mut self.replace_last) {
                // (A safe frame: the retired slot was emptied by `ensure`.)
                self.retired = self.spare.take();
                self.spare = Some(Kept::new(ctx, size)?);
            }
            self.valid = true;
            return Ok(Some(shown));
        }
        let last = self.last.as_ref().expect("checked above");
        let out = self.still.as_ref().expect("made above").binding();
        let set = sets.get(
            ctx,
            &self.pass,
            &[
                accum,
                surfaces,
                last.surfaces.binding(),
                last.history.binding(),
                out,
                guides,
                moments,
            ],
        )?;
        let push = Push {
            camera: last.camera,
            size: [size.0, size.1],
            prev_size: [last.size.0, last.size.1],
            mode: STILL,
            flags: 1,
            max_len: MAX_LEN as f32,
        };
        self.pass
            .record(ctx, cmd, set, bytemuck::bytes_of(&push), groups);
        // SAFETY: recording.
        unsafe { between_passes(ctx, cmd) };
        Ok(Some(out))
    }

    /// Frees everything (no submission may still use it).
    pub fn destroy(self, ctx: &GpuContext) {
        for k in [self.last, self.spare, self.retired].into_iter().flatten() {
            k.destroy(ctx);
        }
        if let Some(b) = self.still {
            b.destroy(ctx);
        }
        self.pass.destroy(ctx);
    }
}
