//! `voxbrick bench-viewport`: the editor's frame loop without a window — the same
//! [`Viewport`] frames in flight the window draws (trace, display pass; only the copy into a
//! swapchain image and egui are absent) — at a window size and internal scales, on the thesis
//! scene. Reports GPU time per frame (timestamp queries), host time to record and submit a
//! frame, and camera move → first frame showing it (frames and ms, submit to completion).

mod objects;
mod orbit;
mod selection;

use super::{args, emit, with_progress};
use anyhow::{Result, bail};
use app::builtin::{SceneSize, default_scene, thesis_scene};
use brickmap::World;
use render::SceneParams;
use render::present::{EguiFrame, Presented, Presenter, Show};
use render::viewport::{FrameRequest, Viewport};
use std::time::Instant;

/// `voxbrick bench-viewport`: what to measure.
#[derive(clap::Args)]
pub(crate) struct BenchViewport {
    /// Output (window) size, as WxH.
    #[arg(long, value_parser = args::window_size, default_value = "1920x1080")]
    size: (u32, u32),
    /// Internal scales, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0.5,1.0")]
    scales: Vec<f32>,
    /// Timed frames per case (after warm-up).
    #[arg(long, default_value_t = 200)]
    frames: usize,
    /// Samples per pixel each frame adds.
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Vulkan device (part of its name).
    #[arg(long)]
    device: Option<String>,
    /// Also measure the window's half: the copy into an offscreen image of the window's
    /// size and egui panels painted on it.
    #[arg(long)]
    ui: bool,
    /// Also measure each case with the viewport's denoiser on.
    #[arg(long)]
    denoise: bool,
    /// Instead: edit → first frame showing it, on the default 512 × 256 × 512 scene, for
    /// live sphere strokes of these radii (comma-separated), and the brush preview's
    /// update time.
    #[arg(long, value_delimiter = ',')]
    edits: Vec<f64>,
    /// Instead: this many frames of the denoised viewport along an orbit, with and without
    /// temporal reprojection, each against a converged reference of its view (at the first
    /// of --scales), then the frames after the stop.
    #[arg(long, value_name = "FRAMES", value_parser = clap::value_parser!(u32).range(2..=600))]
    orbit: Option<u32>,
    /// Samples per pixel of the orbit's references.
    #[arg(long, default_value_t = 1024)]
    reference_spp: u32,
}

/// Checks the arguments, builds the scene (the thesis scene, or the default one for
/// `--edits`) and its GPU session, and prints the report.
pub(crate) fn command(mut b: BenchViewport, workers: usize) -> Result<()> {
    if let Some(s) = b.scales.iter().find(|s| !(**s > 0.0 && **s <= 1.0)) {
        bail!("internal scale {s} is outside (0, 1]");
    }
    if let Some(r) = b.edits.iter().find(|r| !(**r >= 1.0 && **r <= 64.0)) {
        bail!("--edits radius {r} is outside 1..=64");
    }
    let device = b.device.clone().unwrap_or_else(|| "gpu".into());
    if !b.edits.is_empty() {
        let scene = with_progress("building the default scene".into(), || {
            default_scene(SceneSize::Full, workers)
        })?;
        let session = {
            let view = scene.world.read();
            app::gpu::session(&device, &view)?
        };
        return emit(&edits(
            session,
            scene,
            b.size,
            &b.scales,
            &b.edits,
            b.frames.clamp(10, 400),
        )?);
    }
    b.frames = b.frames.max(1);
    b.spp = b.spp.clamp(1, 16);
    let mut scene = thesis_scene(workers)?;
    scene.params.sun.enabled = true;
    scene.params.settings.max_bounces = 3;
    let mut session = {
        let view = scene.world.read();
        app::gpu::session_with(&device, &view, b.ui)?
    };
    if let Some(frames) = b.orbit {
        let internal = scaled(b.size, b.scales[0]);
        let text = orbit::orbit_report(
            &mut session,
            &scene.world,
            &scene.params,
            internal,
            frames as usize,
            b.reference_spp.max(1),
        )?;
        return emit(&text);
    }
    emit(&run(session, &scene.world, &scene.params, &b)?)
}

fn scaled((w, h): (u32, u32), f: f32) -> (u32, u32) {
    (
        ((w as f64 * f as f64).ceil() as u32).max(1),
        ((h as f64 * f as f64).ceil() as u32).max(1),
    )
}

pub(crate) fn stats(mut v: Vec<f64>) -> (f64, f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN, f64::NAN);
    }
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    (q(0.0), q(0.5), q(0.99), v[v.len() - 1])
}

/// Frames before timing starts (pipelines, clocks).
const WARM_UP: usize = 8;

/// Per-frame figures after the warm-up: GPU seconds (each slot's timestamps, read when the
/// slot comes round again), host time, and the wall clock from the end of the warm-up.
struct Timing<T> {
    gpu: Vec<f64>,
    host: Vec<T>,
    timed_from: Option<Instant>,
}

impl<T> Timing<T> {
    fn new() -> Self {
        Self {
            gpu: Vec::new(),
            host: Vec::new(),
            timed_from: None,
        }
    }

    /// Frame number `n` (from 1) was submitted, having taken `spent` on the host.
    fn frame(&mut self, vp: &Viewport, n: usize, spent: T) -> Result<()> {
        if n == WARM_UP {
            vp.wait_idle()?;
            self.timed_from = Some(Instant::now());
        }
        if n > WARM_UP {
            self.host.push(spent);
            if let Some(t) = vp.last_gpu_seconds() {
                self.gpu.push(t);
            }
        }
        Ok(())
    }

    /// (GPU seconds, host times, wall seconds per frame) after `frames` timed frames.
    fn finish(self, vp: &Viewport, frames: usize) -> Result<(Vec<f64>, Vec<T>, f64)> {
        vp.wait_idle()?;
        let wall = self
            .timed_from
            .map_or(f64::NAN, |t| t.elapsed().as_secs_f64() / frames as f64);
        Ok((self.gpu, self.host, wall))
    }
}

/// One case: `frames` frames, each `spp` more samples (restarting each frame when `moving`).
/// Returns (GPU seconds per frame, host seconds per frame: begin, record, submit, and wall
/// seconds per frame of the whole loop: throughput, the GPU kept busy).
fn run_case(
    vp: &mut Viewport,
    world: &World,
    params: &SceneParams,
    req: FrameRequest<'_>,
    frames: usize,
    moving: bool,
) -> Result<(Vec<f64>, Vec<[f64; 3]>, f64)> {
    let mut timing = Timing::new();
    let mut p = params.clone();
    let mut submitted = 0;
    while submitted < frames + WARM_UP {
        let started = Instant::now();
        let Some(frame) = vp.begin_frame()? else {
            // Both slots in flight: the window's loop would handle events meanwhile.
            std::thread::yield_now();
            continue;
        };
        if moving {
            // An orbit of 0.05° per frame drawn (about 3°/s at 60 Hz).
            p.camera.yaw_deg += 0.05;
        }
        let req = FrameRequest { params: &p, ..req };
        let begun = started.elapsed().as_secs_f64();
        let before = Instant::now();
        vp.trace_frame(&frame, world, &req)?;
        let recorded = before.elapsed().as_secs_f64();
        let before = Instant::now();
        vp.submit_frame(frame, &[], &[])?;
        let spent = [begun, recorded, before.elapsed().as_secs_f64()];
        submitted += 1;
        timing.frame(vp, submitted, spent)?;
    }
    timing.finish(vp, frames)
}

/// [`run_case`] through the presenter into an offscreen image, with egui panels like the
/// editor's (menu bar, status line, a settings window) built, tessellated and painted each
/// frame; host time is the whole frame (egui included).
fn run_case_ui(
    vp: &mut Viewport,
    presenter: &mut Presenter,
    world: &World,
    params: &SceneParams,
    req: FrameRequest<'_>,
    frames: usize,
    moving: bool,
) -> Result<(Vec<f64>, Vec<f64>, f64)> {
    let egui_ctx = egui::Context::default();
    let mut pending = egui::TexturesDelta::default();
    let mut timing = Timing::new();
    let mut p = params.clone();
    let mut drawn = 0;
    let mut value = 0.5f32;
    let result = (|| -> Result<()> {
        while drawn < frames + WARM_UP {
            let started = Instant::now();
            let input = egui::RawInput {
                screen_rect: Some(egui::Rect::from_min_size(
                    egui::Pos2::ZERO,
                    egui::vec2(req.output.0 as f32, req.output.1 as f32),
                )),
                ..Default::default()
            };
            let out = egui_ctx.run_ui(input, |ui| {
                egui::Panel::top("menu").show(ui, |ui| {
                    egui::MenuBar::new().ui(ui, |ui| {
                        for m in ["File", "Edit", "View"] {
                            ui.menu_button(m, |_| {});
                        }
                    });
                });
                egui::Panel::bottom("status").show(ui, |ui| {
                    ui.label(format!("{drawn} frames · GPU {:?}", vp.last_gpu_seconds()));
                });
                egui::Window::new("Render settings").show(ui.ctx(), |ui| {
                    ui.add(egui::Slider::new(&mut value, 0.0..=1.0).text("internal resolution"));
                    ui.label("target spp, exposure, autosave …");
                });
            });
            pending.append(out.textures_delta);
            let primitives = egui_ctx.tessellate(out.shapes, out.pixels_per_point);
            let ui = EguiFrame {
                primitives: &primitives,
                pixels_per_point: out.pixels_per_point,
                textures: &pending,
            };
            let r = FrameRequest { params: &p, ..req };
            let framed = presenter.frame(vp, world, &r, None, Some(ui), Show::Show)?;
            if framed.presented != Presented::Shown {
                std::thread::yield_now();
                continue;
            }
            pending.clear();
            drawn += 1;
            if moving {
                p.camera.yaw_deg += 0.05;
            }
            timing.frame(vp, drawn, started.elapsed().as_secs_f64())?;
        }
        Ok(())
    })();
    pending.clear();
    result?;
    timing.finish(vp, frames)
}

/// Camera move → the first frame showing it finished on the GPU, `moves` times: (frames,
/// milliseconds) medians.
fn latency(
    vp: &mut Viewport,
    world: &World,
    params: &SceneParams,
    req: FrameRequest<'_>,
    moves: usize,
) -> Result<(f64, f64)> {
    let mut p = params.clone();
    let (mut frames, mut ms) = (Vec::new(), Vec::new());
    for _ in 0..moves {
        // A frame already in flight, as in the window's loop.
        vp.try_draw(world, &FrameRequest { params: &p, ..req })?;
        p.camera.pitch_deg = (p.camera.pitch_deg - 0.5).max(-80.0);
        let event = Instant::now();
        let mut n = 0;
        loop {
            n += 1;
            if vp
                .draw(world, &FrameRequest { params: &p, ..req })?
                .restarted
            {
                break;
            }
        }
        vp.wait_idle()?;
        frames.push(n as f64);
        ms.push(event.elapsed().as_secs_f64() * 1e3);
    }
    Ok((stats(frames).1, stats(ms).1))
}

/// Runs the benchmark; returns the report.
fn run(mut vp: Viewport, world: &World, params: &SceneParams, b: &BenchViewport) -> Result<String> {
    let ctx = vp.ctx().clone();
    let mut text = format!(
        "device       {} ({})\nscene        thesis, {} bounces, sun {}; output {}x{}, {} spp per frame\n",
        ctx.name,
        ctx.driver,
        params.settings.max_bounces,
        if params.sun.enabled { "on" } else { "off" },
        b.size.0,
        b.size.1,
        b.spp
    );
    text += "case                          internal     GPU ms/frame min / median / p99 / max   wall ms/frame   host µs/frame median (p99): begin, record, submit\n";
    let mut presenter = if b.ui {
        Some(Presenter::offscreen(ctx.clone(), b.size)?)
    } else {
        None
    };
    for &scale in &b.scales {
        let internal = scaled(b.size, scale);
        let req = FrameRequest {
            params,
            internal,
            output: b.size,
            spp: b.spp,
            target_spp: u32::MAX,
            exposure: 0.0,
            bgra: true,
            denoise: false,
            reproject: true,
            dim: None,
            grid: None,
        };
        let mut cases = vec![
            ("refining (still camera)", false, false),
            ("camera moving", true, false),
        ];
        if b.denoise {
            cases.extend([
                ("refining, denoised", false, true),
                ("moving, denoised", true, true),
                ("moving, denoised, no reprojection", true, true),
            ]);
        }
        for (label, moving, denoise) in cases {
            let reproject = !label.ends_with("no reprojection");
            let req = FrameRequest {
                denoise,
                reproject,
                ..req
            };
            let (gpu, host, wall) = run_case(&mut vp, world, params, req, b.frames, moving)?;
            if let Some(presenter) = &mut presenter {
                let (gpu, host, wall) =
                    run_case_ui(&mut vp, presenter, world, params, req, b.frames, moving)?;
                let (g0, g50, g99, gmax) = stats(gpu);
                let (_, h50, h99, _) = stats(host);
                text += &format!(
                    "scale {scale:<4} {:<24} {:>4}x{:<5}  {:.3} / {:.3} / {:.3} / {:.3}   {:.3}           whole frame {:.0} ({:.0})\n",
                    format!("{label} + copy + egui"),
                    internal.0,
                    internal.1,
                    g0 * 1e3,
                    g50 * 1e3,
                    g99 * 1e3,
                    gmax * 1e3,
                    wall * 1e3,
                    h50 * 1e6,
                    h99 * 1e6
                );
            }
            let (g0, g50, g99, gmax) = stats(gpu);
            let h: Vec<String> = (0..3)
                .map(|k| {
                    let (_, m, p, _) = stats(host.iter().map(|h| h[k]).collect());
                    format!("{:.0} ({:.0})", m * 1e6, p * 1e6)
                })
                .collect();
            text += &format!(
                "scale {scale:<4} {label:<24} {:>4}x{:<5}  {:.3} / {:.3} / {:.3} / {:.3}   {:.3}           {}\n",
                internal.0,
                internal.1,
                g0 * 1e3,
                g50 * 1e3,
                g99 * 1e3,
                gmax * 1e3,
                wall * 1e3,
                h.join(", ")
            );
        }
        let (frames, ms) = latency(&mut vp, world, params, req, 20)?;
        text += &format!(
            "scale {scale:<4} camera move → first frame showing it: {frames:.0} frame(s), {ms:.2} ms (median of 20, event to GPU completion)\n"
        );
    }
    Ok(text)
}

/// Edit → first frame showing it in the editor's loop, on `scene` (the default scene): a live
/// sphere stroke (attach) of each radius crosses the terrain in rows, one segment half a
/// radius on per edit (the first frame showing it: restarted, and no upload of it deferred), as the edit thread applies them (the edit's time is the world's workers'), with a
/// frame in flight when each edit is made. Reports per radius and internal scale: the edit's
/// apply time, frames and milliseconds from the edit to the first frame showing it finished
/// on the GPU, GPU time of the frames while the stroke is drawn, and the brush preview's
/// update time (exactly the voxels a click changes, on the UI thread).
fn edits(
    mut vp: Viewport,
    scene: app::Scene,
    size: (u32, u32),
    scales: &[f32],
    radii: &[f64],
    count: usize,
) -> Result<String> {
    use app::editor::Document;
    use app::editor::command::{BrushMode, BrushShape, Mirror, Stroke, preview};
    use app::editor::history::History;
    let ctx = vp.ctx().clone();
    let dims = scene.world.dims().voxels();
    let mut text = format!(
        "device       {} ({})\nscene        default {}x{}x{}, {} bounces; output {}x{}, 1 spp per frame; {count} edits per case\n",
        ctx.name,
        ctx.driver,
        dims.x,
        dims.y,
        dims.z,
        scene.params.settings.max_bounces,
        size.0,
        size.1
    );
    text += "radius  scale  edit apply ms median (p99)   edit → frame: frames median (max), ms median (p99)   GPU ms/frame while stroking median (p99)   preview ms median (max)\n";
    let mut doc = Document::new(scene, History::default());
    let params = doc.scene.params.clone();
    for &r in radii {
        for &scale in scales {
            let req = edit_request(&params, size, scale);
            // Warm-up frames (pipelines, clocks).
            for _ in 0..WARM_UP {
                vp.try_draw(&doc.scene.world, &req)?;
            }
            vp.wait_idle()?;
            let step = (r * 0.5).max(1.0);
            let point = |k: usize| {
                // Rows across the scene at three tenths of its height, each row a brush
                // diameter further in z, so every segment reaches voxels not yet changed.
                let span = dims.x as f64 - 4.0 * r;
                let per_row = (span / step).floor().max(1.0) as usize;
                let (row, i) = (k / per_row, k % per_row);
                let z = (2.0 * r + row as f64 * 2.0 * r) % (dims.z as f64 - 2.0 * r);
                glam::DVec3::new(2.0 * r + i as f64 * step, dims.y as f64 * 0.3, z.max(r))
            };
            let stroke = |k: usize| Stroke {
                mode: BrushMode::Attach,
                shape: BrushShape::Sphere,
                size: r,
                material: 1,
                mirror: Mirror::default(),
                points: vec![point(k)],
                axis: Default::default(),
                in_selection: false,
                paint: Default::default(),
            };
            let (mut apply, mut frames, mut ms, mut gpu, mut prev) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
            let mut changed_before = 0;
            for k in 0..count {
                // The preview of the next click, as the UI computes it.
                if k % 4 == 0 {
                    let view = doc.scene.world.read();
                    let started = Instant::now();
                    let _ = preview(&view, &stroke(k), None)?;
                    prev.push(started.elapsed().as_secs_f64() * 1e3);
                }
                // A frame in flight, as in the window's loop.
                vp.try_draw(&doc.scene.world, &req)?;
                let event = Instant::now();
                if k == 0 {
                    doc.begin_stroke(stroke(0))?;
                } else {
                    doc.extend_stroke(&[point(k)])?;
                }
                apply.push(event.elapsed().as_secs_f64() * 1e3);
                if doc
                    .live_stroke()
                    .is_some_and(|l| l.changed_voxels == changed_before)
                {
                    // Nothing changed: no frame will show it.
                    continue;
                }
                changed_before = doc.live_stroke().map_or(0, |l| l.changed_voxels);
                let (n, _) = frames_until_shown(&mut vp, &doc.scene.world, &req)?;
                ms.push(event.elapsed().as_secs_f64() * 1e3);
                frames.push(n as f64);
                if let Some(g) = vp.last_gpu_seconds() {
                    gpu.push(g * 1e3);
                }
            }
            doc.end_stroke()?;
            // Back to the scene as built, for the next case.
            doc.undo()?;
            vp.wait_idle()?;
            let (_, a50, a99, _) = stats(apply);
            let (_, f50, _, fmax) = stats(frames);
            let (_, m50, m99, _) = stats(ms);
            let (_, g50, g99, _) = stats(gpu);
            let (_, p50, _, pmax) = stats(prev);
            text += &format!(
                "{r:<7} {scale:<5}  {a50:.3} ({a99:.3})               {f50:.0} ({fmax:.0}), {m50:.3} ({m99:.3})                       {g50:.3} ({g99:.3})                              {p50:.3} ({pmax:.3})\n"
            );
        }
    }
    text += &first_clicks(&mut vp, &mut doc, size, &params, radii)?;
    text += &selection::selection_edits(&mut vp, &mut doc, size, &params)?;
    text += &objects::object_edits(&mut vp, &mut doc, size, &params)?;
    Ok(text)
}

/// The editor's first click of a stroke: the frame in flight is at the full internal size,
/// the edit's frame at the moving scale (0.5; the editor draws strokes at it). Each click
/// is a one-point attach stroke, shown, undone (not timed) and followed by full-size frames.
fn first_clicks(
    vp: &mut Viewport,
    doc: &mut app::editor::Document,
    size: (u32, u32),
    params: &render::SceneParams,
    radii: &[f64],
) -> Result<String> {
    use app::editor::command::{BrushMode, BrushShape, Command, Mirror, Stroke};
    const CLICKS: usize = 20;
    let (full, moving) = (
        edit_request(params, size, 1.0),
        edit_request(params, size, 0.5),
    );
    let dims = doc.scene.world.dims().voxels().as_dvec3();
    let mut text = format!(
        "\nfirst click of a stroke: frame in flight at scale 1.0, the edit's frame at 0.5; {CLICKS} clicks\nradius  edit → frame ms median (max)\n"
    );
    for &r in radii {
        let mut ms = Vec::new();
        for k in 0..CLICKS {
            for _ in 0..4 {
                vp.try_draw(&doc.scene.world, &full)?;
            }
            // One frame in flight (as in the stroke cases), then the click.
            vp.wait_idle()?;
            vp.draw(&doc.scene.world, &full)?;
            let event = Instant::now();
            let at = glam::DVec3::new(dims.x * (0.2 + 0.03 * k as f64), dims.y * 0.3, dims.z * 0.5);
            doc.execute(Command::Stroke(Stroke {
                mode: BrushMode::Attach,
                shape: BrushShape::Sphere,
                size: r,
                material: 1,
                mirror: Mirror::default(),
                points: vec![at],
                axis: Default::default(),
                in_selection: false,
                paint: Default::default(),
            }))?;
            frames_until_shown(vp, &doc.scene.world, &moving)?;
            ms.push(event.elapsed().as_secs_f64() * 1e3);
            doc.undo()?;
            frames_until_shown(vp, &doc.scene.world, &full)?;
        }
        let (_, m50, _, mmax) = stats(ms);
        text += &format!("{r:<7} {m50:.3} ({mmax:.3})\n");
    }
    Ok(text)
}

/// The edit benchmarks' frames: 1 spp at `scale` of the output `size`, never converging.
pub(crate) fn edit_request(
    params: &render::SceneParams,
    size: (u32, u32),
    scale: f32,
) -> FrameRequest<'_> {
    FrameRequest {
        params,
        internal: scaled(size, scale),
        output: size,
        spp: 1,
        target_spp: u32::MAX,
        exposure: 0.0,
        bgra: true,
        denoise: false,
        reproject: true,
        dim: None,
        grid: None,
    }
}

/// Frames (submitted back to back, as the window does) until one shows the whole of the
/// latest change: it restarted the accumulation and nothing is left for later uploads.
/// Returns the frames and the bytes uploaded.
fn frames_until_shown(
    vp: &mut Viewport,
    world: &brickmap::World,
    req: &FrameRequest<'_>,
) -> Result<(u32, u64)> {
    let mut n = 0;
    let mut restarted = false;
    let mut bytes = 0;
    loop {
        n += 1;
        let status = vp.draw(world, req)?;
        restarted |= status.restarted;
        bytes += status.upload.uploaded_bytes;
        if restarted && status.upload.deferred_bytes == 0 {
            break;
        }
        anyhow::ensure!(n < 10_000, "the edit never showed");
    }
    vp.wait_idle()?;
    Ok((n, bytes))
}
