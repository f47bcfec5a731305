//! The assess phase: what an estimate is worth (quality from the depth agreement, the visible fraction and the
//! event support), the tracking state that follows from it, and the estimate recorded.

use super::inputs::TickInputs;
use super::model::ObjectModel;
use super::motion::record_estimate;
use super::state::{ObjectState, visibility_factor};
use crate::refine::DepthTermStats;
use crate::track::config::TrackerConfig;
use nalgebra::Isometry3;

/// Records `pose` as this tick's estimate with its quality and state ([`assess`]), then its velocity, depth
/// anchors and history ([`record_estimate`]). `in_view`: the object had an ROI and showed pixels in its render.
#[allow(clippy::too_many_arguments)]
pub(super) fn finish(
    model: &ObjectModel,
    state: &mut ObjectState,
    in_view: bool,
    inputs: &TickInputs<'_>,
    pose: Isometry3<f64>,
    fresh_depth: Option<DepthTermStats>,
    event_support: Option<f64>,
    config: &TrackerConfig,
) {
    if !inputs.inner {
        assess(state, in_view, fresh_depth, event_support, config);
    }
    record_estimate(model, state, inputs, pose, fresh_depth.is_some(), config);
}

/// Quality and state of this tick's estimate. Quality evidence: depth agreement and visibility at the last
/// exposure (`fresh_depth`; both held until the next one), event support of the outline.
pub(super) fn assess(
    state: &mut ObjectState,
    in_view: bool,
    fresh_depth: Option<DepthTermStats>,
    event_support: Option<f64>,
    config: &TrackerConfig,
) {
    if let Some(s) = fresh_depth {
        let used = s.measured.max(1) as f64;
        state.depth_fit = s.inliers as f64 / used;
        state.visibility = (s.measured as f64 / s.points.max(1) as f64).min(1.0);
    }
    let visibility = state.visibility;
    let support = event_support.unwrap_or(1.0);
    let quality = if in_view {
        state.depth_fit * visibility_factor(visibility) * (0.6 + 0.4 * support)
    } else {
        0.0
    };
    state.quality = quality.clamp(0.0, 1.0) as f32;
    let q = config.quality;
    if state.quality < q.lost_below {
        state.low_ticks += 1;
    } else {
        state.low_ticks = 0;
    }
    state.recent_quality.push(state.quality);
    state.tracking = q.state(
        state.quality,
        state.low_ticks,
        state.recent_quality.full_mean(),
    );
    state.reported.update(state.tracking, q.recover_ticks);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::estimate::TrackingState;

    /// Assesses one tick whose estimate has quality `q` (depth agreement `q`, fully visible, full event support).
    fn tick(state: &mut ObjectState, q: f64, config: &TrackerConfig) -> TrackingState {
        state.depth_fit = q;
        state.visibility = 1.0;
        assess(state, true, None, Some(1.0), config);
        state.tracking
    }

    fn state(config: &TrackerConfig) -> ObjectState {
        let pose = Isometry3::translation(0.0, 0.0, 0.6);
        ObjectState::new(pose, 0, config.quality.lost_mean_ticks as usize)
    }

    #[test]
    fn moving_the_object_to_another_place_does_not_restart_the_way_to_lost() {
        let config = TrackerConfig::default();
        let q = config.quality;
        let mut s = state(&config);
        for _ in 1..q.lost_after_ticks {
            assert_ne!(tick(&mut s, 0.1, &config), TrackingState::Lost);
        }
        s.relocate(Isometry3::translation(0.1, 0.0, 0.6));
        assert_eq!(tick(&mut s, 0.1, &config), TrackingState::Lost);
    }
}
