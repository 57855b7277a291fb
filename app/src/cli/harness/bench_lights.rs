//! `voxbrick bench-gpu --lights`: what light sampling of emissive voxels buys. For a lamp-lit
//! room and the thesis scene with lamps added: relative MSE against a converged reference and
//! GPU time at 1 … 64 spp, with light sampling and with BSDF sampling alone; efficiency
//! 1 / (relMSE × time), whose ratio at equal spp is the ratio at equal error (both estimators
//! are unbiased: relMSE ∝ 1/spp, time ∝ spp). Then the cost of an edit adding or removing
//! 10 k emissive voxels (the world's edit with its light update, and the bytes it dirties).

use super::with_progress;
use anyhow::{Context, Result, bail};
use app::Scene;
use app::builtin::thesis_scene;
use brickmap::{EditOp, GpuBuffer, GridDims, MaterialKind, Mode, Shape};
use glam::{DVec3, IVec3};
use render::cpu::RenderJob;
use render::viewport::RenderHow;
use render::vulkan::trace::Variant;
use render::{Camera, Image, Sky};
use std::time::Instant;

fn rel_mse(image: &Image, reference: &Image) -> f64 {
    render::convergence::rel_mse(image, reference).unwrap_or(f64::NAN)
}

fn lamp(scene: &Scene, strength: f32, rgb: [u8; 3]) -> Result<u8> {
    let w = &scene.world;
    let param = 1 + w.materials().len() as u8 % 60;
    w.set_param(MaterialKind::Emissive, param, strength)?;
    let colour = 200 + w.materials().len() as u8 % 50;
    w.set_colour(colour, rgb);
    Ok(w.push_material(brickmap::Material {
        kind: MaterialKind::Emissive,
        param,
        colour,
    })?)
}

fn fill(scene: &Scene, m: u8, min: IVec3, max: IVec3) -> Result<()> {
    scene.edit(EditOp::Shape {
        shape: Shape::Box { min, max },
        mode: Mode::Add(m),
    })?;
    Ok(())
}

/// A 128 × 64 × 128 room (walls of albedo 0.46, a table, a shelf) lit only by a few emissive voxels: a
/// 2 × 1 × 2 ceiling lamp and a 1 × 2 × 1 table lamp; no sun, black sky, 4 bounces.
pub(crate) fn lamp_room(workers: usize) -> Result<Scene> {
    let dims = GridDims::new(16, 8, 16)?;
    let mut scene = Scene::empty(dims, workers)?;
    let v = dims.voxels() - 1;
    // Walls of a mid albedo (sRGB 180: 0.46 linear), as painted interiors have.
    scene.world.set_colour(199, [180, 180, 180]);
    let wall = scene
        .world
        .push_material(brickmap::Material::lambertian(199))?;
    fill(&scene, wall, IVec3::ZERO, v)?;
    scene.edit(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::ONE,
            max: v - 1,
        },
        mode: Mode::Remove,
    })?;
    fill(&scene, wall, IVec3::new(40, 1, 50), IVec3::new(80, 20, 80))?; // table
    fill(&scene, wall, IVec3::new(1, 30, 20), IVec3::new(12, 32, 100))?; // shelf
    let ceiling = lamp(&scene, 300.0, [255, 236, 210])?;
    fill(
        &scene,
        ceiling,
        IVec3::new(63, 62, 63),
        IVec3::new(64, 62, 64),
    )?;
    let table = lamp(&scene, 300.0, [255, 190, 120])?;
    fill(
        &scene,
        table,
        IVec3::new(70, 21, 70),
        IVec3::new(70, 22, 70),
    )?;
    let p = &mut scene.params;
    p.camera = Camera::looking_at(
        DVec3::new(110.0, 40.0, 120.0),
        DVec3::new(55.0, 15.0, 55.0),
        60.0,
    );
    p.sun.enabled = false;
    p.sky = Sky::Uniform { colour: [0.0; 3] };
    p.settings.max_bounces = 4;
    scene.world.take_dirty();
    Ok(scene)
}

/// The thesis scene at complexity 3 (3 bounces, sun) with six 3³ lamps on the ground.
pub(crate) fn thesis_with_lamps(workers: usize) -> Result<Scene> {
    let mut scene = thesis_scene(workers)?;
    scene.params.settings.max_bounces = 3;
    scene.params.sun.enabled = true;
    let m = lamp(&scene, 30.0, [255, 150, 60])?;
    let v = scene.world.dims().voxels();
    for k in 0..6 {
        let x = v.x / 2 - 60 + 24 * k;
        let z = v.z / 2 + 40 - 16 * (k % 3);
        let ground = scene
            .world
            .read()
            .ray_cast(
                &brickmap::Ray {
                    origin: DVec3::new(x as f64 + 0.5, v.y as f64 + 1.0, z as f64 + 0.5),
                    dir: DVec3::NEG_Y,
                },
                f64::INFINITY,
            )?
            .map_or(0, |(hit, _)| hit.voxel.y + 1)
            .min(v.y - 3);
        fill(
            &scene,
            m,
            IVec3::new(x, ground, z),
            IVec3::new(x + 2, ground + 2, z + 2),
        )?;
    }
    scene.world.take_dirty();
    Ok(scene)
}

pub(crate) fn bench_lights(
    device: &str,
    workers: usize,
    (width, height): (u32, u32),
    reference_spp: u32,
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
    ] {
        let view = scene.world.read();
        let params = &scene.params;
        let mut session = app::gpu::session(device, &view)?;
        if text.is_empty() {
            let ctx = session.ctx();
            text += &format!("device       {} ({})\n", ctx.name, ctx.driver);
        }
        let on = Variant::for_scene(&view, params);
        if !on.lights {
            bail!("{name}: no light faces");
        }
        let off = Variant {
            lights: false,
            ..on
        };
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
        text += &format!(
            "{name}: {} light faces, {width}x{height}, reference {reference_spp} spp with light sampling\n  \
             spp   light sampling: GPU ms  relMSE     efficiency   | BSDF only: GPU ms  relMSE     efficiency  | ratio\n",
            view.lights().len()
        );
        let mut ratios = Vec::new();
        // relMSE of the last (64-spp) row, light sampling and BSDF only.
        let mut last_error = [0.0; 2];
        for spp in (0..7).map(|k| 1u32 << k) {
            let mut row = [(0.0, 0.0); 2];
            for (i, v) in [on, off].into_iter().enumerate() {
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
            let ratio = eff[0] / eff[1];
            if spp >= 4 {
                ratios.push(ratio);
            }
            text += &format!(
                "  {spp:<5} {:>23.3}  {:<10.5} {:<12.4e} | {:>17.3}  {:<10.5} {:<12.4e}| {ratio:.1}x\n",
                row[0].0 * 1e3,
                row[0].1,
                eff[0],
                row[1].0 * 1e3,
                row[1].1,
                eff[1],
            );
        }
        ratios.sort_by(f64::total_cmp);
        text += &format!(
            "  efficiency with light sampling over BSDF only, median at 4..64 spp: {:.1}x\n",
            ratios[ratios.len() / 2]
        );
        // Steady state: GPU time per sample of back-to-back dispatches (the GPU never idles,
        // so its clocks stay up), each of the samples per dispatch the renderer uses, and
        // relMSE × spp at 64 spp.
        let pixels = width as u64 * height as u64;
        let mut per_sample = [0.0; 2];
        for (i, v) in [on, off].into_iter().enumerate() {
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
        let [e_on, e_off] = last_error;
        text += &format!(
            "  steady state: {:.3} / {:.3} ms per sample (light sampling / BSDF only, back-to-back dispatches); \
             relMSE x spp at 64 spp {:.2} / {:.2}; efficiency ratio {:.1}x\n",
            per_sample[0] * 1e3,
            per_sample[1] * 1e3,
            e_on * 64.0,
            e_off * 64.0,
            (e_off * per_sample[1]) / (e_on * per_sample[0])
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
