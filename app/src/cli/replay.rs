//! `voxbrick replay`: an edit script replayed headlessly, each step reported.

use super::emit;
use super::render::render_on;
use anyhow::Result;
use std::path::PathBuf;
use std::time::Instant;

/// `voxbrick replay`'s arguments.
#[derive(clap::Args)]
pub(crate) struct ReplayArgs {
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
}

/// Replays the script (non-zero exit at the first failed step), then saves and renders.
pub(crate) fn replay(a: ReplayArgs, workers: usize) -> Result<()> {
    let options = app::editor::script::ReplayOptions {
        workers: (workers > 0).then_some(workers),
        out_dir: a.out_dir,
        device: a.device.clone(),
        history_budget: None,
    };
    let started = Instant::now();
    let replayed = app::editor::script::replay_file(&a.script, &options, &mut |l| {
        let _ = emit(&format!("{l}\n"));
    })?;
    let doc = &replayed.document;
    if let Some(path) = &a.save {
        app::formats::save(&doc.scene, path)?;
    }
    if let Some(path) = &a.render {
        let view = doc.scene.world.read();
        let job = render::cpu::RenderJob {
            width: 512,
            height: 288,
            spp: 16,
            seed: 1,
        };
        let (image, _, _) = render_on(&a.device, &view, &doc.scene.params, &job, (None, None))?;
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
