//! Taking a depth frame as the object's carried depth `D_0`: registered around where the object is, kept with
//! the previous frame's moved surfaces for the safety net's motion check.

use super::model::ObjectModel;
use super::state::ObjectState;
use crate::recon::DepthRig;
use crate::track::config::TrackerConfig;
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Point3};

/// Takes the depth of `frame` (exposed at `t_us`) around the prediction as the depth `D_0` carried to the
/// following ticks (a sphere reaching past the ROI), every point static until it is split.
pub(super) fn carry_depth_from(
    model: &ObjectModel,
    state: &mut ObjectState,
    frame: &DepthFrame,
    rig: &DepthRig,
    t_us: i64,
    config: &TrackerConfig,
) {
    let predicted = state.predicted;
    register_between(
        model, state, frame, rig, &predicted, &predicted, t_us, config,
    );
}

/// Takes the depth of `frame` (exposed at `t_us`) as the new `D_0`, every point static for now: a sphere
/// reaching past the ROI around the object at both `then` and `now`, which lie apart when the frame is used
/// later than it was exposed.
#[allow(clippy::too_many_arguments)]
pub(super) fn register_between(
    model: &ObjectModel,
    state: &mut ObjectState,
    frame: &DepthFrame,
    rig: &DepthRig,
    then: &Isometry3<f64>,
    now: &Isometry3<f64>,
    t_us: i64,
    config: &TrackerConfig,
) {
    let c_then = model.center_at(then);
    let c_now = model.center_at(now);
    let c = Point3::from((c_then.coords + c_now.coords) * 0.5);
    let radius = 0.6 * config.roi.roi_scale * model.diameter + 0.08 + 0.5 * (c_now - c_then).norm();
    state.carried.register(frame, rig, &c, radius, t_us);
}

/// At a fresh depth frame, keeps the previous frame's surfaces around the object that moved since (the carried
/// depth, before the new frame replaces it), for the safety net's motion check
/// ([`super::depth_check::motion_agreement_at`]); forgets them when there is no previous frame to compare with
/// or the check is off.
pub(super) fn capture_neighbourhood(
    state: &mut ObjectState,
    frame: &DepthFrame,
    rig: &DepthRig,
    config: &TrackerConfig,
) {
    match state.anchor {
        Some((t_anchor, anchor))
            if config.safety_net.depth_fallback_motion_margin >= 0.0
                && state.carried.exposure_us() == Some(t_anchor) =>
        {
            state
                .neighbourhood
                .capture(&state.carried, &anchor, frame, rig);
        }
        _ => state.neighbourhood.clear(),
    }
}
