//! The recent estimates of one object: where it was when a depth frame that arrives late was exposed.

use nalgebra::{Isometry3, UnitQuaternion};
use scene::geometry::se3;

/// Estimates kept per object: 533 ms at 120 Hz with the most steps between ticks
/// ([`crate::track::config::MAX_INNER_STEPS`]), more than the longest depth age the tracker accepts
/// ([`crate::track::config::MAX_DEPTH_AGE_LIMIT_MS`]).
pub const POSE_HISTORY_LEN: usize = 64 * (1 + crate::track::config::MAX_INNER_STEPS as usize);

/// The latest [`POSE_HISTORY_LEN`] estimates (time in microseconds, `T_cam_obj`), oldest first. A fixed ring: no
/// allocation. Times strictly increase; an estimate at or before the newest replaces the entries it does not follow.
#[derive(Debug, Clone)]
pub struct PoseHistory {
    entries: [(i64, Isometry3<f64>); POSE_HISTORY_LEN],
    /// Index of the oldest entry.
    start: usize,
    len: usize,
}

impl Default for PoseHistory {
    fn default() -> Self {
        Self::new()
    }
}

impl PoseHistory {
    /// An empty history.
    pub fn new() -> Self {
        Self {
            entries: [(0, Isometry3::identity()); POSE_HISTORY_LEN],
            start: 0,
            len: 0,
        }
    }

    /// Forgets every estimate (the object was moved by re-detection or reset: its past poses no longer fit).
    pub fn clear(&mut self) {
        self.start = 0;
        self.len = 0;
    }

    /// Number of estimates kept.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no estimate is kept.
    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Time of the oldest estimate kept, microseconds; `None` when empty.
    pub fn first_us(&self) -> Option<i64> {
        (self.len > 0).then(|| self.get(0).0)
    }

    fn get(&self, i: usize) -> (i64, Isometry3<f64>) {
        self.entries[(self.start + i) % POSE_HISTORY_LEN]
    }

    /// Records the estimate at `t_us`. Entries at or after `t_us` are dropped first (a tracker that went back in
    /// time, e.g. a reset to an earlier stamp), so times stay strictly increasing.
    pub fn push(&mut self, t_us: i64, pose: Isometry3<f64>) {
        while self.len > 0 && self.get(self.len - 1).0 >= t_us {
            self.len -= 1;
        }
        if self.len == POSE_HISTORY_LEN {
            self.start = (self.start + 1) % POSE_HISTORY_LEN;
            self.len -= 1;
        }
        self.entries[(self.start + self.len) % POSE_HISTORY_LEN] = (t_us, pose);
        self.len += 1;
    }

    /// Moves the estimates at `from_us` and later (all before the next [`Self::push`]) by `correction`, applied in
    /// the object frame (`T_cam_obj * correction`): a depth frame that arrived late corrected the estimate at its
    /// exposure, and the motion estimated since carried that correction on, so the estimates in between are
    /// corrected too. A later late frame's exposure then finds them consistent with the current estimate.
    pub fn correct_since(&mut self, from_us: i64, correction: &Isometry3<f64>) {
        for i in (0..self.len).rev() {
            let k = (self.start + i) % POSE_HISTORY_LEN;
            if self.entries[k].0 < from_us {
                break;
            }
            let corrected = self.entries[k].1 * correction;
            // Unit quaternions stay unit only up to rounding; corrections compound, so renormalise each time.
            self.entries[k].1 = Isometry3::from_parts(
                corrected.translation,
                UnitQuaternion::new_normalize(corrected.rotation.into_inner()),
            );
        }
    }

    /// The pose at `t_us`, interpolated on SE(3) between the estimates either side; `None` outside the span the
    /// history covers (no extrapolation).
    pub fn at(&self, t_us: i64) -> Option<Isometry3<f64>> {
        if self.len == 0 || t_us < self.get(0).0 || t_us > self.get(self.len - 1).0 {
            return None;
        }
        // The first entry at or after `t_us` (binary search over the ring's logical order).
        let (mut lo, mut hi) = (0, self.len - 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.get(mid).0 < t_us {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        let (t1, p1) = self.get(lo);
        if t1 == t_us || lo == 0 {
            return Some(p1);
        }
        let (t0, p0) = self.get(lo - 1);
        let s = (t_us - t0) as f64 / (t1 - t0) as f64;
        Some(se3::interpolate(&p0, &p1, s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, Vector3};
    use proptest::prelude::*;

    fn at_x(x: f64) -> Isometry3<f64> {
        Isometry3::from_parts(Translation3::new(x, 0.0, 0.5), UnitQuaternion::identity())
    }

    #[test]
    fn interpolates_between_estimates_and_refuses_outside_them() {
        let mut h = PoseHistory::new();
        assert!(h.at(0).is_none());
        h.push(1_000, at_x(0.0));
        h.push(2_000, at_x(0.1));
        h.push(4_000, at_x(0.5));
        assert_eq!(h.at(1_000), Some(at_x(0.0)));
        assert_eq!(h.at(4_000), Some(at_x(0.5)));
        let mid = h.at(3_000).unwrap();
        assert!((mid.translation.x - 0.3).abs() < 1e-12, "{mid:?}");
        let quarter = h.at(1_250).unwrap();
        assert!((quarter.translation.x - 0.025).abs() < 1e-12);
        assert!(h.at(999).is_none());
        assert!(h.at(4_001).is_none());
    }

    #[test]
    fn keeps_the_latest_entries_and_stays_increasing() {
        let mut h = PoseHistory::new();
        for k in 0..(POSE_HISTORY_LEN as i64 + 10) {
            h.push(k * 10, at_x(k as f64));
        }
        assert_eq!(h.len(), POSE_HISTORY_LEN);
        assert!(h.at(9 * 10).is_none(), "the oldest ten were dropped");
        assert_eq!(h.at(10 * 10), Some(at_x(10.0)));
        // Going back in time drops what the new estimate does not follow.
        h.push(500, at_x(-1.0));
        assert_eq!(h.at(500), Some(at_x(-1.0)));
        assert!(h.at(510).is_none());
        h.clear();
        assert!(h.is_empty() && h.at(500).is_none());
    }

    #[test]
    fn a_correction_moves_the_estimates_since_its_exposure_only() {
        let mut h = PoseHistory::new();
        for k in 0..5 {
            h.push(k * 100, at_x(k as f64 * 0.1));
        }
        let c = Isometry3::from_parts(
            Translation3::new(0.0, 0.01, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.1),
        );
        h.correct_since(250, &c);
        assert_eq!(h.at(200), Some(at_x(0.2)));
        for (t, x) in [(300, 0.3), (400, 0.4)] {
            let (got, want) = (h.at(t).unwrap(), at_x(x) * c);
            assert!((got.translation.vector - want.translation.vector).norm() < 1e-12);
            assert!(got.rotation.angle_to(&want.rotation) < 1e-12);
        }
    }

    /// Corrections compound: a rotation a hair off unit length, applied many times, must not grow the entries'
    /// quaternions (their inverse would no longer undo them, and a late frame's carried depth ran away
    /// geometrically before this held).
    #[test]
    fn corrections_keep_the_rotations_unit() {
        let mut h = PoseHistory::new();
        h.push(0, at_x(0.0));
        let q =
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.01).into_inner() * (1.0 + 1e-6);
        let c = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 0.0),
            UnitQuaternion::new_unchecked(q),
        );
        for _ in 0..10_000 {
            h.correct_since(0, &c);
        }
        let p = h.at(0).unwrap();
        assert!((p.rotation.into_inner().norm() - 1.0).abs() < 1e-9);
        let round_trip = p * p.inverse();
        assert!(round_trip.translation.vector.norm() < 1e-9);
    }

    proptest! {
        /// Whatever the pushes, a query at a kept time gives that estimate, and one between two kept times lies
        /// between their translations (all on a line here).
        #[test]
        fn queries_match_the_kept_estimates(
            steps in proptest::collection::vec((1i64..20_000, -1.0f64..1.0), 1..200),
            probe in 0.0f64..1.0,
        ) {
            let mut h = PoseHistory::new();
            let mut t = 0;
            let mut kept = Vec::new();
            for (dt, x) in steps {
                t += dt;
                let pose = Isometry3::from_parts(
                    Translation3::new(x, 0.0, 1.0),
                    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), x),
                );
                h.push(t, pose);
                kept.push((t, pose));
            }
            let kept = &kept[kept.len().saturating_sub(POSE_HISTORY_LEN)..];
            prop_assert_eq!(h.len(), kept.len());
            for &(t, p) in kept {
                prop_assert_eq!(h.at(t), Some(p));
            }
            for w in kept.windows(2) {
                let (t0, p0) = w[0];
                let (t1, p1) = w[1];
                let t = t0 + ((t1 - t0) as f64 * probe) as i64;
                let q = h.at(t).unwrap();
                let (a, b) = (p0.translation.x.min(p1.translation.x), p0.translation.x.max(p1.translation.x));
                prop_assert!(q.translation.x >= a - 1e-9 && q.translation.x <= b + 1e-9);
            }
        }
    }
}
