//! The object's range (its centre's distance from the camera) as the depth frames measure it, extrapolated to
//! the ticks between them: the events barely observe motion along the line of sight, so between depth frames
//! only the depth frames' own history says where the object is along it.

/// Longest time, microseconds, [`RangeTrack::range_at`] extrapolates past the latest depth frame (three 30 Hz
/// frame intervals): after a longer gap in the depth frames the ranges say nothing about where the object is.
const MAX_EXTRAPOLATION_US: i64 = 100_000;

/// Longest time, microseconds, between two depth frames whose ranges are still extrapolated together.
const MAX_FRAME_GAP_US: i64 = 100_000;

/// The range of the object's centre (metres from the camera) at the estimates of its latest depth frames, at
/// most three, oldest first, in increasing time. Empty after the object is moved or re-seeded.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct RangeTrack {
    points: [(i64, f64); 3],
    count: usize,
    /// How far, m², each depth frame's range lay from the one before it (holding the range), smoothed.
    held_sq: f64,
    /// How far, m², each depth frame's range lay from the extrapolation to it, smoothed; with `held_sq`, how much
    /// of its extrapolation the track trusts (a fast shake reverses within a frame interval, and extrapolating
    /// its range overshoots).
    extrapolated_sq: f64,
    /// Whether a depth frame has scored the extrapolation since the track was cleared.
    scored: bool,
}

/// Weight of the newest depth frame in [`RangeTrack`]'s smoothed errors.
const ERROR_SMOOTHING: f64 = 0.3;

/// The squared error, m², both of [`RangeTrack`]'s errors are taken to have at least: (1 mm)², below the depth
/// frames' own noise, so that an object at rest trusts the extrapolation by half.
const ERROR_FLOOR_SQ: f64 = 1e-6;

impl RangeTrack {
    /// Records `range_m` as the range at the depth frame exposed at `t_us`. A frame no later than the latest
    /// one (a frame tracked again from its exposure) replaces those at or after it.
    pub fn push(&mut self, t_us: i64, range_m: f64, acceleration_share: f64, max_speed: f64) {
        if !range_m.is_finite() {
            self.clear();
            return;
        }
        while self.count > 0 && self.points[self.count - 1].0 >= t_us {
            self.count -= 1;
        }
        if let Some(extrapolated) = self.extrapolated(t_us, acceleration_share, max_speed) {
            let held = self.points[self.count - 1].1;
            let a = if self.scored { ERROR_SMOOTHING } else { 1.0 };
            self.held_sq += a * ((range_m - held).powi(2) - self.held_sq);
            self.extrapolated_sq += a * ((range_m - extrapolated).powi(2) - self.extrapolated_sq);
            self.scored = true;
        }
        if self.count == self.points.len() {
            self.points.rotate_left(1);
            self.count -= 1;
        }
        self.points[self.count] = (t_us, range_m);
        self.count += 1;
    }

    /// Forgets every range (the object moved to a place the ranges were not measured at).
    pub fn clear(&mut self) {
        *self = Self::default();
    }

    /// The range at `t_us` from the latest depth frames' ranges: the latest one, moved by the share of its
    /// extrapolation ([`Self::extrapolated`]) that the errors of both at the recent depth frames give it
    /// (inverse-variance weights; all of it before a frame has scored them). `None` where the extrapolation is.
    pub fn range_at(&self, t_us: i64, acceleration_share: f64, max_speed: f64) -> Option<f64> {
        let extrapolated = self.extrapolated(t_us, acceleration_share, max_speed)?;
        let held = self.points[self.count - 1].1;
        let trust = if self.scored {
            (self.held_sq + ERROR_FLOOR_SQ)
                / (self.held_sq + self.extrapolated_sq + 2.0 * ERROR_FLOOR_SQ)
        } else {
            1.0
        };
        Some(held + trust * (extrapolated - held))
    }

    /// The range at `t_us` extrapolated from the latest depth frames' ranges: at their latest rate of change
    /// (two frames), plus `acceleration_share` of the change of that rate (three frames), at most `max_speed`
    /// m/s from the latest range. `None` with fewer than two frames, frames further apart than
    /// [`MAX_FRAME_GAP_US`], or `t_us` more than [`MAX_EXTRAPOLATION_US`] past the latest frame.
    fn extrapolated(&self, t_us: i64, acceleration_share: f64, max_speed: f64) -> Option<f64> {
        if self.count < 2 {
            return None;
        }
        let (t2, r2) = self.points[self.count - 1];
        let (t1, r1) = self.points[self.count - 2];
        if t_us < t2 || t_us - t2 > MAX_EXTRAPOLATION_US || t2 - t1 > MAX_FRAME_GAP_US {
            return None;
        }
        let s = |us: i64| us as f64 * 1e-6;
        let rate = (r2 - r1) / s(t2 - t1);
        let mut change = rate * s(t_us - t2);
        if self.count == 3 && acceleration_share > 0.0 {
            let (t0, r0) = self.points[0];
            if t1 - t0 <= MAX_FRAME_GAP_US {
                let rate_before = (r1 - r0) / s(t1 - t0);
                let curvature = (rate - rate_before) / s(t2 - t0);
                change += acceleration_share * curvature * s(t_us - t2) * s(t_us - t1);
            }
        }
        let most = max_speed * s(t_us - t2);
        Some(r2 + change.clamp(-most, most))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FRAME_US: i64 = 33_333;

    fn track(ranges: &[f64]) -> RangeTrack {
        let mut t = RangeTrack::default();
        for (k, r) in ranges.iter().enumerate() {
            t.push(k as i64 * FRAME_US, *r, 1.0, 6.0);
        }
        t
    }

    #[test]
    fn one_frame_extrapolates_nothing() {
        assert_eq!(track(&[0.6]).range_at(FRAME_US, 1.0, 6.0), None);
    }

    #[test]
    fn two_frames_carry_their_rate_on() {
        // 2 cm closer per frame interval: a quarter interval later, 5 mm closer again.
        let t = track(&[0.62, 0.60]);
        let r = t.range_at(FRAME_US + FRAME_US / 4, 1.0, 6.0).unwrap();
        assert!((r - 0.595).abs() < 1e-4, "{r}");
    }

    #[test]
    fn three_frames_add_the_share_of_their_acceleration() {
        // r = 0.6 + 0.5 a t^2 at 40 m/s^2 sampled at three frames; a quarter interval after the last one.
        let r_at = |us: i64| 0.6 + 20.0 * (us as f64 * 1e-6).powi(2);
        let t = track(&[r_at(0), r_at(FRAME_US), r_at(2 * FRAME_US)]);
        let at = 2 * FRAME_US + FRAME_US / 4;
        let full = t.extrapolated(at, 1.0, 6.0).unwrap();
        assert!((full - r_at(at)).abs() < 1e-9, "{full} {}", r_at(at));
        let none = t.extrapolated(at, 0.0, 6.0).unwrap();
        let half = t.extrapolated(at, 0.5, 6.0).unwrap();
        assert!((half - 0.5 * (full + none)).abs() < 1e-12);
        assert!(none < full);
    }

    #[test]
    fn the_extrapolation_is_bounded_by_the_speed_and_time() {
        let t = track(&[0.6, 0.7]);
        // 3 m/s measured; at most 1 m/s accepted.
        let r = t.extrapolated(2 * FRAME_US, 0.0, 1.0).unwrap();
        assert!((r - (0.7 + FRAME_US as f64 * 1e-6)).abs() < 1e-9, "{r}");
        assert_eq!(
            t.range_at(FRAME_US + MAX_EXTRAPOLATION_US + 1, 0.0, 6.0),
            None
        );
        assert_eq!(t.range_at(FRAME_US - 1, 0.0, 6.0), None);
        let mut gap = RangeTrack::default();
        gap.push(0, 0.6, 0.0, 6.0);
        gap.push(MAX_FRAME_GAP_US + 1, 0.6, 0.0, 6.0);
        assert_eq!(gap.range_at(MAX_FRAME_GAP_US + 2, 0.0, 6.0), None);
    }

    #[test]
    fn the_extrapolation_is_trusted_by_how_well_it_predicted_the_recent_frames() {
        // A steady approach at 1 m/s: every frame lands where the extrapolation put it, so it is trusted in full.
        let steady: Vec<f64> = (0..6)
            .map(|k| 0.8 - k as f64 * FRAME_US as f64 * 1e-6)
            .collect();
        let t = track(&steady);
        let at = 5 * FRAME_US + FRAME_US / 2;
        let (r, e) = (
            t.range_at(at, 1.0, 6.0).unwrap(),
            t.extrapolated(at, 1.0, 6.0).unwrap(),
        );
        assert!((r - e).abs() < 0.02 * (e - steady[5]).abs(), "{r} {e}");
        // A shake reversing at every frame: extrapolating it overshoots by more than holding it, so the range
        // stays nearer the latest frame's.
        let shaken: Vec<f64> = (0..6).map(|k| 0.6 + 0.01 * f64::from(k % 2)).collect();
        let t = track(&shaken);
        let (r, e) = (
            t.range_at(at, 1.0, 6.0).unwrap(),
            t.extrapolated(at, 1.0, 6.0).unwrap(),
        );
        let held = shaken[5];
        assert!((r - held).abs() < 0.25 * (e - held).abs(), "{r} {e} {held}");
        // Two frames alone score nothing: the extrapolation is taken whole.
        let t = track(&shaken[..2]);
        assert_eq!(
            t.range_at(at - 4 * FRAME_US, 1.0, 6.0),
            t.extrapolated(at - 4 * FRAME_US, 1.0, 6.0)
        );
    }

    #[test]
    fn a_frame_tracked_again_replaces_the_later_ones() {
        let mut t = track(&[0.60, 0.61, 0.62]);
        t.push(FRAME_US, 0.5, 1.0, 6.0);
        assert_eq!(t.count, 2);
        assert_eq!(t.points[1], (FRAME_US, 0.5));
        t.push(2 * FRAME_US, f64::NAN, 1.0, 6.0);
        assert_eq!(t.count, 0);
    }
}
