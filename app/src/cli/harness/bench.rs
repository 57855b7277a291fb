//! `voxbrick bench`: the thesis benchmark along a camera path. For each preset (the thesis's
//! complexities 1 / 2 / 3 and "physical": 8 bounces, sun, 4 spp) and internal resolution,
//! every frame of the path is timed on the GPU (Vulkan timestamps: the median of a few
//! back-to-back dispatches of that frame, after warm-up), rays are counted by kind on every
//! tenth frame; the CPU reference renders the same path at a small size (wall clock); then a
//! sculpting stroke edits the world every frame while the path plays (bytes uploaded, GPU
//! frame time, edit → first frame showing it). Writes bench.json, bench.md and one PNG plot
//! of frame time along the path per resolution.

use super::plot::{Series, line_plot};
mod runs;

use super::table::Table;
use super::{args, emit};
use anyhow::{Context, Result, bail};
use app::camera_path::CameraPath;
use app::scene::Scene;
use brickmap::{EditOp, Mode, Shape};
use glam::DVec3;
use render::SceneParams;
use render::cpu::{CpuScene, RenderJob};
use render::viewport::{FrameRequest, RenderHow, Viewport};
use render::vulkan::trace::Variant;
use runs::{cpu_run, edit_run, gpu_run};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// What `bench` runs.
#[derive(clap::Args)]
pub(crate) struct Bench {
    /// Device name filter ("gpu": the best).
    #[arg(long, default_value = "gpu")]
    device: String,
    /// A camera path file (RON; default: the built-in thesis path, assets/bench).
    #[arg(long)]
    path: Option<PathBuf>,
    /// Frames along the path, evenly spaced in path time.
    #[arg(long, default_value_t = 240)]
    frames: usize,
    /// Back-to-back dispatches per frame (their median is the frame's time).
    #[arg(long, default_value_t = 5)]
    repeat: u32,
    /// Internal resolutions, WxH, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1024x576,1920x1080", value_parser = args::resolution)]
    sizes: Vec<(u32, u32)>,
    /// Presets to run (complexity-1, complexity-2, complexity-3, physical; default all).
    #[arg(long, value_delimiter = ',')]
    presets: Vec<String>,
    /// CPU reference resolution.
    #[arg(long, default_value = "128x72", value_parser = args::resolution)]
    cpu_size: (u32, u32),
    /// CPU reference frames along the path (0: none).
    #[arg(long, default_value_t = 24)]
    cpu_frames: usize,
    /// Sculpting while rendering: sphere radii, comma-separated (empty: none).
    #[arg(long, value_delimiter = ',', default_value = "16,64")]
    edit_radii: Vec<f64>,
    /// Edits (frames) per radius.
    #[arg(long, default_value_t = 120)]
    edit_frames: usize,
    /// Size of the keyframe views (views/*.png), WxH.
    #[arg(long, default_value = "320x180", value_parser = args::resolution)]
    view_size: (u32, u32),
    /// Samples per pixel of the keyframe views.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=4096))]
    view_spp: u32,
    /// Folder for the report.
    #[arg(long, default_value = "bench-report")]
    out: PathBuf,
}

/// A renderer setting of the benchmark.
#[derive(Clone, Copy, Debug, Serialize)]
pub(crate) struct Preset {
    pub(crate) name: &'static str,
    pub(crate) bounces: u32,
    pub(crate) spp: u32,
    pub(crate) sun: bool,
}

/// The thesis's complexities and the physical preset.
pub(crate) const PRESETS: [Preset; 4] = [
    Preset {
        name: "complexity 1",
        bounces: 1,
        spp: 1,
        sun: false,
    },
    Preset {
        name: "complexity 2",
        bounces: 1,
        spp: 1,
        sun: true,
    },
    Preset {
        name: "complexity 3",
        bounces: 3,
        spp: 2,
        sun: true,
    },
    Preset {
        name: "physical",
        bounces: 8,
        spp: 4,
        sun: true,
    },
];

/// Order statistics of a list of milliseconds.
#[derive(Clone, Copy, Debug, Serialize)]
pub(crate) struct Summary {
    pub(crate) min: f64,
    pub(crate) median: f64,
    pub(crate) p99: f64,
    pub(crate) max: f64,
    pub(crate) mean: f64,
}

impl Summary {
    /// Min, median, p99 and max by `bench_viewport::stats`' order statistics, and the mean.
    pub(crate) fn of(v: &[f64]) -> Summary {
        let (min, median, p99, max) = super::bench_viewport::stats(v.to_vec());
        Summary {
            min,
            median,
            p99,
            max,
            mean: if v.is_empty() {
                f64::NAN
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            },
        }
    }
}

#[derive(Serialize)]
struct Rates {
    primary: f64,
    secondary: f64,
    shadow: f64,
    all: f64,
}

#[derive(Serialize)]
struct GpuRun {
    preset: Preset,
    width: u32,
    height: u32,
    path_time_s: Vec<f64>,
    frame_ms: Vec<f64>,
    summary: Summary,
    /// Millions of rays per second by kind, over the counted frames.
    mrays_per_s: Rates,
    /// Rays per pixel per frame by kind, over the counted frames.
    rays_per_pixel: Rates,
    traversal_caps_hit: u64,
}

#[derive(Serialize)]
struct CpuRun {
    preset: Preset,
    width: u32,
    height: u32,
    path_time_s: Vec<f64>,
    frame_ms: Vec<f64>,
    summary: Summary,
    /// Millions of samples (paths) per second.
    msamples_per_s: f64,
}

#[derive(Serialize)]
struct EditRun {
    radius: f64,
    width: u32,
    height: u32,
    edits: usize,
    /// Host time to apply one stroke sphere (workers, undo records, dirty ranges).
    apply_ms: Summary,
    /// Bytes uploaded per frame while editing.
    uploaded_bytes_per_frame: Summary,
    /// Bytes uploaded per edit (every frame until it shows).
    uploaded_bytes_per_edit: Summary,
    /// GPU time of the frames while editing.
    frame_ms: Summary,
    /// Frames from the edit's first frame to the first showing all of it.
    latency_frames: Summary,
    /// Wall time from applying the edit to that frame finishing on the GPU.
    latency_ms: Summary,
}

/// Scene statistics for the report.
fn scene_stats(scene: &Scene) -> serde_json::Value {
    let view = scene.world.read();
    let m = view.memory();
    let v = scene.world.dims().voxels();
    serde_json::json!({
        "name": "thesis",
        "voxels": [v.x, v.y, v.z],
        "solid_voxels": view.solid_count(),
        "stored_bricks": view.brick_count(),
        "full_cells": m.full_cells,
        "materials": view.materials().len(),
        "light_faces": view.lights().len(),
        "gpu_bytes": m.gpu_used(),
    })
}

/// The GPU's clocks from nvidia-smi, where there is one.
pub(crate) fn clocks() -> Option<String> {
    let out = std::process::Command::new("nvidia-smi")
        .args([
            "--query-gpu=clocks.sm,clocks.max.sm,clocks.mem,power.draw,temperature.gpu",
            "--format=csv,noheader",
        ])
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// A preset's frame times along the path, as a plot series.
fn path_series(preset: &Preset, times: &[f64], ms: &[f64]) -> Series {
    Series {
        name: preset.name.to_string(),
        points: times.iter().copied().zip(ms.iter().copied()).collect(),
    }
}

/// The presets named in `names` (all when empty; "complexity-1" or "complexity 1").
pub(crate) fn select_presets(names: &[String]) -> Result<Vec<Preset>> {
    let presets: Vec<Preset> = PRESETS
        .iter()
        .filter(|p| {
            names.is_empty()
                || names
                    .iter()
                    .any(|n| n == p.name || n.replace('-', " ") == p.name)
        })
        .copied()
        .collect();
    if presets.is_empty() {
        bail!("no preset named {names:?} (complexity-1, complexity-2, complexity-3, physical)");
    }
    Ok(presets)
}

/// The scene's parameters for `preset` at path time `t`.
pub(crate) fn params_at(
    base: &SceneParams,
    path: &CameraPath,
    preset: &Preset,
    t: f64,
    centre: DVec3,
) -> SceneParams {
    let mut p = base.clone();
    p.settings.max_bounces = preset.bounces;
    p.camera = path.camera_at(t, base.camera.fov_y_deg);
    p.sun = path.sun_at(&base.sun, t, centre);
    p.sun.enabled = preset.sun;
    p
}

/// A summary's five cells: min, median, p99, max, mean.
fn summary_cells(s: &Summary) -> [String; 5] {
    [s.min, s.median, s.p99, s.max, s.mean].map(|x| format!("{x:.3}"))
}

/// Runs the benchmark, writes the report files and prints the Markdown.
pub(crate) fn run(mut b: Bench, workers: usize) -> Result<()> {
    if b.edit_radii
        .iter()
        .any(|r| !(r.is_finite() && *r > 0.0 && *r <= 256.0))
    {
        bail!("--edit-radii must be in (0, 256]");
    }
    b.frames = b.frames.max(1);
    b.repeat = b.repeat.max(1);
    b.edit_frames = b.edit_frames.max(1);
    emit(&bench(b, workers)?)
}

/// Runs the benchmark; writes the report files and returns the Markdown.
fn bench(b: Bench, workers: usize) -> Result<String> {
    let path = match &b.path {
        Some(p) => CameraPath::load(p)?,
        None => CameraPath::thesis(),
    };
    let presets = select_presets(&b.presets)?;
    let mut scene = app::builtin::thesis_scene(workers)?;
    // The path's sun circles the scene; the scene's own sun gives its height and distance.
    scene.params.sun.animate = true;
    scene.params.sun.speed_deg_per_s = path.sun_deg_per_s;
    let stats = scene_stats(&scene);
    let mut session = {
        let view = scene.world.read();
        app::gpu::session(&b.device, &view)?
    };
    let ctx = session.ctx().clone();
    let clocks_before = clocks();
    let mut gpu = Vec::new();
    for &size in &b.sizes {
        for preset in &presets {
            eprintln!("GPU {} at {}x{}", preset.name, size.0, size.1);
            gpu.push(gpu_run(
                &mut session,
                &scene,
                &path,
                preset,
                size,
                b.frames,
                b.repeat,
            )?);
        }
    }
    let clocks_after = clocks();
    // What the path shows: each keyframe's view at complexity 3 (by default 16 spp,
    // 320 × 180).
    std::fs::create_dir_all(b.out.join("views"))
        .with_context(|| format!("creating {}", b.out.display()))?;
    {
        let view = scene.world.read();
        let centre = view.dims().voxels().as_dvec3() * 0.5;
        for k in &path.keyframes {
            let p = params_at(&scene.params, &path, &PRESETS[2], k.time_s, centre);
            let job = RenderJob::sized(b.view_size, b.view_spp, 1);
            let img = session.render(&view, &p, &job, RenderHow::SCENE)?.image;
            let file = b.out.join("views").join(format!("t{:04.1}s.png", k.time_s));
            app::atomic::write_atomic(&file, |w| img.write_png(w, p.settings.exposure))?;
        }
    }
    let mut cpu = Vec::new();
    if b.cpu_frames > 0 {
        for preset in &presets {
            eprintln!("CPU {} at {}x{}", preset.name, b.cpu_size.0, b.cpu_size.1);
            cpu.push(cpu_run(&scene, &path, preset, b.cpu_size, b.cpu_frames));
        }
    }
    let mut edits = Vec::new();
    for &r in &b.edit_radii {
        eprintln!("editing: spheres of radius {r}");
        edits.push(edit_run(
            &mut session,
            &scene,
            &path,
            r,
            b.sizes[0],
            b.edit_frames,
        )?);
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let json = serde_json::json!({
        "device": ctx.name,
        "driver": ctx.driver,
        "clocks_before": clocks_before,
        "clocks_after": clocks_after,
        "clocks_fields": "sm MHz, max sm MHz, memory MHz, power, temperature (nvidia-smi)",
        "cpu_threads": threads,
        "scene": stats,
        "path": { "duration_s": path.duration(), "keyframes": path.keyframes.len(), "sun_deg_per_s": path.sun_deg_per_s, "frames": b.frames, "dispatches_per_frame": b.repeat },
        "gpu": gpu,
        "cpu": cpu,
        "editing": edits,
    });
    std::fs::create_dir_all(&b.out).with_context(|| format!("creating {}", b.out.display()))?;
    super::write_json(&b.out.join("bench.json"), &json)?;

    // Markdown.
    let scene_line = format!(
        "{} solid voxels, {} stored bricks, {} full cells, {} materials, {} GPU bytes",
        stats["solid_voxels"],
        stats["stored_bricks"],
        stats["full_cells"],
        stats["materials"],
        stats["gpu_bytes"]
    );
    let mut md = format!(
        "device: {} ({}); clocks before / after (sm, max sm, memory, power, temperature): {} / {}\n\
         scene: thesis, {}; path: {} keyframes over {:.1} s, {} frames, each the median of {} back-to-back dispatches (GPU timestamps); the sun circles at {}°/s\n\n",
        ctx.name,
        ctx.driver,
        json["clocks_before"].as_str().unwrap_or("n/a"),
        json["clocks_after"].as_str().unwrap_or("n/a"),
        scene_line,
        path.keyframes.len(),
        path.duration(),
        b.frames,
        b.repeat,
        path.sun_deg_per_s
    );
    let mut table = Table::new(&[
        "preset",
        "internal",
        "min ms",
        "median ms",
        "p99 ms",
        "max ms",
        "mean ms",
        "Mrays/s primary",
        "secondary",
        "shadow",
        "all",
        "rays/pixel",
        "caps hit",
    ]);
    for g in &gpu {
        let r = &g.mrays_per_s;
        table.row_of(
            [
                g.preset.name.to_string(),
                format!("{}x{}", g.width, g.height),
            ]
            .into_iter()
            .chain(summary_cells(&g.summary))
            .chain([r.primary, r.secondary, r.shadow, r.all].map(|x| format!("{x:.1}")))
            .chain([
                format!("{:.2}", g.rays_per_pixel.all),
                g.traversal_caps_hit.to_string(),
            ]),
        );
    }
    md += &table.finish();
    if !cpu.is_empty() {
        md += &format!("\nCPU reference ({threads} threads, wall clock):\n\n");
        let mut table = Table::new(&[
            "preset",
            "size",
            "min ms",
            "median ms",
            "p99 ms",
            "max ms",
            "mean ms",
            "Msamples/s",
        ]);
        for c in &cpu {
            table.row_of(
                [
                    c.preset.name.to_string(),
                    format!("{}x{}", c.width, c.height),
                ]
                .into_iter()
                .chain(summary_cells(&c.summary))
                .chain([format!("{:.3}", c.msamples_per_s)]),
            );
        }
        md += &table.finish();
    }
    if !edits.is_empty() {
        md += "\nSculpting while the path plays (complexity 3, 1 spp per frame; one sphere per edit; median / p99 / max):\n\n";
        let mut table = Table::new(&[
            "radius",
            "internal",
            "edits",
            "apply ms",
            "uploaded bytes per frame",
            "per edit",
            "GPU frame ms",
            "latency frames",
            "latency ms",
        ]);
        for e in &edits {
            let m =
                |s: &Summary, d: usize| format!("{:.d$} / {:.d$} / {:.d$}", s.median, s.p99, s.max);
            table.row(&[
                &e.radius,
                &format!("{}x{}", e.width, e.height),
                &e.edits,
                &m(&e.apply_ms, 2),
                &m(&e.uploaded_bytes_per_frame, 0),
                &m(&e.uploaded_bytes_per_edit, 0),
                &m(&e.frame_ms, 3),
                &m(&e.latency_frames, 0),
                &m(&e.latency_ms, 2),
            ]);
        }
        md += &table.finish();
    }
    super::write_report(&b.out.join("bench.md"), &md)?;

    // Plots: frame time along the path, one per resolution (and the CPU's).
    for &size in &b.sizes {
        let series: Vec<Series> = gpu
            .iter()
            .filter(|g| (g.width, g.height) == size)
            .map(|g| path_series(&g.preset, &g.path_time_s, &g.frame_ms))
            .collect();
        line_plot(
            &b.out.join(format!("frame_time_{}x{}.png", size.0, size.1)),
            (1000, 560),
            &format!("{} — thesis path at {}x{}", ctx.name, size.0, size.1),
            ("path time (s)", "GPU frame time (ms)"),
            &series,
        )?;
    }
    if !cpu.is_empty() {
        let series: Vec<Series> = cpu
            .iter()
            .map(|c| path_series(&c.preset, &c.path_time_s, &c.frame_ms))
            .collect();
        line_plot(
            &b.out.join("frame_time_cpu.png"),
            (1000, 560),
            &format!(
                "CPU reference ({threads} threads) — thesis path at {}x{}",
                b.cpu_size.0, b.cpu_size.1
            ),
            ("path time (s)", "frame time (ms, wall clock)"),
            &series,
        )?;
    }
    if ctx.validation_errors() > 0 {
        bail!("{} validation errors", ctx.validation_errors());
    }
    Ok(md)
}
