//! Progressive accumulation, restarts, pipeline variants and the internal resolution.
use super::*;
use brickmap::{EditOp, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp};
use common::{add_material as add, params, sun_floor};
use glam::{DVec3, IVec3};
use render::cpu::RenderJob;
use render::vulkan::progressive::Progressive;
use render::vulkan::trace::{PathTracer, Variant};
use render::vulkan::world::GpuWorld;
use render::{Camera, Sky};

#[test]
fn accumulation_continues_while_nothing_changes_and_restarts_on_any_change() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let (w, mut p, _) = sun_floor();
    let mut gpu = GpuWorld::upload(&ctx, &w.read()).unwrap();
    let mut tracer = PathTracer::new(&ctx).unwrap();
    let size = (16, 12);
    let mut acc = Progressive::new(&ctx, size, size, 7).unwrap();
    let mut frame = |acc: &mut Progressive, gpu: &mut GpuWorld, p: &render::SceneParams| {
        let changed = gpu.update(&ctx, &w).unwrap().changed();
        acc.frame(&ctx, &mut tracer, gpu, &w.read(), p, changed, 4)
            .unwrap()
    };
    let first = frame(&mut acc, &mut gpu, &p);
    assert!(first.restarted);
    assert_eq!(first.samples, 4);
    for k in 2..=4 {
        let r = frame(&mut acc, &mut gpu, &p);
        assert!(!r.restarted);
        assert_eq!(r.samples, 4 * k);
    }
    // 4 frames of 4 samples are the 16-sample render with the same seed, here in dispatches
    // of 3, 3, 3, 3, 3 and 1 samples (one submission).
    let accumulated = acc.hdr(&ctx).unwrap();
    let mut one = PathTracer::new(&ctx).unwrap();
    one.set_samples_per_dispatch(Some(3));
    let direct = one
        .render(
            &ctx,
            &gpu,
            &w.read(),
            &p,
            &RenderJob {
                width: size.0,
                height: size.1,
                spp: 16,
                seed: 7,
            },
            RenderHow::SCENE,
        )
        .unwrap()
        .image;
    for (a, b) in accumulated.pixels.iter().zip(&direct.pixels) {
        for k in 0..3 {
            assert!(
                (a[k] - b[k]).abs() <= 1e-5 * b[k].abs().max(1.0),
                "{a:?} vs {b:?}"
            );
        }
    }
    one.destroy(&ctx);
    // Exposure is display-only: no restart.
    p.settings.exposure += 1.0;
    let r = frame(&mut acc, &mut gpu, &p);
    assert!(!r.restarted && r.samples == 20, "{r:?}");
    // Camera, sun, bounces, world edits and material edits each restart.
    let mut moved = p.clone();
    moved.camera.position.x += 0.5;
    let r = frame(&mut acc, &mut gpu, &moved);
    assert!(r.restarted && r.samples == 4, "camera: {r:?}");
    frame(&mut acc, &mut gpu, &moved);
    let mut dimmer = moved.clone();
    dimmer.sun.intensity *= 0.5;
    assert!(frame(&mut acc, &mut gpu, &dimmer).restarted, "sun");
    let mut deeper = dimmer.clone();
    deeper.settings.max_bounces += 1;
    assert!(frame(&mut acc, &mut gpu, &deeper).restarted, "bounces");
    assert!(!frame(&mut acc, &mut gpu, &deeper).restarted);
    w.apply(EditOp::Voxels(vec![VoxelEdit {
        pos: IVec3::new(3, 9, 3),
        op: VoxelOp::Set(0),
    }]))
    .unwrap();
    assert!(frame(&mut acc, &mut gpu, &deeper).restarted, "world edit");
    assert!(!frame(&mut acc, &mut gpu, &deeper).restarted);
    w.set_colour(0, [10, 200, 30]);
    assert!(frame(&mut acc, &mut gpu, &deeper).restarted, "colour edit");
    let r = frame(&mut acc, &mut gpu, &deeper);
    assert!(!r.restarted && r.samples == 8, "{r:?}");
    acc.destroy(&ctx);
    tracer.destroy(&ctx);
    gpu.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn variants_follow_the_scene_and_render_what_the_everything_variant_renders() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    // Lambertian and metal only, no sun, uniform sky: the scene's variant drops
    // dielectrics, emission, the sun and the gradient; its image must be the everything
    // variant's (same seeds, same random numbers consumed).
    let w = common::world((4, 3, 4));
    let floor = add(&w, MaterialKind::Lambertian, 0, [180, 170, 150]);
    let metal = add(&w, MaterialKind::Metal, 20, [220, 200, 160]);
    for (shape, m) in [
        (
            Shape::Box {
                min: IVec3::ZERO,
                max: IVec3::new(31, 1, 31),
            },
            floor,
        ),
        (
            Shape::Sphere {
                centre: DVec3::new(16.0, 8.0, 16.0),
                radius: 5.0,
            },
            metal,
        ),
    ] {
        w.apply(EditOp::Shape {
            shape,
            mode: Mode::Add(m),
        })
        .unwrap();
    }
    let cam = Camera::looking_at(
        DVec3::new(-4.0, 14.0, -6.0),
        DVec3::new(16.0, 5.0, 16.0),
        50.0,
    );
    let p = params(
        cam,
        Sky::Uniform {
            colour: [0.8, 0.9, 1.0],
        },
        None,
        3,
    );
    let view = w.read();
    let v = Variant::for_scene(&view, &p);
    assert!(v.lambertian && v.metal, "{v:?}");
    assert!(
        !v.dielectric && !v.emissive && !v.sun && !v.gradient_sky,
        "{v:?}"
    );
    assert_eq!(v.max_bounces, 3);
    let gpu = GpuWorld::upload(&ctx, &view).unwrap();
    let mut tracer = PathTracer::new(&ctx).unwrap();
    let job = RenderJob {
        width: 24,
        height: 16,
        spp: 8,
        seed: 3,
    };
    let a = tracer
        .render(&ctx, &gpu, &view, &p, &job, RenderHow::variant(v))
        .unwrap()
        .image;
    let b = tracer
        .render(
            &ctx,
            &gpu,
            &view,
            &p,
            &job,
            RenderHow::variant(Variant::everything(3)),
        )
        .unwrap()
        .image;
    assert_eq!(tracer.variants(), 2);
    // Compilers may contract arithmetic differently per variant, so allow a few pixels
    // whose paths took another branch; the rest agree to float precision.
    let close = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(x, y)| (0..3).all(|k| (x[k] - y[k]).abs() <= 1e-4 * y[k].abs().max(1.0)))
        .count();
    assert!(
        close * 100 >= a.pixels.len() * 98,
        "{close} of {} pixels agree",
        a.pixels.len()
    );
    let (ma, mb) = (a.mean(), b.mean());
    for k in 0..3 {
        assert!((ma[k] - mb[k]).abs() < 0.01 * mb[k], "{ma:?} vs {mb:?}");
    }
    drop(view);
    // A scene with a dielectric, an emitter, the sun and a gradient sky gets them all.
    w.push_material(brickmap::Material {
        kind: MaterialKind::Dielectric,
        param: 0,
        colour: 1,
    })
    .unwrap();
    let (_, sunny, _) = sun_floor();
    let v2 = Variant::for_scene(&w.read(), &sunny);
    assert!(
        v2.dielectric && v2.sun && v2.gradient_sky == matches!(sunny.sky, Sky::Gradient { .. })
    );

    tracer.destroy(&ctx);
    gpu.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn back_to_back_benchmark_dispatches_are_each_timed_and_ordered() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let (w, p, _) = sun_floor();
    let gpu = GpuWorld::upload(&ctx, &w.read()).unwrap();
    let mut tracer = PathTracer::new(&ctx).unwrap();
    let size = (16, 12);
    let mut acc = Progressive::new(&ctx, size, size, 3).unwrap();
    let variant = Variant::for_scene(&w.read(), &p);
    let times = acc
        .time_repeated(&ctx, &mut tracer, &gpu, &w.read(), &p, variant, 2, 5)
        .unwrap();
    if ctx.timestamp_period > 0.0 {
        assert_eq!(times.len(), 5);
        assert!(times.iter().all(|t| t.is_finite() && *t > 0.0), "{times:?}");
    } else {
        assert!(times.is_empty());
    }
    // The buffer holds one batch (each dispatch starts it over), the same as a render.
    let repeated = acc.hdr(&ctx).unwrap();
    let job = RenderJob {
        width: size.0,
        height: size.1,
        spp: 2,
        seed: 3,
    };
    let direct = tracer
        .render(&ctx, &gpu, &w.read(), &p, &job, RenderHow::SCENE)
        .unwrap()
        .image;
    // Equal up to the order of the shadow pass's float atomic adds.
    for (a, b) in repeated.pixels.iter().zip(&direct.pixels) {
        for k in 0..3 {
            assert!(
                (a[k] - b[k]).abs() <= 1e-5 * b[k].abs().max(1.0),
                "{a:?} vs {b:?}"
            );
        }
    }
    acc.destroy(&ctx);
    tracer.destroy(&ctx);
    gpu.destroy(&ctx);
    // Sync validation reports a missing barrier between the dispatches.
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn internal_resolution_is_upscaled_bilinearly_before_the_curve() {
    let Some(ctx) = context(DeviceChoice::Best) else {
        return;
    };
    let (w, p, _) = sun_floor();
    let gpu = GpuWorld::upload(&ctx, &w.read()).unwrap();
    let mut tracer = PathTracer::new(&ctx).unwrap();
    let tone = ToneMapper::new(&ctx).unwrap();
    let (internal, output) = ((12, 8), (30, 21));
    let mut acc = Progressive::new(&ctx, internal, output, 1).unwrap();
    acc.frame(&ctx, &mut tracer, &gpu, &w.read(), &p, false, 8)
        .unwrap();
    let shown = acc.display(&ctx, &tone, 0.5).unwrap();
    let hdr = acc.hdr(&ctx).unwrap();
    assert_eq!((hdr.width, hdr.height), internal);
    let expected = hdr.resized_bilinear(output.0, output.1).to_srgb8(0.5);
    assert_eq!(shown.len(), expected.len());
    let worst = shown
        .iter()
        .zip(&expected)
        .flat_map(|(a, b)| (0..3).map(move |k| (a[k] as i32 - b[k] as i32).abs()))
        .max()
        .unwrap();
    assert!(
        worst <= 1,
        "display differs from the CPU upscale by {worst} levels"
    );
    // A structured image (a ramp times a checkerboard) makes interpolation visible: the
    // upscale has more distinct colours than the source has pixels, and still matches.
    let src = Image {
        width: 6,
        height: 4,
        pixels: (0..24)
            .map(|i| {
                let (x, y) = (i % 6, i / 6);
                let v = 0.05 * (x + 6 * y) as f32 * if (x + y) % 2 == 0 { 1.0 } else { 0.3 };
                [v, 0.5 * v, 0.2]
            })
            .collect(),
    };
    let up = tone.upscale(&ctx, &src, (23, 17), 0.0).unwrap();
    let cpu = src.resized_bilinear(23, 17).to_srgb8(0.0);
    for (a, b) in up.iter().zip(&cpu) {
        assert!(
            (0..3).all(|k| (a[k] as i32 - b[k] as i32).abs() <= 1),
            "{a:?} vs {b:?}"
        );
    }
    let distinct: std::collections::HashSet<_> = up.iter().collect();
    assert!(distinct.len() > 24, "{} colours", distinct.len());
    acc.destroy(&ctx);
    tone.destroy(&ctx);
    tracer.destroy(&ctx);
    gpu.destroy(&ctx);
    assert_eq!(ctx.validation_errors(), 0);
}
