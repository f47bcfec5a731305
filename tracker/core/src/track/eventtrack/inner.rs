//! The steps between two ticks ([`crate::track::InnerStepConfig`]): planned at a tick from how fast the objects
//! move in the image, run as the events past each step's time arrive.

use super::engine::TickEngine;
use crate::track::config::MAX_INNER_STEPS;
use crate::track::estimate::TrackingState;
use crate::track::object::ObjectTrack;
use scene::geometry::PinholeCamera;

/// The tick periods over which [`InnerPlan::plan`] measures an object's latest motion: a single period's motion
/// is mostly the estimate's own jitter on a slow object (a slow box moving 2.6 pixels per tick measured 7.5), four
/// periods (a 30 Hz depth camera's frame interval at 120 Hz) bring that near its true speed while a fast object's
/// motion, sustained over them, still shows in full.
const PLAN_WINDOW_TICKS: i64 = 4;

/// The times of the steps between the latest tick and the next one, microseconds, in order; the ones not run
/// yet from `next` on.
#[derive(Debug, Clone, Default)]
pub(super) struct InnerPlan {
    times: [i64; MAX_INNER_STEPS as usize],
    count: usize,
    next: usize,
}

impl InnerPlan {
    /// Plans the steps after the tick at `tick_us`: evenly spaced over the nominal period, one for every
    /// `inner_step_px` the fastest object that a step would refine moves per tick beyond the first, at most
    /// `max_inner_steps`; none when steps between ticks are off or the tracker refines only at depth frames, or
    /// when no object would be refined (each step refines the objects that are not lost and move at least
    /// `inner_step_px` per tick at their smoothed velocity). An object's speed here is the larger of its smoothed
    /// velocity's and its mean motion over the last [`PLAN_WINDOW_TICKS`] tick periods, or over as much as its
    /// history covers if that is shorter (which sees an object speed up a few ticks before the smoothed velocity
    /// does).
    pub fn plan(&mut self, engine: &TickEngine, tick_us: i64) {
        self.count = 0;
        self.next = 0;
        let step_px = engine.config.inner_steps.inner_step_px;
        if step_px <= 0.0 || !engine.refines(false) {
            return;
        }
        let period_s = engine.rig.clock.period_s();
        let period_us = engine.rig.clock.whole_period_us();
        let camera = &engine.rig.event_camera;
        let fastest_px = engine
            .objects
            .iter()
            .filter(|o| o.state.tracking != TrackingState::Lost)
            .filter_map(|o| {
                let smoothed = o.state.image_speed(&o.model, camera);
                if smoothed * period_s < step_px {
                    return None;
                }
                let measured = recent_image_speed(o, camera, tick_us, period_us);
                Some(smoothed.max(measured) * period_s)
            })
            .fold(0.0, f64::max);
        let most = engine
            .config
            .inner_steps
            .max_inner_steps
            .min(MAX_INNER_STEPS) as usize;
        let wanted = (fastest_px / step_px).ceil() - 1.0;
        if wanted.is_nan() || wanted < 1.0 {
            return;
        }
        self.count = (wanted as usize).min(most);
        let parts = (self.count + 1) as f64;
        for (k, t) in self.times[..self.count].iter_mut().enumerate() {
            *t = tick_us + (period_s * 1e6 * (k + 1) as f64 / parts).round() as i64;
        }
    }

    /// The time of the next step not run yet.
    pub fn next_time(&self) -> Option<i64> {
        (self.next < self.count).then(|| self.times[self.next])
    }

    /// Marks the next step as run.
    pub fn advance(&mut self) {
        self.next = (self.next + 1).min(self.count);
    }

    /// Drops the steps not run yet (a tick came).
    pub fn clear(&mut self) {
        self.count = 0;
        self.next = 0;
    }
}

/// The image speed, full-image pixels per second, of `object`'s mean motion over the last [`PLAN_WINDOW_TICKS`]
/// tick periods before `tick_us` (or since its history starts, if that is later); 0 when its history covers less
/// than one period.
fn recent_image_speed(
    object: &ObjectTrack,
    camera: &PinholeCamera,
    tick_us: i64,
    period_us: i64,
) -> f64 {
    let state = &object.state;
    let Some(first_us) = state.history.first_us() else {
        return 0.0;
    };
    let window_us = (tick_us - first_us).min(PLAN_WINDOW_TICKS * period_us);
    if window_us < period_us {
        return 0.0;
    }
    state.history.at(tick_us - window_us).map_or(0.0, |from| {
        let v = object
            .model
            .observable_motion(&from, &state.pose, window_us as f64 * 1e-6);
        state.image_speed_at(&object.model, camera, &v)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::config::TrackerConfig;
    use nalgebra::{Isometry3, Vector3};

    const PERIOD_US: i64 = 8_333;

    fn camera() -> PinholeCamera {
        PinholeCamera::new(600.0, 600.0, 320.0, 240.0, 640, 480).unwrap()
    }

    /// A 10 cm object at 0.6 m whose history holds `x_m(k)` along the camera's x at ticks `k = 0..=ticks`; the
    /// estimate is the last of them.
    fn moving(ticks: i64, x_m: impl Fn(i64) -> f64) -> ObjectTrack {
        let pose = |k: i64| Isometry3::translation(x_m(k), 0.0, 0.6);
        let half = Vector3::new(0.05, 0.0, 0.0);
        let mut o = ObjectTrack::new(
            1,
            0.1,
            -half,
            half,
            pose(0),
            0,
            &[],
            &TrackerConfig::default(),
        );
        o.state.history.clear();
        for k in 0..=ticks {
            o.state.history.push(k * PERIOD_US, pose(k));
        }
        o.state.pose = pose(ticks);
        o
    }

    /// Pixels per tick of `speed` (pixels per second).
    fn per_tick(speed: f64) -> f64 {
        speed * PERIOD_US as f64 * 1e-6
    }

    #[test]
    fn jitter_of_a_slow_object_is_averaged_over_the_window() {
        // 2 mm per tick along x, with +-3 mm of alternating jitter on each estimate.
        let jittered = |k: i64| 0.002 * k as f64 + if k % 2 == 0 { 0.003 } else { -0.003 };
        let o = moving(12, jittered);
        let over_window = per_tick(recent_image_speed(&o, &camera(), 12 * PERIOD_US, PERIOD_US));
        let true_px = 600.0 * 0.002 / 0.6;
        // One period would read (2 + 6) mm: 8 px; the four-period mean reads (8 mm / 4): 2 px.
        assert!(
            (over_window - true_px).abs() < 0.05,
            "{over_window} px vs {true_px} px"
        );
    }

    #[test]
    fn steady_fast_motion_shows_in_full() {
        let o = moving(12, |k| 0.017 * k as f64);
        let px = per_tick(recent_image_speed(&o, &camera(), 12 * PERIOD_US, PERIOD_US));
        assert!((px - 17.0).abs() < 0.05, "{px} px per tick");
    }

    #[test]
    fn a_short_history_uses_what_it_covers_and_none_under_a_period() {
        let o = moving(2, |k| 0.01 * k as f64);
        let px = per_tick(recent_image_speed(&o, &camera(), 2 * PERIOD_US, PERIOD_US));
        assert!(
            (px - 10.0).abs() < 0.05,
            "{px} px per tick over two periods"
        );
        let mut o = moving(0, |_| 0.0);
        o.state
            .history
            .push(PERIOD_US / 2, Isometry3::translation(0.05, 0.0, 0.6));
        o.state.pose = Isometry3::translation(0.05, 0.0, 0.6);
        assert_eq!(
            recent_image_speed(&o, &camera(), PERIOD_US / 2, PERIOD_US),
            0.0
        );
    }
}
