//! `voxbrick`: the voxel scene editor. Without a subcommand it opens the editor window (on
//! a file, or the built-in default scene); subcommands build, convert, inspect, render,
//! replay and benchmark scenes headlessly.
//!
//! In detail: no subcommand opens the editor (a file or the default scene; `--script`,
//! `--capture`, `--window`, `--validation`, `--record`: the session as a replay script from a
//! copy of the file, carried across File → Open with a copy of each opened file beside it).
//! Each subcommand owns its arguments (a `clap::Args` struct) and its run, in `cli/`; this
//! file only parses and dispatches, and turns every error into one line.

mod cli;

use anyhow::Result;
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::time::Duration;

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
    /// A scene to open (.ron, .vox, .qb, .schem); default: the built-in default scene.
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
    #[arg(long, value_parser = cli::args::window_size, default_value = "1280x720")]
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

#[derive(Subcommand)]
enum Command {
    /// Build the built-in default scene and print its statistics.
    Stats(cli::stats::StatsArgs),
    /// Convert between project (.ron) and MagicaVoxel (.vox) files, or to a mesh (.obj, .glb,
    /// .gltf, .ply).
    Convert(cli::scene_file::ConvertArgs),
    /// Create a new scene file.
    New(cli::scene_file::NewArgs),
    /// Render a scene offscreen to an image.
    Render(cli::render::RenderArgs),
    /// The soak test: a long seeded random session (strokes of every mode and shape, selections,
    /// clipboard, palette, terrain, undo / redo bursts, camera, panels, resizes, saves and
    /// re-opens) fed to a headless editor as window input events, or to its edit thread,
    /// checked after every input; on a failure, the seed and the shortest failing prefix as a
    /// replay script.
    Soak(cli::soak::SoakArgs),
    /// Replay an edit script headlessly, reporting each step; exits non-zero at the first
    /// failed step.
    Replay(cli::replay::ReplayArgs),
    /// The editor's frame loop without a window (frames in flight, trace and display) on the
    /// thesis scene: GPU and host time per frame, camera move to first frame.
    BenchViewport(cli::harness::bench_viewport::BenchViewport),
    /// Time the GPU path tracer on the thesis scene with Vulkan timestamp queries: medians
    /// after warm-up for the thesis's complexities 1, 2 and 3.
    BenchGpu(cli::harness::bench_gpu::BenchGpu),
    /// The thesis benchmark along a camera path: GPU frame times (Vulkan timestamps) per
    /// preset (complexity 1, 2, 3, physical) and internal resolution, rays per second by
    /// kind, the CPU reference at a small size, and sculpting while the path plays; writes
    /// bench.json, bench.md and frame-time plots (PNG) into --out.
    Bench(cli::harness::bench::Bench),
    /// Image error against samples and GPU time at views along the benchmark path: every
    /// preset and sampling choice, relMSE and FLIP against a converged reference whose own
    /// noise is measured, slope and bias checks, efficiency at equal error. Writes
    /// error.csv, error.md, error.json and log-log plots; exits non-zero if a check fails.
    BenchError(cli::harness::bench_error::BenchError),
    /// What each skip buys: the pipeline variants, the coarse-grid and in-brick empty-space
    /// skips, uniform media, full cells, accumulation when still and the lower resolution while
    /// moving, with and without each, on the thesis scene and on a scene that needs it. Writes
    /// skips.md and skips.json.
    BenchSkips(cli::harness::bench_skips::BenchSkips),
    /// The numerical stress suite: random and adversarial rays through the GPU traversal
    /// against the exact CPU ray cast, and adversarial scenes' images (NaN, infinite and
    /// negative samples, white-furnace energy, iteration caps) on the GPU and the CPU
    /// reference. Exits non-zero if any count is not zero.
    Stress(cli::harness::stress::Stress),
    /// Print a scene file's dimensions, voxel count, materials and memory.
    Info(cli::scene_file::InfoArgs),
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
        Command::Stats(a) => cli::stats::stats(a, workers),
        Command::Convert(a) => cli::scene_file::convert(a, workers),
        Command::New(a) => cli::scene_file::new(a, workers),
        Command::Info(a) => cli::scene_file::info(a, workers),
        Command::Render(a) if a.finished() => cli::picture::render_finished(a, workers),
        Command::Render(a) => cli::render::render_command(a, workers),
        Command::Soak(a) => cli::soak::soak_command(a, workers),
        Command::Replay(a) => cli::replay::replay(a, workers),
        Command::BenchViewport(a) => cli::harness::bench_viewport::command(a, workers),
        Command::BenchGpu(a) => cli::harness::bench_gpu::run(a, workers),
        Command::Bench(a) => cli::harness::bench::run(a, workers),
        Command::BenchError(a) => cli::harness::bench_error::run(a, workers),
        Command::BenchSkips(a) => cli::harness::bench_skips::run(a, workers),
        Command::Stress(a) => cli::harness::stress::run(a),
    }
}
