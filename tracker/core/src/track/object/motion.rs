//! The object's motion between estimates: the velocity an estimate updates, where a depth frame's estimate is
//! carried to by the motion between depth frames, and which way the object moves in the image.

use super::inputs::TickInputs;
use super::model::ObjectModel;
use super::state::{ObjectState, normalise};
use crate::refine::apply_step;
use crate::track::config::TrackerConfig;
use crate::track::estimate::TrackingState;
use nalgebra::{Isometry3, Vector3, Vector6};

/// The previous depth frame's estimate carried on to `t_us` at the motion between the last two depth frames'
/// estimates (centre speed and angular speed capped like the velocity's, no spin about a continuous symmetry
/// axis): a start for the safety net that the events since the previous depth frame cannot have moved. `None`
/// before two depth frames, and after a re-detection until two more.
pub(super) fn anchored_extrapolation(
    model: &ObjectModel,
    state: &ObjectState,
    t_us: i64,
    config: &TrackerConfig,
) -> Option<Isometry3<f64>> {
    let (t1, p1) = state.anchor?;
    let (t0, p0) = state.anchor_before?;
    let between = (t1 - t0) as f64 * 1e-6;
    if between <= 0.0 {
        return None;
    }
    let mut motion = model.observable_motion(&p0, &p1, between);
    cap_motion(&mut motion, config);
    let span = (t_us - t1).max(0) as f64 * 1e-6;
    Some(apply_step(&p1, &model.center_obj, &(motion * span)))
}

/// Scales a motion (centre m/s, angular rad/s) down to the speeds the motion model accepts
/// ([`crate::track::MotionConfig::max_speed`], [`crate::track::MotionConfig::max_angular_speed`]), keeping its directions.
pub(super) fn cap_motion(v: &mut Vector6<f64>, config: &TrackerConfig) {
    let lin = v.fixed_rows::<3>(0).norm();
    if lin > config.motion.max_speed {
        v.fixed_rows_mut::<3>(0)
            .scale_mut(config.motion.max_speed / lin);
    }
    let ang = v.fixed_rows::<3>(3).norm();
    if ang > config.motion.max_angular_speed {
        v.fixed_rows_mut::<3>(3)
            .scale_mut(config.motion.max_angular_speed / ang);
    }
}

/// Records `pose` as the estimate at this tick, after [`super::assess::assess`] set the state: the velocity,
/// the depth anchors at a fresh depth frame, and the pose history.
pub(super) fn record_estimate(
    model: &ObjectModel,
    state: &mut ObjectState,
    inputs: &TickInputs<'_>,
    pose: Isometry3<f64>,
    fresh_depth: bool,
    config: &TrackerConfig,
) {
    // Velocity: at a fresh depth frame from the motion since the previous one (anchored on depth, so a drift
    // the motion model itself introduced between frames is not fed back); otherwise from the last tick,
    // weighted less.
    let (reference, span, a) = match (fresh_depth, state.anchor) {
        (true, Some((t0, p0))) if inputs.t_us > t0 => (
            p0,
            (inputs.t_us - t0) as f64 * 1e-6,
            config.motion.velocity_smoothing_depth,
        ),
        _ => match inputs
            .velocity_since_us
            .and_then(|t0| Some((t0, state.history.at(t0)?)))
        {
            Some((t0, p0)) if inputs.t_us > t0 => (
                p0,
                (inputs.t_us - t0) as f64 * 1e-6,
                config.motion.velocity_smoothing,
            ),
            // Since the previous estimate: none at the first pose's own tick, whose refinement corrects the
            // first pose rather than measuring a motion.
            _ => (
                state.pose,
                (inputs.t_us - state.t_us) as f64 * 1e-6,
                config.motion.velocity_smoothing,
            ),
        },
    };
    if fresh_depth {
        state.anchor_before = state.anchor;
        // A late frame anchors the estimate carried back to its exposure, by the motion its points were
        // carried by, so that anchors stay at exposures (the next frame's motion check compares frames).
        let anchor = match state.late_motion {
            Some((exposed_us, motion)) => (exposed_us, normalise(motion.inverse() * pose)),
            None => (inputs.t_us, pose),
        };
        state.anchor = Some(anchor);
        state.ranges.push(
            anchor.0,
            model.center_at(&anchor.1).coords.norm(),
            config.motion.range_acceleration_share,
            config.motion.max_speed,
        );
    }
    if inputs.inner {
        // Steps between ticks measure no velocity (see `TickInputs::velocity_since_us`).
    } else if span > 0.0 && state.tracking != TrackingState::Lost {
        let measured = model.observable_motion(&reference, &pose, span);
        let weight_so_far = if config.motion.velocity_start_corrected {
            state.velocity_weight
        } else {
            1.0
        };
        let (mut v, weight) =
            smooth_velocity(&state.velocity, weight_so_far, &measured, a.clamp(0.0, 1.0));
        cap_motion(&mut v, config);
        state.velocity = v;
        state.velocity_weight = weight;
    } else if state.tracking == TrackingState::Lost {
        state.velocity = Vector6::zeros();
        state.velocity_weight = 0.0;
    }
    if fresh_depth && let Some((exposed_us, _)) = state.late_motion {
        // What the late frame changed at this tick, it changes since its exposure.
        state
            .history
            .correct_since(exposed_us, &normalise(state.predicted.inverse() * pose));
    }
    state.previous = Some((state.t_us, state.pose));
    state.pose = normalise(pose);
    state.t_us = inputs.t_us;
    state.history.push(state.t_us, state.pose);
}

/// The smoothed velocity after `measured` (centre m/s, angular rad/s) with smoothing weight `a` in `[0, 1]`,
/// and its new [`ObjectState::velocity_weight`], from `velocity` whose measured share is `weight`. An exponential
/// average corrected for its start: the zero a velocity starts from (a new or re-detected object) is no
/// measurement, so each measurement counts by its weight relative to all weight measured so far; the first one
/// after a reset sets the velocity outright, and once the weight reaches 1 this is the plain average with `a`.
fn smooth_velocity(
    velocity: &Vector6<f64>,
    weight: f64,
    measured: &Vector6<f64>,
    a: f64,
) -> (Vector6<f64>, f64) {
    if weight >= 1.0 {
        return (a * measured + (1.0 - a) * velocity, 1.0);
    }
    let total = a + (1.0 - a) * weight;
    if total <= 0.0 {
        return (*velocity, weight);
    }
    let share = a / total;
    (share * measured + (1.0 - share) * velocity, total)
}

/// Unit image direction (full-image pixels) the centre at `predicted` moves in at the estimated velocity,
/// when it moves at least 2 px per tick and at least as far as turning moves the outline's ends;
/// `None` otherwise, and before the third depth frame (the motion is not measured yet).
pub(super) fn image_motion_direction(
    model: &ObjectModel,
    state: &ObjectState,
    predicted: &Isometry3<f64>,
    inputs: &TickInputs<'_>,
) -> Option<[f64; 2]> {
    if state.depth_frames_used < 2 {
        return None;
    }
    let c = model.center_at(predicted);
    let v = Vector3::new(state.velocity[0], state.velocity[1], state.velocity[2]);
    let a = inputs.camera.project(&c)?;
    let b = inputs.camera.project(&(c + v * inputs.dt_s))?;
    let d = [b.x - a.x, b.y - a.y];
    let n = d[0].hypot(d[1]);
    // Turning moves the outline's ends in other directions than the centre: only a mostly sliding outline
    // has one direction of motion.
    let w = Vector3::new(state.velocity[3], state.velocity[4], state.velocity[5]).norm();
    let turning = inputs.camera.fx * w * model.diameter * 0.5 / c.z.max(0.05) * inputs.dt_s;
    (n >= 2.0 && n >= turning).then(|| [d[0] / n, d[1] / n])
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Point3, Translation3, UnitQuaternion, Vector3};
    use scene::mesh::Symmetry;

    #[test]
    fn velocity_keeps_no_spin_about_a_continuous_symmetry_axis() {
        let half = Vector3::new(0.01, 0.01, 0.06);
        let tilted = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 0.6),
            UnitQuaternion::from_euler_angles(0.4, -0.3, 0.2),
        );
        let marker = [Symmetry::Continuous {
            axis: Vector3::z_axis(),
            offset: Point3::origin(),
        }];
        let symmetric = ObjectModel::new(1, 0.12, -half, half, &marker);
        let plain = ObjectModel::new(1, 0.12, -half, half, &[]);
        let turned = |axis: Vector3<f64>, angle: f64| {
            let mut p = tilted;
            p.rotation *= UnitQuaternion::from_scaled_axis(axis * angle);
            p.translation.vector.x += 0.01;
            p
        };
        let span = 0.1;
        // A turn about the object's own axis (its symmetry): only the translation is motion.
        let spun = turned(Vector3::z(), 0.3);
        let w = symmetric.observable_motion(&tilted, &spun, span);
        assert!((w[0] - 0.1).abs() < 1e-9, "{w}");
        assert!(w.fixed_rows::<3>(3).norm() < 1e-9, "{w}");
        let w = plain.observable_motion(&tilted, &spun, span);
        assert!((w.fixed_rows::<3>(3).norm() - 3.0).abs() < 1e-9, "{w}");
        // A turn across the axis is seen in the shape and kept.
        let tipped = turned(Vector3::x(), 0.3);
        let w = symmetric.observable_motion(&tilted, &tipped, span);
        assert!((w.fixed_rows::<3>(3).norm() - 3.0).abs() < 1e-9, "{w}");
    }

    #[test]
    fn anchored_start_carries_the_motion_between_the_last_two_depth_frames() {
        let mut config = TrackerConfig::default();
        let at = |x: f64, turn: f64| {
            Isometry3::from_parts(
                Translation3::new(x, 0.0, 0.6),
                UnitQuaternion::from_scaled_axis(Vector3::y() * turn),
            )
        };
        let half = Vector3::new(0.05, 0.05, 0.05);
        let model = ObjectModel::new(1, 0.1, -half, half, &[]);
        let mut track = ObjectState::new(at(0.0, 0.0), 0, 0);
        // One depth frame is no motion yet.
        track.anchor = Some((0, at(0.0, 0.0)));
        assert!(anchored_extrapolation(&model, &track, 66_666, &config).is_none());
        // 2 cm and 0.1 rad between frames 33.3 ms apart; the velocity the events updated since says otherwise and
        // is ignored.
        track.anchor_before = track.anchor;
        track.anchor = Some((33_333, at(0.02, 0.1)));
        track.velocity = Vector6::new(-5.0, 1.0, 0.0, 0.0, 9.0, 0.0);
        let start = anchored_extrapolation(&model, &track, 66_666, &config).unwrap();
        assert!(
            (start.translation.vector - Vector3::new(0.04, 0.0, 0.6)).norm() < 1e-4,
            "{start:?}"
        );
        assert!(
            (start.rotation.angle_to(&at(0.0, 0.2).rotation)).abs() < 1e-4,
            "{start:?}"
        );
        // At the anchor's own time the start is the anchor.
        let same = anchored_extrapolation(&model, &track, 33_333, &config).unwrap();
        assert!((same.translation.vector - Vector3::new(0.02, 0.0, 0.6)).norm() < 1e-9);
        // The speed is capped like the velocity's: at 0.3 m/s the 33.3 ms carry 1 cm, not 2.
        config.motion.max_speed = 0.3;
        let capped = anchored_extrapolation(&model, &track, 66_666, &config).unwrap();
        assert!((capped.translation.x - 0.03).abs() < 1e-4, "{capped:?}");
        // A re-detection forgets both anchors.
        track.relocate(at(0.1, 0.0));
        assert!(anchored_extrapolation(&model, &track, 66_666, &config).is_none());
    }

    #[test]
    fn a_started_velocity_is_the_mean_of_its_measurements_not_pulled_to_zero() {
        let m = Vector6::new(2.0, 0.0, -1.0, 0.0, 5.0, 0.0);
        let (mut v, mut w) = (Vector6::zeros(), 0.0);
        // The first measurement after a reset sets the velocity; equal ones keep it (a plain average from zero
        // would give 0.2, 0.36, 0.49 of it).
        for _ in 0..4 {
            (v, w) = smooth_velocity(&v, w, &m, 0.2);
            assert!((v - m).norm() < 1e-12, "{v}");
        }
        assert!((w - (1.0 - 0.8f64.powi(4))).abs() < 1e-12, "{w}");
        // Once the weight is whole, a new measurement counts by `a` alone.
        let (v, w) = smooth_velocity(&m, 1.0, &Vector6::zeros(), 0.2);
        assert!(
            (v - 0.8 * m).norm() < 1e-12 && (w - 1.0).abs() < 1e-12,
            "{v} {w}"
        );
        // Of two measurements after a reset, the first counts 0.16 / 0.36 and the second 0.2 / 0.36.
        let (v1, w1) = smooth_velocity(&Vector6::zeros(), 0.0, &m, 0.2);
        let (v2, _) = smooth_velocity(&v1, w1, &Vector6::zeros(), 0.2);
        assert!((v2 - m * (0.16 / 0.36)).norm() < 1e-12, "{v2}");
        // A weight of 0 and no smoothing leaves the velocity as it is.
        let (v, w) = smooth_velocity(&m, 0.0, &Vector6::zeros(), 0.0);
        assert!(v == m && w == 0.0);
    }
}
