//! `bench-error`'s report: the Markdown tables (per case and view, efficiency at equal
//! error, the denoiser's), the CSV, the JSON and the log-log plots.

use super::super::plot::{Axes, Series, plot};
use super::super::table::Table;
use super::*;

/// What the denoiser buys at each level: the defaults' relMSE over the denoised one (> 1: the
/// denoised image is closer to the reference), and its filter's GPU time.
fn denoiser_table(md: &mut String, run: &CaseRun) {
    for k in 0..run.views[0].curves.len() {
        if run.views[0].curves[k].choice.denoised() {
            denoiser_rows(md, run, k);
        }
    }
}

/// [`denoiser_table`] of the denoised choice `k`.
fn denoiser_rows(md: &mut String, run: &CaseRun, k: usize) {
    let levels = &run.views[0].curves[k].levels;
    // The choice's name heads its table ("Denoised (viewport)", "Denoised, no fade", …).
    let name = run.views[0].curves[k].choice.name();
    let mut head = name.chars();
    let name: String = head
        .next()
        .into_iter()
        .flat_map(char::to_uppercase)
        .chain(head)
        .collect();
    *md += &format!(
        "\n{name}: the defaults' relMSE over the denoised image's at each spp (> 1: the denoiser's bias costs less than the noise it removes), and the filter's GPU ms:\n\n",
    );
    let header: Vec<String> = std::iter::once("view".to_string())
        .chain(levels.iter().map(|l| format!("{} spp", l.spp)))
        .chain(["filter ms".to_string()])
        .collect();
    let mut table = Table::new(&header);
    for view in &run.views {
        let (Some(d), Some(def)) = (view.curves.get(k), view.curves.first()) else {
            continue;
        };
        table.row_of(
            std::iter::once(format!("{} s", view.time_s))
                .chain(
                    d.levels
                        .iter()
                        .zip(&def.levels)
                        .map(|(l, r)| format!("{:.2}", r.rel_mse / l.rel_mse)),
                )
                .chain([format!(
                    "{:.3}",
                    d.levels.first().map_or(f64::NAN, |l| l.filter_ms)
                )]),
        );
    }
    *md += &table.finish();
}

/// At the error the defaults reach at their last level: the defaults' GPU time over the
/// choice's (> 1: the choice is faster at equal error).
fn speedup(defaults: &Curve, curve: &Curve) -> Option<f64> {
    let target = defaults.levels.last()?.rel_mse;
    if curve.choice.biased() && curve.levels.last()?.rel_mse > target {
        // Not reached: a biased curve's slope says nothing about where it would be.
        return None;
    }
    let points = |c: &Curve| -> Vec<(f64, f64)> {
        c.levels.iter().map(|l| (l.rel_mse, l.steady_ms)).collect()
    };
    Some(
        time_at_error(&points(defaults), target, defaults.slope)?
            / time_at_error(&points(curve), target, curve.slope)?,
    )
}

pub(super) fn report(
    b: &BenchError,
    ctx: &render::vulkan::GpuContext,
    runs: &[CaseRun],
) -> Result<String> {
    let (w, h) = b.size;
    let mut csv = String::from(
        "case,view_s,choice,spp,renders,render_gpu_ms,steady_gpu_ms,rel_mse,rel_mse_se,flip,variance_ratio\n",
    );
    let mut md = format!(
        "# Error against samples and GPU time\n\n{} ({}), {w}x{h}, reference {} spp per view (two halves, {:?} numbers), up to {} spp; relMSE ε = {}; FLIP: LDR on the tone-mapped images, {} pixels per degree. Checks, each within {Z_MAX} standard errors (a level's at least {SE_FLOOR} of its value): slope of log relMSE against log spp −1 (Sobol: ≤ −1), relMSE·spp/σ² at {} spp 1 (Sobol: ≤ 1, σ² from 1 spp), and no drift of that ratio from {} to {} spp (a plateau). Choices marked \"same image\" only schedule the same samples otherwise (checked: their image is the defaults' up to float rounding), so their error curve is the defaults'; GPU time per sample is the median of back-to-back dispatches after warm-up, every choice timed in turn in each round.\n\n",
        ctx.name,
        ctx.driver,
        b.reference_spp,
        b.reference_sequence,
        b.max_spp,
        render::convergence::REL_MSE_EPSILON,
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
        b.max_spp,
        b.max_spp / 4,
        b.max_spp
    );
    let mut failed = Vec::new();
    for run in runs {
        let _ = write!(
            md,
            "## {} ({} bounces{})\n\n",
            run.name,
            run.preset.bounces,
            if run.preset.sun { ", sun" } else { "" },
        );
        let at = format!("relMSE at {} spp", b.max_spp);
        let mut table = Table::new(&[
            "view",
            "reference noise (relMSE)",
            "reference FLIP (halves)",
            "choice",
            &at,
            "FLIP",
            "GPU ms per sample (steady)",
            "render GPU ms",
            "slope (se)",
            "relMSE·spp/σ²",
            "drift z",
            "check",
        ]);
        for view in &run.views {
            for c in &view.curves {
                for l in &c.levels {
                    let _ = writeln!(
                        csv,
                        "{},{},{},{},{},{:.6},{:.6},{:.6e},{:.3e},{:.6},{:.4}",
                        run.name,
                        view.time_s,
                        c.name,
                        l.spp,
                        l.renders,
                        l.gpu_ms,
                        l.steady_ms,
                        l.rel_mse,
                        l.rel_mse_se,
                        l.flip,
                        l.variance_ratio
                    );
                }
                let last = c.levels.last().expect("at least one level");
                let same = if c.same_image_rel_mse.is_some() {
                    " (same image)"
                } else {
                    ""
                };
                table.row(&[
                    &format!("{} s", view.time_s),
                    &format!("{:.2e}", view.reference_noise),
                    &format!("{:.4}", view.reference_flip),
                    &format!("{}{same}", c.name),
                    &format!("{:.3e}", last.rel_mse),
                    &format!("{:.4}", last.flip),
                    &format!("{:.4}", c.ms_per_sample),
                    &format!("{:.2}", last.gpu_ms),
                    &format!("{:.3} ({:.3})", c.slope, c.slope_se),
                    &format!("{:.3}", last.variance_ratio),
                    &format!("{:+.1}", c.drift_z),
                    &if c.choice.biased() {
                        "biased: measured"
                    } else if c.passed {
                        "ok"
                    } else {
                        "**FAILED**"
                    },
                ]);
                if !c.passed {
                    failed.push(format!("{} at {} s, {}", run.name, view.time_s, c.name));
                }
            }
        }
        md += &table.finish();
        // Efficiency at equal error, per view, and their geometric mean.
        let _ = write!(
            md,
            "\nSteady-state GPU time at equal error (the defaults' relMSE at {} spp), defaults' over the choice's (> 1: faster):\n\n",
            b.max_spp,
        );
        let header: Vec<String> = std::iter::once("choice".to_string())
            .chain(run.views.iter().map(|v| format!("{} s", v.time_s)))
            .chain(["geometric mean".to_string()])
            .collect();
        let mut table = Table::new(&header);
        for (k, curve) in run.views[0].curves.iter().enumerate() {
            let ratios: Vec<Option<f64>> = run
                .views
                .iter()
                .map(|v| v.curves.get(k).and_then(|c| speedup(&v.curves[0], c)))
                .collect();
            let known: Vec<f64> = ratios.iter().flatten().copied().collect();
            let geo = if known.is_empty() {
                "–".to_string()
            } else {
                let g = (known.iter().map(|r| r.ln()).sum::<f64>() / known.len() as f64).exp();
                format!("{g:.3}")
            };
            table.row_of(
                std::iter::once(curve.name.clone())
                    .chain(
                        ratios
                            .iter()
                            .map(|r| r.map_or("–".into(), |r| format!("{r:.3}"))),
                    )
                    .chain([geo]),
            );
        }
        md += &table.finish();
        denoiser_table(&mut md, run);
        md += "\n";
        plots(b, run)?;
    }
    let json = serde_json::json!({
        "device": ctx.name, "driver": ctx.driver, "clocks": crate::cli::harness::bench::clocks(),
        "size": [w, h], "reference_spp": b.reference_spp, "max_spp": b.max_spp,
        "rel_mse_epsilon": render::convergence::REL_MSE_EPSILON, "z_max": Z_MAX,
        "cases": runs,
    });
    crate::cli::write_json(&b.out.join("error.json"), &json)?;
    crate::cli::write_report(&b.out.join("error.csv"), &csv)?;
    crate::cli::write_report(&b.out.join("error.md"), &md)?;
    if !failed.is_empty() {
        bail!(
            "{} check(s) failed (a bias; report in {}): {}",
            failed.len(),
            b.out.display(),
            failed.join("; ")
        );
    }
    Ok(md)
}

/// Log-log plots per case, each choice's mean over the views: relMSE and FLIP against spp,
/// relMSE against GPU time.
fn plots(b: &BenchError, run: &CaseRun) -> Result<()> {
    let file = run.name.replace([' ', '+'], "_");
    let mean_over_views = |k: usize, f: &dyn Fn(&Level) -> (f64, f64)| -> Vec<(f64, f64)> {
        let levels = run.views[0].curves[k].levels.len();
        (0..levels)
            .map(|i| {
                let pts: Vec<(f64, f64)> = run
                    .views
                    .iter()
                    .filter_map(|v| v.curves.get(k).map(|c| f(&c.levels[i])))
                    .collect();
                let n = pts.len().max(1) as f64;
                (
                    pts.iter().map(|p| p.0).sum::<f64>() / n,
                    pts.iter().map(|p| p.1).sum::<f64>() / n,
                )
            })
            .collect()
    };
    let curves = &run.views[0].curves;
    let series = |f: &dyn Fn(&Level) -> (f64, f64)| -> Vec<Series> {
        curves
            .iter()
            .enumerate()
            .map(|(k, c)| Series {
                name: c.name.clone(),
                points: mean_over_views(k, f),
            })
            .collect()
    };
    let mut by_spp = series(&|l| (f64::from(l.spp), l.rel_mse));
    if let Some(first) = by_spp.first().and_then(|s| s.points.first()).copied() {
        by_spp.push(Series {
            name: "1/spp".into(),
            points: (0..=b.max_spp.trailing_zeros())
                .map(|k| {
                    let n = f64::from(1u32 << k);
                    (n, first.1 / n)
                })
                .collect(),
        });
    }
    let title = |what: &str| format!("{}: {what} (mean of {} views)", run.name, run.views.len());
    plot(
        &b.out.join(format!("relmse_spp_{file}.png")),
        (960, 640),
        &title("relMSE against samples"),
        ("samples per pixel", "relMSE"),
        &by_spp,
        Axes::LogLog,
    )?;
    plot(
        &b.out.join(format!("relmse_time_{file}.png")),
        (960, 640),
        &title("relMSE against steady-state GPU time"),
        ("GPU ms (samples × steady-state time per sample)", "relMSE"),
        &series(&|l| (l.steady_ms, l.rel_mse)),
        Axes::LogLog,
    )?;
    plot(
        &b.out.join(format!("flip_spp_{file}.png")),
        (960, 640),
        &title("FLIP against samples"),
        ("samples per pixel", "mean FLIP"),
        &series(&|l| (f64::from(l.spp), l.flip)),
        Axes::LogLog,
    )
}
