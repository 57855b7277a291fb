//! `voxbrick`: the voxel scene editor. Without a subcommand it opens the editor window (on
//! a file, or the built-in default scene); subcommands build, convert, inspect, render,
//! replay and benchmark scenes headlessly.

mod cli;

use anyhow::{Context, Result, bail};
use app::Scene;
use app::formats::{self, Format};
use app::scene::{SceneSize, default_scene, terrain_materials, thesis_scene, thesis_terrain};
use brickmap::terrain::{NoiseKind, NoiseTerrain};
use brickmap::{GridDims, Ray, World};
use clap::{Parser, Subcommand, ValueEnum};
use glam::{DVec3, IVec3};
use indicatif::{ProgressBar, ProgressStyle};
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
    /// Enable the Vulkan validation layer (a script run fails on any validation error).
    #[arg(long)]
    validation: bool,
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
    Render {
        /// A .ron or .vox file (a .vox gets the default camera, sun and sky).
        scene: PathBuf,
        /// Output image (.png).
        #[arg(long)]
        out: PathBuf,
        /// Also write the linear image as PFM (for error measurement).
        #[arg(long)]
        hdr: Option<PathBuf>,
        /// Samples per pixel.
        #[arg(long, default_value_t = 16)]
        spp: u32,
        /// Max bounces (default: the scene's setting).
        #[arg(long)]
        bounces: Option<u32>,
        /// Image width.
        #[arg(long, default_value_t = 512)]
        width: u32,
        /// Image height.
        #[arg(long, default_value_t = 288)]
        height: u32,
        /// Camera as EYE_X,EYE_Y,EZE_Z:TARGET_X,TARGET_Y,TARGET_Z (default: the scene's; for
        /// .vox, framing the whole scene).
        #[arg(long)]
        camera: Option<String>,
        /// gpu (the Vulkan path tracer on the best device), cpu (the reference path tracer), or
        /// part of a Vulkan device's name.
        #[arg(long, default_value = "gpu")]
        device: String,
        /// Random seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Internal resolution as a fraction of the output (0 < F <= 1): paths are traced at
        /// ceil(W·F)×ceil(H·F) and upscaled bilinearly.
        #[arg(long, default_value_t = 1.0)]
        scale: f64,
        /// GPU: samples per pixel in one dispatch, 1..=16 (default: chosen from the image
        /// size).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16))]
        samples_per_dispatch: Option<u32>,
        /// GPU: invocations each pixel's samples are split among in one dispatch, 1..=8
        /// (default: enough for 0.6 M invocations, where the device has float atomics).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8))]
        slices: Option<u32>,
    },
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
        /// Samples per pixel of the convergence reference.
        #[arg(long, default_value_t = 4096)]
        reference_spp: u32,
        /// Invocations each pixel's samples are split among, 1..=8 (default: the renderer's
        /// choice for the image size).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8))]
        slices: Option<u32>,
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

/// A spinner on stderr while `work` runs (hidden when stderr is not a terminal).
fn with_progress<T>(message: String, work: impl FnOnce() -> Result<T>) -> Result<T> {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} {elapsed}").expect("valid template"),
    );
    bar.set_message(message);
    bar.enable_steady_tick(Duration::from_millis(100));
    let out = work();
    bar.finish_and_clear();
    out
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
        Command::Render {
            scene,
            out,
            hdr,
            spp,
            bounces,
            width,
            height,
            camera,
            device,
            seed,
            scale,
            samples_per_dispatch,
            slices,
        } => render_command(RenderArgs {
            scene,
            out,
            hdr,
            spp,
            bounces,
            width,
            height,
            camera,
            device,
            seed,
            scale,
            samples_per_dispatch,
            slices,
            workers,
        }),
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
        } => {
            if let Some(s) = scales.iter().find(|s| !(**s > 0.0 && **s <= 1.0)) {
                bail!("internal scale {s} is outside (0, 1]");
            }
            let mut scene = thesis_scene(workers)?;
            scene.params.sun.enabled = true;
            scene.params.settings.max_bounces = 3;
            let session = {
                let view = scene.world.read();
                app::gpu::session(device.as_deref().unwrap_or("gpu"), &view)?
            };
            let bench = cli::bench_viewport::BenchViewport {
                size,
                scales,
                frames: frames.max(1),
                spp: spp.clamp(1, 16),
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
            },
            device,
            workers,
        ),
        Command::Info { file } => {
            let started = Instant::now();
            let scene = with_progress(format!("reading {}", file.display()), || {
                Ok(Scene::load(&file, workers)?)
            })?;
            let p = &scene.params;
            let mut text = format!("file         {}\n", file.display());
            text += &stats_text(&scene.world, started.elapsed().as_secs_f64());
            text += &format!(
                "camera       at {} yaw {:.1} pitch {:.1} fov {:.1}\nrender       {} spp, {} bounces, {}x{}\n",
                p.camera.position,
                p.camera.yaw_deg,
                p.camera.pitch_deg,
                p.camera.fov_y_deg,
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

/// Writes to stdout; a reader that went away (`voxbrick info f | head`) ends output quietly.
fn emit(text: &str) -> Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

fn print_stats(world: &World, seconds: f64) -> Result<()> {
    emit(&stats_text(world, seconds))
}

fn stats_text(world: &World, seconds: f64) -> String {
    let view = world.read();
    let dims = world.dims();
    let m = view.memory();
    let solid = view.solid_count();
    let v = dims.voxels();
    let b = dims.bricks();
    let table = view.materials();
    let mut kinds = [0usize; 4];
    for i in 0..table.len() {
        if let Ok(mat) = table.get(i as u8) {
            kinds[mat.kind as usize] += 1;
        }
    }
    let mut lines = vec![
        format!(
            "scene        {} x {} x {} voxels ({} x {} x {} bricks)",
            v.x, v.y, v.z, b.x, b.y, b.z
        ),
        format!(
            "built in     {:.1} ms on {} workers",
            seconds * 1e3,
            world.workers()
        ),
        format!("solid        {solid} voxels"),
        format!(
            "cells        {} stored bricks ({} uniform), {} full cells",
            view.brick_count(),
            m.uniform_bricks,
            m.full_cells
        ),
        format!(
            "materials    {} in the table ({} lambertian, {} metal, {} dielectric, {} emissive)",
            table.len(),
            kinds[0],
            kinds[1],
            kinds[2],
            kinds[3]
        ),
        format!(
            "gpu memory   {} bytes used, {} reserved",
            m.gpu_used(),
            m.gpu_reserved()
        ),
        format!("  brick index  {}", m.brick_index),
        format!("  bricks       {}", m.bricks_used),
        format!("  coarse grid  {}", m.coarse),
        format!(
            "  material     {} ({} payload)",
            m.material_used, m.material_payload
        ),
        format!("  tables       {}", m.tables),
    ];
    if solid > 0 {
        lines.push(format!(
            "per voxel    {:.4} bytes per solid voxel",
            m.gpu_used() as f64 / solid as f64
        ));
    }
    // A pick ray straight down through the middle, as a brush would cast it.
    let centre = v.as_dvec3() * 0.5;
    let ray = Ray {
        origin: DVec3::new(centre.x + 0.5, v.y as f64 + 10.0, centre.z + 0.5),
        dir: -DVec3::Y,
    };
    lines.push(match view.ray_cast(&ray, f64::INFINITY) {
        Ok(Some((hit, material))) => {
            format!(
                "pick         voxel {} material {material} normal {} at t = {:.3}",
                hit.voxel, hit.normal, hit.t
            )
        }
        Ok(None) => "pick         nothing below the centre".to_string(),
        Err(e) => format!("pick         failed: {e}"),
    });
    lines.push(format!("content hash {:016x}", view.content_hash()));
    lines.join("\n") + "\n"
}

struct RenderArgs {
    scene: PathBuf,
    out: PathBuf,
    hdr: Option<PathBuf>,
    spp: u32,
    bounces: Option<u32>,
    width: u32,
    height: u32,
    camera: Option<String>,
    device: String,
    seed: u64,
    scale: f64,
    samples_per_dispatch: Option<u32>,
    slices: Option<u32>,
    workers: usize,
}

fn render_command(a: RenderArgs) -> Result<()> {
    if a.spp == 0 || a.width == 0 || a.height == 0 || a.width > 16384 || a.height > 16384 {
        bail!("--spp, --width and --height must be positive (sizes at most 16384)");
    }
    if !(a.scale > 0.0 && a.scale <= 1.0) {
        bail!("--scale {} is outside (0, 1]", a.scale);
    }
    let scene = with_progress(format!("reading {}", a.scene.display()), || {
        Ok(Scene::load(&a.scene, a.workers)?)
    })?;
    let mut params = scene.params.clone();
    if let Some(spec) = &a.camera {
        let (eye, target) = spec
            .split_once(':')
            .context("--camera wants EYE:TARGET, each X,Y,Z")?;
        let eye = parse_ivec3_f(eye)?;
        let target = parse_ivec3_f(target)?;
        params.camera = render::Camera::looking_at(eye, target, params.camera.fov_y_deg);
        params.camera.validate()?;
    }
    if let Some(b) = a.bounces {
        if !(1..=64).contains(&b) {
            bail!("--bounces {b} is outside 1..=64");
        }
        params.settings.max_bounces = b;
    }
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

fn parse_ivec3_f(s: &str) -> Result<DVec3> {
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

/// What `bench-gpu` measures.
struct BenchGpu {
    width: u32,
    height: u32,
    frames: usize,
    experiment: u32,
    inline_shadows: bool,
    /// Error against time with a reference of this many samples, instead of the complexities.
    convergence: Option<u32>,
    /// Invocations per pixel (None: the renderer's choice).
    slices: Option<u32>,
}

fn bench_gpu(bench: BenchGpu, device: Option<String>, workers: usize) -> Result<()> {
    let BenchGpu {
        width,
        height,
        frames,
        experiment,
        inline_shadows,
        convergence,
        slices,
    } = bench;
    use render::vulkan::trace::Variant;
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
        // The scene's variant and the everything variant, alternated in rounds of
        // back-to-back dispatches (one submission each, so the GPU stays busy and its clocks
        // stay up) so both see the same machine state; the first two rounds of each are
        // warm-up.
        let scene_variant = Variant {
            experiment,
            ..Variant::for_scene(view.materials(), &params)
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
        let rays = match session.render_counted(
            &view,
            &params,
            &render::cpu::RenderJob {
                width,
                height,
                spp,
                seed: 0,
            },
            Some(scene_variant),
        ) {
            Ok((_, _, rays)) => rays,
            Err(e) => {
                failure = Some(e);
                break;
            }
        };
        let n = times[0].len();
        let stats = session
            .statistics(scene_variant)
            .into_iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(", ");
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
             traversal steps per ray: {:.1} primary, {:.1} secondary, {:.1} shadow; most in one ray: {} camera or continuation, {} shadow\n",
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
        );
    }
    if let Some(e) = failure {
        return Err(e.into());
    }
    emit(&text)
}

/// Image error against GPU time (render::convergence): a reference of `reference_spp` samples,
/// then renders of 1, 2, 4 … 256 samples with other seeds, each three times (the middle time
/// and the mean MSE are used).
fn convergence_table(
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
        || Ok(session.render(view, params, &job(reference_spp, 1))?),
    )?;
    let Some(reference_time) = reference_time else {
        bail!("this queue cannot take timestamps");
    };
    let mean = reference.mean().iter().sum::<f64>() / 3.0;
    let mut measurements = Vec::new();
    for spp in (0..9).map(|k| 1u32 << k) {
        let (mut times, mut mse) = (Vec::new(), 0.0);
        for seed in 2..5 {
            let (image, time) = session.render(view, params, &job(spp, seed))?;
            times.push(time.unwrap_or(f64::NAN));
            mse += image.mse(&reference).context("image sizes differ")? / 3.0;
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

/// Renders on a device: "cpu" (the reference), "gpu" (the best Vulkan device) or part of a
/// device's name. Returns the image, the device's name and a timing report.
fn render_on(
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
            || Ok(session.render_counted(view, params, job, None)?),
        );
        let (image, gpu, rays) = rendered?;
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
