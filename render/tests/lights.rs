//! Emissive voxels as lights: light sampling with MIS must converge to the image
//! BSDF sampling alone converges to, on the CPU reference and on the GPU, in rooms lit by one
//! voxel, by thousands, by very different strengths, and through glass; and the GPU must
//! never produce NaN, also when the last light face is gone.

mod common;

use common::{lamp_rooms, same_image_within_noise};
use render::Image;
use render::cpu::{CpuScene, RenderJob};

fn cpu(w: &brickmap::World, p: &render::SceneParams, lights: bool, spp: u32, seed: u64) -> Image {
    let view = w.read();
    CpuScene::new(&view, p)
        .with_light_sampling(lights)
        .render(&RenderJob {
            width: 24,
            height: 24,
            spp,
            seed,
        })
}

fn check(what: &str, l1: &Image, l2: &Image, b1: &Image, b2: &Image) {
    assert!(l1.all_finite() && b1.all_finite(), "{what}: not finite");
    let (ratio, means) = same_image_within_noise(l1, l2, b1, b2);
    eprintln!("{what}: MSE over expected noise {ratio:.3}, means {means:.2} standard errors apart");
    assert!(
        (0.5..1.4).contains(&ratio),
        "{what}: light sampling and BSDF sampling differ by more than noise ({ratio})"
    );
    assert!(
        means < 4.5,
        "{what}: image means differ by {means} standard errors"
    );
}

#[test]
fn cpu_light_sampling_converges_to_the_bsdf_only_image() {
    for (what, w, p) in lamp_rooms() {
        let l1 = cpu(&w, &p, true, 32, 1);
        let l2 = cpu(&w, &p, true, 32, 2);
        let b1 = cpu(&w, &p, false, 128, 3);
        let b2 = cpu(&w, &p, false, 128, 4);
        check(&format!("CPU, {what}"), &l1, &l2, &b1, &b2);
    }
}

mod gpu {
    use super::*;
    use brickmap::{EditOp, Mode, Shape};
    use glam::IVec3;
    use render::vulkan::DeviceChoice;
    use render::vulkan::trace::Variant;

    fn render(
        ctx: &render::vulkan::GpuContext,
        w: &brickmap::World,
        p: &render::SceneParams,
        variant: impl Fn(Variant) -> Variant,
        spp: u32,
        seed: u64,
    ) -> Image {
        common::gpu_render_with(ctx, w, p, 24, spp, seed, variant, true)
    }

    #[test]
    fn gpu_light_sampling_converges_to_the_bsdf_only_image_and_to_the_cpu() {
        let Some(ctx) = common::gpu_context(DeviceChoice::Best) else {
            return;
        };
        for (what, w, p) in lamp_rooms() {
            assert!(Variant::for_scene(&w.read(), &p).lights, "{what}");
            let on = |v: Variant| v;
            let off = |v: Variant| Variant { lights: false, ..v };
            let l1 = render(&ctx, &w, &p, on, 64, 1);
            let l2 = render(&ctx, &w, &p, on, 64, 2);
            let b1 = render(&ctx, &w, &p, off, 512, 3);
            let b2 = render(&ctx, &w, &p, off, 512, 4);
            check(&format!("GPU, {what}"), &l1, &l2, &b1, &b2);
            // And the GPU's light sampling is the CPU's.
            let c1 = cpu(&w, &p, true, 64, 5);
            let c2 = cpu(&w, &p, true, 64, 6);
            check(&format!("GPU against CPU, {what}"), &l1, &l2, &c1, &c2);
            // The benchmark's light-tree experiments (trace.comp EXPERIMENT bits 12, 14, 16..17):
            // the 4-wide and binary descents, the subgroup's one sun-or-faces choice and the
            // least share of 0.02 are other estimators of the same image.
            let wide = match what {
                "thousands of voxels" => vec![("4-wide", 1 << 16), ("binary", 2 << 16)],
                "the sun and lamps" => vec![
                    ("coherent, binary", 4096 | 2 << 16),
                    ("least share 0.02", 16384),
                ],
                _ => vec![],
            };
            for (label, experiment) in wide {
                let x = |v: Variant| Variant { experiment, ..v };
                let x1 = render(&ctx, &w, &p, x, 64, 9);
                let x2 = render(&ctx, &w, &p, x, 64, 10);
                check(
                    &format!("GPU {label} against the CPU, {what}"),
                    &x1,
                    &x2,
                    &c1,
                    &c2,
                );
            }
            if what == "strengths 1 and 1000" {
                // Shadow rays traced where they start (no shadow pass) render the same.
                let i1 = common::gpu_render_with(&ctx, &w, &p, 24, 64, 7, on, false);
                let i2 = common::gpu_render_with(&ctx, &w, &p, 24, 64, 8, on, false);
                check(
                    &format!("GPU in place against queued, {what}"),
                    &i1,
                    &i2,
                    &l1,
                    &l2,
                );
            }
        }
        assert_eq!(ctx.validation_errors(), 0);
    }

    /// A 48 × 16 × 48 room with 36 lamps under its ceiling, 32 of them sealed in hollow boxes
    /// (their faces are light faces no shading point outside can see) and 4 open.
    fn sealed_lamps() -> (brickmap::World, render::SceneParams) {
        let w = common::world((6, 2, 6));
        let wall = common::add_material(&w, brickmap::MaterialKind::Lambertian, 0, [180, 170, 160]);
        w.set_param(brickmap::MaterialKind::Emissive, 1, 40.0)
            .unwrap();
        let lamp = common::add_material(&w, brickmap::MaterialKind::Emissive, 1, [255, 240, 220]);
        let v = w.dims().voxels() - 1;
        let put = |mode, min, max| {
            w.apply(EditOp::Shape {
                shape: Shape::Box { min, max },
                mode,
            })
            .unwrap();
        };
        put(Mode::Add(wall), IVec3::ZERO, v);
        put(Mode::Remove, IVec3::ONE, v - 1);
        for i in 0..6 {
            for k in 0..6 {
                let c = IVec3::new(4 + 8 * i, 11, 4 + 8 * k);
                let open = (i == 1 || i == 4) && (k == 1 || k == 4);
                if !open {
                    put(Mode::Add(wall), c - 2, c + 2);
                    put(Mode::Remove, c - 1, c + 1);
                }
                put(Mode::Add(lamp), c, c);
            }
        }
        assert!(w.read().lights().len() >= 36 * 6);
        let v = v.as_dvec3();
        let camera = render::Camera::looking_at(
            glam::DVec3::new(v.x * 0.5, v.y * 0.5, v.z - 3.0),
            glam::DVec3::new(v.x * 0.5, 2.0, v.z * 0.4),
            70.0,
        );
        let black = render::Sky::Uniform { colour: [0.0; 3] };
        (w, common::params(camera, black, None, 4))
    }

    #[test]
    fn the_light_visibility_cache_learns_which_lamps_are_sealed_and_stays_unbiased() {
        let Some(ctx) = common::gpu_context(DeviceChoice::Best) else {
            return;
        };
        let (w, p) = sealed_lamps();
        let cached = |v: Variant| Variant {
            experiment: render::vulkan::trace::EXPERIMENT_LIGHT_CACHE,
            ..v
        };
        let uncached = |v: Variant| v;
        let on: Vec<Image> = (0..2)
            .map(|s| render(&ctx, &w, &p, cached, 256, 20 + s))
            .collect();
        let off: Vec<Image> = (0..2)
            .map(|s| render(&ctx, &w, &p, uncached, 256, 30 + s))
            .collect();
        let c1 = cpu(&w, &p, true, 64, 40);
        let c2 = cpu(&w, &p, true, 64, 41);
        // Both estimate the CPU reference's image...
        check(
            "GPU with the cache against the CPU, sealed lamps",
            &on[0],
            &on[1],
            &c1,
            &c2,
        );
        check(
            "GPU without the cache against the CPU, sealed lamps",
            &off[0],
            &off[1],
            &c1,
            &c2,
        );
        // ... and the cache, having learnt that most lamps cannot be seen, wastes fewer shadow
        // rays on them: less error at equal samples (against a long render of both).
        let reference = render(&ctx, &w, &p, uncached, 2048, 50);
        let error = |a: &[Image]| {
            a.iter()
                .map(|i| render::convergence::rel_mse(i, &reference).unwrap())
                .sum::<f64>()
                / a.len() as f64
        };
        let (e_on, e_off) = (error(&on), error(&off));
        eprintln!("sealed lamps, relMSE at 256 spp: cache {e_on:.4e}, none {e_off:.4e}");
        assert!(
            e_on < 0.5 * e_off,
            "the cache should cut the error: {e_on} against {e_off}"
        );
        assert_eq!(ctx.validation_errors(), 0);
    }

    #[test]
    fn the_light_cache_counts_each_shadow_ray_keeps_its_counts_and_drops_them_when_the_world_changes()
     {
        use render::vulkan::trace::{LIGHT_CACHE_ENTRIES, PathTracer};
        use render::vulkan::world::GpuWorld;
        let Some(ctx) = common::gpu_context(DeviceChoice::Best) else {
            return;
        };
        let (w, p) = sealed_lamps();
        // A 1-spp render (one dispatch) on `tracer`, and the cache's tries and unblocked rays
        // summed over its entries, per word of an entry (0..64 the nodes, 128 the sun's).
        let counts = |tracer: &mut PathTracer, world: &GpuWorld, seed: u64| {
            let view = w.read();
            let job = RenderJob {
                width: 24,
                height: 24,
                spp: 1,
                seed,
            };
            let variant = Variant {
                experiment: render::vulkan::trace::EXPERIMENT_LIGHT_CACHE,
                ..Variant::for_scene(&view, &p)
            };
            let how = render::viewport::RenderHow::variant(variant);
            tracer.render(&ctx, world, &view, &p, &job, how).unwrap();
            let bytes =
                render::vulkan::buffer::read_device(&ctx, tracer.light_cache().unwrap()).unwrap();
            let words: Vec<u32> = bytes
                .chunks_exact(4)
                .map(|b| u32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            assert_eq!(
                words.len(),
                LIGHT_CACHE_ENTRIES as usize * 256,
                "all entries fit"
            );
            let mut tries = vec![0u64; 64];
            let mut unblocked = vec![0u64; 64];
            for entry in words.chunks_exact(256) {
                for k in 0..64 {
                    tries[k] += u64::from(entry[k]);
                    unblocked[k] += u64::from(entry[64 + k]);
                }
            }
            (tries, unblocked)
        };
        let total = |v: &[u64]| v.iter().sum::<u64>();
        let fresh = |queued: bool| {
            let world = GpuWorld::upload(&ctx, &w.read()).unwrap();
            let mut tracer = PathTracer::new(&ctx).unwrap();
            tracer.set_deferred_shadows(&ctx, queued);
            (tracer, world)
        };
        // Queued shadow rays and rays traced in place count alike.
        let (mut queued, mut world) = fresh(true);
        let (mut in_place, other) = fresh(false);
        let (tries, unblocked) = counts(&mut queued, &world, 1);
        let (tries_here, unblocked_here) = counts(&mut in_place, &other, 1);
        assert_eq!(tries, tries_here, "the same rays, from either pass");
        let (a, b) = (total(&unblocked) as f64, total(&unblocked_here) as f64);
        assert!((a - b).abs() <= 1e-3 * a, "{a} against {b} unblocked");
        // Most lamps are sealed: many rays towards them, few of them unblocked.
        assert!(total(&tries) > 1000 && total(&unblocked) > 0, "{tries:?}");
        assert!(
            total(&unblocked) < total(&tries) / 2,
            "{unblocked:?} of {tries:?}"
        );
        // A second render on the same world adds to the counts (a camera move keeps them).
        let (more, _) = counts(&mut queued, &world, 2);
        assert!(
            total(&more) > total(&tries) * 3 / 2,
            "{more:?} after {tries:?}"
        );
        // An edit (a voxel set and cleared: the same world, changed) drops them: the next
        // render counts as a new tracer's first.
        for mode in [Mode::Add(0), Mode::Remove] {
            let at = IVec3::new(2, 1, 2);
            w.apply(EditOp::Shape {
                shape: Shape::Box { min: at, max: at },
                mode,
            })
            .unwrap();
            world.sync(&ctx, &w).unwrap();
        }
        let (after, _) = counts(&mut queued, &world, 3);
        let (first, _) = counts(&mut in_place, &other, 3);
        let (mut new, unused) = fresh(true);
        let (again, _) = counts(&mut new, &world, 3);
        unused.destroy(&ctx);
        assert_eq!(after, again, "an edit starts the counts afresh");
        assert!(
            total(&first) > total(&after),
            "the untouched tracer kept counting"
        );
        for t in [queued, in_place, new] {
            t.destroy(&ctx);
        }
        world.destroy(&ctx);
        other.destroy(&ctx);
        assert_eq!(ctx.validation_errors(), 0);
    }

    #[test]
    fn no_nan_when_the_last_light_face_is_erased() {
        let Some(ctx) = common::gpu_context(DeviceChoice::Best) else {
            return;
        };
        let (_, w, p) = lamp_rooms().remove(0);
        let lit = render(&ctx, &w, &p, |v| v, 16, 1);
        assert!(lit.all_finite() && lit.mean()[0] > 0.0);
        let v = w.dims().voxels() - 1;
        // Erase the room's inside, the lamp with it, leaving the walls: no light face is left.
        w.apply(EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::ONE,
                max: v - 1,
            },
            mode: Mode::Remove,
        })
        .unwrap();
        assert!(w.read().lights().is_empty() && w.read().lights().total() == 0.0);
        // The variant that samples lights, on a structure with nothing in it.
        for variant in [
            |v: Variant| Variant { lights: true, ..v },
            |_| Variant::everything(4),
        ] {
            let dark = render(&ctx, &w, &p, variant, 16, 2);
            assert!(dark.all_finite());
            assert_eq!(dark.mean(), [0.0; 3], "no light is left");
        }
        assert_eq!(ctx.validation_errors(), 0);
    }
}
