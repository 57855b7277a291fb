//! `voxbrick bench-gpu --lights`: what light sampling of emissive voxels buys. For the scenes
//! of `light_scenes.rs` (a lamp-lit room, the thesis scene with lamps and the sun, a city at
//! night): relative MSE against a converged reference and GPU time at 1 … 64 spp with the light
//! tree, with faces chosen by weight alone (the selection before the tree: trace.comp's
//! experiment bit 11) and with BSDF sampling alone; efficiency 1 / (relMSE × time), whose
//! ratio at equal spp is the ratio at equal error (the estimators are unbiased: relMSE ∝
//! 1/spp, time ∝ spp). Then the cost of an edit adding or removing 10 k emissive voxels (the
//! world's edit with its light update, and the bytes it dirties).

use super::light_scenes::{lamp_room, night_city, thesis_with_lamps};
use super::with_progress;
use anyhow::{Context, Result, bail};
use app::Scene;
use brickmap::{EditOp, GpuBuffer, MaterialKind, Mode, Shape};
use glam::IVec3;
use render::Image;
use render::cpu::RenderJob;
use render::viewport::RenderHow;
use render::vulkan::trace::Variant;
use std::time::Instant;

/// trace.comp's experiment bit choosing light faces by weight alone.
const BY_WEIGHT: u32 = 1 << 11;

fn rel_mse(image: &Image, reference: &Image) -> f64 {
    render::convergence::rel_mse(image, reference).unwrap_or(f64::NAN)
}

pub(crate) fn bench_lights(
    device: &str,
    workers: usize,
    (width, height): (u32, u32),
    reference_spp: u32,
    images: Option<&std::path::Path>,
    experiment: u32,
) -> Result<String> {
    let mut text = String::new();
    for (name, scene) in [
        (
            "lamp-lit room (128x64x128, 6 emissive voxels, 4 bounces, no sun)",
            lamp_room(workers)?,
        ),
        (
            "thesis scene + 6 lamps (3 bounces, sun)",
            thesis_with_lamps(workers)?,
        ),
        (
            "city at night (1024x64x1024, 11,008 street lamps, 3 bounces, no sun)",
            night_city(workers)?,
        ),
    ] {
        let view = scene.world.read();
        let params = &scene.params;
        let mut session = app::gpu::session(device, &view)?;
        if text.is_empty() {
            let ctx = session.ctx();
            text += &format!("device       {} ({})\n", ctx.name, ctx.driver);
        }
        let on = Variant {
            experiment,
            ..Variant::for_scene(&view, params)
        };
        if !on.lights {
            bail!("{name}: no light faces");
        }
        let variants = [
            on,
            Variant {
                experiment: experiment | BY_WEIGHT,
                ..on
            },
            Variant {
                lights: false,
                ..on
            },
        ];
        let job = |spp, seed| RenderJob {
            width,
            height,
            spp,
            seed,
        };
        let reference = with_progress(format!("{name}: reference at {reference_spp} spp"), || {
            let how = RenderHow::variant(on);
            Ok(session
                .render(&view, params, &job(reference_spp, 1), how)?
                .image)
        })?;
        if let Some(dir) = images {
            std::fs::create_dir_all(dir)?;
            let file = dir.join(format!("{}.png", name.split(' ').next().unwrap_or("scene")));
            let mut out = std::io::BufWriter::new(std::fs::File::create(&file)?);
            reference.write_png(&mut out, params.settings.exposure)?;
        }
        for (label, v) in ["light tree", "by weight", "BSDF only"]
            .iter()
            .zip(variants)
        {
            let stats = super::bench_gpu::statistics(&mut session, v);
            text += &format!("{name}, {label}: pipeline statistics: {stats}\n");
        }
        text += &format!(
            "{name}: {} light faces, {width}x{height}, reference {reference_spp} spp with light sampling\n  \
             spp   light tree: GPU ms  relMSE     | by weight: GPU ms  relMSE     | BSDF only: GPU ms  relMSE     | efficiency over BSDF only: tree  by weight\n",
            view.lights().len()
        );
        let mut ratios = [Vec::new(), Vec::new()];
        // relMSE of the last (64-spp) row of each variant.
        let mut last_error = [0.0; 3];
        for spp in (0..7).map(|k| 1u32 << k) {
            let mut row = [(0.0, 0.0); 3];
            for (i, v) in variants.into_iter().enumerate() {
                let (mut times, mut err) = (Vec::new(), 0.0);
                for seed in 2..5 {
                    let r =
                        session.render(&view, params, &job(spp, seed), RenderHow::variant(v))?;
                    times.push(r.gpu_seconds.context("this queue cannot take timestamps")?);
                    err += rel_mse(&r.image, &reference) / 3.0;
                }
                times.sort_by(f64::total_cmp);
                row[i] = (times[1], err);
            }
            let eff = row.map(|(t, e)| 1.0 / (e * t));
            last_error = row.map(|(_, e)| e);
            let ratio = [eff[0] / eff[2], eff[1] / eff[2]];
            if spp >= 4 {
                ratios[0].push(ratio[0]);
                ratios[1].push(ratio[1]);
            }
            text += &format!(
                "  {spp:<5} {:>18.3}  {:<10.5} | {:>17.3}  {:<10.5} | {:>17.3}  {:<10.5} | {:>31.1}x {:>8.1}x\n",
                row[0].0 * 1e3,
                row[0].1,
                row[1].0 * 1e3,
                row[1].1,
                row[2].0 * 1e3,
                row[2].1,
                ratio[0],
                ratio[1],
            );
        }
        let median = |mut r: Vec<f64>| {
            r.sort_by(f64::total_cmp);
            r[r.len() / 2]
        };
        let [tree, weight] = ratios;
        text += &format!(
            "  efficiency over BSDF only, median at 4..64 spp: light tree {:.1}x, by weight {:.1}x\n",
            median(tree),
            median(weight)
        );
        // Steady state: GPU time per sample of back-to-back dispatches (the GPU never idles,
        // so its clocks stay up), each of the samples per dispatch the renderer uses, and
        // relMSE × spp at 64 spp.
        let pixels = width as u64 * height as u64;
        let mut per_sample = [0.0; 3];
        for (i, v) in variants.into_iter().enumerate() {
            let n = session.tracer().samples_per_dispatch_for(pixels, v);
            let mut t = Vec::new();
            for round in 0..6 {
                let times = session.time_repeated(&view, params, v, (width, height), n, 10)?;
                if round >= 2 {
                    t.extend(times);
                }
            }
            if t.is_empty() {
                bail!("this queue cannot take timestamps");
            }
            t.sort_by(f64::total_cmp);
            per_sample[i] = t[t.len() / 2] / n as f64;
        }
        let eff = |i: usize| 1.0 / (last_error[i] * per_sample[i]);
        text += &format!(
            "  steady state: {:.3} / {:.3} / {:.3} ms per sample (light tree / by weight / BSDF only, back-to-back dispatches); \
             relMSE x spp at 64 spp {:.3} / {:.3} / {:.3}; efficiency over BSDF only: light tree {:.1}x, by weight {:.1}x\n",
            per_sample[0] * 1e3,
            per_sample[1] * 1e3,
            per_sample[2] * 1e3,
            last_error[0] * 64.0,
            last_error[1] * 64.0,
            last_error[2] * 64.0,
            eff(0) / eff(2),
            eff(1) / eff(2),
        );
        drop(session);
        drop(view);
        text += &edit_cost(&scene)?;
    }
    Ok(text)
}

/// Adds and removes a 22 × 22 × 21 box of emissive voxels (10 164) in empty space, ten times:
/// the edits' median wall time with their light updates, the light faces and the bytes the
/// light region reports dirty.
fn edit_cost(scene: &Scene) -> Result<String> {
    let w = &scene.world;
    let m = (0..w.materials().len() as u8)
        .find(|&i| {
            w.materials()
                .get(i)
                .is_ok_and(|m| m.kind == MaterialKind::Emissive)
        })
        .context("no emissive material")?;
    let v = w.dims().voxels();
    let min = IVec3::new(v.x * 3 / 4 - 11, v.y - 30, v.z / 4 - 11);
    let shape = Shape::Box {
        min,
        max: min + IVec3::new(21, 20, 21),
    };
    let (mut add, mut remove, mut faces, mut bytes) = (Vec::new(), Vec::new(), 0, 0);
    w.take_dirty();
    for _ in 0..10 {
        let before = w.read().lights().len();
        let t = Instant::now();
        let done = w.apply(EditOp::Shape {
            shape: shape.clone(),
            mode: Mode::Add(m),
        })?;
        add.push(t.elapsed().as_secs_f64());
        faces = w.read().lights().len() - before;
        bytes = w
            .take_dirty()
            .of(GpuBuffer::Lights)
            .iter()
            .map(|r| r.end - r.start)
            .sum::<u64>();
        let t = Instant::now();
        w.apply(EditOp::Restore(done.inverse))?;
        remove.push(t.elapsed().as_secs_f64());
        w.take_dirty();
        if done.changed_voxels != 10_164 {
            bail!("the lamp box changed {} voxels", done.changed_voxels);
        }
    }
    let median = |mut t: Vec<f64>| {
        t.sort_by(f64::total_cmp);
        t[t.len() / 2] * 1e3
    };
    Ok(format!(
        "  edit: 10164 emissive voxels added in {:.2} ms, removed (undo) in {:.2} ms (median of 10, light update included); {faces} light faces, {bytes} light-region bytes dirty\n",
        median(add),
        median(remove)
    ))
}
