//! When the tracker works on a late depth frame. A late frame makes the tracker track the ticks since its
//! exposure again when it arrives ([`tracker::track::LateDepthConfig::retrack_late_depth`]); a frame that arrives
//! just before a tick would make that tick wait for the work. In a real-time run such a frame is handed over
//! deferred ([`tracker::track::DepthHandling::AfterNextTick`]): the tick uses it the cheap way (carried from
//! its exposure) and the tracker tracks again once the tick's poses are out.

use std::time::Duration;

/// The policy and what it learnt of the tracker's cost.
#[derive(Debug)]
pub struct DepthArrival {
    enabled: bool,
    period_us: f64,
    /// Wall-clock work per tick tracked again, microseconds (a running mean of the latest frames).
    per_tick_us: Option<f64>,
    deferred: u64,
    shed: u64,
}

impl DepthArrival {
    /// A policy for ticks `period_us` apart; `enabled` only where the stream's clock runs with the wall clock (a
    /// live rig or a real-time replay), since it compares the two.
    pub fn new(enabled: bool, period_us: f64) -> Self {
        Self {
            enabled,
            period_us: period_us.max(1.0),
            per_tick_us: None,
            deferred: 0,
            shed: 0,
        }
    }

    /// The ticks a frame exposed at `t_us` makes the tracker track again after the tick at `last_tick_us` (its
    /// exposure tick to that one), or `None` for a frame whose tick has not come (on time: no work).
    fn ticks_again(&self, t_us: i64, last_tick_us: i64) -> Option<f64> {
        let behind = (last_tick_us - t_us) as f64 / self.period_us;
        (behind > -0.5).then(|| behind.round().max(0.0) + 1.0)
    }

    /// Whether a frame exposed at `t_us`, arriving when the stream is at `stream_us`, should be handed over
    /// deferred: the work it is expected to take is more than the time left until the tick after
    /// `last_tick_us`, both on the event camera's clock.
    pub fn should_defer(
        &self,
        t_us: i64,
        stream_us: Option<i64>,
        last_tick_us: Option<i64>,
    ) -> bool {
        let (true, Some(now), Some(tick), Some(per_tick)) =
            (self.enabled, stream_us, last_tick_us, self.per_tick_us)
        else {
            return false;
        };
        let Some(ticks) = self.ticks_again(t_us, tick) else {
            return false;
        };
        let left_us = tick as f64 + self.period_us - now as f64;
        per_tick * ticks > left_us
    }

    /// Whether a frame exposed at `t_us` should only be carried, not tracked again: it is late (its tick, at or
    /// before `last_tick_us`, has run) and the thread has fallen behind (the latest tick waited `waited` after its
    /// trigger edge was decoded, more than half a tick period), so tracking again would only add to the backlog.
    pub fn should_shed(&self, t_us: i64, last_tick_us: Option<i64>, waited: Duration) -> bool {
        self.enabled
            && last_tick_us.is_some_and(|tick| self.ticks_again(t_us, tick).is_some())
            && waited.as_secs_f64() * 1e6 > self.period_us / 2.0
    }

    /// Records that working on a frame exposed at `t_us`, up to the tick at `last_tick_us`, took `work`.
    pub fn record(&mut self, t_us: i64, last_tick_us: Option<i64>, work: Duration) {
        let Some(ticks) = last_tick_us.and_then(|tick| self.ticks_again(t_us, tick)) else {
            return;
        };
        let sample = work.as_secs_f64() * 1e6 / ticks;
        self.per_tick_us = Some(match self.per_tick_us {
            Some(mean) => 0.75 * mean + 0.25 * sample,
            None => sample,
        });
    }

    /// Counts a frame handed over deferred.
    pub fn count_deferred(&mut self) {
        self.deferred += 1;
    }

    /// Counts a frame handed over to be carried only.
    pub fn count_shed(&mut self) {
        self.shed += 1;
    }

    /// Frames handed over to be carried only so far.
    pub fn shed(&self) -> u64 {
        self.shed
    }

    /// Frames handed over deferred so far.
    pub fn deferred(&self) -> u64 {
        self.deferred
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runtime::health::Health;
    use crate::runtime::queue::{Ingest, IngestQueue};
    use crate::runtime::worker::Worker;
    use drivers::event::CdEvent;
    use drivers::recording::DepthFrame;
    use drivers::timeline::{Tick, TimelineConfig, ideal_edges};
    use nalgebra::Isometry3;
    use std::sync::{Arc, Mutex};
    use std::time::Instant;
    use tracker::track::{DepthHandling, PoseEstimate, PoseTracker, TrackingState};

    /// A tracker whose work on a late depth frame takes 5 ms, at arrival or after the next tick when deferred;
    /// it records how each frame was handed over.
    struct SlowDepth {
        names: Vec<String>,
        handed: Arc<Mutex<Vec<&'static str>>>,
        pending: bool,
    }

    impl PoseTracker for SlowDepth {
        fn objects(&self) -> &[String] {
            &self.names
        }
        fn push_events(&mut self, _: &[CdEvent]) {}
        fn push_depth(&mut self, _: i64, _: &mut DepthFrame, handling: DepthHandling) {
            match handling {
                DepthHandling::Now => {
                    self.handed.lock().unwrap().push("at arrival");
                    std::thread::sleep(Duration::from_millis(5));
                }
                DepthHandling::AfterNextTick => {
                    self.handed.lock().unwrap().push("deferred");
                    self.pending = true;
                }
                DepthHandling::CarryOnly => self.handed.lock().unwrap().push("carried only"),
            }
        }
        fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
            out.push(PoseEstimate {
                object: 0,
                t_us: tick.t_us,
                pose: Isometry3::identity(),
                quality: 1.0,
                state: TrackingState::Tracking,
            });
        }
        fn prepare_next_tick(&mut self) {
            if std::mem::take(&mut self.pending) {
                std::thread::sleep(Duration::from_millis(5));
            }
        }
        fn pose_at(&self, _: usize, _: i64) -> Option<PoseEstimate> {
            None
        }
    }

    /// Frames 40 ms late, each arriving 1.7 ms before a tick, through the tracker thread (with an age limit of
    /// 200 ms when deferring, 30 ms when not). Everything is queued at once, so the edges' decode instants are
    /// set apart from the queueing: 20 ms before with `behind` (a thread that has fallen behind), else far
    /// ahead (no tick counts as having waited). Returns how each frame was handed over and the health after.
    fn run(defer: bool, behind: bool) -> (Vec<&'static str>, Health) {
        let cfg = TimelineConfig::default();
        let queue = Arc::new(IngestQueue::new(64, 16));
        let health = Arc::new(Mutex::new(Health::new(&["mug".into()], &[])));
        let handed = Arc::new(Mutex::new(Vec::new()));
        let tracker = SlowDepth {
            names: vec!["mug".into()],
            handed: handed.clone(),
            pending: false,
        };
        let worker = Worker::new(
            Box::new(tracker),
            Vec::new(),
            cfg,
            queue.clone(),
            health.clone(),
        )
        .with_depth_deferral(defer)
        .with_depth_age_limit(Some(if defer { 200.0 } else { 30.0 }));
        let thread = std::thread::spawn(move || worker.run());
        let edges = ideal_edges(&cfg, 1_000, 24);
        let exposures: Vec<i64> = edges.chunks(2).step_by(4).map(|p| p[0].t_us).collect();
        let mut due = exposures.iter().map(|&t| t + 40_000).peekable();
        for pulse in edges.chunks(2) {
            // The frame due before this pulse comes after an event at its due time.
            while let Some(t) = due.next_if(|&t| t < pulse[0].t_us) {
                let mut b = queue.buffer();
                b.push(CdEvent {
                    t_us: t,
                    ..CdEvent::default()
                });
                queue.push(Ingest::Events(b));
                queue.push(Ingest::Depth {
                    t_us: t - 40_000,
                    frame: Box::new(DepthFrame {
                        index: 0,
                        width: 1,
                        height: 1,
                        depth_m: vec![1.0],
                    }),
                });
            }
            for &edge in pulse {
                let now = Instant::now();
                let decoded_at = if behind {
                    now.checked_sub(Duration::from_millis(20)).unwrap_or(now)
                } else {
                    now + Duration::from_secs(60)
                };
                queue.push(Ingest::Trigger { edge, decoded_at });
            }
        }
        queue.push(Ingest::End);
        thread.join().unwrap();
        let handed = handed.lock().unwrap().clone();
        let health = health.lock().unwrap().clone();
        (handed, health)
    }

    #[test]
    fn the_tracker_thread_defers_a_frame_whose_work_would_delay_the_next_tick() {
        let (handed, health) = run(true, false);
        // 6 exposures, 5 of them due before the last tick; the first is measured at arrival, the rest deferred.
        assert_eq!(
            handed,
            ["at arrival", "deferred", "deferred", "deferred", "deferred"]
        );
        assert_eq!(health.depth_frames, 5);
        assert_eq!(health.depth_frames_deferred, 4);
        // Each frame's work is measured once: at arrival, or after the tick that followed.
        assert_eq!(health.depth_arrival.count(), 5);
        assert!(health.depth_arrival.quantile_us(0.5).unwrap() >= 5_000.0);
        assert_eq!(health.depth_frame_age.count(), 5);
        assert_eq!(health.depth_frame_age.max_us(), Some(40_000.0));
        assert_eq!(health.depth_frames_too_old, 0);

        let (handed, health) = run(false, false);
        assert_eq!(handed, ["at arrival"; 5]);
        assert_eq!(health.depth_frames_deferred, 0);
        // 40 ms old against a 30 ms limit: each counted (and the first reported on stderr).
        assert_eq!(health.depth_frames_too_old, 5);
    }

    /// A thread that has fallen behind (its ticks wait 20 ms after their edges were decoded) only carries the
    /// late frames: tracking again would add to the backlog.
    #[test]
    fn a_thread_that_has_fallen_behind_carries_late_frames_only() {
        let (handed, health) = run(true, true);
        assert_eq!(handed, ["carried only"; 5]);
        assert_eq!(health.depth_frames_shed, 5);
        assert_eq!(health.depth_arrival.count(), 5);
        assert_eq!(health.depth_frames_deferred, 0);
        assert_eq!(health.depth_frames, 5);
        // Off (a fast replay): handed over as usual whatever the wait.
        let (handed, health) = run(false, true);
        assert_eq!(handed, ["at arrival"; 5]);
        assert_eq!(health.depth_frames_shed, 0);
    }

    #[test]
    fn a_frame_is_deferred_only_when_its_work_would_run_into_the_next_tick() {
        let mut a = DepthArrival::new(true, 8_333.3);
        // Nothing measured yet: at once.
        assert!(!a.should_defer(0, Some(40_000), Some(33_333)));
        // A frame exposed at 0 and worked on after the tick at 16,667: 3 ticks in 3 ms, 1 ms each.
        a.record(0, Some(16_667), Duration::from_millis(3));
        // Exposed at 0, the tick at 33,333 last: 5 ticks again, 5 ms; 1.7 ms left until 41,667.
        assert!(a.should_defer(0, Some(40_000), Some(33_333)));
        // With 6.7 ms left, it fits.
        assert!(!a.should_defer(0, Some(35_000), Some(33_333)));
        // Exposed at 16,667, the tick at 33,333 last: 3 ticks, 3 ms, with 5 ms left.
        assert!(!a.should_defer(16_667, Some(36_667), Some(33_333)));
        // An on-time frame (its tick has not come) costs nothing.
        assert!(!a.should_defer(41_667, Some(41_600), Some(33_333)));
        assert!(!a.should_defer(0, None, Some(33_333)));
        assert!(!a.should_defer(0, Some(40_000), None));
        // On-time frames teach nothing; late ones move the mean.
        a.record(41_667, Some(33_333), Duration::from_millis(100));
        assert!(!a.should_defer(16_667, Some(36_667), Some(33_333)));
        a.record(0, Some(16_667), Duration::from_millis(12));
        assert!(a.should_defer(16_667, Some(36_667), Some(33_333)));
        // Off (a fast replay, whose clock does not run with the wall clock): never.
        let mut off = DepthArrival::new(false, 8_333.3);
        off.record(0, Some(16_667), Duration::from_millis(50));
        assert!(!off.should_defer(0, Some(40_000), Some(33_333)));
        a.count_deferred();
        assert_eq!(a.deferred(), 1);
        // Carried only when late and the latest tick waited more than half a period.
        assert!(a.should_shed(0, Some(33_333), Duration::from_millis(5)));
        assert!(!a.should_shed(0, Some(33_333), Duration::from_millis(3)));
        assert!(!a.should_shed(41_667, Some(33_333), Duration::from_millis(5)));
        assert!(!a.should_shed(0, None, Duration::from_millis(5)));
        assert!(!off.should_shed(0, Some(33_333), Duration::from_millis(50)));
    }
}
