//! The optimise phase of one object's tick: the depth, event and intensity modalities built from this tick's
//! measurements, and the bounded Gauss-Newton loop over them from the correspond phase's start.

use super::inputs::TickInputs;
use super::model::ObjectModel;
use super::scratch::TickScratch;
use super::start::Start;
use super::state::ObjectState;
use crate::refine::{
    DepthModality, DepthTermStats, EventModality, IntensityModality, Optimiser, StartPrior,
    StepBounds,
};
use crate::track::config::TrackerConfig;
use nalgebra::Isometry3;
use scene::geometry::Roi;

/// The optimiser a tick's refinement runs: [`crate::track::OptimiserConfig::iterations`] steps bounded the way the paper's
/// refiner is (`max_step_rotation_deg`, `max_step_translation_diameters` of the object's diameter), with the prior
/// towards the start. `converged_below`: stop once a step is smaller (translation m, rotation rad).
pub(super) fn optimiser(
    model: &ObjectModel,
    config: &TrackerConfig,
    converged_below: Option<(f64, f64)>,
) -> Optimiser {
    Optimiser {
        iterations: config.optimiser.iterations,
        damping: config.optimiser.damping,
        bounds: StepBounds {
            max_rotation: config.optimiser.max_step_rotation_deg.to_radians(),
            max_translation: config.optimiser.max_step_translation_diameters * model.diameter,
        },
        prior: StartPrior::from_sigmas(
            config.optimiser.prior_translation_m,
            config.optimiser.prior_rotation_rad(),
        ),
        converged_below,
    }
}

/// Refines `start.pose` over the modalities this tick has: depth against `D_t` (weighted by how fresh it is),
/// the event residuals, the intensity edges. The prior towards the prediction keeps directions the data cannot
/// see (e.g. rotation about a symmetry axis) where the motion model puts them. Returns the refined pose and the
/// depth term's counts at the last iteration (`None` without depth).
pub(super) fn optimise(
    model: &ObjectModel,
    state: &ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    roi: &Roi,
    start: &Start,
) -> (Isometry3<f64>, Option<DepthTermStats>) {
    let roi_camera = inputs.camera.crop(roi);
    let mut depth = DepthModality {
        active: start.depth.weight > 0.0,
        term: &config.depth_term,
        camera: &roi_camera,
        depth: &scratch.depth_now,
        weight: start.depth.weight,
        stats: None,
    };
    let mut events = EventModality {
        active: start.use_event_residuals,
        term: &config.event_term,
        edges: &mut scratch.edges,
        camera: inputs.camera,
        motion: &state.velocity,
        center_obj: &model.center_obj,
        window_s: start.window_s,
        weight: config.modalities.event_weight,
    };
    let mut intensity = IntensityModality {
        active: start.use_intensity,
        term: &config.intensity_term,
        edges: &mut scratch.intensity_edges,
        camera: inputs.camera,
        surface: inputs.surface,
        t_us: inputs.t_us,
        roi_bin_px: roi.width / f64::from(roi.out_width.max(1)),
    };
    let mut optimiser = optimiser(model, config, Some((1e-5, 1e-4)));
    optimiser.prior = step_prior(optimiser.prior, model, inputs, config, &start.pose);
    let pose = optimiser.run(
        &mut [&mut depth, &mut events, &mut intensity],
        &scratch.view,
        &model.center_obj,
        start.pose,
    );
    (pose, depth.stats)
}

/// The prior of this object's step: at a step between ticks, held along the line of sight to the object at
/// `start` (`line_of_sight_sigma_m`: the events barely observe depth, so each step would add its own drift there;
/// the ticks refine it); then spread over the part of the tick period the step spans ([`StartPrior::spread`]:
/// steps between ticks and the tick after them span less).
fn step_prior(
    prior: StartPrior,
    model: &ObjectModel,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    start: &Isometry3<f64>,
) -> StartPrior {
    let prior = if inputs.inner {
        let center = start * nalgebra::Point3::from(model.center_obj);
        prior.with_along(&center.coords, config.inner_steps.line_of_sight_sigma_m)
    } else {
        prior
    };
    if inputs.span < 1.0 {
        prior.spread(inputs.span)
    } else {
        prior
    }
}
