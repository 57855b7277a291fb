//! Subcommands of the `voxbrick` binary, one file each, and the helpers they share.
//!
//! In detail:
//! one file per larger subcommand: `stats.rs` (stats, info text), `render.rs`, `bench_gpu.rs`
//! (complexities, `--convergence`), `bench_lights.rs` (`bench-gpu --lights`: light sampling
//! against BSDF only on a lamp-lit room and the thesis scene with lamps, relMSE and GPU time
//! per spp and in steady state, and the cost of editing 10 k emissive voxels),
//! `bench_viewport.rs` (the editor's frames in flight without a window on the thesis scene;
//! `--edits`: live sphere strokes on the default scene, edit → first frame showing it, and the
//! preview's time), `bench.rs` (`voxbrick bench`: the thesis path, per preset and resolution
//! every frame's GPU time as the median of a few back-to-back dispatches, rays by kind every
//! tenth frame, the CPU reference along the path, a sphere stroke per frame through the
//! interactive frames with bytes uploaded and edit → shown latency; JSON, Markdown, plots,
//! keyframe views), `bench_skips.rs` (`voxbrick bench-skips`: each skip with and without it on
//! the thesis scene at the path's first view, complexity 3, and on a built scene that needs it
//! — lambertian blocks without sun for the variants, sparse spheres in a 2048 × 256 × 2048
//! grid, scattered voxels, deep water, solid blocks on brick boundaries —; traversal skips
//! turned off by trace.comp's experiment bits 7..10 (`SKIPS_OFF` in brickmap.glsl: coarse grid,
//! in-brick blocks, uniform media, full cells emulated as the stored brick's loads) and checked
//! to render the same image, the variant against the everything variant; accumulation when
//! still as the relMSE of one frame against a second of frames; the moving scale as GPU time
//! per frame; skips.md/json), `stress.rs` (`voxbrick stress`: `render::stress` as tables and
//! files, non-zero exit on any non-zero count), `bench_error.rs` (`voxbrick bench-error`: per
//! case (the four presets, and physical on the thesis scene with lamps) and view of the path a
//! reference of two independent halves (its noise = relMSE(a, b)/4, taken off every error;
//! rejected above an eighth of the least error measured), each `Choice` that changes the
//! estimator (defaults, no light sampling, independent numbers) measured at 1 … N spp over
//! several seeds (relMSE with `render::convergence`, FLIP with nv-flip on the tone-mapped
//! images), the viewport's denoiser as a biased choice (`Viewport::render_denoised`: a batch
//! per dispatch, measured not checked, its filter's GPU time counted once per batch, a table of
//! the defaults' relMSE over its own per spp), each that only schedules samples (samples per
//! dispatch, slices, in-place shadows) checked to render the defaults' image and given its
//! curve; steady-state time per sample of every choice in interleaved rounds of
//! `time_repeated`; slope / ratio / drift checks with a 1 % floor on each level's standard
//! error; GPU time at equal error by `time_at_error`; CSV, JSON, Markdown, log-log plots;
//! non-zero exit on a failed check), `plot.rs` (line plots, linear or log-log axes, drawn in
//! memory with plotters and the built-in DejaVu Sans, `assets/fonts`, written atomically);
//! `mod.rs` has the spinner and stdout helpers.

pub mod bench;
pub mod bench_error;
pub mod bench_gpu;
pub mod bench_lights;
pub mod bench_skips;
pub mod bench_viewport;
pub mod plot;
pub mod render;
pub mod soak;
pub mod stats;
pub mod stress;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use std::time::Duration;

/// A spinner on stderr while `work` runs (hidden when stderr is not a terminal).
pub(crate) fn with_progress<T>(message: String, work: impl FnOnce() -> Result<T>) -> Result<T> {
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

/// Writes to stdout; a reader that went away (`voxbrick info f | head`) ends output quietly.
pub(crate) fn emit(text: &str) -> Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// A sample sequence's name on the command line: sobol or independent.
pub(crate) fn parse_sequence(s: &str) -> Result<::render::Sequence, String> {
    match s {
        "sobol" => Ok(::render::Sequence::Sobol),
        "independent" => Ok(::render::Sequence::Independent),
        _ => Err(format!("{s:?} is not a sequence (sobol or independent)")),
    }
}
