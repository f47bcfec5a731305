//! A depth frame that arrived after its own tick: registered where the object was estimated at its exposure,
//! checked there by the depth safety net, and its object part carried to the tick it is used at. A late frame
//! tells where the object was, not how it moved since: the events carry that across the image, and the depth
//! frames' own motion along the line of sight, where events show little.

use super::carried_depth::register_between;
use super::depth_check::{
    fallback_starts, motion_agreement_at_exposure, refine_on_depth_in, seen_agreement,
};
use super::inputs::TickInputs;
use super::model::ObjectModel;
use super::motion::cap_motion;
use super::scratch::TickScratch;
use super::state::{ObjectState, in_front_or};
use crate::recon::{DepthImage, DepthRig};
use crate::refine::{DepthTermStats, ModelView};
use crate::track::config::TrackerConfig;
use crate::track::fallback_check::{DepthFallbackCheck, FALLBACK_STARTS, FallbackCandidate};
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Point3, Translation3};
use scene::geometry::{PinholeCamera, Roi};

/// Margin around the object's box, metres, within which a late frame's points count as the object's when they are
/// carried to the tick (split at the pose chosen at the exposure).
const LATE_SPLIT_MARGIN_M: f64 = 0.01;

/// What the depth said about a pose at a late frame's exposure ([`settle_at_exposure`]).
#[derive(Debug, Clone, Copy)]
struct Settled {
    /// The pose refined on the frame's depth alone, or the start if that agreed less.
    pose: Isometry3<f64>,
    /// The depth term's counts at `pose`.
    stats: DepthTermStats,
}

/// Registers `frame`, exposed at `exposed_us` when the object was estimated at `then`, as the new `D_0`: a
/// sphere around the object then and at this tick's prediction, every point static for now. The refinement
/// checks and carries it ([`carry_late_depth`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn register_late_depth(
    model: &ObjectModel,
    state: &mut ObjectState,
    frame: &DepthFrame,
    rig: &DepthRig,
    exposed_us: i64,
    then: &Isometry3<f64>,
    config: &TrackerConfig,
) {
    let now = state.predicted;
    register_between(model, state, frame, rig, then, &now, exposed_us, config);
    state.late_frame = Some((exposed_us, *then));
}

/// For a frame registered by [`register_late_depth`]: chooses the pose at the exposure ([`check_at_exposure`]),
/// carries the points in the object's box there to the pose the refinement starts from, and renders the result
/// into `depth_now` in this tick's ROI. That start is the prediction moved by what the check changed at the
/// exposure, at the range the depth frames' motion reaches ([`ranged_by_depth_frames`]). Returns the start and
/// the depth term's counts at the exposure (`None` when the object was out of view then), part of the frame's
/// evidence for quality: at the tick its object part agrees with the start by construction.
pub(super) fn carry_late_depth(
    model: &ObjectModel,
    state: &mut ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    roi_camera: &PinholeCamera,
    use_events: bool,
    config: &TrackerConfig,
) -> (Isometry3<f64>, Option<DepthTermStats>) {
    let Some((exposed_us, then)) = state.late_frame.take() else {
        return (state.predicted, None);
    };
    let checked = check_at_exposure(
        model, state, scratch, &then, exposed_us, inputs, use_events, config,
    );
    let at_exposure = checked.map_or(then, |s| s.pose);
    // The prediction moved by what the check changed at the exposure, in the object frame; along the line of
    // sight, where the events see little, carried on from the exposure by the depth frames' own motion.
    let start = state.predicted * then.inverse() * at_exposure;
    let start = ranged_by_depth_frames(
        model,
        state,
        &at_exposure,
        exposed_us,
        &start,
        inputs.t_us,
        config,
    )
    .unwrap_or(start);
    let start = in_front_or(start, state.predicted);
    let motion = start * at_exposure.inverse();
    state.carried.carry_object_part(
        &at_exposure,
        &motion,
        &model.aabb_min,
        &model.aabb_max,
        LATE_SPLIT_MARGIN_M,
    );
    state.late_motion = Some((exposed_us, motion));
    state
        .carried
        .render(&state.predicted, roi_camera, &mut scratch.depth_now);
    (start, checked.map(|s| s.stats))
}

/// `start`, a pose at the tick `tick_us`, moved along the line of sight through its centre to the range the
/// depth frames' own motion carries the object to: from the previous frame's estimate (`anchor`) to
/// `at_exposure`, the estimate at this frame's exposure, then on at that speed (capped like the velocity's)
/// to the tick. Events show motion across the image, hardly any along the line of sight, so over a late
/// frame's age the events' estimate of the range drifts where the depth frames' does not. `None` without a
/// previous frame's estimate within 0.1 s before the exposure.
fn ranged_by_depth_frames(
    model: &ObjectModel,
    state: &ObjectState,
    at_exposure: &Isometry3<f64>,
    exposed_us: i64,
    start: &Isometry3<f64>,
    tick_us: i64,
    config: &TrackerConfig,
) -> Option<Isometry3<f64>> {
    let (t0, p0) = state.anchor?;
    let between = (exposed_us - t0) as f64 * 1e-6;
    if !(between > 0.0 && between <= 0.1) {
        return None;
    }
    let mut motion = model.observable_motion(&p0, at_exposure, between);
    cap_motion(&mut motion, config);
    let span = (tick_us - exposed_us).max(0) as f64 * 1e-6;
    let ranged = model.center_at(at_exposure) + motion.fixed_rows::<3>(0) * span;
    let c = model.center_at(start);
    let sight = c.coords.try_normalize(1e-9)?;
    let shift = sight * (ranged - c).dot(&sight);
    Some(Translation3::from(shift) * start)
}

/// The depth safety net at a late frame's exposure, where the frame shows the object: the estimate then
/// (`then`, from the pose history) and, with events in use, the safety net's depth-only candidates from the
/// depth frame before, each refined on the frame's depth alone; the rule of [`DepthFallbackCheck::replacement`]
/// chooses (with no event verdict: the events at the exposure are gone). Recorded in `state.fallback_check` at
/// the exposure. `None` when the object was out of view at `then`.
///
/// At the tick the frame is used at, the check could not tell: the points carried there agree with the motion
/// the events estimated, right or wrong.
#[allow(clippy::too_many_arguments)]
fn check_at_exposure(
    model: &ObjectModel,
    state: &mut ObjectState,
    scratch: &mut TickScratch,
    then: &Isometry3<f64>,
    exposed_us: i64,
    inputs: &TickInputs<'_>,
    use_events: bool,
    config: &TrackerConfig,
) -> Option<Settled> {
    let anchor = state.anchor.filter(|&(t, _)| {
        t < exposed_us && use_events && config.safety_net.depth_fallback_margin >= 0.0
    });
    let starts = anchor.map(|(t_anchor, anchor)| {
        fallback_starts(model, state, t_anchor, &anchor, exposed_us, config)
    });
    // One ROI around the estimate and every start: the frame's points are rendered once.
    let camera = roi_covering(
        model,
        state,
        then,
        starts.iter().flatten().flatten().map(|s| &s.1),
        inputs,
        config,
    )?;
    state.carried.render(then, &camera, &mut scratch.late_depth);
    let (view, image) = (&scratch.view, &scratch.late_depth);
    let estimate = settle_at_exposure(model, view, then, &camera, image, config);
    let Some(starts) = starts else {
        return Some(estimate);
    };
    let mut check = DepthFallbackCheck {
        object: usize::from(model.label) - 1,
        t_us: exposed_us,
        tick_us: inputs.t_us,
        estimate: estimate.pose,
        estimate_agreeing: seen_agreement(&estimate.stats),
        estimate_motion_agreeing: motion_agreement_at_exposure(
            state,
            &estimate.pose,
            inputs,
            config,
        ),
        estimate_event_support: None,
        candidates: [None; FALLBACK_STARTS],
        replaced_by: None,
    };
    let mut settled = [None; FALLBACK_STARTS];
    for (k, start) in starts.into_iter().enumerate() {
        let Some((kind, from)) = start else { continue };
        let s = settle_at_exposure(model, view, &from, &camera, image, config);
        check.candidates[k] = Some(FallbackCandidate {
            start: kind,
            pose: s.pose,
            agreeing: seen_agreement(&s.stats),
            motion_agreeing: motion_agreement_at_exposure(state, &s.pose, inputs, config),
            event_support: None,
        });
        settled[k] = Some(s);
    }
    check.replaced_by = check.replacement(&config.safety_net.fallback_rule());
    state.fallback_check = Some(check);
    match check.replaced_by.and_then(|k| settled[k]) {
        Some(s) => {
            state.fallbacks += 1;
            Some(s)
        }
        None => Some(estimate),
    }
}

/// The camera of the ROI around the object at `then` (as at a tick), widened to take in the object at each of
/// `others` when their centres lie more than a tenth of its diameter apart; `None` when out of view.
fn roi_covering<'a>(
    model: &ObjectModel,
    state: &ObjectState,
    then: &Isometry3<f64>,
    others: impl Iterator<Item = &'a Isometry3<f64>>,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
) -> Option<PinholeCamera> {
    let c0 = model.center_at(then);
    let (mut lo, mut hi) = (c0.coords, c0.coords);
    for p in others {
        let c = model.center_at(p).coords;
        if c.iter().all(|v| v.is_finite()) {
            lo = lo.inf(&c);
            hi = hi.sup(&c);
        }
    }
    let gap = (hi - lo).norm();
    let roi = if gap > 0.1 * model.diameter {
        let c = Point3::from((lo + hi) * 0.5);
        if c.z <= 1e-3 {
            return None;
        }
        let scale = config.roi.roi_scale + gap / model.diameter;
        Roi::around_object(
            inputs.camera,
            &c,
            model.diameter,
            scale,
            config.roi.roi_size,
        )
        .ok()?
    } else {
        state.roi_at(model, then, inputs.camera, config, inputs.t_us, false)?
    };
    Some(inputs.camera.crop(&roi))
}

/// `start`, a pose at the late frame's exposure, refined on the frame's depth alone (`image`, rendered in
/// `camera`), with the model view of this tick's render placed there; `start` itself if the depth agrees no
/// better after.
fn settle_at_exposure(
    model: &ObjectModel,
    view: &ModelView,
    start: &Isometry3<f64>,
    camera: &PinholeCamera,
    image: &DepthImage,
    config: &TrackerConfig,
) -> Settled {
    let (refined, stats) = refine_on_depth_in(model, view, *start, camera, image, config);
    let before = config.depth_term.stats(view, start, camera, image);
    if seen_agreement(&stats) >= seen_agreement(&before) {
        Settled {
            pose: refined,
            stats,
        }
    } else {
        Settled {
            pose: *start,
            stats: before,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{UnitQuaternion, Vector3};

    #[test]
    fn a_late_start_takes_its_range_from_the_depth_frames_and_its_image_place_from_the_events() {
        let config = TrackerConfig::default();
        let at = |x: f64, z: f64| {
            Isometry3::from_parts(Translation3::new(x, 0.0, z), UnitQuaternion::identity())
        };
        let half = Vector3::new(0.05, 0.05, 0.05);
        let model = ObjectModel::new(1, 0.1, -half, half, &[]);
        let mut state = ObjectState::new(at(0.0, 0.6), 0, 0);
        // Without an estimate at the frame before there is no motion between frames to range by.
        let start = at(0.03, 0.6);
        assert!(
            ranged_by_depth_frames(
                &model,
                &state,
                &at(0.0, 0.62),
                33_333,
                &start,
                53_333,
                &config
            )
            .is_none()
        );
        // The frames say the object moves away at 0.6 m/s; the events' start kept the range it had.
        state.anchor = Some((0, at(0.0, 0.6)));
        let ranged = ranged_by_depth_frames(
            &model,
            &state,
            &at(0.0, 0.62),
            33_333,
            &start,
            53_333,
            &config,
        )
        .expect("ranged");
        let c = ranged.translation.vector;
        // Where the events put it in the image is kept: the same line of sight.
        assert!((c.x / c.z - 0.03 / 0.6).abs() < 1e-12, "{c}");
        assert!(c.y.abs() < 1e-12);
        // Along it, the range the frames' motion reaches at the tick: 0.62 + 0.6 m/s x 20 ms, projected.
        let sight = Vector3::new(0.03, 0.0, 0.6).normalize();
        let expected = Vector3::new(0.0, 0.0, 0.62 + 0.02 / 0.033_333 * 0.02).dot(&sight);
        assert!((c.dot(&sight) - expected).abs() < 1e-9, "{c}");
        assert_eq!(ranged.rotation, start.rotation);
        // An estimate more than 0.1 s before the exposure is too old to say how it moves now.
        state.anchor = Some((-80_000, at(0.0, 0.6)));
        assert!(
            ranged_by_depth_frames(
                &model,
                &state,
                &at(0.0, 0.62),
                33_333,
                &start,
                53_333,
                &config
            )
            .is_none()
        );
    }
}
