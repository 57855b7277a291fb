//! The viewport's one-shot denoised render (`Viewport::render_denoised`): the samples added a
//! batch per dispatch as interactive frames add them, the guides and moments after each, the
//! filter at the end (optionally timed) — what `bench-error`'s "denoised" choice and finished
//! pictures with `--denoise` measure and use.

use super::*;

/// A render with the viewport's denoiser ([`Viewport::render_denoised`]).
#[derive(Clone, Debug)]
pub struct DenoisedRender {
    /// The accumulation's mean (linear).
    pub raw: Image,
    /// The denoised image (linear).
    pub denoised: Image,
    /// GPU time of the trace dispatches (None when the queue cannot time).
    pub trace_seconds: Option<f64>,
    /// GPU time of one filter (guides and moments not included: they run with the batches),
    /// the median of the timed repetitions; None when not timed.
    pub filter_seconds: Option<f64>,
}

impl Viewport {
    /// The denoiser's fade to the raw mean: `None` for the picture size's
    /// ([`Fade::for_picture`]), else this one (benchmarks: [`Fade::NEVER`] measures the
    /// filter's bias).
    pub fn set_denoise_fade(&mut self, fade: Option<Fade>) {
        self.fade = fade;
    }

    /// Renders `job` with `variant` as the viewport does with its denoiser on, one batch per
    /// dispatch (the tracer's batch shape), and waits; the filter is timed over `timed`
    /// repetitions (0: not timed).
    pub fn render_denoised(
        &mut self,
        view: &WorldView<'_>,
        params: &SceneParams,
        job: &RenderJob,
        variant: Variant,
        timed: u32,
    ) -> Result<DenoisedRender, GpuError> {
        let whole = Window::whole((job.width, job.height));
        self.render_denoised_in(view, params, job, variant, timed, whole)
    }

    /// [`Viewport::render_denoised`] of `job`'s image as the part `window` of a larger
    /// picture (a tile: its pixels and guides are the picture's there).
    pub fn render_denoised_in(
        &mut self,
        view: &WorldView<'_>,
        params: &SceneParams,
        job: &RenderJob,
        variant: Variant,
        timed: u32,
        window: Window,
    ) -> Result<DenoisedRender, GpuError> {
        let ctx = self.ctx.clone();
        // The denoiser's buffers may be the live accumulation's.
        self.wait_idle()?;
        if self.denoiser.is_none() {
            self.denoiser = Some(Denoiser::new(&ctx)?);
        }
        let size = (job.width, job.height);
        let mut acc = Progressive::new(&ctx, size, size, job.seed)?;
        acc.set_window(window);
        let mut guide_params = match HostBuffer::new(
            &ctx,
            "guide params",
            std::mem::size_of::<TraceParams>() as u64,
            gpu_allocator::MemoryLocation::CpuToGpu,
        ) {
            Ok(b) => b,
            Err(e) => {
                acc.destroy(&ctx);
                return Err(e);
            }
        };
        let guides = TraceParams::in_window(view, params, job, window);
        guide_params.write(bytemuck::bytes_of(&guides));
        let mut sets = match SetCache::new(&ctx) {
            Ok(s) => s,
            Err(e) => {
                acc.destroy(&ctx);
                guide_params.destroy(&ctx);
                return Err(e);
            }
        };
        let denoiser = self.denoiser.as_mut().expect("made above");
        denoiser.invalidate();
        denoiser.set_fade(self.fade.unwrap_or(Fade::for_picture(window.picture)));
        let world = &*self.world;
        let result = acc
            .accumulate_with(
                &ctx,
                &mut self.tracer,
                world,
                view,
                params,
                variant,
                job.spp,
                |accum, first| {
                    let mut recorded = Ok(());
                    ctx.submit_and_wait(|cmd| {
                        recorded = denoiser.record_batch(
                            &ctx,
                            cmd,
                            &mut sets,
                            world,
                            guide_params.binding(),
                            accum,
                            size,
                            first,
                        );
                    })?;
                    recorded
                },
            )
            .and_then(|(trace_seconds, _)| {
                let filter_sets = denoiser.filter_sets(&ctx, &mut sets, acc.accumulation())?;
                let record = |cmd| {
                    denoiser.record_filter_sets(&ctx, cmd, filter_sets);
                };
                let times = run_batch(&ctx, timed.max(1), timed > 0, record)?;
                let raw = acc.hdr(&ctx)?;
                let denoised = read_image(&ctx, denoiser.output().expect("filtered"), size)?;
                let mut times: Vec<f64> = times;
                times.sort_by(f64::total_cmp);
                Ok(DenoisedRender {
                    raw,
                    denoised,
                    trace_seconds,
                    filter_seconds: times.get(times.len() / 2).copied(),
                })
            });
        acc.destroy(&ctx);
        guide_params.destroy(&ctx);
        sets.destroy(&ctx);
        denoiser.invalidate();
        result
    }
}
