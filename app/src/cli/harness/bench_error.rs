//! `voxbrick bench-error`: image error against samples and against GPU time, for every
//! preset of the benchmark and every sampling choice the path tracer offers, at views along
//! the benchmark's camera path.
//!
//! Per preset and view, a reference of R samples is rendered as two independent halves (with
//! the scrambled Sobol sequence, independently scrambled); their
//! difference estimates the reference's own noise (render::convergence::reference_noise),
//! which is taken off every error measured against it, and a reference whose noise exceeds an
//! eighth of the least error it measures is rejected. Each choice then renders 1, 2, 4 … N
//! samples per pixel, several times with other seeds (the same seeds for every choice), and
//! each render's relMSE (ε = 0.01), GPU time and, for the first of each, FLIP (LDR, on the
//! tone-mapped images) are kept. Checks, per preset, view and choice: the slope of log relMSE
//! against log spp is −1 within four standard errors (at most −1 for a low-discrepancy
//! sequence), and relMSE × spp / σ² at N spp is 1 within four standard errors (σ² from 1 spp).
//! A failed check is a bias: the command writes its report and exits non-zero. The efficiency
//! table gives, at the error the renderer's defaults reach at N spp, how much less GPU time
//! each choice needs (log-log interpolation along its own curve).

mod choice;
mod report;

use choice::{CHOICES, Choice, dispatch_samples};

use super::args;
use super::bench::{PRESETS, Preset, params_at, select_presets};
use anyhow::{Context, Result, bail};
use app::camera_path::CameraPath;
use render::Sequence;
use render::convergence::{log_log_fit, reference_noise, rel_mse, time_at_error};
use render::cpu::RenderJob;
use render::viewport::{RenderHow, Viewport};
use render::vulkan::denoise::Fade;
use render::vulkan::trace::Variant;
use render::{Image, SceneParams};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;

/// `voxbrick bench-error`: what to measure.
#[derive(clap::Args)]
pub(crate) struct BenchError {
    /// Device name filter ("gpu": the best).
    #[arg(long, default_value = "gpu")]
    device: String,
    /// A camera path file (RON; default: the built-in thesis path).
    #[arg(long)]
    path: Option<PathBuf>,
    /// Path times of the views in seconds, comma-separated (default 0,9,15).
    #[arg(long, value_delimiter = ',')]
    views: Vec<f64>,
    /// Image size, WxH.
    #[arg(long, default_value = "512x288", value_parser = args::resolution)]
    size: (u32, u32),
    /// Samples of each reference (at least 8 × --max-spp; two independent halves).
    #[arg(long, default_value_t = 8192)]
    reference_spp: u32,
    /// The most samples per pixel measured (a power of two, 4 or more).
    #[arg(long, default_value_t = 256)]
    max_spp: u32,
    /// The references' numbers: sobol (the renderer's default) or independent (they
    /// cross-check Sobol's curves against an estimator that shares nothing with them).
    #[arg(long, default_value = "sobol", value_parser = args::sequence)]
    reference_sequence: Sequence,
    /// Presets (complexity-1, complexity-2, complexity-3, physical, lamps; default all).
    #[arg(long, value_delimiter = ',')]
    presets: Vec<String>,
    /// Choices besides the defaults (per-dispatch-1, per-dispatch-16, slices-1, slices-2,
    /// in-place-shadows, no-light-sampling, independent, denoised, denoised-no-fade,
    /// denoised-fade-F-T for a fade from F to T spp at any size; default all but the last).
    #[arg(long, value_delimiter = ',')]
    choices: Vec<String>,
    /// Folder for the report.
    #[arg(long, default_value = "error-report")]
    out: PathBuf,
}

/// One level of one choice: renders of `spp` samples.
#[derive(Clone, Debug, Serialize)]
struct Level {
    spp: u32,
    renders: usize,
    /// Median GPU time of a render, ms (a lone render: the clocks may not be up).
    gpu_ms: f64,
    /// Denoised: the median GPU time of one filter, ms (else 0).
    filter_ms: f64,
    /// Dispatches (batches) of a render: the denoiser filters once per batch in a viewport.
    batches: u32,
    /// spp × the choice's steady-state time per sample (back-to-back dispatches), ms.
    steady_ms: f64,
    /// Mean relMSE less the reference's noise, and its standard error.
    rel_mse: f64,
    rel_mse_se: f64,
    /// Mean FLIP of the first render.
    flip: f64,
    /// relMSE × spp / σ² (σ²: relMSE at 1 spp).
    variance_ratio: f64,
}

impl Level {
    /// The standard error, at least [`SE_FLOOR`] of the value.
    fn se(&self) -> f64 {
        self.rel_mse_se.max(SE_FLOOR * self.rel_mse)
    }
}

#[derive(Clone, Debug, Serialize)]
struct Curve {
    choice: Choice,
    name: String,
    levels: Vec<Level>,
    /// Steady-state GPU time per sample, ms.
    ms_per_sample: f64,
    /// For a choice that only changes timing: relMSE of its image against the defaults' (same
    /// job), which must be float rounding; its error curve is the defaults'.
    same_image_rel_mse: Option<f64>,
    slope: f64,
    slope_se: f64,
    /// (slope + 1) / se; (ratio at N − 1) / se; (ratio at N over ratio at N/4 − 1) / se.
    slope_z: f64,
    ratio_z: f64,
    drift_z: f64,
    passed: bool,
}

#[derive(Clone, Debug, Serialize)]
struct ViewRun {
    time_s: f64,
    reference_spp: u32,
    reference_gpu_ms: f64,
    /// The reference's own relMSE and the FLIP between its halves.
    reference_noise: f64,
    reference_flip: f64,
    curves: Vec<Curve>,
}

#[derive(Clone, Debug, Serialize)]
struct CaseRun {
    name: String,
    preset: Preset,
    lamps: bool,
    views: Vec<ViewRun>,
}

/// How many renders a level of `spp` samples averages: enough for 32 samples in all, at
/// least 3.
fn renders_at(spp: u32) -> usize {
    (32 / spp.max(1)).max(3) as usize
}

/// Allowed standard errors off before a check fails.
const Z_MAX: f64 = 4.0;

/// The least relative standard error of a level's mean relMSE. The spread of a few renders
/// understates it where pixels are heavy-tailed (a bright rare path seen in some renders and
/// not in others): on the H200 the 8-bounce presets' ratios stepped by 2–4 % between levels of
/// 32 and 192 samples in all, where the renders' spread claimed 0.1 %.
const SE_FLOOR: f64 = 0.01;

/// The most relMSE between a timing-only choice's image and the defaults' (float rounding is
/// ~1e-14).
const SAME_IMAGE: f64 = 1e-10;

/// Repetitions of the denoiser's filter timed per render.
const FILTER_TIMINGS: u32 = 5;

/// Dispatches per round and rounds (after two of warm-up) of the steady-state timing.
const TIMING_ROUND: u32 = 10;
const TIMING_ROUNDS: usize = 4;

/// GPU seconds of work before the steady-state timing.
const WARM_UP_S: f64 = 0.5;

/// Mean FLIP between two sRGB 8-bit images.
pub(crate) fn flip(reference: &[u8], test: &[u8], (w, h): (u32, u32)) -> f64 {
    let r = nv_flip::FlipImageRgb8::with_data(w, h, reference);
    let t = nv_flip::FlipImageRgb8::with_data(w, h, test);
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    f64::from(nv_flip::FlipPool::from_image(&map).mean())
}

/// An image tone mapped to sRGB 8-bit as the display shows it.
pub(crate) fn srgb(image: &Image, exposure: f32) -> Vec<u8> {
    image.to_srgb8(exposure).into_iter().flatten().collect()
}

fn average(a: &Image, b: &Image) -> Image {
    Image {
        width: a.width,
        height: a.height,
        pixels: a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(x, y)| [0, 1, 2].map(|k| 0.5 * (x[k] + y[k])))
            .collect(),
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Renders and measures one choice at one view against `reference`.
#[allow(clippy::too_many_arguments)]
fn measure(
    session: &mut Viewport,
    view: &brickmap::WorldView<'_>,
    params: &SceneParams,
    (variant, denoise): (Variant, bool),
    (width, height): (u32, u32),
    max_spp: u32,
    (reference, reference_srgb, noise): (&Image, &[u8], f64),
) -> Result<Vec<Level>> {
    let mut levels = Vec::new();
    let mut sigma2 = f64::NAN;
    let mut spp = 1;
    let pixels = u64::from(width) * u64::from(height);
    let per_dispatch = dispatch_samples(session, variant, pixels);
    while spp <= max_spp {
        let n = renders_at(spp);
        let (mut times, mut errors, mut first_flip) = (Vec::new(), Vec::new(), f64::NAN);
        let mut filter_times = Vec::new();
        for i in 0..n {
            let job = RenderJob {
                width,
                height,
                spp,
                seed: 100 + i as u64,
            };
            let (image, t) = if denoise {
                let r = session.render_denoised(view, params, &job, variant, FILTER_TIMINGS)?;
                let f = r
                    .filter_seconds
                    .context("this queue cannot take timestamps")?;
                filter_times.push(f * 1e3);
                (r.denoised, r.trace_seconds.map(|t| t + f))
            } else {
                let r = session.render(view, params, &job, RenderHow::variant(variant))?;
                (r.image, r.gpu_seconds)
            };
            times.push(t.context("this queue cannot take timestamps")? * 1e3);
            errors.push(rel_mse(&image, reference).context("image sizes differ")? - noise);
            if i == 0 {
                first_flip = flip(
                    reference_srgb,
                    &srgb(&image, params.settings.exposure),
                    (width, height),
                );
            }
        }
        let mean = errors.iter().sum::<f64>() / n as f64;
        let var = errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1).max(1) as f64;
        if spp == 1 {
            sigma2 = mean;
        }
        levels.push(Level {
            spp,
            renders: n,
            gpu_ms: median(times),
            filter_ms: if denoise { median(filter_times) } else { 0.0 },
            batches: spp.div_ceil(per_dispatch),
            steady_ms: f64::NAN,
            rel_mse: mean,
            rel_mse_se: (var / n as f64).sqrt(),
            flip: first_flip,
            variance_ratio: mean * f64::from(spp) / sigma2,
        });
        spp *= 2;
    }
    Ok(levels)
}

/// The checks of one curve, each within [`Z_MAX`] standard errors: the slope of log relMSE
/// against log spp is −1; relMSE·spp/σ² at N spp is 1; and it does not drift from N/4 to N
/// spp (a bias b² adds n·b²/σ² to the ratio: a plateau of the error). For Sobol only a slope
/// above −1, a ratio above 1 and a growing ratio count.
fn judge(choice: Choice, sequence: Sequence, levels: Vec<Level>) -> Curve {
    let points: Vec<_> = levels
        .iter()
        .map(|l| (f64::from(l.spp), l.rel_mse, l.se()))
        .collect();
    let fit = log_log_fit(&points);
    let (slope, slope_se) = fit.map_or((f64::NAN, f64::NAN), |f| (f.slope, f.slope_se));
    let rel = |l: &Level| l.se() / l.rel_mse;
    let n = levels.len();
    let (first, last) = (&levels[0], &levels[n - 1]);
    let quarter = &levels[n.saturating_sub(3)];
    let ratio_z = (last.variance_ratio - 1.0) / (last.variance_ratio * rel(last).hypot(rel(first)));
    let drift = last.variance_ratio / quarter.variance_ratio - 1.0;
    let drift_z = drift / rel(last).hypot(rel(quarter));
    let slope_z = (slope + 1.0) / slope_se;
    let passed = if choice.biased() {
        true
    } else if sequence == Sequence::Sobol {
        slope_z <= Z_MAX && ratio_z <= Z_MAX && drift_z <= Z_MAX
    } else {
        [slope_z, ratio_z, drift_z].iter().all(|z| z.abs() <= Z_MAX)
    };
    Curve {
        choice,
        name: choice.name(),
        levels,
        ms_per_sample: f64::NAN,
        same_image_rel_mse: None,
        slope,
        slope_se,
        slope_z,
        ratio_z,
        drift_z,
        passed,
    }
}

/// Steady-state GPU ms per sample of each choice: rounds of back-to-back dispatches of the
/// samples per dispatch the choice gives, the choices in turn within each round (the GPU
/// stays busy and every choice sees the same clocks); the first two rounds are warm-up.
fn steady_times(
    session: &mut Viewport,
    view: &brickmap::WorldView<'_>,
    params: &SceneParams,
    scene_variant: Variant,
    size: (u32, u32),
    choices: &[Choice],
) -> Result<Vec<f64>> {
    let pixels = u64::from(size.0) * u64::from(size.1);
    // Warm-up: the GPU idled while the errors were computed; its clocks come up within a
    // fraction of a second of work (on the H200 the first view's timings were 10–30 % slow
    // with two rounds of warm-up alone).
    let v = Choice::Default.apply(session, scene_variant);
    let spd = session.tracer().samples_per_dispatch_for(pixels, v);
    let mut busy = 0.0;
    while busy < WARM_UP_S {
        let times = session.time_repeated(view, params, v, size, spd, TIMING_ROUND)?;
        if times.is_empty() {
            bail!("this queue cannot take timestamps");
        }
        busy += times.iter().sum::<f64>();
    }
    let mut per_sample = vec![Vec::new(); choices.len()];
    for round in 0..TIMING_ROUNDS + 2 {
        for (k, choice) in choices.iter().enumerate() {
            let v = choice.apply(session, scene_variant);
            let spd = session.tracer().samples_per_dispatch_for(pixels, v);
            let times = session.time_repeated(view, params, v, size, spd, TIMING_ROUND)?;
            if times.is_empty() {
                bail!("this queue cannot take timestamps");
            }
            if round >= 2 {
                per_sample[k].extend(times.iter().map(|t| t * 1e3 / f64::from(spd)));
            }
        }
    }
    Ok(per_sample.into_iter().map(median).collect())
}

/// The cases: each preset on the thesis scene, and "physical + lamps" (the thesis scene with
/// six emissive lamps, where light sampling applies).
fn cases(names: &[String]) -> Result<Vec<(String, Preset, bool)>> {
    let lamps = names.iter().any(|n| n == "lamps" || n == "physical+lamps");
    let plain: Vec<_> = names
        .iter()
        .filter(|n| *n != "lamps" && *n != "physical+lamps")
        .cloned()
        .collect();
    let mut out: Vec<(String, Preset, bool)> = if plain.is_empty() && lamps {
        Vec::new()
    } else {
        select_presets(&plain)?
            .into_iter()
            .map(|p| (p.name.to_string(), p, false))
            .collect()
    };
    if names.is_empty() || lamps {
        out.push(("physical + lamps".into(), PRESETS[3], true));
    }
    Ok(out)
}

/// Measures, checks, writes the report files and prints the Markdown; a failed check is
/// an error (non-zero exit).
pub(crate) fn run(b: BenchError, workers: usize) -> Result<()> {
    super::emit(&bench_error(b, workers)?)
}

fn bench_error(b: BenchError, workers: usize) -> Result<String> {
    if !b.max_spp.is_power_of_two() || b.max_spp < 4 {
        bail!("--max-spp must be a power of two, at least 4");
    }
    if b.reference_spp < 8 * b.max_spp {
        bail!(
            "--reference-spp must be at least 8 × --max-spp ({}): a reference noisier than an eighth of the least error it measures is rejected",
            8 * b.max_spp
        );
    }
    let path = match &b.path {
        Some(p) => CameraPath::load(p)?,
        None => CameraPath::thesis(),
    };
    let times = if b.views.is_empty() {
        vec![0.0, 9.0, 15.0]
    } else {
        b.views.clone()
    };
    if let Some(t) = times
        .iter()
        .find(|t| !(t.is_finite() && **t >= 0.0 && **t <= path.duration()))
    {
        bail!(
            "view time {t} s is outside the path (0 to {} s)",
            path.duration()
        );
    }
    let cases = cases(&b.presets)?;
    if let Some(unknown) = b.choices.iter().find(|k| Choice::from_key(k).is_none()) {
        bail!(
            "--choices: {unknown:?} is not one of {} or denoised-fade-F-T (0 < F < T)",
            CHOICES.map(Choice::key).join(", ")
        );
    }
    std::fs::create_dir_all(&b.out).with_context(|| format!("creating {}", b.out.display()))?;
    let ctx = app::gpu::context(&b.device, false)?;
    let (width, height) = b.size;
    let pixels = u64::from(width) * u64::from(height);
    let mut runs = Vec::new();
    let mut scenes = [None, None];
    for (name, preset, lamps) in &cases {
        let slot = usize::from(*lamps);
        if scenes[slot].is_none() {
            let mut scene = if *lamps {
                super::light_scenes::thesis_with_lamps(workers)?
            } else {
                app::builtin::thesis_scene(workers)?
            };
            scene.params.sun.animate = true;
            scene.params.sun.speed_deg_per_s = path.sun_deg_per_s;
            let session = Viewport::new(ctx.clone(), &scene.world.read())?;
            scenes[slot] = Some((scene, session));
        }
        let (scene, session) = scenes[slot].as_mut().expect("made above");
        let view = scene.world.read();
        let centre = view.dims().voxels().as_dvec3() * 0.5;
        let mut views = Vec::new();
        for &t in &times {
            let params = params_at(&scene.params, &path, preset, t, centre);
            let scene_variant = Variant::for_scene(&view, &params);
            let exposure = params.settings.exposure;
            eprintln!(
                "{name}, view at {t} s: reference of {} spp",
                b.reference_spp
            );
            // The defaults: scrambled Sobol (unbiased, and of far less noise per sample than
            // independent numbers, which would need many times the samples to stay an eighth
            // below what Sobol reaches at --max-spp).
            let v = Variant {
                sequence: b.reference_sequence,
                ..Choice::Default.apply(session, scene_variant)
            };
            let half = |seed| RenderJob {
                width,
                height,
                spp: b.reference_spp / 2,
                seed,
            };
            let how = RenderHow::variant(v);
            let (a, ta) = {
                let r = session.render(&view, &params, &half(1), how)?;
                (r.image, r.gpu_seconds)
            };
            let (c, tc) = {
                let r = session.render(&view, &params, &half(2), how)?;
                (r.image, r.gpu_seconds)
            };
            let noise = reference_noise(&a, &c).context("image sizes differ")?;
            let reference = average(&a, &c);
            let reference_srgb = srgb(&reference, exposure);
            let reference_flip = flip(&srgb(&a, exposure), &srgb(&c, exposure), (width, height));
            let file = b.out.join(format!(
                "reference_{}_t{t:04.1}s.png",
                name.replace([' ', '+'], "_")
            ));
            app::atomic::write_atomic(&file, |w| reference.write_png(w, exposure))?;
            let fades = b.choices.iter().filter_map(|k| match Choice::from_key(k) {
                Some(c @ Choice::DenoisedFade(..)) => Some(c),
                _ => None,
            });
            let choices: Vec<Choice> = CHOICES
                .into_iter()
                .filter(|c| {
                    *c == Choice::Default || b.choices.is_empty() || b.choices.contains(&c.key())
                })
                .chain(fades)
                .filter(|c| c.applies(session, scene_variant, pixels))
                .collect();
            let mut curves: Vec<Curve> = Vec::new();
            for &choice in &choices {
                eprintln!("  {}", choice.name());
                let v = choice.apply(session, scene_variant);
                if choice.changes_estimator() {
                    session.set_denoise_fade(choice.fade());
                    let levels = measure(
                        session,
                        &view,
                        &params,
                        (v, choice.denoised()),
                        (width, height),
                        b.max_spp,
                        (&reference, &reference_srgb, noise),
                    )?;
                    curves.push(judge(choice, v.sequence, levels));
                    continue;
                }
                // The same samples scheduled otherwise: the defaults' image up to rounding.
                let job = RenderJob {
                    width,
                    height,
                    spp: 4,
                    seed: 100,
                };
                let mine = session
                    .render(&view, &params, &job, RenderHow::variant(v))?
                    .image;
                let v0 = Choice::Default.apply(session, scene_variant);
                let theirs = session
                    .render(&view, &params, &job, RenderHow::variant(v0))?
                    .image;
                let same = rel_mse(&mine, &theirs).context("image sizes differ")?;
                if same > SAME_IMAGE {
                    bail!(
                        "{name}, view at {t} s: {} changes the image (relMSE {same:.2e} against the defaults'), so it needs its own error curve",
                        choice.name()
                    );
                }
                let mut curve = curves[0].clone();
                curve.choice = choice;
                curve.name = choice.name();
                curve.same_image_rel_mse = Some(same);
                curves.push(curve);
            }
            session.set_denoise_fade(None);
            eprintln!("  steady-state timing");
            let per_sample = steady_times(
                session,
                &view,
                &params,
                scene_variant,
                (width, height),
                &choices,
            )?;
            for (curve, ms) in curves.iter_mut().zip(per_sample) {
                curve.ms_per_sample = ms;
                for l in &mut curve.levels {
                    l.steady_ms = ms * f64::from(l.spp) + l.filter_ms * f64::from(l.batches);
                }
            }
            Choice::Default.apply(session, scene_variant);
            let least = curves
                .iter()
                .flat_map(|c| c.levels.iter().map(|l| l.rel_mse))
                .fold(f64::INFINITY, f64::min);
            if noise > least / 8.0 {
                bail!(
                    "{name}, view at {t} s: the reference's own relMSE {noise:.3e} is more than an eighth of the least error it measures ({least:.3e}); raise --reference-spp"
                );
            }
            views.push(ViewRun {
                time_s: t,
                reference_spp: b.reference_spp,
                reference_gpu_ms: (ta.unwrap_or(f64::NAN) + tc.unwrap_or(f64::NAN)) * 1e3,
                reference_noise: noise,
                reference_flip,
                curves,
            });
        }
        runs.push(CaseRun {
            name: name.clone(),
            preset: *preset,
            lamps: *lamps,
            views,
        });
    }
    drop(scenes);
    report::report(&b, &ctx, &runs)
}
