//! The GPU session's interactive frames (frames in flight, cached descriptor sets, no host
//! waits) on a real device with the validation layer: they accumulate exactly the samples a
//! one-shot render takes, restart on an edit and on a camera change, and stop at the target;
//! finished pictures (`render::finished`): alpha, tiles, cancel and noise targets.

mod common;

use brickmap::{EditOp, Mode, Shape};
use glam::{DVec3, IVec3};
use render::cpu::RenderJob;
use render::finished::{Finish, PictureError, Stop, relative_error};
use render::viewport::{FrameRequest, Paced, RenderHow, Viewport};
use render::vulkan::trace::Dim;
use render::vulkan::{DeviceChoice, GpuContext};
use std::sync::Arc;

fn context() -> Option<Arc<GpuContext>> {
    common::gpu_context(DeviceChoice::Best).map(Arc::new)
}

/// Draws frames until `done` says so (at most `limit`); returns the statuses of the frames
/// that were recorded (a slot still in flight yields no frame and is not waited for).
fn frames(
    vp: &mut Viewport,
    world: &brickmap::World,
    req: &FrameRequest<'_>,
    limit: usize,
    done: impl Fn(&Viewport) -> bool,
) -> Vec<render::viewport::FrameStatus> {
    let mut out = Vec::new();
    for _ in 0..limit * 1000 {
        if done(vp) || out.len() >= limit {
            break;
        }
        match vp.try_draw(world, req).unwrap() {
            Some(status) => out.push(status),
            None => std::thread::sleep(std::time::Duration::from_millis(1)),
        }
    }
    vp.wait_idle().unwrap();
    out
}

/// An interactive frame's request: `spp` per frame up to `target`, at `size` in and out.
fn request(
    params: &render::SceneParams,
    size: (u32, u32),
    spp: u32,
    target: u32,
) -> FrameRequest<'_> {
    FrameRequest {
        params,
        internal: size,
        output: size,
        spp,
        target_spp: target,
        exposure: 0.0,
        bgra: false,
        denoise: false,
        reproject: true,
        dim: None,
        grid: None,
    }
}

#[test]
fn interactive_frames_accumulate_the_one_shot_renders_samples() {
    let Some(ctx) = context() else { return };
    let (world, params) = common::showcase();
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    let size = (40, 24);
    let req = request(&params, size, 3, 16);
    let statuses = frames(&mut vp, &world, &req, 64, |v| v.samples() >= 16);
    assert!(statuses[0].restarted && statuses[0].samples <= 3);
    assert_eq!(vp.samples(), 16, "stops exactly at the target");
    // At the target, frames add nothing (the editor then waits for events).
    let idle = frames(&mut vp, &world, &req, 3, |_| false);
    assert!(
        idle.iter().all(|s| s.added == 0 && !s.restarted),
        "{idle:?}"
    );
    let live = vp.live_hdr().unwrap().unwrap();
    let once = vp
        .render(
            &world.read(),
            &params,
            &RenderJob {
                width: size.0,
                height: size.1,
                spp: 16,
                seed: 1,
            },
            RenderHow::SCENE,
        )
        .unwrap()
        .image;
    let worst = live
        .pixels
        .iter()
        .zip(&once.pixels)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs() / b[c].abs().max(1e-3)))
        .fold(0.0f32, f32::max);
    assert!(
        worst < 1e-3,
        "interactive and one-shot samples differ: {worst}"
    );
    assert_eq!(ctx.validation_errors(), 0, "validation errors");
}

#[test]
fn an_edit_or_a_camera_move_restarts_and_the_edit_is_visible_the_next_frame() {
    let Some(ctx) = context() else { return };
    let (world, mut params) = common::showcase();
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    let size = (32, 24);
    let run = |vp: &mut Viewport, params: &render::SceneParams, n| {
        let req = FrameRequest {
            params,
            internal: size,
            output: size,
            spp: 2,
            target_spp: 8,
            exposure: 0.0,
            bgra: false,
            denoise: false,
            reproject: true,
            dim: None,
            grid: None,
        };
        frames(vp, &world, &req, n, |_| false)
    };
    let first = run(&mut vp, &params, 4);
    assert_eq!(first.last().unwrap().samples, 8);
    // An edit: the next frame uploads it and starts over.
    world
        .apply(EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::new(24.0, 12.0, 24.0),
                radius: 6.0,
            },
            mode: Mode::Add(0),
        })
        .unwrap();
    let after_edit = run(&mut vp, &params, 1);
    assert!(after_edit[0].restarted && after_edit[0].upload.uploaded_bytes > 0);
    let edited = vp
        .render(
            &world.read(),
            &params,
            &RenderJob {
                width: size.0,
                height: size.1,
                spp: 2,
                seed: 1,
            },
            RenderHow::SCENE,
        )
        .unwrap()
        .image;
    let live = vp.live_hdr().unwrap().unwrap();
    let diff: f32 = live
        .pixels
        .iter()
        .zip(&edited.pixels)
        .map(|(a, b)| (a[0] - b[0]).abs())
        .sum();
    assert!(
        diff < 1e-2 * live.pixels.len() as f32,
        "the frame after the edit shows it: {diff}"
    );
    // A camera move restarts too.
    run(&mut vp, &params, 4);
    params.camera.yaw_deg += 5.0;
    let moved = run(&mut vp, &params, 1);
    assert!(moved[0].restarted, "{moved:?}");
    assert_eq!(ctx.validation_errors(), 0, "validation errors");
}

#[test]
fn an_edit_whose_upload_spans_frames_shows_only_once_it_is_all_there() {
    let Some(ctx) = context() else { return };
    let (world, params) = common::showcase();
    // One 1 KiB staging slot: an edit of a few bricks takes several frames to upload.
    let mut vp = Viewport::with_staging(ctx.clone(), &world.read(), 1, 1024).unwrap();
    let req = request(&params, (32, 24), 2, 8);
    frames(&mut vp, &world, &req, 8, |v| v.samples() >= 8);
    let before = vp.live_hdr().unwrap().unwrap();
    world
        .apply(EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::new(24.0, 12.0, 24.0),
                radius: 9.0,
            },
            mode: Mode::Add(0),
        })
        .unwrap();
    let first = frames(&mut vp, &world, &req, 1, |_| false);
    assert!(
        first[0].upload.deferred_bytes > 0,
        "the upload spans frames: {first:?}"
    );
    // While held, the previous image stays on display: the accumulation did not change.
    let during = vp.live_hdr().unwrap().unwrap();
    assert_eq!(during.pixels, before.pixels, "a partial upload was traced");
    let mut statuses = first;
    statuses.extend(frames(&mut vp, &world, &req, 24, |_| false));
    let held: Vec<_> = statuses
        .iter()
        .take_while(|s| s.upload.deferred_bytes > 0)
        .collect();
    assert!(held.len() >= 2, "the upload spans frames: {statuses:?}");
    for s in held.iter().take(render::viewport::MAX_HELD_FRAMES as usize) {
        assert!(
            s.added == 0 && !s.restarted,
            "a partial upload was traced: {s:?}"
        );
    }
    if held.len() <= render::viewport::MAX_HELD_FRAMES as usize {
        let shown = &statuses[held.len()];
        assert!(
            shown.restarted && shown.upload.deferred_bytes == 0,
            "{shown:?}"
        );
        assert!(shown.added > 0);
    }
    assert_eq!(ctx.validation_errors(), 0, "validation errors");
}

/// When the interactive frames take more samples per frame (the editor raises them while the
/// GPU keeps up) or more bounces, a lamp-lit scene asks for a larger shadow-ray queue (one ray
/// per vertex) while the other frame slot still traces with the old one: the old queue must
/// outlive that frame (the soak test found it freed under the frame in flight:
/// VUID-vkDestroyBuffer-buffer-00922).
#[test]
fn a_larger_shadow_queue_keeps_the_frame_in_flight_valid() {
    let Some(ctx) = context() else { return };
    let (world, mut params, _) = common::sun_floor();
    params.settings.max_bounces = 2;
    let lamp = common::add_material(&world, brickmap::MaterialKind::Emissive, 0, [255, 240, 220]);
    world
        .apply(EditOp::Shape {
            shape: Shape::Box {
                min: glam::IVec3::new(30, 4, 30),
                max: glam::IVec3::new(33, 5, 33),
            },
            mode: Mode::Add(lamp),
        })
        .unwrap();
    assert!(!world.read().lights().is_empty());
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    let small = request(&params, (96, 64), 1, 1 << 20);
    let _ = frames(&mut vp, &world, &small, 3, |_| false);
    // Frames in flight, then four times the samples per frame, with no wait in between.
    let more = request(&params, (96, 64), 4, 1 << 20);
    let mut drawn = 0;
    for _ in 0..200_000 {
        if drawn >= 6 {
            break;
        }
        let req = if drawn < 2 { &small } else { &more };
        match vp.try_draw(&world, req).unwrap() {
            Some(_) => drawn += 1,
            None => std::thread::sleep(std::time::Duration::from_micros(200)),
        }
    }
    vp.wait_idle().unwrap();
    assert_eq!(drawn, 6);
    assert_eq!(ctx.validation_errors(), 0);
}

/// The image of 8 samples per pixel after a change of the request (which starts over).
fn eight_samples(
    vp: &mut Viewport,
    world: &brickmap::World,
    req: &FrameRequest<'_>,
) -> render::Image {
    let first = frames(vp, world, req, 1, |_| false);
    assert!(first[0].restarted, "a change of the view aids starts over");
    frames(vp, world, req, 64, |v| v.samples() >= 8);
    assert_eq!(vp.samples(), 8);
    vp.live_hdr().unwrap().unwrap()
}

/// Whether two pixels differ by more than the last bits of a variant's arithmetic.
fn differs(a: &[f32; 3], b: &[f32; 3]) -> bool {
    (0..3).any(|c| (a[c] - b[c]).abs() > 1e-4 * b[c].abs().max(1e-3))
}

#[test]
fn the_ground_grid_shows_on_the_floor_and_voxels_hide_it() {
    let Some(ctx) = context() else { return };
    let size = (40, 24);
    // An empty grid seen from above: lines on its floor and around it, the sky beyond.
    let (world, params) = common::showcase();
    let empty = common::world((6, 4, 6));
    let mut vp = Viewport::new(ctx.clone(), &empty.read()).unwrap();
    let grid = |grid| FrameRequest {
        grid,
        ..request(&params, size, 4, 8)
    };
    let plain = eight_samples(&mut vp, &empty, &grid(None));
    let lined = eight_samples(&mut vp, &empty, &grid(Some(8.0)));
    let changed = plain
        .pixels
        .iter()
        .zip(&lined.pixels)
        .filter(|(a, b)| differs(a, b))
        .count();
    assert!(
        changed > plain.pixels.len() / 10 && changed < plain.pixels.len(),
        "{changed} of {} pixels show lines",
        plain.pixels.len()
    );
    // Looking down onto the showcase's floor, which covers the plane there: the same
    // samples, the same image.
    let mut params = params.clone();
    params.camera.position = DVec3::new(24.0, 24.0, 24.0);
    params.camera.pitch_deg = -89.0;
    let grid = |grid| FrameRequest {
        grid,
        ..request(&params, size, 4, 8)
    };
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    let covered = eight_samples(&mut vp, &world, &grid(None));
    let gridded = eight_samples(&mut vp, &world, &grid(Some(8.0)));
    let differ: Vec<_> = covered
        .pixels
        .iter()
        .zip(&gridded.pixels)
        .enumerate()
        .filter(|(_, (a, b))| differs(a, b))
        .map(|(i, (a, b))| (i % size.0 as usize, i / size.0 as usize, *a, *b))
        .collect();
    // (The same samples; a variant's arithmetic may differ in the last bit.)
    assert!(
        differ.is_empty(),
        "{} pixels differ: {:?}",
        differ.len(),
        &differ[..differ.len().min(6)]
    );
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn dimming_weights_exactly_the_camera_hits_outside_the_box() {
    let Some(ctx) = context() else { return };
    let (world, params) = common::showcase();
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    let size = (40, 24);
    let image = |vp: &mut Viewport, dim: Option<Dim>| {
        let req = FrameRequest {
            dim,
            ..request(&params, size, 4, 8)
        };
        eight_samples(vp, &world, &req)
    };
    let plain = image(&mut vp, None);
    let factor = 0.25;
    // The low half of the grid along x at full weight, the rest dimmed.
    let half = Dim {
        lo: IVec3::ZERO,
        hi: IVec3::new(24, 64, 48),
        factor,
    };
    let dimmed = image(&mut vp, Some(half));
    // A box holding the whole grid dims nothing: the same samples, the same image.
    let all = image(
        &mut vp,
        Some(Dim {
            hi: IVec3::splat(48),
            ..half
        }),
    );
    let (mut full, mut dark) = (0, 0);
    for ((p, d), a) in plain.pixels.iter().zip(&dimmed.pixels).zip(&all.pixels) {
        for c in 0..3 {
            let scale = p[c].abs().max(1e-3);
            assert!((a[c] - p[c]).abs() / scale < 1e-4, "{a:?} against {p:?}");
            // Each sample is weighted 1 or the factor: the mean lies between.
            let r = d[c] / p[c].max(1e-6);
            if p[c] > 1e-3 {
                assert!(r > factor - 1e-3 && r < 1.0 + 1e-3, "{d:?} against {p:?}");
            }
        }
        let r = d[1] / p[1].max(1e-6);
        if p[1] > 1e-3 && (r - 1.0).abs() < 1e-4 {
            full += 1;
        }
        if p[1] > 1e-3 && (r - factor).abs() < 1e-4 {
            dark += 1;
        }
    }
    let n = plain.pixels.len();
    assert!(
        full > n / 10 && dark > n / 10,
        "{full} full, {dark} dimmed of {n}"
    );
    assert_eq!(ctx.validation_errors(), 0);
}

/// A finished picture of `params` on `vp` (progress ignored).
fn picture(
    vp: &mut Viewport,
    world: &brickmap::World,
    params: &render::SceneParams,
    finish: &Finish,
) -> render::finished::Picture {
    vp.render_picture(&world.read(), params, finish, &mut |_| true)
        .unwrap()
}

fn finish(size: (u32, u32), stop: Stop, tile: u32) -> Finish {
    Finish {
        size,
        stop,
        denoise: false,
        alpha: true,
        seed: 7,
        tile,
    }
}

#[test]
fn a_finished_pictures_alpha_is_exactly_its_coverage_and_its_background_transparent() {
    let Some(ctx) = context() else { return };
    // Orthographic along −z, a voxel per pixel: two walls cover known pixels wholly.
    let (world, mut params, lit) = common::orthographic_walls();
    params.sky = render::Sky::Uniform { colour: [1.0; 3] };
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    for tile in [32, 12] {
        let p = picture(
            &mut vp,
            &world,
            &params,
            &finish((32, 32), Stop::Samples(4), tile),
        );
        let alpha = p.alpha.as_ref().unwrap();
        for (i, &l) in lit.iter().enumerate() {
            assert_eq!(
                alpha[i],
                if l { 1.0 } else { 0.0 },
                "pixel {i}, tiles of {tile}"
            );
            // Camera rays that miss add nothing, though the sky is white.
            let c = p.image.pixels[i];
            assert_eq!(c == [0.0; 3], !l, "pixel {i}: {c:?}");
        }
    }
    // Without alpha the sky shows.
    let mut opaque = finish((32, 32), Stop::Samples(2), 32);
    opaque.alpha = false;
    let p = picture(&mut vp, &world, &params, &opaque);
    assert!(p.alpha.is_none());
    let sky = lit.iter().position(|l| !l).unwrap();
    assert_eq!(p.image.pixels[sky], [1.0; 3]);
    drop(vp);
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn a_tiled_picture_equals_the_untiled_one_and_a_cancel_stops_it() {
    let Some(ctx) = context() else { return };
    let (world, params) = common::showcase();
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    // The same batches in every tile (the automatic shape follows the pixel count), one
    // invocation per pixel and shadow rays traced in place (sliced sums and the shadow
    // queue's add in any order).
    vp.tracer().set_samples_per_dispatch(Some(3));
    vp.tracer().set_sample_slices(Some(1));
    vp.tracer().set_deferred_shadows(&ctx, false);
    let whole = picture(
        &mut vp,
        &world,
        &params,
        &finish((41, 27), Stop::Samples(7), 64),
    );
    assert_eq!(whole.tiles, 1);
    let tiled = picture(
        &mut vp,
        &world,
        &params,
        &finish((41, 27), Stop::Samples(7), 16),
    );
    assert_eq!(tiled.tiles, 6);
    assert!(whole.image.all_finite() && whole.image.mean()[0] > 0.0);
    assert_eq!(tiled.image, whole.image);
    assert_eq!(tiled.alpha, whole.alpha);
    // Cancelled at the second progress report: an error, and the session still renders.
    let mut calls = 0;
    let r = vp.render_picture(
        &world.read(),
        &params,
        &finish((41, 27), Stop::Samples(7), 16),
        &mut |p| {
            assert!((0.0..=1.0).contains(&p.done) && p.tile.1 == 6);
            calls += 1;
            calls < 2
        },
    );
    assert!(matches!(r, Err(PictureError::Cancelled)), "{r:?}");
    let again = picture(
        &mut vp,
        &world,
        &params,
        &finish((41, 27), Stop::Samples(7), 16),
    );
    assert_eq!(again.image, whole.image);
    drop(vp);
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn a_noise_target_is_reached_as_a_converged_reference_measures_it() {
    let Some(ctx) = context() else { return };
    let (world, params) = common::showcase();
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    let size = (48, 32);
    let mut reference = finish(size, Stop::Samples(2048), 64);
    reference.alpha = false;
    reference.seed = 99;
    let reference = picture(&mut vp, &world, &params, &reference).image;
    let mut taken = Vec::new();
    for target in [0.12, 0.06] {
        let mut f = finish(size, Stop::Noise { target, max: 4096 }, 64);
        f.alpha = false;
        let p = picture(&mut vp, &world, &params, &f);
        let estimate = p.noise.unwrap();
        let error = relative_error(&p.image, &reference);
        eprintln!(
            "target {target}: {} spp, estimated {estimate:.4}, measured {error:.4}",
            p.samples.1
        );
        assert!(estimate <= target, "{estimate} > {target}");
        assert!(p.samples.1 < 4096, "the target never stopped it");
        // The reference's own noise adds a little to what is measured.
        assert!(error <= target * 1.25, "measured {error} for {target}");
        taken.push(p.samples.1);
    }
    assert!(taken[1] >= 2 * taken[0], "{taken:?}");
    drop(vp);
    assert_eq!(ctx.validation_errors(), 0);
}

/// Paced jobs until `done` (at most `limit` submitted), then waits for the device.
fn paced(
    vp: &mut Viewport,
    world: &brickmap::World,
    req: &FrameRequest<'_>,
    limit: usize,
    done: impl Fn(&Viewport) -> bool,
) -> usize {
    let mut submitted = 0;
    for _ in 0..limit * 1000 {
        if done(vp) || submitted >= limit {
            break;
        }
        match vp.trace_paced(world, req).unwrap() {
            Paced::Traced(_) => submitted += 1,
            Paced::Busy => std::thread::sleep(std::time::Duration::from_millis(1)),
            Paced::Idle => break,
        }
    }
    vp.wait_idle().unwrap();
    submitted
}

#[test]
fn a_pass_traced_in_bands_is_the_whole_dispatchs_image_and_only_whole_passes_show() {
    let Some(ctx) = context() else { return };
    let (world, params) = common::showcase();
    let size = (40, 24);
    let req = request(&params, size, 1, 4);
    let mut whole = Viewport::new(ctx.clone(), &world.read()).unwrap();
    frames(&mut whole, &world, &req, 64, |v| v.samples() >= 4);
    let mut banded = Viewport::new(ctx.clone(), &world.read()).unwrap();
    banded.set_bands(Some(3));
    let jobs = paced(&mut banded, &world, &req, 64, |v| v.samples() >= 4);
    assert_eq!(jobs, 12, "four passes of three bands");
    assert_eq!(banded.samples(), 4);
    let shown = banded.shown_image().unwrap().expect("a finished image");
    assert_eq!(shown.image.samples, 4, "the shown image is a whole pass's");
    assert_eq!(shown.image.job, 4, "one image per pass");
    let (a, b) = (
        whole.live_hdr().unwrap().unwrap(),
        banded.live_hdr().unwrap().unwrap(),
    );
    assert_eq!(a.pixels, b.pixels, "the same samples of the same pixels");
    // Converged and unchanged: nothing to trace.
    assert!(matches!(
        banded.trace_paced(&world, &req).unwrap(),
        Paced::Idle
    ));
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn the_shown_image_is_the_last_finished_one_while_the_next_is_traced() {
    let Some(ctx) = context() else { return };
    let (world, params) = common::showcase();
    let mut vp = Viewport::new(ctx.clone(), &world.read()).unwrap();
    let small = request(&params, (16, 16), 1, 1);
    assert_eq!(paced(&mut vp, &world, &small, 8, |v| v.samples() >= 1), 1);
    let first = vp.shown_image().unwrap().expect("the first job finished");
    // A long job (many samples of a larger image): until it is done the first stays shown,
    // and asking never waits for it.
    let long = request(&params, (256, 192), 16, 16);
    assert!(matches!(
        vp.trace_paced(&world, &long).unwrap(),
        Paced::Traced(_)
    ));
    let meanwhile = vp.shown_image().unwrap().expect("still the first");
    assert_eq!(
        meanwhile.image, first.image,
        "shown before the long job finished"
    );
    vp.wait_idle().unwrap();
    let after = vp.shown_image().unwrap().expect("the long job finished");
    assert_eq!(after.image.size, (256, 192));
    assert!(after.image.job > first.image.job);
    assert_eq!(ctx.validation_errors(), 0);
}
