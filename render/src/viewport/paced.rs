//! The interactive loop's tracing at its own pace: a trace job (upload, samples, denoiser,
//! display pass into the slot's display output) is submitted only when the frames in flight
//! allow it and something would change, and the window shows the display output of the
//! latest job that *finished* — so a frame of the UI never waits for a trace on the host, and
//! on the device waits at most for the one job in flight when jobs are slow.
//!
//! Jobs slower than [`SLOW_JOB`] run one at a time: a display submission queued behind them
//! then waits for one job, never two. Faster jobs keep two in flight, so the device never
//! idles while the host records. A sample pass slower than [`BAND_SECONDS`] is traced in
//! bands of rows, one job each (the same samples as one dispatch: each pixel is traced once
//! per pass); the pass's last band runs the denoiser and the display pass, so only whole
//! passes are ever shown. A change (an edit, the camera, a setting) starts a new pass.

use super::*;
use crate::vulkan::vk_call;

/// A job's GPU time above which only one job is in flight.
pub const SLOW_JOB: f64 = 0.004;

/// The GPU time one band of a sample pass should take: a pass slower than this is traced in
/// bands of rows, each its own job, so a display queued behind a job waits at most about
/// this long (plus the display pass of a pass's last band).
pub const BAND_SECONDS: f64 = 0.012;

/// The most bands a sample pass is split into.
pub const MAX_BANDS: u32 = 32;

/// What a slot's display output holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TracedImage {
    /// Its size in pixels (the output size it was traced for).
    pub size: (u32, u32),
    /// Samples per pixel accumulated in it.
    pub samples: u32,
    /// The job that made it (counted from 1 in the viewport's life).
    pub job: u64,
}

/// A traced image on the device, ready to be copied: packed 8-bit pixels, rows top down.
#[derive(Clone, Copy, Debug)]
pub struct ShownImage {
    /// The display output buffer.
    pub buffer: vk::Buffer,
    /// What it holds.
    pub image: TracedImage,
}

/// What [`Viewport::trace_paced`] did.
#[derive(Clone, Copy, Debug)]
pub enum Paced {
    /// A job was submitted.
    Traced(FrameStatus),
    /// The jobs in flight come first (try again when one finished).
    Busy,
    /// Nothing would change: the image is converged and nothing it depends on moved.
    Idle,
}

/// The viewport's bookkeeping of jobs and the images they leave.
#[derive(Debug, Default)]
pub(super) struct Pacing {
    /// Per frame slot: what its display output holds once its last submission finished.
    images: Vec<Option<TracedImage>>,
    /// The slot last submitted.
    latest: Option<usize>,
    /// The slot whose finished output the window shows.
    shown: Option<usize>,
    /// Jobs recorded.
    jobs: u64,
    /// The slot being recorded and what it will hold.
    recording: Option<(usize, TracedImage)>,
    /// What the last paced job was asked.
    asked: Option<Asked>,
    /// The sample pass in bands being traced: its next band and samples per pixel.
    pass: Option<(Band, u32)>,
    /// The band of the job being recorded (None: no paced band).
    band: Option<Band>,
    /// Per frame slot: the band its last job traced.
    bands: Vec<Option<Band>>,
    /// GPU time of the current pass's bands so far.
    pass_seconds: f64,
    /// GPU time of the last job read back.
    job_seconds: Option<f64>,
    /// Bands of every new pass, fixed ([`Viewport::set_bands`]).
    fixed_bands: Option<u32>,
}

impl Pacing {
    /// A job is being recorded into `slot`: its output will be `size` at `samples`.
    pub(super) fn recording(&mut self, slot: usize, size: (u32, u32), samples: u32) {
        self.jobs += 1;
        self.recording = Some((
            slot,
            TracedImage {
                size,
                samples,
                job: self.jobs,
            },
        ));
    }

    /// The frame in `slot` was submitted.
    pub(super) fn submitted(&mut self, slot: usize) {
        if self.images.len() <= slot {
            self.images.resize(slot + 1, None);
            self.bands.resize(slot + 1, None);
        }
        self.bands[slot] = self.band.take();
        // A band before a pass's last leaves the slot's display output as it was.
        if let Some((s, image)) = self.recording.take()
            && s == slot
        {
            self.images[slot] = Some(image);
            self.latest = Some(slot);
        }
    }

    /// The GPU time `t` of `slot`'s last job was read back: the time of a whole sample pass
    /// when that job ended one (the sum of its bands).
    pub(super) fn timed(&mut self, slot: usize, t: f64) -> Option<f64> {
        self.job_seconds = Some(t);
        match self.bands.get(slot).copied().flatten() {
            Some(b) if !b.is_last() => {
                self.pass_seconds += t;
                None
            }
            _ => Some(t + std::mem::take(&mut self.pass_seconds)),
        }
    }

    /// Bands for a new pass whose whole takes about `pass` seconds, over `rows` rows of
    /// workgroups.
    fn bands_for(pass: Option<f64>, rows: u32) -> u32 {
        let wanted = pass.map_or(1.0, |t| (t / BAND_SECONDS).ceil());
        (wanted as u32).clamp(1, MAX_BANDS.min(rows.max(1)))
    }

    /// The latest job's slot becomes the shown one once `finished` says it is done.
    fn poll(&mut self, finished: impl Fn(usize) -> Result<bool, GpuError>) -> Result<(), GpuError> {
        if let Some(l) = self.latest
            && finished(l)?
        {
            self.shown = Some(l);
        }
        Ok(())
    }
}

impl Viewport {
    /// The interactive loop's trace: a job is recorded and submitted when fewer jobs are in
    /// flight than their pace allows (one while they take longer than [`SLOW_JOB`], two
    /// otherwise) and something would change; never blocks.
    pub fn trace_paced(
        &mut self,
        world: &World,
        req: &FrameRequest<'_>,
    ) -> Result<Paced, GpuError> {
        let limit = if self.pacing.job_seconds.is_some_and(|t| t > SLOW_JOB) {
            1
        } else {
            FRAMES_IN_FLIGHT
        };
        if self.in_flight()? >= limit {
            return Ok(Paced::Busy);
        }
        // A finished job's output is the one shown from now on: the next job goes to another
        // slot (one job in flight), so no frame waits on the device for what it shows.
        self.poll_shown()?;
        let asked = Asked::of(req);
        let converged = self
            .live
            .as_ref()
            .is_some_and(|l| l.samples() >= req.target_spp);
        let Some(frame) = self.begin_frame()? else {
            return Ok(Paced::Busy);
        };
        let upload = self.world.update(&self.ctx.clone(), world)?;
        let changed = upload.changed()
            || upload.deferred_bytes > 0
            || self.pacing.asked.as_ref() != Some(&asked);
        if converged && !changed && self.pacing.pass.is_none() && self.pacing.latest.is_some() {
            // The slot's command buffer stays unsubmitted; its next `begin` resets it.
            return Ok(Paced::Idle);
        }
        self.pacing.asked = Some(asked);
        // A pass in bands goes on while nothing changed; a change starts a new one.
        let (band, spp) = match self.pacing.pass {
            Some(pass) if !changed => pass,
            _ => {
                let rows = self.fit_internal(req.internal).1.div_ceil(8);
                let count = match self.pacing.fixed_bands {
                    Some(n) => n.clamp(1, rows.max(1)),
                    None if converged => 1,
                    None => Pacing::bands_for(self.last_gpu_seconds, rows),
                };
                (Band { index: 0, count }, req.spp)
            }
        };
        let req = FrameRequest { spp, ..*req };
        let (status, traced_band) = self.record_frame(&frame, world, &req, upload, band)?;
        if traced_band {
            self.pacing.band = Some(band);
            self.pacing.pass = (!band.is_last()).then_some((
                Band {
                    index: band.index + 1,
                    ..band
                },
                spp,
            ));
        }
        self.submit_frame(frame, &[], &[])?;
        Ok(Paced::Traced(status))
    }

    /// Every new sample pass of [`Viewport::trace_paced`] in `bands` bands (at most one per
    /// row of workgroups) instead of as many as its GPU time asks (None): tests and
    /// measurements.
    pub fn set_bands(&mut self, bands: Option<u32>) {
        self.pacing.fixed_bands = bands;
    }

    /// The job whose image will show what the jobs submitted so far traced: the last one
    /// recorded, or the next while a pass in bands is still being traced.
    pub fn pending_image_job(&self) -> u64 {
        self.pacing.jobs + u64::from(self.pacing.pass.is_some())
    }

    /// Frame slots whose submission has not finished.
    pub fn in_flight(&self) -> Result<usize, GpuError> {
        let mut n = 0;
        for s in &self.frames {
            n += usize::from(!s.ready(&self.ctx)?);
        }
        Ok(n)
    }

    /// The display output of the latest job that finished (polled, never waits), for a
    /// window's frame to copy: None until one finished.
    pub fn shown_image(&mut self) -> Result<Option<ShownImage>, GpuError> {
        self.poll_shown()?;
        let Some(s) = self.pacing.shown else {
            return Ok(None);
        };
        Ok(self
            .frames
            .get(s)
            .and_then(|f| f.ldr.as_ref())
            .zip(self.pacing.images.get(s).copied().flatten())
            .map(|(b, image)| ShownImage {
                buffer: b.raw,
                image,
            }))
    }

    fn poll_shown(&mut self) -> Result<(), GpuError> {
        let (frames, ctx) = (&self.frames, &self.ctx);
        self.pacing.poll(|s| frames[s].ready(ctx))
    }
}

/// Waits for the device before a display output is replaced: a window's frame may still be
/// copying it (rare: the output grew).
pub(super) fn idle_for_output(ctx: &GpuContext) -> Result<(), GpuError> {
    // SAFETY: plain wait.
    vk_call("vkDeviceWaitIdle", unsafe { ctx.device.device_wait_idle() })
}

/// A request as pacing compares it: everything but the samples per frame (the budget's).
#[derive(Clone, Debug, PartialEq)]
struct Asked {
    params: SceneParams,
    sizes: ((u32, u32), (u32, u32)),
    target_spp: u32,
    exposure: f32,
    flags: [bool; 3],
    dim: Option<crate::vulkan::trace::Dim>,
    grid: Option<f32>,
}

impl Asked {
    fn of(req: &FrameRequest<'_>) -> Self {
        Self {
            params: req.params.clone(),
            sizes: (req.internal, req.output),
            target_spp: req.target_spp,
            exposure: req.exposure,
            flags: [req.bgra, req.denoise, req.reproject],
            dim: req.dim,
            grid: req.grid,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(job: u64) -> TracedImage {
        TracedImage {
            size: (4, 3),
            samples: 1,
            job,
        }
    }

    #[test]
    fn a_submitted_job_becomes_the_latest_and_keeps_its_image() {
        let mut p = Pacing::default();
        p.recording(1, (4, 3), 1);
        p.submitted(1);
        assert_eq!(p.latest, Some(1));
        assert_eq!(p.images[1], Some(image(1)));
        // A frame submitted without a recorded job (a benchmark's) holds no image.
        p.submitted(0);
        assert_eq!(p.images[0], None);
        assert_eq!(p.latest, Some(1));
    }

    #[test]
    fn the_shown_slot_is_the_latest_one_finished() {
        let mut p = Pacing::default();
        p.poll(|_| Ok(true)).unwrap();
        assert_eq!(p.shown, None, "nothing traced yet");
        p.recording(0, (4, 3), 1);
        p.submitted(0);
        p.poll(|_| Ok(false)).unwrap();
        assert_eq!(p.shown, None, "the first job still runs");
        p.poll(|s| Ok(s == 0)).unwrap();
        assert_eq!(p.shown, Some(0));
        p.recording(1, (4, 3), 2);
        p.submitted(1);
        p.poll(|s| Ok(s == 0)).unwrap();
        assert_eq!(
            p.shown,
            Some(0),
            "the second job's output is not shown before it is done"
        );
        p.poll(|_| Ok(true)).unwrap();
        assert_eq!(p.shown, Some(1));
        assert_eq!(p.images[1].map(|i| i.job), Some(2));
    }

    #[test]
    fn a_pass_in_bands_reports_its_time_once_whole() {
        let mut p = Pacing::default();
        for (slot, index) in [(0, 0), (1, 1), (0, 2)] {
            p.band = Some(Band { index, count: 3 });
            p.submitted(slot);
            let whole = p.timed(slot, 0.01);
            assert_eq!(whole.is_some(), index == 2, "band {index}");
            if let Some(t) = whole {
                assert!((t - 0.03).abs() < 1e-12, "{t}");
            }
        }
        // A job that is not a paced band is a whole pass by itself.
        p.submitted(1);
        assert_eq!(p.timed(1, 0.02), Some(0.02));
    }

    #[test]
    fn bands_follow_the_pass_time_within_the_rows() {
        assert_eq!(Pacing::bands_for(None, 90), 1);
        assert_eq!(Pacing::bands_for(Some(BAND_SECONDS * 0.5), 90), 1);
        assert_eq!(Pacing::bands_for(Some(BAND_SECONDS * 4.5), 90), 5);
        assert_eq!(Pacing::bands_for(Some(10.0), 90), MAX_BANDS);
        assert_eq!(
            Pacing::bands_for(Some(10.0), 3),
            3,
            "never more bands than rows"
        );
        let rows: Vec<_> = (0..3)
            .map(|index| Band { index, count: 3 }.rows(10))
            .collect();
        assert_eq!(
            rows,
            [(0, 3), (3, 6), (6, 10)],
            "the bands cover every row once"
        );
    }

    #[test]
    fn a_request_is_the_same_but_for_its_samples_per_frame() {
        let params = SceneParams::framing(glam::DVec3::splat(16.0));
        let req = FrameRequest {
            params: &params,
            internal: (8, 8),
            output: (8, 8),
            spp: 1,
            target_spp: 64,
            exposure: 0.0,
            bgra: false,
            denoise: false,
            reproject: false,
            dim: None,
            grid: None,
        };
        assert_eq!(Asked::of(&req), Asked::of(&FrameRequest { spp: 8, ..req }));
        assert_ne!(
            Asked::of(&req),
            Asked::of(&FrameRequest {
                exposure: 0.5,
                ..req
            })
        );
        let mut moved = params.clone();
        moved.camera.yaw_deg += 0.01;
        assert_ne!(
            Asked::of(&req),
            Asked::of(&FrameRequest {
                params: &moved,
                ..req
            })
        );
    }
}
