//! `voxbrick bench-gpu`: the thesis complexities with Vulkan timestamp queries, and image
//! error against GPU time (`--convergence`).

use super::{emit, with_progress};
use anyhow::{Context, Result, bail};
use app::builtin::thesis_scene;
use render::viewport::RenderHow;

/// `voxbrick bench-gpu`: what to measure.
#[derive(clap::Args)]
pub(crate) struct BenchGpu {
    /// Internal resolution width.
    #[arg(long, default_value_t = 1024)]
    width: u32,
    /// Internal resolution height.
    #[arg(long, default_value_t = 576)]
    height: u32,
    /// Timed dispatches per complexity and variant, in rounds of 10 back to back (after
    /// two warm-up rounds).
    #[arg(long, default_value_t = 50)]
    frames: usize,
    /// Device name filter (default: a discrete GPU if any).
    #[arg(long)]
    device: Option<String>,
    /// Shader experiment bits (trace.comp `EXPERIMENT`; 0 = the real renderer).
    #[arg(long, default_value_t = 0)]
    experiment: u32,
    /// Trace shadow rays where they start instead of queueing them for the shadow pass.
    #[arg(long)]
    inline_shadows: bool,
    /// Instead of the complexities: image error against GPU time at complexity 3's
    /// settings (1, 2, 4 … 256 spp against a reference render).
    #[arg(long)]
    convergence: bool,
    /// Instead of the complexities: light sampling of emissive voxels against BSDF
    /// sampling alone (efficiency at equal error; a lamp-lit room and the thesis scene with
    /// lamps), and the cost of editing 10 k emissive voxels.
    #[arg(long, conflicts_with = "convergence")]
    lights: bool,
    /// Samples per pixel of the convergence and light-sampling references.
    #[arg(long, default_value_t = 4096)]
    reference_spp: u32,
    /// Invocations each pixel's samples are split among, 1..=8 (default: the renderer's
    /// choice for the image size).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8))]
    slices: Option<u32>,
    /// With --lights: write each scene's reference image (tone mapped PNG) into this folder.
    #[arg(long, value_name = "DIR", requires = "lights")]
    images: Option<std::path::PathBuf>,
    /// Instead of the complexities: steady-state GPU time per sample of this scene file
    /// (.ron, .vox, .qb, .schem) at 1 spp, its own settings unless --bounces.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["convergence", "lights"])]
    scene: Option<std::path::PathBuf>,
    /// With --scene: the most bounces.
    #[arg(long, requires = "scene")]
    bounces: Option<u32>,
    /// With --scene: samples per pixel in each dispatch, 1..=16 (times are per sample).
    #[arg(long, requires = "scene", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    spp: u32,
    /// The complexities' sample numbers: sobol (the default) or independent.
    #[arg(long, value_parser = super::args::sequence)]
    sequence: Option<render::Sequence>,
}

/// Times the complexities (or, with `--convergence` / `--lights`, those measurements) and
/// prints the table.
pub(crate) fn run(bench: BenchGpu, workers: usize) -> Result<()> {
    let BenchGpu {
        width,
        height,
        frames,
        device,
        experiment,
        inline_shadows,
        convergence,
        lights,
        sequence,
        images,
        reference_spp,
        slices,
        scene,
        bounces,
        spp,
    } = bench;
    let frames = frames.max(1);
    let convergence = convergence.then_some(reference_spp);
    let lights = lights.then_some(reference_spp);
    use render::vulkan::trace::Variant;
    if let Some(reference_spp) = lights {
        let device = device.as_deref().unwrap_or("gpu");
        let text = super::bench_lights::bench_lights(
            device,
            workers,
            (width, height),
            reference_spp,
            images.as_deref(),
            experiment,
        )?;
        return emit(&text);
    }
    if let Some(path) = scene {
        let text = super::bench_scene::bench_scene(
            super::bench_scene::SceneBench {
                path: &path,
                bounces,
                spp,
                size: (width, height),
                frames,
                experiment,
            },
            device.as_deref().unwrap_or("gpu"),
            workers,
        )?;
        return emit(&text);
    }
    let scene = thesis_scene(workers)?;
    let view = scene.world.read();
    let mut session = app::gpu::session(device.as_deref().unwrap_or("gpu"), &view)?;
    let ctx = session.ctx().clone();
    let mut text = format!(
        "device       {} ({})\nscene        thesis (512x256x512, {} solid voxels), {width}x{height}\n",
        ctx.name,
        ctx.driver,
        view.solid_count()
    );
    let mut failure = None;
    let tracer = session.tracer();
    tracer.set_deferred_shadows(&ctx, !inline_shadows);
    tracer.set_sample_slices(slices);
    text += &format!(
        "slices       each pixel's samples split among up to {} invocations\n",
        tracer.sample_slices(width as u64 * height as u64)
    );
    text += &format!(
        "shadow rays  {}\n",
        if tracer.deferred_shadows() {
            "queued for the shadow pass"
        } else {
            "traced in place"
        }
    );
    if let Some(reference_spp) = convergence {
        let mut params = scene.params.clone();
        params.settings.max_bounces = 3;
        params.sun.enabled = true;
        let result =
            convergence_table(&mut session, &view, &params, (width, height), reference_spp);
        return emit(&(text + &result?));
    }
    for (label, bounces, spp, sun) in [
        ("complexity 1 (1 bounce, 1 spp, no sun)", 1, 1, false),
        ("complexity 2 (1 bounce, 1 spp, sun)", 1, 1, true),
        ("complexity 3 (3 bounces, 2 spp, sun)", 3, 2, true),
    ] {
        let mut params = scene.params.clone();
        params.settings.max_bounces = bounces;
        params.sun.enabled = sun;
        if let Some(s) = sequence {
            params.settings.sequence = s;
        }
        // The scene's variant and the everything variant, alternated in rounds of
        // back-to-back dispatches (one submission each, so the GPU stays busy and its clocks
        // stay up) so both see the same machine state; the first two rounds of each are
        // warm-up.
        let scene_variant = Variant {
            experiment,
            ..Variant::for_scene(&view, &params)
        };
        let variants = [scene_variant, Variant::everything(bounces)];
        let mut times = [Vec::with_capacity(frames), Vec::with_capacity(frames)];
        const ROUND: u32 = 10;
        'rounds: for round in 0..frames.div_ceil(ROUND as usize) + 2 {
            for (k, v) in variants.iter().enumerate() {
                match session.time_repeated(&view, &params, *v, (width, height), spp, ROUND) {
                    Ok(t) if round >= 2 => times[k].extend(t),
                    Ok(_) => {}
                    Err(e) => {
                        failure = Some(e);
                        break 'rounds;
                    }
                }
            }
        }
        if failure.is_some() {
            break;
        }
        if times[0].is_empty() {
            text += &format!("{label}: this queue cannot take timestamps\n");
            continue;
        }
        let rays = match session.render(
            &view,
            &params,
            &render::cpu::RenderJob {
                width,
                height,
                spp,
                seed: 0,
            },
            RenderHow::variant(scene_variant).counted(),
        ) {
            Ok(r) => r.rays.expect("counted"),
            Err(e) => {
                failure = Some(e);
                break;
            }
        };
        let n = times[0].len();
        let stats = statistics(&mut session, scene_variant);
        if !stats.is_empty() {
            text += &format!("{label}: pipeline statistics: {stats}\n");
        }
        let [(median, p10, p90), (full, _, _)] = times.map(|mut t| {
            t.sort_by(|a, b| a.total_cmp(b));
            (t[t.len() / 2], t[t.len() / 10], t[t.len() * 9 / 10])
        });
        text += &format!(
            "{label}: median {:.3} ms (p10 {:.3}, p90 {:.3}, {} frames); everything variant {:.3} ms ({:+.1}%)\n  \
             rays: {:.1} M primary, {:.1} M secondary, {:.1} M shadow; {:.0} Mrays/s primary, {:.0} Mrays/s secondary+shadow, {:.0} Mrays/s all\n  \
             traversal steps per ray: {:.1} primary, {:.1} secondary, {:.1} shadow; most in one ray: {} camera or continuation, {} shadow\n  \
             lanes busy in the trace pass's traversals: {:.1} % ({:.1} M lane steps paid for {:.1} M taken)\n",
            median * 1e3,
            p10 * 1e3,
            p90 * 1e3,
            n,
            full * 1e3,
            (full / median - 1.0) * 100.0,
            rays.primary as f64 / 1e6,
            rays.secondary as f64 / 1e6,
            rays.shadow as f64 / 1e6,
            rays.primary as f64 / median / 1e6,
            (rays.secondary + rays.shadow) as f64 / median / 1e6,
            rays.total() as f64 / median / 1e6,
            rays.steps[0] as f64 / rays.primary.max(1) as f64,
            rays.steps[1] as f64 / rays.secondary.max(1) as f64,
            rays.steps[2] as f64 / rays.shadow.max(1) as f64,
            rays.max_steps[0],
            rays.max_steps[1],
            rays.lane_steps[0] as f64 / rays.lane_steps[1].max(1) as f64 * 100.0,
            rays.lane_steps[1] as f64 / 1e6,
            rays.lane_steps[0] as f64 / 1e6,
        );
    }
    if let Some(e) = failure {
        return Err(e.into());
    }
    emit(&text)
}

/// The pipeline statistics of `variant` as `key=value, …` (empty where the driver has none).
pub(crate) fn statistics(
    session: &mut render::viewport::Viewport,
    variant: render::vulkan::trace::Variant,
) -> String {
    session
        .statistics(variant)
        .into_iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Image error against GPU time (render::convergence): a reference of `reference_spp` samples,
/// then renders of 1, 2, 4 … 256 samples with other seeds, each three times (the middle time
/// and the mean MSE are used).
pub(crate) fn convergence_table(
    session: &mut render::viewport::Viewport,
    view: &brickmap::WorldView<'_>,
    params: &render::SceneParams,
    (width, height): (u32, u32),
    reference_spp: u32,
) -> Result<String> {
    use render::convergence::{Measurement, table};
    let job = |spp, seed| render::cpu::RenderJob {
        width,
        height,
        spp,
        seed,
    };
    let (reference, reference_time) = with_progress(
        format!("reference: {width}x{height} at {reference_spp} spp"),
        || {
            let r = session.render(view, params, &job(reference_spp, 1), RenderHow::SCENE)?;
            Ok((r.image, r.gpu_seconds))
        },
    )?;
    let Some(reference_time) = reference_time else {
        bail!("this queue cannot take timestamps");
    };
    let mean = reference.mean().iter().sum::<f64>() / 3.0;
    let mut measurements = Vec::new();
    for spp in (0..9).map(|k| 1u32 << k) {
        let (mut times, mut mse) = (Vec::new(), 0.0);
        for seed in 2..5 {
            let r = session.render(view, params, &job(spp, seed), RenderHow::SCENE)?;
            times.push(r.gpu_seconds.unwrap_or(f64::NAN));
            mse += r.image.mse(&reference).context("image sizes differ")? / 3.0;
        }
        times.sort_by(f64::total_cmp);
        measurements.push(Measurement {
            spp,
            seconds: times[1],
            mse,
        });
    }
    let mut text = format!(
        "convergence  3 bounces, sun; reference {reference_spp} spp in {:.1} ms (GPU), mean pixel value {mean:.4}\n  \
         spp   GPU ms    rel. RMSE   MSE·spp/σ² (1: no bias)   MSE·time (rel. to 1 spp)\n",
        reference_time * 1e3
    );
    for row in table(&measurements, reference_spp, mean) {
        text += &format!(
            "  {:<5} {:<9.3} {:<11.4} {:<25.3} {:.3}\n",
            row.measured.spp,
            row.measured.seconds * 1e3,
            row.relative_rmse,
            row.variance_ratio,
            row.relative_cost
        );
    }
    Ok(text)
}
