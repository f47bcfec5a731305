//! Driving a [`PoseTracker`] over a recording as fast as possible (benchmark, `eventtrack6d track`) on the same
//! [`TickDriver`] as the real-time runtime: events up to a tick, the depth frame exposed at the tick (or, with a
//! depth latency, the frames that have arrived by then), the tick, without pacing.

use super::driver::TickDriver;
use crate::track::{DepthHandling, DepthTransport, PoseEstimate, PoseTracker};
use drivers::event::{CdEvent, EventSink, TriggerEdge};
use drivers::recording::{Recording, RecordingError};
use drivers::timeline::Tick;
use std::collections::VecDeque;

/// Counters of an offline run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OfflineStats {
    /// Events decoded and handed to the tracker up to its last tick.
    pub events: u64,
    /// Ticks handed to the tracker.
    pub ticks: u64,
    /// Depth frames handed to the tracker.
    pub depth_frames: u64,
    /// Depth-exposure ticks whose frame file is missing (dropped by the sensor).
    pub depth_frames_missing: u64,
    /// Depth frames still in transit at the end of the stream (exposed less than the depth latency before it).
    pub depth_frames_in_transit: u64,
    /// Events after the last tick (no tick followed them): not handed to the tracker.
    pub events_after_last_tick: u64,
}

/// The events and trigger edges of one chunk of the event file, in stream order: each edge with how many of the
/// chunk's events came before it.
struct Chunk {
    events: Vec<CdEvent>,
    edges: Vec<(usize, TriggerEdge)>,
    /// The latest time in the stream so far (event or edge), microseconds.
    latest_us: i64,
}

impl EventSink for Chunk {
    fn cd(&mut self, event: CdEvent) {
        self.latest_us = self.latest_us.max(event.t_us);
        self.events.push(event);
    }
    fn trigger(&mut self, edge: TriggerEdge) {
        self.latest_us = self.latest_us.max(edge.t_us);
        self.edges.push((self.events.len(), edge));
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
    on_tick: impl FnMut(&Tick, &[PoseEstimate], &dyn PoseTracker),
    mut on_progress: impl FnMut(u64),
) -> Result<OfflineStats, RecordingError> {
    let mut reader = recording.events()?;
    let mut driver = TickDriver::new(recording.meta.trigger.timeline_config());
    let mut ticks = TickHandler {
        recording,
        start_us: timing.start_us,
        transport: DepthTransport::new(timing.depth_latency_us, timing.depth_jitter_us),
        in_transit: VecDeque::with_capacity(16),
        estimates: Vec::with_capacity(tracker.objects().len()),
        stats: OfflineStats::default(),
        on_tick,
    };
    let path = recording.dir().join("events.raw");
    let mut chunk = Chunk {
        events: Vec::with_capacity(1 << 16),
        edges: Vec::new(),
        latest_us: i64::MIN,
    };
    loop {
        let more = reader.read_chunk(&mut chunk).map_err(|e| RecordingError {
            path: path.clone(),
            problem: e.to_string(),
        })?;
        on_progress(reader.bytes_read());
        // Events go to the tracker just before the edge they precede: those after the latest edge wait for the
        // next one, and the ones no edge follows never reach the tracker, which is left at its last tick.
        let mut handed = 0;
        for &(before, edge) in &chunk.edges {
            driver.events(&chunk.events[handed..before], tracker);
            handed = before;
            driver.edge(edge, tracker);
            while let Some(tick) = driver.next_tick(tracker) {
                ticks.tick(&tick, tracker)?;
            }
        }
        ticks.stats.events += handed as u64;
        chunk.events.drain(..handed);
        chunk.edges.clear();
        if !more {
            break;
        }
    }
    driver.finish();
    while let Some(tick) = driver.next_tick(tracker) {
        ticks.tick(&tick, tracker)?;
    }
    // Frames that arrive after the last tick, while the stream goes on (as the runtime's replay delivers them).
    ticks.deliver_due(chunk.latest_us, tracker)?;
    let after_last_tick = (chunk.events.len() + driver.held()) as u64;
    let mut stats = ticks.stats;
    stats.events -= driver.held() as u64;
    stats.events_after_last_tick = after_last_tick;
    stats.depth_frames_in_transit = ticks.in_transit.len() as u64;
    Ok(stats)
}

/// What an offline run does at each tick: depth frames handed over as they arrive, the tick estimated, the caller
/// told.
struct TickHandler<'a, F> {
    recording: &'a Recording,
    start_us: i64,
    transport: DepthTransport,
    /// Frames exposed but not yet delivered: (exposure, arrival, frame number), oldest first.
    in_transit: VecDeque<(i64, i64, u64)>,
    estimates: Vec<PoseEstimate>,
    stats: OfflineStats,
    on_tick: F,
}

impl<F: FnMut(&Tick, &[PoseEstimate], &dyn PoseTracker)> TickHandler<'_, F> {
    /// The tick: before `start_us` the events it was handed only warm up the tracker; from then on, the depth
    /// frames that have arrived by its time go to the tracker, then the tick is estimated and reported.
    fn tick(&mut self, tick: &Tick, tracker: &mut dyn PoseTracker) -> Result<(), RecordingError> {
        if tick.t_us < self.start_us {
            return Ok(());
        }
        if let Some(n) = tick.depth_frame {
            if self.recording.depth_frames.contains(&n) {
                self.in_transit
                    .push_back((tick.t_us, self.transport.due_us(tick.t_us), n));
            } else {
                self.stats.depth_frames_missing += 1;
            }
        }
        self.deliver_due(tick.t_us, tracker)?;
        self.estimates.clear();
        tracker.tick(tick, &mut self.estimates);
        self.stats.ticks += 1;
        (self.on_tick)(tick, &self.estimates, tracker);
        tracker.prepare_next_tick();
        Ok(())
    }

    /// Hands `tracker` the frames in transit that have arrived by `now_us`, oldest first.
    fn deliver_due(
        &mut self,
        now_us: i64,
        tracker: &mut dyn PoseTracker,
    ) -> Result<(), RecordingError> {
        while let Some(&(exposed_us, due_us, n)) = self.in_transit.front()
            && now_us >= due_us
        {
            self.in_transit.pop_front();
            let mut frame = self.recording.depth_frame(n)?;
            tracker.push_depth(exposed_us, &mut frame, DepthHandling::Now);
            self.stats.depth_frames += 1;
        }
        Ok(())
    }
}
