//! The object's motion between estimates: what two poses say about it, and where a depth frame's estimate is
//! carried to by the motion between depth frames.

use super::ObjectTrack;
use crate::refine::apply_step;
use crate::track::config::TrackerConfig;
use nalgebra::{Isometry3, Vector6};

impl ObjectTrack {
    /// The previous depth frame's estimate carried on to `t_us` at the motion between the last two depth frames'
    /// estimates (centre speed and angular speed capped like the velocity's, no spin about a continuous symmetry
    /// axis): a start for the safety net that the events since the previous depth frame cannot have moved. `None`
    /// before two depth frames, and after a re-detection until two more.
    pub(super) fn anchored_extrapolation(
        &self,
        t_us: i64,
        config: &TrackerConfig,
    ) -> Option<Isometry3<f64>> {
        let (t1, p1) = self.anchor?;
        let (t0, p0) = self.anchor_before?;
        let between = (t1 - t0) as f64 * 1e-6;
        if between <= 0.0 {
            return None;
        }
        let mut motion = self.observable_motion(&p0, &p1, between);
        cap_motion(&mut motion, config);
        let span = (t_us - t1).max(0) as f64 * 1e-6;
        Some(apply_step(&p1, &self.center_obj, &(motion * span)))
    }

    /// The velocity that carries `from` to `to` in `span_s` seconds (centre m/s, angular rad/s, camera frame),
    /// without the spin about any continuous symmetry axis: that rotation leaves the shape unchanged, so what the
    /// refinement reports about it is noise, and feeding it back would spin the prediction.
    pub(super) fn observable_motion(
        &self,
        from: &Isometry3<f64>,
        to: &Isometry3<f64>,
        span_s: f64,
    ) -> Vector6<f64> {
        let v = (self.center_at(to) - self.center_at(from)) / span_s;
        let mut w = (to.rotation * from.rotation.inverse()).scaled_axis() / span_s;
        for axis in &self.spin_axes {
            let a = to.rotation * axis;
            w -= a * a.dot(&w);
        }
        Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z)
    }
}

/// Scales a motion (centre m/s, angular rad/s) down to the speeds the motion model accepts
/// ([`TrackerConfig::max_speed`], [`TrackerConfig::max_angular_speed`]), keeping its directions.
pub(super) fn cap_motion(v: &mut Vector6<f64>, config: &TrackerConfig) {
    let lin = v.fixed_rows::<3>(0).norm();
    if lin > config.max_speed {
        v.fixed_rows_mut::<3>(0).scale_mut(config.max_speed / lin);
    }
    let ang = v.fixed_rows::<3>(3).norm();
    if ang > config.max_angular_speed {
        v.fixed_rows_mut::<3>(3)
            .scale_mut(config.max_angular_speed / ang);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Point3, Translation3, UnitQuaternion, Vector3};
    use scene::mesh::Symmetry;

    #[test]
    fn velocity_keeps_no_spin_about_a_continuous_symmetry_axis() {
        let config = TrackerConfig::default();
        let half = Vector3::new(0.01, 0.01, 0.06);
        let tilted = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 0.6),
            UnitQuaternion::from_euler_angles(0.4, -0.3, 0.2),
        );
        let marker = [Symmetry::Continuous {
            axis: Vector3::z_axis(),
            offset: Point3::origin(),
        }];
        let symmetric = ObjectTrack::new(1, 0.12, -half, half, tilted, 0, &marker, &config);
        let plain = ObjectTrack::new(1, 0.12, -half, half, tilted, 0, &[], &config);
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
        let mut track = ObjectTrack::new(1, 0.1, -half, half, at(0.0, 0.0), 0, &[], &config);
        // One depth frame is no motion yet.
        track.anchor = Some((0, at(0.0, 0.0)));
        assert!(track.anchored_extrapolation(66_666, &config).is_none());
        // 2 cm and 0.1 rad between frames 33.3 ms apart; the velocity the events updated since says otherwise and
        // is ignored.
        track.anchor_before = track.anchor;
        track.anchor = Some((33_333, at(0.02, 0.1)));
        track.velocity = Vector6::new(-5.0, 1.0, 0.0, 0.0, 9.0, 0.0);
        let start = track.anchored_extrapolation(66_666, &config).unwrap();
        assert!(
            (start.translation.vector - Vector3::new(0.04, 0.0, 0.6)).norm() < 1e-4,
            "{start:?}"
        );
        assert!(
            (start.rotation.angle_to(&at(0.0, 0.2).rotation)).abs() < 1e-4,
            "{start:?}"
        );
        // At the anchor's own time the start is the anchor.
        let same = track.anchored_extrapolation(33_333, &config).unwrap();
        assert!((same.translation.vector - Vector3::new(0.02, 0.0, 0.6)).norm() < 1e-9);
        // The speed is capped like the velocity's: at 0.3 m/s the 33.3 ms carry 1 cm, not 2.
        config.max_speed = 0.3;
        let capped = track.anchored_extrapolation(66_666, &config).unwrap();
        assert!((capped.translation.x - 0.03).abs() < 1e-4, "{capped:?}");
        // A re-detection forgets both anchors.
        track.relocate(at(0.1, 0.0));
        assert!(track.anchored_extrapolation(66_666, &config).is_none());
    }
}
