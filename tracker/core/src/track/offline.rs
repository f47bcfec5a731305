//! Driving a [`PoseTracker`] over a recording as fast as possible (benchmark, `eventtrack6d track`): the same
//! order of inputs the real-time runtime produces — events up to a tick, the depth frame exposed at the tick (or,
//! with a depth latency, the frames that have arrived by then), the tick — without pacing.

use super::{DepthTransport, PoseEstimate, PoseTracker};
use drivers::event::{CdEvent, EventSink, TriggerEdge};
use drivers::recording::{Recording, RecordingError};
use drivers::timeline::{Tick, TriggerTimeline};
use std::collections::VecDeque;

/// Counters of an offline run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OfflineStats {
    /// Events decoded and handed to the tracker.
    pub events: u64,
    /// Ticks handed to the tracker.
    pub ticks: u64,
    /// Depth frames handed to the tracker.
    pub depth_frames: u64,
    /// Depth-exposure ticks whose frame file is missing (dropped by the sensor).
    pub depth_frames_missing: u64,
    /// Depth frames still in transit at the end of the stream (exposed less than the depth latency before it).
    pub depth_frames_in_transit: u64,
    /// Events after the last tick (never followed by a tick).
    pub events_after_last_tick: u64,
}

struct Collector<'a> {
    events: &'a mut Vec<CdEvent>,
    timeline: &'a mut TriggerTimeline,
    channel: u8,
    /// The latest time in the stream so far (event or edge), microseconds.
    latest_us: &'a mut i64,
}

impl EventSink for Collector<'_> {
    fn cd(&mut self, event: CdEvent) {
        *self.latest_us = (*self.latest_us).max(event.t_us);
        self.events.push(event);
    }
    fn trigger(&mut self, edge: TriggerEdge) {
        *self.latest_us = (*self.latest_us).max(edge.t_us);
        if edge.channel == self.channel {
            self.timeline.push(edge);
        }
    }
}

/// When an offline run hands its inputs to the tracker.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OfflineTiming {
    /// Ticks before this time (microseconds) only warm up the event state; from it on every tick is estimated.
    pub start_us: i64,
    /// Each depth frame is handed over before the first tick at least this long after its exposure,
    /// microseconds (a live depth camera's transport latency), or after the last tick if the stream still
    /// reaches that time; 0 = before its own tick.
    pub depth_latency_us: i64,
    /// Up to this much more for each frame, microseconds, drawn per frame ([`DepthTransport`]); frames stay in
    /// order.
    pub depth_jitter_us: i64,
}

/// Replays `recording` into `tracker`: ticks before `start_us` only warm up the event state; from `start_us` on,
/// every tick is estimated and `on_tick(tick, estimates, tracker)` is called. `on_progress(bytes_read)` follows
/// the event file. Each depth frame arrives with its own tick ([`track_recording_timed`] delays them).
pub fn track_recording(
    recording: &Recording,
    tracker: &mut dyn PoseTracker,
    start_us: i64,
    on_tick: impl FnMut(&Tick, &[PoseEstimate], &dyn PoseTracker),
    on_progress: impl FnMut(u64),
) -> Result<OfflineStats, RecordingError> {
    let timing = OfflineTiming {
        start_us,
        depth_latency_us: 0,
        depth_jitter_us: 0,
    };
    track_recording_timed(recording, tracker, timing, on_tick, on_progress)
}

/// [`track_recording`] with the depth frames delivered `timing.depth_latency_us` after their exposure.
pub fn track_recording_timed(
    recording: &Recording,
    tracker: &mut dyn PoseTracker,
    timing: OfflineTiming,
    mut on_tick: impl FnMut(&Tick, &[PoseEstimate], &dyn PoseTracker),
    mut on_progress: impl FnMut(u64),
) -> Result<OfflineStats, RecordingError> {
    let OfflineTiming {
        start_us,
        depth_latency_us,
        depth_jitter_us,
    } = timing;
    let mut transport = DepthTransport::new(depth_latency_us, depth_jitter_us);
    let mut reader = recording.events()?;
    let schedule = recording.meta.trigger;
    let mut timeline = TriggerTimeline::new(schedule.timeline_config());
    let mut pending: Vec<CdEvent> = Vec::with_capacity(1 << 16);
    let mut estimates = Vec::with_capacity(tracker.objects().len());
    let mut stats = OfflineStats::default();
    // Frames exposed but not yet delivered: (exposure, arrival, frame number), oldest first.
    let mut in_transit: VecDeque<(i64, i64, u64)> = VecDeque::with_capacity(16);
    let mut feed = |tick: Tick,
                    pending: &mut Vec<CdEvent>,
                    tracker: &mut dyn PoseTracker,
                    stats: &mut OfflineStats|
     -> Result<(), RecordingError> {
        let split = pending.partition_point(|e| e.t_us <= tick.t_us);
        tracker.push_events(&pending[..split]);
        stats.events += split as u64;
        pending.drain(..split);
        if tick.t_us < start_us {
            return Ok(());
        }
        if let Some(n) = tick.depth_frame {
            if recording.depth_frames.contains(&n) {
                in_transit.push_back((tick.t_us, transport.due_us(tick.t_us), n));
            } else {
                stats.depth_frames_missing += 1;
            }
        }
        while let Some(&(exposed_us, due_us, n)) = in_transit.front()
            && tick.t_us >= due_us
        {
            in_transit.pop_front();
            let mut frame = recording.depth_frame(n)?;
            tracker.push_depth(exposed_us, &mut frame);
            stats.depth_frames += 1;
        }
        estimates.clear();
        tracker.tick(&tick, &mut estimates);
        stats.ticks += 1;
        on_tick(&tick, &estimates, tracker);
        tracker.prepare_next_tick();
        Ok(())
    };
    let path = recording.dir().join("events.raw");
    let mut latest_us = i64::MIN;
    loop {
        let more = {
            let mut sink = Collector {
                events: &mut pending,
                timeline: &mut timeline,
                channel: schedule.channel,
                latest_us: &mut latest_us,
            };
            reader.read_chunk(&mut sink).map_err(|e| RecordingError {
                path: path.clone(),
                problem: e.to_string(),
            })?
        };
        on_progress(reader.bytes_read());
        if !more {
            timeline.finish();
        }
        while let Some(tick) = timeline.pop_tick() {
            feed(tick, &mut pending, tracker, &mut stats)?;
        }
        if !more {
            break;
        }
    }
    // Frames that arrive after the last tick, while the stream goes on (as the runtime's replay delivers them).
    while let Some(&(exposed_us, due_us, n)) = in_transit.front()
        && latest_us >= due_us
    {
        in_transit.pop_front();
        let mut frame = recording.depth_frame(n)?;
        tracker.push_depth(exposed_us, &mut frame);
        stats.depth_frames += 1;
    }
    stats.events_after_last_tick = pending.len() as u64;
    stats.depth_frames_in_transit = in_transit.len() as u64;
    Ok(stats)
}
