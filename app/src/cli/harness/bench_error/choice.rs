//! `bench-error`'s sampling choices: the renderer's defaults with one thing changed, how
//! each is set on the tracer, and the dispatches its renders make.

use super::*;

/// A sampling choice: the renderer's defaults with one thing changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub(crate) enum Choice {
    /// The renderer's choices (scrambled Sobol numbers).
    Default,
    /// Fixed samples per pixel in one dispatch.
    SamplesPerDispatch(u32),
    /// Fixed invocations per pixel.
    Slices(u32),
    /// Shadow rays traced where they start instead of queued for the shadow pass.
    InPlaceShadows,
    /// Emissive voxels found by BSDF rays only (no next-event estimation, no MIS).
    NoLightSampling,
    /// Independent random numbers instead of scrambled Sobol points.
    Independent,
    /// The defaults' samples shown through the viewport's denoiser (biased: its error is
    /// measured, not checked against 1/spp).
    Denoised,
    /// The same without its fade to the raw mean (the filter's bias at every count).
    DenoisedUnfaded,
    /// The same with the fade from and to these sample counts at any picture size
    /// (`denoised-fade-F-T` on the command line).
    DenoisedFade(u32, u32),
}

impl Choice {
    pub(super) fn name(self) -> String {
        match self {
            Choice::Default => "defaults".into(),
            Choice::SamplesPerDispatch(1) => "1 sample per dispatch".into(),
            Choice::SamplesPerDispatch(n) => format!("{n} samples per dispatch"),
            Choice::Slices(1) => "1 slice".into(),
            Choice::Slices(n) => format!("{n} slices"),
            Choice::InPlaceShadows => "shadow rays in place".into(),
            Choice::NoLightSampling => "no light sampling".into(),
            Choice::Independent => "independent numbers".into(),
            Choice::Denoised => "denoised (viewport)".into(),
            Choice::DenoisedUnfaded => "denoised, no fade".into(),
            Choice::DenoisedFade(from, to) => format!("denoised, fade {from} to {to} spp"),
        }
    }

    /// The choice's name on the command line (`--choices`).
    pub(super) fn key(self) -> String {
        match self {
            Choice::Default => "defaults".into(),
            Choice::SamplesPerDispatch(n) => format!("per-dispatch-{n}"),
            Choice::Slices(n) => format!("slices-{n}"),
            Choice::InPlaceShadows => "in-place-shadows".into(),
            Choice::NoLightSampling => "no-light-sampling".into(),
            Choice::Independent => "independent".into(),
            Choice::Denoised => "denoised".into(),
            Choice::DenoisedUnfaded => "denoised-no-fade".into(),
            Choice::DenoisedFade(from, to) => format!("denoised-fade-{from}-{to}"),
        }
    }

    /// Whether the image is shown through the denoiser.
    pub(super) fn denoised(self) -> bool {
        matches!(
            self,
            Choice::Denoised | Choice::DenoisedUnfaded | Choice::DenoisedFade(..)
        )
    }

    /// The choice a `--choices` key names, if any.
    pub(super) fn from_key(key: &str) -> Option<Choice> {
        if let Some(c) = CHOICES.into_iter().find(|c| c.key() == key) {
            return Some(c);
        }
        let (from, to) = key.strip_prefix("denoised-fade-")?.split_once('-')?;
        let (from, to) = (from.parse().ok()?, to.parse().ok()?);
        (0 < from && from < to).then_some(Choice::DenoisedFade(from, to))
    }

    /// The denoiser's fade the choice asks for (None: the viewport's own).
    pub(super) fn fade(self) -> Option<Fade> {
        match self {
            Choice::DenoisedUnfaded => Some(Fade::NEVER),
            Choice::DenoisedFade(from, to) => Some(Fade {
                from: from as f32,
                to: to as f32,
            }),
            _ => None,
        }
    }

    /// Whether the estimator is biased (consistent at best): its curve is not checked.
    pub(super) fn biased(self) -> bool {
        self.denoised()
    }

    /// Whether the choice changes the estimator (else only how the same samples are
    /// scheduled: the image is the same up to float rounding).
    pub(super) fn changes_estimator(self) -> bool {
        matches!(
            self,
            Choice::Default
                | Choice::NoLightSampling
                | Choice::Independent
                | Choice::Denoised
                | Choice::DenoisedUnfaded
                | Choice::DenoisedFade(..)
        )
    }

    /// Whether the choice changes anything for `variant` on this tracer.
    pub(super) fn applies(self, session: &mut Viewport, variant: Variant, pixels: u64) -> bool {
        let queue = session.ctx().shadow_queue;
        let tracer = session.tracer();
        match self {
            Choice::Default | Choice::Independent => true,
            Choice::Denoised | Choice::DenoisedUnfaded | Choice::DenoisedFade(..) => true,
            Choice::SamplesPerDispatch(n) => tracer.samples_per_dispatch_for(pixels, variant) != n,
            Choice::Slices(n) => queue && timed_slices(tracer, variant, pixels) != n,
            Choice::InPlaceShadows => tracer.deferred_shadows() && (variant.sun || variant.lights),
            Choice::NoLightSampling => variant.lights,
        }
    }

    /// Sets the tracer for the choice and gives the variant to render.
    pub(super) fn apply(self, session: &mut Viewport, variant: Variant) -> Variant {
        let ctx = session.ctx().clone();
        let tracer = session.tracer();
        tracer.set_samples_per_dispatch(None);
        tracer.set_sample_slices(None);
        tracer.set_deferred_shadows(&ctx, true);
        let mut v = Variant {
            sequence: Sequence::default(),
            ..variant
        };
        match self {
            Choice::Default
            | Choice::Denoised
            | Choice::DenoisedUnfaded
            | Choice::DenoisedFade(..) => {}
            Choice::SamplesPerDispatch(n) => tracer.set_samples_per_dispatch(Some(n)),
            Choice::Slices(n) => tracer.set_sample_slices(Some(n)),
            Choice::InPlaceShadows => tracer.set_deferred_shadows(&ctx, false),
            Choice::NoLightSampling => v.lights = false,
            Choice::Independent => v.sequence = Sequence::Independent,
        }
        v
    }
}

/// The slices a timed dispatch gets: at most its samples, a divisor of them.
pub(super) fn timed_slices(
    tracer: &render::vulkan::trace::PathTracer,
    variant: Variant,
    pixels: u64,
) -> u32 {
    let spd = tracer.samples_per_dispatch_for(pixels, variant);
    (1..=tracer.sample_slices(pixels).min(spd))
        .rev()
        .find(|s| spd.is_multiple_of(*s))
        .unwrap_or(1)
}

/// Samples per pixel one dispatch of a render adds (samples per invocation × slices).
pub(super) fn dispatch_samples(session: &mut Viewport, variant: Variant, pixels: u64) -> u32 {
    let tracer = session.tracer();
    tracer.samples_per_dispatch_for(pixels, variant) * tracer.sample_slices(pixels).max(1)
}

/// Every choice measured, the defaults first.
pub(super) const CHOICES: [Choice; 10] = [
    Choice::Default,
    Choice::SamplesPerDispatch(1),
    Choice::SamplesPerDispatch(16),
    Choice::Slices(1),
    Choice::Slices(2),
    Choice::InPlaceShadows,
    Choice::NoLightSampling,
    Choice::Independent,
    Choice::Denoised,
    Choice::DenoisedUnfaded,
];

#[cfg(test)]
mod tests {
    use super::Choice;

    #[test]
    fn every_key_names_its_choice_and_fades_parse_only_when_they_rise() {
        for c in super::CHOICES {
            assert_eq!(Choice::from_key(&c.key()), Some(c));
        }
        let fade = Choice::from_key("denoised-fade-8-128").expect("a fade from 8 to 128");
        assert_eq!(fade, Choice::DenoisedFade(8, 128));
        assert_eq!(Choice::from_key(&fade.key()), Some(fade));
        let f = fade.fade().expect("a fade");
        assert_eq!((f.from, f.to), (8.0, 128.0));
        assert!(fade.denoised() && fade.changes_estimator());
        for bad in [
            "denoised-fade-0-8",
            "denoised-fade-64-8",
            "denoised-fade-8",
            "denoised-fade-a-b",
            "fade-8-64",
        ] {
            assert_eq!(Choice::from_key(bad), None, "{bad}");
        }
        assert_eq!(Choice::Denoised.fade(), None);
    }
}
