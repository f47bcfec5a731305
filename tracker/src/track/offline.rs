//! Driving a [`PoseTracker`] over a recording as fast as possible (benchmark, `eventtrack6d track`): the same
//! order of inputs the real-time runtime produces — events up to a tick, the depth frame exposed at the tick, the
//! tick — without pacing.

use super::{PoseEstimate, PoseTracker};
use drivers::event::{CdEvent, EventSink, TriggerEdge};
use drivers::recording::{Recording, RecordingError};
use drivers::timeline::{Tick, TriggerTimeline};

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
    /// Events after the last tick (never followed by a tick).
    pub events_after_last_tick: u64,
}

struct Collector<'a> {
    events: &'a mut Vec<CdEvent>,
    timeline: &'a mut TriggerTimeline,
    channel: u8,
}

impl EventSink for Collector<'_> {
    fn cd(&mut self, event: CdEvent) {
        self.events.push(event);
    }
    fn trigger(&mut self, edge: TriggerEdge) {
        if edge.channel == self.channel {
            self.timeline.push(edge);
        }
    }
}

/// Replays `recording` into `tracker`: ticks before `start_us` only warm up the event state; from `start_us` on,
/// every tick is estimated and `on_tick(tick, estimates, tracker)` is called. `on_progress(bytes_read)` follows
/// the event file.
pub fn track_recording(
    recording: &Recording,
    tracker: &mut dyn PoseTracker,
    start_us: i64,
    mut on_tick: impl FnMut(&Tick, &[PoseEstimate], &dyn PoseTracker),
    mut on_progress: impl FnMut(u64),
) -> Result<OfflineStats, RecordingError> {
    let mut reader = recording.events()?;
    let schedule = recording.meta.trigger;
    let mut timeline = TriggerTimeline::new(schedule.timeline_config());
    let mut pending: Vec<CdEvent> = Vec::with_capacity(1 << 16);
    let mut estimates = Vec::with_capacity(tracker.objects().len());
    let mut stats = OfflineStats::default();
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
                let mut frame = recording.depth_frame(n)?;
                tracker.push_depth(tick.t_us, &mut frame);
                stats.depth_frames += 1;
            } else {
                stats.depth_frames_missing += 1;
            }
        }
        estimates.clear();
        tracker.tick(&tick, &mut estimates);
        stats.ticks += 1;
        on_tick(&tick, &estimates, tracker);
        tracker.prepare_next_tick();
        Ok(())
    };
    let path = recording.dir().join("events.raw");
    loop {
        let more = {
            let mut sink = Collector {
                events: &mut pending,
                timeline: &mut timeline,
                channel: schedule.channel,
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
    stats.events_after_last_tick = pending.len() as u64;
    Ok(stats)
}
