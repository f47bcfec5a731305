//! Recording replay: `events.raw` decoded chunk by chunk (`Recording::events`, the format's streaming decoder)
//! into event batches and trigger edges, paced by the recording's clock (real time) or as fast as the tracker
//! takes them, with each depth frame delivered when the trigger edge that completes its phase-coded pulse arrives,
//! or, when that pulse is missing from the stream, the next pulse's (frames numbered by the schedule from the
//! first phase-coded pulse, as the timeline numbers depth ticks); with a depth latency, when the stream reaches
//! its exposure plus that latency, as a live depth camera's transport delivers it (if a tick pulse is open then,
//! after the pulse's falling edge). Frames are read ahead on a helper thread so PNG decoding never delays the
//! stream.

use super::config::Pace;
use super::source::{Source, SourceError, SourceOutput, SourceStats, StopFlag};
use drivers::event::{CdEvent, EventBuffer, TriggerEdge};
use drivers::recording::{DepthFrame, Recording};
use std::collections::VecDeque;
use std::sync::mpsc::{Receiver, sync_channel};
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

    /// The recording.
    pub fn recording(&self) -> &Recording {
        &self.recording
    }
}

type DepthItem = (u64, Result<DepthFrame, String>);

/// Reads the recording's depth frames in order on a helper thread, a couple ahead of use.
fn spawn_depth_reader(rec: &Recording, stop: StopFlag) -> Receiver<DepthItem> {
    let (tx, rx) = sync_channel::<DepthItem>(2);
    let rec = rec.clone();
    std::thread::Builder::new()
        .name("depth-reader".into())
        .spawn(move || {
            for &n in &rec.depth_frames {
                if stop.is_set() {
                    break;
                }
                let frame = rec.depth_frame(n).map_err(|e| e.to_string());
                if tx.send((n, frame)).is_err() {
                    break;
                }
            }
        })
        .map_or_else(
            |_| {
                // No thread: the stream goes on without depth (every frame counted missing).
                let (_tx, rx) = sync_channel(1);
                rx
            },
            |_| rx,
        )
}

/// Wall-clock pacing against the recording's clock.
struct Pacer {
    realtime: bool,
    origin: Option<(i64, Instant)>,
}

impl Pacer {
    /// Waits until the wall clock reaches recording time `t_us` (real time only).
    fn until(&mut self, t_us: i64) {
        if !self.realtime {
            return;
        }
        let (t0, w0) = *self.origin.get_or_insert((t_us, Instant::now()));
        let target = w0 + Duration::from_micros(u64::try_from(t_us - t0).unwrap_or(0));
        let now = Instant::now();
        if target > now {
            std::thread::sleep(target - now);
        }
    }
}

struct Replayer<'a> {
    out: &'a SourceOutput,
    pacer: Pacer,
    batch: Vec<CdEvent>,
    batch_events: usize,
    batch_us: i64,
    channel: u8,
    wide_threshold_us: i64,
    pending_rise: Option<i64>,
    /// The latest phase-coded pulse's rising edge (camera clock, microseconds) and its depth frame: the frames
    /// after it follow every `depth_period_us`.
    depth_anchor: Option<(i64, u64)>,
    depth_period_us: f64,
    tick_period_us: f64,
    /// The next depth frame to deliver.
    next_frame: u64,
    depth: Receiver<DepthItem>,
    next_depth: Option<DepthItem>,
    depth_done: bool,
    transport: DepthTransport,
    /// Frames exposed but not yet delivered (exposure time, arrival time, frame), oldest first.
    in_transit: VecDeque<(i64, i64, Box<DepthFrame>)>,
    stats: SourceStats,
}

impl Replayer<'_> {
    /// At the falling edge of the tick pulse that rose at `rise` (phase-coded or not): the depth frames exposed up
    /// to that pulse go out first, so the tracker has each before the tick the timeline makes of its exposure.
    /// A phase-coded pulse's frame number follows from the previous phase-coded pulse's and the number of depth
    /// periods between them (as the timeline re-locks its schedule), so the count stays right when a phase-coded
    /// pulse is missing, and the trigger clock's drift against the nominal rate never adds up. The frame of a
    /// missing phase-coded pulse goes out at the first pulse after its time, stamped by that schedule.
    fn expose_depth_until(&mut self, rise: i64, wide: bool) {
        let half_tick = (self.tick_period_us * 0.5) as i64;
        if wide {
            let n = match self.depth_anchor {
                None => 0,
                Some((at, n)) => {
                    let periods = ((rise - at) as f64 / self.depth_period_us).round().max(1.0);
                    n + periods as u64
                }
            };
            while self.next_frame < n {
                let k = self.next_frame;
                let exposed = self.scheduled_exposure(k).unwrap_or(rise);
                self.send_depth(k, exposed);
            }
            if self.next_frame == n {
                self.send_depth(n, rise);
            }
            self.depth_anchor = Some((rise, n));
        } else {
            while let Some(due) = self.scheduled_exposure(self.next_frame)
                && due <= rise + half_tick
            {
                self.send_depth(self.next_frame, due);
            }
        }
    }

    /// When frame `k` is exposed by the schedule from the latest phase-coded pulse (`None` before the first).
    fn scheduled_exposure(&self, k: u64) -> Option<i64> {
        let (at, n) = self.depth_anchor?;
        Some(at + ((k as f64 - n as f64) * self.depth_period_us).round() as i64)
    }

    /// Sends depth frame `k`, exposed at `exposed` (or puts it in transit), and moves on to the next frame.
    fn send_depth(&mut self, k: u64, exposed: i64) {
        self.next_frame = k + 1;
        match self.depth_frame(k) {
            Some(frame) if !self.transport.is_immediate() => {
                let arrives = self.transport.due_us(exposed);
                self.in_transit
                    .push_back((exposed, arrives, Box::new(frame)));
            }
            Some(frame) => {
                self.stats.depth_frames += 1;
                self.out.depth(exposed, Box::new(frame));
            }
            None => self.stats.depth_missing += 1,
        }
    }

    fn flush(&mut self) {
        if let Some(last) = self.batch.last() {
            self.pacer.until(last.t_us);
            let full = std::mem::replace(&mut self.batch, self.out.buffer());
            self.out.events(full);
        }
    }

    /// Delivers the frames in transit that are due by stream time `t_us`.
    fn deliver_due(&mut self, t_us: i64) {
        if self.in_transit.front().is_none_or(|f| t_us < f.1) {
            return;
        }
        self.flush();
        while self.in_transit.front().is_some_and(|f| t_us >= f.1)
            && let Some((exposed_us, due_us, frame)) = self.in_transit.pop_front()
        {
            self.pacer.until(due_us);
            self.stats.depth_frames += 1;
            self.out.depth(exposed_us, frame);
        }
    }

    fn cd(&mut self, e: CdEvent) {
        // A frame due inside an open tick pulse waits for its falling edge: the tick that pulse makes was
        // stamped before the frame was due, and the offline driver hands the frame over after it too.
        if self.pending_rise.is_none() {
            self.deliver_due(e.t_us);
        }
        if let Some(first) = self.batch.first()
            && (self.batch.len() >= self.batch_events || e.t_us - first.t_us >= self.batch_us)
        {
            self.flush();
        }
        self.batch.push(e);
        self.stats.events += 1;
    }

    /// The depth frame numbered `n`, if the recording has it (frames are read in order).
    fn depth_frame(&mut self, n: u64) -> Option<DepthFrame> {
        loop {
            if self.next_depth.is_none() && !self.depth_done {
                match self.depth.recv() {
                    Ok(item) => self.next_depth = Some(item),
                    Err(_) => self.depth_done = true,
                }
            }
            match self.next_depth.take() {
                None => return None,
                Some((k, _)) if k < n => continue,
                Some((k, frame)) if k == n => return frame.ok(),
                Some(later) => {
                    self.next_depth = Some(later);
                    return None;
                }
            }
        }
    }

    fn trigger(&mut self, edge: TriggerEdge) {
        self.flush();
        let tick_channel = edge.channel == self.channel;
        // A rising edge on the tick channel also ends a pulse whose falling edge was lost.
        if (tick_channel && edge.rising) || self.pending_rise.is_none() {
            self.deliver_due(edge.t_us);
        }
        self.pacer.until(edge.t_us);
        self.stats.trigger_edges += 1;
        let mut closed = false;
        if tick_channel {
            if edge.rising {
                self.pending_rise = Some(edge.t_us);
            } else if let Some(rise) = self.pending_rise.take() {
                closed = true;
                let wide = edge.t_us - rise >= self.wide_threshold_us;
                self.expose_depth_until(rise, wide);
            }
        }
        self.out.trigger(edge);
        if closed {
            // Frames that fell due while the pulse was open, after the tick it makes.
            self.deliver_due(edge.t_us);
        }
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
        let schedule = self.recording.meta.trigger;
        let mut r = Replayer {
            out,
            pacer: Pacer {
                realtime: self.pace == Pace::Realtime,
                origin: None,
            },
            batch: out.buffer(),
            batch_events: self.batch_events,
            batch_us: self.batch_us,
            channel: schedule.channel,
            wide_threshold_us: (schedule.narrow_width_us + schedule.wide_width_us) / 2,
            pending_rise: None,
            depth_anchor: None,
            depth_period_us: f64::from(schedule.ticks_per_depth) * 1e6 / schedule.tick_rate_hz,
            tick_period_us: 1e6 / schedule.tick_rate_hz,
            next_frame: 0,
            depth: spawn_depth_reader(&self.recording, stop.clone()),
            next_depth: None,
            depth_done: false,
            transport: self.depth_transport,
            in_transit: VecDeque::with_capacity(16),
            stats: SourceStats::default(),
        };
        let deadline = Instant::now() + self.start_delay;
        while Instant::now() < deadline && !stop.is_set() {
            std::thread::sleep(Duration::from_millis(10).min(deadline - Instant::now()));
        }
        let mut chunk = EventBuffer::new();
        loop {
            if stop.is_set() {
                r.stats.stopped = true;
                break;
            }
            chunk.clear();
            let more = reader
                .read_chunk(&mut chunk)
                .map_err(|e| SourceError::Input(e.to_string()))?;
            // Merge the chunk's CD events and trigger edges by time (edges first at equal times).
            let (mut i, mut j) = (0, 0);
            while i < chunk.cd.len() || j < chunk.triggers.len() {
                let take_edge = match (chunk.cd.get(i), chunk.triggers.get(j)) {
                    (Some(c), Some(t)) => t.t_us <= c.t_us,
                    (None, Some(_)) => true,
                    _ => false,
                };
                if take_edge {
                    r.trigger(chunk.triggers[j]);
                    j += 1;
                    if stop.is_set() {
                        break;
                    }
                } else {
                    r.cd(chunk.cd[i]);
                    i += 1;
                }
            }
            if !more {
                break;
            }
        }
        r.flush();
        r.stats.depth_in_transit = r.in_transit.len() as u64;
        r.stats.set_anomalies(reader.anomalies());
        Ok(r.stats)
    }
}
