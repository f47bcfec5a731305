//! The tracker thread: takes ingest in order, turns trigger edges into ticks and feeds the tracker exactly the
//! events up to each tick through the [`TickDriver`] the offline driver runs on too, hands every tick's estimates
//! to each sink, and measures latency (edge decoded -> after each sink, and after all sinks). Steady state
//! allocates nothing: buffers are reused and event batches recycled.

use super::control::ControlApplier;
use super::depth_arrival::DepthArrival;
use super::health::Health;
use super::latency_log::{LatencyLog, TickTiming};
use super::priority::set_fifo_priority;
use super::queue::{Ingest, IngestQueue};
use super::revision::PoseRevisions;
use crate::publish::{PoseSink, TickPoses};
use drivers::timeline::TimelineConfig;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};
use tracker::track::{DepthHandling, PoseEstimate, PoseTracker, TickDriver};

/// What the tracker thread reports when it ends.
pub struct WorkerEnd {
    /// The sinks, flushed (returned so the caller can close them).
    pub sinks: Vec<Box<dyn PoseSink>>,
    /// Flush errors, by sink name, and the latency log's write error.
    pub flush_errors: Vec<String>,
    /// Rows written to the latency log, when one was kept.
    pub latency_log_rows: Option<u64>,
}

/// The tracker thread's state.
pub struct Worker {
    tracker: Box<dyn PoseTracker>,
    sinks: Vec<Box<dyn PoseSink>>,
    driver: TickDriver,
    queue: Arc<IngestQueue>,
    health: Arc<Mutex<Health>>,
    objects: Vec<String>,
    estimates: Vec<PoseEstimate>,
    sink_latency: Vec<Duration>,
    sink_failed: Vec<Option<String>>,
    first_tick_wall: Option<Instant>,
    reported_errors: Vec<bool>,
    latency_log: Option<LatencyLog>,
    /// The latest event or trigger edge time received, event camera clock, microseconds.
    stream_us: Option<i64>,
    /// The latest tick's time, event camera clock, microseconds.
    last_tick_us: Option<i64>,
    /// Whether the tracker works on a late depth frame when it arrives or after the next tick's poses.
    arrival: DepthArrival,
    /// Exposure of the frame handed over deferred since the latest tick.
    deferred_depth_us: Option<i64>,
    /// How long the latest tick waited after its trigger edge was decoded.
    last_waited: Duration,
    /// Oldest depth frame the tracker uses, microseconds after its exposure (`max_depth_age_ms`), if it says.
    depth_age_limit_us: Option<i64>,
    /// Whether a frame older than that was reported.
    reported_old_depth: bool,
    /// Published ticks, for handing the sinks what the tracker revises of them.
    revisions: PoseRevisions,
    /// Commands from outside (re-seed, reset), carried out before each tick; `None` when nothing sends them.
    control: Option<ControlApplier>,
}

impl Worker {
    /// A worker driving `tracker` and `sinks` from `queue`, reporting into `health`.
    pub fn new(
        tracker: Box<dyn PoseTracker>,
        sinks: Vec<Box<dyn PoseSink>>,
        timeline: TimelineConfig,
        queue: Arc<IngestQueue>,
        health: Arc<Mutex<Health>>,
    ) -> Self {
        let objects = tracker.objects().to_vec();
        let objects_count = objects.len();
        let n = sinks.len();
        Self {
            estimates: Vec::with_capacity(objects.len().max(1) * 2),
            objects,
            tracker,
            sinks,
            driver: TickDriver::new(timeline),
            queue,
            health,
            sink_latency: vec![Duration::ZERO; n],
            sink_failed: vec![None; n],
            first_tick_wall: None,
            reported_errors: vec![false; n],
            latency_log: None,
            stream_us: None,
            last_tick_us: None,
            arrival: DepthArrival::new(false, timeline.period_us()),
            deferred_depth_us: None,
            last_waited: Duration::ZERO,
            depth_age_limit_us: None,
            reported_old_depth: false,
            revisions: PoseRevisions::new(objects_count),
            control: None,
        }
    }

    /// Also carries out the control commands `control` receives, before each tick.
    pub fn with_control(mut self, control: Option<ControlApplier>) -> Self {
        self.control = control;
        self
    }

    /// Also writes one row per tick into `log` ([`TickTiming`]).
    pub fn with_latency_log(mut self, log: Option<LatencyLog>) -> Self {
        self.latency_log = log;
        self
    }

    /// In a real-time run (`enabled`), hands a late depth frame over deferred when the tracker's work on it is
    /// expected to run into the next tick ([`DepthArrival`], [`PoseTracker::push_depth_deferred`]).
    pub fn with_depth_deferral(mut self, enabled: bool) -> Self {
        let period_us = self.driver.timeline_config().period_us();
        self.arrival = DepthArrival::new(enabled, period_us);
        self
    }

    /// Warns (once) when a depth frame reaches the tracker thread more than `limit_ms` after its exposure: the
    /// tracker does not use such frames (`max_depth_age_ms`), so a slow depth camera leaves it on events alone.
    pub fn with_depth_age_limit(mut self, limit_ms: Option<f64>) -> Self {
        self.depth_age_limit_us = limit_ms.map(|ms| (ms * 1e3).round() as i64);
        self
    }

    fn health(&self) -> MutexGuard<'_, Health> {
        self.health.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Runs until the queue delivers [`Ingest::End`]; then finishes the timeline, flushes the sinks and returns them.
    pub fn run(self) -> WorkerEnd {
        self.run_loop()
    }

    /// Like [`Self::run`], first asking for `SCHED_FIFO` at `priority` (1..=99; 0 = keep normal scheduling).
    /// Returns why the request was refused, if it was.
    pub fn run_with_priority(self, priority: u8) -> (WorkerEnd, Option<String>) {
        let refused = if priority == 0 {
            None
        } else {
            set_fifo_priority(priority).err()
        };
        (self.run_loop(), refused)
    }

    fn run_loop(mut self) -> WorkerEnd {
        loop {
            let Some(item) = self.queue.pop(Duration::from_millis(100)) else {
                continue;
            };
            match item {
                Ingest::Events(events) => {
                    if let Some(last) = events.last() {
                        self.stream_us =
                            Some(self.stream_us.map_or(last.t_us, |t| t.max(last.t_us)));
                    }
                    self.driver.events(&events, self.tracker.as_mut());
                    let n = events.len() as u64;
                    self.queue.recycle(events);
                    let mut h = self.health();
                    h.events += n;
                    h.event_hold_overflows = self.driver.hold_overflows();
                }
                Ingest::Depth { t_us, frame } => {
                    self.check_depth_age(t_us);
                    self.hand_over_depth(t_us, frame);
                }
                Ingest::Trigger { edge, decoded_at } => {
                    self.stream_us = Some(self.stream_us.map_or(edge.t_us, |t| t.max(edge.t_us)));
                    self.driver.edge(edge, self.tracker.as_mut());
                    while let Some(tick) = self.driver.next_tick(self.tracker.as_mut()) {
                        self.tick(&tick, decoded_at);
                    }
                }
                Ingest::End => {
                    self.driver.finish();
                    let now = Instant::now();
                    while let Some(tick) = self.driver.next_tick(self.tracker.as_mut()) {
                        self.tick(&tick, now);
                    }
                    self.driver.release_held(self.tracker.as_mut());
                    break;
                }
            }
        }
        let mut flush_errors = Vec::new();
        for s in &mut self.sinks {
            if let Err(e) = s.flush() {
                flush_errors.push(e.to_string());
            }
        }
        let latency_log_rows = match self.latency_log.take().map(LatencyLog::finish) {
            Some(Ok(rows)) => Some(rows),
            Some(Err(e)) => {
                flush_errors.push(e);
                None
            }
            None => None,
        };
        self.sync_counters();
        WorkerEnd {
            sinks: self.sinks,
            flush_errors,
            latency_log_rows,
        }
    }

    fn sync_counters(&mut self) {
        let queue = self.queue.counters();
        let timeline = *self.driver.timeline_counters();
        let mut h = self.health.lock().unwrap_or_else(|p| p.into_inner());
        h.queue = queue;
        h.timeline = timeline;
        // Also what the last tick's `prepare_next_tick` did, which the per-tick update precedes.
        if h.tracker.is_some() {
            h.tracker = self.tracker.tracker_counters();
        }
        for (sh, s) in h.sinks.iter_mut().zip(&self.sinks) {
            sh.counters = s.counters();
        }
    }

    /// Records how old the depth frame exposed at `t_us` is on arrival (the latest stream time less its
    /// exposure), and counts and (once) reports a frame older than the tracker uses.
    fn check_depth_age(&mut self, t_us: i64) {
        let Some(age_us) = self.stream_us.map(|now| (now - t_us).max(0)) else {
            return;
        };
        let too_old = self.depth_age_limit_us.filter(|&limit| age_us > limit);
        let mut h = self.health();
        h.depth_frame_age
            .record(Duration::from_micros(age_us.unsigned_abs()));
        h.depth_frames_too_old += u64::from(too_old.is_some());
        drop(h);
        if let Some(limit_us) = too_old
            && !std::mem::replace(&mut self.reported_old_depth, true)
        {
            eprintln!(
                "warning: a depth frame reached the tracker {:.1} ms after its exposure, more than \
                 max_depth_age_ms = {:.0}: the tracker does not use such frames (counted as unused); \
                 raise [tracker.parameters] max_depth_age_ms or reduce the depth camera's latency \
                 (further ones are counted)",
                age_us as f64 * 1e-3,
                limit_us as f64 * 1e-3
            );
        }
    }

    /// Hands the depth frame exposed at `t_us` to the tracker: carried only while the thread is behind, deferred
    /// when its work would delay the next tick, else at once ([`DepthArrival`]); records the work it took.
    fn hand_over_depth(&mut self, t_us: i64, mut frame: Box<drivers::recording::DepthFrame>) {
        let start = Instant::now();
        let shed = self
            .arrival
            .should_shed(t_us, self.last_tick_us, self.last_waited);
        let defer = !shed
            && self
                .arrival
                .should_defer(t_us, self.stream_us, self.last_tick_us);
        let work = if shed {
            self.tracker
                .push_depth(t_us, &mut frame, DepthHandling::CarryOnly);
            self.arrival.count_shed();
            Some(start.elapsed())
        } else if defer {
            self.tracker
                .push_depth(t_us, &mut frame, DepthHandling::AfterNextTick);
            self.arrival.count_deferred();
            // Its work is measured after the next tick ([`Self::tick`]).
            self.deferred_depth_us = Some(t_us);
            None
        } else {
            self.tracker
                .push_depth(t_us, &mut frame, DepthHandling::Now);
            let work = start.elapsed();
            self.arrival.record(t_us, self.last_tick_us, work);
            self.revise_published();
            Some(work)
        };
        let mut h = self.health();
        h.depth_frames += 1;
        h.depth_frames_shed = self.arrival.shed();
        h.depth_frames_deferred = self.arrival.deferred();
        if let Some(work) = work {
            h.depth_arrival.record(work);
        }
    }

    /// Hands the sinks the estimates of published ticks that the tracker says it revised, and counts them.
    fn revise_published(&mut self) {
        let Some(since_us) = self.tracker.take_revision() else {
            return;
        };
        if self
            .revisions
            .revise(since_us, &*self.tracker, &mut self.sinks)
            > 0
        {
            self.health().poses_revised = self.revisions.handed();
        }
    }

    /// One tick: track, publish, record health, hand over revisions, then start the next tick's work.
    fn tick(&mut self, tick: &drivers::timeline::Tick, decoded_at: Instant) {
        let tick_start = Instant::now();
        if let Some(control) = self.control.as_mut()
            && control.apply(self.tracker.as_mut(), tick.t_us, self.last_tick_us)
        {
            self.health
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .control = control.counters().clone();
        }
        self.estimates.clear();
        self.tracker.tick(tick, &mut self.estimates);
        let tick_end = Instant::now();
        self.mark_lost_while_the_camera_was_away(tick.t_us);
        self.publish(tick, decoded_at);
        let total = decoded_at.elapsed();
        self.record_health(tick, total);
        self.revisions.published(&self.estimates);
        // A frame the tracker kept for this tick may have made it track the ticks before again.
        self.revise_published();
        self.last_tick_us = Some(tick.t_us);
        self.last_waited = tick_start.saturating_duration_since(decoded_at);
        let prepare = self.prepare_next_tick();
        if let Some(log) = &mut self.latency_log {
            log.record(&TickTiming {
                t_us: tick.t_us,
                depth: tick.depth_frame.is_some(),
                waited: self.last_waited,
                tick: tick_end - tick_start,
                sinks: total.saturating_sub(tick_end.saturating_duration_since(decoded_at)),
                latency: total,
                prepare,
            });
        }
    }

    /// A tick made while the live event camera was away came from the wall clock with no measurement: every object
    /// is published as `lost` (quality 0) at its last estimate, never as tracked from data that is not there.
    fn mark_lost_while_the_camera_was_away(&mut self, t_us: i64) {
        let away = self
            .health()
            .event_camera
            .as_ref()
            .is_some_and(|c| c.away_at(t_us));
        if away {
            for e in &mut self.estimates {
                e.state = tracker::track::TrackingState::Lost;
                e.quality = 0.0;
            }
        }
    }

    /// Hands the tick's estimates to every sink, timing each; a sink's first error is printed, every one counted.
    fn publish(&mut self, tick: &drivers::timeline::Tick, decoded_at: Instant) {
        let poses = TickPoses {
            tick,
            estimates: &self.estimates,
            objects: &self.objects,
            decoded_at,
        };
        for (i, sink) in self.sinks.iter_mut().enumerate() {
            let r = sink.publish(&poses);
            self.sink_latency[i] = decoded_at.elapsed();
            if let Err(e) = r {
                if !self.reported_errors[i] {
                    self.reported_errors[i] = true;
                    eprintln!(
                        "warning: sink {}: {e} (further errors are counted)",
                        sink.name()
                    );
                }
                self.sink_failed[i] = Some(e.to_string());
            }
        }
    }

    /// Records the tick in the health report: counts, latency from the trigger edge's decoding to the last sink
    /// (`total`), queue and timeline counters, each sink's latency and errors, each object's latest state.
    fn record_health(&mut self, tick: &drivers::timeline::Tick, total: Duration) {
        let now = Instant::now();
        let first = *self.first_tick_wall.get_or_insert(now);
        let queue = self.queue.counters();
        let timeline = *self.driver.timeline_counters();
        let mut h = self.health.lock().unwrap_or_else(|p| p.into_inner());
        h.ticks += 1;
        h.poses += self.estimates.len() as u64;
        h.tracker = self.tracker.tracker_counters();
        h.first_tick_us.get_or_insert(tick.t_us);
        h.last_tick_us = Some(tick.t_us);
        h.tick_wall_s = (now - first).as_secs_f64();
        h.latency.record(total);
        h.queue = queue;
        h.timeline = timeline;
        for (i, (sh, s)) in h.sinks.iter_mut().zip(&self.sinks).enumerate() {
            sh.latency.record(self.sink_latency[i]);
            sh.counters = s.counters();
            if let Some(e) = self.sink_failed[i].take() {
                sh.errors += 1;
                sh.last_error = Some(e);
            }
        }
        for e in &self.estimates {
            if let Some(o) = h.objects.get_mut(e.object) {
                o.state = Some(e.state);
                o.quality = e.quality;
                o.t_us = Some(e.t_us);
            }
        }
    }

    /// With the poses out, starts the next tick's work in the time until it arrives: its renders, and tracking
    /// again from a depth frame handed over deferred (whose revisions go to the sinks). Returns the time it took.
    fn prepare_next_tick(&mut self) -> Duration {
        let prepare_start = Instant::now();
        self.tracker.prepare_next_tick();
        if let Some(t_us) = self.deferred_depth_us.take() {
            let work = prepare_start.elapsed();
            self.arrival.record(t_us, self.last_tick_us, work);
            self.health().depth_arrival.record(work);
            self.revise_published();
        }
        prepare_start.elapsed()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::publish::{PublishError, SinkCounters};
    use crate::runtime::health::Health;
    use drivers::event::CdEvent;
    use drivers::timeline::ideal_edges;
    use nalgebra::Isometry3;
    use tracker::track::HoldPoseTracker;

    /// (tick index, depth frame, estimates) of each publish call.
    type Seen = Arc<Mutex<Vec<(u64, Option<u64>, usize)>>>;

    /// Records tick indices and depth flags; fails every 5th tick to exercise error counting.
    struct Probe {
        seen: Seen,
        counters: SinkCounters,
    }

    impl PoseSink for Probe {
        fn name(&self) -> &str {
            "probe"
        }
        fn publish(&mut self, p: &TickPoses<'_>) -> Result<(), PublishError> {
            self.seen
                .lock()
                .unwrap()
                .push((p.tick.index, p.tick.depth_frame, p.estimates.len()));
            if p.tick.index % 5 == 4 {
                self.counters.failed += 1;
                return Err(PublishError::Transport {
                    sink: "probe".into(),
                    message: "injected".into(),
                });
            }
            self.counters.published += p.estimates.len() as u64;
            Ok(())
        }
        fn counters(&self) -> SinkCounters {
            self.counters
        }
    }

    #[test]
    fn edges_become_ticks_for_every_sink_with_latency_and_errors_counted() {
        let cfg = TimelineConfig::default();
        let queue = Arc::new(IngestQueue::new(8, 16));
        let objects = vec!["a".to_string(), "b".to_string()];
        let health = Arc::new(Mutex::new(Health::new(&objects, &["probe".into()])));
        let seen = Arc::new(Mutex::new(Vec::new()));
        let tracker = HoldPoseTracker::new(
            objects
                .iter()
                .map(|o| (o.clone(), Isometry3::identity()))
                .collect(),
        );
        let sink = Probe {
            seen: seen.clone(),
            counters: SinkCounters::default(),
        };
        let worker = Worker::new(
            Box::new(tracker),
            vec![Box::new(sink)],
            cfg,
            queue.clone(),
            health.clone(),
        );
        let thread = std::thread::spawn(move || worker.run());
        for e in ideal_edges(&cfg, 1000, 12) {
            let mut b = queue.buffer();
            b.push(CdEvent {
                t_us: e.t_us - 1,
                ..CdEvent::default()
            });
            queue.push(Ingest::Events(b));
            queue.push(Ingest::Trigger {
                edge: e,
                decoded_at: Instant::now(),
            });
        }
        queue.push(Ingest::End);
        let end = thread.join().unwrap();
        assert!(end.flush_errors.is_empty());
        let seen = seen.lock().unwrap().clone();
        // 12 pulses -> 12 ticks, in order, depth frames on every 4th, one estimate per object.
        assert_eq!(seen.len(), 12);
        for (i, (index, depth, n)) in seen.iter().enumerate() {
            assert_eq!(*index, i as u64);
            assert_eq!(*depth, (i % 4 == 0).then_some(i as u64 / 4));
            assert_eq!(*n, 2);
        }
        let h = health.lock().unwrap();
        assert_eq!((h.ticks, h.poses), (12, 24));
        // The producer outruns the 8-batch queue: whatever was not tracked was dropped and counted.
        assert_eq!(h.events + h.queue.dropped_events, 24);
        assert_eq!(h.queue.batches, 24);
        assert_eq!(h.latency.count(), 12);
        assert_eq!(h.sinks[0].latency.count(), 12);
        assert_eq!(h.sinks[0].errors, 2);
        assert_eq!(h.sinks[0].counters.failed, 2);
        assert_eq!(h.sinks[0].last_error.as_deref(), Some("probe: injected"));
        assert_eq!(
            h.objects[1].state,
            Some(tracker::track::TrackingState::Tracking)
        );
        assert_eq!(h.timeline.pulses, 12);
    }
}
