//! What a run did ([`Summary`], returned by [`super::run`]) and its plain-text report.

use super::queue::QueueCounters;
use super::{LatencySummary, OutputPaths, SourceStats};
use crate::publish::SinkCounters;
use drivers::timeline::TimelineCounters;
use tracker::track::TrackerCounters;

/// One sink's totals.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SinkSummary {
    /// Sink name.
    pub name: String,
    /// Counters.
    pub counters: SinkCounters,
    /// Publish calls that failed.
    pub errors: u64,
    /// Latency from edge decoded to after this sink.
    pub latency: LatencySummary,
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct Summary {
    /// The source.
    pub source: String,
    /// The hardware the tracker rendered on ([`scene::render::RenderDevice`] as text); `None` if it renders nothing.
    pub renderer: Option<String>,
    /// Objects tracked.
    pub objects: Vec<String>,
    /// Ticks processed.
    pub ticks: u64,
    /// Pose estimates handed to the sinks.
    pub poses: u64,
    /// Wall-clock duration of the run (source start to tracker end), seconds.
    pub wall_s: f64,
    /// Ticks per wall-clock second between the first and the last tick.
    pub tick_rate_hz: Option<f64>,
    /// Ticks per second of the event camera's clock.
    pub camera_tick_rate_hz: Option<f64>,
    /// Latency from a tick's edge decoded to after the last sink.
    pub latency: LatencySummary,
    /// Age of the depth frames when they reached the tracker thread, microseconds of the event camera's clock
    /// ([`super::health::Health::depth_frame_age`]).
    pub depth_frame_age: LatencySummary,
    /// Wall-clock time the tracker took at each depth frame's arrival, microseconds.
    pub depth_arrival: LatencySummary,
    /// Depth frames held until a tick's poses were out (`[tracker] defer_late_depth`).
    pub depth_frames_deferred: u64,
    /// Depth frames that arrived older than the tracker uses (`max_depth_age_ms`).
    pub depth_frames_too_old: u64,
    /// Times a trigger outage held more events than the runtime holds (handed over early).
    pub event_hold_overflows: u64,
    /// Late depth frames carried only, because the tracker thread had fallen behind.
    pub depth_frames_shed: u64,
    /// Estimates of published ticks the tracker revised afterwards, handed to the sinks (the pose queries answer
    /// with them).
    pub poses_revised: u64,
    /// Per sink.
    pub sinks: Vec<SinkSummary>,
    /// Queue counters (dropped events).
    pub queue: QueueCounters,
    /// Timeline counters (missing, extra, jittered pulses).
    pub timeline: TimelineCounters,
    /// What the source read.
    pub source_stats: SourceStats,
    /// The tracker's counters at the end (`None` for a tracker that keeps none).
    pub tracker: Option<TrackerCounters>,
    /// Whether the run was stopped early (Ctrl-C or the caller).
    pub stopped: bool,
    /// File outputs.
    pub outputs: OutputPaths,
    /// The last status document.
    pub status: serde_json::Value,
    /// Errors at shutdown (flush, close), by sink.
    pub shutdown_errors: Vec<String>,
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let rate = |r: Option<f64>| r.map_or_else(|| "-".to_string(), |r| format!("{r:.1} Hz"));
        writeln!(f, "source:          {}", self.source)?;
        if let Some(r) = &self.renderer {
            writeln!(f, "renderer:        {r}")?;
        }
        writeln!(
            f,
            "poses published: {} ({} ticks x {} objects: {}){}",
            self.poses,
            self.ticks,
            self.objects.len(),
            self.objects.join(", "),
            if self.stopped { ", stopped early" } else { "" }
        )?;
        writeln!(
            f,
            "rate:            {} wall clock ({} on the camera clock) over {:.2} s",
            rate(self.tick_rate_hz),
            rate(self.camera_tick_rate_hz),
            self.wall_s
        )?;
        writeln!(
            f,
            "latency:         {} (edge decoded -> after all sinks)",
            self.latency
        )?;
        for s in &self.sinks {
            writeln!(
                f,
                "  {:<14} {} | published {} failed {} dropped {}",
                s.name, s.latency, s.counters.published, s.counters.failed, s.counters.dropped
            )?;
        }
        let t = &self.timeline;
        writeln!(
            f,
            "drops:           {} events in {} batches (queue overload), {} poses in sinks",
            self.queue.dropped_events,
            self.queue.dropped_batches,
            self.sinks.iter().map(|s| s.counters.dropped).sum::<u64>()
        )?;
        if self.event_hold_overflows > 0 {
            writeln!(
                f,
                "trigger outage:  {} times more events waited for a missing pulse than are held; they reached \
                 the tracker before the ticks placed in the gap",
                self.event_hold_overflows
            )?;
        }
        writeln!(
            f,
            "timeline:        {} pulses, {} missing, {} gaps ({} ticks not bridged), {} extra, {} jittered, {} phase errors; depth frames {} ({} missing)",
            t.pulses,
            t.missing,
            t.gaps,
            t.unbridged,
            t.extra,
            t.jittered,
            t.phase_errors,
            self.source_stats.depth_frames,
            self.source_stats.depth_missing
        )?;
        if let Some(c) = &self.tracker {
            writeln!(
                f,
                "tracker:         {} steps between ticks, {} re-detections ({} places checked, {} dropped), {} depth fallbacks, {} render errors, {} depth frames unused, {} renders prefetched ({} used)",
                c.inner_steps,
                c.redetections,
                c.redetect_places_checked,
                c.redetect_places_dropped,
                c.depth_fallbacks,
                c.render_errors,
                c.depth_frames_unused,
                c.renders_prefetched,
                c.prefetched_renders_used
            )?;
        }
        if let Some(c) = &self.tracker
            && (c.depth_frames_late > 0 || self.source_stats.depth_in_transit > 0)
        {
            writeln!(
                f,
                "late depth:      {} frames used after their own tick ({} tracked again from their exposure over {} ticks, {} carried from it; {} times an object's pose history did not reach back), {} still in transit at the end",
                c.depth_frames_late,
                c.late_frames_retracked,
                c.ticks_retracked,
                c.late_frames_not_retracked,
                c.late_depth_unplaced,
                self.source_stats.depth_in_transit
            )?;
        }
        if self.depth_arrival.samples > 0 {
            let ms =
                |x: Option<f64>| x.map_or_else(|| "-".to_string(), |x| format!("{:.1}", x * 1e-3));
            let (a, w) = (&self.depth_frame_age, &self.depth_arrival);
            writeln!(
                f,
                "depth arrival:   {} frames, age p50 {} p99 {} max {} ms (exposure -> tracker thread, camera clock); tracker work then p50 {} p99 {} max {} ms; {} deferred (carried at the next tick, tracked again after its poses); {} carried only (the tracker thread was behind); {} older than max_depth_age_ms; {} poses of published ticks revised (the pose queries answer with them)",
                w.samples,
                ms(a.p50_us),
                ms(a.p99_us),
                ms(a.max_us),
                ms(w.p50_us),
                ms(w.p99_us),
                ms(w.max_us),
                self.depth_frames_deferred,
                self.depth_frames_shed,
                self.depth_frames_too_old,
                self.poses_revised
            )?;
        }
        if let Some(u) = &self.source_stats.usb {
            writeln!(
                f,
                "usb:             {} bytes received in {} session(s), {} outage(s), {} failed open(s); {} transfers \
                 dropped ({} bytes; ring {} MiB), {} transfer errors, {} gaps resynchronised, {} tick pulses made \
                 while away",
                u.bytes,
                u.sessions,
                u.outages,
                u.open_attempts_failed,
                u.dropped_transfers,
                u.dropped_bytes,
                u.ring_bytes / (1024 * 1024),
                u.transfer_errors,
                u.gaps,
                u.pulses_made_while_away
            )?;
            if let Some(e) = &u.last_error {
                writeln!(f, "usb error:       {e}")?;
            }
        }
        if let Some(r) = &self.source_stats.ros2 {
            let unusable: Vec<String> =
                r.unusable.iter().map(|(k, n)| format!("{k} {n}")).collect();
            writeln!(
                f,
                "ros2:            {} event packets ({} bytes), {} missing, {} out of order; {} depth images, {} \
                 CameraInfo; unusable: {}",
                r.packets,
                r.bytes,
                r.packets_missing,
                r.packets_out_of_order,
                r.depth_images,
                r.camera_infos,
                if unusable.is_empty() {
                    "none".to_owned()
                } else {
                    unusable.join(", ")
                }
            )?;
        }
        if !self.source_stats.anomalies.is_empty() {
            let a: Vec<String> = self
                .source_stats
                .anomalies
                .iter()
                .map(|(k, n)| format!("{k} {n}"))
                .collect();
            writeln!(f, "decode anomalies: {}", a.join(", "))?;
        }
        for e in &self.shutdown_errors {
            writeln!(f, "shutdown error:  {e}")?;
        }
        Ok(())
    }
}
