//! `voxbrick stress`: the numerical stress suite (`render::stress`) as a report: every ray
//! class against the exact CPU cast, every adversarial scene's sample counts and furnace
//! energy, as Markdown on stdout and JSON / Markdown files; exits non-zero on any non-zero
//! count.

use super::table::{Table, bold};
use anyhow::{Result, bail};
use render::stress::{ImageRow, RayRow, StressConfig};
use std::path::PathBuf;

/// `voxbrick stress`: what to run.
#[derive(clap::Args)]
pub(crate) struct Stress {
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
    /// Device name filter ("gpu": the best), or "cpu": only the CPU reference's images (no
    /// GPU: rays and GPU images are not tried).
    #[arg(long, default_value = "gpu")]
    device: String,
    /// Also count validation-layer errors (each is a failure).
    #[arg(long)]
    validation: bool,
    /// Folder to write stress.json and stress.md into.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// The Markdown tables.
fn markdown(device: &str, cfg: &StressConfig, rays: &[RayRow], images: &[ImageRow]) -> String {
    let mut t = format!(
        "device: {device}; {} rays per class and world; GPU images {s}x{s}, {} one-sample renders per view; CPU images {c}x{c}, {} per view; seed {}\n\n",
        cfg.rays_per_class,
        cfg.gpu_renders,
        cfg.cpu_renders,
        cfg.seed,
        s = cfg.gpu_size,
        c = cfg.cpu_size,
    );
    if !rays.is_empty() {
        t += "Rays: GPU traversal (f32) against the exact CPU cast (f64) of the same ray; tolerance 4 f32 ulps at the largest coordinate (origin, hit point, grid corner), on |Δt|·max|dᵢ| and on distances to voxel boxes.\n\n";
        let mut table = Table::new(&[
            "world",
            "rays",
            "tried",
            "CPU hits",
            "exact",
            "edge faces",
            "f32 ties",
            "mismatches",
            "caps hit",
            "CPU errors",
        ]);
        for r in rays {
            let x = &r.tally;
            table.row(&[
                &r.world,
                &r.class,
                &x.tried,
                &x.hits,
                &x.exact,
                &x.edge_faces,
                &x.f32_ties,
                &bold(x.mismatches),
                &bold(x.caps_hit),
                &bold(x.cpu_errors),
            ]);
        }
        t += &table.finish();
        let total: u64 = rays.iter().map(|r| r.tally.tried).sum();
        let ties: u64 = rays.iter().map(|r| r.tally.f32_ties).sum();
        let edges: u64 = rays.iter().map(|r| r.tally.edge_faces).sum();
        t += &format!("\n{total} rays in all: {edges} edge faces, {ties} f32 ties.\n");
        for r in rays {
            for e in &r.tally.examples {
                t += &format!("- mismatch ({}, {}): {e}\n", r.world, r.class);
            }
            for e in &r.tally.tie_examples {
                t += &format!("- tie ({}, {}): {e}\n", r.world, r.class);
            }
        }
        t += "\n";
    }
    t += "Images: every sample counted (one-sample renders); furnaces: relative energy lost, 1 − mean/expected (± standard error).\n\n";
    let mut table = Table::new(&[
        "scene",
        "renderer",
        "samples",
        "NaN",
        "inf",
        "negative",
        "caps hit",
        "mean ch. 0",
        "energy lost",
        "verdict",
    ]);
    for r in images {
        let lost = match (r.energy_lost, r.expected) {
            (Some(l), Some(e)) => format!("{:+.2e} ± {:.1e}", l, r.standard_error / e),
            _ => "—".into(),
        };
        table.row(&[
            &r.scene,
            &r.renderer,
            &r.samples,
            &bold(r.nan),
            &bold(r.inf),
            &bold(r.negative),
            &r.caps_hit.map_or("—".into(), bold),
            &format!("{:.4}", r.mean),
            &lost,
            &if r.clean() { "ok" } else { "FAIL" },
        ]);
    }
    t + &table.finish()
}

/// Runs the suite and prints the report; any non-zero count is an error.
pub(crate) fn run(s: Stress) -> Result<()> {
    super::emit(&stress(s)?)
}

fn stress(s: Stress) -> Result<String> {
    let cfg = StressConfig {
        rays_per_class: s.rays,
        gpu_size: s.size.clamp(1, 4096),
        gpu_renders: s.renders,
        cpu_size: s.cpu_size.clamp(1, 4096),
        cpu_renders: s.cpu_renders,
        seed: s.seed,
    };
    let ctx = if s.device == "cpu" {
        None
    } else {
        Some(app::gpu::context(&s.device, s.validation)?)
    };
    let device = ctx.as_ref().map_or("CPU reference only".to_string(), |c| {
        format!("{} ({})", c.name, c.driver)
    });
    let mut rays = Vec::new();
    if let Some(ctx) = &ctx {
        rays = render::stress::ray_suite(ctx, &cfg, |r| {
            eprintln!(
                "rays  {:<24} {:<22} {} tried, {} ties, {} mismatches, {} caps",
                r.world,
                r.class,
                r.tally.tried,
                r.tally.f32_ties,
                r.tally.mismatches,
                r.tally.caps_hit
            )
        })?;
    }
    let images = render::stress::image_suite(ctx.as_ref(), &cfg, |r| {
        eprintln!(
            "image {:<36} {} {} samples: {} NaN, {} inf, {} negative{}",
            r.scene,
            r.renderer,
            r.samples,
            r.nan,
            r.inf,
            r.negative,
            r.energy_lost
                .map_or(String::new(), |l| format!(", energy lost {l:+.2e}"))
        )
    })?;
    let validation = ctx.as_ref().map_or(0, |c| c.validation_errors());
    let mut text = markdown(&device, &cfg, &rays, &images);
    if s.validation {
        text += &format!("\nvalidation errors: {validation}\n");
    }
    if let Some(dir) = &s.out {
        std::fs::create_dir_all(dir)?;
        let json = serde_json::json!({
            "device": device,
            "rays_per_class": cfg.rays_per_class,
            "seed": cfg.seed,
            "rays": rays,
            "images": images,
            "validation_errors": validation,
        });
        let json = serde_json::to_string_pretty(&json)?;
        for (name, bytes) in [
            ("stress.json", json.as_bytes()),
            ("stress.md", text.as_bytes()),
        ] {
            app::atomic::write_atomic(&dir.join(name), |w| w.write_all(bytes))?;
        }
    }
    let bad_rays = rays
        .iter()
        .filter(|r| r.tally.mismatches + r.tally.caps_hit + r.tally.cpu_errors > 0)
        .count();
    let bad_images = images.iter().filter(|r| !r.clean()).count();
    if bad_rays + bad_images > 0 || validation > 0 {
        super::emit(&text)?;
        bail!(
            "{bad_rays} ray classes and {bad_images} scenes with non-zero counts, {validation} validation errors"
        );
    }
    Ok(text)
}
