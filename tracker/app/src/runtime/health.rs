//! Health of the running process: latency histograms (p50 / p99 / max), tick rate, per-object state and quality,
//! drop counters, sink counters, and the status JSON published on the status topic and printed at exit.

use super::queue::QueueCounters;
use crate::publish::SinkCounters;
use drivers::timeline::TimelineCounters;
use serde_json::{Map, Value, json};
use std::time::Duration;
use tracker::track::{TrackerCounters, TrackingState};

/// Buckets of 1 us up to this many microseconds, then 10 us buckets up to [`COARSE_END_US`].
const FINE_END_US: u64 = 2_000;
/// End of the coarse buckets; slower samples go to the overflow bucket (the maximum stays exact).
const COARSE_END_US: u64 = 200_000;
const BUCKETS: usize = FINE_END_US as usize + ((COARSE_END_US - FINE_END_US) / 10) as usize + 1;

/// A fixed-size latency histogram: 1 us resolution to 2 ms, 10 us to 200 ms, exact maximum. Recording is O(1) and
/// never allocates.
#[derive(Debug, Clone)]
pub struct LatencyHistogram {
    counts: Box<[u32]>,
    total: u64,
    max_ns: u64,
    sum_ns: u128,
}

impl Default for LatencyHistogram {
    fn default() -> Self {
        Self::new()
    }
}

impl LatencyHistogram {
    /// An empty histogram (allocates its buckets once).
    pub fn new() -> Self {
        Self {
            counts: vec![0; BUCKETS].into_boxed_slice(),
            total: 0,
            max_ns: 0,
            sum_ns: 0,
        }
    }

    fn bucket(us: u64) -> usize {
        if us < FINE_END_US {
            us as usize
        } else if us < COARSE_END_US {
            FINE_END_US as usize + ((us - FINE_END_US) / 10) as usize
        } else {
            BUCKETS - 1
        }
    }

    /// Upper bound of bucket `i`, microseconds.
    fn bucket_upper_us(i: usize) -> f64 {
        let i = i as u64;
        if i < FINE_END_US {
            (i + 1) as f64
        } else {
            (FINE_END_US + (i - FINE_END_US + 1) * 10) as f64
        }
    }

    /// Records one sample.
    pub fn record(&mut self, d: Duration) {
        let ns = u64::try_from(d.as_nanos()).unwrap_or(u64::MAX);
        let b = Self::bucket(ns / 1000);
        self.counts[b] = self.counts[b].saturating_add(1);
        self.total += 1;
        self.max_ns = self.max_ns.max(ns);
        self.sum_ns += u128::from(ns);
    }

    /// Samples recorded.
    pub fn count(&self) -> u64 {
        self.total
    }

    /// The `q`-quantile (0..=1), microseconds: the upper bound of the bucket holding it, capped at the maximum.
    /// `None` without samples.
    pub fn quantile_us(&self, q: f64) -> Option<f64> {
        if self.total == 0 {
            return None;
        }
        let rank = ((q.clamp(0.0, 1.0) * self.total as f64).ceil() as u64).max(1);
        let mut seen = 0u64;
        for (i, c) in self.counts.iter().enumerate() {
            seen += u64::from(*c);
            if seen >= rank {
                let max = self.max_us().unwrap_or(0.0);
                return Some(if i == BUCKETS - 1 {
                    max
                } else {
                    Self::bucket_upper_us(i).min(max)
                });
            }
        }
        self.max_us()
    }

    /// Largest sample, microseconds.
    pub fn max_us(&self) -> Option<f64> {
        (self.total > 0).then(|| self.max_ns as f64 / 1000.0)
    }

    /// Mean, microseconds.
    pub fn mean_us(&self) -> Option<f64> {
        (self.total > 0).then(|| self.sum_ns as f64 / self.total as f64 / 1000.0)
    }

    /// p50, p99 and max (microseconds) as a summary.
    pub fn summary(&self) -> LatencySummary {
        LatencySummary {
            samples: self.total,
            p50_us: self.quantile_us(0.5),
            p99_us: self.quantile_us(0.99),
            max_us: self.max_us(),
            mean_us: self.mean_us(),
        }
    }
}

/// Latency percentiles, microseconds (`None` without samples).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct LatencySummary {
    /// Number of samples.
    pub samples: u64,
    /// Median.
    pub p50_us: Option<f64>,
    /// 99th percentile.
    pub p99_us: Option<f64>,
    /// Largest.
    pub max_us: Option<f64>,
    /// Mean.
    pub mean_us: Option<f64>,
}

impl std::fmt::Display for LatencySummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = |x: Option<f64>| x.map_or_else(|| "-".to_string(), |x| format!("{x:.0} us"));
        write!(
            f,
            "p50 {} p99 {} max {}",
            v(self.p50_us),
            v(self.p99_us),
            v(self.max_us)
        )
    }
}

/// The latest state and quality of one object.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ObjectHealth {
    /// Object name.
    pub name: String,
    /// Latest tracking state (`None` before the first tick).
    pub state: Option<TrackingState>,
    /// Latest quality.
    pub quality: f32,
    /// Time of the latest estimate, microseconds.
    pub t_us: Option<i64>,
}

/// One sink's health.
#[derive(Debug, Clone)]
pub struct SinkHealth {
    /// Sink name.
    pub name: String,
    /// Its counters.
    pub counters: SinkCounters,
    /// Publish calls that returned an error.
    pub errors: u64,
    /// Latency from the tick's edge being decoded to after this sink's publish returned.
    pub latency: LatencyHistogram,
    /// The latest error message.
    pub last_error: Option<String>,
}

/// Everything the status report shows; updated by the tracker thread, read by the status timer.
#[derive(Debug, Clone)]
pub struct Health {
    /// Ticks processed.
    pub ticks: u64,
    /// Pose estimates handed to the sinks.
    pub poses: u64,
    /// Time on the event camera's clock of the first and the latest tick, microseconds.
    pub first_tick_us: Option<i64>,
    /// See `first_tick_us`.
    pub last_tick_us: Option<i64>,
    /// Wall-clock seconds from the first to the latest tick (for the tick rate).
    pub tick_wall_s: f64,
    /// Decoded-to-after-all-sinks latency.
    pub latency: LatencyHistogram,
    /// Per sink.
    pub sinks: Vec<SinkHealth>,
    /// Per object.
    pub objects: Vec<ObjectHealth>,
    /// Ingest queue counters (drops).
    pub queue: QueueCounters,
    /// Trigger timeline counters (missing, extra, jittered pulses...).
    pub timeline: TimelineCounters,
    /// Depth frames handed to the tracker.
    pub depth_frames: u64,
    /// Events handed to the tracker.
    pub events: u64,
    /// The tracker's own counters, if it keeps any.
    pub tracker: Option<TrackerCounters>,
    /// Estimates of published ticks the tracker revised (tracked again from a late depth frame) and handed to
    /// the sinks, so far ([`crate::publish::PoseSink::revise`]).
    pub poses_revised: u64,
    /// The hardware the tracker renders on ([`scene::render::RenderDevice`] as text); `None` if it renders nothing.
    pub renderer: Option<String>,
    /// The live event camera's state, for a live source (`None` for a replay).
    pub event_camera: Option<CameraHealth>,
    /// How old each depth frame was when it reached the tracker thread: the latest event or edge time handed over
    /// by then less the frame's exposure, on the event camera's clock (a live depth camera's transport latency).
    pub depth_frame_age: LatencyHistogram,
    /// Wall-clock time the tracker took on each depth frame: when it arrived (tracking again from a late frame's
    /// exposure happens then, between ticks), or, for a frame handed over deferred, after the tick that carried
    /// it.
    pub depth_arrival: LatencyHistogram,
    /// Depth frames held until the next tick's poses were out, because the tracker's work on them would have
    /// delayed that tick ([`super::depth_arrival::DepthArrival`]).
    pub depth_frames_deferred: u64,
    /// Depth frames that reached the tracker thread older than the tracker uses (`max_depth_age_ms`).
    pub depth_frames_too_old: u64,
    /// Times a trigger outage held more events than [`tracker::track::MAX_OVERDUE_EVENTS`], which were then
    /// handed to the tracker before the ticks the timeline later placed in the gap.
    pub event_hold_overflows: u64,
    /// Late depth frames handed over to be carried only, because the tracker thread had fallen behind
    /// ([`super::depth_arrival::DepthArrival::should_shed`]).
    pub depth_frames_shed: u64,
    /// What the control commands (re-seed, reset) did so far.
    pub control: super::control::ControlCounters,
    /// What the ROS 2 source received so far (`None` for other sources).
    pub ros2_input: Option<Ros2Stats>,
}

/// What the ROS 2 source received (the summary's `ros2:` line, the status).
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct Ros2Stats {
    /// Event packets decoded.
    pub packets: u64,
    /// EVT3 bytes in them.
    pub bytes: u64,
    /// Packets missing by their sequence numbers (the decoder resynchronised after each gap).
    pub packets_missing: u64,
    /// Packets whose sequence number was not after the previous one's (dropped).
    pub packets_out_of_order: u64,
    /// Depth images used.
    pub depth_images: u64,
    /// CameraInfo messages received.
    pub camera_infos: u64,
    /// Samples that could not be used, by kind.
    pub unusable: std::collections::BTreeMap<String, u64>,
    /// The latest estimate of ROS time minus the event camera's time, nanoseconds.
    pub clock_offset_ns: Option<i64>,
}

/// The live event camera as the status reports it.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct CameraHealth {
    /// `opening` (not found yet, or coming back after an outage), `streaming` or `disconnected`.
    pub state: &'static str,
    /// The camera ("EVK4 serial (firmware, sensor, speed)"), once opened.
    pub camera: Option<String>,
    /// The latest problem, while it lasts (why it cannot be opened, or that it was disconnected).
    pub error: Option<String>,
    /// Times it went away while streaming.
    pub outages: u64,
    /// Transfers dropped because the ring between USB and the decoder was full.
    pub dropped_transfers: u64,
    /// Bytes of those transfers.
    pub dropped_bytes: u64,
    /// The spans of stream time the camera was away, microseconds: ticks after the first and up to the second
    /// (`None` while it is still away) were made on the wall clock with no measurement.
    pub away_us: Vec<(i64, Option<i64>)>,
}

impl CameraHealth {
    /// Whether a tick at stream time `t_us` fell while the camera was away.
    pub fn away_at(&self, t_us: i64) -> bool {
        self.away_us
            .iter()
            .rev()
            .any(|&(after, until)| t_us > after && until.is_none_or(|u| t_us <= u))
    }
}

impl Health {
    /// Empty health for these objects and sinks.
    pub fn new(objects: &[String], sinks: &[String]) -> Self {
        Self {
            ticks: 0,
            poses: 0,
            first_tick_us: None,
            last_tick_us: None,
            tick_wall_s: 0.0,
            latency: LatencyHistogram::new(),
            sinks: sinks
                .iter()
                .map(|n| SinkHealth {
                    name: n.clone(),
                    counters: SinkCounters::default(),
                    errors: 0,
                    latency: LatencyHistogram::new(),
                    last_error: None,
                })
                .collect(),
            objects: objects
                .iter()
                .map(|n| ObjectHealth {
                    name: n.clone(),
                    state: None,
                    quality: 0.0,
                    t_us: None,
                })
                .collect(),
            queue: QueueCounters::default(),
            timeline: TimelineCounters::default(),
            depth_frames: 0,
            events: 0,
            tracker: None,
            renderer: None,
            event_camera: None,
            poses_revised: 0,
            depth_frame_age: LatencyHistogram::new(),
            depth_arrival: LatencyHistogram::new(),
            depth_frames_deferred: 0,
            event_hold_overflows: 0,
            depth_frames_too_old: 0,
            depth_frames_shed: 0,
            control: Default::default(),
            ros2_input: None,
        }
    }

    /// Ticks per second of wall-clock time between the first and the latest tick.
    pub fn tick_rate_hz(&self) -> Option<f64> {
        (self.ticks > 1 && self.tick_wall_s > 0.0)
            .then(|| (self.ticks - 1) as f64 / self.tick_wall_s)
    }

    /// Ticks per second of the event camera's clock (the trigger rate as recorded).
    pub fn camera_tick_rate_hz(&self) -> Option<f64> {
        let (a, b) = (self.first_tick_us?, self.last_tick_us?);
        (self.ticks > 1 && b > a).then(|| (self.ticks - 1) as f64 * 1e6 / (b - a) as f64)
    }

    /// Events dropped anywhere (queue overload) plus poses dropped by sinks.
    pub fn total_drops(&self) -> u64 {
        self.queue.dropped_events + self.sinks.iter().map(|s| s.counters.dropped).sum::<u64>()
    }

    /// The status report (the JSON on the status topic).
    pub fn status_json(&self, state: &str) -> Value {
        let mut objects = Map::new();
        for o in &self.objects {
            objects.insert(
                o.name.clone(),
                json!({
                    "state": o.state.map_or("unknown", TrackingState::as_str),
                    "quality": o.quality,
                    "t_us": o.t_us,
                }),
            );
        }
        let mut sinks = Map::new();
        let mut sink_latency = Map::new();
        for s in &self.sinks {
            sinks.insert(
                s.name.clone(),
                json!({
                    "published": s.counters.published,
                    "failed": s.counters.failed,
                    "dropped": s.counters.dropped,
                    "errors": s.errors,
                    "last_error": s.last_error,
                }),
            );
            sink_latency.insert(s.name.clone(), latency_json(&s.latency.summary()));
        }
        let t = &self.timeline;
        json!({
            "state": state,
            "ticks": self.ticks,
            "poses": self.poses,
            "t_us": self.last_tick_us,
            "tick_rate_hz": self.tick_rate_hz(),
            "objects": objects,
            "latency_us": {
                "overall": latency_json(&self.latency.summary()),
                "sinks": sink_latency,
                "depth_arrival": latency_json(&self.depth_arrival.summary()),
            },
            "drops": {
                "events": self.queue.dropped_events,
                "event_batches": self.queue.dropped_batches,
                "sink_poses": self.sinks.iter().map(|s| s.counters.dropped).sum::<u64>(),
                "sink_failed": self.sinks.iter().map(|s| s.counters.failed).sum::<u64>(),
            },
            "timeline": {
                "pulses": t.pulses,
                "missing": t.missing,
                "gaps": t.gaps,
                "unbridged": t.unbridged,
                "extra": t.extra,
                "jittered": t.jittered,
                "phase_errors": t.phase_errors,
                "irregularities": t.irregularities(),
            },
            "ingest": {
                "events": self.events,
                "depth_frames": self.depth_frames,
                "depth_frame_age_us": latency_json(&self.depth_frame_age.summary()),
                "depth_frames_deferred": self.depth_frames_deferred,
                "depth_frames_too_old": self.depth_frames_too_old,
                "event_hold_overflows": self.event_hold_overflows,
                "depth_frames_shed": self.depth_frames_shed,
                "poses_revised": self.poses_revised,
                "queue_max_batches": self.queue.max_depth,
            },
            "sinks": sinks,
            "tracker": self.tracker,
            "renderer": self.renderer,
            "event_camera": self.event_camera,
            "control": self.control,
            "ros2_input": self.ros2_input,
        })
    }
}

fn latency_json(s: &LatencySummary) -> Value {
    json!({"p50": s.p50_us, "p99": s.p99_us, "max": s.max_us, "samples": s.samples})
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_of_a_known_distribution() {
        let mut h = LatencyHistogram::new();
        assert_eq!(h.quantile_us(0.5), None);
        // 1..=100 us, one sample each, plus one slow outlier of 5 ms.
        for us in 1..=100u64 {
            h.record(Duration::from_micros(us) - Duration::from_nanos(500));
        }
        h.record(Duration::from_micros(5_003));
        assert_eq!(h.count(), 101);
        assert_eq!(h.quantile_us(0.5), Some(51.0));
        assert_eq!(h.quantile_us(0.99), Some(100.0));
        assert_eq!(h.max_us(), Some(5003.0));
        // The coarse region reports its bucket's upper bound, never above the maximum.
        assert_eq!(h.quantile_us(1.0), Some(5003.0));
        // Beyond the last bucket: the exact maximum.
        h.record(Duration::from_secs(2));
        assert_eq!(h.quantile_us(1.0), Some(2_000_000.0));
    }

    #[test]
    fn status_names_objects_sinks_and_drops() {
        let mut h = Health::new(&["mug".into()], &["csv:poses.csv".into()]);
        h.queue.dropped_events = 7;
        h.objects[0].state = Some(TrackingState::Degraded);
        h.objects[0].quality = 0.5;
        h.ticks = 121;
        h.tick_wall_s = 1.0;
        let j = h.status_json("running");
        assert_eq!(j["objects"]["mug"]["state"], "degraded");
        assert_eq!(j["drops"]["events"], 7);
        assert_eq!(j["tick_rate_hz"], 120.0);
        assert!(j["sinks"]["csv:poses.csv"]["published"].is_u64());
        assert_eq!(h.total_drops(), 7);
        assert!(j["tracker"].is_null());
        h.tracker = Some(TrackerCounters {
            redetections: 2,
            redetect_places_checked: 5,
            redetect_places_dropped: 3,
            ..TrackerCounters::default()
        });
        let j = h.status_json("running");
        assert_eq!(j["tracker"]["redetections"], 2);
        assert_eq!(j["tracker"]["redetect_places_checked"], 5);
        assert_eq!(j["tracker"]["redetect_places_dropped"], 3);
    }

    #[test]
    fn a_disconnected_camera_is_in_the_status_document() {
        let mut h = Health::new(&["mug".into()], &[]);
        assert!(h.status_json("running")["event_camera"].is_null());
        h.event_camera = Some(CameraHealth {
            state: "disconnected",
            camera: None,
            error: Some("the EVK4 00EE6D00 was disconnected".into()),
            outages: 1,
            dropped_transfers: 3,
            dropped_bytes: 393_216,
            away_us: vec![(1_000_000, Some(2_000_000)), (5_000_000, None)],
        });
        let doc = h.status_json("running");
        assert_eq!(doc["event_camera"]["state"], "disconnected");
        assert_eq!(doc["event_camera"]["outages"], 1);
        assert_eq!(doc["event_camera"]["dropped_bytes"], 393_216);
        assert!(
            doc["event_camera"]["error"]
                .as_str()
                .unwrap_or("")
                .contains("disconnected")
        );
    }
}
