//! The correspond phase of one object's tick: this tick's depth registered and carried to the prediction, the
//! events of its window binned and matched, the model view of its ROI render, and the pose the optimisation
//! starts from (the prediction, moved by a late frame's check or by the outline's image shift the events show, and
//! at a depth frame onto the range it measures).

use super::carried_depth::{capture_neighbourhood, carry_depth_from};
use super::inputs::TickInputs;
use super::late_depth::{carry_late_depth, register_late_depth};
use super::model::ObjectModel;
use super::motion::image_motion_direction;
use super::range_align::aligned_range;
use super::scratch::TickScratch;
use super::start::{Start, TickDepth};
use super::state::ObjectState;
use crate::refine::{BinnedWindow, EventTermKind, apply_step};
use crate::track::config::{DepthUse, TrackerConfig};
use crate::track::estimate::TrackingState;
use nalgebra::{Isometry3, Translation3, Vector3, Vector6};
use scene::geometry::{PinholeCamera, Roi};

/// Registers this tick's depth frame as the new `D_0` and renders `D_t` at the predicted pose in the ROI chosen
/// by [`ObjectState::update_roi`]. None of it reads the ROI render, so the tracker runs it before taking the
/// render: a render that is still in flight (prefetched on a GPU) overlaps this work.
pub(super) fn prepare_depth(
    model: &ObjectModel,
    state: &mut ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
) -> TickDepth {
    state.late_motion = None;
    state.late_frame = None;
    let Some(roi) = state.roi else {
        return TickDepth::default();
    };
    let roi_camera = inputs.camera.crop(&roi);
    let predicted = state.predicted;
    let mut fresh = inputs.depth.is_some()
        && match config.modalities.depth {
            DepthUse::EveryTick | DepthUse::DepthFramesOnly => true,
            DepthUse::FirstFrameOnly => state.depth_frames_used == 0,
            DepthUse::Off => false,
        };
    // A frame exposed at an earlier tick is placed by the estimate then; without one it is of no use.
    let mut late_from = None;
    if fresh && inputs.depth_exposed_us < inputs.t_us {
        late_from = state.history.at(inputs.depth_exposed_us);
        if late_from.is_none() {
            state.late_depth_unplaced += 1;
            fresh = false;
        }
    }
    let mut depth = TickDepth::default();
    if fresh {
        if let Some(frame) = inputs.depth {
            capture_neighbourhood(state, frame, inputs.depth_rig, config);
            match late_from {
                // Aligned and carried by the refinement, which needs the model view of the ROI render.
                Some(then) => register_late_depth(
                    model,
                    state,
                    frame,
                    inputs.depth_rig,
                    inputs.depth_exposed_us,
                    &then,
                    config,
                ),
                None => {
                    carry_depth_from(model, state, frame, inputs.depth_rig, inputs.t_us, config);
                    state
                        .carried
                        .render(&predicted, &roi_camera, &mut scratch.depth_now);
                }
            }
            depth = TickDepth {
                fresh: true,
                weight: 1.0,
                at_predicted: true,
            };
        }
    } else if config.modalities.depth == DepthUse::EveryTick && !state.carried.is_empty() {
        // Rendered at the pose the refinement starts from: here if the occluded outline is hidden, which needs
        // it at the prediction, else in `correspond`.
        depth.weight = config.modalities.carried_depth_weight;
        if config.correspond.hide_occluded_outline && depth.weight > 0.0 {
            state
                .carried
                .render(&predicted, &roi_camera, &mut scratch.depth_now);
            depth.at_predicted = true;
        }
    }
    depth
}

/// The event window this tick's refinement reads, microseconds: about `event_window_px` of the outline's
/// predicted image motion, within the configured bounds.
fn event_window_us(
    model: &ObjectModel,
    state: &ObjectState,
    camera: &PinholeCamera,
    config: &TrackerConfig,
) -> i64 {
    let speed = state.image_speed(model, camera).max(1.0);
    let window = ((config.correspond.event_window_px / speed) * 1e6) as i64;
    window.clamp(
        config.correspond.min_event_window_us,
        config.correspond.max_event_window_us,
    )
}

/// Bins the events of this tick's window in the ROI chosen by [`ObjectState::update_roi`], which needs no
/// render: the tracker runs it before taking the render, so that a render still in flight overlaps it. The
/// correspond phase reuses the bins.
pub(super) fn prepare_events(
    model: &ObjectModel,
    state: &ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
) {
    if !config.modalities.events {
        return;
    }
    if let Some(roi) = state.roi {
        let window = BinnedWindow {
            t_us: inputs.t_us,
            window_us: event_window_us(model, state, inputs.camera, config),
            roi,
        };
        scratch.edges.bin_ahead(inputs.surface, window);
    }
}

/// The correspond phase at a tick with an ROI render in `scratch.target`: extracts the model view, carries a late
/// frame, hides an outline the depth shows occluded, matches the events, and chooses where the optimisation
/// starts. `None` when the object holds its pose at this tick instead (no depth frame yet while one may still come,
/// or `depth30` between frames).
#[allow(clippy::too_many_arguments)]
pub(super) fn correspond(
    model: &ObjectModel,
    state: &mut ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    depth: TickDepth,
    roi: &Roi,
    prebinned: Option<BinnedWindow>,
) -> Option<Start> {
    let roi_camera = inputs.camera.crop(roi);
    let (predicted, late, late_fit) =
        view_at_prediction(model, state, scratch, inputs, config, depth, &roi_camera);
    if !refines_now(state, inputs, config, depth.fresh) {
        return None;
    }
    let event_term = config.event_term;
    let use_events = config.modalities.events
        && !scratch.view.contour.is_empty()
        && !(depth.fresh && at_first_pose(state, inputs, config));
    let use_intensity = use_events && config.intensity_term.weight > 0.0;
    let contrast_max = use_events && event_term.kind == EventTermKind::ContrastMax;
    let use_event_residuals = use_events && !contrast_max;
    let (window_s, contrast_velocity) = if use_events {
        match_events(
            model, state, scratch, inputs, config, roi, &predicted, prebinned,
        )
    } else {
        (0.0, None)
    };
    let pose = start_pose(
        model,
        state,
        scratch,
        inputs,
        config,
        &predicted,
        contrast_velocity,
        use_event_residuals,
    );
    let pose = if depth.fresh && !late && config.correspond.align_range_at_depth {
        aligned_range(
            model,
            &scratch.view,
            &pose,
            &roi_camera,
            &scratch.depth_now,
            config,
            &mut scratch.range_offsets,
        )
        .unwrap_or(pose)
    } else {
        pose
    };
    if depth.weight > 0.0 && !depth.fresh && !(depth.at_predicted && pose == predicted) {
        state
            .carried
            .render(&pose, &roi_camera, &mut scratch.depth_now);
    }
    Some(Start {
        pose,
        depth,
        late,
        late_fit,
        use_events,
        use_event_residuals,
        use_intensity,
        window_s,
    })
}

/// Whether this tick is at the first pose's own time and the events are left out there
/// ([`crate::track::CorrespondConfig::events_at_first_pose`] off).
fn at_first_pose(state: &ObjectState, inputs: &TickInputs<'_>, config: &TrackerConfig) -> bool {
    !config.correspond.events_at_first_pose && inputs.t_us <= state.first_us
}

/// The model view of the ROI render at the prediction, a late frame carried (its check at the exposure corrects
/// the prediction), and the outline the depth shows occluded hidden. Returns the prediction to start from, whether
/// the tick's depth frame is late, and its depth counts at the exposure.
fn view_at_prediction(
    model: &ObjectModel,
    state: &mut ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    depth: TickDepth,
    roi_camera: &PinholeCamera,
) -> (Isometry3<f64>, bool, Option<crate::refine::DepthTermStats>) {
    let predicted = state.predicted;
    scratch.view.extract(
        &scratch.target,
        roi_camera,
        model.label,
        &predicted,
        config.correspond.max_surface_points,
        config.correspond.max_contour_points,
    );
    // A late frame: checked at its exposure, and the refinement starts from the prediction corrected there.
    let late = depth.fresh && state.late_frame.is_some();
    let (predicted, late_fit) = if late {
        let use_events = config.modalities.events && !scratch.view.contour.is_empty();
        carry_late_depth(
            model, state, scratch, inputs, roi_camera, use_events, config,
        )
    } else {
        (predicted, None)
    };
    // Outline the depth shows behind a nearer surface (a hand gripping the object) fires no events: leave it
    // out of the event and intensity terms rather than pull it onto the occluder's edges.
    if config.correspond.hide_occluded_outline && depth.weight > 0.0 {
        scratch.view.hide_occluded_contour(
            &scratch.depth_now,
            roi_camera,
            &predicted,
            config.depth_term.occlusion_gap,
            config.correspond.hide_occluded_max_share,
        );
    }
    (predicted, late, late_fit)
}

/// Whether the object refines at this tick (`fresh`: a depth frame was registered): `depth30` only at depth
/// frames; until its first depth frame, for as long as a late one could still come, an object holds its first
/// pose: events alone, with no depth to anchor them, drift (a live depth camera's first frame arrives tens of
/// milliseconds after the first tick).
fn refines_now(
    state: &ObjectState,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    fresh: bool,
) -> bool {
    let awaiting_depth = state.depth_frames_used == 0
        && (inputs.t_us - state.first_us) as f64 <= config.late_depth.max_depth_age_ms * 1e3;
    match config.modalities.depth {
        DepthUse::DepthFramesOnly => fresh,
        DepthUse::Off => true,
        DepthUse::EveryTick | DepthUse::FirstFrameOnly => fresh || !awaiting_depth,
    }
}

/// Where the optimisation starts: the previous estimate moved by the velocity contrast maximisation found, else
/// `predicted`, shifted by the outline's image shift the events show when the event residuals take part.
#[allow(clippy::too_many_arguments)]
fn start_pose(
    model: &ObjectModel,
    state: &ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    predicted: &Isometry3<f64>,
    contrast_velocity: Option<Vector6<f64>>,
    use_event_residuals: bool,
) -> Isometry3<f64> {
    let pose = match contrast_velocity {
        // The motion contrast maximisation found, from the previous estimate.
        Some(xi) => {
            let span = (inputs.t_us - state.t_us).max(0) as f64 * 1e-6;
            apply_step(&state.pose, &model.center_obj, &(xi * span))
        }
        None => *predicted,
    };
    if use_event_residuals
        && let Some(shifted) = outline_shift(model, state, scratch, inputs, config, predicted)
    {
        return shifted;
    }
    pose
}

/// How far the outline search looks, full-image pixels: the whole range until two depth frames have measured the
/// motion and while the estimate is not trusted, else a multiple of the predicted image motion per tick.
fn search_range(
    model: &ObjectModel,
    state: &ObjectState,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
) -> f64 {
    let event_term = config.event_term;
    if state.depth_frames_used < 2
        || (config.correspond.search_wide_when_degraded
            && state.tracking != TrackingState::Tracking)
    {
        event_term.search_px
    } else {
        // max-then-min rather than clamp: a config with min > max must not panic (the range is then max).
        (event_term.search_speed_factor * state.image_speed(model, inputs.camera) * inputs.dt_s)
            .max(event_term.search_min_px)
            .min(event_term.search_px)
    }
}

/// Matches the events of this tick's window to the render: collects them in the ROI (`prebinned` if the window was
/// binned ahead) and, for contrast maximisation, finds the velocity that sharpens them. Returns the window in
/// seconds and that velocity, if any.
#[allow(clippy::too_many_arguments)]
fn match_events(
    model: &ObjectModel,
    state: &ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    roi: &Roi,
    predicted: &Isometry3<f64>,
    prebinned: Option<BinnedWindow>,
) -> (f64, Option<Vector6<f64>>) {
    let event_term = config.event_term;
    let window = event_window_us(model, state, inputs.camera, config);
    let window_s = window as f64 * 1e-6;
    // Another object nearer than this one's centre hides it: its events are its own.
    let occluder_z = model.center_at(predicted).z as f32;
    scratch.edges.collect(
        &event_term,
        inputs.surface,
        roi,
        scratch.target.mask(),
        scratch.target.depth(),
        occluder_z,
        model.label,
        inputs.t_us,
        window,
        config.correspond.max_event_points,
        prebinned,
    );
    if event_term.kind != EventTermKind::ContrastMax {
        return (window_s, None);
    }
    let c = model.center_at(predicted);
    scratch.edges.lift_events(
        inputs.surface,
        inputs.camera,
        scratch.target.depth(),
        scratch.target.mask(),
        model.label,
        inputs.t_us,
        window,
        c.z,
        config.correspond.max_event_points * 8,
    );
    let velocity = scratch.edges.maximise_contrast(
        inputs.camera,
        &c,
        &state.velocity,
        event_term.contrast_step_translation,
        event_term.contrast_step_rotation,
        event_term.contrast_rounds,
    );
    (window_s, Some(velocity))
}

/// The prediction moved laterally by the image shift of the whole outline that the events show
/// ([`crate::refine::EventEdges::search_shift`]), if the search finds one.
fn outline_shift(
    model: &ObjectModel,
    state: &ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    predicted: &Isometry3<f64>,
) -> Option<Isometry3<f64>> {
    let event_term = config.event_term;
    let [du, dv] = scratch.edges.search_shift(
        &event_term,
        &scratch.view,
        predicted,
        inputs.camera,
        search_range(model, state, inputs, config),
        (event_term.search_aperture_tolerance > 0.0)
            .then(|| image_motion_direction(model, state, predicted, inputs))
            .flatten(),
    )?;
    // Move the centre laterally by the image shift at its depth.
    let c = model.center_at(predicted);
    let shift = Vector3::new(
        du * c.z / inputs.camera.fx,
        dv * c.z / inputs.camera.fy,
        0.0,
    );
    Some(Isometry3::from_parts(
        Translation3::from(predicted.translation.vector + shift),
        predicted.rotation,
    ))
}
