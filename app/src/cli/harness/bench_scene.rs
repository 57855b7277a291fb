//! `voxbrick bench-gpu --scene FILE`: steady-state GPU time per sample of any scene file at its
//! own settings (or `--bounces`), timed as the complexities are: rounds of back-to-back
//! dispatches of `--spp` samples per pixel after two warm-up rounds, medians per sample; then
//! one counted 1-spp render for the rays.

use anyhow::{Context, Result, bail};
use render::cpu::RenderJob;
use render::viewport::RenderHow;
use render::vulkan::trace::Variant;
use std::path::Path;

/// What `--scene` measures.
pub(crate) struct SceneBench<'a> {
    pub path: &'a Path,
    pub bounces: Option<u32>,
    /// Samples per pixel in each dispatch.
    pub spp: u32,
    pub size: (u32, u32),
    pub frames: usize,
    pub experiment: u32,
}

/// Times the scene and says what it measured.
pub(crate) fn bench_scene(b: SceneBench<'_>, device: &str, workers: usize) -> Result<String> {
    let scene = app::formats::load(b.path, workers)?;
    let mut params = scene.params.clone();
    if let Some(n) = b.bounces {
        if !(1..=64).contains(&n) {
            bail!("--bounces {n} is outside 1..=64");
        }
        params.settings.max_bounces = n;
    }
    let view = scene.world.read();
    let mut session = app::gpu::session(device, &view)?;
    let ctx = session.ctx().clone();
    let variant = Variant {
        experiment: b.experiment,
        ..Variant::for_scene(&view, &params)
    };
    let (width, height) = b.size;
    const ROUND: u32 = 10;
    let mut times = Vec::with_capacity(b.frames);
    for round in 0..b.frames.div_ceil(ROUND as usize) + 2 {
        let t = session.time_repeated(&view, &params, variant, b.size, b.spp, ROUND)?;
        if t.is_empty() {
            bail!("this queue cannot take timestamps");
        }
        if round >= 2 {
            times.extend(t.iter().map(|t| t / b.spp as f64));
        }
    }
    times.sort_by(f64::total_cmp);
    let at = |q: usize| times[(times.len() - 1) * q / 100] * 1e3;
    let job = RenderJob {
        width,
        height,
        spp: 1,
        seed: 0,
    };
    let rays = session
        .render(&view, &params, &job, RenderHow::variant(variant).counted())?
        .rays
        .context("the counted render reported no rays")?;
    let stats = super::bench_gpu::statistics(&mut session, variant);
    let median = at(50);
    Ok(format!(
        "device       {} ({})\nscene        {} ({}x{}x{} voxels, {} solid), {width}x{height}, {} bounces, sun {}\n\
         per sample   median {median:.3} ms (p10 {:.3}, p90 {:.3}, {} dispatches of {} spp)\n\
         rays         {:.2} M camera, {:.2} M continuation, {:.2} M shadow per sample ({:.0} Mrays/s)\n\
         lanes busy   {:.1} % of the trace pass's lane steps\n\
         statistics   {stats}\n",
        ctx.name,
        ctx.driver,
        b.path.display(),
        view.dims().voxels().x,
        view.dims().voxels().y,
        view.dims().voxels().z,
        view.solid_count(),
        params.settings.max_bounces,
        if params.sun.enabled { "on" } else { "off" },
        at(10),
        at(90),
        times.len(),
        b.spp,
        rays.primary as f64 / 1e6,
        rays.secondary as f64 / 1e6,
        rays.shadow as f64 / 1e6,
        rays.total() as f64 / median / 1e3,
        rays.lane_steps[0] as f64 / rays.lane_steps[1].max(1) as f64 * 100.0,
    ))
}
