//! `voxbrick render`'s finished renders (`app::picture`): tiles, a noise target, alpha,
//! denoising, view presets, turntables and camera-path sequences, written as PNG (8 / 16
//! bit), EXR (half / float) or PFM, with a progress bar that says the time left (Ctrl + C
//! stops; files are written whole or not at all).

use super::emit;
use super::render::RenderArgs;
use anyhow::{Context, Result, bail};
use app::formats::picture::PictureFormat;
use app::picture::{Shot, along_path, content_bounds, render_shots, turntable};
use indicatif::{ProgressBar, ProgressStyle};
use render::finished::{Finish, Stop};

pub(crate) fn render_finished(a: RenderArgs, workers: usize) -> Result<()> {
    if a.device == "cpu" {
        bail!(
            "--noise, --alpha, --denoise, --view, sequences, tiles, EXR and 16-bit PNG are the GPU's (the CPU reference writes plain renders)"
        );
    }
    if a.hdr.is_some() {
        bail!(
            "--hdr is for plain renders: a finished render writes linear .exr or .pfm with --out"
        );
    }
    if a.scale != 1.0 {
        bail!("--scale is for plain renders (a finished render traces every pixel)");
    }
    let format = PictureFormat::of(&a.out, a.png16, a.half).map_err(anyhow::Error::msg)?;
    if a.alpha && format == PictureFormat::Pfm {
        bail!("a PFM has no alpha: write .png or .exr with --alpha");
    }
    // A missing folder is found before the render, not after it.
    let folder = a.out.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = folder.filter(|d| !d.is_dir()) {
        bail!(
            "{}: the folder {} does not exist",
            a.out.display(),
            dir.display()
        );
    }
    if a.turntable == Some(0) {
        bail!("--turntable wants at least one frame");
    }
    if !(a.fps.is_finite() && a.fps > 0.0 && a.fps <= 1000.0) {
        bail!("--fps {} is outside (0, 1000]", a.fps);
    }
    let stop = match a.noise {
        Some(target) => Stop::Noise {
            target,
            max: a.spp.max(2),
        },
        None => Stop::Samples(a.spp),
    };
    let finish = Finish {
        size: (a.width, a.height),
        stop,
        denoise: a.denoise,
        alpha: a.alpha,
        seed: a.seed,
        tile: a.tile,
    };
    finish.validate()?;
    let path = match &a.path {
        Some(p) => Some(app::camera_path::CameraPath::load(p)?),
        None => None,
    };
    let scene = super::with_progress(format!("reading {}", a.scene.display()), || {
        Ok(app::formats::load(&a.scene, workers)?)
    })?;
    let mut params = a.params(&scene)?;
    let view = scene.world.read();
    let bounds = content_bounds(&view);
    let aspect = a.width as f64 / a.height as f64;
    params.camera = a.view.camera(&params.camera, bounds, aspect);
    let pivot = (bounds.0 + bounds.1) * 0.5;
    let shots = if let Some(n) = a.turntable {
        turntable(&params, pivot, n, &a.out)
    } else if let Some(path) = &path {
        let centre = view.dims().voxels().as_dvec3() * 0.5;
        along_path(&params, path, a.fps, centre, &a.out)
    } else {
        vec![Shot {
            params,
            out: a.out.clone(),
        }]
    };
    let mut session = app::gpu::session(&a.device, &view)?;
    session
        .tracer()
        .set_samples_per_dispatch(a.samples_per_dispatch);
    session.tracer().set_sample_slices(a.slices);
    let name = session.ctx().name.clone();
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {percent:>3}% {elapsed} {msg}")
            .expect("valid template"),
    );
    let started = std::time::Instant::now();
    let rendered = render_shots(&mut session, &view, &shots, &finish, format, &mut |p| {
        bar.set_position((p.done * 1000.0) as u64);
        let left = p
            .remaining()
            .map_or(String::new(), |s| format!("{s:.0} s left"));
        bar.set_message(format!("tile {}/{} {left}", p.tile.0 + 1, p.tile.1));
        true
    })
    .with_context(|| format!("rendering on {name}"));
    bar.finish_and_clear();
    let rendered = rendered?;
    let seconds = started.elapsed().as_secs_f64();
    let lo = rendered.iter().map(|r| r.samples.0).min().unwrap_or(0);
    let hi = rendered.iter().map(|r| r.samples.1).max().unwrap_or(0);
    let gpu: Option<f64> = rendered.iter().map(|r| r.gpu_seconds).sum();
    let mut text = format!(
        "rendered     {} picture(s) of {}x{} ({} tile(s) each) on {name}, {} at {lo}..{hi} spp\ntime         {seconds:.2} s{}\n",
        rendered.len(),
        a.width,
        a.height,
        rendered.first().map_or(0, |r| r.tiles),
        format.label(),
        gpu.map_or(String::new(), |g| format!(
            " ({:.3} s on the GPU, timestamp queries)",
            g
        )),
    );
    if let Some(worst) = rendered.iter().filter_map(|r| r.noise).reduce(f64::max) {
        text += &format!("noise        {worst:.4} (the worst tile's estimate)\n");
    }
    for r in &rendered {
        text += &format!("wrote        {}\n", r.out.display());
    }
    emit(&text)
}
