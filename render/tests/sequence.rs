//! The numbers samples are made from (render::Sequence): scrambled Sobol points, the default,
//! must converge on the GPU to the image independent numbers converge to (every material
//! kind, glass, the sun, emissive voxels with light sampling), and faster. Machines without a
//! Vulkan driver skip, saying so, unless VOXBRICK_REQUIRE_GPU=1 (CI) makes that a failure.

mod common;

use common::{gpu_render_with, lamp_rooms, same_image_within_noise, showcase, sun_floor};
use render::Sequence;
use render::vulkan::DeviceChoice;
use render::vulkan::trace::Variant;

fn with(sequence: Sequence) -> impl Fn(Variant) -> Variant {
    move |v| Variant { sequence, ..v }
}

#[test]
fn sobol_converges_to_the_image_of_independent_numbers() {
    let Some(ctx) = common::gpu_context(DeviceChoice::Best) else {
        return;
    };
    let mut scenes = vec![{
        let (w, p) = showcase();
        ("showcase", w, p)
    }];
    scenes.extend(lamp_rooms());
    for (what, w, p) in scenes {
        let sobol = with(Sequence::Sobol);
        let independent = with(Sequence::Independent);
        let s1 = gpu_render_with(&ctx, &w, &p, 24, 64, 1, &sobol, true);
        let s2 = gpu_render_with(&ctx, &w, &p, 24, 64, 2, &sobol, true);
        let i1 = gpu_render_with(&ctx, &w, &p, 24, 256, 3, &independent, true);
        let i2 = gpu_render_with(&ctx, &w, &p, 24, 256, 4, &independent, true);
        assert!(s1.all_finite() && s2.all_finite(), "{what}: not finite");
        // Independent scrambles per seed: the two Sobol renders' difference measures their
        // noise as it does for independent numbers.
        let (ratio, means) = same_image_within_noise(&s1, &s2, &i1, &i2);
        eprintln!(
            "{what}: MSE over expected noise {ratio:.3}, means {means:.2} standard errors apart"
        );
        assert!(
            (0.5..1.4).contains(&ratio),
            "{what}: Sobol and independent numbers differ by more than noise ({ratio})"
        );
        assert!(
            means < 4.5,
            "{what}: image means differ by {means} standard errors"
        );
    }
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn sobol_error_falls_faster_than_independent_numbers() {
    let Some(ctx) = common::gpu_context(DeviceChoice::Best) else {
        return;
    };
    // The sun floor's pixels have a closed form; the only decision is the point on the disc.
    let (w, p, expected) = sun_floor();
    let rms = |sequence: Sequence, spp: u32| {
        let f = with(sequence);
        let mut sum = 0.0;
        for seed in 0..4u64 {
            let img = gpu_render_with(&ctx, &w, &p, 16, spp, 10 + seed, &f, true);
            sum += img
                .pixels
                .iter()
                .map(|px| (f64::from(px[0]) - expected).powi(2))
                .sum::<f64>()
                / img.pixels.len() as f64;
        }
        (sum / 4.0).sqrt()
    };
    let (s16, s64) = (rms(Sequence::Sobol, 16), rms(Sequence::Sobol, 64));
    let (i16, i64) = (
        rms(Sequence::Independent, 16),
        rms(Sequence::Independent, 64),
    );
    eprintln!(
        "RMS error at 16 and 64 spp: Sobol {s16:.3e} {s64:.3e}, independent {i16:.3e} {i64:.3e}"
    );
    // Independent numbers halve the error with 4× the samples; stratified points on a smooth
    // integrand do better, and a plateau (a bias) would do worse.
    assert!(
        (1.6..2.5).contains(&(i16 / i64)),
        "independent: {i16} → {i64}"
    );
    assert!(s16 / s64 > 2.2, "Sobol: {s16} → {s64}");
    assert!(
        s64 < 0.5 * i64,
        "Sobol {s64} against independent {i64} at 64 spp"
    );
    assert_eq!(ctx.validation_errors(), 0);
}

#[test]
fn scenes_default_to_sobol_and_the_variant_follows_the_settings() {
    let (w, mut p) = showcase();
    assert_eq!(Sequence::default(), Sequence::Sobol);
    let framing = render::SceneParams::framing(glam::DVec3::splat(64.0));
    assert_eq!(framing.settings.sequence, Sequence::Sobol);
    assert_eq!(
        Variant::for_scene(&w.read(), &framing).sequence,
        Sequence::Sobol
    );
    p.settings.sequence = Sequence::Independent;
    assert_eq!(
        Variant::for_scene(&w.read(), &p).sequence,
        Sequence::Independent
    );
}
