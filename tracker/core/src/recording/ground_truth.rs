//! Ground-truth and estimated pose tracks: time-sorted poses of one object, held or interpolated at any time.

use super::SetupError;
use super::pose_csv::PoseRecord;
use drivers::recording::{PoseSample, Recording};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use scene::geometry::se3;

/// A pose sample as an isometry (`T_cam_obj`, metres).
pub fn sample_pose(s: &PoseSample) -> Isometry3<f64> {
    let [x, y, z, w] = s.rotation_xyzw;
    let [tx, ty, tz] = s.translation;
    Isometry3::from_parts(
        Translation3::new(tx, ty, tz),
        UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
    )
}

/// A time-sorted pose track of one object.
#[derive(Debug, Clone, Default)]
pub struct PoseTrack {
    times: Vec<i64>,
    poses: Vec<Isometry3<f64>>,
}

impl PoseTrack {
    /// A track from `(t_us, pose)` pairs (sorted here; a later duplicate time replaces an earlier one).
    pub fn new(mut samples: Vec<(i64, Isometry3<f64>)>) -> Self {
        samples.sort_by_key(|s| s.0);
        samples.dedup_by(|later, earlier| {
            if later.0 == earlier.0 {
                earlier.1 = later.1;
                true
            } else {
                false
            }
        });
        let (times, poses) = samples.into_iter().unzip();
        Self { times, poses }
    }

    /// The track of `object` in tracker output rows.
    pub fn from_records(records: &[PoseRecord], object: &str) -> Self {
        Self::new(
            records
                .iter()
                .filter(|r| r.object == object)
                .map(|r| (r.t_us, r.pose))
                .collect(),
        )
    }

    /// The ground-truth track of `object`.
    pub fn from_samples(samples: &[PoseSample], object: &str) -> Self {
        Self::new(
            samples
                .iter()
                .filter(|s| s.object == object)
                .map(|s| (s.t_us, sample_pose(s)))
                .collect(),
        )
    }

    /// Whether the track has no pose.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Time of the first pose, microseconds.
    pub fn first(&self) -> Option<(i64, Isometry3<f64>)> {
        Some((*self.times.first()?, *self.poses.first()?))
    }

    /// The latest pose at or before `t_us` (what a consumer of the stream holds at that time).
    pub fn held_at(&self, t_us: i64) -> Option<Isometry3<f64>> {
        let i = self.times.partition_point(|t| *t <= t_us);
        (i > 0).then(|| self.poses[i - 1])
    }

    /// The pose at `t_us`, interpolated on SE(3) between the neighbouring samples; None outside the track.
    pub fn interpolated_at(&self, t_us: i64) -> Option<Isometry3<f64>> {
        let i = self.times.partition_point(|t| *t < t_us);
        if i < self.times.len() && self.times[i] == t_us {
            return Some(self.poses[i]);
        }
        if i == 0 || i == self.times.len() {
            return None;
        }
        let (t0, t1) = (self.times[i - 1], self.times[i]);
        let s = (t_us - t0) as f64 / (t1 - t0) as f64;
        Some(se3::interpolate(&self.poses[i - 1], &self.poses[i], s))
    }
}

/// The objects with ground truth in `rec`, sorted by name.
pub fn ground_truth_objects(rec: &Recording) -> Result<Vec<String>, SetupError> {
    let gt = rec
        .ground_truth
        .as_ref()
        .ok_or_else(|| SetupError::NoGroundTruth(rec.dir().display().to_string()))?;
    let mut names: Vec<String> = gt.iter().map(|s| s.object.clone()).collect();
    names.sort();
    names.dedup();
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn held_and_interpolated_poses() {
        let a = Isometry3::translation(0.0, 0.0, 1.0);
        let b = Isometry3::translation(0.1, 0.0, 1.0);
        // Out of order with a duplicate time: the later row for t = 100 wins.
        let track = PoseTrack::new(vec![
            (100, Isometry3::translation(9.0, 9.0, 9.0)),
            (0, a),
            (100, b),
        ]);
        assert!(track.held_at(-1).is_none());
        assert_eq!(track.held_at(0), Some(a));
        assert_eq!(track.held_at(99), Some(a));
        assert_eq!(track.held_at(1000), Some(b));
        let mid = track.interpolated_at(25).unwrap();
        assert!((mid.translation.vector - Vector3::new(0.025, 0.0, 1.0)).norm() < 1e-12);
        assert_eq!(track.interpolated_at(100), Some(b));
        assert!(track.interpolated_at(101).is_none());
        assert!(track.interpolated_at(-1).is_none());
        assert_eq!(track.first().map(|f| f.0), Some(0));
    }
}
