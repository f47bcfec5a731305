//! Recording replay: `events.raw` decoded chunk by chunk (`Recording::events`, the format's streaming decoder)
//! and assembled into event batches, trigger edges and the recording's depth frames on the trigger timeline
//! ([`super::assembly`]), paced by the recording's clock (real time) or as fast as the tracker takes them.

use super::assembly::StreamAssembler;
use super::config::Pace;
use super::source::{Source, SourceError, SourceOutput, SourceStats, StopFlag};
use drivers::event::EventBuffer;
use drivers::recording::Recording;
use std::time::{Duration, Instant};
use tracker::track::DepthTransport;

/// Replays a recording directory.
pub struct ReplaySource {
    recording: Recording,
    pace: Pace,
    batch_events: usize,
    batch_us: i64,
    start_delay: Duration,
    depth_transport: DepthTransport,
    max_seconds: f64,
}

impl ReplaySource {
    /// A replay of `recording`; events are delivered in batches of at most `batch_events` events spanning at most
    /// `batch_us` microseconds.
    pub fn new(
        recording: Recording,
        pace: Pace,
        batch_events: usize,
        batch_us: i64,
        start_delay: Duration,
    ) -> Self {
        Self {
            recording,
            pace,
            batch_events: batch_events.max(1),
            batch_us: batch_us.max(1),
            start_delay,
            depth_transport: DepthTransport::default(),
            max_seconds: 0.0,
        }
    }

    /// The same replay with each depth frame delivered `latency_us` microseconds (stream time) after its
    /// exposure, between the events either side of that time, as a live depth camera's transport delivers it. A
    /// frame due while a tick pulse is open comes after the pulse's falling edge, so the tick that pulse makes
    /// (stamped at its rising edge, before the frame was due) runs without it, as in the offline driver.
    pub fn with_depth_latency(mut self, latency_us: i64) -> Self {
        self.depth_transport = DepthTransport::new(latency_us, self.depth_transport.jitter_us);
        self
    }

    /// The same replay with up to `jitter_us` microseconds more for each frame, drawn per frame from its exposure
    /// time as the offline driver draws it ([`DepthTransport`]); frames stay in order.
    pub fn with_depth_jitter(mut self, jitter_us: i64) -> Self {
        self.depth_transport = DepthTransport::new(self.depth_transport.latency_us, jitter_us);
        self
    }

    /// The same replay ending after `seconds` of recording time from its first event (0: at its end).
    pub fn with_max_seconds(mut self, seconds: f64) -> Self {
        self.max_seconds = seconds;
        self
    }

    /// The recording.
    pub fn recording(&self) -> &Recording {
        &self.recording
    }
}

impl Source for ReplaySource {
    fn describe(&self) -> String {
        format!(
            "replay of {} ({})",
            self.recording.dir().display(),
            match self.pace {
                Pace::Realtime => "real time",
                Pace::Fast => "as fast as possible",
            }
        )
    }

    fn run(&mut self, out: &SourceOutput, stop: &StopFlag) -> Result<SourceStats, SourceError> {
        let mut reader = self
            .recording
            .events()
            .map_err(|e| SourceError::Input(e.to_string()))?;
        let mut r = StreamAssembler::new(
            out,
            Some(&self.recording),
            self.recording.meta.trigger,
            self.pace == Pace::Realtime,
            (self.batch_events, self.batch_us),
            self.depth_transport,
            stop,
        )
        .with_max_seconds(self.max_seconds);
        let deadline = Instant::now() + self.start_delay;
        while Instant::now() < deadline && !stop.is_set() {
            std::thread::sleep(Duration::from_millis(10).min(deadline - Instant::now()));
        }
        let mut chunk = EventBuffer::new();
        let mut stopped = false;
        loop {
            if stop.is_set() {
                stopped = true;
                break;
            }
            chunk.clear();
            let more = reader
                .read_chunk(&mut chunk)
                .map_err(|e| SourceError::Input(e.to_string()))?;
            r.feed(&chunk, stop);
            if !more || r.reached_end() {
                break;
            }
        }
        let mut stats = r.finish();
        stats.stopped = stopped;
        stats.set_anomalies(reader.anomalies());
        Ok(stats)
    }
}
