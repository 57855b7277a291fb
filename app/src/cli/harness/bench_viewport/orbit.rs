//! `bench-viewport --orbit N`: what temporal reprojection buys while the camera moves. N frames
//! of the denoised viewport along an orbit about the point the camera looks at (1 spp each, at
//! the moving scale of the window size), with and without reprojection; each displayed frame
//! against a converged reference of its own view (relMSE, ε = 0.01, and FLIP of the tone-mapped
//! images), then the first frames after the camera stops.

use super::super::bench_error::{flip, srgb};
use super::super::with_progress;
use anyhow::{Context, Result};
use brickmap::World;
use render::cpu::RenderJob;
use render::viewport::{FrameRequest, RenderHow, Viewport};
use render::{Camera, Image, SceneParams};

/// Degrees the camera turns about the orbit's centre each frame (15°/s at 60 Hz).
const STEP_DEG: f64 = 0.25;
/// Frames drawn after the stop.
const STOPPED: usize = 8;

/// The camera `deg` degrees along the orbit of `start` about `centre`.
fn orbit(start: &Camera, centre: glam::DVec3, deg: f64) -> Camera {
    let (s, c) = deg.to_radians().sin_cos();
    let v = start.position - centre;
    let v = glam::DVec3::new(v.x * c + v.z * s, v.y, -v.x * s + v.z * c);
    Camera::looking_at(centre + v, centre, start.fov_y_deg)
}

/// The report: per frame, relMSE and FLIP without and with reprojection.
pub(super) fn orbit_report(
    vp: &mut Viewport,
    world: &World,
    params: &SceneParams,
    internal: (u32, u32),
    frames: usize,
    reference_spp: u32,
) -> Result<String> {
    let start = params.camera.clone();
    let centre = start.position + start.forward() * 120.0;
    let exposure = params.settings.exposure;
    let views: Vec<Camera> = (0..frames + STOPPED)
        .map(|k| orbit(&start, centre, STEP_DEG * k.min(frames - 1) as f64))
        .collect();
    let mut references = Vec::new();
    for (k, camera) in views.iter().enumerate().take(frames) {
        let p = SceneParams {
            camera: camera.clone(),
            ..params.clone()
        };
        let image = with_progress(format!("reference {}/{frames}", k + 1), || {
            Ok(vp
                .render(
                    &world.read(),
                    &p,
                    &RenderJob::sized(internal, reference_spp, 1000 + k as u64),
                    RenderHow::SCENE,
                )?
                .image)
        })?;
        references.push(image);
    }
    let measure = |shown: &Image, reference: &Image| {
        (
            render::convergence::rel_mse(shown, reference).unwrap_or(f64::NAN),
            flip(&srgb(reference, exposure), &srgb(shown, exposure), internal),
        )
    };
    let mut rows: Vec<[(f64, f64); 2]> = vec![[(0.0, 0.0); 2]; frames + STOPPED];
    for (i, reproject) in [false, true].into_iter().enumerate() {
        // A still frame first, so the orbit's first frame is a camera move.
        let mut p = SceneParams {
            camera: orbit(&start, centre, -STEP_DEG),
            ..params.clone()
        };
        for (k, camera) in views.iter().enumerate() {
            p.camera = camera.clone();
            let req = FrameRequest {
                params: &p,
                internal,
                output: internal,
                spp: 1,
                target_spp: u32::MAX,
                exposure,
                bgra: false,
                denoise: true,
                reproject,
                dim: None,
                grid: None,
            };
            vp.draw(world, &req)?;
            let shown = vp.live_denoised()?.context("no denoised frame")?;
            rows[k][i] = measure(&shown, &references[k.min(frames - 1)]);
        }
    }
    let mut text = format!(
        "orbit: {frames} frames of {STEP_DEG}° about a point 120 voxels ahead, then {STOPPED} frames stopped; \
         {}x{} internal, 1 spp a frame, denoised; references {reference_spp} spp\n\
         frame        relMSE without / with reprojection   FLIP without / with\n",
        internal.0, internal.1
    );
    let mean = |range: std::ops::Range<usize>, i: usize, j: usize| {
        let n = range.len() as f64;
        range
            .map(|k| if j == 0 { rows[k][i].0 } else { rows[k][i].1 })
            .sum::<f64>()
            / n
    };
    for (k, r) in rows.iter().enumerate() {
        let label = if k < frames {
            format!("moving {}", k + 1)
        } else {
            format!("stopped {}", k - frames + 1)
        };
        text += &format!(
            "{label:<12} {:>10.5} / {:<10.5}                 {:>7.4} / {:<7.4}\n",
            r[0].0, r[1].0, r[0].1, r[1].1
        );
    }
    let steady = 8.min(frames - 1)..frames;
    text += &format!(
        "mean over moving frames {}..{frames}: relMSE {:.5} / {:.5} ({:.2}x less), FLIP {:.4} / {:.4}\n",
        steady.start + 1,
        mean(steady.clone(), 0, 0),
        mean(steady.clone(), 1, 0),
        mean(steady.clone(), 0, 0) / mean(steady.clone(), 1, 0),
        mean(steady.clone(), 0, 1),
        mean(steady, 1, 1),
    );
    Ok(text)
}
