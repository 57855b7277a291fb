//! The CPU reference path tracer against answers known in closed form.
//!
//! Statistical tolerances: a pixel's value is a mean of `spp` independent samples; the image
//! mean's standard error is estimated from the spread of pixel means (s / √pixels), and a
//! check passes within 4 standard errors (a false failure about once in 16,000 runs).

use brickmap::{EditOp, MaterialKind, Mode, Shape};
use glam::{DVec3, IVec3};
mod common;

use common::{
    SKY, add_material, assert_finite_and_nonnegative, block_scene, mean_and_error, params,
    sun_floor, world,
};
use render::{Camera, Sky};

use common::cpu_render as render;

fn looking_at(eye: DVec3, target: DVec3, fov: f64) -> Camera {
    Camera::looking_at(eye, target, fov)
}

#[test]
fn white_furnace_lambertian_and_mirror_are_exact() {
    for (kind, param) in [(MaterialKind::Lambertian, 0), (MaterialKind::Metal, 0)] {
        let (w, p) = block_scene(kind, param);
        for bounces in [1, 2, 5] {
            let mut p = p.clone();
            p.settings.max_bounces = bounces;
            let img = render(&w, &p, 24, 4, 1);
            for px in &img.pixels {
                for c in 0..3 {
                    assert!(
                        (px[c] - SKY[c]).abs() < 1e-5,
                        "{kind:?} B={bounces}: {px:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn white_furnace_glass_and_rough_metal_converge() {
    // Glass: every path that enters leaves again (1/η² in, η² out); with B = 64 the lost
    // tail is negligible, so the mean is the sky within the statistical error.
    let (w, mut p) = block_scene(MaterialKind::Dielectric, 0);
    p.settings.max_bounces = 64;
    let img = render(&w, &p, 24, 64, 2);
    let (mean, se) = mean_and_error(&img);
    assert!(
        (mean - SKY[0] as f64).abs() < 4.0 * se + 1e-4,
        "glass: {mean} ± {se}"
    );
    assert!(img.all_finite());
    // Rough metal (single-scattering GGX) loses some energy, never gains any.
    let (w, mut p) = block_scene(MaterialKind::Metal, 40);
    p.settings.max_bounces = 8;
    let img = render(&w, &p, 24, 32, 3);
    for px in &img.pixels {
        assert!(px[0] <= SKY[0] * (1.0 + 1e-4), "{px:?}");
    }
    let (mean, _) = mean_and_error(&img);
    assert!(mean > 0.9 * SKY[0] as f64, "{mean}");
}

#[test]
fn emissive_box_seen_from_inside_gives_its_emission() {
    let w = world((2, 2, 2));
    w.set_param(MaterialKind::Emissive, 2, 3.5).unwrap();
    let lamp = add_material(&w, MaterialKind::Emissive, 2, [255, 128, 64]);
    w.apply(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::ZERO,
            max: IVec3::splat(15),
        },
        mode: Mode::Add(lamp),
    })
    .unwrap();
    w.apply(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::ONE,
            max: IVec3::splat(14),
        },
        mode: Mode::Remove,
    })
    .unwrap();
    let cam = looking_at(DVec3::new(4.3, 5.1, 6.2), DVec3::new(9.0, 8.0, 12.0), 100.0);
    let p = params(cam, Sky::Uniform { colour: [0.0; 3] }, None, 3);
    let img = render(&w, &p, 24, 2, 4);
    let expected = [
        1.0,
        render::cpu::srgb_to_linear(128),
        render::cpu::srgb_to_linear(64),
    ]
    .map(|c| c * 3.5);
    for px in &img.pixels {
        for c in 0..3 {
            assert!(
                (px[c] as f64 - expected[c]).abs() < 1e-5,
                "{px:?} vs {expected:?}"
            );
        }
    }
}

#[test]
fn sun_disc_irradiance_matches_the_closed_form() {
    let (w, p, expected) = sun_floor();
    for bounces in [1, 3] {
        let mut p = p.clone();
        p.settings.max_bounces = bounces;
        let img = render(&w, &p, 16, 256, 10 + bounces as u64);
        let (mean, se) = mean_and_error(&img);
        assert!(
            (mean - expected).abs() < 4.0 * se + 1e-4 * expected,
            "B={bounces}: {mean} ± {se}, expected {expected}"
        );
    }
}

#[test]
fn error_falls_as_one_over_sqrt_spp() {
    // RMS error against the closed form at 4, 16 and 64 spp: each 4× more samples must
    // halve it (no plateau, so no bias), within sampling slack.
    let (w, p, expected) = sun_floor();
    common::assert_error_halves(|spp| render(&w, &p, 24, spp, 100 + spp as u64), expected);
}

#[test]
fn same_seed_same_image_and_no_nan_in_hard_places() {
    // (The furnace has zero variance, so the sun scene is where seeds show.)
    let (w, p, _) = sun_floor();
    assert_eq!(render(&w, &p, 16, 2, 9), render(&w, &p, 16, 2, 9));
    assert_ne!(render(&w, &p, 16, 2, 9), render(&w, &p, 16, 2, 10));

    let (w, views) = common::hard_places();
    for (i, p) in views.iter().enumerate() {
        assert_finite_and_nonnegative(&render(&w, p, 20, 4, i as u64), &format!("camera {i}"));
    }
    let (w, views) = common::far_places();
    for (i, p) in views.iter().enumerate() {
        let what = format!("far camera {i}");
        assert_finite_and_nonnegative(&render(&w, p, 8, 2, i as u64), &what);
    }
}

#[test]
fn radiance_inside_glass_is_eta_squared_times_outside() {
    // Radiance seen from inside a clear dielectric looking out through a face is η²·L (L/η²
    // is invariant across the interface): this checks the (η_i/η_t)² factor, which the
    // outside furnace cannot (it cancels on the way in and out). Near-normal directions
    // only: in a cube, directions with every |dᵢ| below cos θc are trapped by total internal
    // reflection forever, and a wide view would include them.
    for (what, orthographic) in [("perspective", false), ("orthographic", true)] {
        let (w, p, expected) = common::inside_glass(orthographic);
        let img = render(&w, &p, 20, 64, 21);
        let (mean, se) = mean_and_error(&img);
        assert!(
            (mean - expected).abs() < 4.0 * se + 2e-3 * expected,
            "{what}: {mean} ± {se}, expected {expected}"
        );
    }
}

#[test]
fn an_orthographic_camera_sees_parallel_projections_from_its_plane() {
    let (w, mut p, lit) = common::orthographic_walls();
    common::assert_orthographic_walls(&render(&w, &p, 32, 4, 3), &lit, "orthographic");
    // The check can fail: the same view in perspective shows the rectangles elsewhere.
    p.camera.projection = render::Projection::Perspective;
    let img = render(&w, &p, 32, 4, 3);
    let wrong = img
        .pixels
        .iter()
        .zip(&lit)
        .filter(|(px, l)| (px[0] > 0.0) != **l)
        .count();
    assert!(wrong > 50, "{wrong} pixels differ");
}
