//! `voxbrick soak`: the soak test ([`app::soak`]) from the command line — a seeded random
//! session fed to a headless editor as window input events (`--through editor`, the default)
//! or to the edit thread as edits (`--through edits`), checked after every input; prints
//! events per second and exits non-zero with the seed and the shortest failing prefix (a
//! replay script) on a failure.

use anyhow::{Result, bail};
use app::soak::{SoakOptions, Through, soak};
use std::path::PathBuf;
use std::time::Duration;

/// `voxbrick soak`'s arguments.
#[derive(clap::Args)]
pub(crate) struct SoakArgs {
    /// The session's seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// What the session feeds: "editor" (window input events into a headless editor: egui,
    /// the key map, picking, the tools) or "edits" (edits into the edit thread).
    #[arg(long, default_value = "editor")]
    through: String,
    /// The headless editor's window size, as WxH (--through editor).
    #[arg(long, default_value = "480x300")]
    window: String,
    /// Run this many minutes (then stop at the next event).
    #[arg(long)]
    minutes: Option<f64>,
    /// Stop after this many events (default: 10 000 without --minutes, no limit with it).
    #[arg(long)]
    events: Option<u64>,
    /// World size in voxels, as WxHxD.
    #[arg(long, default_value = "64x32x64")]
    size: String,
    /// The viewport's largest size, as WxH (resizes pick sizes up to it).
    #[arg(long, default_value = "96x64")]
    view: String,
    /// Vulkan device for the viewport's frames ("gpu": the best), or "none": no frames
    /// (--through edits only: the editor always draws).
    #[arg(long, default_value = "gpu")]
    device: String,
    /// Events between whole-history checks.
    #[arg(long, default_value_t = 1000)]
    check_every: u64,
    /// Events (--through edits) or inputs (--through editor) between viewport frames.
    #[arg(long, default_value_t = 8)]
    frame_every: u64,
    /// Folder for saves and a failure's replay script.
    #[arg(long, default_value = "soak-out")]
    out: PathBuf,
}

fn numbers(text: &str, n: usize) -> Result<Vec<u32>> {
    let v: Vec<u32> = text
        .split('x')
        .map(|p| p.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("{text:?} is not {n} numbers joined by x"))?;
    if v.len() != n || v.contains(&0) {
        bail!("{text:?} is not {n} positive numbers joined by x");
    }
    Ok(v)
}

pub(crate) fn soak_command(a: SoakArgs, workers: usize) -> Result<()> {
    let size = numbers(&a.size, 3)?;
    let view = numbers(&a.view, 2)?;
    let window = numbers(&a.window, 2)?;
    let through = match a.through.as_str() {
        "editor" => Through::Editor,
        "edits" => Through::Edits,
        other => bail!("--through {other:?}: say \"editor\" or \"edits\""),
    };
    if through == Through::Editor && a.device == "none" {
        bail!("--through editor draws every frame: it needs a --device (or use --through edits)");
    }
    if let Some(m) = a.minutes
        && !(m > 0.0 && m.is_finite())
    {
        bail!("--minutes {m} must be positive");
    }
    std::fs::create_dir_all(&a.out)?;
    let opts = SoakOptions {
        seed: a.seed,
        through,
        window: (window[0], window[1]),
        events: a
            .events
            .unwrap_or(if a.minutes.is_some() { 0 } else { 10_000 }),
        duration: a.minutes.map(|m| Duration::from_secs_f64(m * 60.0)),
        size: glam::UVec3::new(size[0], size[1], size[2]),
        view: (view[0], view[1]),
        device: (a.device != "none").then_some(a.device),
        check_every: a.check_every,
        frame_every: a.frame_every,
        workers: workers.max(1),
        out_dir: a.out,
        ..SoakOptions::default()
    };
    match soak(&opts) {
        Ok(r) => {
            let secs = r.elapsed.as_secs_f64().max(1e-9);
            println!(
                "soak seed {}: {} events ({} inputs) in {:.1} s ({:.0} events/s, {:.0} inputs/s), {} frames, {} whole-history checks, {} edits refused (each left the document as it was), clean",
                opts.seed,
                r.events,
                r.inputs,
                secs,
                r.events as f64 / secs,
                r.inputs as f64 / secs,
                r.frames,
                r.checks,
                r.refused
            );
            println!(
                "peak history {:.1} MiB, peak resident {:.1} MiB",
                r.peak_history as f64 / 1048576.0,
                r.peak_rss as f64 / 1048576.0
            );
            for (kind, n) in &r.kinds {
                println!("  {kind:<28} {n}");
            }
            Ok(())
        }
        Err(f) => bail!("{f}"),
    }
}
