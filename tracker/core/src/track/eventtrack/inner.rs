//! The steps between two ticks ([`crate::track::InnerStepConfig`]): planned at a tick from how fast the objects
//! move in the image, run as the events past each step's time arrive.

use super::engine::TickEngine;
use crate::track::config::MAX_INNER_STEPS;
use crate::track::estimate::TrackingState;

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
    /// `inner_step_px` the fastest object that is not lost moves per tick beyond the first, at most
    /// `max_inner_steps`; none when steps between ticks are off or the tracker refines only at depth frames. An
    /// object's speed here is the larger of its smoothed velocity's and its motion over the last tick period (which
    /// sees an object start or speed up a few ticks before the smoothed velocity does).
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
            .map(|o| {
                let smoothed = o.state.image_speed(&o.model, camera);
                let measured = o.state.history.at(tick_us - period_us).map_or(0.0, |p0| {
                    let v = o.model.observable_motion(&p0, &o.state.pose, period_s);
                    o.state.image_speed_at(&o.model, camera, &v)
                });
                smoothed.max(measured) * period_s
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
