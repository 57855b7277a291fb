//! `voxbrick render`: a scene to an image on the GPU session or the CPU reference.

use super::{emit, with_progress};
use anyhow::{Context, Result, bail};
use glam::DVec3;
use render::viewport::RenderHow;
use std::path::PathBuf;
use std::time::Instant;

/// `voxbrick render`'s arguments.
#[derive(clap::Args)]
pub(crate) struct RenderArgs {
    /// A .ron, .vox, .qb or .schem file (the last three get the default sun and sky).
    pub(crate) scene: PathBuf,
    /// Output image: .png, .exr or .pfm (a turntable or a path numbers it: NAME_0000.png…).
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Also write the linear image as PFM (for error measurement).
    #[arg(long)]
    pub(crate) hdr: Option<PathBuf>,
    /// Samples per pixel (with --noise: the most a tile takes).
    #[arg(long, default_value_t = 16)]
    pub(crate) spp: u32,
    /// Stop each tile at this relative noise (e.g. 0.02), estimated from two halves of its
    /// samples, or at --spp (GPU only).
    #[arg(long, value_name = "NOISE")]
    pub(crate) noise: Option<f64>,
    /// Filter the noise with the viewport's denoiser (GPU only).
    #[arg(long)]
    pub(crate) denoise: bool,
    /// A transparent background: alpha is the coverage of the camera rays by voxels (PNG,
    /// EXR; GPU only).
    #[arg(long)]
    pub(crate) alpha: bool,
    /// The view: scene (the scene's camera), or iso, front, side, top (orthographic,
    /// framing the content).
    #[arg(long, default_value = "scene", value_parser = app::picture::Preset::parse)]
    pub(crate) view: app::picture::Preset,
    /// 16 bits per channel for .png.
    #[arg(long)]
    pub(crate) png16: bool,
    /// Half floats for .exr (default: 32-bit floats).
    #[arg(long)]
    pub(crate) half: bool,
    /// A tile's side in pixels: larger pictures render tile by tile (GPU only).
    #[arg(long, default_value_t = 2048)]
    pub(crate) tile: u32,
    /// A turntable of N frames about the content's centre, from the camera's place.
    #[arg(long, value_name = "N", conflicts_with = "path")]
    pub(crate) turntable: Option<usize>,
    /// A camera path (the benchmark's RON format) rendered as a sequence at --fps.
    #[arg(long, value_name = "P.ron")]
    pub(crate) path: Option<PathBuf>,
    /// Frames per second of path time for --path.
    #[arg(long, default_value_t = 24.0)]
    pub(crate) fps: f64,
    /// Max bounces (default: the scene's setting).
    #[arg(long)]
    pub(crate) bounces: Option<u32>,
    /// Image width.
    #[arg(long, default_value_t = 512)]
    pub(crate) width: u32,
    /// Image height.
    #[arg(long, default_value_t = 288)]
    pub(crate) height: u32,
    /// Camera as EYE_X,EYE_Y,EYE_Z:TARGET_X,TARGET_Y,TARGET_Z (default: the scene's; for
    /// .vox, framing the whole scene).
    #[arg(long)]
    pub(crate) camera: Option<String>,
    /// An orthographic view H voxels tall (parallel rays from the plane through the eye).
    #[arg(long, value_name = "H")]
    pub(crate) orthographic: Option<f64>,
    /// gpu (the Vulkan path tracer on the best device), cpu (the reference path tracer), or
    /// part of a Vulkan device's name.
    #[arg(long, default_value = "gpu")]
    pub(crate) device: String,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Internal resolution as a fraction of the output (0 < F <= 1): paths are traced at
    /// ceil(W·F)×ceil(H·F) and upscaled bilinearly.
    #[arg(long, default_value_t = 1.0)]
    pub(crate) scale: f64,
    /// GPU: samples per pixel in one dispatch, 1..=16 (default: chosen from the image
    /// size).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub(crate) samples_per_dispatch: Option<u32>,
    /// GPU: invocations each pixel's samples are split among in one dispatch, 1..=8
    /// (default: enough for 0.6 M invocations, where the device has float atomics).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8))]
    pub(crate) slices: Option<u32>,
    /// GPU: the numbers samples are made from, sobol or independent (default: the scene's
    /// setting; the CPU reference always uses independent numbers).
    #[arg(long, value_parser = super::args::sequence)]
    pub(crate) sequence: Option<render::Sequence>,
}

pub(crate) fn render_command(a: RenderArgs, workers: usize) -> Result<()> {
    if a.spp == 0 || a.width == 0 || a.height == 0 || a.width > 16384 || a.height > 16384 {
        bail!("--spp, --width and --height must be positive (sizes at most 16384)");
    }
    if !(a.scale > 0.0 && a.scale <= 1.0) {
        bail!("--scale {} is outside (0, 1]", a.scale);
    }
    let scene = with_progress(format!("reading {}", a.scene.display()), || {
        Ok(app::formats::load(&a.scene, workers)?)
    })?;
    let params = a.params(&scene)?;
    let view = scene.world.read();
    let internal = (
        ((a.width as f64 * a.scale).ceil() as u32).max(1),
        ((a.height as f64 * a.scale).ceil() as u32).max(1),
    );
    let job = render::cpu::RenderJob {
        width: internal.0,
        height: internal.1,
        spp: a.spp,
        seed: a.seed,
    };
    let (image, backend, timing) = render_on(
        &a.device,
        &view,
        &params,
        &job,
        (a.samples_per_dispatch, a.slices),
    )?;
    let image = if internal == (a.width, a.height) {
        image
    } else {
        image.resized_bilinear(a.width, a.height)
    };
    let write = |path: &PathBuf, f: &dyn Fn(&mut dyn std::io::Write) -> std::io::Result<()>| {
        app::atomic::write_atomic(path, f).with_context(|| format!("writing {}", path.display()))
    };
    write(&a.out, &|w| image.write_png(w, params.settings.exposure))?;
    if let Some(hdr) = &a.hdr {
        write(hdr, &|w| image.write_pfm(w))?;
    }
    let samples = internal.0 as u64 * internal.1 as u64 * a.spp as u64;
    emit(&format!(
        "rendered     {samples} samples ({}x{} at {} spp, {} bounces) on {backend}, shown at {}x{}\n{timing}wrote        {}\n",
        internal.0,
        internal.1,
        a.spp,
        params.settings.max_bounces,
        a.width,
        a.height,
        a.out.display()
    ))
}

impl RenderArgs {
    /// Whether this is a finished render (`render::finished`: tiles, noise targets, alpha,
    /// denoising, presets, sequences, EXR and 16-bit PNG) rather than a plain one (which
    /// also runs on the CPU reference and counts rays).
    pub(crate) fn finished(&self) -> bool {
        let ext = self.out.extension().and_then(|e| e.to_str()).unwrap_or("");
        self.noise.is_some()
            || self.denoise
            || self.alpha
            || self.view != app::picture::Preset::Scene
            || self.png16
            || self.turntable.is_some()
            || self.path.is_some()
            || !ext.eq_ignore_ascii_case("png")
            || self.width.max(self.height) > self.tile
    }

    /// The scene's parameters with the camera, projection, bounces and sequence asked for.
    pub(crate) fn params(&self, scene: &app::scene::Scene) -> Result<render::SceneParams> {
        let mut params = scene.params.clone();
        if let Some(spec) = &self.camera {
            let (eye, target) = spec
                .split_once(':')
                .context("--camera wants EYE:TARGET, each X,Y,Z")?;
            let eye = parse_ivec3_f(eye)?;
            let target = parse_ivec3_f(target)?;
            let aimed =
                render::Camera::aimed(eye, target, params.camera.fov_y_deg).context("--camera")?;
            params.camera = render::Camera {
                projection: params.camera.projection,
                ..aimed
            };
        }
        if let Some(height) = self.orthographic {
            params.camera.projection = render::Projection::Orthographic { height };
        }
        params
            .camera
            .validate()
            .context("--camera / --orthographic")?;
        if let Some(b) = self.bounces {
            if !(1..=64).contains(&b) {
                bail!("--bounces {b} is outside 1..=64");
            }
            params.settings.max_bounces = b;
        }
        if let Some(q) = self.sequence {
            params.settings.sequence = q;
        }
        Ok(params)
    }
}

pub(crate) fn parse_ivec3_f(s: &str) -> Result<DVec3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("{s:?} is not X,Y,Z"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(DVec3::new(x, y, z)),
        _ => bail!("{s:?} is not three finite numbers X,Y,Z"),
    }
}

/// Renders on a device: "cpu" (the reference), "gpu" (the best Vulkan device) or part of a
/// device's name. Returns the image, the device's name and a timing report.
pub(crate) fn render_on(
    device: &str,
    view: &brickmap::WorldView<'_>,
    params: &render::SceneParams,
    job: &render::cpu::RenderJob,
    (samples_per_dispatch, slices): (Option<u32>, Option<u32>),
) -> Result<(render::Image, String, String)> {
    let started = Instant::now();
    Ok(if device == "cpu" {
        let cpu = render::cpu::CpuScene::new(view, params);
        let image = with_progress(
            format!(
                "rendering {}x{} at {} spp on the CPU",
                job.width, job.height, job.spp
            ),
            || Ok(cpu.render(job)),
        )?;
        let seconds = started.elapsed().as_secs_f64();
        let rays = cpu.rays_traced();
        (
            image,
            "the CPU".to_string(),
            format!(
                "time         {seconds:.2} s\nrays         {rays} ({:.2} Mrays/s)\n",
                rays as f64 / seconds / 1e6
            ),
        )
    } else {
        let mut session = app::gpu::session(device, view)?;
        session
            .tracer()
            .set_samples_per_dispatch(samples_per_dispatch);
        session.tracer().set_sample_slices(slices);
        let name = session.ctx().name.clone();
        let rendered = with_progress(
            format!(
                "rendering {}x{} at {} spp on {name}",
                job.width, job.height, job.spp
            ),
            || Ok(session.render(view, params, job, RenderHow::SCENE.counted())?),
        )?;
        let (image, gpu, rays) = (
            rendered.image,
            rendered.gpu_seconds,
            rendered.rays.expect("counted"),
        );
        let timing = match gpu {
            Some(t) => format!(
                "gpu time     {:.3} ms (timestamp queries)\nrays         {} ({:.1} Mrays/s: {} primary, {} secondary, {} shadow)\n",
                t * 1e3,
                rays.total(),
                rays.total() as f64 / t / 1e6,
                rays.primary,
                rays.secondary,
                rays.shadow
            ),
            None => format!(
                "time         {:.2} s (this queue cannot take timestamps)\n",
                started.elapsed().as_secs_f64()
            ),
        };
        (image, name, timing)
    })
}
