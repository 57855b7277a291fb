//! `bench`'s measurements along the path: GPU frames per preset and size, the CPU
//! reference's frames, and a sculpting stroke while the path plays.

use super::*;
use crate::cli::harness::bench_viewport::edit_request;

fn times(frames: usize, duration: f64) -> Vec<f64> {
    (0..frames)
        .map(|i| {
            if frames > 1 {
                duration * i as f64 / (frames - 1) as f64
            } else {
                0.0
            }
        })
        .collect()
}

/// One preset at one size along the path on the GPU.
pub(super) fn gpu_run(
    session: &mut Viewport,
    scene: &Scene,
    path: &CameraPath,
    preset: &Preset,
    size: (u32, u32),
    frames: usize,
    repeat: u32,
) -> Result<GpuRun> {
    let view = scene.world.read();
    let centre = view.dims().voxels().as_dvec3() * 0.5;
    let ts = times(frames, path.duration());
    // Warm-up: pipelines built, clocks up.
    let p0 = params_at(&scene.params, path, preset, 0.0, centre);
    for _ in 0..3 {
        session.time_repeated(
            &view,
            &p0,
            Variant::for_scene(&view, &p0),
            size,
            preset.spp,
            10,
        )?;
    }
    let (mut frame_ms, mut counted_ms) = (Vec::new(), 0.0);
    let mut rays = render::vulkan::trace::RayCounts::default();
    let mut counted_frames = 0u64;
    for (i, &t) in ts.iter().enumerate() {
        let p = params_at(&scene.params, path, preset, t, centre);
        let variant = Variant::for_scene(&view, &p);
        let mut v = session.time_repeated(&view, &p, variant, size, preset.spp, repeat)?;
        if v.is_empty() {
            bail!("this queue cannot take timestamps");
        }
        v.sort_by(f64::total_cmp);
        let ms = v[v.len() / 2] * 1e3;
        frame_ms.push(ms);
        if i % 10 == 0 {
            let job = RenderJob {
                width: size.0,
                height: size.1,
                spp: preset.spp,
                seed: i as u64,
            };
            let how = RenderHow::variant(variant).counted();
            let c = session.render(&view, &p, &job, how)?.rays.expect("counted");
            rays.primary += c.primary;
            rays.secondary += c.secondary;
            rays.shadow += c.shadow;
            rays.capped += c.capped;
            counted_ms += ms;
            counted_frames += 1;
        }
    }
    let s = counted_ms / 1e3;
    let px = (size.0 as u64 * size.1 as u64 * counted_frames).max(1) as f64;
    Ok(GpuRun {
        preset: *preset,
        width: size.0,
        height: size.1,
        path_time_s: ts,
        summary: Summary::of(&frame_ms),
        frame_ms,
        mrays_per_s: Rates {
            primary: rays.primary as f64 / s / 1e6,
            secondary: rays.secondary as f64 / s / 1e6,
            shadow: rays.shadow as f64 / s / 1e6,
            all: rays.total() as f64 / s / 1e6,
        },
        rays_per_pixel: Rates {
            primary: rays.primary as f64 / px,
            secondary: rays.secondary as f64 / px,
            shadow: rays.shadow as f64 / px,
            all: rays.total() as f64 / px,
        },
        traversal_caps_hit: rays.capped,
    })
}

/// One preset along the path on the CPU reference (wall clock, all cores).
pub(super) fn cpu_run(
    scene: &Scene,
    path: &CameraPath,
    preset: &Preset,
    size: (u32, u32),
    frames: usize,
) -> CpuRun {
    let view = scene.world.read();
    let centre = view.dims().voxels().as_dvec3() * 0.5;
    let ts = times(frames, path.duration());
    let frame_ms: Vec<f64> = ts
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            let p = params_at(&scene.params, path, preset, t, centre);
            let started = Instant::now();
            let cpu = CpuScene::new(&view, &p);
            std::hint::black_box(cpu.render(&RenderJob {
                width: size.0,
                height: size.1,
                spp: preset.spp,
                seed: i as u64,
            }));
            started.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    let total_s = frame_ms.iter().sum::<f64>() / 1e3;
    CpuRun {
        preset: *preset,
        width: size.0,
        height: size.1,
        path_time_s: ts,
        summary: Summary::of(&frame_ms),
        msamples_per_s: (size.0 as u64 * size.1 as u64 * preset.spp as u64 * frames as u64) as f64
            / total_s
            / 1e6,
        frame_ms,
    }
}

/// A sculpting stroke while the path plays: one sphere of `radius` added per frame at the
/// next point of a circle of stroke points on the terrain's surface, each shown before the
/// next (frames in flight as in the editor), at complexity 3's settings, 1 spp per frame.
pub(super) fn edit_run(
    session: &mut Viewport,
    scene: &Scene,
    path: &CameraPath,
    radius: f64,
    size: (u32, u32),
    frames: usize,
) -> Result<EditRun> {
    let preset = PRESETS[2];
    let dims = scene.world.dims().voxels().as_dvec3();
    let centre = dims * 0.5;
    // The stroke's points on the surface, found by the exact CPU cast (before any edit).
    let points: Vec<DVec3> = {
        let view = scene.world.read();
        (0..frames)
            .map(|i| {
                let a = i as f64 * (radius * 0.5 / 150.0);
                let (x, z) = (centre.x + 150.0 * a.cos(), centre.z + 150.0 * a.sin());
                let ray = brickmap::Ray {
                    origin: DVec3::new(x, dims.y - 0.5, z),
                    dir: DVec3::NEG_Y,
                };
                let y = view
                    .ray_cast(&ray, f64::INFINITY)
                    .ok()
                    .flatten()
                    .map_or(dims.y * 0.4, |(h, _)| h.voxel.y as f64 + 1.0);
                DVec3::new(x, y, z)
            })
            .collect()
    };
    let material = 0u8;
    let (mut apply, mut per_frame, mut per_edit, mut gpu, mut lat_frames, mut lat_ms) = (
        Vec::new(),
        Vec::new(),
        Vec::new(),
        Vec::new(),
        Vec::new(),
        Vec::new(),
    );
    let ts = times(frames, path.duration());
    for (i, &t) in ts.iter().enumerate() {
        let p = params_at(&scene.params, path, &preset, t, centre);
        let req: FrameRequest<'_> = edit_request(&p, size, 1.0);
        let started = Instant::now();
        // Through the active object, as the editor's brush.
        scene
            .edit(EditOp::Shape {
                shape: Shape::Sphere {
                    centre: points[i],
                    radius,
                },
                mode: Mode::Add(material),
            })
            .context("the stroke's sphere")?;
        apply.push(started.elapsed().as_secs_f64() * 1e3);
        let (mut n, mut bytes, mut restarted) = (0u32, 0u64, false);
        loop {
            n += 1;
            let status = session.draw(&scene.world, &req)?;
            if let Some(g) = session.last_gpu_seconds() {
                gpu.push(g * 1e3);
            }
            per_frame.push(status.upload.uploaded_bytes as f64);
            bytes += status.upload.uploaded_bytes;
            restarted |= status.restarted;
            if restarted && status.upload.deferred_bytes == 0 {
                break;
            }
            anyhow::ensure!(n < 10_000, "the edit never showed");
        }
        session.wait_idle()?;
        lat_ms.push(started.elapsed().as_secs_f64() * 1e3);
        lat_frames.push(n as f64);
        per_edit.push(bytes as f64);
    }
    Ok(EditRun {
        radius,
        width: size.0,
        height: size.1,
        edits: frames,
        apply_ms: Summary::of(&apply),
        uploaded_bytes_per_frame: Summary::of(&per_frame),
        uploaded_bytes_per_edit: Summary::of(&per_edit),
        frame_ms: Summary::of(&gpu),
        latency_frames: Summary::of(&lat_frames),
        latency_ms: Summary::of(&lat_ms),
    })
}
