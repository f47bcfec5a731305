//! The depth safety net at a fresh depth frame: the depth-only refinement from the previous depth frame's pose
//! (what `depth30` would report), and from that pose carried on, against the event-driven estimate. If events led
//! the estimate astray, the depth image says so: the hypothesis more of the model points in view agree with is
//! kept, unless the surroundings contradict its motion ([`DepthFallbackCheck::replacement`]).

use super::depth_check::{
    depth_stats_at, fallback_starts, motion_agreement_at, refine_on_depth, seen_agreement,
};
use super::inputs::TickInputs;
use super::model::ObjectModel;
use super::scratch::TickScratch;
use super::state::ObjectState;
use crate::refine::DepthTermStats;
use crate::track::config::TrackerConfig;
use crate::track::fallback_check::{DepthFallbackCheck, FALLBACK_STARTS, FallbackCandidate};
use nalgebra::Isometry3;
use scene::geometry::PinholeCamera;

/// What the safety net decided: the pose kept, the depth term's counts there and its event support.
#[derive(Debug, Clone, Copy)]
pub(super) struct Checked {
    /// The estimate, or the candidate that replaced it.
    pub pose: Isometry3<f64>,
    /// The depth term's counts at `pose`.
    pub depth_stats: DepthTermStats,
    /// The event support of `pose`'s outline, as measured for the check.
    pub event_support: Option<f64>,
}

/// Checks `estimate` at a fresh depth frame against the depth-only candidates from the previous depth frame's
/// estimate `anchor` (exposed at `t_anchor`): records the check in `state.fallback_check`, counts a replacement in
/// `state.fallbacks`, and returns what was kept.
#[allow(clippy::too_many_arguments)]
pub(super) fn check(
    model: &ObjectModel,
    state: &mut ObjectState,
    scratch: &TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    roi_camera: &PinholeCamera,
    estimate: Isometry3<f64>,
    (t_anchor, anchor): (i64, Isometry3<f64>),
) -> Checked {
    let starts = fallback_starts(model, state, t_anchor, &anchor, inputs.t_us, config);
    let main_stats = depth_stats_at(scratch, &estimate, roi_camera, config);
    let mut check = DepthFallbackCheck {
        object: usize::from(model.label) - 1,
        t_us: inputs.t_us,
        tick_us: inputs.t_us,
        estimate,
        estimate_agreeing: seen_agreement(&main_stats),
        estimate_motion_agreeing: motion_agreement_at(state, &estimate, inputs, config),
        estimate_event_support: scratch.edges.contour_support(
            &scratch.view,
            &estimate,
            inputs.camera,
        ),
        candidates: [None; FALLBACK_STARTS],
        replaced_by: None,
    };
    let mut candidate_stats = [None; FALLBACK_STARTS];
    for (k, start) in starts.into_iter().enumerate() {
        let Some((kind, from)) = start else { continue };
        let (refined, stats) = refine_on_depth(model, scratch, from, roi_camera, config);
        check.candidates[k] = Some(FallbackCandidate {
            start: kind,
            pose: refined,
            agreeing: seen_agreement(&stats),
            motion_agreeing: motion_agreement_at(state, &refined, inputs, config),
            event_support: scratch
                .edges
                .contour_support(&scratch.view, &refined, inputs.camera),
        });
        candidate_stats[k] = Some(stats);
    }
    check.replaced_by = check.replacement(&config.safety_net.fallback_rule());
    let replacement = check
        .replaced_by
        .and_then(|k| Some((check.candidates[k]?, candidate_stats[k]?)));
    state.fallback_check = Some(check);
    match replacement {
        Some((candidate, stats)) => {
            state.fallbacks += 1;
            Checked {
                pose: candidate.pose,
                depth_stats: stats,
                event_support: candidate.event_support,
            }
        }
        None => Checked {
            pose: estimate,
            depth_stats: main_stats,
            event_support: check.estimate_event_support,
        },
    }
}
