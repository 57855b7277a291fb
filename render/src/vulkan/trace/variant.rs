//! `Variant`: what a trace pipeline is specialised to (specialization constants of
//! shaders/trace.comp): the material kinds present, light sampling, the sun, the sky, the
//! path length, ray counting, experiments and the sample numbers.

use super::*;

/// What a pipeline variant contains (`constant_id` 0..8 and 10..15 of shaders/trace.comp; 9, the shadow
/// queue, is the tracer's choice).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Variant {
    /// Code for lambertian materials.
    pub lambertian: bool,
    /// Code for metals (mirror and GGX).
    pub metal: bool,
    /// Code for dielectrics (and media: without them every ray is in air).
    pub dielectric: bool,
    /// Code for emissive voxels.
    pub emissive: bool,
    /// Next-event estimation of emissive voxels (the scene has light faces; off: they are
    /// found by BSDF rays only, the same converged image).
    pub lights: bool,
    /// The sun disc (next-event estimation, MIS, hits).
    pub sun: bool,
    /// A gradient sky (else uniform).
    pub gradient_sky: bool,
    /// Scattering vertices per path (docs/DESIGN.md's B).
    pub max_bounces: u32,
    /// Count rays into the counters buffer (for Mrays/s; not for timing).
    pub count_rays: bool,
    /// Benchmark experiments (`EXPERIMENT` in trace.comp); 0 for real renders.
    pub experiment: u32,
    /// The numbers samples are made from (`SEQUENCE` in trace.comp).
    pub sequence: Sequence,
    /// Weight camera hits outside a box ([`TraceParams::dimmed`]; the editor's dimming of
    /// the objects it is not editing).
    pub dim: bool,
    /// The ground grid ([`TraceParams::with_grid`]).
    pub grid: bool,
    /// Coverage only: camera rays add 1 where they hit a voxel, 0 elsewhere, and end (a
    /// finished render's alpha; [`Variant::coverage`]).
    pub coverage: bool,
    /// A transparent background: camera rays that miss every voxel add nothing (the sky
    /// and the sun still light the voxels; a finished render with alpha).
    pub transparent: bool,
}

impl Variant {
    /// The variant a scene needs: the kinds present in its material table (every entry, used
    /// or not, so any voxel is shaded by its kind), light sampling when it has light faces,
    /// its sun, sky and path length.
    pub fn for_scene(view: &WorldView<'_>, params: &SceneParams) -> Self {
        let mut v = Self::for_table(view.materials(), params);
        v.lights = v.emissive && view.lights().total() > 0.0;
        v
    }

    /// [`Variant::for_scene`] without light sampling.
    fn for_table(materials: &MaterialTable, params: &SceneParams) -> Self {
        let mut v = Self {
            lambertian: false,
            metal: false,
            dielectric: false,
            emissive: false,
            lights: false,
            sun: params.sun.enabled,
            gradient_sky: matches!(params.sky, Sky::Gradient { .. }),
            max_bounces: params.settings.max_bounces.max(1),
            count_rays: false,
            experiment: 0,
            sequence: params.settings.sequence,
            dim: false,
            grid: false,
            coverage: false,
            transparent: false,
        };
        for i in 0..materials.len() {
            if let Ok(m) = materials.get(i as u8) {
                match m.kind {
                    MaterialKind::Lambertian => v.lambertian = true,
                    MaterialKind::Metal => v.metal = true,
                    MaterialKind::Dielectric => v.dielectric = true,
                    MaterialKind::Emissive => v.emissive = true,
                }
            }
        }
        v
    }

    /// The variant with every feature (what an unspecialised shader would run).
    pub fn everything(max_bounces: u32) -> Self {
        Self {
            lambertian: true,
            metal: true,
            dielectric: true,
            emissive: true,
            lights: true,
            sun: true,
            gradient_sky: true,
            max_bounces: max_bounces.max(1),
            count_rays: false,
            experiment: 0,
            sequence: Sequence::Independent,
            dim: false,
            grid: false,
            coverage: false,
            transparent: false,
        }
    }

    /// The coverage variant: the camera rays of `sequence`'s numbers, nothing else.
    pub fn coverage(sequence: Sequence) -> Self {
        Self {
            lambertian: false,
            metal: false,
            dielectric: false,
            emissive: false,
            lights: false,
            sun: false,
            gradient_sky: false,
            max_bounces: 1,
            count_rays: false,
            experiment: 0,
            sequence,
            dim: false,
            grid: false,
            coverage: true,
            transparent: false,
        }
    }

    pub(super) fn constants(&self, shadow_queue: bool) -> [u32; 16] {
        [
            self.lambertian as u32,
            self.metal as u32,
            self.dielectric as u32,
            self.emissive as u32,
            self.sun as u32,
            self.gradient_sky as u32,
            self.max_bounces,
            self.count_rays as u32,
            self.experiment,
            shadow_queue as u32,
            self.lights as u32,
            (self.sequence == Sequence::Sobol) as u32,
            self.dim as u32,
            self.grid as u32,
            self.coverage as u32,
            self.transparent as u32,
        ]
    }
}
