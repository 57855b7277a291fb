//! `voxbrick`: the voxel scene editor. Without a subcommand it opens the editor window (on
//! a file, or the built-in default scene); subcommands build, convert, inspect, render,
//! replay and benchmark scenes headlessly.
//!
//! In detail:
//! clap CLI: no subcommand opens the editor (a file or the default scene; `--script`,
//! `--capture`, `--window`, `--validation`, `--record`: the session as a replay script from a
//! copy of the file, carried across File → Open with a copy of each opened file beside it);
//! `stats`, `new`, `convert`, `info`, `render`, `replay`, `bench-gpu`, `bench-viewport`;
//! one-line errors.

mod cli;

use cli::bench_gpu::{BenchGpu, bench_gpu};
use cli::render::{RenderArgs, render_command, render_on};
use cli::stats::{print_stats, stats_text};
use cli::{emit, with_progress};

use anyhow::{Context, Result, bail};
use app::Scene;
use app::formats::{self, Format};
use app::scene::{SceneSize, default_scene, terrain_materials, thesis_scene, thesis_terrain};
use brickmap::GridDims;
use brickmap::terrain::{NoiseKind, NoiseTerrain};
use clap::{Parser, Subcommand, ValueEnum};
use glam::IVec3;
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(
    name = "voxbrick",
    version,
    about = "Voxel scene editor with a path-traced viewport",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    /// Worker threads for the voxel world (0: one per core).
    #[arg(long, global = true, default_value_t = 0)]
    workers: usize,
    #[command(flatten)]
    editor: EditorArgs,
    #[command(subcommand)]
    command: Option<Command>,
}

/// The editor window (no subcommand).
#[derive(clap::Args)]
struct EditorArgs {
    /// A scene to open (.ron or .vox); default: the built-in default scene.
    file: Option<PathBuf>,
    /// Run a replay script's steps in the live editor, capture the presented frame and exit.
    #[arg(long)]
    script: Option<PathBuf>,
    /// With --script: write the presented frame here (PNG).
    #[arg(long, requires = "script")]
    capture: Option<PathBuf>,
    /// With --script: samples per pixel before the capture.
    #[arg(long, default_value_t = 16)]
    capture_spp: u32,
    /// With --script: keep the window open this many milliseconds after the capture.
    #[arg(long, default_value_t = 0)]
    linger_ms: u64,
    /// Window size in pixels, as WxH.
    #[arg(long, value_parser = parse_window_size, default_value = "1280x720")]
    window: (u32, u32),
    /// Vulkan device: gpu (the best) or part of a device's name.
    #[arg(long, default_value = "gpu")]
    device: String,
    /// Enable the Vulkan validation layer (the editor exits non-zero on any validation
    /// error).
    #[arg(long)]
    validation: bool,
    /// Record the session's edits (strokes, commands, undo, redo, saves) as a replay script,
    /// written here when the editor exits (needs FILE: the script starts from it).
    #[arg(long, requires = "file", conflicts_with = "script")]
    record: Option<PathBuf>,
}

fn parse_window_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("{s:?} is not WxH"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|n| (64..=16384).contains(n))
            .ok_or_else(|| format!("{v:?} is not a size in 64..=16384"))
    };
    Ok((parse(w)?, parse(h)?))
}

#[derive(Subcommand)]
enum Command {
    /// Build the built-in default scene and print its statistics.
    Stats {
        /// Scene size.
        #[arg(long, value_enum, default_value = "full")]
        size: SceneSize,
    },
    /// Convert between project (.ron) and MagicaVoxel (.vox) files.
    Convert {
        /// Input file (.ron or .vox).
        input: PathBuf,
        /// Output file (.ron or .vox); replaced atomically.
        output: PathBuf,
        /// Offset added to imported .vox voxels, as X,Y,Z.
        #[arg(long, value_parser = parse_ivec3, default_value = "0,0,0")]
        offset: IVec3,
        /// Import nodes on hidden layers too.
        #[arg(long)]
        include_hidden: bool,
    },
    /// Create a new scene file.
    New {
        /// A noise terrain with water (the parameters below).
        #[arg(long, conflicts_with = "thesis")]
        terrain: bool,
        /// The thesis benchmark scene: 512×256×512 terrain, water and a metal statue.
        #[arg(long)]
        thesis: bool,
        /// Grid size in voxels, as WxHxD (multiples of 8 are used as they are).
        #[arg(long, value_parser = parse_size, default_value = "512x256x512")]
        size: IVec3,
        /// Noise seed.
        #[arg(long, default_value_t = 2022)]
        seed: u32,
        /// Noise function.
        #[arg(long, value_enum, default_value = "perlin")]
        noise: Noise,
        /// Wavelength of the first octave, in voxels.
        #[arg(long)]
        scale: Option<f64>,
        /// Octaves of fractal noise (1..=12).
        #[arg(long, default_value_t = 5)]
        octaves: u32,
        /// Lowest surface height in voxels.
        #[arg(long)]
        height_min: Option<u32>,
        /// Highest surface height in voxels.
        #[arg(long)]
        height_max: Option<u32>,
        /// Water level in voxels (0: none).
        #[arg(long)]
        water_level: Option<u32>,
        /// Output file (.ron or .vox).
        output: PathBuf,
    },
    /// Render a scene offscreen to an image.
    Render(RenderArgs),
    /// The soak test: a long seeded random session (strokes of every mode and shape, selections,
    /// clipboard, palette, terrain, undo / redo bursts, camera, panels, resizes, saves and
    /// re-opens) fed to a headless editor as window input events, or to its edit thread,
    /// checked after every input; on a failure, the seed and the shortest failing prefix as a
    /// replay script.
    Soak(cli::soak::SoakArgs),
    /// Replay an edit script headlessly, reporting each step; exits non-zero at the first
    /// failed step.
    Replay {
        /// The script (.ron).
        script: PathBuf,
        /// Save the final scene here (.ron or .vox).
        #[arg(long)]
        save: Option<PathBuf>,
        /// Render the final scene to this PNG (CPU: needs --device cpu).
        #[arg(long)]
        render: Option<PathBuf>,
        /// Where the script's outputs go (default: next to the script).
        #[arg(long)]
        out_dir: Option<PathBuf>,
        /// Render device for render steps: gpu or cpu.
        #[arg(long, default_value = "gpu")]
        device: String,
    },
    /// The editor's frame loop without a window (frames in flight, trace and display) on the
    /// thesis scene: GPU and host time per frame, camera move to first frame.
    BenchViewport {
        /// Output (window) size, as WxH.
        #[arg(long, value_parser = parse_window_size, default_value = "1920x1080")]
        size: (u32, u32),
        /// Internal scales, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "0.5,1.0")]
        scales: Vec<f32>,
        /// Timed frames per case.
        #[arg(long, default_value_t = 200)]
        frames: usize,
        /// Samples per pixel each frame adds.
        #[arg(long, default_value_t = 1)]
        spp: u32,
        /// Vulkan device (part of its name).
        #[arg(long)]
        device: Option<String>,
        /// Also measure the window's half: the copy into an offscreen image of the window's
        /// size and egui panels painted on it.
        #[arg(long)]
        ui: bool,
        /// Also measure each case with the viewport's denoiser on.
        #[arg(long)]
        denoise: bool,
        /// Instead: edit → first frame showing it, on the default 512 × 256 × 512 scene, for
        /// live sphere strokes of these radii (comma-separated), and the brush preview's
        /// update time.
        #[arg(long, value_delimiter = ',')]
        edits: Vec<f64>,
    },
    /// Time the GPU path tracer on the thesis scene with Vulkan timestamp queries: medians
    /// after warm-up for the thesis's complexities 1, 2 and 3.
    BenchGpu {
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
        /// Samples per pixel of the convergence reference.
        #[arg(long, default_value_t = 4096)]
        reference_spp: u32,
        /// Invocations each pixel's samples are split among, 1..=8 (default: the renderer's
        /// choice for the image size).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8))]
        slices: Option<u32>,
    },
    /// The thesis benchmark along a camera path: GPU frame times (Vulkan timestamps) per
    /// preset (complexity 1, 2, 3, physical) and internal resolution, rays per second by
    /// kind, the CPU reference at a small size, and sculpting while the path plays; writes
    /// bench.json, bench.md and frame-time plots (PNG) into --out.
    Bench {
        /// Device name filter ("gpu": the best).
        #[arg(long, default_value = "gpu")]
        device: String,
        /// A camera path file (RON; default: the built-in thesis path, assets/bench).
        #[arg(long)]
        path: Option<PathBuf>,
        /// Frames along the path.
        #[arg(long, default_value_t = 240)]
        frames: usize,
        /// Back-to-back dispatches per frame (their median is the frame's time).
        #[arg(long, default_value_t = 5)]
        repeat: u32,
        /// Internal resolutions, WxH, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "1024x576,1920x1080", value_parser = parse_resolution)]
        sizes: Vec<(u32, u32)>,
        /// Presets to run (complexity-1, complexity-2, complexity-3, physical; default all).
        #[arg(long, value_delimiter = ',')]
        presets: Vec<String>,
        /// CPU reference resolution.
        #[arg(long, default_value = "128x72", value_parser = parse_resolution)]
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
        /// Folder for the report.
        #[arg(long, default_value = "bench-report")]
        out: PathBuf,
    },
    /// Image error against samples and GPU time at views along the benchmark path: every
    /// preset and sampling choice, relMSE and FLIP against a converged reference whose own
    /// noise is measured, slope and bias checks, efficiency at equal error. Writes
    /// error.csv, error.md, error.json and log-log plots; exits non-zero if a check fails.
    BenchError {
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
        #[arg(long, default_value = "512x288", value_parser = parse_resolution)]
        size: (u32, u32),
        /// Samples of each reference (at least 8 × --max-spp).
        #[arg(long, default_value_t = 8192)]
        reference_spp: u32,
        /// The most samples per pixel measured (a power of two, 4 or more).
        #[arg(long, default_value_t = 256)]
        max_spp: u32,
        /// The references' numbers: sobol (the renderer's default) or independent.
        #[arg(long, default_value = "sobol", value_parser = cli::parse_sequence)]
        reference_sequence: render::Sequence,
        /// Presets (complexity-1, complexity-2, complexity-3, physical, lamps; default all).
        #[arg(long, value_delimiter = ',')]
        presets: Vec<String>,
        /// Folder for the report.
        #[arg(long, default_value = "error-report")]
        out: PathBuf,
    },
    /// What each skip buys: the pipeline variants, the coarse-grid and in-brick empty-space
    /// skips, uniform media, full cells, accumulation when still and the lower resolution while
    /// moving, with and without each, on the thesis scene and on a scene that needs it. Writes
    /// skips.md and skips.json.
    BenchSkips {
        /// Device name filter ("gpu": the best).
        #[arg(long, default_value = "gpu")]
        device: String,
        /// Internal resolution of the traversal and pipeline cases, WxH.
        #[arg(long, default_value = "1024x576", value_parser = parse_resolution)]
        size: (u32, u32),
        /// Window size of the moving-resolution case, WxH.
        #[arg(long, default_value = "1920x1080", value_parser = parse_resolution)]
        window: (u32, u32),
        /// Timed rounds of 10 dispatches per variant (after two of warm-up).
        #[arg(long, default_value_t = 5)]
        rounds: usize,
        /// Folder for the report.
        #[arg(long, default_value = "skips-report")]
        out: PathBuf,
    },
    /// The numerical stress suite: random and adversarial rays through the GPU traversal
    /// against the exact CPU ray cast, and adversarial scenes' images (NaN, infinite and
    /// negative samples, white-furnace energy, iteration caps) on the GPU and the CPU
    /// reference. Exits non-zero if any count is not zero.
    Stress {
        /// Rays per class and world (12 classes, 2 worlds).
        #[arg(long, default_value_t = 250_000)]
        rays: usize,
        /// GPU images: width and height.
        #[arg(long, default_value_t = 128)]
        size: u32,
        /// GPU images: one-sample renders per view.
        #[arg(long, default_value_t = 64)]
        renders: u32,
        /// CPU reference images: width and height.
        #[arg(long, default_value_t = 32)]
        cpu_size: u32,
        /// CPU reference images: one-sample renders per view.
        #[arg(long, default_value_t = 8)]
        cpu_renders: u32,
        /// Seed of the rays and samples.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Device name filter ("gpu": the best), or "cpu": only the CPU reference's images.
        #[arg(long, default_value = "gpu")]
        device: String,
        /// Also count validation-layer errors (each is a failure).
        #[arg(long)]
        validation: bool,
        /// Folder to write stress.json and stress.md into.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Print a scene file's dimensions, voxel count, materials and memory.
    Info {
        /// A .ron or .vox file.
        file: PathBuf,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum Noise {
    Perlin,
    OpenSimplex,
    SuperSimplex,
    Value,
}

fn parse_ivec3(s: &str) -> Result<IVec3, String> {
    let v: Vec<i32> = s
        .split(',')
        .map(|p| p.trim().parse::<i32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))?;
    match v[..] {
        [x, y, z] => Ok(IVec3::new(x, y, z)),
        _ => Err(format!("{s:?}: expected three integers X,Y,Z")),
    }
}

fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    match s
        .split_once('x')
        .map(|(w, h)| (w.trim().parse::<u32>(), h.trim().parse::<u32>()))
    {
        Some((Ok(w), Ok(h))) if (1..=8192).contains(&w) && (1..=8192).contains(&h) => Ok((w, h)),
        _ => Err(format!("{s:?}: expected WxH, each 1..=8192")),
    }
}

fn parse_size(s: &str) -> Result<IVec3, String> {
    let v: Vec<i32> = s
        .split('x')
        .map(|p| p.trim().parse::<i32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))?;
    match v[..] {
        [x, y, z] if x > 0 && y > 0 && z > 0 => Ok(IVec3::new(x, y, z)),
        _ => Err(format!("{s:?}: expected three positive integers WxHxD")),
    }
}

fn main() -> std::process::ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // Help and version go to stdout as clap prints them.
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            let text = e.to_string();
            let first = text.lines().next().unwrap_or("invalid arguments");
            eprintln!(
                "voxbrick: {} (see voxbrick --help)",
                first.trim_start_matches("error: ")
            );
            return std::process::ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("voxbrick: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    let workers = cli.workers;
    let Some(command) = cli.command else {
        let e = cli.editor;
        return app::ui::run(app::ui::EditorOptions {
            file: e.file,
            script: e.script,
            capture: e.capture,
            capture_spp: e.capture_spp.max(1),
            linger: Duration::from_millis(e.linger_ms),
            size: e.window,
            workers,
            device: e.device,
            validation: e.validation,
            record: e.record,
            config: None,
        });
    };
    match command {
        Command::Stats { size } => {
            let started = Instant::now();
            let scene = with_progress("building the default scene".into(), || {
                default_scene(size, workers)
            })?;
            print_stats(&scene.world, started.elapsed().as_secs_f64())
        }
        Command::Convert {
            input,
            output,
            offset,
            include_hidden,
        } => {
            let started = Instant::now();
            let scene = with_progress(
                format!("reading {}", input.display()),
                || match Format::of(&input)? {
                    Format::Project => Ok(formats::project::load(&input, workers)?),
                    Format::Vox => {
                        let options = formats::vox::ImportOptions {
                            offset,
                            include_hidden,
                        };
                        let (scene, report) = formats::vox::import_file(&input, &options, workers)?;
                        eprintln!(
                            "imported {} voxels from {} instances of {} models, {} materials",
                            report.voxels, report.instances, report.models, report.materials
                        );
                        for line in &report.dropped {
                            eprintln!("  dropped: {line}");
                        }
                        Ok(scene)
                    }
                },
            )?;
            with_progress(format!("writing {}", output.display()), || {
                Ok(scene.save(&output)?)
            })?;
            eprintln!(
                "wrote {} in {:.2} s",
                output.display(),
                started.elapsed().as_secs_f64()
            );
            Ok(())
        }
        Command::New {
            terrain,
            thesis,
            size,
            seed,
            noise,
            scale,
            octaves,
            height_min,
            height_max,
            water_level,
            output,
        } => {
            if !terrain && !thesis {
                bail!("say what to create: --terrain (with its parameters) or --thesis");
            }
            Format::of(&output)?;
            let started = Instant::now();
            let scene = with_progress("generating".into(), || {
                if thesis {
                    return thesis_scene(workers);
                }
                let dims = GridDims::from_voxels(size.as_uvec3()).context("grid size")?;
                let scene = Scene::empty(dims, workers)?;
                let h = dims.voxels().y as u32;
                let mut params = thesis_terrain(terrain_materials(&scene.world)?, h);
                params.seed = seed;
                params.noise = match noise {
                    Noise::Perlin => NoiseKind::Perlin,
                    Noise::OpenSimplex => NoiseKind::OpenSimplex,
                    Noise::SuperSimplex => NoiseKind::SuperSimplex,
                    Noise::Value => NoiseKind::Value,
                };
                params.octaves = octaves;
                params.scale = scale.unwrap_or(params.scale);
                params.height_range = (
                    height_min.unwrap_or(params.height_range.0),
                    height_max.unwrap_or(params.height_range.1),
                );
                params.water_level = water_level.unwrap_or(params.water_level);
                scene.world.apply(NoiseTerrain::new(params, dims)?.edit())?;
                scene.world.take_dirty();
                Ok(scene)
            })?;
            let generated = started.elapsed().as_secs_f64();
            with_progress(format!("writing {}", output.display()), || {
                Ok(scene.save(&output)?)
            })?;
            eprintln!(
                "generated in {generated:.2} s, wrote {} in {:.2} s total",
                output.display(),
                started.elapsed().as_secs_f64()
            );
            Ok(())
        }
        Command::Render(args) => render_command(args, workers),
        Command::Soak(args) => cli::soak::soak_command(args, workers),
        Command::Replay {
            script,
            save,
            render,
            out_dir,
            device,
        } => {
            let options = app::editor::script::ReplayOptions {
                workers: (workers > 0).then_some(workers),
                out_dir,
                device: device.clone(),
                history_budget: None,
            };
            let started = Instant::now();
            let mut lines = Vec::new();
            let result = app::editor::script::replay_file(&script, &options, &mut |l| {
                let _ = emit(&format!("{l}\n"));
                lines.push(l.to_string());
            });
            let replayed = result?;
            let doc = &replayed.document;
            if let Some(path) = &save {
                doc.scene.save(path)?;
            }
            if let Some(path) = &render {
                let view = doc.scene.world.read();
                let job = render::cpu::RenderJob {
                    width: 512,
                    height: 288,
                    spp: 16,
                    seed: 1,
                };
                let (image, _, _) =
                    render_on(&device, &view, &doc.scene.params, &job, (None, None))?;
                app::atomic::write_atomic(path, |w| {
                    image.write_png(w, doc.scene.params.settings.exposure)
                })?;
            }
            emit(&format!(
                "replayed     {} steps in {:.2} s\ncontent hash {:016x}\n",
                replayed.steps,
                started.elapsed().as_secs_f64(),
                doc.scene.world.read().content_hash()
            ))
        }
        Command::BenchViewport {
            size,
            scales,
            frames,
            spp,
            device,
            ui,
            denoise,
            edits,
        } => {
            if let Some(s) = scales.iter().find(|s| !(**s > 0.0 && **s <= 1.0)) {
                bail!("internal scale {s} is outside (0, 1]");
            }
            if let Some(r) = edits.iter().find(|r| !(**r >= 1.0 && **r <= 64.0)) {
                bail!("--edits radius {r} is outside 1..=64");
            }
            if !edits.is_empty() {
                let scene = with_progress("building the default scene".into(), || {
                    default_scene(SceneSize::Full, workers)
                })?;
                let session = {
                    let view = scene.world.read();
                    app::gpu::session(device.as_deref().unwrap_or("gpu"), &view)?
                };
                return emit(&cli::bench_viewport::edits(
                    session,
                    scene,
                    size,
                    &scales,
                    &edits,
                    frames.clamp(10, 400),
                )?);
            }
            let mut scene = thesis_scene(workers)?;
            scene.params.sun.enabled = true;
            scene.params.settings.max_bounces = 3;
            let session = {
                let view = scene.world.read();
                app::gpu::session_with(device.as_deref().unwrap_or("gpu"), &view, ui)?
            };
            let bench = cli::bench_viewport::BenchViewport {
                size,
                scales,
                frames: frames.max(1),
                spp: spp.clamp(1, 16),
                ui,
                denoise,
            };
            emit(&cli::bench_viewport::run(
                session,
                &scene.world,
                &scene.params,
                &bench,
            )?)
        }
        Command::BenchGpu {
            width,
            height,
            frames,
            device,
            experiment,
            inline_shadows,
            convergence,
            lights,
            reference_spp,
            slices,
        } => bench_gpu(
            BenchGpu {
                width,
                height,
                frames: frames.max(1),
                experiment,
                inline_shadows,
                convergence: convergence.then_some(reference_spp),
                slices,
                lights: lights.then_some(reference_spp),
            },
            device,
            workers,
        ),
        Command::Bench {
            device,
            path,
            frames,
            repeat,
            sizes,
            presets,
            cpu_size,
            cpu_frames,
            edit_radii,
            edit_frames,
            out,
        } => {
            if edit_radii
                .iter()
                .any(|r| !(r.is_finite() && *r > 0.0 && *r <= 256.0))
            {
                anyhow::bail!("--edit-radii must be in (0, 256]");
            }
            let text = cli::bench::bench(
                cli::bench::Bench {
                    device,
                    path,
                    frames: frames.max(1),
                    repeat: repeat.max(1),
                    sizes,
                    presets,
                    cpu_size,
                    cpu_frames,
                    edit_radii,
                    edit_frames: edit_frames.max(1),
                    out,
                },
                workers,
            )?;
            emit(&text)
        }
        Command::BenchSkips {
            device,
            size,
            window,
            rounds,
            out,
        } => emit(&cli::bench_skips::bench_skips(
            cli::bench_skips::BenchSkips {
                device,
                size,
                window,
                rounds,
                out,
            },
            workers,
        )?),
        Command::BenchError {
            device,
            path,
            views,
            size,
            reference_spp,
            max_spp,
            reference_sequence,
            presets,
            out,
        } => {
            let text = cli::bench_error::bench_error(
                cli::bench_error::BenchError {
                    device,
                    path,
                    views,
                    size,
                    reference_spp,
                    max_spp,
                    reference_sequence,
                    presets,
                    out,
                },
                workers,
            )?;
            emit(&text)
        }
        Command::Stress {
            rays,
            size,
            renders,
            cpu_size,
            cpu_renders,
            seed,
            device,
            validation,
            out,
        } => {
            let config = render::stress::StressConfig {
                rays_per_class: rays,
                gpu_size: size.clamp(1, 4096),
                gpu_renders: renders,
                cpu_size: cpu_size.clamp(1, 4096),
                cpu_renders,
                seed,
            };
            let text = cli::stress::stress(cli::stress::Stress {
                config,
                cpu_only: device == "cpu",
                device,
                out,
                validation,
            })?;
            emit(&text)
        }
        Command::Info { file } => {
            let started = Instant::now();
            let scene = with_progress(format!("reading {}", file.display()), || {
                Ok(Scene::load(&file, workers)?)
            })?;
            let p = &scene.params;
            let mut text = format!("file         {}\n", file.display());
            text += &stats_text(&scene.world, started.elapsed().as_secs_f64());
            let lens = match p.camera.projection {
                render::Projection::Perspective => format!("fov {:.1}", p.camera.fov_y_deg),
                render::Projection::Orthographic { height } => {
                    format!("orthographic {height:.1} voxels tall")
                }
            };
            text += &format!(
                "camera       at {} yaw {:.1} pitch {:.1} {lens}\nrender       {} spp, {} bounces, {}x{}\n",
                p.camera.position,
                p.camera.yaw_deg,
                p.camera.pitch_deg,
                p.settings.samples_per_pixel,
                p.settings.max_bounces,
                p.settings.internal_resolution.0,
                p.settings.internal_resolution.1
            );
            emit(&text)?;
            Ok(())
        }
    }
}
