//! The benchmark and stress harness: what measures the product, apart from the editor's code
//! (the library) and from the subcommands that make and convert scenes. Each file's own docs
//! say what it measures or writes; BENCHMARKS.md holds the figures.
//!
//! - `bench.rs` (the thesis path; `bench/runs.rs` its measurements), `bench_gpu.rs`
//!   (complexities, `--convergence`) with `bench_lights.rs` (`--lights`, its scenes in
//!   `light_scenes.rs`), `bench_viewport.rs`
//!   (the editor's frame loop headless), `bench_skips.rs`, `bench_error.rs` (its report in
//!   `bench_error/report.rs`), `stress.rs` (the numerical stress suite);
//! - `plot.rs` draws their plots; tables, reports and stdout go through the CLI's helpers.

pub mod bench;
pub mod bench_error;
pub mod bench_gpu;
pub mod bench_lights;
pub mod bench_scene;
pub mod bench_skips;
pub mod bench_viewport;
pub mod light_scenes;
pub mod plot;
pub mod stress;

pub(crate) use super::{args, emit, table, with_progress, write_json, write_report};
