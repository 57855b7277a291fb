//! `voxbrick bench-skips`: what each thing the renderer skips buys, on the benchmark scene
//! (the thesis scene at the path's first view, complexity 3) and on a scene that needs it.
//! Traversal and pipeline skips: steady-state GPU time per dispatch with the skip and without
//! it (trace.comp's experiment bits 7..10 turn traversal skips off; the everything variant
//! has every material kind, the sun and the gradient sky compiled in), every variant timed in
//! turn in each round after warm-up, and a check that both render the same image. Viewport
//! skips: accumulation when still (relMSE of one frame's samples against that of a second of
//! frames, against a reference) and the lower internal resolution while moving (GPU time per
//! frame at the editor's moving scale and at full size). Writes skips.md and skips.json.

use super::bench::{PRESETS, params_at};
use super::table::Table;
use super::{args, emit};
use anyhow::{Context, Result, bail};
use app::camera_path::CameraPath;
use brickmap::{
    EditOp, GridDims, Material, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp, World, WorldConfig,
};
use glam::{DVec3, IVec3};
use render::convergence::rel_mse;
use render::cpu::RenderJob;
use render::viewport::{RenderHow, Viewport};
use render::vulkan::trace::Variant;
use render::{Camera, SceneParams, Sky};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;

/// `voxbrick bench-skips`: what to measure.
#[derive(clap::Args)]
pub(crate) struct BenchSkips {
    /// Device name filter ("gpu": the best).
    #[arg(long, default_value = "gpu")]
    device: String,
    /// Internal resolution of the traversal and pipeline cases, WxH.
    #[arg(long, default_value = "1024x576", value_parser = args::resolution)]
    size: (u32, u32),
    /// Window size of the moving-resolution case, WxH.
    #[arg(long, default_value = "1920x1080", value_parser = args::resolution)]
    window: (u32, u32),
    /// Timed rounds of 10 dispatches per variant (after two of warm-up).
    #[arg(long, default_value_t = 5)]
    rounds: usize,
    /// Seconds of 60 Hz frames in the accumulation case's reference image.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(2..=1024))]
    reference_seconds: u32,
    /// Folder for the report.
    #[arg(long, default_value = "skips-report")]
    out: PathBuf,
}

/// A thing the renderer skips.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
enum Skip {
    /// Pipeline variants without unused material kinds, the sun or the gradient sky.
    Variant,
    /// Empty 32³ coarse cells crossed whole.
    CoarseGrid,
    /// Empty 4³ and 2³ blocks inside stored bricks crossed whole.
    InBrickBlocks,
    /// Inside a dielectric, a brick full of it crossed whole.
    UniformMedia,
    /// Full cells: solid uniform bricks in the brick index alone.
    FullCells,
    /// Samples accumulate while nothing changes.
    Accumulation,
    /// A lower internal resolution while the camera moves.
    MovingResolution,
}

impl Skip {
    fn name(self) -> &'static str {
        match self {
            Skip::Variant => "pipeline variant (unused kinds, sun, sky compiled out)",
            Skip::CoarseGrid => "coarse-grid empty-space skip (32³)",
            Skip::InBrickBlocks => "in-brick empty-space skip (4³, 2³)",
            Skip::UniformMedia => "uniform media (a brick full of the medium crossed whole)",
            Skip::FullCells => "full cells (no brick stored)",
            Skip::Accumulation => "accumulation when still",
            Skip::MovingResolution => "lower internal resolution while moving",
        }
    }

    /// trace.comp's experiment bit that turns a traversal skip off.
    fn experiment(self) -> Option<u32> {
        match self {
            Skip::CoarseGrid => Some(1 << 7),
            Skip::InBrickBlocks => Some(1 << 8),
            Skip::UniformMedia => Some(1 << 9),
            Skip::FullCells => Some(1 << 10),
            _ => None,
        }
    }
}

/// One row of the table.
#[derive(Clone, Debug, Serialize)]
struct Row {
    skip: Skip,
    name: &'static str,
    scene: String,
    /// What is compared: "GPU ms per dispatch" or "relMSE".
    measure: &'static str,
    with: f64,
    without: f64,
    /// without / with (> 1: the skip pays).
    gain: f64,
    /// relMSE between the images with and without it (traversal and pipeline skips).
    same_image_rel_mse: Option<f64>,
    note: String,
}

/// A scene to measure on.
struct Case {
    name: String,
    world: World,
    params: SceneParams,
}

/// Dispatches per round.
const ROUND: u32 = 10;
/// The most relMSE between the images with and without a traversal skip (float rounding).
const SAME_IMAGE: f64 = 1e-8;
/// Frames of a second of refinement at 60 Hz.
const SECOND: u32 = 60;
/// The editor's default internal scale while moving.
const MOVING_SCALE: f64 = 0.5;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median GPU ms per dispatch of `spp` samples of each variant, interleaved in rounds.
fn steady(
    session: &mut Viewport,
    case: &Case,
    sizes: &[((u32, u32), Variant)],
    spp: u32,
    rounds: usize,
) -> Result<Vec<f64>> {
    let view = case.world.read();
    let mut times = vec![Vec::new(); sizes.len()];
    for round in 0..rounds + 2 {
        for (k, (size, v)) in sizes.iter().enumerate() {
            let t = session.time_repeated(&view, &case.params, *v, *size, spp, ROUND)?;
            if t.is_empty() {
                bail!("this queue cannot take timestamps");
            }
            if round >= 2 {
                times[k].extend(t.iter().map(|s| s * 1e3));
            }
        }
    }
    Ok(times.into_iter().map(median).collect())
}

fn everything(v: Variant) -> Variant {
    Variant {
        lambertian: true,
        metal: true,
        dielectric: true,
        emissive: true,
        sun: true,
        gradient_sky: true,
        ..v
    }
}

/// With and without a traversal or pipeline skip: times and the same-image check.
fn traversal_row(
    session: &mut Viewport,
    case: &Case,
    skip: Skip,
    (size, spp, rounds): ((u32, u32), u32, usize),
) -> Result<Row> {
    let view = case.world.read();
    let with = Variant::for_scene(&view, &case.params);
    let without = match skip.experiment() {
        Some(bit) => Variant {
            experiment: bit,
            ..with
        },
        None => everything(with),
    };
    let job = RenderJob::sized(size, spp, 5);
    let a = session
        .render(&view, &case.params, &job, RenderHow::variant(with))?
        .image;
    let b = session
        .render(&view, &case.params, &job, RenderHow::variant(without))?
        .image;
    let same = rel_mse(&b, &a).context("image sizes differ")?;
    if same > SAME_IMAGE {
        bail!(
            "{} on {}: the image without it differs (relMSE {same:.2e})",
            skip.name(),
            case.name
        );
    }
    let memory = view.memory();
    drop(view);
    let t = steady(session, case, &[(size, with), (size, without)], spp, rounds)?;
    let mut note = format!("{spp} spp per dispatch");
    if skip == Skip::FullCells {
        // What full cells save: each would be a stored uniform brick (68 bytes, no material
        // bytes), the brick index unchanged.
        let used = memory.gpu_used() as f64 / 1e6;
        let _ = write!(
            note,
            "; world GPU memory {used:.1} MB with full cells, {:.1} MB with its {} full cells stored as bricks",
            used + memory.full_cells as f64 * 68.0 / 1e6,
            memory.full_cells
        );
    }
    Ok(Row {
        skip,
        name: skip.name(),
        scene: case.name.clone(),
        measure: "GPU ms per dispatch",
        with: t[0],
        without: t[1],
        gain: t[1] / t[0],
        same_image_rel_mse: Some(same),
        note,
    })
}

/// Accumulation when still: one frame's samples against a second of frames, as relMSE
/// against a reference of `seconds` seconds of frames.
fn accumulation_row(
    session: &mut Viewport,
    case: &Case,
    size: (u32, u32),
    spp: u32,
    seconds: u32,
) -> Result<Row> {
    let view = case.world.read();
    let mut render = |spp: u32, seed: u64| {
        session
            .render(
                &view,
                &case.params,
                &RenderJob::sized(size, spp, seed),
                RenderHow::SCENE,
            )
            .map(|r| r.image)
    };
    let reference = render(seconds * SECOND * spp, 1)?;
    let one = render(spp, 2)?;
    let second = render(SECOND * spp, 3)?;
    let (e1, e60) = (
        rel_mse(&one, &reference).context("sizes")?,
        rel_mse(&second, &reference).context("sizes")?,
    );
    Ok(Row {
        skip: Skip::Accumulation,
        name: Skip::Accumulation.name(),
        scene: case.name.clone(),
        measure: "relMSE after 1 s at 60 Hz",
        with: e60,
        without: e1,
        gain: e1 / e60,
        same_image_rel_mse: None,
        note: format!(
            "{spp} spp per frame; without it every frame shows its own samples; reference {} spp",
            seconds * SECOND * spp
        ),
    })
}

/// The lower internal resolution while moving: GPU ms per frame at the moving scale and at
/// full size.
fn moving_row(
    session: &mut Viewport,
    case: &Case,
    (window, spp, rounds): ((u32, u32), u32, usize),
) -> Result<Row> {
    let scaled = (
        ((f64::from(window.0) * MOVING_SCALE).ceil() as u32).max(1),
        ((f64::from(window.1) * MOVING_SCALE).ceil() as u32).max(1),
    );
    let v = Variant::for_scene(&case.world.read(), &case.params);
    let t = steady(session, case, &[(scaled, v), (window, v)], spp, rounds)?;
    Ok(Row {
        skip: Skip::MovingResolution,
        name: Skip::MovingResolution.name(),
        scene: case.name.clone(),
        measure: "GPU ms per frame",
        with: t[0],
        without: t[1],
        gain: t[1] / t[0],
        same_image_rel_mse: None,
        note: format!(
            "{}x{} while moving (scale {MOVING_SCALE}) against {}x{}, {spp} spp",
            scaled.0, scaled.1, window.0, window.1
        ),
    })
}

fn material(w: &World, kind: MaterialKind, param: u8, colour: u8, rgb: [u8; 3]) -> Result<u8> {
    w.set_colour(colour, rgb);
    Ok(w.push_material(Material {
        kind,
        param,
        colour,
    })?)
}

fn add(w: &World, shape: Shape, m: u8) -> Result<()> {
    w.apply(EditOp::Shape {
        shape,
        mode: Mode::Add(m),
    })?;
    Ok(())
}

fn boxed(min: [i32; 3], max: [i32; 3]) -> Shape {
    Shape::Box {
        min: IVec3::from(min),
        max: IVec3::from(max),
    }
}

/// Parameters of a needy scene: the thesis scene's settings, a camera, a sky, sun or not.
fn needy_params(base: &SceneParams, camera: Camera, sky: Sky, sun: bool) -> SceneParams {
    let mut p = base.clone();
    p.camera = camera;
    p.sky = sky;
    p.sun.enabled = sun;
    p
}

/// The scene that needs each skip (the benchmark scene's parameters as a base).
fn needy_scene(skip: Skip, base: &SceneParams, workers: usize) -> Result<Case> {
    let config = WorldConfig::with_workers(workers);
    let sky = Sky::Uniform {
        colour: [0.8, 0.85, 1.0],
    };
    let (name, world, params) = match skip {
        Skip::Variant | Skip::Accumulation | Skip::MovingResolution => {
            // Lambertian blocks under a uniform sky, no sun: the variant drops metal,
            // dielectric and emissive code, the sun and the gradient.
            let w = World::new(GridDims::new(32, 8, 32)?, config)?;
            let floor = material(&w, MaterialKind::Lambertian, 0, 200, [180, 170, 150])?;
            let block = material(&w, MaterialKind::Lambertian, 0, 201, [120, 160, 200])?;
            add(&w, boxed([0, 0, 0], [255, 3, 255]), floor)?;
            for k in 0..24 {
                let (x, z) = (20 + (k % 6) * 38, 20 + (k / 6) * 55);
                add(
                    &w,
                    boxed([x, 4, z], [x + 14, 8 + (k * 7) % 30, z + 14]),
                    block,
                )?;
            }
            let cam = Camera::looking_at(
                DVec3::new(-20.0, 90.0, -20.0),
                DVec3::new(128.0, 0.0, 128.0),
                60.0,
            );
            (
                "lambertian blocks, no sun",
                w,
                needy_params(base, cam, sky, false),
            )
        }
        Skip::CoarseGrid => {
            // A large, mostly empty grid: a few spheres far apart.
            let w = World::new(GridDims::new(256, 32, 256)?, config)?;
            let m = material(&w, MaterialKind::Lambertian, 0, 200, [200, 120, 90])?;
            for k in 0..12 {
                let c = DVec3::new(
                    150.0 + 150.0 * f64::from(k % 4) * 1.1,
                    40.0,
                    200.0 + 500.0 * f64::from(k / 4),
                );
                add(
                    &w,
                    Shape::Sphere {
                        centre: c,
                        radius: 24.0,
                    },
                    m,
                )?;
            }
            let cam = Camera::looking_at(
                DVec3::new(0.0, 120.0, 0.0),
                DVec3::new(1024.0, 0.0, 1024.0),
                60.0,
            );
            (
                "sparse spheres in a 2048 x 256 x 2048 grid",
                w,
                needy_params(base, cam, sky, true),
            )
        }
        Skip::InBrickBlocks => {
            // Scattered voxels: nearly every brick stored, most of each brick empty.
            let w = World::new(GridDims::new(32, 8, 32)?, config)?;
            let m = material(&w, MaterialKind::Lambertian, 0, 200, [150, 200, 120])?;
            let mut edits = Vec::new();
            let mut state = 0x9e37_79b9_u32;
            for x in 0..256 {
                for z in 0..256 {
                    for y in 0..40 {
                        state ^= state << 13;
                        state ^= state >> 17;
                        state ^= state << 5;
                        if state.is_multiple_of(50) {
                            edits.push(VoxelEdit {
                                pos: IVec3::new(x, y, z),
                                op: VoxelOp::Set(m),
                            });
                        }
                    }
                }
            }
            w.apply(EditOp::Voxels(edits))?;
            let cam = Camera::looking_at(
                DVec3::new(-10.0, 70.0, -10.0),
                DVec3::new(128.0, 10.0, 128.0),
                60.0,
            );
            (
                "scattered voxels (2 % of the lower 40 layers)",
                w,
                needy_params(base, cam, sky, true),
            )
        }
        Skip::UniformMedia => {
            // Deep water over a floor, seen from above.
            let w = World::new(GridDims::new(32, 8, 32)?, config)?;
            let floor = material(&w, MaterialKind::Lambertian, 0, 200, [190, 180, 140])?;
            w.set_param(MaterialKind::Dielectric, 1, 1.333)?;
            let water = material(&w, MaterialKind::Dielectric, 1, 201, [200, 230, 255])?;
            add(&w, boxed([0, 0, 0], [255, 3, 255]), floor)?;
            add(&w, boxed([0, 4, 0], [255, 55, 255]), water)?;
            let cam = Camera::looking_at(
                DVec3::new(128.0, 110.0, -40.0),
                DVec3::new(128.0, 0.0, 128.0),
                60.0,
            );
            (
                "deep water (52 voxels)",
                w,
                needy_params(base, cam, sky, true),
            )
        }
        Skip::FullCells => {
            // Solid stone: every surface brick that is solid is a full cell.
            let w = World::new(GridDims::new(32, 8, 32)?, config)?;
            let m = material(&w, MaterialKind::Lambertian, 0, 200, [140, 140, 150])?;
            add(&w, boxed([0, 0, 0], [255, 31, 255]), m)?;
            for k in 0..8 {
                let x = 16 + k * 30;
                add(&w, boxed([x, 32, 40], [x + 15, 63, 215]), m)?;
            }
            let cam = Camera::looking_at(
                DVec3::new(128.0, 100.0, -60.0),
                DVec3::new(128.0, 30.0, 128.0),
                60.0,
            );
            (
                "solid blocks on brick boundaries",
                w,
                needy_params(base, cam, sky, true),
            )
        }
    };
    Ok(Case {
        name: name.into(),
        world,
        params,
    })
}

/// Runs every skip on the benchmark scene and on the scene that needs it.
/// Measures every skip, writes skips.md and skips.json and prints the table.
pub(crate) fn run(b: BenchSkips, workers: usize) -> Result<()> {
    emit(&bench_skips(b, workers)?)
}

fn bench_skips(b: BenchSkips, workers: usize) -> Result<String> {
    std::fs::create_dir_all(&b.out).with_context(|| format!("creating {}", b.out.display()))?;
    let ctx = app::gpu::context(&b.device, false)?;
    let thesis = app::builtin::thesis_scene(workers)?;
    let path = CameraPath::thesis();
    let preset = &PRESETS[2];
    let centre = thesis.world.read().dims().voxels().as_dvec3() * 0.5;
    let params = params_at(&thesis.params, &path, preset, 0.0, centre);
    let bench_case = Case {
        name: "thesis (complexity 3, path at 0 s)".into(),
        world: thesis.world,
        params,
    };
    let skips = [
        Skip::Variant,
        Skip::CoarseGrid,
        Skip::InBrickBlocks,
        Skip::UniformMedia,
        Skip::FullCells,
        Skip::Accumulation,
        Skip::MovingResolution,
    ];
    let rounds = b.rounds.max(1);
    let mut rows = Vec::new();
    for skip in skips {
        let needy = needy_scene(skip, &bench_case.params, workers)?;
        for case in [&bench_case, &needy] {
            eprintln!("{}: {}", skip.name(), case.name);
            let mut session = Viewport::new(ctx.clone(), &case.world.read())?;
            let spp = preset.spp;
            let row = match skip {
                Skip::Accumulation => {
                    accumulation_row(&mut session, case, b.size, spp, b.reference_seconds)?
                }
                Skip::MovingResolution => moving_row(&mut session, case, (b.window, spp, rounds))?,
                _ => traversal_row(&mut session, case, skip, (b.size, spp, rounds))?,
            };
            rows.push(row);
        }
    }
    report(&b, &ctx, &rows)
}

/// Milliseconds to four places; small errors in scientific notation.
fn figure(x: f64) -> String {
    if x < 0.01 {
        format!("{x:.3e}")
    } else {
        format!("{x:.4}")
    }
}

fn report(b: &BenchSkips, ctx: &render::vulkan::GpuContext, rows: &[Row]) -> Result<String> {
    let mut md = format!(
        "# What each skip buys\n\n{} ({}), {}x{} internal ({}x{} window for the moving case); GPU times are medians of {} rounds of {ROUND} back-to-back dispatches after two rounds of warm-up, with and without in turn. Gain = without / with (> 1: the skip pays).\n\n",
        ctx.name, ctx.driver, b.size.0, b.size.1, b.window.0, b.window.1, b.rounds
    );
    let mut table = Table::new(&[
        "skip",
        "scene",
        "measure",
        "with",
        "without",
        "gain",
        "same image (relMSE)",
        "note",
    ]);
    for r in rows {
        table.row(&[
            &r.name,
            &r.scene,
            &r.measure,
            &figure(r.with),
            &figure(r.without),
            &format!("{:.2}", r.gain),
            &r.same_image_rel_mse
                .map_or("–".into(), |s| format!("{s:.1e}")),
            &r.note,
        ]);
    }
    md += &table.finish();
    let json = serde_json::json!({
        "device": ctx.name, "driver": ctx.driver, "clocks": super::bench::clocks(),
        "size": [b.size.0, b.size.1], "window": [b.window.0, b.window.1], "rows": rows,
    });
    super::write_json(&b.out.join("skips.json"), &json)?;
    super::write_report(&b.out.join("skips.md"), &md)?;
    Ok(md)
}
