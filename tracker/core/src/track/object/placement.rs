//! Where re-detection puts an object: the place it found on a depth frame, carried to this tick, with that frame
//! as the object's carried depth.

use super::carried_depth::register_between;
use super::model::ObjectModel;
use super::state::{ObjectState, in_front_or, normalise};
use crate::recon::DepthRig;
use crate::track::config::TrackerConfig;
use drivers::recording::DepthFrame;
use nalgebra::Isometry3;

/// Moves the object to where re-detection found it on `frame`, exposed at `found_us`: `found` there, carried
/// to this tick by the motion estimated since the exposure (none when that is this tick). The
/// motion estimate and the depth anchor, which belong to the place it was lost at, are dropped; the next
/// refinement starts there. The pose history restarts at the exposure, so that the next frame, late too,
/// finds an estimate at its own exposure, and the frame becomes the depth `D_0` carried on.
pub(super) fn relocate_on(
    model: &ObjectModel,
    state: &mut ObjectState,
    frame: &DepthFrame,
    rig: &DepthRig,
    found: Isometry3<f64>,
    found_us: i64,
    config: &TrackerConfig,
) {
    let motion = state
        .history
        .at(found_us)
        .filter(|_| found_us < state.t_us)
        .map(|then| state.predicted * then.inverse());
    let now = in_front_or(motion.map_or(found, |m| m * found), found);
    state.relocate(now);
    state.history.push(found_us, normalise(found));
    let now = state.predicted;
    register_between(model, state, frame, rig, &found, &now, found_us, config);
    if let Some(m) = motion {
        state
            .carried
            .carry_object_part(&found, &m, &model.aabb_min, &model.aabb_max, 0.01);
    }
    state
        .carried
        .attach_to_object(&state.predicted, &model.aabb_min, &model.aabb_max, 0.01);
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion, Vector3, Vector6};
    use scene::geometry::PinholeCamera;

    fn at_x(x: f64) -> Isometry3<f64> {
        Isometry3::from_parts(Translation3::new(x, 0.0, 0.5), UnitQuaternion::identity())
    }

    /// A 100 x 100 px depth camera at the event camera, and its frame of a 20 x 20 px square (the object, 10 cm
    /// wide) at 0.5 m straight ahead on a wall at 1 m.
    fn square_ahead() -> (DepthRig, DepthFrame) {
        let cam = PinholeCamera::new(100.0, 100.0, 49.5, 49.5, 100, 100).unwrap();
        let rig = DepthRig {
            camera: cam,
            event_from_depth: Isometry3::identity(),
        };
        let mut depth_m = vec![1.0; 100 * 100];
        for v in 40..60 {
            for u in 40..60 {
                depth_m[v * 100 + u] = 0.5;
            }
        }
        let frame = DepthFrame {
            index: 3,
            width: 100,
            height: 100,
            depth_m,
        };
        (rig, frame)
    }

    #[test]
    fn a_place_found_on_a_late_frame_is_carried_to_the_tick_and_the_history_restarts_at_the_exposure()
     {
        let config = TrackerConfig::default();
        let (rig, frame) = square_ahead();
        let half = Vector3::new(0.06, 0.06, 0.01);
        // The estimate wandered off to the right: 10 cm at 10 ms, 14 cm at 40 ms (its latest), predicted 16 cm at
        // this tick. Re-detection finds the object straight ahead on the frame exposed at 20 ms.
        let model = ObjectModel::new(1, 0.12, -half, half, &[]);
        let mut track = ObjectState::new(at_x(0.1), 10_000, 0);
        track.history.push(10_000, at_x(0.1));
        track.history.push(40_000, at_x(0.14));
        track.t_us = 40_000;
        track.predicted = at_x(0.16);
        track.velocity = Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        relocate_on(&model, &mut track, &frame, &rig, at_x(0.0), 20_000, &config);
        // Carried on by the estimate's motion since the exposure (from 11.3 cm then to 16 cm now).
        let moved = 0.16 - (0.1 + 0.04 / 3.0);
        assert!(
            (track.pose.translation.x - moved).abs() < 1e-9,
            "{:?}",
            track.pose
        );
        assert_eq!(track.predicted, track.pose);
        assert_eq!(track.velocity, Vector6::zeros());
        assert_eq!(track.redetections, 1);
        // The estimates restart at the exposure: a later frame finds one there, none before it.
        assert_eq!(track.history.at(20_000), Some(at_x(0.0)));
        assert!(track.history.at(19_999).is_none());
        // The square's points move with the object: in the object frame they lie on its face, 10 cm wide.
        let points = track.carried.object_points();
        assert!(points.len() > 50, "{} object points", points.len());
        assert!(
            points
                .iter()
                .all(|p| p.x.abs() <= 0.06 && p.y.abs() <= 0.06 && p.z.abs() < 1e-3),
            "{points:?}"
        );

        // Found on the frame of this very tick: put there as found.
        let mut track = ObjectState::new(at_x(0.1), 10_000, 0);
        track.history.push(10_000, at_x(0.1));
        track.predicted = at_x(0.12);
        relocate_on(&model, &mut track, &frame, &rig, at_x(0.0), 18_333, &config);
        assert_eq!(track.pose, at_x(0.0));
        assert_eq!(track.history.at(18_333), Some(at_x(0.0)));
    }
}
